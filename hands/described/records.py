"""The hand records' answers as functions (issue 15), kept for tests and users: thin wrappers over the records.

The planner does not ask here (issue 32): it asks the :class:`~qsplan.hands.protocol.Hand` protocol, whose one
implementation, :class:`~qsplan.hands.described.hand.DescribedHand`, hands its questions to the record it picked at
construction.  Each record answers for itself (:class:`~qsplan.hands.protocol.HandRecord`): the paper's
:class:`~qsplan.hands.paper_hand.record.PaperRecord` (two single-link revolute fingers ``"left"`` and ``"right"``,
Fig. 9: its cached manipulator, :func:`~qsplan.hands.paper_hand.scene.hand_polygons`,
:func:`~qsplan.hands.paper_hand.scene.hand_scene`) and a chain hand's
:class:`~qsplan.hands.chains.record.ChainRecord` (its description: :func:`~qsplan.hands.chains.hand.chain_polygons`,
:func:`~qsplan.hands.chains.hand.chain_scene`).  The functions below take a record
(:class:`~qsplan.hands.paper_hand.two_finger.TwoFingerHand`, :class:`~qsplan.hands.chains.hand.ChainHand`) or a
described hand, find its answering record at the door (:func:`qsplan.hands.described.build.record_of`) and ask it.

Joint quantities carry their kind's unit (:data:`JOINT_UNITS`): rad, rad/s and N m for a revolute
joint; m, m/s and N for a prismatic one.  :func:`hand_metadata` records a hand in an exported plan's
metadata (the paper's hand by its parameters, as before; a chain hand by its description as a plain
table in the hand-file format of :mod:`qsplan.hands.description.files`, and its workpiece), and
:func:`hand_from_metadata` rebuilds it.  Errors are :class:`~qsplan.mechanics.errors.QsplanError`
naming the field.
"""

from __future__ import annotations

import numpy as np

from qsplan.hands.described.build import record_from_metadata, record_of
from qsplan.hands.description import files as hand_files
from qsplan.hands.description.model import HandDescription
from qsplan.hands.protocol import JOINT_UNITS
from qsplan.mechanics.errors import QsplanError

__all__ = [
    "JOINT_UNITS",
    "contacts_at",
    "description_table",
    "finger_joint_names",
    "finger_of_joint",
    "finger_reach",
    "hand_body_polygons",
    "hand_from_metadata",
    "hand_metadata",
    "is_chain_hand",
    "joint_axes",
    "joint_kinds",
    "joint_names",
    "joint_units",
    "link_width",
    "manipulator_of",
    "palm_thickness",
    "range_fields",
    "scene_at",
]


def is_chain_hand(hand) -> bool:
    """Whether ``hand`` answers as a described chain hand (not by the paper's closed forms)."""
    return not record_of(hand).closed_form


def manipulator_of(hand):
    """The hand's :class:`~qsplan.mechanics.model.manipulator.Manipulator` (palm as the base, one link per joint)."""
    return record_of(hand).manipulator


def joint_names(hand) -> tuple:
    """Joint names in the hand's joint order (``("left", "right")`` for the paper's hand)."""
    return record_of(hand).joint_names


def joint_kinds(hand) -> tuple:
    """``"revolute"`` or ``"prismatic"`` per joint, in joint order."""
    return record_of(hand).joint_kinds


def joint_units(hand, quantity: str = "q") -> tuple:
    """The unit of each joint's ``quantity`` (``"q"``: position, ``"qd"``: velocity, ``"tau"``: effort), in joint order:
    ``("rad", "m")`` for a revolute and a prismatic joint's positions (:data:`JOINT_UNITS`)."""
    if quantity not in JOINT_UNITS["revolute"]:
        raise QsplanError(f"quantity: expected one of {', '.join(JOINT_UNITS['revolute'])}; got {quantity!r}")
    return tuple(JOINT_UNITS[k][quantity] for k in joint_kinds(hand))


def joint_unit(hand, joint: str, quantity: str = "q") -> str:
    """The unit of joint ``joint``'s ``quantity`` (:func:`joint_units`): a jaw's effort in N, a finger's in N m."""
    return joint_units(hand, quantity)[joint_names(hand).index(joint)]


def finger_joint_names(hand) -> tuple:
    """``(left finger's joints, right finger's joints)``, each a tuple of names from the palm to the tip."""
    return record_of(hand).finger_joint_names


def finger_of_joint(hand) -> dict:
    """``{joint name: "left" or "right"}``: the finger each joint belongs to."""
    return {name: side for side, names in zip(("left", "right"), finger_joint_names(hand)) for name in names}


def hand_body_polygons(hand, pose, q) -> dict:
    """World polygons (m) of the palm, the workpiece and every link: ``{"palm", "workpiece", <joint name>...}`` -> (k, 2).

    Parameters
    ----------
    pose : array-like, shape (3,)
        Workpiece ``(x, y, theta)`` (m, m, rad).
    q : array-like, shape (n_j,)
        Joint positions (rad or m); for the paper's hand None gives the fingers' tangency angles.
    """
    return record_of(hand).body_polygons(pose, q)


def scene_at(hand, pose, q, effort_controlled, velocity, effort=None, mu=None, method: str = "auto"):
    """The :class:`~qsplan.mechanics.Scene` of a grasp (contacts palm:0, palm:1, left finger, right finger).

    Parameters
    ----------
    pose : array-like, shape (3,)
        Workpiece ``(x, y, theta)`` (m, m, rad).
    q : array-like, shape (n_j,)
        Joint positions (rad or m).
    effort_controlled : array-like of bool, shape (n_j,)
        The effort-controlled joints; the paper's hand takes exactly one.
    velocity : array-like, shape (n_j,)
        Velocities of the velocity-controlled joints (rad/s or m/s); ignored where effort-controlled.
    effort : array-like, shape (n_j,), optional
        Efforts of the effort-controlled joints (N m or N); default 0 (band computations ignore them).
    mu : float, optional
        Friction of every contact; default the hand's.
    method : {"auto", "generic"}
        The paper's hand only (:func:`qsplan.hands.paper_hand.scene.hand_scene`): ``"generic"`` finds the
        contacts in the polygons (the reference), ``"auto"`` uses the grasp's closed form where it can.  A
        chain hand's contacts are always found in the polygons.

    Raises
    ------
    SceneError
        Naming the field: the polygons give another contact set, or bad inputs.
    """
    return record_of(hand).scene(pose, q, effort_controlled, velocity, effort, mu, method)


def contacts_at(hand, pose, q) -> list:
    """The contacts of the grasp at ``(pose, q)``, found in the polygons, in the scene's order (palm, palm, left
    finger, right finger): :class:`~qsplan.mechanics.model.geometry.FoundContact` with ``point`` and ``normal``
    (into the workpiece) in the world (m).

    Raises
    ------
    SceneError
        When the polygons give another contact set.
    """
    return record_of(hand).contacts_at(pose, q)


def range_fields(hand) -> list:
    """``[(field, value, kind)]``: the hand's numbers a task checks against its plausible ranges (``kind`` a key of
    ``qsplan.planner.task.fields.TASK_RANGES``): the paper's parameters when given so (finger sizes and mass, the
    palm), and for every hand the workpiece's span, mass, gravity and friction (a described hand's own numbers are
    checked by its file's ranges, :data:`qsplan.hands.description.model.HAND_RANGES`); each record answers its own
    (:meth:`qsplan.hands.paper_hand.two_finger.TwoFingerHand.range_fields`,
    :meth:`qsplan.hands.chains.hand.ChainHand.range_fields`)."""
    return record_of(hand).range_fields()


def palm_thickness(hand) -> float:
    """How far (m) the palm reaches below its top ``y = 0``: ``-min y`` of the palm polygon."""
    return record_of(hand).palm_thickness


def link_width(hand) -> float:
    """A characteristic link width (m): the paper's finger width; for a chain hand the narrowest width of its
    narrowest link polygon (the scale of the marks drawn on links)."""
    return record_of(hand).link_width


def finger_reach(hand) -> float:
    """A characteristic finger length (m): the paper's finger length; for a chain hand the longer finger's sum, over
    its links, of the farthest link vertex from the link's frame origin (the scale of the drawn contact normals)."""
    return record_of(hand).finger_reach


def joint_axes(hand, q) -> np.ndarray:
    """World position (m) of each joint's frame origin at ``q``, shape (n_j, 2): a revolute joint's axis, where a
    prismatic joint's link frame sits at ``q_i = 0``.  The paper's fingers turn about fixed pivots."""
    return record_of(hand).joint_axes(q)


def description_table(hand) -> dict:
    """A chain hand's description (or a :class:`~qsplan.hands.description.HandDescription`) as a plain table in the
    hand-file format (:func:`qsplan.hands.description.files.description_table`): ``name``, ``gravity``, ``palm``,
    ``fingers``.

    Numbers are Python floats (JSON and TOML keep them exactly);
    :func:`qsplan.hands.description.files.hand_from_table` gives the description back.
    """
    if isinstance(hand, HandDescription):  # a description as it is, not a hand
        return hand_files.description_table(hand)
    return record_of(hand).description_table()


def hand_metadata(hand) -> dict:
    """The hand as an exported plan's metadata records it (all SI).

    The paper's hand: its parameters (``workpiece_vertices_m``, ``finger_base_m``, ...), as always.  A chain hand:
    ``description`` (:func:`description_table`), ``description_source``, ``workpiece_vertices_m`` (internal
    form: about the centroid, counter-clockwise from the bottom edge's left end), ``workpiece_mass_kg``, ``mu``.
    """
    return record_of(hand).metadata()


def hand_from_metadata(meta) -> object:
    """The hand a plan's ``metadata["hand"]`` records (:func:`hand_metadata`): a ChainHand when it holds a
    ``description``, else the paper's TwoFingerHand (:func:`qsplan.hands.described.build.record_from_metadata`).

    Raises
    ------
    QsplanError
        Naming the field (``hand.description.fingers[0]...``, ``hand.workpiece_vertices_m``).
    """
    return record_from_metadata(meta)
