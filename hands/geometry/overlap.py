"""Overlap of convex polygons in numpy, batched: the fast path of :mod:`qsplan.hands.geometry.collision`.

Two measures of how deeply convex polygons ``A`` and ``B`` overlap, vectorised over batch axes:

* :func:`separating_depth`, the separating-axis theorem: the smallest overlap of the two
  projections over the edge normals of both (negative when an axis separates them).  Cheap,
  and an upper bound of the width below: the intersection lies in both bodies, so its extent
  along any axis is at most the overlap of their projections.
* :func:`intersection_width`, the narrowest width of ``A ∩ B`` (the measure of
  :func:`qsplan.hands.geometry.collision.overlap_depth`), exactly: every edge of the
  intersection lies on an edge line of ``A`` or ``B``, so its vertices are the crossings of two
  of those lines that satisfy every edge's half-plane, and its narrowest width is its smallest
  extent across one of those normals (rotating calipers: extents across the others are no smaller).

Polygons are :class:`Polygons`, arrays with the vertex axis first and the batch axes after it
(``(k, ...)``), so that every reduction over vertices runs over contiguous batches; polygons of
different sizes share ``k`` by repeating a vertex.  :func:`disk_pieces` covers and fills a polygon
outside a disk with convex pieces (a link outside its joint housing).  Units m.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

__all__ = ["PARALLEL_SIN", "VERTEX_SLACK", "PolygonPairs", "Polygons", "clip_polygon", "convex_vertices", "disk_pieces",
           "intersection_width", "make_polygons", "pair_depths", "polygon_pairs", "separating_depth"]  # fmt: skip

#: Two edge lines whose unit normals have a cross product below this are parallel: they cross at no
#: vertex of the intersection (it has a vertex there only if the lines also meet another edge line,
#: which defines it).  Dropping a true crossing of lines this close to parallel moves the width by at
#: most this angle times the bodies' size, ~1e-13 m for a hand of 0.3 m.
PARALLEL_SIN = 1e-12

#: Distance (m) by which a crossing of two edge lines may lie outside an edge's half-plane and still
#: count as a vertex of the intersection: the rounding of a crossing (~1e-16 m per m of coordinate for
#: lines crossing at a fair angle), with room for nearly parallel ones.  Accepting a point this far
#: outside moves a width by about as much, far inside the callers' decision band.
VERTEX_SLACK = 1e-12


@dataclass(frozen=True, slots=True, eq=False)
class Polygons:
    """Convex polygons, counter-clockwise, as vertices and as half-planes ``Re(conj(w) p) <= offset``.

    Points and directions are complex numbers ``x + iy`` (a rotation is one product).  Every
    attribute has shape ``(k, ...)``: vertex (or edge) ``i`` first, the batch axes after.  Padding
    repeats the last vertex; its zero-length edges repeat the closing edge's line.

    Attributes
    ----------
    z : ndarray of complex
        Vertices (m).
    w : ndarray of complex
        Outward unit normal of the edge from vertex ``i``.
    offset : ndarray
        ``Re(conj(w) z)`` of that edge (m).
    breadth : ndarray
        Extent of the polygon across that edge's normal (m): unchanged by a rigid motion.
    """

    z: np.ndarray
    w: np.ndarray
    offset: np.ndarray
    breadth: np.ndarray

    def __getitem__(self, index) -> Polygons:
        """The polygons at ``index`` of the batch axes (the vertex axis kept)."""
        index = (slice(None), *(index if isinstance(index, tuple) else (index,)))
        return Polygons(self.z[index], self.w[index], self.offset[index], self.breadth[index])

    def moved(self, turn, shift) -> Polygons:
        """The polygons rotated by ``turn`` (complex, unit) then translated by ``shift`` (complex, m); arrays
        broadcasting against the batch axes, the result's batch shape the broadcast one (``breadth`` kept as is)."""
        w = turn * self.w
        return Polygons(turn * self.z + shift, w, self.offset + (w.conj() * shift).real, self.breadth)


def convex_vertices(vertices) -> np.ndarray | None:
    """``vertices`` (array-like, shape (m, 2), m, either orientation) counter-clockwise without repeats,
    shape (k, 2); None when the polygon is not convex or has no area."""
    V = np.asarray(vertices, float).reshape(-1, 2)
    if len(V) < 3:
        return None
    # drop repeated vertices (a closing copy, a clip through a vertex): an edge of rounding's length has
    # a normal of no meaning, and its half-plane would cut the polygon
    V = V[np.hypot(*(np.roll(V, -1, axis=0) - V).T) > 1e-12 * float(np.ptp(V, axis=0).max())]
    if len(V) < 3:
        return None
    if np.sum(V[:, 0] * np.roll(V[:, 1], -1) - np.roll(V[:, 0], -1) * V[:, 1]) < 0.0:
        V = V[::-1]
    e = np.roll(V, -1, axis=0) - V
    length = np.hypot(e[:, 0], e[:, 1])
    turn = e[:, 0] * np.roll(e[:, 1], -1) - e[:, 1] * np.roll(e[:, 0], -1)
    # a straight vertex computes as turning either way by rounding: tolerate 1e-12 of the edges' product
    if np.any(turn < -1e-12 * length * np.roll(length, -1)) or not np.any(turn > 0.0):
        return None
    return V


def make_polygons(polygons, k: int | None = None) -> Polygons:
    """T convex polygons stacked as :class:`Polygons` of batch shape (T,), padded to ``k`` vertices.

    Parameters
    ----------
    polygons : sequence of ndarray, each shape (m_t, 2)
        Counter-clockwise convex polygons without repeated vertices (:func:`convex_vertices`), m.
    k : int, optional
        Vertex count; default the largest ``m_t``.
    """
    k = max(len(V) for V in polygons) if k is None else k
    cols = []
    for V in polygons:
        z = V[:, 0] + 1j * V[:, 1]
        e = np.roll(z, -1) - z
        w = -1j * e / np.abs(e)  # the edge turned clockwise: outward for a counter-clockwise polygon
        pad = k - len(z)
        # padding repeats the last vertex: the edges that start there are copies of the closing edge
        z = np.concatenate([z, np.repeat(z[-1:], pad)])
        w = np.concatenate([w[:-1], np.repeat(w[-1:], pad + 1)])
        proj = (w.conj()[:, None] * z[None]).real
        cols.append((z, w, proj.diagonal(), proj.max(axis=1) - proj.min(axis=1)))
    return Polygons(*(np.stack(c, axis=1) for c in zip(*cols)))


def clip_polygon(vertices, direction, offset) -> np.ndarray:
    """The part of a convex polygon where ``direction @ p >= offset``, shape (m, 2) (m; m < 3 when empty).

    Parameters
    ----------
    vertices : array-like, shape (k, 2)
        Convex polygon (m), in order.
    direction : array-like, shape (2,)
        Unit vector.
    offset : float
        m.
    """
    V = np.asarray(vertices, float)
    s = V @ np.asarray(direction, float) - offset
    out = []
    for i in range(len(V)):  # Sutherland-Hodgman against one line
        j = (i + 1) % len(V)
        if s[i] >= 0.0:
            out.append(V[i])
        if (s[i] >= 0.0) != (s[j] >= 0.0):
            out.append(V[i] + (V[j] - V[i]) * (s[i] / (s[i] - s[j])))
    return np.array(out, float).reshape(-1, 2)


def disk_pieces(vertices, inner: float, outer: float) -> tuple:
    """Convex pieces of a polygon about a disk at the origin: ``(cover, inside)``, lists of vertex arrays (m, 2).

    ``cover``: disjoint pieces whose union holds every point of the polygon outside the circle of
    radius ``inner`` (the polygon beyond ``|x| >= s0``, where ``s0^2 + max|y|^2 = inner^2``; the whole
    polygon when ``s0 = 0``), so that each connected part of the polygon outside a disk containing that
    circle lies in one piece.  ``inside``: pieces outside the circle of radius ``outer`` (beyond its
    tangents along the x axis and through the points at height ``+-max|y|``), each in one such part
    when the disk lies inside that circle.

    Parameters
    ----------
    vertices : array-like, shape (k, 2)
        Convex polygon (m), counter-clockwise.
    inner, outer : float
        Radii (m).
    """
    V = np.asarray(vertices, float)
    ymax = float(np.abs(V[:, 1]).max())
    s0 = float(np.sqrt(max(inner**2 - ymax**2, 0.0)))
    cover = [V] if s0 == 0.0 else [clip_polygon(V, (sign, 0.0), s0) for sign in (1.0, -1.0)]
    a = float(np.sqrt(max(outer**2 - ymax**2, 0.0)))
    ends = [(1.0, 0.0), (a / outer, ymax / outer), (a / outer, -ymax / outer)]
    inside = [clip_polygon(V, d, outer) for x, y in ends for d in ((x, y), (-x, y))]
    convex = ([convex_vertices(p) if len(p) >= 3 else None for p in ps] for ps in (cover, inside))
    return tuple([p for p in ps if p is not None] for ps in convex)


def _overlap_along(A: Polygons, B: Polygons) -> np.ndarray:
    """Overlap of the projections of A and B on each of A's normals, shape (k_A, ...)."""
    p = (A.w.conj()[:, None] * B.z[None]).real  # (k_A, k_B, ...)
    return np.minimum(A.offset, p.max(axis=1)) - np.maximum(A.offset - A.breadth, p.min(axis=1))


def separating_depth(A: Polygons, B: Polygons) -> np.ndarray:
    """Smallest overlap (m) of the projections of two convex polygons over the edge normals of both.

    ``<= 0``: separated or touching; otherwise at least the narrowest width of their intersection.

    Parameters
    ----------
    A, B : Polygons
        In one frame; batch shapes broadcasting together.

    Returns
    -------
    ndarray, the broadcast batch shape
    """
    return np.minimum(_overlap_along(A, B).min(axis=0), _overlap_along(B, A).min(axis=0))


@lru_cache(maxsize=8)
def _line_pairs(K: int):
    return np.triu_indices(K, 1)


def intersection_width(A: Polygons, B: Polygons) -> np.ndarray:
    """Narrowest width (m) of the intersection of two convex polygons; 0 where they only touch or miss.

    Parameters
    ----------
    A, B : Polygons
        In one frame, batch shape (m,) both (their vertices unused).

    Returns
    -------
    ndarray, shape (m,)
    """
    w = np.concatenate([A.w, B.w])  # (K, m): every edge line of both
    b = np.concatenate([A.offset, B.offset])
    i, j = _line_pairs(len(w))
    det = (w[i].conj() * w[j]).imag  # (P, m): sine of the angle between lines i and j
    crossing = np.abs(det) > PARALLEL_SIN
    p = -1j * (b[i] * w[j] - b[j] * w[i]) / np.where(crossing, det, 1.0)  # where they cross
    proj = (w.conj()[:, None] * p[None]).real  # (K, P, m)
    vertex = crossing & np.all(proj <= b[:, None] + VERTEX_SLACK, axis=0)  # (P, m)
    hi = np.where(vertex[None], proj, -np.inf).max(axis=1)
    lo = np.where(vertex[None], proj, np.inf).min(axis=1)
    width = (hi - lo).min(axis=0)
    return np.where(vertex.any(axis=0), np.maximum(width, 0.0), 0.0)


@dataclass(frozen=True, slots=True, eq=False)
class PolygonPairs:
    """T pairs of convex polygons measured together, each polygon fixed in the frame of a body.

    Attributes
    ----------
    a, b : Polygons
        Batch shape (T,), each in its body's frame.
    a_column, b_column : Polygons
        The same, batch shape (T, 1), to broadcast over states.
    frame_a, frame_b : ndarray of int, shape (T,)
        The frame each polygon is fixed in (an index into the frames of :func:`pair_depths`).
    """

    a: Polygons
    b: Polygons
    a_column: Polygons
    b_column: Polygons
    frame_a: np.ndarray
    frame_b: np.ndarray


def polygon_pairs(items, k: int | None = None) -> PolygonPairs:
    """:class:`PolygonPairs` of ``items``, a sequence of ``(vertices a, frame a, vertices b, frame b, ...)``
    (vertices: counter-clockwise convex polygons, shape (m, 2), m; later fields ignored), padded to ``k``
    vertices (default the most)."""
    a, fa, b, fb = [list(c) for c in zip(*items)][:4]
    k = max(len(V) for V in a + b) if k is None else k
    a, b = make_polygons(a, k), make_polygons(b, k)
    return PolygonPairs(a, b, a[:, None], b[:, None], np.array(fa), np.array(fb))


def pair_depths(pairs: PolygonPairs, frames, threshold) -> np.ndarray:
    """Depth bound (m) of each pair at each of n states, shape (T, n): the narrowest width of the intersection
    (:func:`intersection_width`) where the separating-axis depth exceeds ``threshold``, else that depth.

    Parameters
    ----------
    pairs : PolygonPairs
    frames : (ndarray, ndarray)
        ``(turn, origin)``, complex, shapes (F, n): each frame's rotation ``exp(i angle)`` and origin (m).
    threshold : ndarray, shape (T,)
        m.
    """
    turn, origin = frames
    back = turn[pairs.frame_a].conj()  # (T, n): into a's frame, where a's polygons stay as stored
    b = pairs.b_column.moved(back * turn[pairs.frame_b], back * (origin[pairs.frame_b] - origin[pairs.frame_a]))
    depth = separating_depth(pairs.a_column, b)
    t, s = np.nonzero(depth > threshold[:, None])
    if len(t):
        near = Polygons(b.z[:, t, s], b.w[:, t, s], b.offset[:, t, s], pairs.b.breadth[:, t])
        depth[t, s] = intersection_width(pairs.a[t], near)
    return depth
