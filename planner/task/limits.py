"""Where a task's joint limits come from: the one place, for the planner and the certifier alike (issue 21).

A hand has limits of its own: a hand description (:mod:`qsplan.hands.description`) gives every joint a
range and a speed; the paper's hand in its parameter form gives none, and :data:`PAPER_DEFAULTS` stand
in.  A task's ``[limits]`` table may **narrow** them, never widen them:

* ``<joint> = [lo, hi]``: a joint's range (rad; m for a prismatic joint), inside the hand's range;
* ``joint_speed = v``: one speed (rad/s) for every revolute joint, at most each one's own;
* ``[limits.speed] <joint> = v``: one joint's speed in its unit (rad/s or m/s), at most its own;
  it overrides ``joint_speed`` for that joint.

A task value beyond the hand's is refused with both numbers and where each comes from, so the planner
never plans, and the certifier never accepts, a motion the hand cannot make.  Whatever a task leaves
out is the hand's.  :func:`resolve_limits` is used by :func:`qsplan.planner.task.task.make_task`,
so every plan and every certificate reads the same :class:`JointLimits`.  Units SI.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qsplan.mechanics.errors import QsplanError

__all__ = ["PAPER_DEFAULTS", "LIMIT_KEYS", "JointLimits", "resolve_limits"]

#: The paper hand's limits when it is given by its parameters (no description): each finger turns
#: in ``(0.05, 3.09)`` rad, clear of the palm by 0.05 rad on both sides, at 0.5 rad/s (Section 5.2's
#: hand; the bundled ``paper_hand.toml`` says the same).
PAPER_DEFAULTS = {"range": (0.05, 3.09), "speed": 0.5}

#: The keys of ``[limits]`` besides the joints' names.
LIMIT_KEYS = ("joint_speed", "speed", "workpiece_speed", "workpiece_acceleration", "joint_acceleration", "acceleration",
              "release_acceleration")

#: A task's range may touch the hand's edge up to rounding of decimal values written in two files (rad or m).
EDGE_TOL = 1e-12


@dataclass(frozen=True, slots=True, eq=False)
class JointLimits:
    """Every joint's range and speed, after the task narrowed the hand's.

    Attributes
    ----------
    ranges : ndarray, shape (n_j, 2)
        ``[lo, hi]`` per joint (rad, m for a prismatic joint), read-only.
    speeds : ndarray, shape (n_j,)
        Largest speed per joint (rad/s, m/s), read-only.
    sources : tuple of str
        Per joint, where its speed comes from (``"hand"`` or ``"task"``), for reports.
    """

    ranges: np.ndarray
    speeds: np.ndarray
    sources: tuple


def _pair(value, field, unit) -> tuple:
    from qsplan.planner.task.fields import short_repr, task_number

    if not isinstance(value, (list, tuple, np.ndarray)) or len(value) != 2:
        raise QsplanError(f"{field}: expected two numbers [lo, hi] ({unit}); got {short_repr(value)}")
    lo, hi = (task_number(v, field, unit) for v in value)
    if not lo < hi:
        raise QsplanError(f"{field}: expected lo < hi (the joint must move); got [{lo:g}, {hi:g}]")
    return lo, hi


def resolve_limits(names, kinds, hand_ranges=None, hand_speeds=None, *, ranges=None, joint_speed=None, speeds=None,
                   hand_label: str = "the hand") -> JointLimits:  # fmt: skip
    """The limits a task's plans keep: the hand's, narrowed by the task's.

    Parameters
    ----------
    names, kinds : sequence of str, shape (n_j,)
        The hand's joints in order, and ``"revolute"`` or ``"prismatic"`` for each.
    hand_ranges : array-like, shape (n_j, 2), optional
        The hand's own ranges (rad or m); None: the hand states none (the paper hand's parameter form): the
        default is :data:`PAPER_DEFAULTS` and a task may set any range inside ``TASK_RANGES``.
    hand_speeds : array-like, shape (n_j,), optional
        The hand's own speeds (rad/s or m/s); None: as for ``hand_ranges``.
    ranges : dict or sequence, optional
        The task's ranges: ``{joint: [lo, hi]}`` for some joints, or one ``[lo, hi]`` per joint in order.
    joint_speed : float, optional
        rad/s: every revolute joint's speed.
    speeds : dict, optional
        ``{joint: speed}`` in each joint's unit; overrides ``joint_speed``.
    hand_label : str
        Names the hand in errors (e.g. ``"two_link_hand"``).

    Raises
    ------
    QsplanError
        Naming the field (``limits.<joint>``, ``limits.joint_speed``, ``limits.speed.<joint>``): not a number, out of
        :data:`qsplan.planner.task.fields.TASK_RANGES`, or beyond the hand's own limit.
    """
    from qsplan.planner.task.fields import field_name, in_task_range, short_repr, task_number

    names, n = tuple(names), len(names)
    units = ["rad" if k == "revolute" else "m" for k in kinds]
    # the hand's own limits bound the task's; a hand without any (the paper's parameter form) has only defaults
    if hand_ranges is None:
        out_r = np.tile(np.array(PAPER_DEFAULTS["range"], dtype=float), (n, 1))
        own_r = np.tile([-np.inf, np.inf], (n, 1))
    else:
        out_r = np.array(hand_ranges, dtype=float).reshape(n, 2)
        own_r = out_r.copy()
    if hand_speeds is None:
        out_s, own_s = np.full(n, PAPER_DEFAULTS["speed"], dtype=float), np.full(n, np.inf)
    else:
        out_s = np.array(hand_speeds, dtype=float).reshape(n)
        own_s = out_s.copy()
    src = ["hand"] * n
    if ranges is not None:
        if isinstance(ranges, dict):
            table = ranges
        elif isinstance(ranges, (list, tuple, np.ndarray)) and len(ranges) == n:
            table = dict(zip(names, ranges))
        else:
            raise QsplanError(f"limits: expected the ranges of the joints {', '.join(names)}; got {short_repr(ranges)}")
        for name, value in table.items():
            if name not in names:
                known = ", ".join(sorted((*names, *LIMIT_KEYS)))
                raise QsplanError(f"limits.{field_name(name)}: unknown field; expected some of {known} (the hand's "
                                  "joints by name)")  # fmt: skip
            j = names.index(name)
            lo, hi = _pair(value, f"limits.{name}", units[j])
            if units[j] == "rad":
                for v in (lo, hi):
                    in_task_range(v, f"limits.{name}", "joint_limit")
            a, b = own_r[j]
            if lo < a - EDGE_TOL or hi > b + EDGE_TOL:
                raise QsplanError(f"limits.{name}: [{lo:g}, {hi:g}] {units[j]} reaches beyond the range [{a:g}, {b:g}] "
                                  f"{units[j]} of {hand_label}; a task may narrow a hand's limits, not widen them")  # fmt: skip
            out_r[j] = (lo, hi)
    if joint_speed is not None:
        v = in_task_range(task_number(joint_speed, "limits.joint_speed", "rad/s", positive=True), "limits.joint_speed",
                          "joint_speed")  # fmt: skip
        revolute = [j for j in range(n) if units[j] == "rad"]
        if not revolute:
            raise QsplanError("limits.joint_speed: the hand has no revolute joint to apply it to (rad/s); give "
                              "[limits.speed] <joint> = v per joint (m/s for a prismatic joint)")  # fmt: skip
        for j in revolute:
            _speed_within(v, own_s[j], names[j], units[j], "limits.joint_speed", hand_label)
            out_s[j], src[j] = v, "task"
    if speeds is not None:
        if not isinstance(speeds, dict):
            raise QsplanError(f"limits.speed: expected a table of joint speeds {{joint = speed}}; got {short_repr(speeds)}")
        for name, value in speeds.items():
            if name not in names:
                raise QsplanError(f"limits.speed.{field_name(name)}: unknown joint; the hand's joints are "
                                  f"{', '.join(names)}")  # fmt: skip
            j, field = names.index(name), f"limits.speed.{name}"
            v = task_number(value, field, f"{units[j]}/s", positive=True)
            if units[j] == "rad":  # a prismatic joint's: positive and at most the hand's (whose file is range-checked)
                in_task_range(v, field, "joint_speed")
            _speed_within(v, own_s[j], name, units[j], field, hand_label)
            out_s[j], src[j] = v, "task"
    out_r.setflags(write=False)
    out_s.setflags(write=False)
    return JointLimits(out_r, out_s, tuple(src))


def _speed_within(v, own, name, unit, field, hand_label) -> None:
    if v > own * (1 + 1e-12):
        raise QsplanError(f"{field}: {v:g} {unit}/s is faster than joint {name}'s speed {own:g} {unit}/s in "
                          f"{hand_label}; a task may lower a hand's speed, not raise it")  # fmt: skip
