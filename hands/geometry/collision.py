"""Collisions between the bodies of a hand's configuration: every pair of palm, links and workpiece.

:func:`find_collisions` tests every pair of the hand's polygons
(:meth:`qsplan.hands.protocol.HandRecord.body_polygons`: the palm, one polygon per link,
the workpiece), for the paper's hand and any described chain hand alike.  Two
bodies collide when their intersection is deeper (its narrowest width) than a
tolerance: :data:`CONTACT_DEPTH_TOL` for the workpiece against a finger or the palm
(they touch by design, by tangency and along the bottom edge) and
:data:`LINK_DEPTH_TOL` for bodies that never touch (two links, a link and the palm).
A link on a revolute joint and the body it turns on (the palm, or the parent link) are
compared outside the joint housing, a disk of :data:`JOINT_HOUSING` link widths about
the joint axis, where the link's root turns inside its carrier by construction; a
prismatic joint's link never turns inside its carrier and has no housing.

Two implementations of that one definition.  :func:`shapely_collisions` is the reference,
one state at a time with shapely.  :func:`collision_decisions` is the fast path, batched
over states in numpy (:mod:`qsplan.hands.geometry.overlap`: every body is convex, so the
depth of a pair is the narrowest width of a convex intersection, computed exactly).  It
decides a pair only where the depth is :data:`DECISION_BAND` clear of the tolerance; for a
link against its carrier it bounds the depth of the housing-clipped region between two
convex regions (see :func:`collision_decisions`), and leaves what lies between to shapely.
:func:`find_collisions_batch` and :func:`find_collisions` use it, shapely measuring only
the pairs it did not clear.

The plan certifier (:mod:`qsplan.planner.certify.rows`) measures overlaps the
same way on purpose but with its own code: it must not trust this module.  Units SI (m, m^2).
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import combinations

import numpy as np

from qsplan.hands.geometry.collision_view import (CONTACT_DEPTH_TOL, DECISION_BAND, HOUSING_QUAD_SEGS, HOUSING_RTOL,
                                                  JOINT_HOUSING, LINK_DEPTH_TOL, body_frames, hand_structure)  # fmt: skip
from qsplan.hands.geometry.overlap import pair_depths

__all__ = ["CLEAR", "COLLIDES", "CONTACT_DEPTH_TOL", "DECISION_BAND", "HOUSING_QUAD_SEGS", "HOUSING_RTOL",
           "JOINT_HOUSING", "LINK_DEPTH_TOL", "UNDECIDED", "Collision", "body_label", "collision_decisions",
           "collision_pairs", "find_collisions", "find_collisions_batch", "overlap_depth",
           "shapely_collisions"]  # fmt: skip

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
    """A body of :meth:`qsplan.hands.protocol.HandRecord.body_polygons` in words: ``"left"`` -> ``"left finger"``
    (the paper's fingers), ``"left_distal"`` -> ``"left_distal link"`` (a chain hand's links)."""
    return _FIXED.get(name, f"{name} finger" if name in ("left", "right") else f"{name} link")


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


def collision_pairs(hand) -> tuple:
    """The pairs of bodies tested, in the order :func:`find_collisions` reports them: ``((a, b), ...)``
    with names of :meth:`qsplan.hands.protocol.HandRecord.body_polygons` (``"palm"``, ``"workpiece"``, the links)."""
    man = hand_structure(hand)[0]
    return tuple(combinations(["palm", "workpiece", *(j.name for j in man.joints if j.link_shape is not None)], 2))


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
    hand : TwoFingerHand, ChainHand, or their answerer (:class:`qsplan.hands.protocol.HandRecord`)
        Read for its ``manipulator`` and ``workpiece`` only.
    poses : array-like, shape (n, 3)
        Workpiece ``(x, y, theta)`` (m, m, rad).
    qs : array-like, shape (n, n_j)
        Joint positions (rad or m).

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

    n_j = hand_structure(hand)[0].n_joints
    if single:
        return check_finite_array(poses, "pose", (3,))[None], check_finite_array(qs, "q", (n_j,))[None]
    poses = check_finite_array(poses, "poses", (None, 3))
    return poses, check_finite_array(qs, "qs", (len(poses), n_j))


def _decisions(hand, poses, qs, exact=True) -> np.ndarray:
    """:func:`collision_decisions` of checked ``poses`` (n, 3) and ``qs`` (n, n_j); ``exact=False`` screens by the
    separating axis alone (an upper bound of the depth: it clears, it never finds a collision)."""
    man, _, _, fast = hand_structure(hand)
    if fast is None:
        return np.full((len(poses), len(collision_pairs(hand))), UNDECIDED, np.int8)
    frames = body_frames(man, poses, qs)
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
    hand : TwoFingerHand, ChainHand, or their answerer (:class:`qsplan.hands.protocol.HandRecord`)
        Read for its ``manipulator`` and ``workpiece`` only.
    poses : array-like, shape (n, 3)
        Workpiece ``(x, y, theta)`` (m, m, rad).
    qs : array-like, shape (n, n_j)
        Joint positions (rad or m).

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

    from qsplan.hands.geometry.workpiece import workpiece_world
    from qsplan.mechanics.model.manipulator import link_polygons, link_poses

    q = np.asarray(q, float)
    man, palm, housings, _ = hand_structure(hand)
    # the bodies of HandRecord.body_polygons, from the cached manipulator (building it is 2/3
    # of the cost)
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
    hand : TwoFingerHand, ChainHand, or their answerer (:class:`qsplan.hands.protocol.HandRecord`)
        Read for its ``manipulator`` and ``workpiece`` only.
    pose : array-like, shape (3,)
        Workpiece ``(x, y, theta)`` (m, m, rad).
    q : array-like, shape (n_j,)
        Joint positions (rad or m).
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
