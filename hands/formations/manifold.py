"""A contact formation's configuration manifold, solved for any hand (Section 3, eqs. 1, 5, 6).

A configuration is ``c = (x, y, theta, q_1 .. q_nj)``: the workpiece's pose (m, m, rad) and the joints (rad or m).
A formation keeps some features touching: each constraint here is a vertex of one body on the *line* of an edge of
another (:class:`VertexOnLine`), its signed gap ``g(c)`` (m, positive outside the edge's polygon) zero.  A body edge
flush on a workpiece edge is two constraints: both ends of the workpiece edge on the body edge's line.  Where the
contact sits along its edge is not a constraint but an event (:func:`along_edges`: a vertex leaving its edge).

The gap's rate is the relative normal velocity of eq. 6, ``g' = n . (v_workpiece(r) - v_body(r))`` with ``n`` the
normal into the workpiece and ``r`` the touching vertex, so the constraints' Jacobian is, row by row,
``dg/dc = [n_x, n_y, n . (z x (r - p)), -n^T J_p(r)]`` with ``J_p`` the body point's Jacobian
(:func:`qsplan.mechanics.model.manipulator.point_jacobian`; zero on the palm).  :func:`project` solves ``g(c) = 0``
for the coordinates a caller leaves *free* by Newton's method from a guess; :func:`tangent` gives the manifold's
direction per unit of one *driving* coordinate (its other coordinates held: a hand's free joints); :func:`sweep`
follows the manifold along the driving coordinate by prediction (the tangent) and correction (:func:`project`).

One algorithm for every hand the :class:`qsplan.hands.protocol.Hand` protocol describes (single-link fingers,
chains, prismatic jaws); the tests check it against the paper hand's closed form (``tests/reference/paper_pivot.py``).
Units SI.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qsplan.mechanics.errors import QsplanError

__all__ = ["GAP_TOL", "MAX_NEWTON", "MAX_STEP", "ManifoldPoints", "VertexOnLine", "along_edges", "constraint_jacobian", "gaps",
           "project", "sweep", "tangent"]

#: Newton's stopping gap (m): fifty rounding units of a 0.1 m coordinate (2e-17 m each), far below the contact
#: tolerance (1e-6 m) the contact search and the certifier use.  Newton converges quadratically, so this costs one
#: iteration more than a looser 1e-12 and leaves angles exact to ~1e-14 rad (1e-12 m left them 1e-11 rad off a
#: closed form).
GAP_TOL = 1e-15

#: Newton iterations before a projection gives up: from a prediction one step along the tangent it converges
#: quadratically in 2-4; a configuration out of reach (a finger that cannot close there) does not converge at all.
MAX_NEWTON = 25

#: Largest Newton step (m or rad) before a projection is taken as diverging: half a turn (past it a joint's
#: linearisation means nothing); a first step from a rough guess may well be a radian.
MAX_STEP = np.pi

#: The bodies a feature can belong to: the workpiece, the palm, a finger's last link.
_BODIES = ("workpiece", "palm", "left", "right")


@dataclass(frozen=True, slots=True)
class VertexOnLine:
    """A vertex of ``vertex_body`` on the line of edge ``edge`` of ``edge_body`` (one of them the workpiece).

    Attributes
    ----------
    vertex_body, edge_body : str
        ``"workpiece"``, ``"palm"``, ``"left"`` or ``"right"`` (a finger's last link); exactly one is the workpiece.
    vertex, edge : int
        Indices into the bodies' polygons (the workpiece's internal numbering, ``hand.workpiece``; a body's ring as
        the hand writes it); edge ``k`` runs from vertex ``k`` to ``k + 1``.
    """

    vertex_body: str
    vertex: int
    edge_body: str
    edge: int

    def __post_init__(self):
        for field, body in (("vertex_body", self.vertex_body), ("edge_body", self.edge_body)):
            if body not in _BODIES:
                raise QsplanError(f"{field}: expected one of {', '.join(_BODIES)}; got {body!r}")
        if (self.vertex_body == "workpiece") == (self.edge_body == "workpiece"):
            raise QsplanError(f"VertexOnLine: exactly one of vertex_body, edge_body must be the workpiece; got "
                              f"{self.vertex_body!r} and {self.edge_body!r}")  # fmt: skip

    @property
    def body(self) -> str:
        """The hand's body (``"palm"``, ``"left"``, ``"right"``)."""
        return self.edge_body if self.vertex_body == "workpiece" else self.vertex_body


@dataclass(frozen=True, slots=True, eq=False)
class ManifoldPoints:
    """A formation's manifold at ``n`` values of its driving coordinate (:func:`sweep`).

    Attributes
    ----------
    c : ndarray, shape (n, 3 + n_j)
        Configurations ``(x, y, theta, q)`` (m, m, rad, rad or m).
    dc : ndarray, shape (n, 3 + n_j)
        Their rates per unit of the driving coordinate (the held coordinates' 0).
    driving : int
        The driving coordinate's index in ``c`` (0: x, 2: theta).
    reached : int
        How many of the asked values the manifold reached (the rest: ``c`` NaN): Newton did not converge there (no
        configuration: a finger out of reach, a singular grasp).
    """

    c: np.ndarray
    dc: np.ndarray
    driving: int
    reached: int

    @property
    def pose(self) -> np.ndarray:
        return self.c[:, :3]

    @property
    def q(self) -> np.ndarray:
        return self.c[:, 3:]


def _polygon(hand, body: str, c) -> np.ndarray:
    """``body``'s world polygon (m), shape (k, 2), at configuration ``c``."""
    from qsplan.hands.contacts.sets import body_ring
    from qsplan.hands.geometry.workpiece import workpiece_world

    if body == "workpiece":
        return workpiece_world(hand, c[:3])
    return body_ring(hand, body, c[3:])


def _ccw(P) -> bool:
    """Whether the ring ``P`` runs counter-clockwise (the shoelace formula's sign)."""
    x, y = P[:, 0], P[:, 1]
    return float(x[:-1] @ y[1:] - x[1:] @ y[:-1] + x[-1] * y[0] - x[0] * y[-1]) > 0.0


def _located(hand, constraints, c) -> tuple:
    """Per constraint: ``(vertex point r, unit edge direction e, outward normal m of the edge, edge start a, length)``."""
    polys = {b: _polygon(hand, b, c) for b in {k.vertex_body for k in constraints} | {k.edge_body for k in constraints}}
    out = []
    for k in constraints:
        V, E = polys[k.vertex_body], polys[k.edge_body]
        if not (0 <= k.vertex < len(V) and 0 <= k.edge < len(E)):
            raise QsplanError(f"constraint {k}: a feature index is out of range (the polygons have {len(V)} and "
                              f"{len(E)} vertices)")  # fmt: skip
        a, b = E[k.edge], E[(k.edge + 1) % len(E)]
        d = b - a
        length = float(np.hypot(*d))
        e = d / length
        m = np.array([e[1], -e[0]]) if _ccw(E) else np.array([-e[1], e[0]])
        out.append((V[k.vertex], e, m, a, length))
    return out


def gaps(hand, constraints, c) -> np.ndarray:
    """Each constraint's signed gap (m), shape (n_k,): the vertex's distance from the edge's line, positive outside
    the edge's polygon."""
    return np.array([(r - a) @ m for r, _, m, a, _ in _located(hand, constraints, np.asarray(c, float))])


def along_edges(hand, constraints, c) -> np.ndarray:
    """Where each constraint's vertex lies along its edge, as a fraction of the edge's length (shape (n_k,)): in
    ``[0, 1]`` while it touches the edge itself, outside once it has passed an end."""
    return np.array([((r - a) @ e) / length for r, e, _, a, length in _located(hand, constraints, np.asarray(c, float))])


def constraint_jacobian(hand, constraints, c) -> np.ndarray:
    """``d gaps / d c``, shape (n_k, 3 + n_j) (the module docstring's rows)."""
    from qsplan.hands.contacts.sets import finger_link
    from qsplan.mechanics.model.manipulator import point_jacobian

    c = np.asarray(c, dtype=float)
    man = hand.manipulator
    rows = []
    for k, (r, _, m, _, _) in zip(constraints, _located(hand, constraints, c)):
        n = m if k.vertex_body == "workpiece" else -m  # into the workpiece
        rel = r - c[:2]
        row = np.zeros(c.size)
        row[:3] = n[0], n[1], n[0] * -rel[1] + n[1] * rel[0]
        link = finger_link(hand, k.body)
        if link >= 0:
            row[3:] = -n @ point_jacobian(man, c[3:], link, r)
        rows.append(row)
    return np.array(rows)


def project(hand, constraints, c0, free, tol: float = GAP_TOL, max_iter: int = MAX_NEWTON):
    """``c0`` moved in its ``free`` coordinates (indices into ``c``) until every gap is within ``tol``: Newton's
    method (least squares where the constraints do not fix every free coordinate).  None when it does not converge
    (no configuration near ``c0``)."""
    c = np.array(c0, dtype=float)
    free = np.asarray(free, dtype=int)
    for _ in range(max_iter):
        g = gaps(hand, constraints, c)
        if not np.all(np.isfinite(g)):
            return None
        if np.max(np.abs(g), initial=0.0) <= tol:
            return c
        J = constraint_jacobian(hand, constraints, c)[:, free]
        step = np.linalg.lstsq(J, -g, rcond=None)[0]
        c[free] += step
        if not np.all(np.isfinite(c)) or np.max(np.abs(step)) > MAX_STEP:
            return None
    return None


def tangent(hand, constraints, c, driving: int, free) -> np.ndarray:
    """The manifold's rate per unit of coordinate ``driving`` at ``c``: the ``free`` coordinates' rates that keep
    every gap (``J_free dc_free = -J_driving``), the driving one's 1, the others' 0.  Shape (3 + n_j,)."""
    c = np.asarray(c, dtype=float)
    free = np.asarray(free, dtype=int)
    J = constraint_jacobian(hand, constraints, c)
    dc = np.zeros(c.size)
    dc[driving] = 1.0
    dc[free] = np.linalg.lstsq(J[:, free], -J[:, driving], rcond=None)[0]
    return dc


def sweep(hand, constraints, c0, driving: int, values, free) -> ManifoldPoints:
    """The manifold through ``c0`` at each of ``values`` (its driving coordinate's, in order from ``c0``'s):
    predicted along the tangent, corrected by :func:`project`.  Stops at the first value it cannot reach."""
    values = np.asarray(values, dtype=float)
    n, size = values.size, np.asarray(c0).size
    c, dc = np.full((n, size), np.nan), np.full((n, size), np.nan)
    prev = project(hand, constraints, c0, free)
    reached = 0
    if prev is not None:
        t = tangent(hand, constraints, prev, driving, free)
        for i, v in enumerate(values):
            guess = prev + t * (v - prev[driving])  # predicted along the last point's tangent
            guess[driving] = v
            found = project(hand, constraints, guess, free)
            if found is None:
                break
            t = tangent(hand, constraints, found, driving, free)
            c[i], dc[i], prev = found, t, found
            reached = i + 1
    return ManifoldPoints(c, dc, int(driving), reached)
