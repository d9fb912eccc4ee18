"""A hand as the collision test sees it: its bodies, the joint housings and the fast path's view (numpy).

:func:`hand_structure` gives, once per hand (cached), the manipulator
(``hand.manipulator``: any hand record, its answerer or a described hand), the palm, the
housings and the :class:`FastView` that :mod:`qsplan.hands.geometry.collision` batches over states; :func:`body_frames`
places every body at each state.  The tolerances the collision test applies are defined here, where the fast view bakes
them in; :mod:`qsplan.hands.geometry.collision` re-exports them.  Units SI (m, rad).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from itertools import combinations

import numpy as np

from qsplan.mechanics.model.geometry import CONTACT_TOL
from qsplan.hands.geometry.overlap import PolygonPairs, convex_vertices, disk_pieces, polygon_pairs

__all__ = ["CONTACT_DEPTH_TOL", "DECISION_BAND", "HOUSING_QUAD_SEGS", "HOUSING_RTOL", "JOINT_HOUSING",
           "LINK_DEPTH_TOL", "FastView", "body_frames", "fast_view", "hand_structure"]

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

#: Segments per quarter circle of the housing disk as :func:`qsplan.hands.geometry.collision.shapely_collisions` draws
#: it (``Point.buffer(r, HOUSING_QUAD_SEGS)``, vertices on the circle): the fast path bounds that
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


@dataclass(frozen=True, slots=True, eq=False)
class FastView:
    """The fast path's view of a hand: stage 1 (every pair), stage 2 (the housings' lower bounds)."""

    stage1: PolygonPairs
    clear_below: np.ndarray  # (T,) m: a stage-1 test whose separating-axis depth is no more is clear
    starts: np.ndarray  # (n_pairs,) first stage-1 test of each pair
    tolerance: np.ndarray  # (n_pairs,) m
    collides_above: np.ndarray  # (n_pairs,) m: a stage-1 depth beyond this is a collision (inf: housed pairs)
    stage2: dict  # pair index -> PolygonPairs


def fast_view(man, palm, workpiece, housings):
    """The :class:`FastView` of a hand, or None when a body is not convex (shapely then decides everything).

    A link and its carrier are measured as stage 1 by the pieces covering the link outside the
    housing polygon's inscribed circle, and as stage 2 by the pieces outside its circumscribed one
    (:func:`qsplan.hands.geometry.overlap.disk_pieces`), in the link's frame (axis at the origin).
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
    return FastView(polygon_pairs(stage1, k), clear_below, starts, np.array(tolerance), collides_above,
                    {p: polygon_pairs(items, k) for p, items in stage2.items() if items})  # fmt: skip


@lru_cache(maxsize=16)
def hand_structure(hand):
    """``(manipulator, palm polygon, {(link, carrier): (joint, housing radius (m), housing disk or None)},
    fast view or None)``.

    Cached (hands are immutable).  Revolute joints only (a prismatic link never turns inside its carrier).  The
    disk is built here when the joint's axis cannot move (on the palm), else per state from the joint's pose.
    """
    from shapely.geometry import Point

    from qsplan.mechanics.model.manipulator import base_polygon, link_poses

    man = hand.manipulator
    fixed_axes = link_poses(man, np.zeros(len(man.joints)))[:, :2]
    housings = {}
    for j, joint in enumerate(man.joints):
        if joint.link_shape is None or joint.kind != "revolute":  # a prismatic link never turns in its carrier
            continue
        carrier = "palm" if joint.parent < 0 else man.joints[joint.parent].name
        y = np.asarray(joint.link_shape, float)[:, 1]
        r = JOINT_HOUSING * float(y.max() - y.min())
        fixed = joint.parent < 0
        disk = Point(fixed_axes[j]).buffer(r, HOUSING_QUAD_SEGS) if fixed else None
        housings[(joint.name, carrier)] = (j, r, disk)
    palm = base_polygon(man)
    fast = None if palm is None else fast_view(man, man.base_shape, hand.workpiece, housings)
    return man, palm, housings, fast


def body_frames(man, poses, qs) -> tuple:
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
