"""The workpiece a hand holds: a convex polygon resting on one edge on the palm (Section 5.2, Fig. 9).

:func:`prepare_workpiece` is the one place where a workpiece as the user wrote it becomes the
hands' internal form: counter-clockwise, about its centroid (the centre of mass of a uniform
plate), vertex 0 the left end of the edge that lies on the palm, and the two maps between the
user's vertex numbering and the internal one.  Every hand (:mod:`qsplan.hands.paper_hand.two_finger`,
:mod:`qsplan.hands.chains.hand`) builds on it.  Units m.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qsplan.mechanics.errors import SceneError

__all__ = ["polygon_inertia", "FLAT_TOL", "PreparedWorkpiece", "prepare_workpiece", "rotation", "workpiece_world"]

#: Relative tolerance (of the workpiece's size) within which the two lowest
#: vertices count as one horizontal bottom edge; polygon coordinates are
#: decimal inputs, so 1e-9 of the size is rounding, not a tilt.
FLAT_TOL = 1e-9


@dataclass(frozen=True, slots=True, eq=False)
class PreparedWorkpiece:
    """A workpiece in the hands' internal form.

    Attributes
    ----------
    vertices : ndarray, shape (k, 2)
        Counter-clockwise about the centroid (m), read-only; vertex 0 is the left end of the bottom edge, vertex 1
        its right end.
    vertex_order : tuple of int, shape (k,)
        Internal vertex ``i`` is the vertex ``vertex_order[i]`` of the polygon as the user wrote it.
    vertex_of_user : tuple of int, shape (k_user,)
        The internal vertex of each row of the polygon as written (a repeated row maps to the vertex it repeats).
    """

    vertices: np.ndarray
    vertex_order: tuple
    vertex_of_user: tuple


def rotation(theta) -> np.ndarray:
    """The 2 x 2 rotation matrix by ``theta`` (rad)."""
    c, s = np.cos(theta), np.sin(theta)
    return np.array([[c, -s], [s, c]])


def workpiece_world(hand, pose) -> np.ndarray:
    """Workpiece vertices in the world (m), shape (k, 2), at ``pose = (x, y, theta)`` of its centre of mass.

    ``hand`` is any hand with a ``workpiece`` (k, 2) in its body frame."""
    pose = np.asarray(pose, dtype=float)
    return hand.workpiece @ rotation(pose[2]).T + pose[:2]


def prepare_workpiece(workpiece, palm_edge=None, field: str = "workpiece") -> PreparedWorkpiece:
    """Validate a workpiece polygon and put it in the internal form (see :class:`PreparedWorkpiece`).

    Parameters
    ----------
    workpiece : array-like, shape (k, 2)
        Convex polygon (m), any placement and orientation.  Its two lowest vertices must be level (the edge that
        rests on the palm) unless ``palm_edge`` says which edge rests there.
    palm_edge : int, optional
        The edge (0-based, numbered as written: edge ``K`` runs from vertex ``K`` to ``K + 1``) that rests on the
        palm: the polygon is turned to lay it level at the bottom, and its centroid must lie over it.
    field : str
        The field named in errors.

    Raises
    ------
    SceneError
        Naming the field: non-convex or degenerate workpiece, no level bottom edge, a ``palm_edge`` out of range
        or that the workpiece cannot rest on.
    """
    from shapely.geometry import Polygon

    from qsplan.mechanics.model.geometry import check_polygon

    V = check_polygon(workpiece, field)
    poly = Polygon(V)
    if abs(poly.convex_hull.area - poly.area) > 1e-12 * poly.area or len(np.asarray(poly.convex_hull.exterior.coords)) - 1 != len(V):
        raise SceneError(f"{field}: expected a convex polygon with no straight vertices (the fingers touch its corners)")
    raw = np.asarray(workpiece, dtype=float).reshape(-1, 2)  # the validated vertex of each row (repeats are dropped):
    of_user = np.argmin(np.linalg.norm(raw[:, None] - V[None], axis=2), axis=1)
    perm = np.arange(len(V))
    if not poly.exterior.is_ccw:
        V, perm = V[::-1], perm[::-1]
    if palm_edge is not None:
        V, poly = _lay_on_edge(V, perm, of_user, palm_edge)
    size = float(np.ptp(V, axis=0).max())
    order = np.argsort(V[:, 1], kind="stable")
    low = V[order[:2]]
    if abs(low[0, 1] - low[1, 1]) > FLAT_TOL * size or abs(V[order[2], 1] - low[0, 1]) <= FLAT_TOL * size:
        raise SceneError(f"{field}: expected exactly two lowest vertices at the same height (the edge resting on the palm)")
    start = int(order[0] if V[order[0], 0] < V[order[1], 0] else order[1])
    V, perm = np.roll(V, -start, axis=0), np.roll(perm, -start)
    if V[1, 0] <= V[0, 0] or abs(V[1, 1] - V[0, 1]) > FLAT_TOL * size:
        raise SceneError(f"{field}: the bottom edge must run left to right from vertex 0 (counter-clockwise order)")
    c = np.asarray(poly.centroid.coords[0])
    V = V - c
    V.setflags(write=False)
    return PreparedWorkpiece(V, tuple(int(np.flatnonzero(of_user == j)[0]) for j in perm),
                             tuple(int(i) for i in np.argsort(perm)[of_user]))  # fmt: skip


def _lay_on_edge(V, perm, of_user, palm_edge):
    """``V`` (k, 2, counter-clockwise; ``perm`` its validated vertex order) turned so that the edge
    ``palm_edge`` as written is level at the bottom, and its shapely Polygon."""
    from shapely.geometry import Polygon

    n_user = len(of_user)
    if isinstance(palm_edge, (bool, np.bool_)) or not isinstance(palm_edge, (int, np.integer)) or not 0 <= palm_edge < n_user:
        raise SceneError(f"palm_edge: expected an edge index in [0, {n_user}) of the workpiece as written; got {palm_edge!r}")
    pos = np.argsort(perm)  # validated vertex -> position in V
    a, b = pos[of_user[palm_edge]], pos[of_user[(palm_edge + 1) % n_user]]
    if a == b:  # a row repeating its predecessor
        raise SceneError(f"palm_edge: edge {palm_edge} of the workpiece as written has zero length")
    a, b = (a, b) if (b - a) % len(V) == 1 else (b, a)  # counter-clockwise: the palm below the edge
    d = V[b] - V[a]
    V = V @ rotation(-np.arctan2(d[1], d[0])).T
    level = 0.5 * (V[a, 1] + V[b, 1])  # the turn leaves ~1e-17 m of tilt: lay the edge exactly level
    V[a, 1] = V[b, 1] = level
    poly = Polygon(V)
    if not V[a, 0] < poly.centroid.x < V[b, 0]:
        raise SceneError(f"palm_edge: the workpiece cannot rest on edge {palm_edge}: its centroid (x = {poly.centroid.x:.6g} m "
                         f"along the edge) is not over the edge [{V[a, 0]:.6g}, {V[b, 0]:.6g}] m")  # fmt: skip
    return V, poly


def polygon_inertia(polygon, mass) -> tuple:
    """``(centroid (2,), inertia about it)`` of a uniform lamina of ``mass`` (kg) over ``polygon`` (k, 2) (m): the
    polar second moment (kg m^2), by the shoelace sums."""
    p = np.asarray(polygon, dtype=float)
    a, b = p, np.roll(p, -1, axis=0)
    cross = a[:, 0] * b[:, 1] - b[:, 0] * a[:, 1]
    area = cross.sum() / 2.0
    c = ((a + b) * cross[:, None]).sum(axis=0) / (6.0 * area)
    a, b = a - c, b - c
    cross = a[:, 0] * b[:, 1] - b[:, 0] * a[:, 1]
    j = (cross * (a[:, 0] ** 2 + a[:, 0] * b[:, 0] + b[:, 0] ** 2 + a[:, 1] ** 2 + a[:, 1] * b[:, 1]
                  + b[:, 1] ** 2)).sum() / 12.0  # fmt: skip
    return c, abs(float(mass) * j / area)
