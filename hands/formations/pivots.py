"""Pivot formations generated per workpiece and hand: the workpiece turning on a vertex on the palm (issue 32).

A pivot keeps one workpiece vertex on the palm's top (:attr:`Pivot.vertex`), one finger lying flush along a side of
the workpiece (:attr:`Pivot.flush`, :attr:`Pivot.edge`: two contacts, the ends of the overlap) and the other finger
on one feature (:attr:`Pivot.other`, a :class:`FingerFeature`): four constraints on the pose and the closing joints,
a one-parameter manifold in the workpiece's angle theta (a hand's free joints held).  It starts at a **flush
instant**, a configuration of the palm-edge slide where the flush finger lies along its side (:func:`flush_instant`:
the bottom edge on the palm, five contacts), and turns away from the flush finger: clockwise on the bottom edge's
right end for the left finger flush, counter-clockwise on its left end for the right one (the paper's Section 5.2
and its mirror image).

Everything is generated from the hand and the workpiece (:func:`pivot_formations`): each finger, each side it can
lie along, each feature of the other finger (:data:`FINGER_FEATURES`, one registry: a workpiece vertex on the
finger's inner edge, a finger corner on a workpiece edge).  The manifold is solved by one algorithm for every hand
(:mod:`qsplan.hands.formations.manifold`); the paper hand's closed form, derived apart from it for the tests
(``tests/reference/paper_pivot.py``), agrees with it to 1e-14 in the pose.  Where a row's contacts are, in the
canonical order a plan's letters follow, is the polygon search's (:mod:`qsplan.hands.contacts.found`): a pivot adds
no second way to name contacts.  Units SI.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np

from qsplan.hands.formations.manifold import VertexOnLine, project, sweep
from qsplan.mechanics.errors import QsplanError

__all__ = ["FINGER_FEATURES", "FLUSH_STARTS", "CornerOnEdge", "FingerFeature", "Pivot", "PivotPath", "VertexOnFinger",
           "finger_sides", "flush_instant", "flush_pose", "pivot_formations", "pivot_from_name", "pivot_path"]

#: Workpiece x (fractions of the palm's range) from which :func:`flush_instant` starts Newton's method: the flush
#: configuration is unique on a palm but its basin is not the whole palm (a finger folded past the workpiece).
FLUSH_STARTS = np.linspace(0.1, 0.9, 9)

#: The fingers, and the turning direction (sign of theta) of a pivot with each one flush.
_TURN = {"left": -1.0, "right": 1.0}


class FingerFeature(Protocol):
    """What a pivot's non-flush finger touches: a value that says how (one gap constraint) and in words.

    Attributes
    ----------
    kind : str
        Its key in :data:`FINGER_FEATURES`.
    key : str
        Names it among its hand's candidates, in :attr:`Pivot.name` (letters and digits: ``vertex2``, ``corner2e1``).
    """

    kind: str

    @property
    def key(self) -> str: ...

    def constraint(self, hand, finger: str) -> VertexOnLine:
        """The gap constraint that keeps ``finger`` on it (:mod:`qsplan.hands.formations.manifold`)."""

    def words(self, hand) -> str:
        """In words, the task's numbering (``on vertex 2``)."""


@dataclass(frozen=True, slots=True)
class VertexOnFinger:
    """The finger's inner edge on a workpiece vertex (internal numbering)."""

    vertex: int
    kind = "vertex"

    @property
    def key(self) -> str:
        return f"vertex{self.vertex}"

    def constraint(self, hand, finger: str) -> VertexOnLine:
        from qsplan.hands.contacts.sets import finger_inner_edge

        return VertexOnLine("workpiece", self.vertex, finger, finger_inner_edge(hand, finger))

    def words(self, hand) -> str:
        return f"on vertex {int(hand.user_vertices[self.vertex])}"


@dataclass(frozen=True, slots=True)
class CornerOnEdge:
    """A corner of the finger's last link (its ring's vertex ``corner``) on a workpiece edge (internal numbering)."""

    corner: int
    edge: int
    kind = "corner"

    @property
    def key(self) -> str:
        return f"corner{self.corner}e{self.edge}"

    def constraint(self, hand, finger: str) -> VertexOnLine:
        return VertexOnLine(finger, self.corner, "workpiece", self.edge)

    def words(self, hand) -> str:
        return f"its corner {self.corner} on edge {int(hand.user_edges[self.edge])}"


#: What the non-flush finger of a pivot may touch, by kind: each kind's candidates on a hand and workpiece.  A new
#: kind (a value of the :class:`FingerFeature` protocol) is one entry here: the search, the names, the certifier's
#: formation check and the plots take it from here.
FINGER_FEATURES = {
    "vertex": lambda hand, finger: tuple(VertexOnFinger(v) for v in range(len(hand.workpiece))),
    "corner": lambda hand, finger: tuple(CornerOnEdge(c, e) for c in _tip_corners(hand, finger)
                                         for e in range(len(hand.workpiece))),
}


def _tip_corners(hand, finger: str) -> tuple:
    """The corners of a finger's last link farthest along it (its tip), as ring indices."""
    from qsplan.hands.contacts.sets import finger_link

    shape = np.asarray(hand.manipulator.joints[finger_link(hand, finger)].link_shape, dtype=float)
    far = shape[:, 0].max()
    return tuple(int(i) for i in np.flatnonzero(np.isclose(shape[:, 0], far)))


@dataclass(frozen=True, slots=True)
class Pivot:
    """A pivot formation (the module docstring).

    Attributes
    ----------
    vertex : int
        The workpiece vertex on the palm (internal numbering): 1 (the bottom edge's right end) for a clockwise turn,
        0 for a counter-clockwise one.
    flush : str
        ``"left"`` or ``"right"``: the finger lying flush.
    edge : int
        The workpiece edge it lies along (internal numbering).
    other : FingerFeature
        The other finger's contact.
    """

    vertex: int
    flush: str
    edge: int
    other: object

    @property
    def direction(self) -> float:
        """The sign of theta's change: -1 clockwise (the left finger flush), +1 counter-clockwise."""
        return _TURN[self.flush]

    @property
    def other_finger(self) -> str:
        return "right" if self.flush == "left" else "left"

    @property
    def name(self) -> str:
        """A key naming the formation (internal numbering): ``pivot:v1:left:e3:vertex2``."""
        return f"pivot:v{self.vertex}:{self.flush}:e{self.edge}:{self.other.key}"

    def words(self, hand) -> str:
        """In words, the task's numbering: ``pivot on vertex 1 (clockwise), the left finger flush on edge 3, the
        right finger on vertex 2``."""
        turn = "clockwise" if self.direction < 0 else "counter-clockwise"
        return (f"pivot on vertex {int(hand.user_vertices[self.vertex])} ({turn}), the {self.flush} finger flush on "
                f"edge {int(hand.user_edges[self.edge])}, the {self.other_finger} finger {self.other.words(hand)}")

    def constraints(self, hand) -> tuple:
        """The manifold's four constraints: the pivot vertex on the palm's top, both ends of the flush edge on the
        flush finger's inner edge (its line), the other finger's feature."""
        from qsplan.hands.contacts.sets import finger_inner_edge, palm_top_edge

        k, inner = len(hand.workpiece), finger_inner_edge(hand, self.flush)
        return (VertexOnLine("workpiece", self.vertex, "palm", palm_top_edge(hand)),
                VertexOnLine("workpiece", self.edge, self.flush, inner),
                VertexOnLine("workpiece", (self.edge + 1) % k, self.flush, inner),
                self.other.constraint(hand, self.other_finger))  # fmt: skip

    def flush_constraints(self, hand) -> tuple:
        """The flush instant's five: the bottom edge's other end on the palm too."""
        from qsplan.hands.contacts.sets import palm_top_edge

        lifting = 1 - self.vertex
        return (VertexOnLine("workpiece", lifting, "palm", palm_top_edge(hand)), *self.constraints(hand))

    def lifting_vertex(self) -> int:
        """The bottom edge's end that lifts off the palm as the pivot starts."""
        return 1 - self.vertex


def pivot_from_name(name: str, hand) -> Pivot | None:
    """The pivot formation of ``hand`` that :attr:`Pivot.name` names (``pivot:v1:left:e3:vertex2``,
    ``pivot:v0:right:e1:corner3e2``): its feature the candidate of :data:`FINGER_FEATURES` with that key; None where
    ``name`` names none (another formation, not a formation's name, or a feature this hand does not have)."""
    import re

    m = re.fullmatch(r"pivot:v(\d+):(left|right):e(\d+):(\w+)", str(name))
    if m is None:
        return None
    flush = m[2]
    other = "right" if flush == "left" else "left"
    for candidates in FINGER_FEATURES.values():
        for feature in candidates(hand, other):
            if feature.key == m[4]:
                return Pivot(int(m[1]), flush, int(m[3]), feature)
    return None


def finger_sides(hand, finger: str) -> tuple:
    """The workpiece edges (internal numbering) ``finger`` can lie flush along, longest first: a side facing it
    (the left finger's run downward counter-clockwise, the right finger's upward), not the bottom edge."""
    V = np.asarray(hand.workpiece, dtype=float)
    d = np.roll(V, -1, axis=0) - V  # edge k from vertex k to k + 1
    rising = d[:, 1] > 0.0
    ks = np.flatnonzero(~rising & (d[:, 1] < 0.0)) if finger == "left" else np.flatnonzero(rising)
    return tuple(int(k) for k in sorted(ks, key=lambda k: (-np.hypot(*d[k]), k)))


def _moving(hand) -> tuple:
    """Indices into a configuration ``(x, y, theta, q)`` of the joints that move with the workpiece: each finger's
    closing joint (a hand's free joints are held)."""
    return tuple(3 + j for j in hand.closing_joints)


def flush_pose(hand, flush: str, edge: int, free=None):
    """The configuration ``(x, y, 0, q)`` of the palm-edge slide where ``flush``'s finger lies flush along workpiece
    ``edge`` (the bottom edge on the palm, both ends of ``edge`` on the finger's inner edge, overlapping it): Newton's
    method in x and the finger's closing joint from :data:`FLUSH_STARTS` along the palm; the other finger's closing
    joint left mid-range.  ``free``: the free joints' values (rad or m; default mid-range).  None where there is none.
    """
    from qsplan.hands.contacts.sets import finger_inner_edge, palm_top_edge
    from qsplan.hands.formations.manifold import along_edges

    k, inner = len(hand.workpiece), finger_inner_edge(hand, flush)
    cons = (VertexOnLine("workpiece", 0, "palm", palm_top_edge(hand)), VertexOnLine("workpiece", 1, "palm", palm_top_edge(hand)),
            VertexOnLine("workpiece", edge, flush, inner), VertexOnLine("workpiece", (edge + 1) % k, flush, inner))
    joint = 3 + hand.closing_joints[0 if flush == "left" else 1]
    lo, hi = _palm_x(hand)
    guess = _closing_guess(hand, flush, edge, free)
    for s in FLUSH_STARTS:
        c0 = np.concatenate([[lo + s * (hi - lo), hand.rest_height, 0.0], _start_joints(hand, free)])
        c0[joint] = guess
        c = project(hand, cons, c0, [0, joint])  # y and theta exact on the palm edge
        if c is None:
            continue
        along = along_edges(hand, cons, c)
        if np.all((along[:2] >= 0.0) & (along[:2] <= 1.0)) and _overlap(along[2:]) > 0.0:
            return c
    return None


def flush_instant(hand, pivot: Pivot, free=None, pose=None):
    """The configuration ``(x, y, 0, q)`` where ``pivot`` starts: :func:`flush_pose` (given as ``pose`` when already
    found), the other finger closed onto its feature (Newton's method in its closing joint), the feature on its edge
    itself (not its line's extension).  None where there is none."""
    from qsplan.hands.formations.manifold import along_edges

    c = flush_pose(hand, pivot.flush, pivot.edge, free) if pose is None else np.array(pose, dtype=float)
    if c is None:
        return None
    other = pivot.other.constraint(hand, pivot.other_finger)
    joint = 3 + hand.closing_joints[0 if pivot.other_finger == "left" else 1]
    c = project(hand, (other,), c, [joint])
    if c is None or not 0.0 <= along_edges(hand, (other,), c)[0] <= 1.0:
        return None
    return c


def _overlap(along) -> float:
    """The length (fraction of the finger's inner edge) over which the flush edge's two ends, at fractions ``along`` of
    the finger's inner edge, overlap it."""
    a, b = np.sort(np.asarray(along, dtype=float))
    return float(min(b, 1.0) - max(a, 0.0))


def _palm_x(hand) -> tuple:
    palm = np.asarray(hand.manipulator.base_shape, dtype=float)
    top = palm[np.isclose(palm[:, 1], palm[:, 1].max()), 0]
    V = hand.workpiece
    return float(top.min() - V[0, 0]), float(top.max() - V[1, 0])


def _start_joints(hand, free) -> np.ndarray:
    lim = np.asarray(hand.description.joint_limits, dtype=float)
    q = 0.5 * (lim[:, 0] + lim[:, 1])
    if free is not None:
        q[list(hand.free_joints)] = np.asarray(free, dtype=float)
    return q


def _closing_guess(hand, flush: str, edge: int, free=None) -> float:
    """A first guess of the flush finger's closing joint at its flush instant: its last link along the side (its
    absolute angle the side's, the link's inner edge facing the workpiece); a prismatic joint mid-range."""
    man = hand.manipulator
    f = 0 if flush == "left" else 1
    chain = hand.finger_joints[f]
    lim = np.asarray(hand.description.joint_limits, dtype=float)
    if man.joints[chain[-1]].kind != "revolute":
        return float(0.5 * (lim[chain[-1], 0] + lim[chain[-1], 1]))
    V = np.asarray(hand.workpiece, dtype=float)
    d = V[(edge + 1) % len(V)] - V[edge]
    side = float(np.arctan2(d[1], d[0]))
    # the left finger's inner edge faces right: its link runs up the side, against the edge's (downward) direction;
    # the right finger's faces left: along the (upward) edge
    absolute = side + np.pi if flush == "left" else side
    held = _start_joints(hand, free)
    before = sum(held[j] for j in chain[:-1] if man.joints[j].kind == "revolute")
    return float(np.angle(np.exp(1j * (absolute - before))))


def pivot_formations(hand, free=None) -> tuple:
    """Every pivot formation of ``hand`` and its workpiece: each finger flush along each side facing it
    (:func:`finger_sides`), turning away from it on the bottom edge's far end, the other finger on each feature of
    :data:`FINGER_FEATURES` it touches at the flush instant (:func:`flush_instant` exists), the free joints (a chain
    finger's all but its last) held at ``free`` (rad or m; default mid-range).  In a fixed order: the left finger
    flush first (the paper's), sides longest first, features as the registry lists them.

    Returns
    -------
    tuple of (Pivot, ndarray)
        Each formation and its flush instant ``(x, y, 0, q)``.
    """
    out = []
    for flush in ("left", "right"):
        vertex = 1 if flush == "left" else 0
        other = "right" if flush == "left" else "left"
        for edge in finger_sides(hand, flush):
            try:
                pose = flush_pose(hand, flush, edge, free)
            except QsplanError:  # a finger without an inner edge or polygon: no flush
                pose = None
            if pose is None:
                continue
            for kind, candidates in FINGER_FEATURES.items():
                for feature in candidates(hand, other):
                    pivot = Pivot(vertex, flush, edge, feature)
                    c = flush_instant(hand, pivot, free, pose)
                    if c is not None and _touches_only(hand, pivot, c):
                        out.append((pivot, c))
    return tuple(out)


def _touches_only(hand, pivot: Pivot, c) -> bool:
    """Whether at ``c`` the polygons show exactly the flush instant's five contacts and no two bodies overlap (the
    other finger really closes on its feature, nothing else, and no finger passes through the palm or the other)."""
    from qsplan.hands.contacts.found import ordered_contacts
    from qsplan.mechanics.errors import SceneError

    try:
        five = len(ordered_contacts(hand, c[:3], c[3:])) == 5
    except SceneError:  # a body in the workpiece
        return False
    return five and not hand.collisions(c[:3], c[3:], first=True)


@dataclass(frozen=True, slots=True, eq=False)
class PivotPath:
    """A pivot's manifold at angles ``theta`` (:func:`pivot_path`).

    Attributes
    ----------
    pivot : Pivot
    theta : ndarray, shape (n,)
        Workpiece angles (rad), from the start's.
    pose : ndarray, shape (n, 3)
    q : ndarray, shape (n, n_j)
    dpose : ndarray, shape (n, 3)
        ``d pose / d theta`` (theta's 1).
    dq : ndarray, shape (n, n_j)
        ``d q / d theta`` (a free joint's 0).
    reached : int
        Rows the manifold reached (the rest NaN: no configuration, a finger out of reach).
    """

    pivot: Pivot
    theta: np.ndarray
    pose: np.ndarray
    q: np.ndarray
    dpose: np.ndarray
    dq: np.ndarray
    reached: int


def pivot_path(hand, pivot: Pivot, start, thetas) -> PivotPath:
    """``pivot``'s manifold from configuration ``start`` (on it: its flush instant, or an earlier path's row) at each
    of ``thetas`` (rad, in order from ``start``'s angle): :func:`qsplan.hands.formations.manifold.sweep` along theta."""
    thetas = np.asarray(thetas, dtype=float)
    free = [0, 1] + list(_moving(hand))
    m = sweep(hand, pivot.constraints(hand), np.asarray(start, dtype=float), 2, thetas, free)
    return PivotPath(pivot, thetas, m.pose, m.q, m.dc[:, :3], m.dc[:, 3:], m.reached)
