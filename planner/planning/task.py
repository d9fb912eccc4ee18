"""Planning tasks for the two-finger hand (Section 5.2, Fig. 9): what a plan must achieve, and nothing more.

A task names the hand and its workpiece, the workpiece's start and the goal of
each in-contact segment, the friction uncertainty, the torque resolution of the
effort-controlled joint's controller and the joint and speed limits.  Everything
else is derived by :mod:`qsplan.planner.planning.plan`: the contacts (from the polygons), the
desired mode of each segment (4S: the workpiece slides on the palm and under
both fingers), which finger is effort-controlled (the control-mode partitioner
and the guaranteed bands) and the grasps (the fingers' tangency with the workpiece).

The workpiece always rests on its bottom edge on the palm (``y`` = the hand's
rest height, ``theta = 0``), so its pose in a task is its centre-of-mass ``x``.

TOML form (all SI: m, kg, rad, s, N m)::

    name = "regrasp like Fig. 9"
    [hand]                       # hands.two_finger.make_two_finger_hand's arguments
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
    [limits]
    left = [0.05, 3.09]          # joint range (rad) of each finger
    right = [0.05, 3.09]
    joint_speed = 0.5            # rad/s, each joint
    workpiece_speed = 0.01       # m/s

:func:`load_task` reads it; :func:`make_task` is the Python equivalent.  Errors
are :class:`mechanics.QsplanError` naming the field.
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from qsplan.mechanics.errors import QsplanError
from qsplan.mechanics.model.friction import check_mu_range

__all__ = ["Task", "load_task", "make_task", "demo_task_path", "task_paths"]

_DATA = Path(__file__).parent.parent / "data"  # planner/data, installed as qsplan.planner package data


@dataclass(frozen=True, slots=True, eq=False)
class Task:
    """A two-finger manipulation task.

    Attributes
    ----------
    name : str
    hand : hands.two_finger.TwoFingerHand
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
    joint_limits : ndarray, shape (2, 2)
        ``[[lo, hi], [lo, hi]]`` (rad) of the left and right finger.
    joint_speed : float
        rad/s, positive: limit on each joint's speed.
    workpiece_speed : float
        m/s, positive: limit on the workpiece's speed.
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

    def pose(self, x) -> np.ndarray:
        """Workpiece pose ``(x, rest height, 0)`` (m, m, rad), shape (3,)."""
        return np.array([float(x), self.hand.rest_height, 0.0])


def _number(value, field, unit, positive=False, nonnegative=False) -> float:
    if isinstance(value, bool):
        raise QsplanError(f"{field}: expected a number ({unit}); got {value!r}")
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise QsplanError(f"{field}: expected a number ({unit}); got {value!r}") from None
    if not np.isfinite(x) or (positive and x <= 0) or (nonnegative and x < 0):
        kind = "positive finite" if positive else ("nonnegative finite" if nonnegative else "finite")
        raise QsplanError(f"{field}: expected a {kind} number ({unit}); got {value!r}")
    return x


def _pair(value, field, unit) -> tuple:
    if not isinstance(value, (list, tuple, np.ndarray)) or len(value) != 2:
        raise QsplanError(f"{field}: expected two numbers [lo, hi] ({unit}); got {value!r}")
    lo, hi = (_number(v, field, unit) for v in value)
    if lo > hi:
        raise QsplanError(f"{field}: expected lo <= hi; got [{lo}, {hi}]")
    return lo, hi


def make_task(hand, start_x, waypoints, mu_range=(0.0, 0.2), torque_resolution=0.02, shared_mu=False,
              joint_limits=((0.05, 3.09), (0.05, 3.09)), joint_speed=0.5, workpiece_speed=0.01,
              name="task") -> Task:  # fmt: skip
    """Validate and build a :class:`Task` (parameters as its attributes; ``hand`` a TwoFingerHand or a dict of
    :func:`hands.two_finger.make_two_finger_hand` arguments).

    Raises
    ------
    QsplanError
        Naming the field, what was expected and what was received.
    """
    from qsplan.hands.two_finger import TwoFingerHand, make_two_finger_hand

    if isinstance(hand, dict):
        if "workpiece" not in hand:
            raise QsplanError("hand.workpiece: expected the workpiece polygon [[x, y], ...] (m); it is missing")
        try:
            hand = make_two_finger_hand(**hand)
        except TypeError as exc:
            raise QsplanError(f"hand: {exc}") from None
    if not isinstance(hand, TwoFingerHand):
        raise QsplanError(f"hand: expected a TwoFingerHand or a table of its parameters; got {type(hand).__name__}")
    start_x = _number(start_x, "motion.start_x", "m")
    if not isinstance(waypoints, (list, tuple, np.ndarray)) or len(waypoints) < 1:
        raise QsplanError(f"motion.waypoints: expected a nonempty list of workpiece x (m); got {waypoints!r}")
    wp = np.array([_number(v, "motion.waypoints", "m") for v in waypoints])
    prev = np.concatenate([[start_x], wp[:-1]])
    if np.any(wp == prev):
        k = int(np.flatnonzero(wp == prev)[0])
        raise QsplanError(f"motion.waypoints: segment {k + 1} does not move the workpiece (x = {wp[k]})")
    lo, hi = check_mu_range(*_pair(mu_range, "friction.range", "friction coefficients"), "friction.range")
    limits = np.array([_pair(joint_limits[k], f"limits.{side}", "rad") for k, side in enumerate(("left", "right"))])
    base = hand.workpiece[:2, 0]
    if not base.min() < 0.0 < base.max():
        raise QsplanError("hand.workpiece: its centre of mass must lie over its bottom edge, so that it rests on the "
                          "palm while the fingers regrasp")  # fmt: skip
    wp.setflags(write=False)
    limits.setflags(write=False)
    return Task(str(name), hand, start_x, wp, (lo, hi), bool(shared_mu),
                _number(torque_resolution, "controller.torque_resolution", "N m", positive=True), limits,
                _number(joint_speed, "limits.joint_speed", "rad/s", positive=True),
                _number(workpiece_speed, "limits.workpiece_speed", "m/s", positive=True))  # fmt: skip


_KNOWN = {"name", "hand", "motion", "friction", "controller", "limits"}


def _table(doc, key):
    v = doc.get(key, {})
    if not isinstance(v, dict):
        raise QsplanError(f"{key}: expected a table; got {v!r}")
    return v


def load_task(path) -> Task:
    """Read a task file (TOML, see the module docstring).

    Raises
    ------
    QsplanError
        File missing or unreadable, bad TOML, or a bad field (named).
    """
    path = Path(path)
    try:
        doc = tomllib.loads(path.read_text())
    except OSError as exc:
        raise QsplanError(f"task: cannot read {str(path)!r}: {exc.strerror or exc}") from None
    except tomllib.TOMLDecodeError as exc:
        raise QsplanError(f"task: {str(path)!r} is not valid TOML: {exc}") from None
    unknown = sorted(set(doc) - _KNOWN)
    if unknown:
        raise QsplanError(f"{unknown[0]}: unknown task field; expected one of {', '.join(sorted(_KNOWN))}")
    motion, friction = _table(doc, "motion"), _table(doc, "friction")
    controller, limits = _table(doc, "controller"), _table(doc, "limits")
    for key, table in (("motion.start_x", motion), ("motion.waypoints", motion)):
        if key.split(".")[1] not in table:
            raise QsplanError(f"{key}: missing")
    if "torque_resolution" not in controller:
        raise QsplanError("controller.torque_resolution: missing (N m)")
    kw = {}
    if "range" in friction:
        kw["mu_range"] = friction["range"]
    if "shared" in friction:
        if not isinstance(friction["shared"], bool):
            raise QsplanError(f"friction.shared: expected true or false; got {friction['shared']!r}")
        kw["shared_mu"] = friction["shared"]
    if "left" in limits or "right" in limits:
        kw["joint_limits"] = (limits.get("left", (0.05, 3.09)), limits.get("right", (0.05, 3.09)))
    for key in ("joint_speed", "workpiece_speed"):
        if key in limits:
            kw[key] = limits[key]
    return make_task(_table(doc, "hand"), motion["start_x"], motion["waypoints"],
                     torque_resolution=controller["torque_resolution"], name=doc.get("name", path.stem), **kw)  # fmt: skip


def demo_task_path() -> Path:
    """The bundled task of ``qsplan demo``: a regrasp like the paper's Fig. 9 (three 4S segments)."""
    return _DATA / "demo_task.toml"


def task_paths() -> dict:
    """Every bundled task file, ``{stem: Path}``."""
    return {p.stem: p for p in sorted(_DATA.glob("*.toml"))}
