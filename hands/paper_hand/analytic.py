"""Analytic scenes of the two-finger hand: the contacts it knows, not a polygon search (Section 3, eqs. 1-5).

At a grasp the hand's contacts are known: the workpiece's bottom edge lies on the
palm (contacts at its two ends, normal the edge's inward normal, +y when level) and
each finger either touches one workpiece vertex with its inner edge (the tangency of
:func:`qsplan.hands.paper_hand.two_finger.finger_angles`; normal the edge's outward normal,
into the workpiece) or one workpiece edge with a corner (a fingertip,
:mod:`qsplan.hands.paper_hand.grasp_geometry`; normal the edge's inward normal).
:func:`grasp_contacts` finds them in closed form and checks,
with margins, that the polygon search (:func:`qsplan.mechanics.model.geometry.find_contacts`)
would find exactly these four and nothing else; :func:`analytic_hand_scene` turns
them into the :class:`qsplan.mechanics.Scene` (:func:`scene_from_contacts`, the one builder) that
:func:`qsplan.hands.paper_hand.scene.hand_scene` builds by the generic path, to
round-off (the tests compare the two on hundreds of configurations).  Where the
check fails (a finger flush with an edge, a tip or corner near the workpiece, the
workpiece off the palm) both return None and the caller takes the generic path.
Units SI (m, rad, N, N m).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from qsplan.hands.paper_hand.two_finger import JOINT_NAMES, TwoFingerHand, workpiece_world
from qsplan.mechanics.model.contact import wrench_matrices
from qsplan.mechanics.model.geometry import CONTACT_TOL
from qsplan.mechanics.model.scene import Scene

__all__ = ["GraspContacts", "analytic_constants", "analytic_hand_scene", "finger_jacobians", "grasp_contacts", "gravity_efforts",
           "scene_from_arrays", "scene_from_contacts"]  # fmt: skip

#: Margins (in contact tolerances) of the closed-form check: a feature the polygon search must
#: find lies within NEAR tolerances, one it must not find beyond FAR; values between fall back
#: to the generic path, so rounding in either path never decides which contacts a scene has.
NEAR, FAR = 0.5, 2.0

#: A workpiece vertex whose turn is below this relative size is (nearly) straight: the polygon
#: search may drop it (:mod:`qsplan.mechanics.model.geometry` drops turns below 1e-12), so a hand
#: with one always takes the generic path.
_STRAIGHT_TOL = 1e-9

_CONTACT_NAMES = ("palm:0", "palm:1", "left:2", "right:3")


@dataclass(frozen=True, slots=True, eq=False)
class GraspContacts:
    """The four contacts of a grasp, in the hand's order (palm left end, palm right end, left, right).

    Attributes
    ----------
    points : ndarray, shape (4, 2)
        Contact points ``r_i``, world frame (m): workpiece vertices, or finger corners (tips).
    normals : ndarray, shape (4, 2)
        Unit normals ``n_i`` into the workpiece.
    features : ndarray of int, shape (4,)
        The workpiece vertex of each contact, or for a fingertip the workpiece edge it lies on.
    tips : ndarray of bool, shape (2,)
        Whether each finger touches with a tip corner (on an edge) rather than its inner edge (on a vertex).
    """

    points: np.ndarray
    normals: np.ndarray
    features: np.ndarray
    tips: np.ndarray


@lru_cache(maxsize=16)
def analytic_constants(hand: TwoFingerHand):
    """Per-hand constants (cached: hands are immutable): whether the analytic path applies, each finger's inner
    edge in its link frame (its two ends in the link ring's order, m) and the joint axes (m), as plain floats."""
    V = hand.workpiece
    d_prev, d_next = V - np.roll(V, 1, axis=0), np.roll(V, -1, axis=0) - V
    turn = np.abs(d_prev[:, 0] * d_next[:, 1] - d_prev[:, 1] * d_next[:, 0])
    corners_only = bool(np.all(turn > _STRAIGHT_TOL * np.linalg.norm(d_prev, axis=1) * np.linalg.norm(d_next, axis=1)))
    L, w = float(hand.finger_length), 0.5 * hand.finger_width
    # hand_manipulator's link shape is (0, -w), (L, -w), (L, w), (0, w): the left finger touches with its
    # first edge (outward normal -y), the right one with its third (outward normal +y)
    inner = (((0.0, -w), (L, -w)), ((L, w), (0.0, w)))
    return corners_only, inner, tuple(map(tuple, hand.pivots.tolist())), ((0.0, -w), (L, -w), (L, w), (0.0, w))


def _segment_distance(p, a, b) -> float:
    """Distance (m) from the point ``p`` to the segment ``a -> b`` (pairs of floats)."""
    dx, dy = b[0] - a[0], b[1] - a[1]
    rx, ry = p[0] - a[0], p[1] - a[1]
    t = min(max((rx * dx + ry * dy) / (dx * dx + dy * dy), 0.0), 1.0)
    return math.hypot(rx - t * dx, ry - t * dy)


def _unit(v) -> np.ndarray:
    """``v / |v|`` exactly as :func:`qsplan.mechanics.model.geometry.find_contacts` normalises a normal."""
    v = np.array(v)
    return v / math.sqrt(v.dot(v))


def grasp_contacts(hand: TwoFingerHand, pose, q, tol: float = CONTACT_TOL) -> GraspContacts | None:
    """The four contacts of the hand at workpiece ``pose`` and joints ``q``; None where the polygons could give others.

    Parameters
    ----------
    hand : TwoFingerHand
    pose : array-like, shape (3,)
        Workpiece ``(x, y, theta)`` (m, m, rad).
    q : array-like, shape (2,)
        Joint angles (rad), left and right.
    tol : float
        The polygon search's contact tolerance (m).

    Returns
    -------
    GraspContacts or None
        None unless: the bottom edge's two ends are within ``NEAR * tol`` of the palm's top and every other
        vertex above ``FAR * tol``; each finger's inner edge is within ``NEAR * tol`` of one workpiece vertex,
        ``FAR * tol`` inside its ends, every other vertex beyond ``FAR * tol`` (or a finger corner within ``NEAR * tol``
        of one workpiece edge, ``FAR * tol`` inside its ends, the finger outside its line, :func:`_tip_contact`); and no end of the palm's top
        edge or of a finger's inner edge within ``FAR * tol`` of a workpiece edge, nor a workpiece edge lying
        along one of them (an edge-edge contact) but the bottom edge on the palm.
    """
    # plain floats: a handful of numbers per state, where numpy's per-call overhead would dominate
    corners_only, inner, pivots, shape = analytic_constants(hand)
    if not corners_only:
        return None
    near, far = NEAR * tol, FAR * tol
    V = workpiece_world(hand, pose)
    P = V.tolist()
    k = len(P)
    if not (abs(P[0][1]) <= near and abs(P[1][1]) <= near and min(p[1] for p in P[2:]) > far):
        return None
    q = np.asarray(q, dtype=float).tolist()
    halfwidth = float(hand.palm_halfwidth)
    # (edge ends, unit normal into the workpiece, workpiece edges to check (index, test facing)): the palm's top
    # edge right to left (the palm ring's order), with the edges at the bottom edge's ends; then each finger's inner edge
    bodies = [((halfwidth, 0.0), (-halfwidth, 0.0), (0.0, 1.0), ((k - 1, True), (0, False), (1, True)))]
    touch, tips, tip_points, tip_normals = [], [False, False], {}, {}
    for f, ((ax, ay), ends, qf) in enumerate(zip(pivots, inner, q)):
        # the link's corners as qsplan.mechanics.model.manipulator.link_polygons computes them
        c, s = math.cos(qf), math.sin(qf)
        (e0x, e0y), (e1x, e1y) = ((ax + (c * lx - s * ly), ay + (s * lx + c * ly)) for lx, ly in ends)
        dx, dy = e1x - e0x, e1y - e0y
        length = math.sqrt(dx * dx + dy * dy)
        nx, ny = dy / length, -dx / length  # the finger's outward normal: into the workpiece
        dist = [(x - e0x) * nx + (y - e0y) * ny for x, y in P]  # signed, positive outside the finger
        i = min(range(k), key=dist.__getitem__)
        along = ((P[i][0] - e0x) * dx + (P[i][1] - e0y) * dy) / length
        others = min(d for j, d in enumerate(dist) if j != i)
        if not (abs(dist[i]) <= near and others > far and far < along < length - far):
            tip = _tip_contact(P, [(ax + (c * lx - s * ly), ay + (s * lx + c * ly)) for lx, ly in shape], near, far)
            if tip is None:
                return None
            touch.append(tip[0])
            tips[f], tip_points[f], tip_normals[f] = True, tip[1], tip[2]
            continue
        touch.append(i)
        bodies.append(((e0x, e0y), (e1x, e1y), (nx, ny), (((i - 1) % k, True), (i, True))))
    if not _clear(P, bodies, near, far):
        return None
    ex, ey = P[1][0] - P[0][0], P[1][1] - P[0][1]
    size = math.sqrt(ex * ex + ey * ey)
    bottom = _unit((-(ey / size), -(-ex / size)))  # the bottom edge's inward normal
    fingers = iter(bodies[1:])
    normals, points = [bottom, bottom], [V[0], V[1]]
    for f in range(2):
        normals.append(_unit(tip_normals[f]) if tips[f] else _unit(next(fingers)[2]))
        points.append(np.array(tip_points[f]) if tips[f] else V[touch[f]])
    return GraspContacts(np.stack(points), np.stack(normals), np.array([0, 1, *touch]), np.array(tips))


def _tip_contact(P, corners, near, far):
    """``(edge, point, normal into the workpiece)`` where one finger corner touches one workpiece edge and nothing
    else can touch (see :func:`grasp_contacts`), else None.  ``P``: the workpiece's world vertices, ``corners``: the
    finger's four world corners in the link ring's order, pairs of floats."""
    k = len(P)
    best = None
    for j in range(k):  # the edge whose line the finger lies outside of and touches
        (x0, y0), (x1, y1) = P[j], P[(j + 1) % k]
        size = math.hypot(x1 - x0, y1 - y0)
        ex, ey = (x1 - x0) / size, (y1 - y0) / size
        dist = [(cx - x0) * ey - (cy - y0) * ex for cx, cy in corners]  # signed, positive outside the workpiece
        if min(dist) >= -near and (best is None or min(dist) < best[1]):
            best = (j, min(dist), dist, (ex, ey), size)
    if best is None:
        return None
    j, low, dist, (ex, ey), size = best
    c = min(range(4), key=dist.__getitem__)
    corner, (x0, y0) = corners[c], P[j]
    along = (corner[0] - x0) * ex + (corner[1] - y0) * ey
    if not (abs(low) <= near and min(d for i, d in enumerate(dist) if i != c) > far and far < along < size - far):
        return None
    sides = [(corners[c], corners[(c + 1) % 4]), (corners[(c - 1) % 4], corners[c])]  # the finger edges at the corner
    if any(_segment_distance(corner, P[i], P[(i + 1) % k]) <= far for i in range(k) if i != j):
        return None
    if any(_segment_distance(v, a, b) <= far for v in P for a, b in sides):
        return None
    for a, b in sides:  # an edge of the finger lying along edge j (an edge-edge contact, the polygon search's facing test)
        sa, sb = (a[0] - x0) * ex + (a[1] - y0) * ey, (b[0] - x0) * ex + (b[1] - y0) * ey
        lo, hi = max(0.0, min(sa, sb)), min(size, max(sa, sb))
        ends = [(x0 + t * ex, y0 + t * ey) for t in (lo, hi)]
        if hi - lo >= near and all(_segment_distance(e, a, b) <= far for e in ends):
            return None
    return j, corner, (-ey, ex)


def _clear(P, bodies, near, far) -> bool:
    """Whether no other contact can appear next to the expected ones: no end of the palm's top edge or of a
    finger's inner edge within ``far`` of a workpiece edge at its touching vertices (a vertex on an edge), and
    none of those workpiece edges facing the body's edge with both ends of their overlap within ``far`` of its
    line (an edge on an edge, as :func:`qsplan.mechanics.model.geometry.find_contacts` tests it).  Other edges
    have both ends beyond ``far`` from the body's line, so cannot touch it; the bottom edge (edge 0, checked for
    corners only) lies on the palm by design.

    ``P``: the workpiece's world vertices, k pairs of floats; ``bodies``: (edge start, edge end, unit normal into
    the workpiece, the workpiece edges to check as (index, whether to test it for facing too)) of the palm and
    each finger.
    """
    k = len(P)
    for e0, e1, (nx, ny), edges in bodies:
        for edge, facing in edges:
            f0, f1 = P[edge], P[(edge + 1) % k]
            if min(_segment_distance(e0, f0, f1), _segment_distance(e1, f0, f1)) <= far:
                return False
            if not facing:
                continue
            ux, uy = f1[0] - f0[0], f1[1] - f0[1]
            size = math.sqrt(ux * ux + uy * uy)
            ux, uy = ux / size, uy / size
            se0 = (e0[0] - f0[0]) * ux + (e0[1] - f0[1]) * uy
            se1 = (e1[0] - f0[0]) * ux + (e1[1] - f0[1]) * uy
            lo, hi = max(0.0, min(se0, se1)), min(size, max(se0, se1))
            if hi - lo >= near:
                off = (f0[0] - e0[0]) * nx + (f0[1] - e0[1]) * ny
                slope = ux * nx + uy * ny
                if max(off + lo * slope, off + hi * slope) <= far:
                    return False
    return True


def finger_jacobians(hand: TwoFingerHand, points, normals) -> np.ndarray:
    """Contact Jacobian rows ``j_in, j_it`` (eq. 5) of each finger's contact, batched over states.

    A point ``p`` on a link turning about the fixed axis ``a_k`` moves at ``ez x (p - a_k) qdot_k``, the only
    nonzero column of its point Jacobian; the rows are ``[n^T; t^T] J_p`` with ``t`` the normal turned +90
    degrees (the general tree is :func:`qsplan.mechanics.model.manipulator.contact_jacobian`, which the tests
    compare against).

    Parameters
    ----------
    points : ndarray, shape (..., 2, 2)
        Each finger's contact point (m), left then right.
    normals : ndarray, shape (..., 2, 2)
        Their normals into the workpiece (normalised here).

    Returns
    -------
    ndarray, shape (..., 2, 2, 2)
        ``[finger, row (n, t), joint]`` (m).
    """
    rel = points - hand.pivots
    Jp = np.zeros(rel.shape[:-2] + (2, 2, 2))  # [finger, x/y, joint]
    for k in range(2):
        Jp[..., k, 0, k], Jp[..., k, 1, k] = -rel[..., k, 1], rel[..., k, 0]
    n = normals / np.hypot(normals[..., 0], normals[..., 1])[..., None]
    return np.stack([n, np.stack([-n[..., 1], n[..., 0]], axis=-1)], axis=-2) @ Jp


def gravity_efforts(hand: TwoFingerHand, q) -> np.ndarray:
    """``g_man`` (eq. 3), shape (..., 2): each finger's weight at half its length, ``m g (L/2) cos q_k`` (N m)."""
    q = np.asarray(q, dtype=float)
    if hand.finger_mass == 0.0:
        return np.zeros(q.shape)
    pivots = hand.pivots
    com_x = pivots[:, 0] + (np.cos(q) * (0.5 * hand.finger_length) - np.sin(q) * 0.0)
    return hand.finger_mass * hand.gravity * (com_x - pivots[:, 0])


def _frozen(a):
    a = np.asarray(a)
    a.setflags(write=False)
    return a


def analytic_hand_scene(hand: TwoFingerHand, pose, q, effort_controlled, velocity=0.0, effort=0.0, mu=None):
    """The hand's :class:`qsplan.mechanics.Scene` at a grasp from :func:`grasp_contacts`, or None off a grasp.

    Parameters
    ----------
    hand : TwoFingerHand
    pose : array-like, shape (3,)
        Workpiece ``(x, y, theta)`` (m, m, rad).
    q : array-like, shape (2,)
        Joint angles (rad).
    effort_controlled : ndarray of bool, shape (2,)
        The control mode of each joint (validated by the caller).
    velocity, effort : float
        Input of the velocity-controlled joint (rad/s) and the effort-controlled one (N m).
    mu : float, optional
        Friction of every contact (validated by the caller); default ``hand.mu``.

    Returns
    -------
    Scene or None
        :func:`scene_from_contacts` at the contacts of :func:`grasp_contacts`: equal to the generic path's
        scene to round-off.
    """
    pose = np.asarray(pose, dtype=float)
    q = np.asarray(q, dtype=float)
    found = grasp_contacts(hand, pose, q)
    if found is None:
        return None
    return scene_from_contacts(hand, pose, q, found.points, found.normals, effort_controlled, velocity, effort, mu)


def scene_from_contacts(hand: TwoFingerHand, pose, q, points, normals, effort_controlled, velocity=0.0, effort=0.0,
                        mu=None):  # fmt: skip
    """The hand's :class:`qsplan.mechanics.Scene` with the four contacts ``points``, ``normals`` (the one builder).

    Parameters
    ----------
    pose : ndarray, shape (3,)
        Workpiece ``(x, y, theta)`` (m, m, rad).
    q : ndarray, shape (2,)
        Joint angles (rad).
    points, normals : ndarray, shape (4, 2)
        Contacts in the hand's order (palm left end, palm right end, left finger, right finger): points (m) and
        normals into the workpiece (eq. 1).
    effort_controlled, velocity, effort, mu
        As :func:`analytic_hand_scene` takes them (validated by the caller).

    Returns
    -------
    Scene
        ``W_n, W_t`` (eq. 1), ``J_n, J_t`` (eq. 5; zero rows on the palm), ``g_obj`` the workpiece weight at its
        centre of mass (eq. 2), ``g_man`` (eq. 3).
    """
    Wn, Wt = wrench_matrices(points, normals)
    J = finger_jacobians(hand, points[2:], normals[2:])
    Jn, Jt = np.zeros((4, 2)), np.zeros((4, 2))  # the palm's rows are zero
    Jn[2:], Jt[2:] = J[:, 0], J[:, 1]
    weight = -hand.workpiece_mass * hand.gravity
    g_obj = np.array([0.0, weight, pose[0] * weight - pose[1] * 0.0])  # qsplan.mechanics.model.contact.point_wrench
    return scene_from_arrays(hand, Wn, Wt, Jn, Jt, g_obj, gravity_efforts(hand, q), effort_controlled, velocity, effort, mu)


def scene_from_arrays(hand: TwoFingerHand, Wn, Wt, Jn, Jt, g_obj, g_man, effort_controlled, velocity=0.0, effort=0.0,
                      mu=None) -> Scene:  # fmt: skip
    """The hand's :class:`qsplan.mechanics.Scene` from its model arrays (:func:`scene_from_contacts` computes them; the
    band tables stack them over states, :func:`qsplan.hands.paper_hand.batch_scenes.checked_scene_arrays`).

    Parameters
    ----------
    Wn, Wt : ndarray, shape (3, 4)
    Jn, Jt : ndarray, shape (4, 2)
    g_obj : ndarray, shape (3,)
    g_man : ndarray, shape (2,)
    effort_controlled, velocity, effort, mu
        As :func:`analytic_hand_scene` takes them (validated by the caller).
    """
    e = np.array(effort_controlled, dtype=bool)
    return Scene(
        Wn=_frozen(Wn), Wt=_frozen(Wt), Jn=_frozen(Jn), Jt=_frozen(Jt),
        mu=_frozen(np.full(4, hand.mu if mu is None else float(mu))), g_obj=_frozen(g_obj),
        g_man=_frozen(g_man), effort_controlled=_frozen(e),
        joint_velocity=_frozen(np.where(e, np.nan, float(velocity))),
        joint_effort=_frozen(np.where(e, float(effort), np.nan)),
        joint_names=JOINT_NAMES, contact_names=_CONTACT_NAMES,
    )  # fmt: skip
