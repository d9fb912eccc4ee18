"""Where a task starts and where it must end: grasps named by workpiece features (issue 14's file contract).

A task without scripted ``[motion] waypoints`` has a ``[goal]`` table and the planner
(:mod:`qsplan.planner.search`) finds the sequence of 4S slides and regrasps itself::

    [goal]
    x = -0.03            # m: the workpiece's centre-of-mass x at the goal
    left = "edge:2"      # optional: the feature the left finger touches at the goal
    right = "vertex:1"   # optional: the same for the right finger
    [start]              # optional: where each finger touches at the start (default: "inner")
    left = "inner"
    right = "edge:1"

A feature is ``"edge:K"`` (the fingertip on edge ``K``, from vertex ``K`` to vertex ``K + 1``)
or ``"vertex:K"`` (the finger's inner long edge on vertex ``K``), ``K`` the 0-based index into
the ``workpiece`` polygon **as written** in the task; at the start, ``"inner"`` means the inner
long edge on whichever vertex the geometry puts it (the only placement of the scripted tasks).
Units SI (m).
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np

from qsplan.mechanics.errors import QsplanError

__all__ = ["Goal", "FEATURE_KINDS", "feature_text", "parse_feature", "make_goal", "make_start_features", "palm_x_range",
           "task_positions"]

#: The feature kinds of a goal: the fingertip on an edge, the inner long edge on a vertex.
FEATURE_KINDS = ("edge", "vertex")

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
    x : float
        Workpiece centre-of-mass x at the goal (m).
    left, right : (str, int) or None
        The feature each finger must touch at the goal, ``(kind, K)`` with ``K`` in the polygon's
        order as written; None: any.
    """

    x: float
    left: tuple | None = None
    right: tuple | None = None

    def describe(self) -> str:
        """The goal in words."""
        parts = [f"x = {self.x:.4g} m"]
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
        raise QsplanError(f"goal: expected a table with x (m) and optionally left, right; got {table!r}")
    extra = sorted(set(table) - {"x", "left", "right"})
    if extra:
        raise QsplanError(f"goal.{extra[0]}: unknown field; expected some of left, right, x")
    if "x" not in table:
        raise QsplanError("goal.x: missing (m, the workpiece's x at the goal)")
    x = number(table["x"], "goal.x", "m")
    feats = {side: parse_feature(table[side], f"goal.{side}", n_vertices) if side in table else None
             for side in ("left", "right")}  # fmt: skip
    return Goal(x, feats["left"], feats["right"])


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
    from qsplan.hands.interface import manipulator_of

    palm = np.asarray(manipulator_of(hand).base_shape, dtype=float)
    top = palm[palm[:, 1] == 0.0, 0]
    V = hand.workpiece
    return float(top.min() - V[0, 0]), float(top.max() - V[1, 0])


def task_positions(task) -> list:
    """Every workpiece x (m) a task names, in order: ``[(where, field, x)]`` (the start, each waypoint, the goal)."""
    out = [("the start", "motion.start_x", float(task.start_x))]
    last = len(task.waypoints) - 1
    for i, x in enumerate(task.waypoints):
        where = "the goal" if i == last else f"the end of segment {i + 1}"
        out.append((where, f"motion.waypoints[{i}]", float(x)))
    if task.goal is not None:
        out.append(("the goal", "goal.x", float(task.goal.x)))
    return out


def feature_text(feature):
    """A task's finger feature (``("inner", None)``, ``("edge", K)``, ``("vertex", K)`` or None) as a grasp's ``matches``
    reads it (:func:`qsplan.hands.grasps.grasp_meets`): None (any), ``"vertex"`` (the start's ``"inner"``: the inner
    edge on whichever vertex), ``"edge:K"``, ``"vertex:K"``."""
    if feature is None:
        return None
    return "vertex" if feature[0] == "inner" else f"{feature[0]}:{feature[1]}"
