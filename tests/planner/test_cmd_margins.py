"""``--min-normal`` / ``--min-slack`` of ``qsplan band`` and ``qsplan sweep``: the margins reach the bands and the files."""

import json

import numpy as np
import pytest

from qsplan.mechanics import planted_scene
from qsplan.mechanics.bands.effort import ForceMargin
from qsplan.mechanics.bands.guaranteed import guaranteed_band_box, guaranteed_band_shared
from qsplan.mechanics.model.scene_io_write import scene_to_dict
from qsplan.planner.cli.main import main

SWEEP = ["sweep", "--samples", "11", "--no-plots", "--json"]


def run(args, capsys):
    code = main(args)
    out, err = capsys.readouterr()
    return code, out, err


@pytest.fixture()
def scene_file(tmp_path):
    scene, mode = planted_scene(np.random.default_rng(3), 3, 1, mu_range=(0.3, 0.4))  # RSS, bounded bands
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(scene_to_dict(scene)))
    return str(path), scene, mode


def test_band_without_margins_prints_what_it_did_before(scene_file, capsys):
    path, scene, mode = scene_file
    args = ["band", path, "--mode", mode.letters, "--mu-range", "0.3", "0.4"]
    plain = run(args + ["--json"], capsys)
    zero = run(args + ["--json", "--min-normal", "0", "--min-slack", "0"], capsys)
    assert plain == zero and plain[0] == 0
    assert "min_normal_force" not in json.loads(plain[1])
    assert run(args, capsys) == run(args + ["--min-normal", "0"], capsys)


@pytest.mark.parametrize("shared", [False, True])
def test_band_with_margins_is_the_library_band(scene_file, capsys, shared):
    path, scene, mode = scene_file
    fm = ForceMargin(0.05, 0.02)
    args = ["band", path, "--mode", mode.letters, "--mu-range", "0.3", "0.4", "--min-normal", "0.05", "--min-slack", "0.02"]
    code, out, err = run(args + ["--json"] + (["--shared-mu"] if shared else []), capsys)
    assert code == 0 and err == ""
    doc = json.loads(out)
    ref = (guaranteed_band_shared if shared else guaranteed_band_box)(scene, mode, 0.3, 0.4, force_margin=fm)
    plain = (guaranteed_band_shared if shared else guaranteed_band_box)(scene, mode, 0.3, 0.4)
    assert ref.feasible and doc["feasible"] and doc["min_normal_force"] == 0.05 and doc["min_coulomb_slack"] == 0.02
    assert (doc["lower"], doc["upper"]) == (ref.lower, ref.upper)
    assert plain.lower < ref.lower < ref.upper < plain.upper
    code, out, _ = run(args + (["--shared-mu"] if shared else []), capsys)
    assert code == 0 and "with c_n >= 0.05 N and Coulomb slacks >= 0.02 N" in out


@pytest.mark.parametrize("option, value", [("--min-normal", "-1"), ("--min-slack", "nan"), ("--min-normal", "inf")])
def test_bad_margin_is_one_line_exit_2(scene_file, capsys, tmp_path, option, value):
    path, _, mode = scene_file
    for args in (["band", path, "--mode", mode.letters], ["sweep", "--samples", "3", "--no-plots", "--out", str(tmp_path / "o")]):
        code, out, err = run(args + [option, value], capsys)
        assert code == 2 and out == "" and err.count("\n") == 1
        assert f"{option}: expected a nonnegative finite force (N)" in err
    assert not (tmp_path / "o").exists()


def test_sweep_records_the_margin_and_narrows_every_band(tmp_path, capsys):
    code, out, _ = run(SWEEP + ["--out", str(tmp_path / "a")], capsys)
    plain = json.loads(out)
    assert code == 0 and plain["force_margin"] == {"min_normal_force_N": 0.0, "min_coulomb_slack_N": 0.0}
    code, out, _ = run(SWEEP + ["--out", str(tmp_path / "b"), "--min-normal", "0.05"], capsys)
    kept = json.loads(out)
    assert code == 0 and kept["force_margin"] == {"min_normal_force_N": 0.05, "min_coulomb_slack_N": 0.0}
    assert kept["guaranteed"]["narrowest"]["width"] < plain["guaranteed"]["narrowest"]["width"]
    docs = [json.loads((tmp_path / d / "segment1.json").read_text()) for d in "ab"]
    assert docs[0]["metadata"]["band"]["force_margin"]["min_normal_force_N"] == 0.0
    assert docs[1]["metadata"]["band"]["force_margin"]["min_normal_force_N"] == 0.05
    lo = [np.array([np.nan if v is None else v for v in d["data"]["tau_right_min"]]) for d in docs]
    hi = [np.array([np.inf if v is None else v for v in d["data"]["tau_right_max"]]) for d in docs]
    assert np.all(lo[1] >= lo[0]) and np.all(hi[1] <= hi[0])  # a margin only narrows


TASK = ("[hand]\nworkpiece = [[0,0],[0.08,0],[0.085,0.08],[0.008,0.1]]\n[motion]\nstart_x = 0.0\nwaypoints = [-0.01]\n"
        "[controller]\ntorque_resolution = 0.02\n")  # fmt: skip


def test_task_force_margin_defaults_and_fields(tmp_path):
    from qsplan.planner.task.fields import PLAN_FORCE_MARGIN
    from qsplan.planner.task.task import load_task

    p = tmp_path / "t.toml"
    p.write_text(TASK)
    assert load_task(p).force_margin == PLAN_FORCE_MARGIN and PLAN_FORCE_MARGIN.normal > 0
    p.write_text(TASK + "min_normal_force = 0.1\n")
    assert load_task(p).force_margin == ForceMargin(0.1, PLAN_FORCE_MARGIN.slack)
    p.write_text(TASK + "min_normal_force = 0\nmin_coulomb_slack = 0\n")
    assert load_task(p).force_margin.is_zero


@pytest.mark.parametrize("line, match", [
    ("min_normal_force = -0.1", r"controller\.min_normal_force: expected a nonnegative finite force \(N\); got -0\.1"),
    ("min_coulomb_slack = 'x'", r"controller\.min_coulomb_slack: expected a nonnegative finite force"),
    ("min_coulomb_slack = nan", r"controller\.min_coulomb_slack"),
    ("min_normal_forse = 0.1", r"controller\.min_normal_forse: unknown field"),
])  # fmt: skip
def test_task_force_margin_validation(tmp_path, line, match):
    from qsplan.mechanics import QsplanError
    from qsplan.planner.task.task import load_task

    p = tmp_path / "t.toml"
    p.write_text(TASK + line + "\n")
    with pytest.raises(QsplanError, match=match):
        load_task(p)


@pytest.mark.ompl
def test_planned_bands_keep_the_margin_at_their_edges(tmp_path):
    """A one-segment plan: metadata records the margin, and just inside every exported band edge the
    all-modes solver at the friction box's corners finds 4S with every normal force at least the margin."""
    from dataclasses import replace
    from itertools import product

    from tests.planner.rest_rows import moving_velocity

    from qsplan.hands import hand_scene
    from qsplan.mechanics import solve
    from qsplan.planner.export.plan_files import export_plan, read_plan_csv
    from qsplan.planner.plan.scripted import plan_task
    from qsplan.planner.task.task import load_task

    p = tmp_path / "t.toml"
    p.write_text(TASK + "min_normal_force = 0.08\n")
    task = load_task(p)
    export_plan(plan_task(task), tmp_path / "out")
    meta = json.loads((tmp_path / "out" / "plan.json").read_text())["metadata"]
    assert meta["force_margin"]["min_normal_force_N"] == 0.08
    d = read_plan_csv(tmp_path / "out" / "plan.csv")
    lo, hi = task.mu_range
    worst, checked = np.inf, 0
    for k in np.flatnonzero(d["mode"] == "SSSS")[::4]:
        e = str(d["effort_joint"][k])
        v = "left" if e == "right" else "right"
        pose = np.array([d["x_workpiece"][k], d["y_workpiece"][k], d["theta_workpiece"][k]])
        q = np.array([d["q_left"][k], d["q_right"][k]])
        for tau in (d[f"tau_{e}_min"][k] + 1e-9, d[f"tau_{e}_max"][k] - 1e-9):
            if not np.isfinite(tau):
                continue
            # a row at rest (qd 0): the direction of the motion that leaves or reaches it, the adjacent row's
            nb = k + 1 if k + 1 < len(d["t"]) and d["phase"][k + 1] == d["phase"][k] else k - 1
            speed = float(d[f"qd_{v}"][k]) or float(np.sign(d[f"q_{v}"][max(k, nb)] - d[f"q_{v}"][min(k, nb)]))
            calm = hand_scene(task.hand.paper, pose, q, e, velocity=speed, effort=float(tau))
            # the bands withstand the task's disturbance box (the time scaling's inertial load): the margin is
            # reached at the worst of its vertices
            for w in task.disturbance.vertices():
                scene = replace(calm, g_obj=calm.g_obj + w)
                for mu in product((lo, hi), repeat=4):
                    sol = solve(scene.with_mu(np.array(mu)), residuals=False, workers=1, search="all").solution("SSSS")
                    worst = min(worst, -np.inf if sol is None else float(sol.c_n.min()))
                    checked += 1
    assert checked >= 100
    assert 0.08 - 1e-7 <= worst < 0.08 + 1e-3  # held everywhere, and reached at an edge
