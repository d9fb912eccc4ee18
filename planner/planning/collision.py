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

The plan certifier (:mod:`qsplan.planner.planning.certify_rows`) measures overlaps the
same way on purpose but with its own code: it must not trust this module.  Units SI (m, m^2).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from itertools import combinations

import numpy as np

from qsplan.mechanics.model.geometry import CONTACT_TOL

__all__ = ["CONTACT_DEPTH_TOL", "JOINT_HOUSING", "LINK_DEPTH_TOL", "Collision", "body_label", "find_collisions",
           "overlap_depth"]  # fmt: skip

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


@lru_cache(maxsize=16)
def _structure(hand):
    """``(manipulator, palm polygon, {(link, carrier): (joint, housing radius (m), housing disk or None)})``.

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
        disk = Point(fixed_axes[j]).buffer(r, 64) if joint.parent < 0 and joint.kind == "revolute" else None
        housings[(joint.name, carrier)] = (j, r, disk)
    return man, base_polygon(man), housings


def find_collisions(hand, pose, q, first: bool = False) -> list:
    """Every pair of the hand's bodies overlapping beyond its tolerance at workpiece ``pose`` and joints ``q``.

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
    from shapely.geometry import Point, Polygon

    from qsplan.hands.two_finger import workpiece_world
    from qsplan.mechanics.model.manipulator import link_polygons, link_poses

    q = np.asarray(q, float)
    man, palm, housings = _structure(hand)
    # the bodies of qsplan.hands.two_finger_scene.hand_polygons, from the cached manipulator (building it is 2/3 of the cost)
    polys = {"palm": palm if palm is not None else Polygon(), "workpiece": Polygon(workpiece_world(hand, pose))}
    polys.update((j.name, p) for j, p in zip(man.joints, link_polygons(man, q)) if p is not None)
    axes = None
    out = []
    for a, b in combinations(polys, 2):
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
                disk = Point(axes[j]).buffer(r, 64)
            region = region.difference(disk)
        if region.is_empty or region.area <= 0.0:
            continue
        depth = overlap_depth(region)
        if depth > (CONTACT_DEPTH_TOL if "workpiece" in (a, b) else LINK_DEPTH_TOL):
            out.append(Collision((body_label(a), body_label(b)), float(region.area), depth))
            if first:
                break
    return out
