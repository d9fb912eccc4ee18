"""A task's dynamic limits: how fast a plan may speed up and slow down, and the inertial load that costs (issue 24).

A plan is quasistatic: its bands ignore inertia.  Every phase starts and ends at rest
(:mod:`qsplan.planner.plan.timing`), so the workpiece and the joints accelerate; the workpiece's inertial
force ``-m a`` (at its centre of mass) is an external wrench the bands must withstand.  The task bounds it:

* ``[limits] workpiece_acceleration`` (m/s^2, default :data:`DEFAULT_WORKPIECE_ACCELERATION`): the
  workpiece's largest acceleration;
* ``[limits] joint_acceleration`` (rad/s^2 for every revolute joint; default :data:`DEFAULT_JOINT_ACCELERATION`,
  m/s^2 for a prismatic joint) and ``[limits.acceleration] <joint> = a`` (one joint's, in its unit);
* ``[limits] release_acceleration`` (rad/s^2, every revolute joint; default :data:`DEFAULT_RELEASE_ACCELERATION`):
  the regrasp legs that leave and reach the workpiece, gentler (a compliant contact released fast kicks);
* ``[controller] disturbance``: the box of external wrenches every band withstands.  A task that gives none gets
  :func:`inertial_box`: the inertial load of the workpiece at its largest acceleration, and nothing more.  A task
  that gives one keeps it, and the workpiece's acceleration is cut to what the box holds
  (:func:`box_acceleration`): the time scaling never asks for an inertial load outside the box.

The workpiece moves along the palm (x) in the formations planned today, at a fixed orientation: its inertial
wrench about the world origin is ``(fx, 0, -y fx)`` with ``|fx| <= m a`` and ``y`` its centre of mass's height.
The hand's links: the bundled hands' links are massless; a link's own inertia is not bounded here
(:func:`dynamics_metadata` says so when a hand has link masses).  Units SI.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qsplan.mechanics.errors import QsplanError

__all__ = ["DEFAULT_JOINT_ACCELERATION", "DEFAULT_RELEASE_ACCELERATION", "DEFAULT_WORKPIECE_ACCELERATION", "Dynamics",
           "box_acceleration", "dynamics_metadata", "inertial_box", "inertial_wrench", "link_mass", "resolve_dynamics",
           "task_dynamics", "turning_box", "turning_wrench", "workpiece_radius"]

#: The workpiece's largest acceleration by default (m/s^2): it reaches the default 0.01 m/s workpiece speed in
#: 0.5 s over 2.5 mm (five of the slides' 0.5 mm rows).  Its inertial force on the demo workpiece (0.2 kg) is
#: 4 mN, 0.2 % of its weight: the bands it costs are a few mN m (0.238 -> 0.234 N m on the demo's narrowest).
DEFAULT_WORKPIECE_ACCELERATION = 0.02

#: Every joint's largest acceleration by default, by kind (rad/s^2; m/s^2): a revolute finger reaches the default
#: 0.5 rad/s in 0.25 s (a hobby servo does in ~0.05 s); a prismatic jaw 0.02 m/s in 0.1 s.
DEFAULT_JOINT_ACCELERATION = {"revolute": 0.5, "prismatic": 0.05}

#: The acceleration of a regrasp's legs that leave and reach the workpiece, by kind (rad/s^2; m/s^2).  A squeezed
#: contact is compliant (a robot's fingers, MuJoCo's soft contacts): a finger that leaves it fast releases its
#: stored force as a kick, and on a palm without friction the workpiece drifts.  Measured in MuJoCo
#: (``benchmarks/bench_mujoco.py``, the 16 friction vertices) on ``two_link_regrasp_task``, the worst bundled
#: plan, at zero palm friction: opening at 0.5 rad/s^2 the workpiece drifted up to 0.28 mm, at 0.15 rad/s^2
#: 0.138 mm, at 0.1 rad/s^2 0.083 mm, at 0.05 rad/s^2 0.039 mm (the acceptance asks 0.1 mm; 0.05 leaves room).
DEFAULT_RELEASE_ACCELERATION = {"revolute": 0.05, "prismatic": 0.005}

#: Plausible ranges of the task's accelerations (a unit slip, not a hand, beyond them): from a crawl that takes
#: ~100 s to reach the slowest speed limit to a hundredfold of the defaults.
ACCELERATION_RANGES = {"workpiece_acceleration": (1e-4, 2.0, "m/s^2"), "joint_acceleration": (1e-3, 200.0, "rad/s^2")}


#: The grid (N, N m) the default box's corners are rounded up to: 1e-12, five orders below the smallest inertial
#: force the ranges allow (1 g at 1e-4 m/s^2: 1e-7 N), far above a float's rounding of these sizes (~1e-19).
BOX_GRID = 1e-12


@dataclass(frozen=True, slots=True, eq=False)
class Dynamics:
    """A task's dynamic limits.

    Attributes
    ----------
    workpiece_acceleration : float
        The workpiece's largest acceleration (m/s^2), the task's, cut to what the disturbance box holds.
    joint_accelerations : ndarray, shape (n_j,)
        Each joint's largest acceleration (rad/s^2, m/s^2), read-only.
    release_accelerations : ndarray, shape (n_j,)
        Each joint's largest acceleration on a regrasp's legs that leave and reach the workpiece (rad/s^2, m/s^2):
        at most its ``joint_accelerations``.
    disturbance : qsplan.mechanics.bands.disturbance.WrenchBox
        The box every band withstands: the task's, or :func:`inertial_box`.
    source : str
        ``"task"`` (the task gave the box) or ``"inertia"`` (the default box).
    """

    workpiece_acceleration: float
    joint_accelerations: np.ndarray
    disturbance: object
    source: str
    release_accelerations: np.ndarray

    def angular_acceleration(self, hand) -> float:
        """The workpiece's largest angular acceleration (rad/s^2) while it turns: ``workpiece_acceleration`` over its
        farthest vertex's distance from its centre of mass, so no point of it accelerates faster from the turning
        alone than the task allows its centre of mass."""
        return float(self.workpiece_acceleration / workpiece_radius(hand))


def _number(v, field, key) -> float:
    from qsplan.planner.task.fields import short_repr, task_number

    x = task_number(v, field, ACCELERATION_RANGES[key][2], positive=True)
    lo, hi, unit = ACCELERATION_RANGES[key]
    if not lo <= x <= hi:
        raise QsplanError(f"{field}: {short_repr(v)} {unit} is outside the plausible range [{lo:g}, {hi:g}] {unit}")
    return x


def inertial_wrench(mass: float, height: float, ax) -> np.ndarray:
    """The workpiece's inertial wrench about the world origin (N, N, N m), shape (..., 3), at acceleration ``ax``
    along the palm (m/s^2): ``(-m ax, 0, m ax y)`` at its centre of mass at height ``y`` (m); :func:`turning_wrench`
    of a workpiece that slides without turning."""
    ax = np.asarray(ax, dtype=float)
    return turning_wrench(mass, 0.0, (0.0, float(height)), np.stack([ax, np.zeros_like(ax)], axis=-1), 0.0)


def workpiece_radius(hand) -> float:
    """The distance (m) from the workpiece's centre of mass to its farthest vertex."""
    return float(np.max(np.hypot(*np.asarray(hand.workpiece, dtype=float).T)))


def turning_wrench(mass: float, inertia: float, com, acceleration, angular) -> np.ndarray:
    """The workpiece's inertial wrench about the world origin (N, N, N m), shape (..., 3), its centre of mass at
    ``com`` (..., 2) (m) accelerating at ``acceleration`` (..., 2) (m/s^2) and turning at ``angular`` (...,) (rad/s^2):
    ``f = -m a``, moment ``c x f - I alpha`` (``inertia`` about the centre of mass, kg m^2)."""
    com, acc = np.asarray(com, dtype=float), np.asarray(acceleration, dtype=float)
    f = -float(mass) * acc
    moment = com[..., 0] * f[..., 1] - com[..., 1] * f[..., 0] - float(inertia) * np.asarray(angular, dtype=float)
    return np.concatenate([f, moment[..., None]], axis=-1)


def turning_box(hand, acceleration: float):
    """The box (a WrenchBox) holding the inertial wrench of a workpiece that turns and moves anywhere over the palm:
    ``|fx|, |fy| <= m a``, and a moment within ``m a (X + Y) + I a / R``: ``X`` the palm's half-width (the centre of
    mass's largest ``|x|``), ``Y = R`` (its largest height with a vertex on the palm), ``R`` its farthest vertex's
    distance (the angular acceleration's bound, :meth:`Dynamics.angular_acceleration`).  Rounded up to
    :data:`BOX_GRID`."""
    from qsplan.hands.geometry.workpiece import polygon_inertia
    from qsplan.mechanics.bands.disturbance import WrenchBox

    m, R = float(hand.workpiece_mass), workpiece_radius(hand)
    X = float(np.max(np.abs(np.asarray(hand.manipulator.base_shape, dtype=float)[:, 0])))
    _, inertia = polygon_inertia(hand.workpiece, m)
    f = m * acceleration
    w = _grid_ceil(np.array([f, f, f * (X + R) + inertia * acceleration / R]))
    return WrenchBox(tuple(-w), tuple(w))


def _grid_ceil(w) -> np.ndarray:
    """``w`` (N, N m) rounded up to :data:`BOX_GRID`: a box's corners still hold the load, and a task read back from a
    plan's record (its workpiece re-centred, a rounding apart) gets the same box to the last digit."""
    return np.ceil(np.asarray(w, dtype=float) / BOX_GRID) * BOX_GRID


def inertial_box(mass: float, height: float, acceleration: float):
    """The smallest box holding the inertial wrench at every acceleration in ``[-a, a]`` (a WrenchBox)."""
    from qsplan.mechanics.bands.disturbance import WrenchBox

    w = _grid_ceil(np.abs(inertial_wrench(mass, height, acceleration)))
    return WrenchBox((-w[0], 0.0, -w[2]), (w[0], 0.0, w[2]))


def box_acceleration(box, mass: float, height: float) -> float:
    """The largest ``a`` (m/s^2) with the inertial wrench at every acceleration in ``[-a, a]`` inside ``box``
    (0: the box cannot hold any; the wrench is linear in ``a``, so its two ends decide)."""
    lo, hi = np.asarray(box.lo, float), np.asarray(box.hi, float)
    per = np.abs(inertial_wrench(mass, height, 1.0))  # the wrench per m/s^2, both signs
    if not (lo[1] <= 0.0 <= hi[1]) or np.any(lo > 0) or np.any(hi < 0):
        return 0.0
    room = np.minimum(-lo, hi)
    with np.errstate(divide="ignore"):
        return float(np.min(np.where(per > 0, room / np.where(per > 0, per, 1.0), np.inf)))


def resolve_dynamics(hand, box, workpiece_acceleration=None, joint_acceleration=None, accelerations=None,
                     release_acceleration=None, turning: bool = False) -> Dynamics:
    """A task's :class:`Dynamics` from its ``[limits]`` and ``[controller] disturbance`` (``box``: a WrenchBox or None).

    Raises
    ------
    QsplanError
        Naming ``limits.workpiece_acceleration``, ``limits.joint_acceleration``, ``limits.acceleration.<joint>`` or
        ``controller.disturbance`` (a box that holds no inertial load: the plan's stops need some).
    """
    from qsplan.planner.task.fields import field_name, short_repr

    names, kinds = tuple(hand.joint_names), tuple(hand.joint_kinds)
    a_wp = (DEFAULT_WORKPIECE_ACCELERATION if workpiece_acceleration is None
            else _number(workpiece_acceleration, "limits.workpiece_acceleration", "workpiece_acceleration"))  # fmt: skip
    acc = np.array([DEFAULT_JOINT_ACCELERATION[k] for k in kinds])
    if joint_acceleration is not None:
        v = _number(joint_acceleration, "limits.joint_acceleration", "joint_acceleration")
        acc = np.where(np.array(kinds) == "revolute", v, acc)
    if accelerations is not None:
        if not isinstance(accelerations, dict):
            raise QsplanError(f"limits.acceleration: expected a table {{joint = a}}; got {short_repr(accelerations)}")
        for key, v in accelerations.items():
            if key not in names:
                raise QsplanError(f"limits.acceleration.{field_name(key)}: unknown joint; expected some of {', '.join(names)}")
            acc[names.index(key)] = _number(v, f"limits.acceleration.{key}", "joint_acceleration")
    acc.setflags(write=False)
    rel = np.array([DEFAULT_RELEASE_ACCELERATION[k] for k in kinds])
    if release_acceleration is not None:
        v = _number(release_acceleration, "limits.release_acceleration", "joint_acceleration")
        rel = np.where(np.array(kinds) == "revolute", v, rel)
    rel = np.minimum(rel, acc)
    rel.setflags(write=False)
    m, y = float(hand.workpiece_mass), float(hand.rest_height)
    if box is None and turning:  # a goal that turns the workpiece: its inertial load in every direction
        return Dynamics(a_wp, acc, turning_box(hand, a_wp), "inertia", rel)
    if box is None:
        return Dynamics(a_wp, acc, inertial_box(m, y, a_wp), "inertia", rel)
    room = box_acceleration(box, m, y)
    if not room > 0:
        raise QsplanError("controller.disturbance: the box holds no inertial load of the workpiece; every phase starts "
                          "and ends at rest, so it must hold force x from -F to F (N), force y 0 and the moment "
                          f"-{y:.4g} m x force x (N m) for some F > 0")  # fmt: skip
    if turning:  # the box must hold the turning load at the (cut) acceleration: the turning box's corners inside it
        need = turning_box(hand, 1.0)
        per = np.asarray(need.hi, float)
        room = min(room, float(np.min(np.minimum(-np.asarray(box.lo, float), np.asarray(box.hi, float)) / per)))
        if not room > 0:
            raise QsplanError("controller.disturbance: the box holds no inertial load of a turning workpiece (the goal "
                              "turns it): it must hold force x and y and a moment on both sides of 0")  # fmt: skip
    return Dynamics(min(a_wp, room), acc, box, "task", rel)


def task_dynamics(task) -> Dynamics:
    """The task's :class:`Dynamics`; a Task built by hand without one gets the defaults, with its own box (or none)."""
    if task.dynamics is not None:
        return task.dynamics
    d = resolve_dynamics(task.hand, None)
    return Dynamics(d.workpiece_acceleration, d.joint_accelerations, task.disturbance, "task", d.release_accelerations)


def link_mass(hand) -> float:
    """The mass of the hand's links together (kg): a chain hand's links, the paper hand's two fingers."""
    return float(sum(float(j.link_mass) for j in hand.manipulator.joints))


def dynamics_metadata(task) -> dict:
    """``metadata.dynamics``: the time scaling's limits and the inertial load the bands withstand (SI)."""
    hand = task.hand
    dyn = task_dynamics(task)
    a = dyn.workpiece_acceleration
    massive = link_mass(hand) > 0
    return {
        "workpiece_acceleration_m_s2": a,
        "joint_acceleration": {n: float(v) for n, v in zip(hand.joint_names, dyn.joint_accelerations)},
        "release_acceleration": {n: float(v) for n, v in zip(hand.joint_names, dyn.release_accelerations)},
        "joint_acceleration_units": {n: f"{u}/s^2" for n, u in zip(hand.joint_names, hand.joint_units())},
        "inertial_force_N": float(hand.workpiece_mass) * a,
        "disturbance_source": dyn.source,
        "links": ("massless: no link inertia" if not massive else
                  "the links have mass: their inertia is not bounded by the time scaling (labelled, not proved)"),
        "meaning": "every phase starts and ends at rest; the workpiece's acceleration is at most "
                   "workpiece_acceleration_m_s2, so its inertial wrench lies in metadata.disturbance, which every "
                   "band withstands; each velocity command changes by at most its joint's acceleration per second",
    }  # fmt: skip
