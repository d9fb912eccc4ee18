"""Collisions between the bodies of a two-finger configuration: every pair of palm, links and workpiece.

:func:`find_collisions` tests every pair of the hand's polygons
(:func:`qsplan.hands.two_finger_scene.hand_polygons`: the palm, one polygon per link,
the workpiece), so a hand with more links is covered without a change here.  Two
bodies collide when their intersection is deeper (its narrowest width) than a
tolerance: :data:`CONTACT_DEPTH_TOL` for the workpiece against a finger or the palm
(they touch by design, by tangency and along the bottom edge) and
:data:`LINK_DEPTH_TOL` for bodies that never touch (two links, a link and the palm).
A link and the body it turns on (a finger and the palm) are compared outside the
joint housing, a disk of :data:`JOINT_HOUSING` link widths about the joint axis,
where the link's root turns inside its parent by construction.

Two implementations of that one definition.  :func:`shapely_collisions` is the reference,
one state at a time with shapely.  :func:`collision_decisions` is the fast path, batched
over states in numpy (:mod:`qsplan.planner.planning.overlap`: every body is convex, so the
depth of a pair is the narrowest width of a convex intersection, computed exactly).  It
decides a pair only where the depth is :data:`DECISION_BAND` clear of the tolerance; for a
link against its carrier it bounds the depth of the housing-clipped region between two
convex regions (see :func:`collision_decisions`), and leaves what lies between to shapely.
:func:`find_collisions_batch` and :func:`find_collisions` use it, shapely measuring only
the pairs it did not clear.

The plan certifier (:mod:`qsplan.planner.planning.certify_rows`) measures overlaps the
same way on purpose but with its own code: it must not trust this module.  Units SI (m, m^2).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from itertools import combinations

import numpy as np

from qsplan.mechanics.model.geometry import CONTACT_TOL
from qsplan.planner.planning.overlap import (PolygonPairs, convex_vertices, disk_pieces, pair_depths,
                                             polygon_pairs)  # fmt: skip

__all__ = ["CLEAR", "COLLIDES", "CONTACT_DEPTH_TOL", "DECISION_BAND", "HOUSING_QUAD_SEGS", "HOUSING_RTOL",
           "JOINT_HOUSING", "LINK_DEPTH_TOL", "UNDECIDED", "Collision", "body_label", "collision_decisions",
           "collision_pairs", "find_collisions", "find_collisions_batch", "overlap_depth",
           "shapely_collisions"]  # fmt: skip

#: Depth (m) to which bodies that touch by design (a finger on the workpiece, the workpiece on
#: the palm) may overlap: the contact finder's own tolerance (:data:`qsplan.mechanics.model.geometry.CONTACT_TOL`,
#: 1 micron), far above the ~1e-15 m by which a tangency computes as overlapping and far below
#: anything a planar hand could tolerate.
CONTACT_DEPTH_TOL = CONTACT_TOL

#: Depth (m) to which bodies that never touch (finger and finger, a finger and the palm outside
#: its joint housing) may overlap: rounding only, so the same micron.  Not smaller: two fingers
#: that graze each other at a planned state compute as overlapping by about the rounding of the
#: tangency that places them; not larger: the planner must accept nothing the plan certifier
#: (1 micron of depth) rejects.
LINK_DEPTH_TOL = 1e-6

#: Radius of a joint's housing in link widths: a link's root turns inside the body that carries
#: it (a finger's rectangle is centred on its joint axis at the palm's surface), so the two are
#: compared only outside this disk.  hypot(1, 1/2): the disk through the corners of one link
#: width of root.
JOINT_HOUSING = float(np.hypot(1.0, 0.5))

#: Segments per quarter circle of the housing disk as :func:`shapely_collisions` draws it
#: (``Point.buffer(r, HOUSING_QUAD_SEGS)``, vertices on the circle): the fast path bounds that
#: polygon between its inscribed circle, radius ``r cos(pi / (4 HOUSING_QUAD_SEGS))``, and the circle.
HOUSING_QUAD_SEGS = 64

#: Relative allowance (of the housing radius) for the rounding of the housing polygon's vertices
#: (~1e-16 relative): the fast path's inner radius is taken this much smaller, its outer this much
#: larger, so its bounds hold for the polygon shapely computes.  1e-9 of a ~1 cm radius is 1e-11 m.
HOUSING_RTOL = 1e-9

#: Half-width (m) of the band about a tolerance within which the fast path leaves the decision to
#: shapely: both compute a depth from the same coordinates with rounding of ~1e-16 m per metre
#: (GEOS's overlay and this module's line crossings; the two differ by at most 2e-15 m on the
#: tests' random pairs), so a depth 1 nm clear of the tolerance, a thousandth of it, is on the same
#: side for both.  States inside the band are rare (a depth within a nanometre of a micron) and cost
#: one shapely measurement of the pair.
DECISION_BAND = 1e-9

#: A pair's decision in :func:`collision_decisions`: no collision; a collision; left to shapely.
CLEAR, COLLIDES, UNDECIDED = 0, 1, 2

_FIXED = {"palm": "palm", "workpiece": "workpiece"}


@dataclass(frozen=True, slots=True)
class Collision:
    """Two bodies overlapping beyond their tolerance.

    Attributes
    ----------
    bodies : (str, str)
        Their names in words ("left finger", "palm", ...).
    area : float
        Area of the overlap (m^2).
    depth : float
        Its narrowest width (m).
    """

    bodies: tuple
    area: float
    depth: float

    @property
    def message(self) -> str:
        a, b = self.bodies
        return f"{a} and {b} overlap by {self.area * 1e6:.3g} mm^2 ({self.depth * 1e3:.3g} mm deep)"


def body_label(name: str) -> str:
    """A body of :func:`qsplan.hands.two_finger_scene.hand_polygons` in words: ``"left"`` -> ``"left finger"``."""
    return _FIXED.get(name, f"{name} finger")


def overlap_depth(region) -> float:
    """Narrowest width (m) of an overlap region (a shapely geometry): for each part, the smallest
    extent of its convex hull across one of the hull's edges (rotating calipers); the largest over parts."""
    best = 0.0
    for part in getattr(region, "geoms", (region,)):
        if part.is_empty or part.area <= 0.0:
            continue
        hull = np.asarray(part.convex_hull.exterior.coords)[:-1]
        edges = np.roll(hull, -1, axis=0) - hull
        length = np.hypot(edges[:, 0], edges[:, 1])
        keep = length > 0
        normals = np.stack([-edges[keep, 1], edges[keep, 0]], axis=1) / length[keep, None]
        widths = hull @ normals.T
        best = max(best, float((widths.max(axis=0) - widths.min(axis=0)).min()))
    return best


@dataclass(frozen=True, slots=True, eq=False)
class _Fast:
    """The fast path's view of a hand: stage 1 (every pair), stage 2 (the housings' lower bounds)."""

    stage1: PolygonPairs
    clear_below: np.ndarray  # (T,) m: a stage-1 test whose separating-axis depth is no more is clear
    starts: np.ndarray  # (n_pairs,) first stage-1 test of each pair
    tolerance: np.ndarray  # (n_pairs,) m
    collides_above: np.ndarray  # (n_pairs,) m: a stage-1 depth beyond this is a collision (inf: housed pairs)
    stage2: dict  # pair index -> PolygonPairs


def _fast_view(man, palm, workpiece, housings):
    """The :class:`_Fast` view of a hand, or None when a body is not convex (shapely then decides everything).

    A link and its carrier are measured as stage 1 by the pieces covering the link outside the
    housing polygon's inscribed circle, and as stage 2 by the pieces outside its circumscribed one
    (:func:`qsplan.planner.planning.overlap.disk_pieces`), in the link's frame (axis at the origin).
    """
    bodies = {"palm": (convex_vertices(palm), 0), "workpiece": (convex_vertices(workpiece), 1)}
    bodies.update((j.name, (convex_vertices(j.link_shape), 2 + i)) for i, j in enumerate(man.joints)
                  if j.link_shape is not None)
    if any(V is None for V, _ in bodies.values()):
        return None
    pairs = list(combinations(bodies, 2))
    stage1, stage2, housed = [], {}, []
    for p, (a, b) in enumerate(pairs):
        (A, fa), (B, fb) = bodies[a], bodies[b]
        joint = housings.get((a, b)) or housings.get((b, a))
        housed.append(joint is not None)
        if joint is None:
            stage1.append((A, fa, B, fb, p))
            continue
        if (a, b) not in housings:  # the link first: its pieces live in its frame
            (A, fa), (B, fb) = (B, fb), (A, fa)
        r = joint[1]
        cover, inside = disk_pieces(A, r * np.cos(np.pi / (4 * HOUSING_QUAD_SEGS)) * (1.0 - HOUSING_RTOL),
                                    r * (1.0 + HOUSING_RTOL))  # fmt: skip
        stage1 += [(piece, fa, B, fb, p) for piece in cover or [A]]  # no piece: the link never leaves it
        stage2[p] = [(piece, fa, B, fb, p) for piece in inside]
    k = max(len(t[i]) for t in stage1 + sum(stage2.values(), []) for i in (0, 2))
    tolerance = [CONTACT_DEPTH_TOL if "workpiece" in pair else LINK_DEPTH_TOL for pair in pairs]
    starts = np.searchsorted([t[4] for t in stage1], np.arange(len(pairs)))
    clear_below = np.array(tolerance)[[t[4] for t in stage1]] - DECISION_BAND
    collides_above = np.where(housed, np.inf, np.array(tolerance) + DECISION_BAND)
    return _Fast(polygon_pairs(stage1, k), clear_below, starts, np.array(tolerance), collides_above,
                 {p: polygon_pairs(items, k) for p, items in stage2.items() if items})  # fmt: skip


@lru_cache(maxsize=16)
def _structure(hand):
    """``(manipulator, palm polygon, {(link, carrier): (joint, housing radius (m), housing disk or None)},
    fast view or None)``.

    Cached (hands are immutable). The disk is built here when the joint's axis cannot move (a
    revolute joint on the palm), else per state from the joint's pose.
    """
    from shapely.geometry import Point

    from qsplan.hands.two_finger_scene import hand_manipulator
    from qsplan.mechanics.model.manipulator import base_polygon, link_poses

    man = hand_manipulator(hand)
    fixed_axes = link_poses(man, np.zeros(len(man.joints)))[:, :2]
    housings = {}
    for j, joint in enumerate(man.joints):
        if joint.link_shape is None:
            continue
        carrier = "palm" if joint.parent < 0 else man.joints[joint.parent].name
        y = np.asarray(joint.link_shape, float)[:, 1]
        r = JOINT_HOUSING * float(y.max() - y.min())
        fixed = joint.parent < 0 and joint.kind == "revolute"
        disk = Point(fixed_axes[j]).buffer(r, HOUSING_QUAD_SEGS) if fixed else None
        housings[(joint.name, carrier)] = (j, r, disk)
    palm = base_polygon(man)
    fast = None if palm is None else _fast_view(man, man.base_shape, hand.workpiece, housings)
    return man, palm, housings, fast


def collision_pairs(hand) -> tuple:
    """The pairs of bodies tested, in the order :func:`find_collisions` reports them: ``((a, b), ...)``
    with names of :func:`qsplan.hands.two_finger_scene.hand_polygons` (``"palm"``, ``"workpiece"``, the links)."""
    man = _structure(hand)[0]
    return tuple(combinations(["palm", "workpiece", *(j.name for j in man.joints if j.link_shape is not None)], 2))


def _frames(man, poses, qs) -> tuple:
    """Every body's frame at each state: ``(turn, origin)``, complex, shapes (F, n): the rotation
    ``exp(i angle)`` and the origin ``x + iy`` (m) of the world (the palm), the workpiece and each link;
    the links' :func:`qsplan.mechanics.model.manipulator.link_poses`, batched over states."""
    angle = np.zeros((2 + man.n_joints, len(poses)))
    origin = np.zeros((2 + man.n_joints, len(poses)), complex)
    angle[1], origin[1] = poses[:, 2], poses[:, 0] + 1j * poses[:, 1]
    for i, j in enumerate(man.joints):  # parents first, each joint vectorised over the states
        k, ox, oy, oa = 2 + i, *j.origin
        if j.parent < 0:
            angle[k], origin[k] = oa, ox + 1j * oy
        else:
            p = 2 + j.parent
            angle[k], origin[k] = angle[p] + oa, origin[p] + np.exp(1j * angle[p]) * (ox + 1j * oy)
        if j.kind == "revolute":
            angle[k] += qs[:, i]
        else:
            origin[k] += np.exp(1j * angle[k]) * qs[:, i]
    return np.exp(1j * angle), origin


def collision_decisions(hand, poses, qs) -> np.ndarray:
    """Each pair of bodies judged at each state by the fast path: :data:`CLEAR`, :data:`COLLIDES` or :data:`UNDECIDED`.

    A pair is decided where its depth is :data:`DECISION_BAND` clear of its tolerance.  A link
    and its carrier (housing clipped) are judged by two convex regions: the depth of the link's
    part beyond ``|x| = s0`` in its frame (``s0`` such that nearer points lie inside the housing
    polygon's inscribed circle) against the carrier bounds the reference's depth from above; the
    link's part beyond a tangent of the housing circle against the carrier bounds it from below
    (a convex part of the clipped region lies in one of its parts).  Between the bounds, undecided:
    a finger dipping into the palm with its depth near the tolerance just outside the housing.

    Parameters
    ----------
    hand : qsplan.hands.two_finger.TwoFingerHand
    poses : array-like, shape (n, 3)
        Workpiece ``(x, y, theta)`` (m, m, rad).
    qs : array-like, shape (n, n_j)
        Joint angles (rad).

    Returns
    -------
    ndarray of int8, shape (n, n_pairs)
        Columns in the order of :func:`collision_pairs`; all :data:`UNDECIDED` where a body is not convex.
    """
    return _decisions(hand, *_check_states(hand, poses, qs))


def _check_states(hand, poses, qs, single=False) -> tuple:
    """``poses`` (n, 3) and ``qs`` (n, n_j) as float arrays (one state: ``pose`` (3,) and ``q`` (n_j,));
    :class:`qsplan.mechanics.SceneError` naming the field otherwise."""
    from qsplan.mechanics.model.scene import check_finite_array

    n_j = _structure(hand)[0].n_joints
    if single:
        return check_finite_array(poses, "pose", (3,))[None], check_finite_array(qs, "q", (n_j,))[None]
    poses = check_finite_array(poses, "poses", (None, 3))
    return poses, check_finite_array(qs, "qs", (len(poses), n_j))


def _decisions(hand, poses, qs, exact=True) -> np.ndarray:
    """:func:`collision_decisions` of checked ``poses`` (n, 3) and ``qs`` (n, n_j); ``exact=False`` screens by the
    separating axis alone (an upper bound of the depth: it clears, it never finds a collision)."""
    man, _, _, fast = _structure(hand)
    if fast is None:
        return np.full((len(poses), len(collision_pairs(hand))), UNDECIDED, np.int8)
    frames = _frames(man, poses, qs)
    upto = fast.clear_below if exact else np.full_like(fast.clear_below, np.inf)
    depth = np.maximum.reduceat(pair_depths(fast.stage1, frames, upto), fast.starts, axis=0)  # (pairs, n)
    near = depth > fast.clear_below[fast.starts, None]
    if not exact:
        return np.where(near, UNDECIDED, CLEAR).T.astype(np.int8)
    out = np.where(depth > fast.collides_above[:, None], COLLIDES, np.where(near, UNDECIDED, CLEAR)).T
    out = out.astype(np.int8)
    for p, tests in fast.stage2.items():  # the housings' lower bounds, where the upper one did not clear
        rows = np.nonzero(near[p])[0]
        if len(rows):
            bound = fast.tolerance[p] + DECISION_BAND
            lower = pair_depths(tests, (frames[0][:, rows], frames[1][:, rows]), np.full(len(tests.frame_a), bound))
            out[rows[lower.max(axis=0) > bound], p] = COLLIDES
    return out


def find_collisions_batch(hand, poses, qs) -> np.ndarray:
    """Whether any two bodies collide at each state (:func:`find_collisions`' verdict, batched over states).

    Parameters
    ----------
    hand : qsplan.hands.two_finger.TwoFingerHand
    poses : array-like, shape (n, 3)
        Workpiece ``(x, y, theta)`` (m, m, rad).
    qs : array-like, shape (n, n_j)
        Joint angles (rad).

    Returns
    -------
    ndarray of bool, shape (n,)
        The pairs :func:`collision_decisions` leaves undecided are measured by :func:`shapely_collisions`.
        The first collision of state ``i``, with its message: ``find_collisions(hand, poses[i], qs[i], first=True)``.
    """
    poses, qs = _check_states(hand, poses, qs)
    decisions = _decisions(hand, poses, qs)
    hit = np.any(decisions == COLLIDES, axis=1)
    pairs = collision_pairs(hand)
    for i in np.nonzero(~hit & np.any(decisions == UNDECIDED, axis=1))[0]:  # rare: depths near a tolerance
        near = {pair for pair, d in zip(pairs, decisions[i]) if d == UNDECIDED}
        hit[i] = bool(shapely_collisions(hand, poses[i], qs[i], True, near))
    return hit


def shapely_collisions(hand, pose, q, first: bool = False, pairs=None) -> list:
    """Every pair of the hand's bodies overlapping beyond its tolerance, measured with shapely: the reference.

    Parameters are those of :func:`find_collisions`, and

    pairs : set of (str, str), optional
        Measure only these pairs (of :func:`collision_pairs`); default all.
    """
    from shapely.geometry import Point, Polygon

    from qsplan.hands.two_finger import workpiece_world
    from qsplan.mechanics.model.manipulator import link_polygons, link_poses

    q = np.asarray(q, float)
    man, palm, housings, _ = _structure(hand)
    # the bodies of qsplan.hands.two_finger_scene.hand_polygons, from the cached manipulator (building it is 2/3 of the cost)
    polys = {"palm": palm if palm is not None else Polygon(), "workpiece": Polygon(workpiece_world(hand, pose))}
    polys.update((j.name, p) for j, p in zip(man.joints, link_polygons(man, q)) if p is not None)
    axes = None
    out = []
    for a, b in combinations(polys, 2):
        if pairs is not None and (a, b) not in pairs:
            continue
        A, B = polys[a], polys[b]
        if not A.intersects(B):
            continue
        region = A.intersection(B)
        joint = housings.get((a, b)) or housings.get((b, a))
        if joint is not None:
            j, r, disk = joint
            if disk is None:
                if axes is None:
                    axes = link_poses(man, q)[:, :2]
                disk = Point(axes[j]).buffer(r, HOUSING_QUAD_SEGS)
            region = region.difference(disk)
        if region.is_empty or region.area <= 0.0:
            continue
        depth = overlap_depth(region)
        if depth > (CONTACT_DEPTH_TOL if "workpiece" in (a, b) else LINK_DEPTH_TOL):
            out.append(Collision((body_label(a), body_label(b)), float(region.area), depth))
            if first:
                break
    return out


def find_collisions(hand, pose, q, first: bool = False) -> list:
    """Every pair of the hand's bodies overlapping beyond its tolerance at workpiece ``pose`` and joints ``q``.

    The fast path's separating-axis screen (:func:`collision_decisions`) clears the pairs clearly
    apart; shapely (:func:`shapely_collisions`) measures the others, so the result is the reference's.

    Parameters
    ----------
    hand : qsplan.hands.two_finger.TwoFingerHand
    pose : array-like, shape (3,)
        Workpiece ``(x, y, theta)`` (m, m, rad).
    q : array-like, shape (n_j,)
        Joint angles (rad).
    first : bool
        Stop at the first collision found.

    Returns
    -------
    list of Collision
        Empty when nothing collides.
    """
    poses, qs = _check_states(hand, pose, q, single=True)
    # shapely measures every pair not cleared, so the exact widths would only repeat its work
    near = {pair for pair, d in zip(collision_pairs(hand), _decisions(hand, poses, qs, exact=False)[0]) if d != CLEAR}
    return shapely_collisions(hand, poses[0], qs[0], first, near) if near else []
