"""Where a task starts and where it must end: grasps named by workpiece features (issue 14's file contract).

A task without scripted ``[motion] waypoints`` has a ``[goal]`` table and the planner
(:mod:`qsplan.planner.search`) finds the sequence of 4S slides and regrasps itself::

    [goal]
    x = -0.03            # m: the workpiece's centre-of-mass x at the goal
    left = "edge:2"      # optional: the feature the left finger touches at the goal
    right = "vertex:1"   # optional: the same for the right finger
    theta = -0.5         # optional (rad, counter-clockwise; 0: resting on its palm edge, as at the start)
    palm = "vertex:1"    # optional: what rests on the palm at the goal, "edge:K" or "vertex:K"
    [start]              # optional: where each finger touches at the start (default: "inner")
    left = "inner"
    right = "edge:1"

A feature is ``"edge:K"`` (the fingertip on edge ``K``, from vertex ``K`` to vertex ``K + 1``)
or ``"vertex:K"`` (the finger's inner long edge on vertex ``K``), ``K`` the 0-based index into
the ``workpiece`` polygon **as written** in the task; at the start, ``"inner"`` means the inner
long edge on whichever vertex the geometry puts it (the only placement of the scripted tasks).

A goal gives at least one of ``x``, ``theta`` and ``palm``; with ``theta`` or ``palm``, ``x`` is optional.
``theta`` is the workpiece's orientation (rad, counter-clockwise, in [-pi, pi]): 0 is the workpiece resting on its
palm edge (its bottom edge, or the ``[hand] palm_edge``), as every task starts.  ``palm`` names what rests on the
palm at the goal, ``K`` as for the fingers.  The planner serves one formation today, ``palm_edge`` (the resting edge
on the palm, ``theta = 0``), placed by its ``x``: a goal that asks another orientation (``theta`` beyond
:data:`THETA_TOL` of 0, ``palm`` naming another edge or a vertex) or gives no ``x`` is a valid task that the planner
refuses (:func:`check_goal_served`, a :class:`GoalNotServedError`), before any planning.
Units SI (m, rad).
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np

from qsplan.mechanics.errors import NoAnswerError, QsplanError
from qsplan.planner.task.fields import task_number

__all__ = ["Goal", "FEATURE_KINDS", "GOAL_KEYS", "THETA_TOL", "GoalNotServedError", "check_goal_served", "feature_text",
           "goal_refusal", "goal_turns", "parse_feature", "make_goal", "reorients", "make_start_features", "palm_x_range", "task_positions"]

#: The feature kinds of a goal: the fingertip on an edge, the inner long edge on a vertex.
FEATURE_KINDS = ("edge", "vertex")

#: The keys of a ``[goal]`` table (a file contract: keys are added, never renamed).
GOAL_KEYS = ("x", "left", "right", "theta", "palm")

#: Largest |theta| (rad) of a goal that the palm-edge formation (theta = 0) serves: a TOML 0 or -0.0 parses exactly,
#: so this only absorbs the round-off of a computed value; 1e-9 rad turns a 0.1 m workpiece's corner by 1e-10 m,
#: far below any hand's accuracy.
THETA_TOL = 1e-9

_FEATURE = re.compile(r"^(edge|vertex):(\d{1,3})$")


def parse_feature(text, field: str, n_vertices: int, allow_inner: bool = False):
    """``(kind, K)`` of a feature string (``K`` in the polygon's order as written), or ``("inner", None)``.

    Raises
    ------
    QsplanError
        Naming ``field``: not a string, not ``"edge:K"``/``"vertex:K"``, ``K`` beyond the polygon.
    """
    if allow_inner and text == "inner":
        return ("inner", None)
    expected = '"edge:K" or "vertex:K"' + (' or "inner"' if allow_inner else "")
    if not isinstance(text, str):
        raise QsplanError(f"{field}: expected {expected} (K a 0-based index into the workpiece polygon); got {text!r}")
    m = _FEATURE.match(text.strip())
    if not m:
        raise QsplanError(f"{field}: expected {expected} (K a 0-based index into the workpiece polygon); got {text!r}")
    kind, k = m.group(1), int(m.group(2))
    if not 0 <= k < n_vertices:
        raise QsplanError(f"{field}: the workpiece has {n_vertices} vertices and edges (0 to {n_vertices - 1}); "
                          f"got {text!r}")  # fmt: skip
    return (kind, k)


@dataclass(frozen=True, slots=True)
class Goal:
    """The goal of an automatically planned task.

    Attributes
    ----------
    x : float or None
        Workpiece centre-of-mass x at the goal (m); None: not given (a goal with ``theta`` or ``palm``).
    left, right : (str, int) or None
        The feature each finger must touch at the goal, ``(kind, K)`` with ``K`` in the polygon's
        order as written; None: any.
    theta : float or None
        The workpiece's orientation at the goal (rad, counter-clockwise; 0: resting on its palm edge); None: not given.
    palm : (str, int) or None
        What rests on the palm at the goal, ``(kind, K)`` as the fingers' features; None: not given.
    """

    x: float | None
    left: tuple | None = None
    right: tuple | None = None
    theta: float | None = None
    palm: tuple | None = None

    def describe(self) -> str:
        """The goal in words."""
        parts = [] if self.x is None else [f"x = {self.x:.4g} m"]
        if self.theta is not None:
            parts.append(f"theta = {self.theta:.4g} rad")
        if self.palm is not None:
            parts.append(f"{self.palm[0]} {self.palm[1]} on the palm")
        for side, feat in (("left", self.left), ("right", self.right)):
            if feat is not None:
                parts.append(f"{side} finger on {feat[0]} {feat[1]}")
        return ", ".join(parts)


def make_goal(table, n_vertices: int, number) -> Goal:
    """A :class:`Goal` from a ``[goal]`` table (``number(value, field, unit)`` validates ``x``).

    Raises
    ------
    QsplanError
        Naming the field.
    """
    if not isinstance(table, dict):
        raise QsplanError(f"goal: expected a table with x (m), theta (rad) or palm and optionally left, right; "
                          f"got {table!r}")  # fmt: skip
    extra = sorted(set(table) - set(GOAL_KEYS))
    if extra:
        raise QsplanError(f"goal.{extra[0]}: unknown field; expected some of {', '.join(sorted(GOAL_KEYS))}")
    if not {"x", "theta", "palm"} & set(table):
        raise QsplanError("goal.x: missing: give x (m: the workpiece's x), or theta (rad: its orientation) or palm "
                          "(\"edge:K\" or \"vertex:K\": what rests on the palm)")  # fmt: skip
    x = number(table["x"], "goal.x", "m") if "x" in table else None
    theta = None
    if "theta" in table:
        theta = task_number(table["theta"], "goal.theta", "rad")
        if not -np.pi <= theta <= np.pi:
            raise QsplanError(f"goal.theta: expected an angle within [-pi, pi] rad (the workpiece's orientation, "
                              f"counter-clockwise); got {theta:g}")  # fmt: skip
    feats = {side: parse_feature(table[side], f"goal.{side}", n_vertices) if side in table else None
             for side in ("left", "right", "palm")}  # fmt: skip
    return Goal(x, feats["left"], feats["right"], theta, feats["palm"])


class GoalNotServedError(NoAnswerError):
    """A valid goal the planner cannot plan to yet: an orientation other than the palm-edge formation's, or no ``x``.

    Not bad input (the task is valid): no answer exists from today's planner.  ``field`` names the goal's field
    (``goal.theta``, ``goal.palm`` or ``goal.x``); the message says what exists and what is missing.
    """

    def __init__(self, field: str, message: str):
        super().__init__(message)
        self.field = field


#: Where a goal that turns the workpiece goes (said in the refusals of the goals the planner cannot place).
_REORIENTATION = ("a goal that turns the workpiece (theta, or palm naming another feature) is planned through the "
                  "flush instant, a hold and a pivot (docs/reorientation.md)")  # fmt: skip


def reorients(task) -> bool:
    """Whether ``task``'s goal asks another orientation than the start's (:func:`goal_turns`)."""
    return goal_turns(task.goal, task.hand)


def goal_turns(goal, hand) -> bool:
    """Whether ``goal`` asks another orientation than the start's: ``theta`` beyond :data:`THETA_TOL` of 0, or
    ``palm`` naming another feature than ``hand``'s resting edge (the formation search of :mod:`qsplan.planner.plan.turning`)."""
    if goal is None:
        return False
    resting = int(hand.user_edges[0])
    return bool((goal.theta is not None and abs(goal.theta) > THETA_TOL)
                or (goal.palm is not None and goal.palm != ("edge", resting)))  # fmt: skip


def goal_refusal(task) -> GoalNotServedError | None:
    """Why the planner refuses ``task``'s goal before planning (a :class:`GoalNotServedError`, not raised), or None.

    A goal that turns the workpiece (:func:`reorients`) goes to the reorientation route, which refuses what it
    cannot serve by name (:mod:`qsplan.planner.plan.turning`); a goal that keeps the start's orientation is placed
    by its x, so one without ``x`` is refused here.
    """
    goal = task.goal
    if goal is None or reorients(task):  # the formation search decides (qsplan.planner.plan.turning)
        return None
    resting = int(task.hand.user_edges[0])  # the edge the workpiece rests on, as the task's polygon numbers it
    if goal.x is None:
        return GoalNotServedError("goal.x", f"goal.x: missing: the goal keeps the start's orientation (the palm_edge "
                                            f"formation: edge {resting} on the palm, theta = 0), and the planner "
                                            "places it by the workpiece's x (m); "
                                            f"{_REORIENTATION}")  # fmt: skip
    return None


def check_goal_served(task) -> None:
    """Raise :func:`goal_refusal`'s :class:`GoalNotServedError` if the planner refuses ``task``'s goal."""
    refusal = goal_refusal(task)
    if refusal is not None:
        raise refusal


def make_start_features(table, n_vertices: int) -> tuple:
    """``(left, right)`` start features from a ``[start]`` table: ``(kind, K)`` or ``("inner", None)`` (default)."""
    if not isinstance(table, dict):
        raise QsplanError(f"start: expected a table with left and right features; got {table!r}")
    extra = sorted(set(table) - {"left", "right"})
    if extra:
        raise QsplanError(f"start.{extra[0]}: unknown field; expected some of left, right")
    return tuple(parse_feature(table.get(side, "inner"), f"start.{side}", n_vertices, allow_inner=True)
                 for side in ("left", "right"))  # fmt: skip


def palm_x_range(hand) -> tuple:
    """The workpiece x (m) over which its resting edge lies on the palm's top: ``(lo, hi)``.

    The workpiece rests on its bottom edge (vertices 0 and 1, relative to its centre of mass) on the palm's
    top edge ``y = 0``; both ends of that edge must be on the palm (the two palm contacts of every grasp,
    eq. 1), so ``x + V[0, 0] >= palm's left end`` and ``x + V[1, 0] <= palm's right end``.  Exact, from
    the hand's palm polygon (an asymmetric palm included).
    """
    palm = np.asarray(hand.manipulator.base_shape, dtype=float)
    top = palm[palm[:, 1] == 0.0, 0]
    V = hand.workpiece
    return float(top.min() - V[0, 0]), float(top.max() - V[1, 0])


def task_positions(task) -> list:
    """Every workpiece x (m) a task names, in order: ``[(where, field, x)]`` (the start, each waypoint, the goal).

    Positions are x along the palm-edge formation, the one the planner serves; the palm check that opens planning
    and the preview (:func:`qsplan.planner.plan.failure.palm_report`) reads them here.

    Raises
    ------
    GoalNotServedError
        The goal is not one of the palm-edge formation (:func:`check_goal_served`): it has no such position.
    """
    check_goal_served(task)
    out = [("the start", "motion.start_x", float(task.start_x))]
    last = len(task.waypoints) - 1
    for i, x in enumerate(task.waypoints):
        where = "the goal" if i == last else f"the end of segment {i + 1}"
        out.append((where, f"motion.waypoints[{i}]", float(x)))
    if task.goal is not None and task.goal.x is not None:  # a reorienting goal may give no x
        out.append(("the goal", "goal.x", float(task.goal.x)))
    return out


def feature_text(feature):
    """A task's finger feature (``("inner", None)``, ``("edge", K)``, ``("vertex", K)`` or None) as a grasp's ``matches``
    reads it (:func:`qsplan.hands.paper_hand.grasps.grasp_meets`): None (any), ``"vertex"`` (the start's ``"inner"``:
    the inner edge on whichever vertex), ``"edge:K"``, ``"vertex:K"``."""
    if feature is None:
        return None
    return "vertex" if feature[0] == "inner" else f"{feature[0]}:{feature[1]}"
