"""A chain hand's record answering for itself (issue 32): :class:`ChainRecord`, the questions a described hand hands to
its chain record (the polygon search, the reference), each answered from the hand's description.

The counterpart of :class:`qsplan.hands.paper_hand.record.PaperRecord`; both answer the members of
:class:`qsplan.hands.protocol.HandRecord`.  Joint quantities in their kind's units (rad or m); lengths in m.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qsplan.hands.chains.hand import ChainHand, chain_contacts, chain_geometric_scene, chain_polygons, chain_scene
from qsplan.hands.description.files import description_table
from qsplan.hands.description.model import joint_frames
from qsplan.mechanics.errors import QsplanError

__all__ = ["ChainRecord"]


def _width(polygon) -> float:
    """Narrowest width (m) of a polygon: its convex hull's smallest extent across one of the hull's edges."""
    from shapely.geometry import MultiPoint

    hull = np.asarray(MultiPoint(np.asarray(polygon, dtype=float)).convex_hull.exterior.coords)[:-1]
    edges = np.roll(hull, -1, axis=0) - hull
    length = np.hypot(edges[:, 0], edges[:, 1])
    normals = np.stack([-edges[:, 1], edges[:, 0]], axis=1)[length > 0] / length[length > 0, None]
    widths = hull @ normals.T
    return float((widths.max(axis=0) - widths.min(axis=0)).min())


@dataclass(frozen=True, slots=True, eq=False)
class ChainRecord:
    """A chain hand's answers (:class:`qsplan.hands.protocol.HandRecord`), from its description (``hand``)."""

    hand: ChainHand

    #: Answered by the polygon search, not by the paper's closed forms.
    closed_form = False

    @property
    def workpiece(self) -> np.ndarray:
        return self.hand.workpiece

    @property
    def manipulator(self):
        return self.hand.manipulator

    @property
    def joint_names(self) -> tuple:
        return tuple(self.hand.joint_names)

    @property
    def joint_kinds(self) -> tuple:
        return tuple(self.hand.description.joint_kinds)

    @property
    def finger_joint_names(self) -> tuple:
        """``(left finger's joints, right finger's joints)``, each a tuple of names from the palm to the tip."""
        names = self.hand.joint_names
        return tuple(tuple(names[j] for j in self.hand.finger_joints(f)) for f in range(2))

    @property
    def palm_thickness(self) -> float:
        """``-min y`` of the palm polygon (m)."""
        return float(-np.asarray(self.hand.description.palm)[:, 1].min())

    @property
    def link_width(self) -> float:
        """The narrowest width (m) of the narrowest link polygon (the scale of the marks drawn on links)."""
        return min(_width(j.link_shape) for j in self.hand.manipulator.joints if j.link_shape is not None)

    @property
    def finger_reach(self) -> float:
        """The longer finger's sum, over its links, of the farthest link vertex from the link's frame origin (m)."""
        joints = self.hand.manipulator.joints
        return max(sum(float(np.max(np.hypot(*np.asarray(joints[j].link_shape, dtype=float).T)))
                       for j in self.hand.finger_joints(f) if joints[j].link_shape is not None) for f in range(2))  # fmt: skip

    def joint_axes(self, q) -> np.ndarray:
        """World position (m) of each joint's frame origin at ``q`` (n_j,), shape (n_j, 2)."""
        return joint_frames(self.hand.description, np.asarray(q, dtype=float))[:, :2]

    def body_polygons(self, pose, q) -> dict:
        """:func:`qsplan.hands.chains.hand.chain_polygons`.

        Raises
        ------
        QsplanError
            Naming ``q`` when it is None (a chain hand has no default configuration).
        """
        if q is None:
            raise QsplanError("q: expected the joint positions of a chain hand (rad or m); got None")
        return chain_polygons(self.hand, pose, q)

    def scene(self, pose, q, effort_controlled, velocity, effort=None, mu=None, method: str = "auto"):
        """:func:`qsplan.hands.chains.hand.chain_scene`: the contacts always found in the polygons (``method``
        ignored)."""
        return chain_scene(self.hand, pose, q, effort_controlled, velocity, effort, mu)

    def contacts_at(self, pose, q) -> list:
        """The grasp's contacts found in the polygons (palm, palm, left finger, right finger)."""
        n = len(self.hand.joint_names)
        return chain_contacts(self.hand, chain_geometric_scene(self.hand, pose, q, np.zeros(n, dtype=bool), np.zeros(n)))

    def range_fields(self) -> list:
        """:meth:`qsplan.hands.chains.hand.ChainHand.range_fields`."""
        return self.hand.range_fields()

    def description_table(self) -> dict:
        """:func:`qsplan.hands.description.files.description_table` of the hand's description."""
        return description_table(self.hand.description)

    def metadata(self) -> dict:
        """The description (:meth:`description_table`), its source, the workpiece (internal form), its mass and
        friction."""
        h = self.hand
        return {"description": self.description_table(), "description_source": h.description.source,
                "workpiece_vertices_m": h.workpiece.tolist(), "workpiece_mass_kg": float(h.workpiece_mass),
                "mu": float(h.mu)}  # fmt: skip
