"""The fields of a task file's ``[hand]`` table and the number checks every task field shares.

A ``[hand]`` table gives the workpiece (``workpiece``, ``workpiece_mass``, ``palm_edge``, ``mu``) and the hand:
either the paper's hand by its parameters (:func:`qsplan.hands.paper_hand.two_finger.make_two_finger_hand`'s
arguments, the original form), or a hand description (:mod:`qsplan.hands.description`): ``file`` (a bundled
hand's name or a path, relative to the task file) or the description's own fields inline (``palm``,
``fingers``, ``name``, ``gravity``).  A description of the paper's form (two single-link fingers,
:func:`qsplan.hands.description.two_finger_form.two_finger_parameters`) becomes the paper's hand with its fast
closed forms; any other a :class:`qsplan.hands.chains.hand.ChainHand`.  Units SI.
"""

from __future__ import annotations

import numpy as np

from qsplan.mechanics.bands.effort import ForceMargin
from qsplan.mechanics.errors import QsplanError
from qsplan.mechanics.model.fields import in_range, short_repr

__all__ = ["PLAN_FORCE_MARGIN", "TASK_RANGES", "WORKPIECE_KEYS", "HandChoice", "check_hand", "hand_from_task_table",
           "start_joints_of", "task_disturbance",
           "in_task_range", "plan_force_margin", "short_repr", "task_number", "field_name"]

#: Plausible physical range ``(lo, hi)`` of every number of a task, with its unit; outside it a value is
#: a mistake (a unit slip, a typo), not a hand.  Reasons:
#:
#: * ``size`` (m): finger and palm dimensions and workpiece coordinates of a hand-scale gripper lie
#:   between a millimetre and a metre; the contact tolerance (1e-6 m) and the planner's steps
#:   assume that scale (finger sizes of 1e21 m overflowed the geometry).
#: * ``position`` (m): workpiece ``x`` on a palm at most a metre wide.
#: * ``mass`` (kg) and ``gravity`` (m/s^2): a workpiece two fingers can hold; Earth is 9.81, 100 is 10 g.
#: * ``friction``: no dry material pair exceeds a coefficient of about 2; 5 leaves room.
#: * ``torque_resolution`` (N m): finger motors resolve between 1e-6 and 10 N m; the loads of a hand
#:   this size are below 1 N m, so a resolution of 10 already leaves nothing plannable.
#: * ``joint_limit`` (rad): finger angles are measured from the palm's +x axis; above the palm is
#:   (0, pi), and a limit beyond a half turn either way (e.g. +-100 rad) describes no finger.
#: * ``joint_speed`` (rad/s): from 1e-3 (slower is holding still) to 10 (a fast servo).
#: * ``workpiece_speed`` (m/s): from 1e-4 (a 4 cm segment then takes 7 minutes; 1e-300 m/s gave joint
#:   velocities of 1e11 rad/s) to 0.5 (beyond, the inertial forces of a workpiece turning over a 5 cm
#:   corner, v^2/r, exceed gravity and the quasistatic model no longer holds).
#: * ``min_normal_force``, ``min_coulomb_slack`` (N): ``[controller]``'s force margin
#:   (:data:`PLAN_FORCE_MARGIN`, 0.05 N by default), from 0 (none) to 100 N:
#:   the margin covers loads the model leaves out (a mass error, the workpiece's inertia), and a
#:   hand-scale finger presses with tens of newtons (a human fingertip about 50 N), so a margin beyond
#:   100 N (the weight of 10 kg) asks for contact forces no such finger exerts (1e6 N was planned, with
#:   a command of 713,407 N m).
#: * ``disturbance`` (N, N, N m): ``[controller] disturbance``'s corners, from -100 to 100: a box of external
#:   wrenches on the workpiece (inertia at the time scaling's accelerations, bumps, a cable's pull) the bands
#:   withstand; the same 100 N as the force margin (10 kg's weight, beyond a hand-scale finger), and 100 N m at
#:   the workpiece (100 N at a metre, far beyond a palm-sized part).
TASK_RANGES = {
    "size": (1e-3, 1.0, "m"),
    "position": (-1.0, 1.0, "m"),
    "mass": (1e-3, 100.0, "kg"),
    "finger_mass": (0.0, 100.0, "kg"),
    "gravity": (0.0, 100.0, "m/s^2"),
    "friction": (0.0, 5.0, "friction coefficient"),
    "torque_resolution": (1e-6, 10.0, "N m"),
    "joint_limit": (-np.pi, np.pi, "rad"),
    "joint_speed": (1e-3, 10.0, "rad/s"),
    "workpiece_speed": (1e-4, 0.5, "m/s"),
    "min_normal_force": (0.0, 100.0, "N"),
    "min_coulomb_slack": (0.0, 100.0, "N"),
    "disturbance": (-100.0, 100.0, "N, N, N m"),
}


def field_name(key) -> str:
    """A key of a task file as an error names it: as written, cut to 40 characters (a 3 MB key is one short line)."""
    text = str(key)
    return text if len(text) <= 40 else text[:30] + "..." + text[-7:]


def task_number(value, field, unit, positive=False, nonnegative=False) -> float:
    if isinstance(value, (bool, str)):
        raise QsplanError(f"{field}: expected a number ({unit}); got {short_repr(value)}")
    try:
        x = float(value)
    except OverflowError:
        x = float("inf")
    except (TypeError, ValueError):
        raise QsplanError(f"{field}: expected a number ({unit}); got {short_repr(value)}") from None
    if not np.isfinite(x) or (positive and x <= 0) or (nonnegative and x < 0):
        kind = "positive finite" if positive else ("nonnegative finite" if nonnegative else "finite")
        raise QsplanError(f"{field}: expected a {kind} number ({unit}); got {short_repr(value)}")
    return x


def in_task_range(x: float, field: str, kind: str) -> float:
    """``x`` inside ``TASK_RANGES[kind]``; the error names the field, the range and a unit slip (mm, degrees)."""
    lo, hi, unit = TASK_RANGES[kind]
    return in_range(x, field, lo, hi, unit, f"qsplan.planner.task.task.TASK_RANGES[{kind!r}]", QsplanError)


def check_hand(hand) -> None:
    """Every size, mass and coefficient of a hand (and its workpiece) inside :data:`TASK_RANGES`
    (``hand.range_fields()``: :meth:`qsplan.hands.protocol.Hand.range_fields`; at the door, before a record becomes a
    described hand, the record's own, :meth:`qsplan.hands.paper_hand.two_finger.TwoFingerHand.range_fields`)."""
    for field, value, kind in hand.range_fields():
        in_task_range(value, field, kind)


def _paper_hand_from_table(table: dict):
    """A TwoFingerHand from a ``[hand]`` table of its parameters: keys checked, numbers checked before the geometry."""
    import inspect

    from qsplan.hands.paper_hand.two_finger import make_two_finger_hand

    allowed = set(inspect.signature(make_two_finger_hand).parameters)
    unknown = sorted(set(table) - allowed)
    if unknown:
        raise QsplanError(f"hand.{unknown[0]}: unknown field; expected some of {', '.join(sorted(allowed))}")
    _check_workpiece(table)
    for key, value in table.items():
        if key != "workpiece":
            task_number(value, f"hand.{key}", "SI units")
    try:
        return make_two_finger_hand(**table)
    except QsplanError as exc:
        raise QsplanError(f"hand.{exc}") from None


#: The keys of a ``[hand]`` table that describe the workpiece (and its friction), whatever the hand.
WORKPIECE_KEYS = ("workpiece", "workpiece_mass", "palm_edge", "mu")

#: The keys that make a ``[hand]`` table a hand description (else: the paper hand's parameters).
_DESCRIPTION_KEYS = ("file", "palm", "fingers", "name")


class HandChoice(tuple):
    """``(hand, joint_limits (n_j, 2) or None, joint_speeds (n_j,) or None)``: a task's hand and, for a described
    hand, the limits and speeds its description gives (the task's defaults)."""

    __slots__ = ()


def _check_workpiece(table: dict) -> None:
    if "workpiece" not in table:
        raise QsplanError("hand.workpiece: expected the workpiece polygon [[x, y], ...] (m); it is missing")
    wp = table["workpiece"]
    if not isinstance(wp, (list, tuple, np.ndarray)) or not 3 <= len(wp) <= 64:
        raise QsplanError(f"hand.workpiece: expected a polygon of 3 to 64 vertices [[x, y], ...] (m); got {short_repr(wp)}")
    for i, v in enumerate(wp):
        if not isinstance(v, (list, tuple, np.ndarray)) or len(v) != 2:
            raise QsplanError(f"hand.workpiece[{i}]: expected a vertex [x, y] (m); got {short_repr(v)}")
        for c in v:
            in_task_range(task_number(c, f"hand.workpiece[{i}]", "m"), f"hand.workpiece[{i}]", "position")


def hand_from_task_table(table: dict, base_dir=None) -> HandChoice:
    """The hand of a task's ``[hand]`` table (see the module docstring).

    Raises
    ------
    QsplanError
        Naming the field (``hand.<key>``; for a hand file, the file and the field in it).
    """
    from qsplan.hands.chains.hand import make_chain_hand
    from qsplan.hands.description.files import hand_from_table
    from qsplan.hands.described.build import as_hand
    from qsplan.hands.description.two_finger_form import two_finger_parameters
    from qsplan.hands.paper_hand.two_finger import make_two_finger_hand

    if not isinstance(table, dict):
        raise QsplanError(f"hand: expected a table; got {short_repr(table)}")
    if not any(k in table for k in _DESCRIPTION_KEYS):
        paper = _paper_hand_from_table(table)
        check_hand(paper)
        return HandChoice((as_hand(paper), None, None))
    desc = hand_from_table(table, "hand", extra_keys=frozenset(WORKPIECE_KEYS), base_dir=base_dir)
    _check_workpiece(table)
    kw = {k: table[k] for k in WORKPIECE_KEYS if k in table}
    for key in ("workpiece_mass", "mu"):
        if key in kw:
            task_number(kw[key], f"hand.{key}", "SI units")
    params = two_finger_parameters(desc)
    try:
        if params is not None:
            hand = make_two_finger_hand(**kw, **params)
        else:
            hand = make_chain_hand(desc, **kw)
    except QsplanError as exc:
        raise QsplanError(f"hand.{exc}") from None
    check_hand(hand)
    limits, speeds = np.asarray(desc.joint_limits, float), np.asarray(desc.joint_speeds, float)
    return HandChoice((as_hand(hand, own_limits=(limits, speeds)), limits, speeds))


#: The force margin of plans (task files' ``[controller] min_normal_force`` and
#: ``min_coulomb_slack``), N.  At a band edge of eq. (28) some normal force or cone slack is
#: zero, and near steep edges the model's normal forces are a few mN: any load the model
#: leaves out lifts that contact.  The torque error is covered by the band's width (the
#: command sits mid-band, at least the torque resolution wide); the margin covers the
#: rest.  0.05 N is 2.5 % of the demo workpiece's weight (0.2 kg, 1.96 N): the weight of
#: a 5 g mass error, or the inertial force of the workpiece accelerating at 0.25 m/s^2
#: (reaching the 0.01 m/s default speed limit in 40 ms), and ten times the few mN seen
#: near steep edges.  It costs the demo little: its narrowest guaranteed band goes from
#: 0.164 to 0.139 N m (normal forces change by ~2-4 N per N m of finger torque there),
#: still seven times the 0.02 N m torque resolution.
#: The slack margin binds only rolling contacts (the planner's 4S mode has none: a sliding
#: contact is on its cone's edge by definition, eq. 17).
PLAN_FORCE_MARGIN = ForceMargin(normal=0.05, slack=0.05)


def plan_force_margin(min_normal_force=None, min_coulomb_slack=None, field: str = "controller") -> ForceMargin:
    """A plan's :class:`ForceMargin` (N), :data:`PLAN_FORCE_MARGIN`'s value where one is not given.

    Each inside its plausible range (:data:`TASK_RANGES` ``['min_normal_force']``, ``['min_coulomb_slack']``,
    with the reason).  Errors name ``<field>.min_normal_force`` /
    ``<field>.min_coulomb_slack`` (the task file's keys).
    """
    values = []
    for name, v, default in (("min_normal_force", min_normal_force, PLAN_FORCE_MARGIN.normal),
                             ("min_coulomb_slack", min_coulomb_slack, PLAN_FORCE_MARGIN.slack)):  # fmt: skip
        v = default if v is None else v
        try:
            x = float(v) if not isinstance(v, (bool, str)) else np.nan
        except OverflowError:  # an integer of hundreds of digits
            x = np.inf
        except (TypeError, ValueError):
            x = np.nan
        if not (np.isfinite(x) and x >= 0):
            raise QsplanError(f"{field}.{name}: expected a nonnegative finite force (N); got {short_repr(v)}")
        values.append(in_task_range(x, f"{field}.{name}", name))
    return ForceMargin(*values)


def task_disturbance(table, field: str = "controller.disturbance"):
    """A task's ``[controller] disturbance`` table ``{lo = [fx, fy, m], hi = [fx, fy, m]}`` (N, N, N m; about the world
    origin, added to the workpiece's weight) as a :class:`qsplan.mechanics.bands.disturbance.WrenchBox`, None for
    none (absent, or zeros).  Each corner inside :data:`TASK_RANGES` ``["disturbance"]``.

    Raises
    ------
    QsplanError
        Naming ``controller.disturbance.<key>`` and the component.
    """
    from qsplan.mechanics.bands.disturbance import WrenchBox, check_wrench_box

    if table is None or isinstance(table, WrenchBox):
        return check_wrench_box(table)
    if not isinstance(table, dict):
        raise QsplanError(f"{field}: expected a table {{lo = [fx, fy, m], hi = [fx, fy, m]}} (N, N, N m); "
                          f"got {short_repr(table)}")  # fmt: skip
    extra = sorted(set(table) - {"lo", "hi"}, key=str)
    if extra:
        raise QsplanError(f"{field}.{field_name(extra[0])}: unknown field; expected lo and hi")
    corners = []
    for key in ("lo", "hi"):
        if key not in table:
            raise QsplanError(f"{field}.{key}: missing (3 numbers: force x, force y in N, moment in N m)")
        v = table[key]
        if not isinstance(v, (list, tuple)) or len(v) != 3:
            raise QsplanError(f"{field}.{key}: expected 3 numbers (N, N, N m); got {short_repr(v)}")
        corners.append([in_task_range(task_number(x, f"{field}.{key}[{i}]", "N or N m"), f"{field}.{key}[{i}]",
                                      "disturbance") for i, x in enumerate(v)])  # fmt: skip
    try:
        return check_wrench_box(WrenchBox(*corners))
    except QsplanError as exc:
        raise QsplanError(f"controller.{exc}") from None


def start_joints_of(hand, table) -> np.ndarray | None:
    """A described hand's ``[start]``: every free joint by name (rad or m), or none of them (the planner chooses)."""
    if not isinstance(table, dict):
        raise QsplanError(f"start: expected a table of the free joints' positions; got {short_repr(table)}")
    free = [hand.joint_names[j] for j in hand.free_joints]
    extra = sorted(set(table) - set(free))
    if extra:
        raise QsplanError(f"start.{field_name(extra[0])}: unknown field; expected the free joints {', '.join(free)} (each finger's "
                          "last joint closes onto the workpiece)")  # fmt: skip
    if not table:
        return None
    missing = [n for n in free if n not in table]
    if missing:
        raise QsplanError(f"start.{missing[0]}: missing (give every free joint: {', '.join(free)})")
    q = np.zeros(len(hand.joint_names))
    for j in hand.free_joints:
        q[j] = task_number(table[hand.joint_names[j]], f"start.{hand.joint_names[j]}", "rad or m")
    q.setflags(write=False)
    return q
