"""Closing a finger of any serial chain onto the workpiece: where its last joint first touches (Section 3, eq. 1).

A finger of a hand description (:mod:`qsplan.hands.description`) is a serial chain of
revolute and prismatic joints.  With every joint but the last held (its *free* joints), the
last joint (the *closing* joint) moves the distal link on a circle about its axis or along a
line.  The finger closes from the end of the closing joint's range that lies away from the
workpiece, in the direction that moves the distal link toward the other finger (its centroid's
``x`` increasing for the left finger, decreasing for the right one), and stops at the first
contact: the first value at which the link and the workpiece (both convex) touch.

The candidates are closed forms (:func:`contact_events`): a link vertex reaching a workpiece
edge's line, or a workpiece vertex reaching a link edge's line, on a circle (``acos``) or a line
(a division).  A candidate is a contact where the two polygons touch without overlapping (their
separation, :func:`separation`, within :data:`TOUCH_TOL`).  For the paper's single-link fingers
this is the tangency of :func:`qsplan.hands.paper_hand.two_finger.finger_angles` (the tests compare the two).

Contacts follow the paper's conventions: the normal points into the workpiece; a workpiece vertex on
a link edge has the link edge's outward normal, a link vertex on a workpiece edge that edge's
inward normal.  Units SI (m, rad).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qsplan.mechanics.model.geometry import CONTACT_TOL

__all__ = ["ClosedFinger", "TOUCH_TOL", "FLUSH_TOL", "close_finger", "closing_direction", "contact_events",
           "separation"]

#: Separation (m) within which a candidate contact counts as touching: the contact finder's tolerance
#: (:data:`qsplan.mechanics.model.geometry.CONTACT_TOL`, a micron), far above the ~1e-15 m rounding of a
#: closed-form event and far below any gap a hand distinguishes from contact.
TOUCH_TOL = CONTACT_TOL

#: Two candidates of one closing closer than this (rad or m) are one event: a link edge lying flush on a
#: workpiece edge reaches both of its end contacts at once (two contacts on one link: not a one-contact
#: grasp).  1e-9 rad moves a point 10 cm out by 1e-10 m, a ten-thousandth of the contact tolerance.
FLUSH_TOL = 1e-9


@dataclass(frozen=True, slots=True, eq=False)
class ClosedFinger:
    """A finger closed onto the workpiece.

    Attributes
    ----------
    value : float
        The closing joint's position at first contact (rad or m).
    link : int
        The touching link (manipulator joint index; the closing joint's link).
    kind : str
        ``"vertex"``: workpiece vertex ``feature`` on the link's edge ``link_feature``; ``"edge"``: the link's vertex
        ``link_feature`` (a fingertip corner) on workpiece edge ``feature`` (internal numbering).
    feature, link_feature : int
    point : ndarray, shape (2,)
        Contact point (m), world frame.
    normal : ndarray, shape (2,)
        Unit normal into the workpiece.
    flush : bool
        A second contact arrives at the same value (a link edge flush with a workpiece edge).
    """

    value: float
    link: int
    kind: str
    feature: int
    link_feature: int
    point: np.ndarray
    normal: np.ndarray
    flush: bool

    @property
    def key(self) -> tuple:
        """``(link, kind, feature)``: what touches what, the identity of a grasp's contact."""
        return (self.link, self.kind, self.feature)


def _outward(P):
    """Outward unit normals (k, 2) and offsets (k,) of the edges of a counter-clockwise polygon ``P`` (k, 2)."""
    d = np.concatenate((P[1:], P[:1])) - P
    m = d[:, ::-1] * np.array([1.0, -1.0]) / np.hypot(d[:, 0], d[:, 1])[:, None]
    return m, (m * P).sum(axis=1)


def _ccw(P):
    P = np.asarray(P, dtype=float)
    x, y = P[:, 0], P[:, 1]
    return P if np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y) > 0 else P[::-1]


def separation(A, B, normals_b=None) -> float:
    """Signed separation (m) of two convex counter-clockwise polygons: positive apart, zero touching, minus the
    penetration depth along the best separating axis where they overlap (the separating-axis theorem).
    ``normals_b``: ``_outward(B)`` when the caller has it."""
    m, h = _outward(A)
    mb, hb = _outward(B) if normals_b is None else normals_b
    return float(max(np.max(np.min(B @ m.T, axis=0) - h), np.max(np.min(A @ mb.T, axis=0) - hb)))


def _rot(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s], [s, c]])


def contact_events(kind: str, origin, angle: float, link, W, normals_w=None) -> tuple:
    """Closing-joint values at which the link's polygon first meets a workpiece feature's line, in closed form.

    Parameters
    ----------
    kind : {"revolute", "prismatic"}
    origin : array-like, shape (2,)
        The closing joint's axis (revolute) or the link frame's origin at value 0 (prismatic), world (m).
    angle : float
        The link frame's angle at value 0 (rad).
    link : ndarray, shape (k, 2)
        The link polygon, counter-clockwise, in its frame (m).
    W : ndarray, shape (w, 2)
        The workpiece, counter-clockwise, world (m).
    normals_w : (ndarray (w, 2), ndarray (w,)), optional
        The workpiece's outward edge normals and offsets, when the caller has them.

    Returns
    -------
    values : ndarray, shape (m,)
        Candidate values (rad or m), revolute ones in ``(-pi, pi]`` plus ``angle`` turns (wrapped by the caller).
    events : ndarray of int, shape (m, 3)
        ``(kind, link feature, workpiece feature)``: kind 0 a link vertex on a workpiece edge, 1 a workpiece vertex
        on a link edge.
    """
    c = np.asarray(origin, dtype=float)
    m, h = _outward(W) if normals_w is None else normals_w  # workpiece edges
    n, g = _outward(link)  # link edges, link frame
    vals, evs = [], []
    if kind == "revolute":
        rho, gam = np.hypot(link[:, 0], link[:, 1]), np.arctan2(link[:, 1], link[:, 0])
        beta, rhs = np.arctan2(m[:, 1], m[:, 0]), h - m @ c
        with np.errstate(invalid="ignore", divide="ignore"):
            ac = np.arccos(rhs[None, :] / rho[:, None])  # (link vertex, workpiece edge)
        for sign in (1.0, -1.0):
            s = beta[None, :] - angle - gam[:, None] + sign * ac
            i, j = np.nonzero(np.isfinite(s))
            vals.append(s[i, j]), evs.append(np.column_stack([np.zeros_like(i), i, j]))
        d = W - c
        r, delta, nu = np.hypot(d[:, 0], d[:, 1]), np.arctan2(d[:, 1], d[:, 0]), np.arctan2(n[:, 1], n[:, 0])
        with np.errstate(invalid="ignore", divide="ignore"):
            ac = np.arccos(g[:, None] / r[None, :])  # (link edge, workpiece vertex)
        for sign in (1.0, -1.0):
            s = delta[None, :] - nu[:, None] - angle + sign * ac
            e, k = np.nonzero(np.isfinite(s))
            vals.append(s[e, k]), evs.append(np.column_stack([np.ones_like(e), e, k]))
    else:
        u, R = np.array([np.cos(angle), np.sin(angle)]), _rot(angle)
        Lw = link @ R.T + c
        mu_ = m @ u
        with np.errstate(invalid="ignore", divide="ignore"):
            s = (h[None, :] - Lw @ m.T) / mu_[None, :]  # (link vertex, workpiece edge)
        i, j = np.nonzero(np.isfinite(s))
        vals.append(s[i, j]), evs.append(np.column_stack([np.zeros_like(i), i, j]))
        nw = n @ R.T
        with np.errstate(invalid="ignore", divide="ignore"):
            s = ((W - c) @ nw.T - g[None, :]).T / (nw @ u)[:, None]  # (link edge, workpiece vertex)
        e, k = np.nonzero(np.isfinite(s))
        vals.append(s[e, k]), evs.append(np.column_stack([np.ones_like(e), e, k]))
    return np.concatenate(vals), np.concatenate(evs).astype(int)


def closing_direction(man, q, joint: int, side: float) -> float:
    """+1 or -1: the sign of the closing joint's motion that moves its link's centroid toward the other finger
    (``side`` +1 for the left finger, which closes toward +x; -1 for the right one) at the joint positions ``q``
    (the caller puts the closing joint mid-range); 0 where it does not move in x."""
    from qsplan.mechanics.model.manipulator import link_poses

    poses = link_poses(man, q)
    x, y, a = poses[joint]
    shape = np.asarray(man.joints[joint].link_shape, dtype=float)
    cx, cy = shape.mean(axis=0) @ _rot(a).T + (x, y)
    dx = -(cy - y) if man.joints[joint].kind == "revolute" else np.cos(a)
    return float(np.sign(side * dx))


def close_finger(man, q, joints, limits, W, side: float, tol: float = TOUCH_TOL) -> ClosedFinger | None:
    """Close a finger onto the workpiece ``W`` by its last joint (see the module docstring).

    Parameters
    ----------
    man : qsplan.mechanics.model.manipulator.Manipulator
    q : ndarray, shape (n_j,)
        Joint positions; the finger's free joints are read from it, its closing joint's entry is ignored.
    joints : sequence of int
        The finger's joints, base to tip; the last closes.
    limits : ndarray, shape (n_j, 2)
        Joint ranges (rad or m).
    W : ndarray, shape (w, 2)
        Workpiece, counter-clockwise, world (m).
    side : float
        +1 for the left finger, -1 for the right one.
    tol : float
        Separation (m) within which the link and the workpiece touch.

    Returns
    -------
    ClosedFinger or None
        None where the finger closes onto nothing within its range, or already overlaps the workpiece where it
        starts closing.
    """
    from qsplan.mechanics.model.manipulator import link_poses

    k = int(joints[-1])
    joint = man.joints[k]
    q = np.array(q, dtype=float)
    lo, hi = (float(v) for v in limits[k])
    q[k] = 0.5 * (lo + hi)
    direction = closing_direction(man, q, k, side)
    q[k] = 0.0
    base = link_poses(man, q)[k]  # the link frame at closing value 0
    if direction == 0.0:
        return None
    link = _ccw(joint.link_shape)
    start = hi if direction < 0 else lo

    def world(v):
        if joint.kind == "revolute":
            return (link @ _rot(base[2] + v).T) + base[:2]
        return link @ _rot(base[2]).T + base[:2] + v * np.array([np.cos(base[2]), np.sin(base[2])])

    normals_w = _outward(W)
    if separation(world(start), W, normals_w) < -tol:
        return None
    vals, evs = contact_events(joint.kind, base[:2], float(base[2]), link, W, normals_w)
    if joint.kind == "revolute":  # the turn that reaches each candidate first from the start, in the closing direction
        vals = start + direction * np.mod(direction * (vals - start), 2.0 * np.pi)
    ahead = (direction * (vals - start) >= 0.0) & (vals >= lo) & (vals <= hi)
    vals, evs = vals[ahead], evs[ahead]
    order = np.argsort(direction * (vals - start), kind="stable")
    vals, evs = vals[order], evs[order]
    on = _on_segments(joint.kind, base, link, W, vals, evs, tol)
    for idx in np.flatnonzero(on):  # the first segment event is the first contact (both convex, apart at the start)
        v = float(vals[idx])
        P = world(v)
        if abs(separation(P, W, normals_w)) > tol:  # rounding put an event on a segment's end: the next one is the contact
            continue
        near = on & (np.abs(vals - v) <= FLUSH_TOL)
        kind_, lf, wf = (int(x) for x in evs[idx])
        if kind_ == 0:  # link vertex lf on workpiece edge wf
            m = normals_w[0]
            point, normal, out = P[lf], -m[wf], ("edge", wf, lf)
        else:  # workpiece vertex wf on link edge lf
            n, _ = _outward(P)
            point, normal, out = W[wf], n[lf], ("vertex", wf, lf)
        flush = len({_contact_point(e, P, W) for e in evs[near].tolist()}) > 1
        return ClosedFinger(v, k, out[0], out[1], out[2], point.copy(), normal.copy(), flush)
    return None


def _on_segments(kind, base, link, W, vals, evs, tol) -> np.ndarray:
    """Whether each candidate's touching point lies on the edge it reaches (within ``tol`` m of its ends), shape (m,)."""
    a = base[2] + vals if kind == "revolute" else np.full(len(vals), base[2])
    shift = base[:2] if kind == "revolute" else base[:2] + vals[:, None] * np.array([np.cos(base[2]), np.sin(base[2])])
    c, s = np.cos(a), np.sin(a)

    def place(local):  # link-frame points (m, 2) at each candidate
        return np.stack([c * local[:, 0] - s * local[:, 1], s * local[:, 0] + c * local[:, 1]], axis=1) + shift

    k0, lf, wf = evs[:, 0] == 0, evs[:, 1], evs[:, 2]
    p = np.where(k0[:, None], place(link[lf]), W[wf])  # the touching vertex
    a0 = np.where(k0[:, None], W[wf], place(link[lf]))  # the edge reached: from a0 to a1
    a1 = np.where(k0[:, None], W[(wf + 1) % len(W)], place(link[(lf + 1) % len(link)]))
    d = a1 - a0
    length = np.hypot(d[:, 0], d[:, 1])
    along = np.einsum("ij,ij->i", p - a0, d) / length
    return (along >= -tol) & (along <= length + tol)


def _contact_point(event, P, W) -> tuple:
    """The contact point of a candidate, rounded to a nanometre (one point reached by two events is one contact)."""
    kind, lf, wf = event
    p = P[lf] if kind == 0 else W[wf]
    return (round(float(p[0]), 9), round(float(p[1]), 9))
