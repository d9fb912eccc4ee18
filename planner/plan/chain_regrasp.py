"""Regrasps of a described hand: release, reposition and re-contact in joint space through OMPL (Section 5.2).

The workpiece rests on the palm (its centroid over its bottom edge) while both fingers let go: each
finger's closing joint opens (:data:`OPENING`, against its closing direction), OMPL plans a
collision-free motion of all joints to the new grasp opened, and the fingers close.  Every leg is
planned by :func:`qsplan.planner.search.ompl_bridge.plan_path` over the joint box with validity
"inside the limits and no two bodies overlapping" (the fingers may touch the workpiece, within the
contact tolerance, :func:`qsplan.planner.plan.chain_states.free_problem`); the lines between the
exported rows are checked again every :data:`ROW_STEP` of joint motion.  Units SI.
"""

from __future__ import annotations

import numpy as np

from qsplan.planner.plan.chain_states import free_problem
from qsplan.planner.plan.failure import configuration_report
from qsplan.planner.plan.results import PlanFailure, RegraspPlan

__all__ = ["OPENING", "ROW_STEP", "chain_regrasp", "opening_vector"]

#: How far each finger's closing joint opens to let go (rad for a revolute joint, m for a prismatic one):
#: 0.1 rad is about 7 mm at the tip of a 7 cm link; 5 mm of jaw travel.  Both far above the contact tolerance
#: and small beside the fingers.
OPENING = {"revolute": 0.1, "prismatic": 0.005}

#: Joint motion (rad or m) between the states at which the lines between exported rows are checked again:
#: 0.005 rad moves a point 10 cm out by 0.5 mm, the in-contact sweeps' sample spacing.
ROW_STEP = 0.005


def opening_vector(hand, q) -> np.ndarray:
    """Joint offsets (n_j,) that open both fingers' closing joints from ``q`` (against their closing directions)."""
    from qsplan.hands.closing import closing_direction

    man, lim = hand.manipulator, hand.description.joint_limits
    out = np.zeros(man.n_joints)
    for f, side in enumerate((1.0, -1.0)):
        k = hand.finger_joints(f)[-1]
        qm = np.array(q, dtype=float)
        qm[k] = 0.5 * (lim[k, 0] + lim[k, 1])
        out[k] = -closing_direction(man, qm, k, side) * OPENING[man.joints[k].kind]
    return out


def chain_regrasp(task, name, x, q_from, q_to, t0, options, progress, counters) -> RegraspPlan:
    """The regrasp from grasp ``q_from`` to grasp ``q_to`` (n_j,) with the workpiece at ``x`` (see the module docstring).

    Raises
    ------
    PlanFailure
        Naming the leg that has no collision-free motion or the row line that collides.
    """
    from qsplan.planner.search.ompl_bridge import plan_path

    progress(name)
    hand, lim = task.hand, task.joint_limits
    q, q_to = np.asarray(q_from, float), np.asarray(q_to, float)
    q_open, q_to_open = q + opening_vector(hand, q), q_to + opening_vector(hand, q_to)
    legs = [(q, q_open, "the opening"), (q_open, q_to_open, "the move to the new grasp"), (q_to_open, q_to, "the closing")]
    results, path = [], [q[None, :]]
    for a, b, what in legs:
        res = plan_path(lim[:, 0], lim[:, 1], a, b, lambda s: free_problem(task, x, s) is None, options)
        counters[0] += res.validity_checks
        counters[1] += res.seconds
        progress(f"  OMPL: {what} of the fingers: {res.status}, {len(res.path)} states in {res.seconds:.2f} s")
        if not res.exact:
            raise PlanFailure(configuration_report(task, name, f"{what} of the fingers", x, None,
                                                   f"OMPL found no collision-free finger motion ({res.status})",
                                                   res.status))  # fmt: skip
        results.append(res)
        path.append(res.path[1:])
    path = np.vstack(path)
    for a, b in zip(path[:-1], path[1:]):  # the controller moves on straight lines between rows: check them again
        n = max(1, int(np.ceil(np.max(np.abs(b - a)) / ROW_STEP)))
        for s in np.linspace(0.0, 1.0, n + 1)[1:-1]:
            why = free_problem(task, x, a + s * (b - a))
            if why:
                raise PlanFailure(configuration_report(task, name, "a state between OMPL's states", x, None, why,
                                                       results[-1].status))  # fmt: skip
    steps = np.max(np.abs(np.diff(path, axis=0)) / task.joint_speeds[None, :], axis=1)  # each line at the slowest joint's pace
    t = t0 + np.concatenate([[0.0], np.cumsum(steps)])
    qd = np.vstack([np.diff(path, axis=0) / np.maximum(np.diff(t), 1e-12)[:, None], np.zeros((1, len(q)))])
    return RegraspPlan(name, float(x), t, path, qd, tuple(results))
