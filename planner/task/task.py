"""Planning tasks for the two-finger hand (Section 5.2, Fig. 9): what a plan must achieve, and nothing more.

A task names the hand and its workpiece, the workpiece's start and the goal of each in-contact segment, the
friction uncertainty, the torque resolution of the effort-controlled joint's controller and the joint, speed and
acceleration limits.  Everything else is derived by :mod:`qsplan.planner.plan.scripted`: the contacts (from the
polygons), the desired mode of each segment (4S), which finger is effort-controlled (the control-mode
partitioner and the guaranteed bands) and the grasps (the fingers' tangency with the workpiece).

The workpiece rests on its bottom edge on the palm (``y`` = the hand's rest height, ``theta = 0``), so its
pose in a task is its centre-of-mass ``x``.

TOML form (all SI: m, kg, rad, s, N m)::

    name = "regrasp like Fig. 9"
    formation = "palm_edge"      # optional: how the hand holds the workpiece (qsplan.hands.formations.registry)
    [hand]                       # qsplan.hands.paper_hand.two_finger.make_two_finger_hand's arguments
    workpiece = [[0.0, 0.0], [0.080, 0.0], [0.085, 0.080], [0.008, 0.100]]
    workpiece_mass = 0.2         # optional from here on, with make_two_finger_hand's defaults
    finger_base = 0.09
    finger_length = 0.16
    [motion]
    start_x = 0.0                # workpiece x at the start (m)
    waypoints = [-0.04, 0.03, 0.0]  # workpiece x at the end of each in-contact segment (m)
    [friction]
    range = [0.0, 0.2]           # every contact's coefficient in [lo, hi]
    shared = false               # true: one coefficient shared by all contacts
    [controller]
    torque_resolution = 0.02     # N m: the narrowest band the controller can hold
    min_normal_force = 0.05      # N, optional: every contact's normal force at least this, for all friction
    min_coulomb_slack = 0.05     # N, optional: rolling contacts' cone slacks at least this (qsplan.planner.task.fields.PLAN_FORCE_MARGIN)
    disturbance = { lo = [-0.1, -0.1, -0.005], hi = [0.1, 0.1, 0.005] }  # optional (N, N, N m): every band
                                 # holds for every external wrench on the workpiece in this box (none by default)
    [limits]                     # optional: narrows the hand's own limits, never widens them
    left = [0.05, 3.09]          # a joint's range by its name (rad; m for a prismatic joint)
    right = [0.05, 3.09]
    joint_speed = 0.5            # rad/s, every revolute joint
    speed = { left = 0.4 }       # optional: a joint's speed by name, in its unit (rad/s, m/s)
    workpiece_speed = 0.01       # m/s
    workpiece_acceleration = 0.02  # m/s^2, optional: phases start and end at rest (qsplan.planner.task.dynamics)
    joint_acceleration = 0.5     # rad/s^2, optional, every revolute joint; [limits.acceleration] by joint name
    release_acceleration = 0.05  # rad/s^2, optional: the regrasp legs that leave and reach the workpiece

:func:`load_task` reads it; :func:`make_task` is the Python equivalent; :func:`task_from_record` reads the same
tables from a dict (:func:`qsplan.planner.task.record.task_record` writes a task as one: the round trip
``plan.json`` and the certifier use).  Errors
are :class:`qsplan.mechanics.QsplanError` naming the field.
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from qsplan.mechanics.bands.effort import ForceMargin, check_force_margin
from qsplan.mechanics.errors import QsplanError
from qsplan.mechanics.model.friction import check_mu_range
from qsplan.planner.task.dynamics import resolve_dynamics
from qsplan.planner.task.fields import (PLAN_FORCE_MARGIN, TASK_RANGES, check_hand, field_name, hand_from_task_table,
                                        in_task_range, plan_force_margin, short_repr, start_joints_of, task_disturbance,
                                        task_number)  # fmt: skip
from qsplan.hands.formations.registry import DEFAULT_FORMATION, FORMATIONS, Formation
from qsplan.planner.task.goal import Goal, make_goal, make_start_features
from qsplan.planner.task.limits import LIMIT_KEYS, resolve_limits

__all__ = ["Task", "load_task", "make_task", "task_from_record", "demo_task_path", "task_path", "task_paths", "TASK_RANGES", "MAX_WAYPOINTS",
           "MIN_SEGMENT_LENGTH"]

#: Most in-contact segments a task may have: each is one OMPL query of up to its time limit, so
#: 50 segments already mean an hour of planning in the worst case (a long zig-zag hung the planner).
MAX_WAYPOINTS = 50

#: Shortest in-contact segment (m): a tenth of a millimetre, below any hand's positioning accuracy;
#: shorter segments make a time grid of vanishing steps.
MIN_SEGMENT_LENGTH = 1e-4

#: The keys of each table of a task file (unknown keys are refused at every level).
_TABLE_KEYS = {
    "motion": {"start_x", "waypoints"},
    "friction": {"range", "shared"},
    "controller": {"torque_resolution", "min_normal_force", "min_coulomb_slack", "disturbance"},
}

_DATA = Path(__file__).parent.parent / "data"  # planner/data, installed as qsplan.planner package data


@dataclass(frozen=True, slots=True, eq=False)
class Task:
    """A two-finger manipulation task.

    Attributes
    ----------
    name : str
    hand : qsplan.hands.described.hand.DescribedHand
        The hand (:class:`qsplan.hands.protocol.Hand`): the paper's form answers with its closed forms.
    start_x : float
        Workpiece centre-of-mass ``x`` at the start (m).
    waypoints : ndarray, shape (k,)
        Workpiece ``x`` at the end of each of the ``k`` in-contact segments (m); the last is the goal.
    mu_range : (float, float)
        Friction uncertainty ``0 <= lo <= hi``.
    shared_mu : bool
        One coefficient for all contacts (else each contact's independently in the range).
    torque_resolution : float
        N m, positive: every guaranteed band along the plan must be at least this wide.
    joint_limits : ndarray, shape (n_j, 2)
        ``[[lo, hi], ...]`` (rad, m for a prismatic joint) of each joint: the left and right finger of the paper's
        hand, a described hand's joints in its order (:func:`qsplan.planner.task.limits.resolve_limits`: the
        hand's, narrowed by the task's ``[limits]``).
    joint_speed : float
        rad/s, positive: the slowest joint's speed limit (the paper hand's single-speed planner uses it).
    workpiece_speed : float
        m/s, positive: limit on the workpiece's speed.
    force_margin : ForceMargin
        Minimum normal force and Coulomb slack (N) every guaranteed band keeps for all friction in the range
        (default :data:`qsplan.planner.task.fields.PLAN_FORCE_MARGIN`, with its reason).
    goal : qsplan.planner.task.goal.Goal or None
        Where an automatically planned task ends (then ``waypoints`` is empty).
    start_features : ((str, int or None), (str, int or None))
        Where each finger touches at the start: ``("inner", None)`` or ``(kind, K)`` (polygon as written).
    speeds : ndarray, shape (n_j,)
        Each joint's speed limit (rad/s or m/s): the hand's, narrowed by the task's (see :attr:`joint_speeds`).
    start_joints : ndarray, shape (n_j,), or None
        A described hand's free joints at the start (``[start]`` by joint name; the closing joints' entries 0);
        None: the planner chooses.
    formation : qsplan.hands.formations.registry.Formation
        How the hand holds the workpiece: its contacts, their order, the desired mode (today's one entry of
        :data:`qsplan.hands.formations.registry.FORMATIONS`, the bottom edge on the palm and a point of each finger,
        4S).
    disturbance : qsplan.mechanics.bands.disturbance.WrenchBox or None
        A box of external wrenches on the workpiece (N, N, N m) every guaranteed band and preclusion withstands
        (:mod:`qsplan.mechanics.bands.disturbance`): the task's, else the inertial load of the time scaling
        (:func:`qsplan.planner.task.dynamics.inertial_box`); None only for a Task built by hand.
    dynamics : qsplan.planner.task.dynamics.Dynamics or None
        The time scaling's limits (accelerations; the box's source); None only for a Task built by hand
        (:func:`qsplan.planner.task.dynamics.task_dynamics` gives the defaults).
    """

    name: str
    hand: object
    start_x: float
    waypoints: np.ndarray
    mu_range: tuple
    shared_mu: bool
    torque_resolution: float
    joint_limits: np.ndarray
    joint_speed: float
    workpiece_speed: float
    force_margin: ForceMargin = PLAN_FORCE_MARGIN
    goal: Goal | None = None
    start_features: tuple = (("inner", None), ("inner", None))
    speeds: np.ndarray | None = None
    start_joints: np.ndarray | None = None
    formation: Formation = FORMATIONS[DEFAULT_FORMATION]
    disturbance: object = None
    dynamics: object = None

    @property
    def joint_speeds(self) -> np.ndarray:
        """Speed limit of each joint (rad/s, m/s for a prismatic joint), shape (n_j,)."""
        return self.speeds if self.speeds is not None else np.full(len(self.joint_limits), self.joint_speed)

    @property
    def start_free(self) -> np.ndarray | None:
        """The hand's free joints as the task starts them (rad or m, in ``hand.free_joints``' order; a chain hand's
        ``[start]``), or None: a hand without free joints, or a task that does not start them."""
        free = list(self.hand.free_joints)
        if not free or self.start_joints is None:
            return None
        return np.asarray(self.start_joints, dtype=float)[free]

    @property
    def automatic(self) -> bool:
        """Whether the planner finds the sequence (a ``[goal]``, no scripted waypoints)."""
        return self.goal is not None

    def pose(self, x) -> np.ndarray:
        """Workpiece pose ``(x, rest height, 0)`` (m, m, rad), shape (3,)."""
        return np.array([float(x), self.hand.rest_height, 0.0])


def _pair(value, field, unit) -> tuple:
    if not isinstance(value, (list, tuple, np.ndarray)) or len(value) != 2:
        raise QsplanError(f"{field}: expected two numbers [lo, hi] ({unit}); got {value!r}")
    lo, hi = (task_number(v, field, unit) for v in value)
    if lo > hi:
        raise QsplanError(f"{field}: expected lo <= hi; got [{lo}, {hi}]")
    return lo, hi


def make_task(hand, start_x, waypoints=None, mu_range=(0.0, 0.2), torque_resolution=0.02, shared_mu=False,
              joint_limits=None, joint_speed=None, workpiece_speed=0.01,
              name="task", force_margin=None, goal=None, start=None, base_dir=None, joint_speeds=None,
              formation=None, disturbance=None, workpiece_acceleration=None, joint_acceleration=None,
              joint_accelerations=None, release_acceleration=None) -> Task:  # fmt: skip
    """Validate and build a :class:`Task` (parameters as its attributes; ``hand`` a TwoFingerHand or a dict of
    :func:`qsplan.hands.paper_hand.two_finger.make_two_finger_hand` arguments).  Either ``waypoints`` (a scripted
    sequence) or ``goal`` (the ``[goal]`` table as a dict, or a :class:`Goal`: the planner finds the sequence);
    ``start`` the ``[start]`` table as a dict (default both fingers ``"inner"``; a described hand: its free joints
    by name).  ``hand`` may also be a :class:`qsplan.hands.chains.hand.ChainHand` or a ``[hand]`` table naming a
    hand description (:mod:`qsplan.planner.task.fields`; ``base_dir`` resolves its relative ``file``).
    Limits (:func:`qsplan.planner.task.limits.resolve_limits`, the one place): ``joint_limits``
    (``{joint: [lo, hi]}`` for some joints, or one pair per joint in order), ``joint_speed`` (rad/s, every
    revolute joint) and ``joint_speeds`` (``{joint: speed}`` in each joint's unit) narrow the hand's own
    (a description's; the paper hand's parameter form has none: ``[0.05, 3.09]`` rad and 0.5 rad/s by
    default), never widen them.

    Raises
    ------
    QsplanError
        Naming the field, what was expected and what was received.
    """
    from qsplan.hands.described.build import as_hand

    if isinstance(hand, dict):
        hand, *_ = hand_from_task_table(hand, base_dir)
        hand_label = "the hand file"
    else:
        hand = as_hand(hand)  # the door: today's records become described hands
        check_hand(hand)
        hand_label = f"the hand {hand.name!r}"
    own_limits, own_speeds = hand.own_limits if hand.own_limits is not None else (None, None)
    chain = bool(hand.free_joints)  # a hand with free joints starts from them; the others from features
    if not isinstance(name, str) or len(name) > 200:
        raise QsplanError(f"name: expected a string of at most 200 characters; got {short_repr(name)}")
    start_x = in_task_range(task_number(start_x, "motion.start_x", "m"), "motion.start_x", "position")
    n_v = len(hand.workpiece)
    start_joints = None
    if chain:
        start_joints = start_joints_of(hand, {} if start is None else start)
        start_features = (("inner", None), ("inner", None))
    else:
        start_features = make_start_features({} if start is None else start, n_v)
    if goal is not None and waypoints is not None:
        raise QsplanError("goal: give either motion.waypoints (a scripted sequence) or [goal] (the planner finds the "
                          "sequence), not both")  # fmt: skip
    if goal is not None:
        number = lambda v, field, unit: in_task_range(task_number(v, field, unit), field, "position")  # noqa: E731
        goal = goal if isinstance(goal, Goal) else make_goal(goal, n_v, number)
        waypoints = ()
    elif waypoints is None:
        raise QsplanError("motion.waypoints: missing (or give a [goal] table: the planner then finds the sequence)")
    elif not isinstance(waypoints, (list, tuple, np.ndarray)) or not 1 <= len(waypoints) <= MAX_WAYPOINTS:
        raise QsplanError(f"motion.waypoints: expected a list of 1 to {MAX_WAYPOINTS} workpiece x (m); "
                          f"got {short_repr(waypoints)}")  # fmt: skip
    wp = np.array([in_task_range(task_number(v, f"motion.waypoints[{i}]", "m"), f"motion.waypoints[{i}]", "position")
                   for i, v in enumerate(waypoints)], dtype=float)  # fmt: skip
    prev = np.concatenate([[start_x], wp[:-1]])
    short = np.abs(wp - prev) < MIN_SEGMENT_LENGTH
    if np.any(short):
        k = int(np.flatnonzero(short)[0])
        raise QsplanError(f"motion.waypoints[{k}]: segment {k + 1} moves the workpiece {abs(wp[k] - prev[k]):g} m "
                          f"(x {prev[k]:g} to {wp[k]:g}); expected at least {MIN_SEGMENT_LENGTH:g} m")  # fmt: skip
    lo, hi = check_mu_range(*_pair(mu_range, "friction.range", "friction coefficients"), "friction.range")
    in_task_range(hi, "friction.range", "friction")
    if not lo < hi:
        raise QsplanError(f"friction.range: expected lo < hi (plans are guaranteed over an interval of friction; for "
                          f"one known coefficient give a small interval around it); got [{lo:g}, {hi:g}]")  # fmt: skip
    names, kinds = hand.joint_names, hand.joint_kinds
    resolved = resolve_limits(names, kinds, own_limits, own_speeds, ranges=joint_limits, joint_speed=joint_speed,
                              speeds=joint_speeds, hand_label=hand_label)  # fmt: skip
    limits, speeds = resolved.ranges, resolved.speeds
    base = hand.workpiece[:2, 0]
    if not base.min() < 0.0 < base.max():
        raise QsplanError("hand.workpiece: its centre of mass must lie over its bottom edge, so that it rests on the "
                          "palm while the fingers regrasp")  # fmt: skip
    wp.setflags(write=False)
    if not isinstance(shared_mu, (bool, np.bool_)):
        raise QsplanError(f"friction.shared: expected true or false; got {short_repr(shared_mu)}")
    checked = {key: in_task_range(task_number(value, field, TASK_RANGES[key][2], positive=True), field, key)
               for key, field, value in (("torque_resolution", "controller.torque_resolution", torque_resolution),
                                         ("workpiece_speed", "limits.workpiece_speed", workpiece_speed))}  # fmt: skip
    if force_margin is not None:  # the task file's ranges for the API too (plan_force_margin names the fields)
        fm = check_force_margin(force_margin)
        force_margin = plan_force_margin(fm.normal, fm.slack, "force_margin")
    else:
        force_margin = PLAN_FORCE_MARGIN
    if formation is None:
        formation = FORMATIONS[DEFAULT_FORMATION]
    elif not isinstance(formation, Formation):
        from qsplan.hands.formations.registry import formation as registered

        formation = registered(formation)
    from qsplan.planner.task.goal import goal_turns

    turning = goal_turns(goal, hand)  # a goal that turns the workpiece: its inertia in every direction
    dyn = resolve_dynamics(hand, task_disturbance(disturbance), workpiece_acceleration, joint_acceleration,
                           joint_accelerations, release_acceleration, turning)  # fmt: skip
    return Task(name, hand, start_x, wp, (lo, hi), bool(shared_mu), checked["torque_resolution"], limits,
                float(np.min(speeds)), checked["workpiece_speed"], force_margin, goal, start_features, speeds,
                start_joints, formation, dyn.disturbance, dyn)  # fmt: skip


_KNOWN = {"name", "hand", "motion", "friction", "controller", "limits", "goal", "start", "formation", "version"}


def _table(doc, key):
    v = doc.get(key, {})
    if not isinstance(v, dict):
        raise QsplanError(f"{key}: expected a table; got {short_repr(v)}")
    return v


def load_task(path) -> Task:
    """Read a task file (TOML, see the module docstring).

    Raises
    ------
    QsplanError
        File missing or unreadable, bad TOML, or a bad field (named).
    """
    from qsplan.mechanics.model.fields import read_text

    path = Path(path)
    try:
        doc = tomllib.loads(read_text(path, "task", QsplanError))
    except RecursionError:
        raise QsplanError(f"task: {str(path)!r} is not valid TOML: nested too deeply") from None
    except ValueError as exc:  # TOMLDecodeError, and integers of thousands of digits
        if isinstance(exc, QsplanError):
            raise
        raise QsplanError(f"task: {str(path)!r} is not valid TOML: {' '.join(str(exc).split())}") from None
    return task_from_record(doc, base_dir=path.parent, default_name=path.stem)


def task_from_record(doc, base_dir=None, default_name: str = "task") -> Task:
    """The task of a task file's tables ``doc`` (a parsed TOML document, or :func:`qsplan.planner.task.record.task_record`'s
    record), every field checked as :func:`load_task` checks a file's; ``base_dir`` resolves a relative ``[hand] file``,
    ``default_name`` names a task that gives no name.

    Raises
    ------
    QsplanError
        Naming the field.
    """
    from qsplan.planner.task.record import RECORD_VERSION

    if not isinstance(doc, dict):
        raise QsplanError(f"task: expected a table of the task file's fields; got {short_repr(doc)}")
    unknown = sorted(set(doc) - _KNOWN)
    if unknown:
        raise QsplanError(f"{field_name(unknown[0])}: unknown task field; expected one of {', '.join(sorted(_KNOWN))}")
    kw = {}
    motion, friction = _table(doc, "motion"), _table(doc, "friction")
    controller, limits = _table(doc, "controller"), _table(doc, "limits")
    for key, table in (("motion", motion), ("friction", friction), ("controller", controller)):
        extra = sorted(set(table) - _TABLE_KEYS[key])
        if extra:
            raise QsplanError(f"{key}.{field_name(extra[0])}: unknown field; expected some of {', '.join(sorted(_TABLE_KEYS[key]))}")
    if "start_x" not in motion:
        raise QsplanError("motion.start_x: missing")
    if "goal" in doc:
        kw["goal"] = _table(doc, "goal")
    if "start" in doc:
        kw["start"] = _table(doc, "start")
    if "torque_resolution" not in controller:
        raise QsplanError("controller.torque_resolution: missing (N m)")
    if "range" in friction:
        kw["mu_range"] = friction["range"]
    if "shared" in friction:
        if not isinstance(friction["shared"], bool):
            raise QsplanError(f"friction.shared: expected true or false; got {short_repr(friction['shared'])}")
        kw["shared_mu"] = friction["shared"]
    ranges = {k: v for k, v in limits.items() if k not in LIMIT_KEYS}  # joints by name, checked against the hand
    if ranges:
        kw["joint_limits"] = ranges
    if "speed" in limits:
        kw["joint_speeds"] = limits["speed"]
    kw["base_dir"] = base_dir
    for key in ("joint_speed", "workpiece_speed", "workpiece_acceleration", "joint_acceleration", "release_acceleration"):
        if key in limits:
            kw[key] = limits[key]
    if "acceleration" in limits:
        kw["joint_accelerations"] = limits["acceleration"]
    if doc.get("version", RECORD_VERSION) != RECORD_VERSION:
        raise QsplanError(f"version: expected {RECORD_VERSION} (a task record of this qsplan); got {short_repr(doc['version'])}")
    if "formation" in doc:
        kw["formation"] = doc["formation"]
    kw["force_margin"] = plan_force_margin(controller.get("min_normal_force"), controller.get("min_coulomb_slack"))
    if "disturbance" in controller:
        kw["disturbance"] = controller["disturbance"]
    return make_task(_table(doc, "hand"), motion["start_x"], motion.get("waypoints"),
                     torque_resolution=controller["torque_resolution"], name=doc.get("name", default_name), **kw)  # fmt: skip


def demo_task_path() -> Path:
    """The bundled task of ``qsplan demo``: the first 4S segment of the paper's Fig. 9, planned from a start and a goal."""
    return _DATA / "demo_task.toml"


def task_paths() -> dict:
    """Every bundled task file, ``{stem: Path}``."""
    return {p.stem: p for p in sorted(_DATA.glob("*.toml"))}


def task_path(ref) -> Path:
    """The task file ``ref`` names: an existing path, else a bundled task's name (:func:`task_paths`), else ``ref``
    as a path (whose loading then names it missing)."""
    path = Path(ref)
    bundled = task_paths()
    return bundled[str(ref)] if str(ref) in bundled and not path.exists() else path
