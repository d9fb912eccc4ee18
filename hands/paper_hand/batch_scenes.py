"""Scenes of a grasp at many workpiece positions at once (Section 3, eqs. 1-5), for planners.

:func:`scene_arrays` stacks the model's matrices of the states of a
:class:`~qsplan.hands.paper_hand.grasp_geometry.GraspConfigurations` (``W_n, W_t`` by
:func:`qsplan.mechanics.model.contact.wrench_matrices`, ``J_n, J_t`` by
:func:`qsplan.hands.paper_hand.analytic.finger_jacobians`: the same functions the one-state scenes use);
:func:`grasp_scenes` turns them into :class:`qsplan.mechanics.Scene` objects for a slide at a
given speed, each checked (by default) to be the scene the polygon search would give.
:func:`checked_scene_arrays` is the same check and the same arrays with no object per state (the
band tables): the closed-form contacts of every state at once (:func:`grasp_contacts_batch`, the
vectorised twin of :func:`qsplan.hands.paper_hand.analytic.grasp_contacts`, bit for bit).  Units SI.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from qsplan.hands.paper_hand.grasp_geometry import GraspConfigurations
from qsplan.hands.paper_hand.two_finger import JOINT_NAMES, TwoFingerHand, workpiece_world
from qsplan.hands.paper_hand.analytic import (FAR, NEAR, analytic_constants, finger_jacobians, grasp_contacts,
                                              gravity_efforts, scene_from_contacts)  # fmt: skip
from qsplan.mechanics.errors import SceneError
from qsplan.mechanics.model.contact import wrench_matrices
from qsplan.mechanics.model.friction import check_friction
from qsplan.mechanics.model.geometry import CONTACT_TOL

__all__ = ["GraspContactsBatch", "SceneArrays", "checked_scene_arrays", "grasp_contacts_batch", "grasp_scenes", "scene_arrays"]


@dataclass(frozen=True, slots=True, eq=False)
class SceneArrays:
    """The model's matrices at ``n`` states of one grasp, contacts in the hand's order (palm, palm, left, right).

    Attributes
    ----------
    Wn, Wt : ndarray, shape (n, 3, 4)
        Normal and tangential wrench matrices (eq. 1), about the world origin.
    Jn, Jt : ndarray, shape (n, 4, 2)
        Contact Jacobians (eq. 5; zero rows on the palm) (m).
    g_obj : ndarray, shape (n, 3)
        The workpiece's weight as a wrench about the origin (eq. 2) (N, N, N m).
    g_man : ndarray, shape (n, 2)
        The fingers' gravity efforts (eq. 3) (N m).
    """

    Wn: np.ndarray
    Wt: np.ndarray
    Jn: np.ndarray
    Jt: np.ndarray
    g_obj: np.ndarray
    g_man: np.ndarray


def scene_arrays(hand: TwoFingerHand, configs: GraspConfigurations) -> SceneArrays:
    """:class:`SceneArrays` at every state of ``configs`` (nan where it has no contacts: ``configs.q`` nan; validity is
    ``configs.ok``)."""
    return _arrays(hand, configs.x, configs.q, configs.points, configs.normals)


def _arrays(hand: TwoFingerHand, x, q, points, normals) -> SceneArrays:
    """:class:`SceneArrays` of the contacts ``points, normals`` (n, 4, 2) at workpiece ``x`` (n,) and joints ``q`` (n, 2)."""
    n = len(x)
    has = np.all(np.isfinite(points) & np.isfinite(normals), axis=(1, 2))
    m = int(has.sum())
    Wn, Wt = np.full((n, 3, 4), np.nan), np.full((n, 3, 4), np.nan)
    W = wrench_matrices(points[has].reshape(-1, 2), normals[has].reshape(-1, 2)) if m else (Wn[:0],) * 2
    Wn[has], Wt[has] = (w.reshape(3, m, 4).transpose(1, 0, 2) for w in W)
    J = finger_jacobians(hand, points[:, 2:], normals[:, 2:])
    Jn, Jt = np.zeros((n, 4, 2)), np.zeros((n, 4, 2))
    Jn[:, 2:], Jt[:, 2:] = J[:, :, 0], J[:, :, 1]
    weight = -hand.workpiece_mass * hand.gravity
    g_obj = np.column_stack([np.zeros(n), np.full(n, weight), x * weight - hand.rest_height * 0.0])
    return SceneArrays(Wn, Wt, Jn, Jt, g_obj, gravity_efforts(hand, q))


def grasp_scenes(hand: TwoFingerHand, configs: GraspConfigurations, effort_joint: str = "right", speed: float = 0.0,
                 mu=None, check: bool = True) -> list:  # fmt: skip
    """The scenes of a slide through the states of ``configs``: the workpiece moving along x at ``speed``.

    Parameters
    ----------
    effort_joint : {"left", "right"}
        The torque-controlled joint; the other turns at ``configs.dq_dx * speed`` (rad/s).
    speed : float
        Workpiece velocity along x (m/s).
    mu : float, optional
        Friction of every contact; default ``hand.mu``.
    check : bool
        Build a state's scene only where :func:`qsplan.hands.paper_hand.analytic.grasp_contacts` finds exactly the
        expected contacts (the scene the polygon search would give, to round-off); False trusts ``configs.ok``.

    Returns
    -------
    list of Scene or None, length n
        None where ``configs.ok`` is False, or the check fails (the generic path of
        :func:`qsplan.hands.paper_hand.scene.hand_scene` says what the polygons give there).
    """
    if effort_joint not in JOINT_NAMES:
        raise SceneError(f"effort_joint: expected one of {JOINT_NAMES}; got {effort_joint!r}")
    mu = None if mu is None else float(check_friction(mu, "mu"))
    e = np.array([name == effort_joint for name in JOINT_NAMES])
    v = JOINT_NAMES.index(effort_joint) ^ 1
    poses = configs.poses(hand.rest_height)
    out = []
    for i in range(len(configs.x)):
        points, normals = configs.points[i], configs.normals[i]
        if not configs.ok[i]:
            out.append(None)
            continue
        if check:
            found = grasp_contacts(hand, poses[i], configs.q[i])
            if found is None or not np.array_equal(found.features[2:], configs.touched[i]) \
                    or not np.array_equal(found.tips, configs.tip):
                out.append(None)
                continue
            points, normals = found.points, found.normals
        velocity = float(configs.dq_dx[i, v] * speed)
        out.append(scene_from_contacts(hand, poses[i], configs.q[i], points, normals, e, velocity, 0.0, mu))
    return out


def checked_scene_arrays(hand: TwoFingerHand, configs: GraspConfigurations) -> tuple:
    """The arrays of the scenes :func:`grasp_scenes` builds (``check=True``), with no object per state.

    Returns
    -------
    arrays : SceneArrays
        Of the contacts :func:`grasp_contacts_batch` finds, n states (NaN where ``ok`` is False): bit for bit those of
        :func:`grasp_scenes`' scenes.
    ok : ndarray of bool, shape (n,)
        Where ``configs.ok`` and the closed form finds exactly the expected contacts (elsewhere :func:`grasp_scenes`
        gives None: the generic path says what the polygons give).
    """
    found = grasp_contacts_batch(hand, configs.poses(hand.rest_height), configs.q)
    ok = configs.ok & found.ok & np.all(found.features[:, 2:] == configs.touched, axis=1) & np.all(found.tips == configs.tip, axis=1)
    points = np.where(ok[:, None, None], found.points, np.nan)
    return _arrays(hand, configs.x, configs.q, points, np.where(ok[:, None, None], found.normals, np.nan)), ok


@dataclass(frozen=True, slots=True, eq=False)
class GraspContactsBatch:
    """:class:`qsplan.hands.paper_hand.analytic.GraspContacts` at ``n`` states (meaningful where ``ok``).

    Attributes
    ----------
    ok : ndarray of bool, shape (n,)
        Where :func:`~qsplan.hands.paper_hand.analytic.grasp_contacts` returns contacts (elsewhere it returns None).
    points, normals : ndarray, shape (n, 4, 2)
    features : ndarray of int, shape (n, 4)
    tips : ndarray of bool, shape (n, 2)
    """

    ok: np.ndarray
    points: np.ndarray
    normals: np.ndarray
    features: np.ndarray
    tips: np.ndarray


def _hypot(x, y):
    """``math.hypot`` elementwise (the closed form's own distance function, so every comparison is its, bit for bit)."""
    x, y = np.broadcast_arrays(x, y)
    return np.fromiter(map(math.hypot, x.ravel().tolist(), y.ravel().tolist()), float, x.size).reshape(x.shape)


def _segment_distance(px, py, ax, ay, bx, by):
    """Distance (m) from the points ``p`` to the segments ``a -> b``, elementwise over broadcast arrays (the closed
    form's segment distance, the same operations)."""
    dx, dy = bx - ax, by - ay
    rx, ry = px - ax, py - ay
    t = np.minimum(np.maximum((rx * dx + ry * dy) / (dx * dx + dy * dy), 0.0), 1.0)
    return _hypot(rx - t * dx, ry - t * dy)


def _unit_rows(vx, vy):
    """``v / |v|`` (n, 2) as the closed form normalises a normal (``v.dot(v)``: the same dot product per row)."""
    v = np.stack([vx, vy], axis=-1)
    return v / np.sqrt((v[:, None, :] @ v[:, :, None])[:, 0, 0])[:, None]


def _edge_clear(X, Y, e0, e1, normal, edge, facing, near, far):
    """Where a body edge ``e0 -> e1`` (pairs of (n,) arrays, unit ``normal`` into the workpiece) has no extra contact
    with workpiece edge ``edge`` (n,): the test of the closed form's ``_clear`` for one (body, edge) pair."""
    r, k = np.arange(X.shape[0]), X.shape[1]
    f0x, f0y, f1x, f1y = X[r, edge], Y[r, edge], X[r, (edge + 1) % k], Y[r, (edge + 1) % k]
    near_end = np.minimum(_segment_distance(*e0, f0x, f0y, f1x, f1y), _segment_distance(*e1, f0x, f0y, f1x, f1y)) <= far
    if not facing:
        return ~near_end
    ux, uy = f1x - f0x, f1y - f0y
    size = np.sqrt(ux * ux + uy * uy)
    ux, uy = ux / size, uy / size
    se0 = (e0[0] - f0x) * ux + (e0[1] - f0y) * uy
    se1 = (e1[0] - f0x) * ux + (e1[1] - f0y) * uy
    lo, hi = np.maximum(0.0, np.minimum(se0, se1)), np.minimum(size, np.maximum(se0, se1))
    off = (f0x - e0[0]) * normal[0] + (f0y - e0[1]) * normal[1]
    slope = ux * normal[0] + uy * normal[1]
    return ~near_end & ~((hi - lo >= near) & (np.maximum(off + lo * slope, off + hi * slope) <= far))


def _workpiece_world(hand: TwoFingerHand, poses) -> np.ndarray:
    """The workpiece's world vertices (m) at ``poses`` (n, 3), shape (n, k, 2), as ``workpiece_world`` computes them
    state by state: the turned vertices once per angle (offset by -0.0, which adds exactly nothing), then the offset."""
    V = np.empty((len(poses), len(hand.workpiece), 2))
    angles, inverse = np.unique(poses[:, 2].view(np.int64), return_inverse=True)  # bit patterns: -0.0 is not 0.0
    for j, theta in enumerate(angles.view(float).tolist()):
        at = inverse.reshape(-1) == j
        V[at] = workpiece_world(hand, (-0.0, -0.0, theta))[None] + poses[at, None, :2]
    return V


def _tip_contacts(X, Y, Cx, Cy, near, far):
    """The closed form's fingertip contact at every state: ``(found (m,), edge (m,), point (m, 2), normal (m, 2))``.
    ``X, Y`` (m, k): the workpiece's world vertices; ``Cx, Cy`` (m, 4): the finger's corners, the link ring's order."""
    m, k = X.shape
    r = np.arange(m)
    X1, Y1 = np.roll(X, -1, axis=1), np.roll(Y, -1, axis=1)  # each edge's end
    size = _hypot(X1 - X, Y1 - Y)
    ex, ey = (X1 - X) / size, (Y1 - Y) / size
    dist = (Cx[:, None, :] - X[:, :, None]) * ey[:, :, None] - (Cy[:, None, :] - Y[:, :, None]) * ex[:, :, None]  # (m, k, 4)
    low = dist.min(axis=2)
    found = np.any(low >= -near, axis=1)
    j = np.argmin(np.where(low >= -near, low, np.inf), axis=1)  # the first edge of the smallest eligible distance
    d, low = dist[r, j], low[r, j]
    c = np.argmin(d, axis=1)
    x0, y0, ex, ey, size = X[r, j], Y[r, j], ex[r, j], ey[r, j], size[r, j]
    cx, cy = Cx[r, c], Cy[r, c]
    along = (cx - x0) * ex + (cy - y0) * ey
    others = np.min(np.where(np.arange(4) == c[:, None], np.inf, d), axis=1)
    found &= (np.abs(low) <= near) & (others > far) & (far < along) & (along < size - far)
    # no other workpiece edge near the corner, no workpiece vertex near the finger edges at the corner
    found &= ~np.any((_segment_distance(cx[:, None], cy[:, None], X, Y, X1, Y1) <= far) & (np.arange(k) != j[:, None]), axis=1)
    sides = [((cx, cy), (Cx[r, (c + 1) % 4], Cy[r, (c + 1) % 4])), ((Cx[r, (c - 1) % 4], Cy[r, (c - 1) % 4]), (cx, cy))]
    for (ax, ay), (bx, by) in sides:
        found &= ~np.any(_segment_distance(X, Y, ax[:, None], ay[:, None], bx[:, None], by[:, None]) <= far, axis=1)
    for (ax, ay), (bx, by) in sides:  # a finger edge lying along edge j (an edge-edge contact)
        sa, sb = (ax - x0) * ex + (ay - y0) * ey, (bx - x0) * ex + (by - y0) * ey
        lo, hi = np.maximum(0.0, np.minimum(sa, sb)), np.minimum(size, np.maximum(sa, sb))
        along_edge = (hi - lo >= near) & (_segment_distance(x0 + lo * ex, y0 + lo * ey, ax, ay, bx, by) <= far) \
            & (_segment_distance(x0 + hi * ex, y0 + hi * ey, ax, ay, bx, by) <= far)
        found &= ~along_edge
    return found, j, np.stack([cx, cy], axis=-1), np.stack([-ey, ex], axis=-1)


def grasp_contacts_batch(hand: TwoFingerHand, poses, q, tol: float = CONTACT_TOL) -> GraspContactsBatch:
    """:func:`qsplan.hands.paper_hand.analytic.grasp_contacts` at ``n`` states at once, bit for bit.

    Parameters
    ----------
    poses : array-like, shape (n, 3)
        Workpiece ``(x, y, theta)`` (m, m, rad).
    q : array-like, shape (n, 2)
        Joint angles (rad).
    tol : float
        The polygon search's contact tolerance (m).

    Returns
    -------
    GraspContactsBatch
        ``ok`` False where ``grasp_contacts`` returns None.

    Notes
    -----
    The same operations on the same numbers, state by state: the link corners from ``math.cos``/``math.sin`` and
    every distance to a segment from ``math.hypot`` as the closed form takes them, numpy elementwise elsewhere (no
    fused operations), first minima where it takes ``min``, and each normal divided by ``sqrt(v.dot(v))``;
    ``tests/hands/test_analytic_scene.py`` compares the two on hundreds of states.
    """
    poses = np.asarray(poses, dtype=float).reshape(-1, 3)
    q = np.asarray(q, dtype=float).reshape(-1, 2)
    n, k = len(poses), len(hand.workpiece)
    corners_only, inner, pivots, shape = analytic_constants(hand)
    ok = np.isfinite(poses).all(axis=1) & np.isfinite(q).all(axis=1) & corners_only
    points, normals = np.full((n, 4, 2), np.nan), np.full((n, 4, 2), np.nan)
    features, tips = np.zeros((n, 4), int), np.zeros((n, 2), bool)
    if not ok.any():
        return GraspContactsBatch(ok, points, normals, features, tips)
    near, far = NEAR * tol, FAR * tol
    V = _workpiece_world(hand, poses)
    X, Y = V[..., 0], V[..., 1]
    r = np.arange(n)
    ok &= (np.abs(Y[:, 0]) <= near) & (np.abs(Y[:, 1]) <= near) & (Y[:, 2:].min(axis=1) > far)
    hw = float(hand.palm_halfwidth)
    for edge, facing in ((k - 1, True), (0, False), (1, True)):  # the palm's top edge right to left
        ok &= _edge_clear(X, Y, (hw, 0.0), (-hw, 0.0), (0.0, 1.0), np.full(n, edge), facing, near, far)
    features[:, 1] = 1
    for f, ((ax, ay), ends, qf) in enumerate(zip(pivots, inner, q.T.tolist())):
        c = np.array([math.cos(v) for v in qf])  # the link's corners as link_polygons computes them
        s = np.array([math.sin(v) for v in qf])
        (e0x, e0y), (e1x, e1y) = ((ax + (c * lx - s * ly), ay + (s * lx + c * ly)) for lx, ly in ends)
        dx, dy = e1x - e0x, e1y - e0y
        length = np.sqrt(dx * dx + dy * dy)
        nx, ny = dy / length, -dx / length  # the finger's outward normal: into the workpiece
        dist = (X - e0x[:, None]) * nx[:, None] + (Y - e0y[:, None]) * ny[:, None]  # signed, positive outside the finger
        i = np.argmin(dist, axis=1)
        along = ((X[r, i] - e0x) * dx + (Y[r, i] - e0y) * dy) / length
        others = np.min(np.where(np.arange(k) == i[:, None], np.inf, dist), axis=1)
        vertex = (np.abs(dist[r, i]) <= near) & (others > far) & (far < along) & (along < length - far)
        for edge in ((i - 1) % k, i):  # the workpiece edges at the touched vertex, both tested for facing
            ok &= _edge_clear(X, Y, (e0x, e0y), (e1x, e1y), (nx, ny), edge, True, near, far) | ~vertex
        features[:, 2 + f], points[:, 2 + f], normals[:, 2 + f] = i, V[r, i], _unit_rows(nx, ny)
        tip = ok & ~vertex
        if tip.any():
            t = np.flatnonzero(tip)
            Cx, Cy = (np.stack(z, axis=1) for z in zip(*((ax + (c[t] * lx - s[t] * ly), ay + (s[t] * lx + c[t] * ly)) for lx, ly in shape)))
            found, j, point, normal = _tip_contacts(X[t], Y[t], Cx, Cy, near, far)
            ok[t] &= found
            features[t, 2 + f], points[t, 2 + f], normals[t, 2 + f] = j, point, _unit_rows(normal[:, 0], normal[:, 1])
            tips[t, f] = True
    ex, ey = X[:, 1] - X[:, 0], Y[:, 1] - Y[:, 0]
    size = np.sqrt(ex * ex + ey * ey)
    bottom = _unit_rows(-(ey / size), -(-ex / size))  # the bottom edge's inward normal
    points[:, :2], normals[:, 0], normals[:, 1] = V[:, :2], bottom, bottom
    return GraspContactsBatch(ok, points, normals, features, tips)
