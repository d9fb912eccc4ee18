"""What users hit first (issue 16): ``qsplan --version``; ``qsplan demo`` run twice into one directory replaces the
outputs it wrote itself and nothing else; the plan card among the outputs."""

import json

import pytest

from qsplan import __version__
from qsplan.planner.cli.main import main
from qsplan.planner.export.manifest import MANIFEST, own_outputs, record_outputs


def run(args, capsys):
    code = main(args)
    out, err = capsys.readouterr()
    return code, out, err


def test_version(capsys):
    assert run(["--version"], capsys) == (0, f"qsplan {__version__}\n", "")
    code, out, _ = run(["--version", "count", "--contacts", "3", "--dof", "3"], capsys)
    assert code == 0 and out == f"qsplan {__version__}\n"


def test_manifest_knows_only_unchanged_files(tmp_path):
    a, b = tmp_path / "a.csv", tmp_path / "b.png"
    a.write_text("1\n")
    b.write_bytes(b"png")
    record_outputs(tmp_path, [a, b])
    assert own_outputs(tmp_path) == {"a.csv", "b.png"}
    a.write_text("2\n")  # edited by someone: no longer qsplan's
    b.unlink()
    (tmp_path / "b.png").symlink_to(tmp_path / MANIFEST)  # a link in its place is never qsplan's
    assert own_outputs(tmp_path) == set()
    (tmp_path / MANIFEST).write_text("{not json")
    assert own_outputs(tmp_path) == set()


@pytest.mark.ompl
def test_demo_runs_twice_into_one_directory(tmp_path, capsys):
    out = tmp_path / "out"
    args = ["demo", "--out", str(out), "--no-plots", "--verify", "0", "--quiet"]  # the demo's plan, fast
    code, first, err = run(args, capsys)
    assert code == 0 and err == ""
    written = sorted(p.name for p in out.iterdir())
    assert written == [MANIFEST, "certificate.json", "plan.csv", "plan.json", "scene.xml"]
    before = (out / "plan.csv").read_bytes()
    (out / "notes.txt").write_text("the operator's notes")
    code, second, err = run(args, capsys)  # its own outputs, unchanged: replaced without --force
    assert code == 0 and err == "" and second.count("wrote ") == 4
    assert (out / "plan.csv").read_bytes() == before and (out / "notes.txt").read_text() == "the operator's notes"
    manifest = json.loads((out / MANIFEST).read_text())
    assert set(manifest["files"]) == {"plan.csv", "plan.json", "certificate.json", "scene.xml"}
    (out / "plan.json").write_text("{}")  # a file qsplan did not write (edited): refused, in one line, untouched
    code, _, err = run(args, capsys)
    assert code == 2 and err.count("\n") == 1 and "plan.json" in err and "--force" in err
    assert (out / "plan.json").read_text() == "{}" and (out / "plan.csv").read_bytes() == before
    code, _, err = run([*args, "--force"], capsys)
    assert code == 0 and json.loads((out / "plan.json").read_text())["format"] == "qsplan.torque_schedule.plan"


@pytest.mark.ompl
def test_pipeline_writes_the_plan_card(small_run):
    from PIL import Image

    assert str(small_run.out_dir / "plan_card.png") in small_run.files
    with Image.open(small_run.out_dir / "plan_card.png") as im:
        w, h = im.size
        assert im.info.get("Software") == f"qsplan {__version__}"
    assert abs(h / w - 297 / 210) < 0.01 and w >= 1200  # an A4 page, sharp enough to print
    assert own_outputs(small_run.out_dir) >= {"plan_card.png", "plan.csv", "replay.json"}
