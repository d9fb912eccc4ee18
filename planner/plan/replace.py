"""A finger lifted and replaced during a turn (issue 34, item 2).

A pivot keeps its other finger on one feature (:mod:`qsplan.hands.formations.pivots`); when that feature runs out
before the goal (the contact leaves its edge, a joint limit, two bodies meeting, no band), the turn can go on only
with the finger somewhere else.  At rest at some angle of the pivot:

1. **the hold with the finger lifted** (:func:`lifted_hold`): the workpiece rests on the pivot vertex and the flush
   finger alone, every joint held.  It is proved for every friction coefficient in the task's box, every wrench of its
   disturbance box (:func:`qsplan.mechanics.bands.friction_hold.prove_friction_hold`: an equilibrium inside the
   narrowest cones, and no motion for any coefficient of the box).  A box whose lower bound is 0 never proves it (the
   workpiece slides off the flush finger for free); the hold needs friction it can count on.  The scene is
   :func:`qsplan.hands.contacts.found.lifted_scene`, the certifier's rule too;
2. **the finger replaced** (:func:`replace_phase`): its closing joint opens (:data:`~qsplan.planner.plan.phases.
   OPENING`, the way that leaves the workpiece), its joints move through OMPL to the new grasp opened, and it closes;
   the other finger's joints do not move.  Every state collision-free, the lines between OMPL's states checked every
   :data:`~qsplan.planner.plan.phases.SWEEP_STEP` at the fingertips;
3. **the new grasp** (:func:`reclosings`): the same pivot vertex and flush finger, the finger on any feature of
   :data:`~qsplan.hands.formations.pivots.FINGER_FEATURES` it closes on at that pose without overlap and with exactly
   the pivot's four contacts, its free joints (a chain finger's all but its last) held at a new value from a grid over
   their limits (:data:`FREE_GRID`).

The formation search (:mod:`qsplan.planner.plan.turning`) uses these steps like its other edges: a route may turn on
one formation to an angle where the lifted hold is proved, replace the finger, hold while its torque is taken over,
and turn on with the new formation.  Units SI.
"""

from __future__ import annotations

import numpy as np

from qsplan.planner.plan.results import PlanFailure, ReplacePhase

__all__ = ["CLOSING_GRID", "FREE_GRID", "lifted_hold", "opening_direction", "reclosed", "reclosings", "replace_phase"]

#: Values of a chain finger's free joints tried for the new grasp, evenly over each joint's limits (the ends left out:
#: a joint held at its limit has no room).  24 steps of a 3 rad range are 7 deg apart: a held knuckle moves its pad by
#: 7 mm per step at 6 cm; finer grids found nothing more on the bundled hands.
FREE_GRID = 24

#: Values of the closing joint over its limits at which the new feature's gap is evaluated: Newton's method starts in
#: each interval where the gap changes sign (a finger can close on a feature from either side).  48 steps of a 5 rad
#: range are 6 deg: two roots closer than that are a feature grazed, not closed on.
CLOSING_GRID = 48


def lifted_hold(task, pose, q, finger: str):
    """Whether the workpiece at ``pose`` (m, m, rad) stays put with ``finger`` lifted and every joint held at ``q``: a
    :class:`qsplan.mechanics.bands.friction_hold.FrictionHold` over the task's friction box and disturbance box."""
    from qsplan.hands.contacts.found import lifted_scene
    from qsplan.mechanics.bands.friction_hold import prove_friction_hold
    from qsplan.mechanics.errors import QsplanError, SceneError

    try:
        scene = lifted_scene(task.hand, pose, q, finger)
    except (SceneError, QsplanError) as exc:
        from qsplan.mechanics.bands.friction_hold import FrictionHold

        return FrictionHold(False, f"no scene with the {finger} finger lifted: {exc}")
    return prove_friction_hold(scene, task.mu_range, disturbance=task.disturbance)


def opening_direction(task, pose, q, finger: str) -> np.ndarray:
    """Per joint -1, 0 or +1 (shape (n_j,)): ``finger``'s closing joint opened by its :data:`~qsplan.planner.plan.
    phases.OPENING` the way that leaves the workpiece at ``pose`` without overlap (tried both ways; the first that
    works, +1 first).

    Raises
    ------
    PlanFailure
        Neither way leaves the workpiece free of the finger.
    """
    from qsplan.hands.contacts.found import lifted_contacts
    from qsplan.planner.plan.failure import configuration_report
    from qsplan.planner.plan.phases import OPENING
    from qsplan.planner.states.contact import configuration_problem

    hand = task.hand
    j = hand.closing_joints[0 if finger == "left" else 1]
    q = np.asarray(q, dtype=float)
    for sign in (1.0, -1.0):
        d = np.zeros(q.size)
        d[j] = sign
        opened = q + d * OPENING[hand.joint_kinds[j]]
        if configuration_problem(task, pose, opened) is None and not lifted_contacts(hand, pose, opened, finger)[2].any():
            return d
    raise PlanFailure(configuration_report(task, f"the {finger} finger replaced", "its opening", float(pose[0]), q,
                                           f"the {finger} finger cannot open away from the workpiece either way",
                                           None, pose))  # fmt: skip


def replace_phase(task, name, pose, q_from, q_to, finger: str, t0, options, progress, counters) -> ReplacePhase:
    """``finger`` lifted from joints ``q_from`` and closed again at ``q_to`` (rad or m, shape (n_j,); the other
    finger's joints equal), the workpiece held at ``pose`` meanwhile (the module docstring).

    Raises
    ------
    PlanFailure
        The hold with the finger lifted is not proved (its reason), the finger cannot open away from the workpiece, or
        OMPL finds no collision-free motion (:func:`qsplan.planner.plan.phases.free_motion`).
    """
    from qsplan.hands.contacts.found import lifted_contacts
    from qsplan.planner.plan.failure import configuration_report
    from qsplan.planner.plan.phases import OPENING, free_motion

    progress(name)
    hand = task.hand
    pose = np.asarray(pose, dtype=float)
    q, q_to = np.asarray(q_from, dtype=float), np.asarray(q_to, dtype=float)
    mine = np.zeros(q.size, dtype=bool)
    mine[list(hand.finger_joints[0 if finger == "left" else 1])] = True
    if np.any(q[~mine] != q_to[~mine]):
        raise ValueError("replace_phase: the other finger's joints must not move")
    proof = lifted_hold(task, pose, q, finger)
    if not proof.proved:
        raise PlanFailure(configuration_report(task, name, "the hold with the finger lifted", float(pose[0]), q,
                                               f"the hold with the {finger} finger lifted is not proved over the "
                                               f"friction box: {proof.reason}", None, pose))  # fmt: skip
    amount = np.array([OPENING[k] for k in hand.joint_kinds])
    q_open = q + amount * opening_direction(task, pose, q, finger)
    q_to_open = q_to + amount * opening_direction(task, pose, q_to, finger)
    t, path, qd, results = free_motion(task, name, pose, q, q_open, q_to_open, q_to, t0, options, progress, counters,
                                       mine, f"the {finger} finger")  # fmt: skip
    _, names, lifted = lifted_contacts(hand, pose, q, finger)
    kept = tuple(n for n, off in zip(names, lifted) if not off)
    return ReplacePhase(name, float(pose[0]), t, path, qd, results, None, pose=pose, finger=finger, kept=kept,
                        hold_margin=float(proof.rest_margin))  # fmt: skip


def reclosings(task, pivot, pose, q) -> list:
    """Every new grasp of ``pivot``'s other finger at ``pose`` (the other joints as ``q`` has them): ``[(Pivot,
    configuration (x, y, theta, q))]``, the finger on each feature it closes on with its free joints held at each
    value of the grid (:data:`FREE_GRID`), without overlap and with exactly the pivot's four contacts, its point on
    its edge; the grasp ``q`` already has left out.  In a fixed order: features as the registry lists them, then the
    free joints' values, then the closing joint's."""
    from itertools import product

    from qsplan.hands.formations.manifold import gaps, project
    from qsplan.hands.formations.pivots import FINGER_FEATURES, Pivot

    hand = task.hand
    finger = pivot.other_finger
    joints = list(hand.finger_joints[0 if finger == "left" else 1])
    closing = hand.closing_joints[0 if finger == "left" else 1]
    free = [j for j in joints if j != closing]
    lim = np.asarray(task.joint_limits, dtype=float)
    grids = [np.linspace(lim[j, 0], lim[j, 1], FREE_GRID + 2)[1:-1] for j in free]
    base = np.concatenate([np.asarray(pose, dtype=float), np.asarray(q, dtype=float)])
    closings = np.linspace(lim[closing, 0], lim[closing, 1], CLOSING_GRID + 1)
    out, seen = [], {tuple(np.round(base, 9))}  # the grasp it has, and each new one once
    for kind, candidates in FINGER_FEATURES.items():
        for feature in candidates(hand, finger):
            other = Pivot(pivot.vertex, pivot.flush, pivot.edge, feature)
            cons = other.constraints(hand)
            for values in product(*grids) if free else [()]:
                c0 = base.copy()
                for j, v in zip(free, values):
                    c0[3 + j] = v
                g = []
                for v in closings:  # the feature's gap along the closing joint: a root in each change of sign
                    c0[3 + closing] = v
                    g.append(gaps(hand, cons[3:], c0)[0])
                g = np.asarray(g)
                for k in np.flatnonzero(np.isfinite(g[:-1]) & np.isfinite(g[1:]) & (np.sign(g[:-1]) != np.sign(g[1:]))):
                    c0[3 + closing] = 0.5 * (closings[k] + closings[k + 1])
                    c = project(hand, cons, c0, [3 + closing])
                    if c is None or tuple(np.round(c, 9)) in seen:
                        continue
                    seen.add(tuple(np.round(c, 9)))
                    if _closes(task, cons, c):
                        out.append((other, c))
    return out


def _closes(task, constraints, c) -> bool:
    """Whether configuration ``c`` (on a pivot's ``constraints``) is a grasp: the other finger's point on its edge, no
    joint beyond its limit and no overlap, and exactly the pivot's four contacts in the polygons."""
    from qsplan.hands.contacts.found import ordered_contacts
    from qsplan.hands.formations.manifold import along_edges
    from qsplan.mechanics.errors import SceneError
    from qsplan.planner.states.contact import configuration_problem

    if not 0.0 <= along_edges(task.hand, constraints, c)[3] <= 1.0 or configuration_problem(task, c[:3], c[3:]):
        return False
    try:
        return len(ordered_contacts(task.hand, c[:3], c[3:])) == 4
    except SceneError:
        return False


def reclosed(task, pivot, pose, q, grasp):
    """The new grasp ``grasp`` (a configuration :func:`reclosings` found, for ``pivot``) closed again from ``pose``, ``q``
    exactly: the other finger's joints and the pose as they are, the moving finger's free joints as ``grasp`` holds
    them, its closing joint by Newton's method from ``grasp``'s.  None when it does not close there (no
    configuration, or not a grasp: :func:`_closes`)."""
    from qsplan.hands.formations.manifold import project

    hand = task.hand
    fi = 0 if pivot.other_finger == "left" else 1
    c = np.concatenate([np.asarray(pose, dtype=float), np.asarray(q, dtype=float)])
    for j in hand.finger_joints[fi]:
        c[3 + j] = grasp[3 + j]
    cons = pivot.constraints(hand)
    c = project(hand, cons, c, [3 + hand.closing_joints[fi]])
    return c if c is not None and _closes(task, cons, c) else None
