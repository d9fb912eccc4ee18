"""Configurations of a grasp along the palm, vectorized over the workpiece x (closed form).

The workpiece rests on its bottom edge at pose ``(x, rest_height, 0)``.  For a
:class:`~qsplan.hands.paper_hand.grasps.Grasp`, :func:`grasp_configurations` gives at every x of a batch the
joint angles that realise each finger's placement, whether they are valid, the four contacts (palm
left end, palm right end, left finger, right finger; normals into the workpiece, eq. 1) and the joint
rates that keep the contacts while the workpiece slides along +x.  :func:`tip_angles` is the
fingertip's closed form; the inner edge's is :func:`qsplan.hands.paper_hand.two_finger.tangency_angles`.
:func:`candidate_grasps` lists the grasps a finger can reach somewhere on the palm.  Units SI.
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import product

import numpy as np

from qsplan.hands.paper_hand.grasps import (Grasp, OnVertex, TipOnEdge, internal_edge, internal_vertex, parse_goal,
                                            placement_matches, user_edge, user_vertex)  # fmt: skip
from qsplan.hands.paper_hand.two_finger import JOINT_NAMES, TwoFingerHand, tangency_angles, tangency_rates
from qsplan.mechanics.errors import SceneError
from qsplan.mechanics.model.geometry import CONTACT_TOL

__all__ = ["GraspConfigurations", "TIP_MARGIN", "candidate_grasps", "grasp_configurations", "palm_range", "tip_angles"]

#: Margin (m) of a fingertip placement's validity: its contact lies this far inside the edge (a tip on a
#: vertex is a vertex-vertex contact, whose normal is undefined), the other tip corner and the finger's long
#: edge clear the edge's line by this much (else the tip or the side lies flush on the edge: two contacts).
#: Twice the contact tolerance, the analytic scene's FAR margin: beyond it the polygon search sees one contact.
TIP_MARGIN = 2.0 * CONTACT_TOL

#: Workpiece positions that :func:`candidate_grasps` samples along the palm: 1 mm steps on the 0.3 m palm
#: of the default hand, finer than any feature of a fingertip's reach.
CANDIDATE_SAMPLES = 401

#: The sign of each finger's inner tip corner in its link frame (``(L, -w)`` left, ``(L, +w)`` right).
_INNER_CORNER = (-1.0, 1.0)


@dataclass(frozen=True, slots=True, eq=False)
class GraspConfigurations:
    """A grasp at ``n`` workpiece positions on the palm.

    Attributes
    ----------
    grasp : Grasp
    x : ndarray, shape (n,)
        Workpiece x (m); its pose is ``(x, rest_height, 0)``.
    q : ndarray, shape (n, 2)
        Joint angles (rad), left in ``(-pi, 3 pi / 2]``, right in ``(-pi / 2, 2 pi)``; nan where no solution exists.
    ok : ndarray of bool, shape (n,)
        Both fingers' solutions exist and are valid (``finger_ok``); joint limits are not checked.
    finger_ok : ndarray of bool, shape (n, 2)
        Per finger: an inner edge reaches its vertex within the finger's length (as ``finger_angles`` requires), leaves
        every vertex outside its line by ``-TIP_MARGIN`` at most (the finger does not cross the workpiece, which
        ``finger_angles`` does not check) and touches the named vertex if any; a tip lies on its edge by :data:`TIP_MARGIN` inside it, its other corner and
        its long edge clear the edge's line by :data:`TIP_MARGIN`, the finger pointing into the edge.
    touched : ndarray of int, shape (n, 2)
        The vertex (inner edge) or edge (tip) each finger touches, the hand's numbering (``hand.workpiece``).
    touched_as_written : ndarray of int, shape (n, 2)
        The same in the user's numbering.
    tip : ndarray of bool, shape (2,)
        Whether each finger's placement is a tip on an edge.
    points : ndarray, shape (n, 4, 2)
        Contact points (m): palm left end, palm right end, left finger, right finger.
    normals : ndarray, shape (n, 4, 2)
        Unit normals into the workpiece (eq. 1), same order.
    dq_dx : ndarray, shape (n, 2)
        Joint rates (rad/m) that keep both finger contacts while the workpiece translates along +x.
    """

    grasp: Grasp
    x: np.ndarray
    q: np.ndarray
    ok: np.ndarray
    finger_ok: np.ndarray
    touched: np.ndarray
    touched_as_written: np.ndarray
    tip: np.ndarray
    points: np.ndarray
    normals: np.ndarray
    dq_dx: np.ndarray

    def take(self, rows) -> "GraspConfigurations":
        """The states ``rows`` (array of int) of these configurations, as configurations."""
        from dataclasses import fields, replace

        rows = np.asarray(rows, dtype=int)
        per_state = {f.name: getattr(self, f.name)[rows] for f in fields(self) if f.name not in ("grasp", "tip")}
        return replace(self, **per_state)

    def poses(self, rest_height: float) -> np.ndarray:
        """Workpiece poses ``(x, rest_height, 0)`` (m, m, rad), shape (n, 3)."""
        return np.column_stack([self.x, np.full_like(self.x, rest_height), np.zeros_like(self.x)])

    def matches(self, goal_left=None, goal_right=None) -> np.ndarray:
        """Where the grasp meets the goal placements (strings as :meth:`Grasp.matches` takes), shape (n,) bool:
        ``"vertex:K"`` where the inner edge touches vertex ``K`` (user numbering), the others wherever valid."""
        out = self.ok.copy()
        for k, (placement, goal, field) in enumerate(zip((self.grasp.left, self.grasp.right), (goal_left, goal_right),
                                                         ("goal_left", "goal_right"))):  # fmt: skip
            if not placement_matches(placement, goal, field):
                return np.zeros_like(out)
            kind, index, _ = parse_goal(goal, field) if goal is not None else ("edge", None, None)
            if kind == "vertex" and index is not None:
                out &= self.touched_as_written[:, k] == index
        return out


def palm_range(hand: TwoFingerHand) -> tuple:
    """The workpiece x (m) over which its bottom edge lies on the palm: ``(lo, hi)``."""
    V = hand.workpiece
    return float(-hand.palm_halfwidth - V[0, 0]), float(hand.palm_halfwidth - V[1, 0])


def tip_angles(hand: TwoFingerHand, finger: int, edge: int, branch: int, xs):
    """Joint angle putting a tip corner of finger ``finger`` on the hand's edge ``edge``, at workpiece ``xs``.

    The corner ``p + L u + s w m`` (``u = (cos phi, sin phi)``, ``m`` its left normal, ``w`` half the finger's
    width, ``s`` the corner's side) lies at distance ``R = sqrt(L^2 + w^2)`` from the joint ``p``, at angle
    ``delta = atan2(s w, L)`` from ``u``.  On the edge's line ``n . x = d`` (``n`` its outward normal, angle
    ``theta_n``): ``R cos(phi + s delta - theta_n) = C = d - n . p``.  The finger clears the line on both tip
    corners exactly at ``phi = theta_n + s (alpha - |delta|)``, ``alpha = acos(C / R)``, with corner ``s`` on
    it; ``s`` is the inner corner for ``branch`` 0, the outer one for 1.  Along +x, ``dC/dx = n_x``, so
    ``dphi/dx = -s n_x / (R sin alpha)``.

    Parameters
    ----------
    finger : {0, 1}
        Left, right.
    edge : int
        The hand's edge (``hand.workpiece`` row ``edge`` to ``edge + 1``).
    branch : {0, 1}
    xs : ndarray, shape (n,)
        Workpiece x (m).

    Returns
    -------
    phi, dphi_dx : ndarray, shape (n,)
        Joint angle (rad; left in ``[-pi, pi)``, right in ``[0, 2 pi)``; nan where the edge's line is out of
        reach) and its rate (rad/m).
    ok : ndarray of bool, shape (n,)
        Valid as :attr:`GraspConfigurations.finger_ok` says.
    point, normal : ndarray, shape (n, 2)
        The touching corner (m) and the edge's unit normal into the workpiece.
    """
    V = hand.workpiece
    L, w = float(hand.finger_length), 0.5 * hand.finger_width
    s = _INNER_CORNER[finger] * (1.0 if branch == 0 else -1.0)
    a, b = V[edge], V[(edge + 1) % len(V)]
    length = float(np.hypot(*(b - a)))
    e = (b - a) / length
    n = np.array([e[1], -e[0]])  # outward (counter-clockwise polygon)
    p = hand.pivots[finger]
    R, delta = np.hypot(L, w), np.arctan2(w, L)
    C = (a + [0.0, hand.rest_height] - p) @ n + n[0] * xs
    z = C / R
    exists = np.abs(z) <= 1.0
    alpha = np.arccos(np.where(exists, z, np.nan))
    phi = np.arctan2(n[1], n[0]) + s * (alpha - delta)
    phi = np.mod(phi + np.pi, 2.0 * np.pi) - np.pi if finger == 0 else np.mod(phi, 2.0 * np.pi)
    u = np.stack([np.cos(phi), np.sin(phi)], axis=1)
    m = np.stack([-u[:, 1], u[:, 0]], axis=1)
    point = p + L * u + (s * w) * m
    along = (point - a - np.column_stack([xs, np.full_like(xs, hand.rest_height)])) @ e
    with np.errstate(invalid="ignore"):
        ok = exists & (-L * np.cos(alpha - delta) > TIP_MARGIN) & (2.0 * w * np.sin(alpha - delta) > TIP_MARGIN) \
            & (along > TIP_MARGIN) & (along < length - TIP_MARGIN)
        dphi = -s * n[0] / (R * np.sin(alpha))
    return phi, dphi, ok, point, np.broadcast_to(-n, point.shape)


def grasp_configurations(hand: TwoFingerHand, grasp: Grasp, xs) -> GraspConfigurations:
    """The grasp's joint angles, validity, contacts and joint rates at workpiece positions ``xs``.

    Parameters
    ----------
    hand : TwoFingerHand
    grasp : Grasp
        Placements in the user's numbering.
    xs : array-like, shape (n,)
        Workpiece x (m), pose ``(x, rest_height, 0)``.

    Returns
    -------
    GraspConfigurations
        For an :class:`OnVertex` finger ``q`` and ``dq_dx`` equal
        :func:`~qsplan.hands.paper_hand.two_finger.finger_angles` and
        :func:`~qsplan.hands.paper_hand.two_finger.finger_angle_rates` (at pose rate ``(1, 0, 0)``) bit for bit.

    Raises
    ------
    SceneError
        Naming the placement whose index is out of range for the workpiece.
    """
    xs = np.atleast_1d(np.asarray(xs, dtype=float))
    if xs.ndim != 1 or not np.all(np.isfinite(xs)):
        raise SceneError(f"xs: expected a finite 1-D array of workpiece x (m); got shape {xs.shape}")
    n, V = len(xs), hand.workpiece
    shift = np.column_stack([xs, np.full(n, hand.rest_height)])
    W = V[None] + shift[:, None]  # workpiece_world at (x, rest_height, 0): the turn by 0 is exact
    q, dq, touched = np.full((n, 2), np.nan), np.full((n, 2), np.nan), np.zeros((n, 2), dtype=int)
    ok, points, normals = np.zeros((n, 2), dtype=bool), np.empty((n, 4, 2)), np.empty((n, 4, 2))
    placements = (grasp.left, grasp.right)
    if any(isinstance(pl, OnVertex) for pl in placements):
        phi, idx, reached = tangency_angles(hand, W)
        rows = np.arange(n)
        d = W[rows[:, None], idx] - hand.pivots  # the touching vertices about the joints, (n, 2, 2)
        with np.errstate(invalid="ignore"):  # nan where no tangent exists (``reached`` False)
            rates = tangency_rates(hand, d, np.broadcast_to([1.0, 0.0], d.shape))
    for k, pl in enumerate(placements):
        field = f"grasp.{JOINT_NAMES[k]}"
        if isinstance(pl, OnVertex):
            u = np.stack([np.cos(phi[:, k]), np.sin(phi[:, k])], axis=1)
            along = np.sum(d[:, k] * u, axis=1)
            nu = (1.0 if k == 0 else -1.0) * np.stack([u[:, 1], -u[:, 0]], axis=1)  # inner edge normal: -m left, +m right
            clear = np.min(np.einsum("nkj,nj->nk", W - hand.pivots[k], nu), axis=1) - 0.5 * hand.finger_width
            ok[:, k] = reached[:, k] & (along > 0.0) & (along < hand.finger_length) & (clear > -TIP_MARGIN)
            if pl.vertex is not None:
                ok[:, k] &= idx[:, k] == internal_vertex(hand, pl.vertex, f"{field}.vertex")
            q[:, k], dq[:, k], touched[:, k] = phi[:, k], rates[:, k], idx[:, k]
            points[:, 2 + k], normals[:, 2 + k] = W[rows, idx[:, k]], nu
        elif isinstance(pl, TipOnEdge):
            e = internal_edge(hand, pl.edge, f"{field}.edge")
            if pl.branch not in (0, 1):
                raise SceneError(f"{field}.branch: expected 0 or 1; got {pl.branch!r}")
            q[:, k], dq[:, k], ok[:, k], points[:, 2 + k], normals[:, 2 + k] = tip_angles(hand, k, e, pl.branch, xs)
            touched[:, k] = e
        else:
            raise SceneError(f"{field}: expected an OnVertex or TipOnEdge placement; got {pl!r}")
    points[:, :2] = W[:, :2]
    ex, ey = V[1] - V[0]
    size = np.hypot(ex, ey)
    normals[:, :2] = (-(ey / size), ex / size)  # the bottom edge's inward normal
    tip = np.array([isinstance(pl, TipOnEdge) for pl in placements])
    k_v = len(V)
    as_written = np.column_stack([np.array([(user_edge if tip[k] else user_vertex)(hand, i) for i in range(k_v)])[touched[:, k]]
                                  for k in range(2)]).astype(int).reshape(n, 2)  # fmt: skip
    return GraspConfigurations(grasp, xs, q, ok.all(axis=1), ok, touched, as_written, tip, points, normals, dq)


def candidate_grasps(hand: TwoFingerHand, samples: int = CANDIDATE_SAMPLES) -> tuple:
    """Every grasp worth considering: per finger :class:`OnVertex` and each :class:`TipOnEdge` (edge, branch) that is
    valid with the finger above the palm's plane (``0 < q < pi``) somewhere on the palm, combined where both fingers'
    placements are valid at one workpiece x of ``samples`` along :func:`palm_range`.

    Returns
    -------
    tuple of Grasp
        Ordered left placement first (:class:`OnVertex`, then tips by user edge and branch), then right.
    """
    xs = np.linspace(*palm_range(hand), int(samples))
    k = len(hand.workpiece)
    tips = [TipOnEdge(user_edge(hand, e), b) for e in range(k) for b in (0, 1)]
    tips.sort(key=lambda t: (t.edge, t.branch))
    per_finger = []
    for finger in range(2):
        options = [(OnVertex(), None)]
        for t in tips:
            phi, _, ok, _, _ = tip_angles(hand, finger, internal_edge(hand, t.edge), t.branch, xs)
            with np.errstate(invalid="ignore"):
                ok &= (phi > 0.0) & (phi < np.pi)
            if ok.any():
                options.append((t, ok))
        per_finger.append(options)
    out = []
    for (left, okl), (right, okr) in product(*per_finger):
        grasp = Grasp(left, right)
        if okl is None and okr is None:
            out.append(grasp)
            continue
        if grasp_configurations(hand, grasp, xs).ok.any():
            out.append(grasp)
    return tuple(out)
