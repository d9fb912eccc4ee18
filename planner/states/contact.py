"""Judging configurations of a two-finger task: in contact (mode 4S, guaranteed band) and in free space.

:func:`check_contact_state` is OMPL's validity checker of an in-contact segment (no
overlap between any two bodies, the same four contacts, the 4S kinematics of eqs. 24-25, joint limits, and
a guaranteed band with every competitor precluded at least the torque resolution wide);
:func:`check_free_state` that of a regrasp (the fingers clear the workpiece, the palm
and each other).  Both judge the geometry with :func:`configuration_problem`: joint
limits, and every pair of bodies of the hand's polygons (fingers, palm, workpiece)
for overlap.  Units SI (m, rad, s, N m).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qsplan.mechanics.errors import QsplanError

from qsplan.planner.task.task import Task

__all__ = ["TOUCH_AREA", "StateCheck", "check_contact_state", "check_free_state", "configuration_problem",
           "contact_samples", "free_state_problem", "limit_problem", "mode_name"]

#: Intersection area (m^2) below which two polygons only touch (kept for callers; the checks now measure
#: overlaps by depth: :data:`qsplan.hands.geometry.collision.CONTACT_DEPTH_TOL`).
TOUCH_AREA = 1e-10

def mode_name(letters: str) -> str:
    """The paper's name of a mode (four S -> ``"4S"``, ``"RBSS"`` -> ``"R1S3"``: :attr:`ContactMode.name`)."""
    from qsplan.mechanics.modes.contact_mode import ContactMode

    return ContactMode(letters).name


@dataclass(frozen=True, slots=True)
class StateCheck:
    """One configuration of an in-contact segment, judged.

    Attributes
    ----------
    x : float
        Workpiece x (m).
    ok : bool
    reason : str or None
        Why not, in words.
    lower, upper : float
        Guaranteed band (N m), NaN without one.
    desired_lower, desired_upper : float
        The desired mode's guaranteed band before precluding competitors (N m).
    competitors : tuple of str
        Competing modes possible inside the desired mode's band (they cut it).
    """

    x: float
    ok: bool
    reason: str | None
    lower: float = np.nan
    upper: float = np.nan
    desired_lower: float = np.nan
    desired_upper: float = np.nan
    competitors: tuple = ()

    @property
    def width(self) -> float:
        return float(self.upper - self.lower) if np.isfinite(self.lower) or np.isfinite(self.upper) else np.nan


def contact_samples(task, xs, effort_joint, speed, name="segment", grasp=None, free=None, free_rates=None):
    """The configurations at workpiece ``xs`` (m, shape (n,)) moving at ``speed`` (m/s, signed) as
    :class:`qsplan.hands.paper_hand.segments.SegmentSamples` (times 0, 1, ...: bands do not depend on them), from the
    hand (:meth:`qsplan.hands.protocol.Hand.slide_motion`).

    ``grasp``: the features the fingers touch (a grasp of :meth:`~qsplan.hands.protocol.Hand.grasp_candidates`);
    None: the paper hand's default, both inner edges on the vertices of tangency (the scripted tasks).  ``free``
    (n, n_free) and ``free_rates`` (n, n_j): a described hand's free joints along the slide and their rates
    (rad/s or m/s at ``speed``; default the grasp's, held).  ``effort_joint``: the effort-controlled joint's name.

    Raises
    ------
    qsplan.mechanics.SceneError
        Where a configuration has no four-contact grasp.
    """
    from qsplan.hands.paper_hand.segments import ManipulationSegment, SegmentSamples

    hand = task.hand
    xs = np.atleast_1d(np.asarray(xs, float))
    m = hand.slide_motion(task.formation, grasp, xs, speed, hand.joint_names.index(effort_joint), free, free_rates)
    n = len(xs)
    seg = ManipulationSegment(hand, name, m.poses[0], m.poses[-1], float(max(n - 1, 1)), task.formation.mode,
                              effort_joint)  # fmt: skip
    return SegmentSamples(seg, np.arange(n, dtype=float), np.linspace(0.0, 1.0, n), m.poses, m.q, m.qd, m.touching,
                          tuple(m.scenes))  # fmt: skip


def limit_problem(task, q) -> str | None:
    """Which joint of ``q`` (rad or m, shape (n_j,)) is beyond its limit, in words, or None."""
    lim, hand = task.joint_limits, task.hand
    units = hand.joint_units()
    for k, name in enumerate(hand.joint_names):
        if lim[k, 0] <= q[k] <= lim[k, 1]:
            continue
        u = units[k]
        finger = any(f == (k,) for f in hand.finger_joints)  # a finger of one joint: the paper's words
        what = f"the {name} finger's angle" if finger and u == "rad" else f"joint {name} at"
        return (f"joint limits: {what} {q[k]:.4g} {u} is outside its limits [{lim[k, 0]:g}, {lim[k, 1]:g}] {u} "
                f"(q = {np.round(q, 4).tolist()}{' rad' if set(units) == {'rad'} else ''})")  # fmt: skip
    return None


def configuration_problem(task, pose, q) -> str | None:
    """What is wrong with the hand at workpiece ``pose`` (shape (3,)) and joints ``q`` (rad, shape (2,)),
    in words, or None: a joint beyond its limit, or two bodies overlapping (every pair of the palm, the
    fingers and the workpiece: :func:`qsplan.hands.geometry.collision.find_collisions`)."""
    q = np.asarray(q, float)
    why = limit_problem(task, q)
    if why:
        return why
    hit = task.hand.collisions(pose, q, first=True)
    return hit[0].message if hit else None


def check_contact_state(task: Task, x: float, effort_joint: str, direction: float, touching=None,
                        competitors=None, grasp=None, free=None, free_slope=None) -> StateCheck:  # fmt: skip
    """Judge workpiece ``x`` (m) of an in-contact segment moving in ``direction`` (sign of xdot).

    Valid when the four contacts are found (the same finger vertices as ``touching``),
    the joints are inside their limits, no two bodies overlap (:func:`configuration_problem`: every
    pair, finger against finger too), the 4S kinematics hold and the guaranteed band, competitors precluded, is at least ``task.torque_resolution`` wide.
    ``grasp``: as in :func:`contact_samples`; ``free`` (n_free,): a described hand's free joints there, and
    ``free_slope`` (n_j,): their rates per metre of workpiece travel (rad/m or m/m; default held).
    """
    from qsplan.mechanics.bands.effort import band_kinematics
    from qsplan.mechanics.modes.contact_mode import ContactMode

    from qsplan.planner.torque.pointwise import guaranteed_sweep

    try:
        speed = float(np.sign(direction)) * task.workpiece_speed
        rates = None if free_slope is None else np.asarray(free_slope, float).reshape(1, -1) * speed
        S = contact_samples(task, [x], effort_joint, speed, grasp=grasp,
                            free=None if free is None else np.asarray(free, float).reshape(1, -1), free_rates=rates)  # fmt: skip
    except QsplanError as exc:
        return StateCheck(float(x), False, f"no four-contact grasp: {exc}")
    if touching is not None and np.any(S.touching[0] != touching):
        return StateCheck(float(x), False, "a finger moves to another workpiece vertex (a contact change)")
    why = configuration_problem(task, S.pose[0], S.q[0])
    if why:
        return StateCheck(float(x), False, why)
    mode = task.formation.mode
    if not band_kinematics(S.scenes[0], ContactMode(mode)).ok:
        return StateCheck(float(x), False, f"the {mode_name(mode)} kinematics fail (eqs. 24-25)")
    g = guaranteed_sweep(S, task.mu_range, task.shared_mu, mode, competitors, force_margin=task.force_margin,
                         disturbance=task.disturbance)
    b, d = g.band, g.desired
    cut = tuple(c for c, (lo, hi) in g.competitors.items() if np.isfinite(lo[0]))
    lo, hi = float(b.lower[0]), float(b.upper[0])
    common = dict(desired_lower=float(d.lower[0]), desired_upper=float(d.upper[0]), competitors=cut)
    if not b.feasible[0]:
        return StateCheck(float(x), False, "no guaranteed band: " + (b.reasons[0] or f"{mode_name(mode)} not guaranteed"),
                          **common)  # fmt: skip
    if hi - lo < task.torque_resolution:
        return StateCheck(float(x), False, f"band {hi - lo:.4g} N m narrower than the resolution", lo, hi, **common)
    return StateCheck(float(x), True, None, lo, hi, **common)


def free_state_problem(task: Task, x: float, q) -> str | None:
    """What is wrong with the free-space finger configuration ``q`` (rad, shape (2,)) with the workpiece
    at ``x`` (m), in words, or None (see :func:`configuration_problem`)."""
    return configuration_problem(task, task.pose(x), q)


def check_free_state(task: Task, x: float, q) -> bool:
    """A free-space finger configuration ``q`` (rad, shape (2,)) with the workpiece at ``x`` (m):
    inside the joint limits, and no two of the fingers, the palm and the workpiece overlapping
    (the fingers may touch the workpiece, within :data:`qsplan.hands.geometry.collision.CONTACT_DEPTH_TOL`)."""
    return free_state_problem(task, x, q) is None
