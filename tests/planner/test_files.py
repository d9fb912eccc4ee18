"""Output files (issue 12): atomic writes, no overwrite without --force, never an input, never through a
symbolic link, no stale outputs; Ctrl-C exits 130 in one line; integer options bounded."""

import json

import pytest

from qsplan.hands.examples.paper import eq42_scene
from qsplan.mechanics import QsplanError
from qsplan.planner.cli.main import COMMANDS, main
from qsplan.planner.cli.options import COUNT_RANGES, EXIT_INTERRUPTED
from qsplan.planner.export.files import OutputExistsError, atomic_write, check_outputs, remove_stale


def run(args, capsys):
    code = main(args)
    out, err = capsys.readouterr()
    return code, out, err


@pytest.fixture
def scene(tmp_path):
    p = tmp_path / "eq42.json"
    p.write_text(json.dumps(eq42_scene()))
    return p


def test_atomic_write_leaves_no_temporary(tmp_path):
    path = atomic_write(tmp_path / "sub" / "a.txt", "hello\n")
    assert path.read_text() == "hello\n" and [p.name for p in path.parent.iterdir()] == ["a.txt"]
    assert path.stat().st_mode & 0o644 == 0o644


@pytest.mark.parametrize("exc", [KeyboardInterrupt, OSError, RuntimeError])
def test_interrupted_write_keeps_the_old_file(tmp_path, exc):
    path = tmp_path / "a.csv"
    path.write_text("old\n")

    def write(f):
        f.write("half a ")
        raise exc("stop")

    with pytest.raises((exc, QsplanError)):
        atomic_write(path, write, force=True)
    assert path.read_text() == "old\n" and [p.name for p in tmp_path.iterdir()] == ["a.csv"]


def test_no_overwrite_without_force(tmp_path):
    path = tmp_path / "a.json"
    path.write_text("mine")
    with pytest.raises(OutputExistsError, match="pass force=True"):
        atomic_write(path, "new", force=False)
    assert path.read_text() == "mine"
    atomic_write(path, "new", force=True)
    assert path.read_text() == "new"


def test_never_through_a_symlink_nor_over_an_input(tmp_path):
    target = tmp_path / "precious.txt"
    target.write_text("keep")
    link = tmp_path / "link.txt"
    link.symlink_to(target)
    with pytest.raises(QsplanError, match="symbolic link; refusing to write through it"):
        atomic_write(link, "x", force=True)
    with pytest.raises(QsplanError, match="is an input of this run"):
        check_outputs([tmp_path / "." / "precious.txt"], force=True, inputs=[target])
    assert target.read_text() == "keep" and link.is_symlink()


def test_remove_stale_removes_only_named_files(tmp_path):
    for name in ("plan.csv", "failure.json", "notes.txt"):
        (tmp_path / name).write_text("x")
    removed = remove_stale(tmp_path, ["plan.csv", "failure.json", "missing.png"])
    assert sorted(p.name for p in removed) == ["failure.json", "plan.csv"]
    assert [p.name for p in tmp_path.iterdir()] == ["notes.txt"]


def test_muspace_out_refuses_existing_png_and_the_scene(tmp_path, scene, capsys):
    png = tmp_path / "map.png"
    png.write_bytes(b"user's picture")
    base = ["muspace", str(scene), "--x", "mu1", "--y", "mu2", "--range", "0", "1", "--n", "3", "--workers", "1"]
    code, _, err = run([*base, "--out", str(png)], capsys)
    assert code == 2 and err.count("\n") == 1 and "--force" in err and png.read_bytes() == b"user's picture"
    code, _, err = run([*base, "--out", str(png), "--force"], capsys)
    assert code == 0 and png.read_bytes()[:4] == b"\x89PNG"
    link = tmp_path / "link.png"
    link.symlink_to(png)
    code, _, err = run([*base, "--out", str(link), "--force"], capsys)
    assert code == 2 and "symbolic link" in err and err.count("\n") == 1


def test_simulate_out_refuses_existing_png(tmp_path, capsys):
    png = tmp_path / "rod.png"
    png.write_bytes(b"mine")
    args = ["simulate", "rod", "--l1", "1", "--l2", "0.6", "--mu-static", "0.3", "0.3", "--mu-kinetic", "0.2", "0.2",
            "--speed", "0.1", "--duration", "1", "--out", str(png)]  # fmt: skip
    code, _, err = run(args, capsys)
    assert code == 2 and "exists" in err and png.read_bytes() == b"mine"


def test_paper_refuses_existing_outputs_before_any_work(tmp_path, capsys):
    (tmp_path / "table1.txt").write_text("mine")
    code, _, err = run(["paper", "--out", str(tmp_path), "--n", "3"], capsys)
    assert code == 2 and err.count("\n") == 1 and "--force" in err
    assert (tmp_path / "table1.txt").read_text() == "mine"


def test_ctrl_c_exits_130_in_one_line(monkeypatch, capsys):
    def interrupted(args, out):
        raise KeyboardInterrupt

    monkeypatch.setattr(COMMANDS["count"], "run", interrupted)
    code, out, err = run(["count", "--contacts", "3", "--dof", "3"], capsys)
    assert code == EXIT_INTERRUPTED == 130 and err == "qsplan: interrupted\n"


@pytest.mark.parametrize(
    "argv,option",
    [(["plan", "x.toml", "--verify", "99999999999999999999"], "--verify"), (["count", "--contacts", "10000", "--dof", "3"], "--contacts"),
     (["paper", "--n", "5000"], "--n"), (["modes", "x.json", "--workers", "100000000000"], "--workers"),
     (["plan", "x.toml", "--seed", "-1"], "--seed")],  # fmt: skip
)
def test_counts_are_bounded(argv, option, capsys):
    code, _, err = run(argv, capsys)
    assert code == 2 and err.startswith(f"qsplan: error: {option}: expected ") and err.count("\n") == 1


def test_count_ranges_are_ordered():
    assert all(lo < hi for lo, hi, _ in COUNT_RANGES.values())


class _Report:
    message = "no plan: the band closes"

    def as_dict(self):
        return {"message": self.message}


def test_failing_forced_plan_leaves_no_old_plan_beside_failure_json(tmp_path, monkeypatch):
    from qsplan.planner.pipeline import run as pipeline
    from qsplan.planner.plan.results import PlanFailure
    from qsplan.planner.task.task import demo_task_path, load_task

    def fail(*args, **kwargs):
        raise PlanFailure(_Report())

    for name in ("plan.csv", "plan.json", "replay.json", "plan_bands.png"):
        (tmp_path / name).write_text("an earlier run")
    monkeypatch.setattr(pipeline, "plan_task", fail)
    task = load_task(demo_task_path())
    with pytest.raises(OutputExistsError):
        pipeline.run_plan(task, tmp_path, force=False)
    with pytest.raises(PlanFailure) as info:
        pipeline.run_plan(task, tmp_path, force=True)
    assert info.value.report_path == tmp_path / "failure.json"
    assert sorted(p.name for p in tmp_path.iterdir() if not p.name.startswith(".")) == ["failure.json", "failure.png"]
    with pytest.raises(PlanFailure):  # the report qsplan wrote is replaced by the next run (issue 16)
        pipeline.run_plan(task, tmp_path, force=False)
    (tmp_path / "failure.json").write_text("annotated by hand")
    with pytest.raises(OutputExistsError):  # the report is an output too: once edited, not replaced without force
        pipeline.run_plan(task, tmp_path, force=False)
