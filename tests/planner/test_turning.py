"""The formation search that turns the workpiece (issue 32): generated formations, either direction, chains of pivots.

- The generic manifold (:mod:`qsplan.hands.formations.manifold`) against the paper hand's closed form, an independent
  derivation (``tests/reference/paper_pivot.py``): poses, joints and their rates, and where a contact's sliding
  reverses.
- The formations a hand and workpiece offer are generated, and named so that a reader (the certifier) can parse them.
- The demo mirrored (x -> -x) with theta = +0.5 rad plans the mirror image of ``reorient_task``'s plan: counter-
  clockwise on vertex 0, the right finger flush; joint angles ``pi - q`` of the other finger to 1e-9 rad.
- From the demo's start theta = -0.84 rad: the pivot's slip reversal at -45.69 deg is crossed by a hold between two
  pieces (slide, hold, pivot, hold, pivot), certified and re-simulated.
"""

from __future__ import annotations

import numpy as np
import pytest

from qsplan.hands.formations.manifold import VertexOnLine, constraint_jacobian, gaps, sweep
from qsplan.hands.formations.pivots import Pivot, VertexOnFinger, pivot_formations, pivot_from_name
from qsplan.planner.task.task import load_task, task_paths

#: The demo's workpiece, and the same reflected x -> -x (its vertices kept counter-clockwise).
DEMO = "workpiece = [[0.0, 0.0], [0.080, 0.0], [0.085, 0.080], [0.008, 0.100]]"
MIRRORED = "workpiece = [[-0.080, 0.0], [0.0, 0.0], [-0.008, 0.100], [-0.085, 0.080]]"

#: How close the mirrored plan's joint angles are to ``pi -`` the other finger's (rad): the two runs take the same
#: steps on mirrored numbers (the slide's closed forms, the pivot's Newton solves), rounding apart.
MIRROR_TOL = 1e-9


def _task(tmp_path, edits, name="turn.toml"):
    text = task_paths()["reorient_task"].read_text()
    for old, new in edits:
        assert old in text
        text = text.replace(old, new)
    path = tmp_path / name
    path.write_text(text)
    return load_task(path)


def test_the_generic_manifold_is_the_paper_hands_closed_form():
    from qsplan.hands.contacts.sets import finger_inner_edge, palm_top_edge
    from tests.reference.paper_pivot import flush_instant, pivot_configurations

    hand = load_task(task_paths()["reorient_task"]).hand
    inst = flush_instant(hand)
    k = inst.edge
    cons = (VertexOnLine("workpiece", 1, "palm", palm_top_edge(hand)),
            VertexOnLine("workpiece", k, "left", finger_inner_edge(hand, "left")),
            VertexOnLine("workpiece", (k + 1) % 4, "left", finger_inner_edge(hand, "left")),
            VertexOnLine("workpiece", inst.right_vertex, "right", finger_inner_edge(hand, "right")))  # fmt: skip
    theta = np.linspace(0.0, -0.79, 60)
    m = sweep(hand, cons, np.concatenate([inst.pose, inst.q]), 2, theta, free=[0, 1, 3, 4])
    ref = pivot_configurations(hand, theta, 1, k, inst.right_vertex)
    assert m.reached == theta.size
    np.testing.assert_allclose(m.pose, ref.pose, atol=1e-14)
    np.testing.assert_allclose(m.q, ref.q, atol=1e-13)
    np.testing.assert_allclose(m.dc[:, :3], ref.dpose, atol=1e-13)
    np.testing.assert_allclose(m.dc[:, 3:], ref.dq, atol=1e-12)


def test_the_generic_slip_reversal_is_the_closed_forms():
    """Where the generic search cuts the demo's pivot (a contact's sliding reverses, bisected on the generic manifold
    with the polygons' contacts) the closed form's right contact reverses its sliding (eq. 6 with the closed form's
    tangent), within the bisection's bracket, and no other contact does."""
    from qsplan.planner.plan.pivot import REVERSAL_TOL, pivot_geometry

    from tests.reference.paper_pivot import PIVOT, pivot_configurations, pivot_scene

    task = load_task(task_paths()["reorient_task"])
    hand = task.hand
    (pivot, start), _ = pivot_formations(hand)
    geometry = pivot_geometry(task, pivot, start, -0.84)
    assert geometry.end is None and len(geometry.cuts) == 1
    cut = geometry.cuts[0]
    assert np.degrees(cut) == pytest.approx(-45.69, abs=5e-3)

    def slips(theta):
        c = pivot_configurations(hand, [theta])
        scene, (dx, dy, dth), (x, y) = pivot_scene(hand, c, 0), c.dpose[0], c.pose[0, :2]
        nu = np.array([dx + dth * y, dy - dth * x, dth])  # the twist at the world origin per unit theta
        return scene.Wt.T @ nu - scene.Jt @ c.dq[0]

    # the cut lies on the bracket's far side: the zero is within REVERSAL_TOL before it (the turn is clockwise)
    before, after = np.sign(slips(cut + 2 * REVERSAL_TOL)), np.sign(slips(cut))
    assert [PIVOT.contact_names[j] for j in np.flatnonzero(before != after)] == ["right"]


def test_the_constraint_jacobian_is_the_gaps_derivative():
    """Finite differences of the gaps (central, 1e-7) against eq. 6's rows, at a pivot configuration."""
    hand = load_task(task_paths()["reorient_task"]).hand
    (pivot, start), _ = pivot_formations(hand)
    cons = pivot.constraints(hand)
    c = np.array(start, dtype=float)
    c[2] = -0.2  # off the manifold: the derivative holds anywhere
    J = constraint_jacobian(hand, cons, c)
    h = 1e-7
    fd = np.column_stack([(gaps(hand, cons, c + h * e) - gaps(hand, cons, c - h * e)) / (2 * h) for e in np.eye(c.size)])
    np.testing.assert_allclose(J, fd, atol=1e-8)


def test_the_demo_offers_a_pivot_each_way_named_for_a_reader():
    hand = load_task(task_paths()["reorient_task"]).hand
    found = pivot_formations(hand)
    names = [p.name for p, _ in found]
    assert names == ["pivot:v1:left:e3:vertex2", "pivot:v0:right:e1:vertex3"]
    assert [p.direction for p, _ in found] == [-1.0, 1.0]
    assert all(pivot_from_name(p.name, hand) == p for p, _ in found)
    assert pivot_from_name("palm_edge", hand) is None and pivot_from_name("pivot:v1:up:e3:vertex2", hand) is None
    assert pivot_from_name("pivot:v1:left:e3:vertex9", hand) is None  # no vertex 9 on this workpiece
    for p, c in found:  # each flush instant: the five constraints closed, theta 0, on the palm
        assert np.max(np.abs(gaps(hand, p.flush_constraints(hand), c))) < 1e-14 and c[2] == 0.0


def test_the_mirror_image_of_a_turn_is_its_mirrored_plan(tmp_path, bundled_plan):
    """The acceptance's mirror: the demo reflected, theta = +0.5 rad: counter-clockwise on vertex 0, every joint angle
    the other finger's ``pi - q`` to :data:`MIRROR_TOL`, every time equal, every torque negated."""
    from qsplan.planner.export.plan_files import export_plan, read_plan_csv
    from qsplan.planner.plan.scripted import plan_task

    task = _task(tmp_path, [(DEMO, MIRRORED), ("\ntheta = -0.5", "\ntheta = 0.5")])
    plan = plan_task(task)
    export_plan(plan, tmp_path / "mirror")
    b = read_plan_csv(tmp_path / "mirror" / "plan.csv")
    a = read_plan_csv(bundled_plan("reorient_task") / "plan.csv")
    assert a["t"].size == b["t"].size and [p.kind for p in plan.phases] == ["slide", "hold", "pivot"]
    np.testing.assert_allclose(b["q_left"], np.pi - a["q_right"], atol=MIRROR_TOL, rtol=0)
    np.testing.assert_allclose(b["q_right"], np.pi - a["q_left"], atol=MIRROR_TOL, rtol=0)
    np.testing.assert_allclose(b["t"], a["t"], atol=MIRROR_TOL, rtol=0)
    np.testing.assert_allclose(b["x_workpiece"], -a["x_workpiece"], atol=MIRROR_TOL, rtol=0)
    np.testing.assert_allclose(b["theta_workpiece"], -a["theta_workpiece"], atol=MIRROR_TOL, rtol=0)
    mirrored = {"left": "right", "right": "left"}
    assert [mirrored[e] for e in a["effort_joint"]] == list(b["effort_joint"])
    tau_a = np.array([a[f"tau_{e}"][k] for k, e in enumerate(a["effort_joint"])])
    tau_b = np.array([b[f"tau_{e}"][k] for k, e in enumerate(b["effort_joint"])])
    np.testing.assert_allclose(tau_b, -tau_a, atol=1e-9, rtol=0)
    assert plan.phases[-1].formation == "pivot:v0:right:e1:vertex3"


@pytest.mark.slow
def test_a_turn_past_the_slip_reversal_chains_two_pivots_through_a_hold(tmp_path):
    """theta = -0.84 rad from the demo's start: slide, hold, pivot to the slip reversal (-45.69 deg), hold, pivot;
    certified from the task alone and re-simulated at the friction set's extremes."""
    from qsplan.planner.pipeline.run import run_plan

    task = _task(tmp_path, [("\ntheta = -0.5", "\ntheta = -0.84")])
    run = run_plan(task, tmp_path / "out", verify=2, plots=False)
    assert [(p.kind, p.formation) for p in run.plan.phases] == [
        ("slide", "palm_edge"), ("hold", "pivot:v1:left:e3:vertex2"), ("pivot", "pivot:v1:left:e3:vertex2"),
        ("hold", "pivot:v1:left:e3:vertex2"), ("pivot", "pivot:v1:left:e3:vertex2")]  # fmt: skip
    cut = run.plan.phases[2].pose[-1, 2]
    assert np.degrees(cut) == pytest.approx(-45.69, abs=0.01) and run.plan.phases[4].pose[-1, 2] == -0.84
    assert run.certificate.ok and run.followed
    steps = [s.kind for s in run.plan.sequence]
    assert steps[:5] == ["slide", "hold", "pivot", "hold", "pivot"]


def test_a_pivot_without_a_registered_name_is_refused_by_name():
    hand = load_task(task_paths()["reorient_task"]).hand
    assert Pivot(1, "left", 3, VertexOnFinger(2)).words(hand) == (
        "pivot on vertex 1 (clockwise), the left finger flush on edge 3, the right finger on vertex 2")
