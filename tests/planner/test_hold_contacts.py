"""A hold at rest is proved with every contact present (issue 31: the palm-edge turn refused at its flush instant).

At a slide's last row the mode is judged for the motion that reaches it, which leaves out a contact it makes only
there (it opens along that motion); at rest that contact pushes as well as any other.  One rule,
:func:`qsplan.hands.contacts.found.hold_scene`, gives the planner's holds and the certifier's their contacts.

Checked against an independent method: a hold is proved iff every extreme ray of the admissible motions
``{x : A x >= 0}`` (enumerated from the rows of ``A`` without a programme) has negative power ``p . x`` (the loads'
work, eqs. 2-3) at every vertex of the disturbance box: any admissible motion is a nonnegative combination of them.
"""

from __future__ import annotations

from itertools import combinations, product

import numpy as np
import pytest
from qsplan.mechanics.bands.hold import hold_load, hold_matrix, hold_torque_interval, prove_hold

#: The palm-edge turn of ``benchmarks/mujoco_tasks/palm_edge.toml``: a pentagon pivoted onto another palm edge.
TASK = """
name = "a pentagon pivoted onto another palm edge, friction [0.05, 0.2]"
[hand]
file = "paper_hand"
workpiece = [[0.0, 0.0], [0.045, 0.0], [0.074, 0.0125], [0.060, 0.098], [0.007, 0.103]]
workpiece_mass = 0.2
[motion]
start_x = 0.0
[goal]
palm = "edge:1"
[friction]
range = [0.05, 0.2]
shared = false
[controller]
torque_resolution = 0.02
[limits]
left = [0.05, 3.09]
right = [0.05, 3.09]
joint_speed = 0.5
workpiece_speed = 0.01
"""

#: ``A x`` of a ray may be this far below 0 relative to ``|A| |x|`` (the SVD's rounding).
RAY_TOL = 1e-10


def _rays(A):
    """The extreme rays of ``{x : A x >= 0}`` (pointed at full column rank): null directions of ``m - 1`` independent
    rows that satisfy every other row, shape (r, m)."""
    n, m = A.shape
    out = []
    for rows in combinations(range(n), m - 1):
        _, s, vt = np.linalg.svd(A[list(rows)])
        if s[-1] < 1e-9 * s[0]:
            continue
        for d in (vt[-1], -vt[-1]):
            if np.all(A @ d >= -RAY_TOL * np.abs(A).max()):
                out.append(d)
    return np.array(out).reshape(-1, m)


def _worst_power(scene, tau, box):
    """The largest power ``p . x`` of the loads over the extreme rays (unit length) and the box's vertices: negative
    iff the hold is proved (the module docstring); ``inf`` for a rank-deficient ``A`` (a motion both ways)."""
    A = hold_matrix(scene)
    if np.linalg.matrix_rank(A) < A.shape[1]:
        return np.inf
    rays = _rays(A)
    rays = rays / np.linalg.norm(rays, axis=1, keepdims=True)
    W = [np.zeros(3)] if box is None else [np.array(v) for v in product(*zip(box.lo, box.hi))]
    return max(float(np.max(rays @ hold_load(scene, [tau], w))) for w in W)


@pytest.fixture(scope="module")
def flush_row(tmp_path_factory):
    """``(task, cols, k, certificate)``: the palm-edge turn planned and certified, and its slide's last row (at the
    flush instant)."""
    import tomllib

    from qsplan.planner.export.plan_files import read_plan_csv
    from qsplan.planner.pipeline.run import run_plan
    from qsplan.planner.task.task import task_from_record

    task = task_from_record(tomllib.loads(TASK))
    out = tmp_path_factory.mktemp("palm_edge") / "out"
    run = run_plan(task, out, verify=0, plots="none")
    assert run.certificate.ok, run.certificate.summary()  # refused before: "row 99 ... hold: nothing is proved"
    cols = read_plan_csv(out / "plan.csv")
    k = int(np.flatnonzero(cols["phase"] == 0)[-1])
    return task, cols, k, run.certificate


@pytest.mark.slow
@pytest.mark.ompl
def test_the_flush_instant_holds_with_the_contact_it_makes(flush_row):
    """At the slide's last row the mode leaves out one contact (made there); the hold with the four others is not
    proved at the row's torque and the hold with all five is, by the programme and by the extreme rays alike."""
    from qsplan.hands.contacts.found import hold_scene, row_contact_scene
    from qsplan.hands.described.records import joint_names
    from qsplan.planner.certify.contacts import judged_contacts
    from qsplan.planner.certify.rows import row_pose, row_q

    task, cols, k, cert = flush_row
    names = joint_names(task.hand)
    e = str(cols["effort_joint"][k])
    effort = np.array(names) == e
    tau = float(cols[f"tau_{e}"][k])
    pose, q = row_pose(cols, k), row_q(cols, k, names)
    found, drop = judged_contacts(task, cols, k)
    assert len(found) == 5 and int(np.sum(drop)) == 1  # the mode's four, and the contact the motion makes
    four = row_contact_scene(task.hand, pose, q, effort, np.zeros(len(names)), drop=drop, found=found)
    five = hold_scene(task.hand, pose, q, effort)
    assert five.n_contacts == 5 and four.n_contacts == 4
    box = task.disturbance
    assert not prove_hold(four, torques=[tau], disturbance=box).proved
    assert _worst_power(four, tau, box) >= 0.0  # a ray along which the loads do work: the refusal was right there
    assert prove_hold(five, torques=[tau], disturbance=box).proved
    assert _worst_power(five, tau, box) < 0.0
    record = next(h for h in cert.holds if h["row"] == k)
    assert record["proved"] and record["margin_N"] > 0


@pytest.mark.slow
@pytest.mark.ompl
def test_the_hold_interval_ends_where_a_ray_turns(flush_row):
    """The five-contact hold's torque interval (the planner's band at the flush instant) ends where the extreme rays'
    largest power crosses zero: 1e-6 N m inside every ray loses power, 1e-6 N m outside one gains it."""
    from qsplan.hands.contacts.found import hold_scene
    from qsplan.hands.described.records import joint_names
    from qsplan.mechanics.bands.hold import MARGIN_TOL
    from qsplan.planner.certify.rows import row_pose, row_q

    task, cols, k, _ = flush_row
    names = joint_names(task.hand)
    e = str(cols["effort_joint"][k])
    effort = np.array(names) == e
    five = hold_scene(task.hand, row_pose(cols, k), row_q(cols, k, names), effort)
    lo, hi = hold_torque_interval(five, task.disturbance, margin=1e3 * MARGIN_TOL)
    ends = [v for v in (lo, hi) if np.isfinite(v)]
    assert ends, "the interval is bounded on at least one side"
    for end in ends:
        inward = 1.0 if end == lo else -1.0
        assert _worst_power(five, end + inward * 1e-6, task.disturbance) < 0.0
        assert _worst_power(five, end - inward * 1e-6, task.disturbance) >= -1e-9


def test_a_chain_hand_holds_with_the_contacts_the_polygons_show():
    """The two-link hand: a hold's scene is the contacts the polygons show, in the canonical order (one path for
    every hand), the same points and normals as its grasp's closed contacts, every joint but the effort joint held."""
    from qsplan.hands.contacts.found import hold_scene
    from qsplan.hands.described.records import scene_at
    from qsplan.planner.states.contact import contact_samples
    from qsplan.planner.task.task import load_task, task_paths

    task = load_task(task_paths()["two_link_task"])
    joint = task.hand.joint_names[0]
    effort = np.array(task.hand.joint_names) == joint
    s = contact_samples(task, [task.start_x], joint, -0.01)
    scene = hold_scene(task.hand, s.pose[0], s.q[0], effort)
    grasp = scene_at(task.hand, s.pose[0], s.q[0], effort, s.qd[0])
    assert scene.contact_names == ("palm:0", "palm:1", "left", "right") and grasp.n_contacts == 4
    np.testing.assert_allclose(scene.Wn, grasp.Wn, atol=1e-12)
    np.testing.assert_allclose(scene.Jn, grasp.Jn, atol=1e-12)
    assert np.all(scene.joint_velocity[~effort] == 0.0)