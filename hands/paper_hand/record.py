"""The paper hand's record answering for itself (issue 32): :class:`PaperRecord`, the questions a described hand of the
paper's form hands to its record where the closed forms answer, each answered by the paper hand's own code.

A :class:`~qsplan.hands.described.hand.DescribedHand` picks its record's answerer once, at construction: this one
(around its :class:`~qsplan.hands.paper_hand.two_finger.TwoFingerHand`) when accelerated, else the chain record's
(:class:`qsplan.hands.chains.record.ChainRecord`); both answer the members of
:class:`qsplan.hands.protocol.HandRecord`.  Joints ``("left", "right")``, revolute; units SI (m, rad, N m).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qsplan.hands.paper_hand.scene import hand_contacts, hand_geometric_scene, hand_polygons, hand_scene
from qsplan.hands.paper_hand.two_finger import JOINT_NAMES, TwoFingerHand
from qsplan.mechanics.errors import QsplanError

__all__ = ["PaperRecord", "paper_metadata"]


def paper_metadata(hand: TwoFingerHand) -> dict:
    """The paper's hand as an exported plan's metadata records it: its parameters (SI), as always."""
    return {"workpiece_vertices_m": hand.workpiece.tolist(), "workpiece_mass_kg": hand.workpiece_mass,
            "finger_base_m": hand.finger_base, "finger_length_m": hand.finger_length,
            "finger_width_m": hand.finger_width, "finger_mass_kg": hand.finger_mass,
            "palm_halfwidth_m": hand.palm_halfwidth, "gravity_m_s2": hand.gravity}  # fmt: skip


@dataclass(frozen=True, slots=True, eq=False)
class PaperRecord:
    """The paper hand's answers (:class:`qsplan.hands.protocol.HandRecord`), from its parameters ``hand``."""

    hand: TwoFingerHand

    #: The paper's closed forms answer (a chain record's answers come from the polygon search).
    closed_form = True

    @property
    def workpiece(self) -> np.ndarray:
        return self.hand.workpiece

    @property
    def manipulator(self):
        """The fingers as a :class:`~qsplan.mechanics.model.manipulator.Manipulator` (cached per hand)."""
        return self.hand.manipulator

    @property
    def joint_names(self) -> tuple:
        return self.hand.joint_names

    @property
    def joint_kinds(self) -> tuple:
        return ("revolute", "revolute")

    @property
    def finger_joint_names(self) -> tuple:
        """``(("left",), ("right",))``: one joint per finger."""
        return tuple((name,) for name in JOINT_NAMES)

    @property
    def palm_thickness(self) -> float:
        return float(self.hand.palm_thickness)

    @property
    def link_width(self) -> float:
        """The finger width (m)."""
        return float(self.hand.finger_width)

    @property
    def finger_reach(self) -> float:
        """The finger length (m)."""
        return float(self.hand.finger_length)

    def joint_axes(self, q) -> np.ndarray:
        """The fingers' fixed pivots (m), shape (2, 2), whatever ``q``."""
        return self.hand.pivots

    def body_polygons(self, pose, q) -> dict:
        """:func:`qsplan.hands.paper_hand.scene.hand_polygons` (``q`` None: the tangency angles)."""
        return hand_polygons(self.hand, pose, q)

    def scene(self, pose, q, effort_controlled, velocity, effort=None, mu=None, method: str = "auto"):
        """:func:`qsplan.hands.paper_hand.scene.hand_scene` under joint inputs given per joint: ``effort_controlled``
        (2,) bool with exactly one True, ``velocity`` and ``effort`` (2,) (rad/s, N m; the other finger's entry of each
        ignored).

        Raises
        ------
        QsplanError
            Naming ``effort_controlled`` unless exactly one finger is effort-controlled.
        """
        e = np.asarray(effort_controlled, dtype=bool).reshape(-1)
        if e.shape != (2,) or e.sum() != 1:
            raise QsplanError(f"effort_controlled: expected exactly one of the two fingers effort-controlled; got {e.tolist()}")
        k = int(np.flatnonzero(e)[0])
        v = np.broadcast_to(np.asarray(velocity, dtype=float), (2,))
        tau = np.zeros(2) if effort is None else np.broadcast_to(np.asarray(effort, dtype=float), (2,))
        return hand_scene(self.hand, pose, q, JOINT_NAMES[k], velocity=float(v[1 - k]), effort=float(tau[k]), mu=mu,
                          method=method)  # fmt: skip

    def contacts_at(self, pose, q) -> list:
        """The grasp's contacts found in the polygons (palm, palm, left, right)."""
        return hand_contacts(hand_geometric_scene(self.hand, pose, q))

    def range_fields(self) -> list:
        """:meth:`qsplan.hands.paper_hand.two_finger.TwoFingerHand.range_fields`."""
        return self.hand.range_fields()

    def metadata(self) -> dict:
        """:func:`paper_metadata`."""
        return paper_metadata(self.hand)

    def description_table(self) -> dict:
        """Refused: the paper's hand is recorded by its parameters.

        Raises
        ------
        QsplanError
        """
        raise QsplanError("hand: a TwoFingerHand is recorded by its parameters (hand_metadata), not a description")
