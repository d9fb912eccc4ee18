"""The hand records' answers, one dispatch place: the paper's hand and described chain hands (issue 15).

The planner does not ask here (issue 32): it asks the :class:`~qsplan.hands.protocol.Hand` protocol, whose one
implementation, :class:`~qsplan.hands.described.hand.DescribedHand`, knows which record answers it (the paper's where
its closed forms answer, else its chain record) and hands that record to the functions below.  They take a record
(or a described hand, answered by its record) and dispatch on its type: a
:class:`~qsplan.hands.paper_hand.two_finger.TwoFingerHand` (two single-link revolute fingers ``"left"`` and
``"right"``, Fig. 9) is answered by exactly the code that answered it before (its cached
manipulator, :func:`~qsplan.hands.paper_hand.scene.hand_polygons`,
:func:`~qsplan.hands.paper_hand.scene.hand_scene`); a :class:`~qsplan.hands.chains.hand.ChainHand`
(a :class:`~qsplan.hands.description.HandDescription`: two serial fingers of revolute and prismatic
joints) by its description (:func:`~qsplan.hands.chains.hand.chain_polygons`,
:func:`~qsplan.hands.chains.hand.chain_scene`).

Joint quantities carry their kind's unit (:data:`JOINT_UNITS`): rad, rad/s and N m for a revolute
joint; m, m/s and N for a prismatic one.  :func:`hand_metadata` records a hand in an exported plan's
metadata (the paper's hand by its parameters, as before; a chain hand by its description as a plain
table in the hand-file format of :mod:`qsplan.hands.description.files`, and its workpiece), and
:func:`hand_from_metadata` rebuilds it.  Errors are :class:`~qsplan.mechanics.errors.QsplanError`
naming the field.
"""

from __future__ import annotations

import numpy as np

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



def _record(hand):
    """The record the implementations below answer from: a described hand's (:class:`qsplan.hands.described.hand.
    DescribedHand`) paper record where its closed forms answer (accelerated), else its chain record; today's records
    as they are.  (Read by attribute, so that this module does not import the described hand, which builds on it.)"""
    if hasattr(hand, "accelerated") and hasattr(hand, "chain"):
        return hand.paper if hand.accelerated else hand.chain
    return hand


def _two_finger(hand) -> bool:
    from qsplan.hands.paper_hand.two_finger import TwoFingerHand

    return isinstance(_record(hand), TwoFingerHand)


def is_chain_hand(hand) -> bool:
    """Whether ``hand`` answers as a described chain hand (not by the paper's closed forms)."""
    from qsplan.hands.chains.hand import ChainHand

    return isinstance(_record(hand), ChainHand)


def _check(hand) -> bool:
    """True for a chain hand, False for the paper's; :class:`QsplanError` naming ``hand`` for anything else."""
    if _two_finger(hand):
        return False
    if is_chain_hand(hand):
        return True
    raise QsplanError(f"hand: expected a TwoFingerHand or a ChainHand; got {type(hand).__name__}")


def manipulator_of(hand):
    """The hand's :class:`~qsplan.mechanics.model.manipulator.Manipulator` (palm as the base, one link per joint)."""
    hand = _record(hand)
    if _check(hand):
        return hand.manipulator
    from qsplan.hands.paper_hand.scene import hand_manipulator

    return hand_manipulator(hand)


def joint_names(hand) -> tuple:
    """Joint names in the hand's joint order (``("left", "right")`` for the paper's hand)."""
    hand = _record(hand)
    if _check(hand):
        return tuple(hand.joint_names)
    from qsplan.hands.paper_hand.two_finger import JOINT_NAMES

    return JOINT_NAMES


def joint_kinds(hand) -> tuple:
    """``"revolute"`` or ``"prismatic"`` per joint, in joint order."""
    hand = _record(hand)
    if _check(hand):
        return tuple(hand.description.joint_kinds)
    return ("revolute", "revolute")


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
    hand = _record(hand)
    if _check(hand):
        names = hand.joint_names
        return tuple(tuple(names[j] for j in hand.finger_joints(f)) for f in range(2))
    return (("left",), ("right",))


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
    hand = _record(hand)
    if _check(hand):
        from qsplan.hands.chains.hand import chain_polygons

        if q is None:
            raise QsplanError("q: expected the joint positions of a chain hand (rad or m); got None")
        return chain_polygons(hand, pose, q)
    from qsplan.hands.paper_hand.scene import hand_polygons

    return hand_polygons(hand, pose, q)


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
    hand = _record(hand)
    if _check(hand):
        from qsplan.hands.chains.hand import chain_scene

        return chain_scene(hand, pose, q, effort_controlled, velocity, effort, mu)
    from qsplan.hands.paper_hand.two_finger import JOINT_NAMES
    from qsplan.hands.paper_hand.scene import hand_scene

    e = np.asarray(effort_controlled, dtype=bool).reshape(-1)
    if e.shape != (2,) or e.sum() != 1:
        raise QsplanError(f"effort_controlled: expected exactly one of the two fingers effort-controlled; got {e.tolist()}")
    k = int(np.flatnonzero(e)[0])
    v = np.broadcast_to(np.asarray(velocity, dtype=float), (2,))
    tau = np.zeros(2) if effort is None else np.broadcast_to(np.asarray(effort, dtype=float), (2,))
    return hand_scene(hand, pose, q, JOINT_NAMES[k], velocity=float(v[1 - k]), effort=float(tau[k]), mu=mu,
                      method=method)  # fmt: skip


def contacts_at(hand, pose, q) -> list:
    """The contacts of the grasp at ``(pose, q)``, found in the polygons, in the scene's order (palm, palm, left
    finger, right finger): :class:`~qsplan.mechanics.model.geometry.FoundContact` with ``point`` and ``normal``
    (into the workpiece) in the world (m).

    Raises
    ------
    SceneError
        When the polygons give another contact set.
    """
    hand = _record(hand)
    if _check(hand):
        from qsplan.hands.chains.hand import chain_contacts, chain_geometric_scene

        n = len(hand.joint_names)
        return chain_contacts(hand, chain_geometric_scene(hand, pose, q, np.zeros(n, dtype=bool), np.zeros(n)))
    from qsplan.hands.paper_hand.scene import hand_contacts, hand_geometric_scene

    return hand_contacts(hand_geometric_scene(hand, pose, q))


def range_fields(hand) -> list:
    """``[(field, value, kind)]``: the hand's numbers a task checks against its plausible ranges (``kind`` a key of
    ``qsplan.planner.task.fields.TASK_RANGES``): the paper's parameters when given so (finger sizes and mass, the
    palm), and for every hand the workpiece's span, mass, gravity and friction (a described hand's own numbers are
    checked by its file's ranges, :data:`qsplan.hands.description.model.HAND_RANGES`); each record answers its own
    (:meth:`qsplan.hands.paper_hand.two_finger.TwoFingerHand.range_fields`,
    :meth:`qsplan.hands.chains.hand.ChainHand.range_fields`)."""
    _check(_record(hand))
    return _record(hand).range_fields()


def palm_thickness(hand) -> float:
    """How far (m) the palm reaches below its top ``y = 0``: ``-min y`` of the palm polygon."""
    hand = _record(hand)
    if _check(hand):
        return float(-np.asarray(hand.description.palm)[:, 1].min())
    return float(hand.palm_thickness)


def _width(polygon) -> float:
    """Narrowest width (m) of a polygon: its convex hull's smallest extent across one of the hull's edges."""
    from shapely.geometry import MultiPoint

    hull = np.asarray(MultiPoint(np.asarray(polygon, dtype=float)).convex_hull.exterior.coords)[:-1]
    edges = np.roll(hull, -1, axis=0) - hull
    length = np.hypot(edges[:, 0], edges[:, 1])
    normals = np.stack([-edges[:, 1], edges[:, 0]], axis=1)[length > 0] / length[length > 0, None]
    widths = hull @ normals.T
    return float((widths.max(axis=0) - widths.min(axis=0)).min())


def link_width(hand) -> float:
    """A characteristic link width (m): the paper's finger width; for a chain hand the narrowest width of its
    narrowest link polygon (the scale of the marks drawn on links)."""
    hand = _record(hand)
    if _check(hand):
        return min(_width(j.link_shape) for j in hand.manipulator.joints if j.link_shape is not None)
    return float(hand.finger_width)


def finger_reach(hand) -> float:
    """A characteristic finger length (m): the paper's finger length; for a chain hand the longer finger's sum, over
    its links, of the farthest link vertex from the link's frame origin (the scale of the drawn contact normals)."""
    hand = _record(hand)
    if _check(hand):
        joints = hand.manipulator.joints
        return max(sum(float(np.max(np.hypot(*np.asarray(joints[j].link_shape, dtype=float).T)))
                       for j in hand.finger_joints(f) if joints[j].link_shape is not None) for f in range(2))  # fmt: skip
    return float(hand.finger_length)


def joint_axes(hand, q) -> np.ndarray:
    """World position (m) of each joint's frame origin at ``q``, shape (n_j, 2): a revolute joint's axis, where a
    prismatic joint's link frame sits at ``q_i = 0``.  The paper's fingers turn about fixed pivots."""
    hand = _record(hand)
    if _check(hand):
        from qsplan.hands.description.model import joint_frames

        return joint_frames(hand.description, np.asarray(q, dtype=float))[:, :2]
    return hand.pivots


def description_table(hand) -> dict:
    """A chain hand's description (or a :class:`~qsplan.hands.description.HandDescription`) as a plain table in the
    hand-file format (:mod:`qsplan.hands.description.files`): ``name``, ``gravity``, ``palm``, ``fingers``.

    Numbers are Python floats (JSON and TOML keep them exactly);
    :func:`qsplan.hands.description.files.hand_from_table` gives the description back.
    """
    from qsplan.hands.description.model import HandDescription

    desc = hand if isinstance(hand, HandDescription) else (hand.description if _check(hand) else None)
    if desc is None:
        raise QsplanError("hand: a TwoFingerHand is recorded by its parameters (hand_metadata), not a description")
    man = desc.manipulator
    fingers = []
    for finger in desc.fingers:
        joints = []
        for i in finger.joints:
            j = man.joints[i]
            joints.append({"name": j.name, "type": j.kind, "origin": [float(v) for v in j.origin],
                           "limits": [float(v) for v in desc.joint_limits[i]], "speed": float(desc.joint_speeds[i]),
                           "link": {"polygon": np.asarray(j.link_shape, dtype=float).tolist(),
                                    "mass": float(j.link_mass), "com": [float(v) for v in j.link_com]}})  # fmt: skip
        fingers.append({"name": finger.name, "joints": joints})
    return {"name": desc.name, "gravity": float(man.gravity), "palm": {"polygon": np.asarray(desc.palm).tolist()},
            "fingers": fingers}  # fmt: skip


def hand_metadata(hand) -> dict:
    """The hand as an exported plan's metadata records it (all SI).

    The paper's hand: its parameters (``workpiece_vertices_m``, ``finger_base_m``, ...), as always.  A chain hand:
    ``description`` (:func:`description_table`), ``description_source``, ``workpiece_vertices_m`` (internal
    form: about the centroid, counter-clockwise from the bottom edge's left end), ``workpiece_mass_kg``, ``mu``.
    """
    hand = _record(hand)
    if _check(hand):
        return {"description": description_table(hand), "description_source": hand.description.source,
                "workpiece_vertices_m": hand.workpiece.tolist(), "workpiece_mass_kg": float(hand.workpiece_mass),
                "mu": float(hand.mu)}  # fmt: skip
    h = hand
    return {"workpiece_vertices_m": h.workpiece.tolist(), "workpiece_mass_kg": h.workpiece_mass,
            "finger_base_m": h.finger_base, "finger_length_m": h.finger_length, "finger_width_m": h.finger_width,
            "finger_mass_kg": h.finger_mass, "palm_halfwidth_m": h.palm_halfwidth, "gravity_m_s2": h.gravity}  # fmt: skip


def hand_from_metadata(meta) -> object:
    """The hand a plan's ``metadata["hand"]`` records (:func:`hand_metadata`): a ChainHand when it holds a
    ``description``, else the paper's TwoFingerHand (whose palm thickness is not recorded: the default).

    Raises
    ------
    QsplanError
        Naming the field (``hand.description.fingers[0]...``, ``hand.workpiece_vertices_m``).
    """
    if not isinstance(meta, dict):
        raise QsplanError(f"hand: expected the metadata's hand table; got {type(meta).__name__}")
    try:
        if "description" in meta:
            from qsplan.hands.chains.hand import make_chain_hand
            from qsplan.hands.description.files import hand_from_table

            desc = hand_from_table(meta["description"], field="hand.description",
                                   source=str(meta.get("description_source", "plan metadata")))  # fmt: skip
            return make_chain_hand(desc, meta["workpiece_vertices_m"], meta["workpiece_mass_kg"], meta.get("mu", 0.2))
        from qsplan.hands.paper_hand.two_finger import make_two_finger_hand

        return make_two_finger_hand(meta["workpiece_vertices_m"], meta["workpiece_mass_kg"], meta["finger_base_m"],
                                    meta["finger_length_m"], meta["finger_width_m"], meta["finger_mass_kg"],
                                    meta["palm_halfwidth_m"], gravity=meta["gravity_m_s2"])  # fmt: skip
    except KeyError as exc:
        raise QsplanError(f"hand.{exc.args[0]}: missing from the plan's metadata") from None
    except QsplanError as exc:
        text = str(exc)
        raise QsplanError(text if text.startswith("hand") else f"hand.{text}") from None
