"""The ``qsplan`` command's contracts: modes, count, partition, paper; errors exit 2 in one line."""

import json
import subprocess
import sys

import numpy as np
import pytest

from qsplan.hands.examples.paper import eq42_scene, rod_scene
from qsplan.mechanics import planted_scene, solve
from qsplan.mechanics.model.scene_io_write import scene_to_dict
from qsplan.planner.cli.main import main


def run(args, capsys):
    code = main(args)
    out, err = capsys.readouterr()
    return code, out, err


@pytest.fixture
def eq42_file(tmp_path):
    p = tmp_path / "eq42.json"
    p.write_text(json.dumps(eq42_scene(0.5)))
    return p


def test_modes_json_contract(eq42_file, capsys):
    code, out, err = run(["modes", str(eq42_file), "--json"], capsys)
    assert code == 0 and err == ""
    doc = json.loads(out)
    assert doc["modes_tested"] == 7
    assert [f["mode"] for f in doc["feasible"]] == ["SSS", "RBS", "SRB"]
    assert [f["name"] for f in doc["feasible"]] == ["3S", "R1S3", "R2S1"]
    for f in doc["feasible"]:
        assert len(f["qdot"]) == 3
        for key in ("normal_forces", "tangential_forces", "sliding_directions"):
            assert len(f[key]) == 3
        assert f["joint_velocities"] == [] and f["joint_efforts"] == []  # scene gives contact velocities
        for i, letter in enumerate(f["mode"]):
            if letter == "B":
                assert f["normal_forces"][i] == 0 and f["tangential_forces"][i] == 0
            assert (f["sliding_directions"][i] != 0) == (letter == "S")


def test_modes_json_with_joints_reports_all_joints(tmp_path, capsys):
    scene, planted = planted_scene(np.random.default_rng(9), 5, 2)
    p = tmp_path / "s.json"
    p.write_text(json.dumps(scene_to_dict(scene)))
    code, out, _ = run(["modes", str(p), "--json"], capsys)
    doc = json.loads(out)
    assert code == 0 and planted.letters in [f["mode"] for f in doc["feasible"]]
    f = doc["feasible"][0]
    assert len(f["joint_velocities"]) == scene.n_joints == len(f["joint_efforts"])
    ref = solve(scene).solutions[0]
    np.testing.assert_allclose(f["joint_efforts"], ref.tau)


@pytest.mark.parametrize("mu,expected", [(["0.05"], []), (["0.5"], ["SSS", "RBS", "SRB"]), (["0.05", "0.05", "1.0"], ["SSS", "SBR"])])
def test_modes_mu_override(eq42_file, capsys, mu, expected):
    code, out, _ = run(["modes", str(eq42_file), "--json", "--mu", *mu], capsys)
    assert code == 0 and [f["mode"] for f in json.loads(out)["feasible"]] == expected


def test_modes_table_is_readable(eq42_file, capsys):
    code, out, _ = run(["modes", str(eq42_file)], capsys)
    assert code == 0 and "AMBIGUOUS" in out and "R1S3" in out and "modes tested: 7" in out


def test_count(capsys):
    assert run(["count", "--contacts", "20", "--dof", "20"], capsys)[1] == "377379369\n"
    assert run(["count", "--contacts", "3", "--dof", "3"], capsys)[1] == "7\n"
    code, out, _ = run(["count", "--contacts", "12", "--dof", "12", "--json"], capsys)
    assert json.loads(out)["modes"] == 73789


@pytest.mark.parametrize(
    "args,match",
    [
        (["modes", "{scene}", "--mu", "-0.2"], "--mu: expected nonnegative"),
        (["modes", "{scene}", "--mu", "abc"], "invalid float value"),
        (["modes", "{scene}", "--mu", "nan"], "--mu"),
        (["modes", "{scene}", "--mu", "0.1", "0.2"], "expected 1 or 3 values"),
        (["modes", "{scene}", "--frobnicate"], "unrecognized arguments"),
        (["modes", "{missing}"], "cannot read scene file"),
        (["modes", "{badjson}"], "invalid JSON"),
        (["modes", "{nomu}"], r"contacts\[0\].mu: missing"),
        (["count", "--contacts", "x", "--dof", "3"], "invalid int value"),
        (["count", "--contacts", "-3", "--dof", "3"], "--contacts"),
        (["bogus"], "invalid choice"),
        ([], "required"),
    ],
)
def test_bad_input_one_line_exit_2(tmp_path, eq42_file, capsys, args, match):
    (tmp_path / "bad.json").write_text('{"g_obj": [0, -1')
    nomu = eq42_scene()
    del nomu["contacts"][0]["mu"]
    (tmp_path / "nomu.json").write_text(json.dumps(nomu))
    files = {"scene": eq42_file, "missing": tmp_path / "none.json", "badjson": tmp_path / "bad.json", "nomu": tmp_path / "nomu.json"}
    code, out, err = run([a.format(**files) for a in args], capsys)
    assert code == 2 and out == ""
    assert err.count("\n") == 1 and "Traceback" not in err
    import re

    assert re.search(match, err), err


def test_console_script_subprocess_no_traceback(tmp_path):
    p = tmp_path / "rod.json"
    p.write_text(json.dumps(rod_scene(l1=1.0, l2=0.5, mu=(0.3, 0.3))))
    ok = subprocess.run([sys.executable, "-m", "qsplan.planner.cli", "modes", str(p), "--json"], capture_output=True, text=True)
    assert ok.returncode == 0 and [f["name"] for f in json.loads(ok.stdout)["feasible"]] == ["R2S1"]
    bad = subprocess.run([sys.executable, "-m", "qsplan.planner.cli", "modes", str(p), "--mu", "-1"], capture_output=True, text=True)
    assert bad.returncode == 2 and bad.stdout == "" and len(bad.stderr.splitlines()) == 1


def test_partition_command(tmp_path, capsys):
    scene, planted = planted_scene(np.random.default_rng(4), 4, 1, 3)
    p = tmp_path / "s.json"
    p.write_text(json.dumps(scene_to_dict(scene)))
    code, out, _ = run(["partition", str(p), "--mode", planted.letters, "--json"], capsys)
    doc = json.loads(out)
    assert code == 0 and doc["mode"] == planted.letters
    own = [scene.joint_names[i] for i in scene.effort_joints]
    assert own in [r["effort_joints"] for r in doc["partitions"]]  # the scene's own partition admits its mode
    code, out, _ = run(["partition", str(p), "--json"], capsys)
    table = {tuple(r["effort_joints"]): r["modes"] for r in json.loads(out)["partitions"]}
    assert planted.letters in table[tuple(own)]


def test_paper_writes_results(tmp_path, capsys):
    out_dir = tmp_path / "out"
    code, out, _ = run(["paper", "--out", str(out_dir), "--n", "41"], capsys)
    assert code == 0 and "FAIL" not in out
    for name in ("fig3_eq37.png", "fig6_eq42.png", "fig8_rod.png", "table1.txt", "paper_results.json"):
        assert (out_dir / name).stat().st_size > 0
    res = json.loads((out_dir / "paper_results.json").read_text())
    assert res["eq42"]["modes"] == ["3S", "R1S3", "R2S1", "R3S1"]
    assert all(v for r in res.values() if isinstance(r, dict) for k, v in r.items() if k.startswith("check_"))


def test_geometric_scene_file(capsys):
    # the bundled geometric example: a box pushed right and down by a finger tip slides (3S)
    from pathlib import Path

    path = Path(__file__).parents[2] / "examples" / "scenes" / "box_and_finger.toml"
    code, out, _ = run(["modes", str(path), "--json"], capsys)
    doc = json.loads(out)
    assert code == 0 and [f["mode"] for f in doc["feasible"]] == ["SSS"]
    f = doc["feasible"][0]
    assert f["qdot"][0] > 0 and abs(f["qdot"][2]) < 1e-12 and len(f["joint_efforts"]) == 1


def test_no_feasible_mode_with_undecided_modes_is_not_called_a_jam():
    from qsplan.mechanics import SolveResult
    from qsplan.mechanics.model.scene_io import scene_from_dict
    from qsplan.mechanics.numerics import Status
    from qsplan.planner.reports.solve_report import format_solve_result

    scene = scene_from_dict(eq42_scene(0.5))
    counts = dict.fromkeys(Status.ORDER, 0)
    counts.update(kinematics_singular=1, coulomb_violated=6)
    text = format_solve_result(SolveResult(scene=scene, modes_tested=7, solutions=(), counts=counts))
    assert "not a proven jam" in text and "the scene jams" not in text
    counts.update(kinematics_singular=0, coulomb_violated=7)
    assert "the scene jams" in format_solve_result(SolveResult(scene=scene, modes_tested=7, solutions=(), counts=counts))
