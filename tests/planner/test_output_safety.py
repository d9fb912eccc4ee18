"""Output safety of ``plan``/``demo``/``paper`` (issue 21, items 9, 10, 11): a plan file never appears in DIR before
it is certified (Ctrl-C while certifying leaves none); one run at a time into a directory (a second fails at once,
a killed run's lock blocks nobody); never an input replaced, force or not; an unwritable ``--out`` in one line."""

import json
import os
import signal
import subprocess
import sys
import time

import pytest

from qsplan.planner.cli.main import main
from qsplan.planner.export import manifest
from qsplan.planner.export.files import LOCK_NAME, STAGE_PREFIX, OutDirLockedError, locked_out_dir
from qsplan.planner.export.manifest import MANIFEST, own_outputs, publish_outputs
from qsplan.planner.task.task import demo_task_path, task_paths

#: The demo's plan without plots or re-simulations: planned, exported and certified in a second or two.
FAST = ["--no-plots", "--verify", "0", "--quiet"]

#: Seconds a subprocess may take to reach a line of its progress (imports and planning on a loaded machine).
REACH = 120


def no_work(monkeypatch):
    """Make the work of ``plan``/``demo`` (planning) and ``paper`` (its examples) fail the test: a run refused "at
    once" is refused before either starts."""

    def worked(*args, **kwargs):
        raise AssertionError("the work started")

    from qsplan.planner.pipeline import run as pipeline
    from qsplan.planner.reports import paper

    monkeypatch.setattr(pipeline, "plan_task", worked)
    monkeypatch.setattr(paper, "_reproduce", worked)


def run(args, capsys):
    code = main(args)
    out, err = capsys.readouterr()
    return code, out, err


def snapshot(d):
    """``{name: bytes}`` of the regular files in ``d``."""
    return {p.name: p.read_bytes() for p in d.iterdir() if p.is_file()}


def leftovers(d):
    """What a run must never leave in ``d``: its lock file and staging directories."""
    return [p.name for p in d.iterdir() if p.name == LOCK_NAME or p.name.startswith(STAGE_PREFIX)]


def start_plan(out, *extra):
    """``qsplan plan demo_task --out out`` in a subprocess (progress lines on its stderr)."""
    argv = [sys.executable, "-m", "qsplan.planner.cli", "plan", "demo_task", "--out", str(out), *extra]
    return subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def wait_for_line(proc, text):
    """Read ``proc``'s stderr until a line holding ``text``; returns what was read."""
    seen, t0 = [], time.perf_counter()
    while time.perf_counter() - t0 < REACH:
        line = proc.stderr.readline()
        if not line:
            break
        seen.append(line)
        if text in line:
            return seen
    proc.kill()
    raise AssertionError(f"never saw {text!r}: {''.join(seen)[-1000:]}")


# --- item 10: one run at a time --------------------------------------------------------------------------


def test_a_held_directory_refuses_a_second_run_at_once(tmp_path, capsys, monkeypatch):
    out = tmp_path / "out"
    no_work(monkeypatch)
    with locked_out_dir(out) as held:
        assert (held / LOCK_NAME).read_text() == f"{os.getpid()}\n"
        code, stdout, err = run(["demo", "--out", str(out), *FAST], capsys)
        with pytest.raises(OutDirLockedError, match=f"is being written by another qsplan run \\(pid {os.getpid()}\\)"):
            with locked_out_dir(out):
                pass
    assert code == 2 and stdout == "" and err.count("\n") == 1
    assert err == (f"qsplan: error: --out: {str(out)!r} is being written by another qsplan run (pid {os.getpid()}); "
                   "wait for it or choose another directory\n")  # fmt: skip
    assert not out.exists()  # released: the lock file removed, and the directory the holder created with it


def test_a_lock_file_left_behind_blocks_nobody(tmp_path, capsys):
    out = tmp_path / "out"
    out.mkdir()
    (out / LOCK_NAME).write_text("999999999\n")  # a killed run's: no process holds its flock
    (out / f"{STAGE_PREFIX}killed").mkdir()
    (out / f"{STAGE_PREFIX}killed" / "plan.csv").write_text("never certified")
    with locked_out_dir(out):
        assert leftovers(out) == [LOCK_NAME]  # a killed run's staging directory removed under the lock
    assert leftovers(out) == []


@pytest.mark.slow
@pytest.mark.ompl
def test_two_runs_into_one_directory_at_once(tmp_path):
    """Two real runs started together: one plans, the other fails at once naming it; the first's results intact."""
    out = tmp_path / "same"
    procs = [start_plan(out, "--no-plots"), start_plan(out, "--no-plots")]
    results = [p.communicate(timeout=600) + (p.returncode, p.pid) for p in procs]
    codes = sorted(r[2] for r in results)
    assert codes == [0, 2], [r[1][-500:] for r in results]
    (_, _, _, winner), (_, err, _, _) = sorted(results, key=lambda r: r[2])
    assert err.splitlines() == [f"qsplan: error: --out: {str(out)!r} is being written by another qsplan run "
                                f"(pid {winner}); wait for it or choose another directory"]  # fmt: skip
    names = sorted(p.name for p in out.iterdir())
    assert names == sorted([MANIFEST, "plan.csv", "plan.json", "certificate.json", "replay.json", "scene.xml"])
    assert own_outputs(out) == set(names) - {MANIFEST}  # the winner's files, as it recorded them
    assert json.loads((out / "certificate.json").read_text())["certified"] is True


@pytest.mark.slow
@pytest.mark.ompl
def test_a_killed_runs_lock_does_not_block_the_next(tmp_path):
    out = tmp_path / "out"
    proc = start_plan(out)
    wait_for_line(proc, "certifying the exported plan")  # the lock held, the plan staged
    proc.send_signal(signal.SIGKILL)  # no cleanup at all
    proc.communicate(timeout=60)
    assert LOCK_NAME in leftovers(out) and not (out / "plan.csv").exists()
    proc = start_plan(out, "--no-plots", "--verify", "0", "--quiet")
    _, err = proc.communicate(timeout=600)
    assert proc.returncode == 0 and err == ""
    assert leftovers(out) == [] and (out / "plan.csv").is_file()


# --- item 9: nothing uncertified in DIR ------------------------------------------------------------------


@pytest.mark.ompl
def test_ctrl_c_while_certifying_leaves_no_plan(tmp_path):
    """SIGINT once the certification has started: exit 130, one line, no plan file (the plots and re-simulations
    that follow take seconds, so the signal lands before anything is published)."""
    out = tmp_path / "out"
    proc = start_plan(out)
    wait_for_line(proc, "certifying the exported plan")
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err[-500:]
    assert err.splitlines()[-1] == "qsplan: interrupted" and "Traceback" not in err
    assert not out.exists() or sorted(p.name for p in out.iterdir()) == []


@pytest.mark.ompl
def test_an_interrupted_rerun_keeps_the_earlier_results(tmp_path, capsys, monkeypatch):
    from qsplan.planner.pipeline import run as pipeline

    out = tmp_path / "out"
    assert run(["demo", "--out", str(out), *FAST], capsys)[0] == 0
    before = snapshot(out)
    cert = json.loads(before["certificate.json"])
    assert cert["source"] == str(out / "plan.csv")  # the file certified, under the name it is published as

    def interrupted(plan, *args):
        raise KeyboardInterrupt

    monkeypatch.setattr(pipeline, "_certify", interrupted)  # Ctrl-C while the rerun certifies its staged plan
    code, _, err = run(["demo", "--out", str(out), *FAST], capsys)
    assert code == 130 and err == "qsplan: interrupted\n"
    assert snapshot(out) == before and leftovers(out) == []


@pytest.mark.parametrize("stop_after", range(4))
def test_publishing_interrupted_anywhere_is_consistent(tmp_path, monkeypatch, stop_after):
    """The publish order: earlier outputs removed, the manifest written, the plan files renamed last.  Wherever it
    stops, a plan file present means all its run's files are, and every file present is one qsplan recorded."""
    out, stage = tmp_path / "out", tmp_path / "out" / f"{STAGE_PREFIX}x"
    stage.mkdir(parents=True)
    names = ["plan.csv", "plan.json", "certificate.json", "replay.json"]
    for n in names:
        (out / n).write_text(f"old {n}")
        (stage / n).write_text(f"new {n}")
    manifest.record_outputs(out, [out / n for n in names])
    renames = []
    real_replace = os.replace

    def replace(src, dst):  # os.replace is shared: the manifest's own atomic write passes through
        if os.path.dirname(src) == str(stage):
            if len(renames) == stop_after:
                raise KeyboardInterrupt
            renames.append(os.path.basename(dst))
        real_replace(src, dst)

    monkeypatch.setattr(manifest.os, "replace", replace)
    with pytest.raises(KeyboardInterrupt):
        publish_outputs(out, stage, names, remove=names, last=("plan.csv", "plan.json"))
    present = {p.name: p.read_text() for p in out.iterdir() if p.is_file() and p.name != MANIFEST}
    assert all(v.startswith("new ") for v in present.values())  # no old file beside a new one
    assert set(present) <= own_outputs(out)  # recorded: a rerun replaces them without --force
    if "plan.csv" in present:
        assert {"certificate.json", "replay.json"} <= set(present)
    assert renames == ["certificate.json", "replay.json", "plan.csv", "plan.json"][:stop_after]


# --- item 11: inputs and unwritable directories ----------------------------------------------------------


@pytest.mark.parametrize("name, extra", [
    ("plan.json", []),
    ("failure.json", []),
    ("plan_card.png", ["--no-plots"]),  # not written by this run, but an earlier run's plot it would remove
])  # fmt: skip
def test_force_never_replaces_the_task_file(tmp_path, capsys, name, extra):
    out = tmp_path / "out"
    out.mkdir()
    task = out / name
    task.write_text(task_paths()["demo_task"].read_text())
    code, _, err = run(["plan", str(task), "--out", str(out), "--force", "--verify", "0", "--quiet", *extra], capsys)
    assert code == 2 and err.count("\n") == 1
    assert err == (f"qsplan: error: --out: {str(task)!r}"
                   " is an input of this run; refusing to replace it, even with force\n")
    assert task.read_text() == task_paths()["demo_task"].read_text() and sorted(p.name for p in out.iterdir()) == [name]


def test_the_lock_file_is_never_an_input(tmp_path):
    from qsplan.mechanics import QsplanError
    from qsplan.planner.pipeline.run import run_plan
    from qsplan.planner.task.task import load_task

    (tmp_path / LOCK_NAME).write_text("a task under the lock file's name")
    with pytest.raises(QsplanError, match="is an input of this run"):  # it would be unlinked after the run
        run_plan(load_task(demo_task_path()), tmp_path, inputs=[tmp_path / LOCK_NAME])
    assert (tmp_path / LOCK_NAME).read_text() == "a task under the lock file's name"


def test_paper_out_under_a_file_is_one_line(tmp_path, capsys):
    (tmp_path / "a_file").write_text("")
    code, _, err = run(["paper", "--out", str(tmp_path / "a_file" / "sub"), "--n", "3"], capsys)
    assert code == 2 and err.count("\n") == 1
    assert err.startswith(f"qsplan: error: --out: cannot create the directory {str(tmp_path / 'a_file' / 'sub')!r}: ")


def cannot_create_in(directory) -> bool:
    """Whether creating a file in ``directory`` fails (for anyone, root included: sysfs)."""
    path = os.path.join(directory, f".qsplan-probe-{os.getpid()}")
    try:
        os.close(os.open(path, os.O_CREAT | os.O_EXCL | os.O_WRONLY))
    except OSError:
        return True
    os.unlink(path)
    return False


@pytest.mark.skipif(not (os.path.isdir("/sys") and cannot_create_in("/sys")), reason="needs sysfs (read-only for all)")
@pytest.mark.parametrize("argv", [["paper", "--n", "3"], ["demo", *FAST]])
def test_out_read_only_directory_is_one_line(capsys, argv, monkeypatch):
    no_work(monkeypatch)
    code, _, err = run([*argv, "--out", "/sys"], capsys)
    assert code == 2 and err.count("\n") == 1 and "Traceback" not in err
    assert err.startswith("qsplan: error: --out: cannot write into '/sys'")


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes into read-only directories")
def test_paper_out_without_write_permission_is_one_line(tmp_path, capsys):
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o555)
    try:
        code, _, err = run(["paper", "--out", str(ro), "--n", "3"], capsys)
        assert code == 2 and err.count("\n") == 1 and "Permission denied" in err
        code, _, err = run(["paper", "--out", str(ro / "new"), "--n", "3"], capsys)
        assert code == 2 and err.count("\n") == 1 and "cannot create the directory" in err
    finally:
        ro.chmod(0o755)
