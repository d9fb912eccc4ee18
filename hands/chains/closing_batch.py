"""Closing the fingers of any serial chain onto the workpiece at many states at once (Section 3, eq. 1).

The batched twin of :func:`qsplan.hands.chains.closing.close_finger` (the per-state reference, which the
tests compare against): at each of ``n`` states (a workpiece polygon and the finger's free joints) the
finger's last joint closes from the end of its range away from the workpiece, in the direction that
moves its link toward the other finger, and stops at the first contact.  The same closed-form
candidates (a link vertex reaching a workpiece edge's line, a workpiece vertex reaching a link edge's
line, on a circle or a line), the same order (stable, by distance from the start in the closing
direction), the same touch and flush rules and tolerances (:data:`qsplan.hands.chains.closing.TOUCH_TOL`,
:data:`qsplan.hands.chains.closing.FLUSH_TOL`); only the loop over states is gone.  :func:`link_poses_batch` is
:func:`qsplan.mechanics.model.manipulator.link_poses` over states.  Units SI (m, rad).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qsplan.hands.chains.closing import FLUSH_TOL, TOUCH_TOL

__all__ = ["ClosedFingers", "ccw_ring", "close_finger_batch", "edge_normals", "following", "link_poses_batch",
           "place_link", "separation_batch"]


@dataclass(frozen=True, slots=True, eq=False)
class ClosedFingers:
    """One finger closed at ``n`` states (meaningful where ``found``).

    Attributes
    ----------
    found : ndarray of bool, shape (n,)
        Where :func:`qsplan.hands.chains.closing.close_finger` returns a contact (elsewhere None).
    value : ndarray, shape (n,)
        The closing joint's position at first contact (rad or m); NaN where not found.
    link : int
        The touching link (manipulator joint index: the closing joint's).
    kind : ndarray of int, shape (n,)
        0: a link vertex on a workpiece edge (``"edge"``); 1: a workpiece vertex on a link edge (``"vertex"``).
    feature, link_feature : ndarray of int, shape (n,)
        The workpiece edge or vertex (internal numbering) and the link vertex or edge (counter-clockwise ring).
    point, normal : ndarray, shape (n, 2)
        Contact point (m) and unit normal into the workpiece, world frame.
    flush : ndarray of bool, shape (n,)
        A second contact arrives at the same value (a link edge flush with a workpiece edge).
    """

    found: np.ndarray
    value: np.ndarray
    link: int
    kind: np.ndarray
    feature: np.ndarray
    link_feature: np.ndarray
    point: np.ndarray
    normal: np.ndarray
    flush: np.ndarray

    def take(self, rows) -> "ClosedFingers":
        """The states ``rows`` (array of int)."""
        return ClosedFingers(*(getattr(self, f) if f == "link" else getattr(self, f)[rows] for f in self.__slots__))


def ccw_ring(P) -> np.ndarray:
    """The polygon ``P`` (k, 2) counter-clockwise (:func:`qsplan.hands.chains.closing.close_finger`'s link ring)."""
    P = np.asarray(P, dtype=float)
    x, y = P[:, 0], P[:, 1]
    return P if np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y) > 0 else P[::-1]


def following(P) -> np.ndarray:
    """Each vertex's successor around the polygons ``P`` (..., k, 2): ``np.roll(P, -1, axis=-2)``, in one copy."""
    return np.concatenate([P[..., 1:, :], P[..., :1, :]], axis=-2)


def edge_normals(P):
    """Outward unit normals (..., k, 2) and offsets (..., k) of the edges of counter-clockwise polygons ``P``
    (..., k, 2)."""
    d = following(P) - P
    m = d[..., ::-1] * np.array([1.0, -1.0]) / np.hypot(d[..., 0], d[..., 1])[..., None]
    return m, (m * P).sum(axis=-1)


def separation_batch(A, B, normals_b=None) -> np.ndarray:
    """Signed separation (m) of convex counter-clockwise polygons ``A`` (n, a, 2) and ``B`` (n, b, 2) at each state:
    :func:`qsplan.hands.chains.closing.separation`, shape (n,)."""
    m, h = edge_normals(A)
    mb, hb = edge_normals(B) if normals_b is None else normals_b
    s_a = np.max(np.min(np.einsum("nbk,nak->nab", B, m), axis=2) - h, axis=1)
    s_b = np.max(np.min(np.einsum("nak,nbk->nba", A, mb), axis=2) - hb, axis=1)
    return np.maximum(s_a, s_b)


def link_poses_batch(man, q) -> np.ndarray:
    """World poses of every link frame at ``n`` joint vectors: :func:`qsplan.mechanics.model.manipulator.link_poses`
    per state.

    Parameters
    ----------
    man : qsplan.mechanics.model.manipulator.Manipulator
    q : ndarray, shape (n, n_j)
        Joint positions (rad or m).

    Returns
    -------
    ndarray, shape (n, n_j, 3)
        ``(x, y, angle)`` (m, m, rad; angles not wrapped).
    """
    q = np.asarray(q, dtype=float)
    out = np.empty(q.shape + (3,))
    zero = np.zeros(len(q))
    for i, j in enumerate(man.joints):
        px, py, pa = (zero, zero, zero) if j.parent < 0 else tuple(out[:, j.parent, c] for c in range(3))
        ox, oy, oa = (float(v) for v in j.origin)
        c, s = np.cos(pa), np.sin(pa)
        x, y, a = px + c * ox - s * oy, py + s * ox + c * oy, pa + oa
        if j.kind == "revolute":
            a = a + q[:, i]
        else:
            x, y = x + np.cos(a) * q[:, i], y + np.sin(a) * q[:, i]
        out[:, i, 0], out[:, i, 1], out[:, i, 2] = x, y, a
    return out


def place_link(kind: str, base, link, v) -> np.ndarray:
    """World vertices (n, k, 2) of a link polygon ``link`` (k, 2, its frame) whose joint of ``kind`` is at ``v`` (n,),
    from its frame ``base`` (n, 3) at value 0: turned by ``v`` about the frame's origin, or slid by ``v`` along its +x."""
    a = base[:, 2] + v if kind == "revolute" else base[:, 2]
    c, s = np.cos(a)[:, None], np.sin(a)[:, None]
    P = np.stack([c * link[None, :, 0] - s * link[None, :, 1], s * link[None, :, 0] + c * link[None, :, 1]], axis=2)
    P = P + base[:, None, :2]
    if kind != "revolute":
        P = P + (v[:, None] * np.stack([np.cos(base[:, 2]), np.sin(base[:, 2])], axis=1))[:, None, :]
    return P


def _candidates(kind, base, link, W, m, h):
    """:func:`qsplan.hands.chains.closing.contact_events` at every state, in its order with NaN where it has no
    candidate: ``values (n, M)`` and ``events (M, 3)`` (the same for every state: kind, link feature, workpiece
    feature)."""
    n, w = W.shape[:2]
    k = len(link)
    c, angle = base[:, :2], base[:, 2]
    nl, g = edge_normals(link)
    ii, jj = np.meshgrid(np.arange(k), np.arange(w), indexing="ij")
    pairs = np.column_stack([ii.ravel(), jj.ravel()])  # (link feature, workpiece feature), row-major as np.nonzero gives
    ev0 = np.column_stack([np.zeros(len(pairs), int), pairs])
    ev1 = np.column_stack([np.ones(len(pairs), int), pairs])
    vals = []
    with np.errstate(invalid="ignore", divide="ignore"):
        if kind == "revolute":
            rho, gam = np.hypot(link[:, 0], link[:, 1]), np.arctan2(link[:, 1], link[:, 0])
            beta, rhs = np.arctan2(m[..., 1], m[..., 0]), h - np.einsum("nwk,nk->nw", m, c)
            ac = np.arccos(rhs[:, None, :] / rho[None, :, None])  # (n, link vertex, workpiece edge)
            for sign in (1.0, -1.0):
                vals.append((beta[:, None, :] - angle[:, None, None] - gam[None, :, None] + sign * ac).reshape(n, -1))
            d = W - c[:, None, :]
            r, delta = np.hypot(d[..., 0], d[..., 1]), np.arctan2(d[..., 1], d[..., 0])
            nu = np.arctan2(nl[:, 1], nl[:, 0])
            ac = np.arccos(g[None, :, None] / r[:, None, :])  # (n, link edge, workpiece vertex)
            for sign in (1.0, -1.0):
                vals.append((delta[:, None, :] - nu[None, :, None] - angle[:, None, None] + sign * ac).reshape(n, -1))
            events = np.concatenate([ev0, ev0, ev1, ev1])
        else:
            u = np.stack([np.cos(angle), np.sin(angle)], axis=1)
            Lw = place_link("revolute", base, link, np.zeros(n))  # the link at value 0 (turned by the frame's angle)
            s = (h[:, None, :] - np.einsum("nlk,nwk->nlw", Lw, m)) / np.einsum("nwk,nk->nw", m, u)[:, None, :]
            vals.append(s.reshape(n, -1))
            c_, s_ = np.cos(angle)[:, None], np.sin(angle)[:, None]
            nw = np.stack([c_ * nl[None, :, 0] - s_ * nl[None, :, 1], s_ * nl[None, :, 0] + c_ * nl[None, :, 1]], axis=2)
            s = np.einsum("nwk,nek->new", W - c[:, None, :], nw) - g[None, :, None]
            s = s / np.einsum("nek,nk->ne", nw, u)[:, :, None]
            vals.append(s.reshape(n, -1))
            events = np.concatenate([ev0, ev1])
    vals = np.concatenate(vals, axis=1)
    return np.where(np.isfinite(vals), vals, np.nan), events


def _on_segments(kind, base, link, W, r, e, v, events, tol) -> np.ndarray:
    """:func:`qsplan.hands.chains.closing._on_segments` of the candidates ``e`` (m,) at value ``v`` (m,) of the states
    ``r`` (m,): whether the touching point lies on the edge it reaches, within ``tol`` (m) of its ends, shape (m,)."""
    # per event first (M of them), then one-index gathers of 1-D arrays: numpy's integer modulo and multi-index
    # gathers cost ten times a multiplication
    k, n_link = W.shape[1], len(link)
    k0_e, lf_e, wf_e = events[:, 0] == 0, events[:, 1], events[:, 2]
    nxt_l, nxt_w = np.append(np.arange(1, n_link), 0)[lf_e], np.append(np.arange(1, k), 0)[wf_e]
    k0, l0x, l0y, l1x, l1y = k0_e[e], link[lf_e, 0][e], link[lf_e, 1][e], link[nxt_l, 0][e], link[nxt_l, 1][e]
    ba = np.ascontiguousarray(base[:, 2])[r]
    a = ba + v if kind == "revolute" else ba
    sx, sy = np.ascontiguousarray(base[:, 0])[r], np.ascontiguousarray(base[:, 1])[r]
    if kind != "revolute":
        sx, sy = sx + v * np.cos(ba), sy + v * np.sin(ba)
    c, s = np.cos(a), np.sin(a)
    p0x, p0y = c * l0x - s * l0y + sx, s * l0x + c * l0y + sy  # link vertex lf placed
    p1x, p1y = c * l1x - s * l1y + sx, s * l1x + c * l1y + sy
    Wx, Wy = W[..., 0].ravel(), W[..., 1].ravel()
    i0, i1 = r * k + wf_e[e], r * k + nxt_w[e]
    w0x, w0y, w1x, w1y = Wx[i0], Wy[i0], Wx[i1], Wy[i1]
    px, py = np.where(k0, p0x, w0x), np.where(k0, p0y, w0y)  # the touching vertex
    ax, ay = np.where(k0, w0x, p0x), np.where(k0, w0y, p0y)  # the edge reached: from a0 to a1
    dx, dy = np.where(k0, w1x, p1x) - ax, np.where(k0, w1y, p1y) - ay
    length = np.sqrt(dx * dx + dy * dy)
    along = ((px - ax) * dx + (py - ay) * dy) / length
    return (along >= -tol) & (along <= length + tol)


def close_finger_batch(man, q, joints, limits, W, side: float, tol: float = TOUCH_TOL) -> ClosedFingers:
    """:func:`qsplan.hands.chains.closing.close_finger` at ``n`` states at once.

    Parameters
    ----------
    man : qsplan.mechanics.model.manipulator.Manipulator
    q : ndarray, shape (n, n_j)
        Joint positions; the finger's free joints are read from it, its closing joint's entry is ignored.
    joints : sequence of int
        The finger's joints, base to tip; the last closes.
    limits : ndarray, shape (n_j, 2)
        Joint ranges (rad or m).
    W : ndarray, shape (n, w, 2)
        The workpiece at each state, counter-clockwise, world (m).
    side : float
        +1 for the left finger, -1 for the right one.
    tol : float
        Separation (m) within which the link and the workpiece touch.

    Returns
    -------
    ClosedFingers
        ``found`` False where the reference returns None.
    """
    n = len(W)
    k = int(joints[-1])
    joint = man.joints[k]
    lo, hi = (float(v) for v in limits[k])
    q0 = np.array(q, dtype=float)
    q0[:, k] = 0.0
    base = link_poses_batch(man, q0)[:, k]  # the link frame at closing value 0
    # closing_direction at mid-range: the link centroid's x velocity toward the other finger
    centroid = np.asarray(joint.link_shape, float).mean(axis=0)[None]
    mid = place_link(joint.kind, base, centroid, np.full(n, 0.5 * (lo + hi)))[:, 0]
    dx = -(mid[:, 1] - base[:, 1]) if joint.kind == "revolute" else np.cos(base[:, 2])
    direction = np.sign(side * dx)
    start = np.where(direction < 0, hi, lo)
    link = ccw_ring(joint.link_shape)
    normals_w = edge_normals(W)
    found = (direction != 0.0) & (separation_batch(place_link(joint.kind, base, link, start), W, normals_w) >= -tol)
    vals, events = _candidates(joint.kind, base, link, W, *normals_w)
    if joint.kind == "revolute":  # the turn that reaches each candidate first from the start, in the closing direction
        vals = start[:, None] + direction[:, None] * np.mod(direction[:, None] * (vals - start[:, None]), 2.0 * np.pi)
    with np.errstate(invalid="ignore"):
        ahead = (direction[:, None] * (vals - start[:, None]) >= 0.0) & (vals >= lo) & (vals <= hi)
    vals = np.where(ahead & found[:, None], vals, np.nan)
    key = direction[:, None] * (vals - start[:, None])
    r, e = np.nonzero(np.isfinite(vals))  # the candidates ahead (most are not), on their segments or not
    on = np.zeros(vals.shape, bool)
    on[r, e] = _on_segments(joint.kind, base, link, W, r, e, vals[r, e], events, tol)
    key = np.where(on, key, np.inf)
    pick = np.full(n, -1)
    pending = np.flatnonzero(on.any(axis=1))
    while pending.size:  # the first candidate on its segment (ties: the reference's order) whose placement touches:
        idx = np.argmin(key[pending], axis=1)  # rounding may put one just off its segment, then the next is the contact
        P = place_link(joint.kind, base[pending], link, vals[pending, idx])
        sub = (normals_w[0][pending], normals_w[1][pending])
        touch = np.abs(separation_batch(P, W[pending], sub)) <= tol
        pick[pending[touch]] = idx[touch]
        rest, idx = pending[~touch], idx[~touch]
        key[rest, idx] = np.inf
        pending = rest[np.isfinite(key[rest]).any(axis=1)]
    found &= pick >= 0
    rows = np.flatnonzero(found)
    value = np.full(n, np.nan)
    kind, feature, link_feature = np.zeros(n, int), np.zeros(n, int), np.zeros(n, int)
    point, normal, flush = np.full((n, 2), np.nan), np.full((n, 2), np.nan), np.zeros(n, bool)
    if rows.size:
        idx = pick[rows]
        v = vals[rows, idx]
        P = place_link(joint.kind, base[rows], link, v)
        kind_, lf, wf = events[idx, 0], events[idx, 1], events[idx, 2]
        r = np.arange(rows.size)
        n_link, _ = edge_normals(P)
        edge = kind_ == 0  # link vertex lf on workpiece edge wf: the edge's inward normal
        point[rows] = np.where(edge[:, None], P[r, lf], W[rows, wf])
        normal[rows] = np.where(edge[:, None], -normals_w[0][rows, wf], n_link[r, lf])
        value[rows], kind[rows], feature[rows], link_feature[rows] = v, kind_, wf, lf
        # flush: a candidate on its segment at the same value (FLUSH_TOL) touching at another point (to a nanometre)
        i, e = np.nonzero(np.abs(vals[rows] - v[:, None]) <= FLUSH_TOL)
        on = _on_segments(joint.kind, base, link, W, rows[i], e, vals[rows[i], e], events, tol)
        i, e = i[on], e[on]
        pts = np.where((events[e, 0] == 0)[:, None], P[i, events[e, 1]], W[rows[i], events[e, 2]])
        other = np.any(np.round(pts, 9) != np.round(point[rows[i]], 9), axis=1)
        flush[rows[i[other]]] = True
    return ClosedFingers(found, value, k, kind, feature, link_feature, point, normal, flush)
