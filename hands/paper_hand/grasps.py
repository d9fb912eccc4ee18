"""Grasps of the two-finger hand: where each finger touches the workpiece, in the user's numbering.

A finger touches the workpiece one of two ways (its *placement*):

* :class:`OnVertex` - its inner long edge on a workpiece vertex, the tangency of
  :func:`qsplan.hands.paper_hand.two_finger.finger_angles` (which vertex is decided by the geometry at each
  workpiece x, unless the placement names one); written ``"vertex"`` or ``"vertex:K"``;
* :class:`TipOnEdge` - a tip corner on workpiece edge ``K``; written ``"edge:K"`` (the finger's inner
  corner, ``branch`` 0) or ``"edge:K:1"`` (its outer corner, ``branch`` 1).

A :class:`Grasp` pairs a left and a right placement.  Indices are the user's: ``K`` counts the
``workpiece`` polygon as written (0-based), and edge ``K`` runs from vertex ``K`` to ``K + 1``;
:func:`make_two_finger_hand <qsplan.hands.paper_hand.two_finger.make_two_finger_hand>` re-orders the polygon, and
:func:`internal_vertex`, :func:`internal_edge`, :func:`user_vertex`, :func:`user_edge` convert.
The configurations of a grasp are in :mod:`qsplan.hands.paper_hand.grasp_geometry`.
"""

from __future__ import annotations

from dataclasses import dataclass

from qsplan.hands.paper_hand.two_finger import JOINT_NAMES, TwoFingerHand
from qsplan.mechanics.errors import SceneError

__all__ = [
    "Grasp",
    "OnVertex",
    "TipOnEdge",
    "internal_edge",
    "internal_vertex",
    "parse_goal",
    "parse_grasp",
    "parse_placement",
    "grasp_meets",
    "no_placement_words",
    "placement_matches",
    "touch_words",
    "user_edge",
    "user_vertex",
]


def _maps(hand: TwoFingerHand):
    """``(vertex_order, vertex_of_user)`` of the hand, the identity when it does not record them."""
    k = len(hand.workpiece)
    order = hand.vertex_order if hand.vertex_order is not None else tuple(range(k))
    of_user = hand.vertex_of_user if hand.vertex_of_user is not None else tuple(range(k))
    return order, of_user


def _index(value, n: int, field: str, what: str) -> int:
    if isinstance(value, bool) or not hasattr(value, "__index__") or not 0 <= int(value) < n:
        kind, _, where = what.partition(" ")
        raise SceneError(f"{field}: expected {'an' if kind[0] in 'aeiou' else 'a'} {kind} index in [0, {n}) {where}; got {value!r}")
    return int(value)


def internal_vertex(hand: TwoFingerHand, vertex, field: str = "vertex") -> int:
    """The hand's vertex (``hand.workpiece`` row) of the user's vertex ``vertex`` (a row of the polygon as written)."""
    of_user = _maps(hand)[1]
    return of_user[_index(vertex, len(of_user), field, "vertex (of the workpiece as written)")]


def user_vertex(hand: TwoFingerHand, vertex, field: str = "vertex") -> int:
    """The user's vertex (row of the polygon as written) of the hand's vertex ``vertex``."""
    order = _maps(hand)[0]
    return order[_index(vertex, len(order), field, "vertex (of hand.workpiece)")]


def internal_edge(hand: TwoFingerHand, edge, field: str = "edge") -> int:
    """The hand's edge (from ``hand.workpiece`` row ``e`` to ``e + 1``) of the user's edge ``edge`` (vertex ``K`` to ``K + 1``
    as written; the same segment, traversed the other way when the user's polygon is clockwise)."""
    of_user = _maps(hand)[1]
    n, k = len(of_user), len(hand.workpiece)
    K = _index(edge, n, field, "edge (of the workpiece as written)")
    a, b = of_user[K], of_user[(K + 1) % n]
    if b == (a + 1) % k:
        return a
    if a == (b + 1) % k:
        return b
    raise SceneError(f"{field}: edge {K} of the workpiece as written has zero length (vertex {(K + 1) % n} repeats vertex {K})")


def user_edge(hand: TwoFingerHand, edge, field: str = "edge") -> int:
    """The user's edge (vertex ``K`` to ``K + 1`` as written) of the hand's edge ``edge``; the first such ``K``."""
    of_user = _maps(hand)[1]
    n, k = len(of_user), len(hand.workpiece)
    e = _index(edge, k, field, "edge (of hand.workpiece)")
    ends = {e, (e + 1) % k}
    return next(K for K in range(n) if {of_user[K], of_user[(K + 1) % n]} == ends)


@dataclass(frozen=True, slots=True)
class OnVertex:
    """The finger's inner long edge on a workpiece vertex (the tangency of ``finger_angles``).

    Attributes
    ----------
    vertex : int or None
        The vertex (user numbering) it must touch; None: whichever the geometry picks at each x.
    """

    vertex: int | None = None

    def __str__(self) -> str:
        return "vertex" if self.vertex is None else f"vertex:{self.vertex}"


@dataclass(frozen=True, slots=True)
class TipOnEdge:
    """A tip corner of the finger on a workpiece edge, inside it.

    Attributes
    ----------
    edge : int
        The edge (user numbering: vertex ``edge`` to ``edge + 1`` as written).
    branch : {0, 1}
        Which of the two circle/line solutions: 0 puts the finger's *inner* tip corner on the edge
        (the corner on the side the finger leans towards: link corner ``(L, -w)`` of the left finger,
        ``(L, +w)`` of the right), 1 its outer corner.  Each is one closed-form branch, continuous in
        the workpiece x wherever it exists (:func:`qsplan.hands.paper_hand.grasp_geometry.tip_angles`).
    """

    edge: int
    branch: int = 0

    def __str__(self) -> str:
        return f"edge:{self.edge}" + (f":{self.branch}" if self.branch else "")


def parse_goal(text, field: str = "goal"):
    """``(kind, index, branch)`` of a placement string: ``"vertex"`` or ``"edge"``, the user's index or None, the branch
    or None where not written.  Raises :class:`SceneError` naming ``field`` when ``text`` is not one of the forms."""
    expected = "'vertex', 'vertex:K', 'edge:K' or 'edge:K:B' (K a 0-based index into the workpiece as written, B 0 or 1)"
    if not isinstance(text, str):
        raise SceneError(f"{field}: expected a string {expected}; got {text!r}")
    parts = text.strip().split(":")
    try:
        nums = [int(p) for p in parts[1:]]
    except ValueError:
        raise SceneError(f"{field}: expected {expected}; got {text!r}") from None
    ok = (parts[0] == "vertex" and len(nums) <= 1) or (parts[0] == "edge" and len(nums) in (1, 2))
    if not ok or any(v < 0 for v in nums) or (len(nums) == 2 and nums[1] not in (0, 1)):
        raise SceneError(f"{field}: expected {expected}; got {text!r}")
    return parts[0], (nums[0] if nums else None), (nums[1] if len(nums) == 2 else None)


def parse_placement(text, field: str = "placement"):
    """The :class:`OnVertex` or :class:`TipOnEdge` written ``text`` (``str(placement)`` gives it back).

    Raises
    ------
    SceneError
        Naming ``field`` when ``text`` is not one of the forms.
    """
    kind, index, branch = parse_goal(text, field)
    return OnVertex(index) if kind == "vertex" else TipOnEdge(index, branch or 0)


def placement_matches(placement, goal, field: str = "goal") -> bool:
    """Whether ``placement`` can meet the goal string ``goal`` (None: anything); see :meth:`Grasp.matches`."""
    if goal is None:
        return True
    kind, index, branch = parse_goal(goal, field)
    if kind == "vertex":
        return isinstance(placement, OnVertex) and (index is None or placement.vertex in (None, index))
    return isinstance(placement, TipOnEdge) and placement.edge == index and branch in (None, placement.branch)


@dataclass(frozen=True, slots=True)
class Grasp:
    """Where each finger touches the workpiece: a left and a right placement (user numbering)."""

    left: OnVertex | TipOnEdge
    right: OnVertex | TipOnEdge

    @property
    def label(self) -> str:
        """``"L vertex / R edge:2"``: each finger's placement as :func:`parse_placement` reads it."""
        return f"L {self.left} / R {self.right}"

    def __str__(self) -> str:
        return self.label

    def matches(self, goal_left=None, goal_right=None) -> bool:
        """Whether the grasp can meet a goal: ``"edge:K"`` (any branch unless ``"edge:K:B"``) and ``"vertex"`` are
        met by the placement itself, ``"vertex:K"`` by an :class:`OnVertex` wherever it touches vertex ``K``
        (:meth:`qsplan.hands.paper_hand.grasp_geometry.GraspConfigurations.matches` says where); None: anything.

        Raises
        ------
        SceneError
            Naming ``goal_left`` or ``goal_right`` when it is not a placement string.
        """
        return placement_matches(self.left, goal_left, "goal_left") & placement_matches(self.right, goal_right, "goal_right")


def parse_grasp(text, field: str = "grasp") -> Grasp:
    """The :class:`Grasp` labelled ``text`` (``"L vertex / R edge:2"``, as :attr:`Grasp.label` writes it)."""
    parts = text.split("/") if isinstance(text, str) else []
    sides = [p.strip().split(None, 1) for p in parts]
    if len(sides) != 2 or [s[0] for s in sides] != ["L", "R"] or any(len(s) != 2 for s in sides):
        raise SceneError(f"{field}: expected 'L <placement> / R <placement>'; got {text!r}")
    left, right = (parse_placement(s[1], f"{field}.{name}") for s, name in zip(sides, JOINT_NAMES))
    return Grasp(left, right)


def touch_words(hand, grasp, finger: int, touched: int) -> str:
    """What finger ``finger`` (0 left, 1 right) of ``grasp`` touches, in words and the polygon's numbering as written:
    a paper :class:`Grasp` by its placement and the feature ``touched`` (the hand's numbering), a
    :class:`~qsplan.hands.protocol.ChainGrasp` by its contact (``touched`` unused)."""
    side = ("left", "right")[finger]
    placement = (grasp.left, grasp.right)[finger]
    if isinstance(placement, TipOnEdge):
        return f"the {side} fingertip on edge {user_edge(hand, touched)}"
    if isinstance(placement, OnVertex):
        return f"the {side} finger's inner edge on vertex {user_vertex(hand, touched)}"
    return f"the {side} finger's {placement}"


def no_placement_words(grasp, finger: int) -> str:
    """Why ``finger`` (0 left, 1 right) has no contact of a paper ``grasp``'s placement, in words."""
    side = ("left", "right")[finger]
    placement = (grasp.left, grasp.right)[finger]
    if isinstance(placement, TipOnEdge):
        return (f"the {side} fingertip cannot rest on edge {placement.edge} (out of reach, at an end of the edge, "
                "or the finger would cross the workpiece)")  # fmt: skip
    return (f"the {side} finger's inner edge cannot rest on a workpiece vertex (the vertex of tangency lies beyond "
            "the finger's length, or the finger would cross the workpiece)")  # fmt: skip


def grasp_meets(hand, grasp, touched, feats) -> bool:
    """Whether ``grasp`` touching ``touched`` (per finger, :meth:`qsplan.hands.protocol.GraspStates.touching`) meets the
    features ``feats`` (left, right: ``"vertex"``, ``"vertex:K"``, ``"edge:K"`` or None; the user's numbering): its
    placements (or contacts) match, and a paper placement's ``"vertex:K"`` is the vertex it touches there."""
    if not grasp.matches(*feats):
        return False
    if not isinstance(grasp, Grasp):  # contact keys: matches() compared the features themselves
        return True
    for k, f in enumerate(feats):
        if f is not None and f.startswith("vertex:"):
            t = int(touched[k])
            if t < 0 or user_vertex(hand, t) != int(f.split(":")[1]):
                return False
    return True
