"""The reorientation route (issue 23): slide to the flush instant, a certified hold, the pivot, planned from the
demo's start and ``[goal] theta = -0.5`` alone; its rows' contacts rebuilt from the polygons, its transition and
hold checked at their edges against the all-modes solver and the hold proof, its export and certificate."""

from __future__ import annotations

import json

import numpy as np
import pytest

from qsplan.hands.contacts.found import ordered_contacts, row_contact_scene
from qsplan.hands.formations.pivots import pivot_formations
from qsplan.mechanics import solve_many
from qsplan.mechanics.bands.hold import hold_torque_interval, prove_hold
from qsplan.planner.certify.rows import friction_points
from qsplan.planner.plan.results import PlanFailure
from qsplan.planner.plan.scripted import plan_task

#: Seeded random friction vectors checked besides the friction box's vertices.
N_RANDOM = 20


@pytest.fixture(scope="module")
def task():
    from tests.planner.bundled import bundled_task

    return bundled_task("reorient_task")


@pytest.fixture(scope="module")
def plan(task):
    from tests.planner.bundled import planned

    return planned("reorient_task")


def _contacts(task, ph, k):
    pose = ph.poses(task.hand.rest_height)[k]
    return ordered_contacts(task.hand, pose, ph.q[k])


def test_the_route_is_slide_hold_pivot(task, plan):
    assert [p.kind for p in plan.phases] == ["slide", "hold", "pivot"]
    slide, hold, pivot = plan.phases
    start = pivot_formations(task.hand)[0][1]  # the clockwise pivot's flush instant (x, y, 0, q)
    assert slide.x[-1] == start[0] and np.array_equal(slide.q[-1], start[3:])  # the slide ends at the flush instant
    assert len(_contacts(task, slide, slide.t.size - 1)) == 5 and len(_contacts(task, slide, slide.t.size - 2)) == 4
    assert set(slide.modes()) == {"SSSS"}  # its last row judged for the motion that reaches it: four contacts
    assert np.ptp(hold.q, axis=0).max() == 0 and np.ptp(hold.poses(0.0), axis=0).max() == 0  # nothing moves
    assert hold.modes() == ("RRRRR",) * hold.t.size and np.all(hold.speed_scale == 0)
    assert hold.command[0] == slide.command[-1] and hold.command[-1] == pivot.command[0]  # no torque step
    assert pivot.modes()[0] == "BSSSS" and set(pivot.modes()[1:]) == {"SSSS"}
    for ph in plan.phases:  # every row's letters follow the contacts the polygons show there (the slide's last row:
        for k in range(ph.t.size):  # all but the one it makes)
            made = ph is slide and k == ph.t.size - 1
            assert len(_contacts(task, ph, k)) - made == len(ph.modes()[k]), (ph.name, k)
    pose = pivot.poses(task.hand.rest_height)
    assert pose[0, 2] == 0.0 and pose[-1, 2] == task.goal.theta and np.all(np.diff(pose[:, 2]) < 0)
    assert np.all(pivot.width >= task.torque_resolution) and np.all(pivot.margin > 0)
    plan.check()


def test_the_hold_band_is_the_proved_interval_and_its_edges_are_sharp(task, plan):
    hold = plan.phases[1]
    pose = hold.poses(task.hand.rest_height)[0]
    scene = row_contact_scene(task.hand, pose, hold.q[0], [False, True], [0.0, 0.0])
    lo, hi = hold_torque_interval(scene, task.disturbance, margin=task.force_margin.normal)
    assert (hold.lower[0], hold.upper[0]) == (lo, hi) and np.isinf(hi)
    assert lo < hold.command.min() and hold.command.max() < hi
    margin = task.force_margin.normal  # the band: where the hold is proved with every contact loaded by this much
    for tau in (hold.command[0], hold.command[-1], lo + 1e-6, 1e3):  # the ramp's ends, the edge, far along
        proof = prove_hold(scene, torques=[tau], disturbance=task.disturbance)
        assert proof.proved and proof.margin >= margin - 1e-9
    assert prove_hold(scene, torques=[lo - 1e-3], disturbance=task.disturbance).margin < margin


@pytest.mark.parametrize("where", ["lower edge", "command", "far"])
def test_the_transition_row_has_its_mode_alone_against_the_all_modes_solver(task, plan, where):
    from dataclasses import replace

    pivot = plan.phases[2]
    pose = pivot.poses(task.hand.rest_height)
    chord = pivot.q[1] - pivot.q[0]  # the motion that leaves the row at rest
    tau = {"lower edge": pivot.lower[0] + 1e-6, "command": pivot.command[0], "far": pivot.command[0] + 100.0}[where]
    scene = row_contact_scene(task.hand, pose[0], pivot.q[0], [False, True], [chord[0], np.nan], effort=[0.0, tau])
    assert len(scene.contact_names) == 5
    mus = friction_points(task, N_RANDOM, np.random.default_rng(3), 5)  # the box's 32 vertices, then seeded draws
    for w in task.disturbance.vertices():
        sv = solve_many(replace(scene, g_obj=scene.g_obj + w), mus)
        feasible = sv.codes == 0
        j = sv.letters.index("BSSSS")
        assert feasible[:, j].all(), where
        assert feasible.sum(axis=1).max() == 1, where  # no competitor at any friction vector
        held = sv.c_n[:, j][:, 1:]  # palm:0 lifts (B); the others carry at least the force margin
        assert held.min() >= task.force_margin.normal - 1e-9, where


def test_export_names_each_phases_contacts_and_fills_the_pose(tmp_path, plan):
    from qsplan.planner.export.plan_files import export_plan, read_plan_csv
    from qsplan.planner.export.schema import check_schedule_files

    export_plan(plan, tmp_path)
    assert check_schedule_files(tmp_path / "plan.json", tmp_path / "plan.csv") == []
    doc = json.loads((tmp_path / "plan.json").read_text())
    phases = doc["metadata"]["phases"]
    assert [p["phase_kind"] for p in phases] == ["slide", "hold", "pivot"]
    assert phases[1]["contacts"] == ["palm:0", "palm:1", "left:base", "left:tip", "right"]
    assert phases[2]["contact_sets"][0] == {"rows": [0, 0], "contacts": phases[1]["contacts"], "mode": "BSSSS"}
    assert phases[2]["contact_sets"][1]["contacts"] == ["palm:1", "left:base", "left:tip", "right"]
    assert [s["kind"] for s in doc["metadata"]["sequence"]][-3:] == ["hold", "pivot", "search"]
    cols = read_plan_csv(tmp_path / "plan.csv")
    assert cols["theta_workpiece"][-1] == -0.5 and np.all(cols["theta_workpiece"][cols["phase"] < 2] == 0.0)


@pytest.mark.slow
def test_the_pivot_crosses_its_slip_reversal_through_a_hold_and_ends_where_its_band_closes(task):
    """The right contact's sliding reverses at -45.69 deg: the formation search cuts the pivot there and joins the
    pieces by a certified hold; the second piece's band falls below the resolution near -48.7 deg (issue 32)."""
    from dataclasses import replace

    longer = replace(task, goal=replace(task.goal, theta=-0.85))
    with pytest.raises(PlanFailure, match=r"the band is 0\.01\d+ N m wide at theta = -48\.\d+ deg"):
        plan_task(longer)
    ok = plan_task(replace(task, goal=replace(task.goal, theta=-0.79)))  # just short of the reversal: one piece
    assert ok.phases[-1].poses(0.0)[-1, 2] == -0.79 and [p.kind for p in ok.phases] == ["slide", "hold", "pivot"]


@pytest.fixture(scope="module")
def run(tmp_path_factory, task):
    from qsplan.planner.pipeline.run import run_plan

    return run_plan(task, tmp_path_factory.mktemp("reorient"), verify=3, plots=False)


@pytest.mark.slow
def test_certified_from_the_task_alone_and_re_simulated(run):
    cert = json.loads((run.out_dir / "certificate.json").read_text())
    assert cert["certified"] and run.certificate.ok
    holds = {h["row"] for h in cert["holds"]}
    hold_rows = [k for k, v in enumerate(run.certificate.rows) if set(v.mode) == {"R"}]
    assert set(hold_rows) <= holds and all(h["proved"] for h in cert["holds"])
    assert run.followed and len(run.replays) == 3
    for r in run.replays:
        assert [s.planned_mode for s in r.segments] == ["SSSS", "RRRRR", "SSSS"] and r.x_error < 1e-5


@pytest.mark.slow
@pytest.mark.parametrize("tamper, kind", [("letters", "contact"), ("moving hold", "mode"), ("hold torque", "torque")])
def test_tampered_turning_plans_are_refused(run, task, tmp_path, tamper, kind):
    import csv

    from qsplan.planner.certify.certify import certify_plan

    rows = list(csv.DictReader((run.out_dir / "plan.csv").open()))
    ph = [int(r["phase"]) for r in rows]
    pivot0, hold0 = ph.index(2), ph.index(1)
    if tamper == "letters":
        rows[pivot0 + 5]["mode"] = "SSSSS"
    elif tamper == "moving hold":
        rows[hold0 + 3]["q_left"] = repr(float(rows[hold0 + 3]["q_left"]) + 1e-3)
    else:
        rows[hold0 + 2]["tau_right"] = repr(float(rows[hold0 + 2]["tau_right_min"]) - 0.05)
    path = tmp_path / "plan.csv"
    with path.open("w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    cert = certify_plan(path, task, n_random=2)
    assert not cert.ok and cert.counts[kind] >= 1


@pytest.mark.slow
def test_mujoco_keeps_the_turning_plans_modes(run):
    """The exported plan executed in MuJoCo (compliant contacts, inertia, a 1 kHz controller, no stop added) at the
    friction box's two uniform corners: every row's planned letters on the scene's contact pairs (the lifted
    vertex 0 open), the workpiece within 0.1 mm."""
    pytest.importorskip("mujoco")
    from qsplan.planner.replay.mujoco_replay import replay_mujoco

    result = replay_mujoco(run.out_dir, mu=[[0.0] * 4, [0.2] * 4])
    for r in result.runs:
        assert r.modes_kept and not r.contacts_lost and r.max_error() < 1e-4
        pivot = r.phase == 2
        # palm:0 open on the pivot, the left finger's two contacts one pair, the upper feet (palm:2, palm:3) open
        assert set(r.planned[pivot][1:]) == {"BSSSBB"}


def test_the_pivot_with_the_left_finger_torque_controlled(task):
    """The other candidate of the widest-first choice: the left finger torque-controlled, the right one driven; its
    transition band is bounded above (the left finger pushes inward, issue 23: <= -2.72 N m without margin)."""
    from qsplan.hands.formations.pivots import pivot_path
    from qsplan.planner.plan.pivot import piece_phase, pivot_rate, pivot_thetas, widest_piece

    pivot, start = pivot_formations(task.hand)[0]
    path = pivot_path(task.hand, pivot, start, pivot_thetas(0.0, -0.2))
    rows = np.arange(path.theta.size)
    left = piece_phase(task, "left", pivot, path, rows, "left", pivot_rate(task, path, rows), True)
    assert left.effort_joint == "left" and np.isnan(left.qd[:, 0]).all() and np.isfinite(left.qd[:, 1]).all()
    assert np.isinf(left.lower[0]) and left.upper[0] < -2.72 and np.all(left.command < left.upper)
    assert np.all(left.width >= task.torque_resolution) and left.modes()[0] == "BSSSS"
    right = widest_piece(task, "right", pivot, path, rows, True)
    assert right.effort_joint == "right" and np.isinf(np.min(right.width))  # unbounded: nothing is wider