"""Contacts from geometry: where a polygonal workpiece touches polygonal bodies (Section 3, eq. 1).

The paper takes the contact points ``r_i`` and inward normals ``n_i`` as given
(assumption 1: positions and geometries of all bodies are known).  Here they
are found from polygons: a workpiece vertex on a body edge, a body vertex on a
workpiece edge, or two facing edges that overlap.  Where the normal is not
defined (a convex corner touching a convex corner) we raise rather than guess.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import shapely
from shapely.geometry import Polygon
from shapely.ops import polylabel

from qsplan.mechanics.model.contact import cross2
from qsplan.mechanics.errors import SceneError
from qsplan.mechanics.model.scene import check_finite_array

__all__ = ["CONTACT_TOL", "FoundContact", "find_contacts", "check_polygon"]

#: Distance (m) below which two features count as touching, and overlap depth
#: (m) tolerated as touching.  Scene coordinates are decimal numbers and link
#: poses come from trigonometric forward kinematics, so an exact touch computes
#: as a gap or overlap of ~1e-15 m per metre of scene size; a micron is far above
#: that and far below any gap a planar hand should distinguish from contact.
CONTACT_TOL = 1e-6

#: Two contacts of one body closer than the contact tolerance whose unit normals
#: differ by less than this (rad) are one contact: they only arise from edges
#: shorter than the tolerance, and keeping both would give W two equal columns.
_NORMAL_MERGE_TOL = 1e-6

#: Relative size of ``|d_prev x d_next|`` below which a polygon vertex is straight
#: (collinear with its neighbours) and dropped: it is no corner, and keeping it
#: would make a touch there look like a vertex-on-vertex contact.
_COLLINEAR_TOL = 1e-12


@dataclass(frozen=True, slots=True, eq=False)
class FoundContact:
    """One contact between the workpiece and a body.

    Attributes
    ----------
    body : int
        Link index of the touching body, -1 for the fixed base (palm).
    point : ndarray, shape (2,)
        Contact point ``r_i``, world frame (m).
    normal : ndarray, shape (2,)
        Unit normal ``n_i`` pointing into the workpiece (eq. 1).
    kind : str
        ``"vertex-edge"`` (workpiece vertex on a body edge), ``"edge-vertex"``
        (body vertex on a workpiece edge) or ``"edge-edge"`` (an end of the
        overlap of two facing edges; normal = the workpiece edge's inward normal).
    """

    body: int
    point: np.ndarray
    normal: np.ndarray
    kind: str


def check_polygon(value, field: str) -> np.ndarray:
    """Validate a simple polygon given as vertices; raise :class:`SceneError` naming ``field``.

    Parameters
    ----------
    value : array-like, shape (k, 2)
        Vertices (m), either orientation; a repeated closing vertex, and any vertex within 1e-12 m of
        its predecessor, is dropped.

    Returns
    -------
    ndarray, shape (k, 2)
    """
    v = check_finite_array(value, field, (None, 2))
    if len(v) > 1 and np.array_equal(v[0], v[-1]):
        v = v[:-1]
    # a vertex repeating its predecessor (to 1e-12 m) makes a zero-length edge, whose direction is 0/0
    keep = np.linalg.norm(v - np.roll(v, 1, axis=0), axis=1) > 1e-12 if len(v) > 1 else np.ones(len(v), bool)
    v = v[keep] if keep.any() else v[:1]
    if len(v) < 3:
        raise SceneError(f"{field}: expected at least 3 vertices [x, y]; got {len(v)}")
    if np.linalg.matrix_rank(v - v[0]) < 2:
        raise SceneError(f"{field}: expected a polygon with positive area; got collinear vertices {v.tolist()}")
    poly = Polygon(v)
    if not poly.is_valid:
        raise SceneError(f"{field}: expected a simple polygon; got an invalid one ({shapely.is_valid_reason(poly)})")
    return v


def _ring(poly, field: str):
    """Counter-clockwise vertices (k, 2) of a valid hole-free polygon, first vertex kept."""
    if not isinstance(poly, Polygon) or poly.is_empty:
        raise SceneError(f"{field}: expected a non-empty shapely Polygon; got {type(poly).__name__}")
    if len(poly.interiors):
        raise SceneError(f"{field}: polygons with holes are not supported; got {len(poly.interiors)} hole(s)")
    if not poly.is_valid:
        raise SceneError(f"{field}: expected a valid polygon; got an invalid one ({shapely.is_valid_reason(poly)})")
    v = np.asarray(poly.exterior.coords, dtype=float)[:-1, :2]
    if np.sum(cross2(v, np.roll(v, -1, axis=0))) < 0:
        v = np.concatenate([v[:1], v[:0:-1]])
    return v


def _corners(v: np.ndarray) -> np.ndarray:
    """Drop repeated and straight (collinear) vertices of a CCW ring."""
    changed = True
    while changed and len(v) > 3:
        d_prev = v - np.roll(v, 1, axis=0)
        d_next = np.roll(v, -1, axis=0) - v
        lp, ln = np.linalg.norm(d_prev, axis=1), np.linalg.norm(d_next, axis=1)
        straight = (np.abs(cross2(d_prev, d_next)) <= _COLLINEAR_TOL * lp * ln) & (np.sum(d_prev * d_next, axis=1) >= 0)
        bad = np.flatnonzero(straight | (ln == 0))
        changed = bad.size > 0
        if changed:
            v = np.delete(v, bad[0], axis=0)
    return v


def _segment_distance(p, a, b):
    """Distances (m, k) and parameters in [0, 1] from points ``p`` (m, 2) to segments ``a -> b`` (k, 2)."""
    d = b - a
    rel = p[:, None, :] - a[None, :, :]
    s = np.clip(np.sum(rel * d[None], axis=2) / np.sum(d * d, axis=1)[None], 0.0, 1.0)
    return np.linalg.norm(rel - s[..., None] * d[None], axis=2), s


def _edge_normals(v):
    """Outward unit normals (k, 2) of the edges ``v[i] -> v[i+1]`` of a CCW ring."""
    d = np.roll(v, -1, axis=0) - v
    return np.stack([d[:, 1], -d[:, 0]], axis=1) / np.linalg.norm(d, axis=1)[:, None]


def _convex(v):
    return cross2(v - np.roll(v, 1, axis=0), np.roll(v, -1, axis=0) - v) > 0


def _facing_overlap(f0, f1, e0, e1, tol) -> bool:
    """Whether workpiece edge ``f0 -> f1`` and body edge ``e0 -> e1`` face each other and overlap by more than ``tol``."""
    length = np.linalg.norm(f1 - f0)
    u = (f1 - f0) / length
    if u @ (e1 - e0) >= 0:  # same direction: not facing (CCW rings face with opposite directions)
        return False
    se = np.array([(e0 - f0) @ u, (e1 - f0) @ u])
    lo, hi = max(0.0, se.min()), min(length, se.max())
    if hi - lo <= tol:
        return False
    ends = f0[None] + np.array([lo, hi])[:, None] * u[None]
    dist, _ = _segment_distance(ends, e0[None], e1[None])
    return bool(np.all(dist <= tol))


def _label(body: int, body_names) -> str:
    base = "palm" if body < 0 else f"link {body}"
    name = (body_names or {}).get(body)
    return f"{base} ({name!r})" if name is not None and name != base else base


def _penetration_depth(wp_poly, body_poly, wv, bv) -> float:
    """How deep (m) the body and workpiece overlap: deepest vertex inside the other, or overlap inradius."""
    inter = wp_poly.intersection(body_poly)
    if inter.area == 0.0:
        return 0.0
    depth = 0.0
    for pts, other, ov in ((wv, body_poly, bv), (bv, wp_poly, wv)):
        inside = shapely.contains_xy(other, pts[:, 0], pts[:, 1])
        if inside.any():
            dist, _ = _segment_distance(pts[inside], ov, np.roll(ov, -1, axis=0))
            depth = max(depth, float(dist.min(axis=1).max()))
    # Two polygons can cross with no vertex inside the other (a plus sign): use the overlap's inradius.
    for part in getattr(inter, "geoms", [inter]):
        if isinstance(part, Polygon) and part.area > 0.0:
            centre = polylabel(part, tolerance=max(1e-12, 1e-3 * np.sqrt(part.area)))
            depth = max(depth, float(part.exterior.distance(centre)))
    return depth


def _body_contacts(wv, bv, tol, label):
    """Raw (point, normal, kind) contacts between a CCW workpiece ring ``wv`` and a CCW body ring ``bv``."""
    nw, nb = len(wv), len(bv)
    w_next, b_next = np.roll(wv, -1, axis=0), np.roll(bv, -1, axis=0)
    w_in = -_edge_normals(wv)  # inward normals of workpiece edges
    b_out = _edge_normals(bv)  # outward normals of body edges = into the workpiece
    w_convex, b_convex = _convex(wv), _convex(bv)
    d_wv_be, _ = _segment_distance(wv, bv, b_next)  # (nw, nb)
    d_bv_we, _ = _segment_distance(bv, wv, w_next)  # (nb, nw)
    d_vv = np.linalg.norm(wv[:, None] - bv[None], axis=2)

    def facing(fi, ek):
        return _facing_overlap(wv[fi], w_next[fi], bv[ek], b_next[ek], tol)

    out = []
    for i in range(nw):
        w_edges = ((i - 1) % nw, i)
        near = np.flatnonzero(d_vv[i] <= tol)
        if near.size == 0:
            for ek in np.flatnonzero(d_wv_be[i] <= tol):
                f = next((fi for fi in w_edges if facing(fi, ek)), None)
                out.append((wv[i], b_out[ek], "vertex-edge") if f is None else (wv[i], w_in[f], "edge-edge"))
            continue
        k = int(near[np.argmin(d_vv[i, near])])
        b_edges = ((k - 1) % nb, k)
        if not b_convex[k]:  # workpiece corner in a body notch: both body edges constrain it
            for ek in b_edges:
                f = next((fi for fi in w_edges if facing(fi, ek)), None)
                out.append((wv[i], b_out[ek], "vertex-edge") if f is None else (wv[i], w_in[f], "edge-edge"))
        elif not w_convex[i]:  # body corner in a workpiece notch: both workpiece edges constrain it
            for fi in w_edges:
                kind = "edge-edge" if any(facing(fi, ek) for ek in b_edges) else "edge-vertex"
                out.append((bv[k], w_in[fi], kind))
        else:
            pairs = [(fi, ek) for fi in w_edges for ek in b_edges if facing(fi, ek)]
            if not pairs:
                raise SceneError(
                    f"contact normal undefined: vertex of {label} at ({bv[k][0]:.6g}, {bv[k][1]:.6g}) "
                    f"touches workpiece vertex at ({wv[i][0]:.6g}, {wv[i][1]:.6g}); move one body so that a "
                    "vertex meets an edge"
                )
            out.extend((wv[i], w_in[fi], "edge-edge") for fi, _ in pairs)
    for k in range(nb):
        if np.any(d_vv[:, k] <= tol):
            continue  # handled as vertex-on-vertex above
        b_edges = ((k - 1) % nb, k)
        for fi in np.flatnonzero(d_bv_we[k] <= tol):
            kind = "edge-edge" if any(facing(fi, ek) for ek in b_edges) else "edge-vertex"
            out.append((bv[k], w_in[fi], kind))
    return out


def _boundary_position(points, ring):
    """Arc length (m) along the CCW ``ring`` (k, 2) from its first vertex to the nearest point of each of ``points``."""
    nxt = np.roll(ring, -1, axis=0)
    lengths = np.linalg.norm(nxt - ring, axis=1)
    start = np.concatenate([[0.0], np.cumsum(lengths)[:-1]])
    dist, s = _segment_distance(points, ring, nxt)
    edge = np.argmin(dist, axis=1)
    pos = start[edge] + s[np.arange(len(points)), edge] * lengths[edge]
    return np.where(pos >= lengths.sum() - 1e-12 * lengths.sum(), 0.0, pos)


def find_contacts(workpiece, bodies, tol: float = CONTACT_TOL, body_names=None) -> list[FoundContact]:
    """Contacts between a workpiece polygon and body polygons (``r_i``, ``n_i`` of eq. 1).

    Rules: a workpiece vertex within ``tol`` of a body edge gives a contact at
    the vertex with the edge's outward normal; a body vertex within ``tol`` of a
    workpiece edge gives a contact at the body vertex with the edge's inward
    normal; two facing edges overlapping by more than ``tol`` give contacts at
    the two ends of the overlap (``kind="edge-edge"``, normal = the workpiece
    edge's inward normal).  A convex corner in a notch of the other body gives
    one contact per notch edge.  Each physical point and normal appears once.

    Parameters
    ----------
    workpiece : shapely.Polygon
        World frame (m); no holes.
    bodies : sequence of (int, shapely.Polygon)
        Body index (link index, -1 for the base/palm) and its world-frame polygon.
    tol : float
        Contact tolerance (m), :data:`CONTACT_TOL` by default: features closer
        than this touch, overlaps shallower than this are accepted as touching.
    body_names : dict of int to str, optional
        Names used in error messages.

    Returns
    -------
    list of FoundContact
        Ordered by body index, then along the workpiece boundary (counter-
        clockwise from its first vertex), then by normal angle.

    Raises
    ------
    SceneError
        If a body penetrates the workpiece deeper than ``tol`` (naming the body
        and the depth), if a convex corner touches a convex corner with no facing
        edges (the normal is undefined), or on malformed input.
    """
    if isinstance(tol, bool) or not isinstance(tol, (int, float)) or not np.isfinite(tol) or tol <= 0:
        raise SceneError(f"tol: expected a positive finite contact tolerance (m); got {tol!r}")
    tol = float(tol)
    ring = _ring(workpiece, "workpiece")
    wv = _corners(ring)
    found = []
    for j, item in enumerate(bodies):
        try:
            body, poly = item
        except (TypeError, ValueError):
            raise SceneError(f"bodies[{j}]: expected a (body_index, Polygon) pair; got {item!r}") from None
        if isinstance(body, (bool, np.bool_)) or not isinstance(body, (int, np.integer)) or body < -1:
            raise SceneError(f"bodies[{j}]: expected a body index >= -1; got {body!r}")
        label = _label(int(body), body_names)
        bv = _corners(_ring(poly, f"bodies[{j}] ({label})"))
        depth = _penetration_depth(workpiece, poly, wv, bv)
        if depth > tol:
            raise SceneError(
                f"{label}: penetrates the workpiece by {depth:.6g} m (more than the contact tolerance {tol:g} m)"
            )
        for point, normal, kind in _body_contacts(wv, bv, tol, label):
            if not any(
                c.body == body
                and np.linalg.norm(c.point - point) <= tol
                and np.linalg.norm(c.normal - normal) <= _NORMAL_MERGE_TOL
                for c in found
            ):
                found.append(FoundContact(int(body), _frozen(point), _frozen(normal / np.linalg.norm(normal)), kind))
    if not found:
        return []
    pos = _boundary_position(np.array([c.point for c in found]), ring)
    angle = np.array([np.arctan2(c.normal[1], c.normal[0]) for c in found])
    order = sorted(range(len(found)), key=lambda i: (found[i].body, pos[i], angle[i]))
    return [found[i] for i in order]


def _frozen(a) -> np.ndarray:
    a = np.array(a, dtype=float, copy=True)
    a.setflags(write=False)
    return a
