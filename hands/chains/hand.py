"""A hand from a description holding a workpiece: any two serial-chain fingers on a palm (Section 3, eqs. 1-5).

:class:`ChainHand` pairs a :class:`qsplan.hands.description.HandDescription` (palm, fingers,
limits) with a workpiece in the internal form of :func:`qsplan.hands.geometry.workpiece.prepare_workpiece`.
The workpiece rests on its bottom edge on the palm (pose ``(x, rest_height, 0)``); each finger
closes onto it by its last joint (:func:`qsplan.hands.chains.closing.close_finger`) from the values of its
other joints, so a configuration in contact is the workpiece's ``x`` and the fingers' free joints.

Its scene (:func:`chain_scene`) is built by the generic path, from the contacts the polygon search
finds (:func:`qsplan.mechanics.model.geometric_scene.find_scene_contacts`), and checked to be a grasp:
the two ends of the bottom edge on the palm and one contact on each finger, in that order (the
order of :data:`CONTACT_ORDER`).  Units SI (m, kg, rad, N, N m).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qsplan.hands.chains.closing import close_finger
from qsplan.hands.geometry.workpiece import prepare_workpiece, workpiece_world
from qsplan.mechanics.errors import SceneError
from qsplan.mechanics.model.friction import check_friction

__all__ = ["CONTACT_ORDER", "ChainHand", "chain_contacts", "chain_geometric_scene", "chain_polygons", "chain_scene",
           "close_grasp", "make_chain_hand"]

#: The contacts of a grasp, in the scene's order.
CONTACT_ORDER = ("palm, left end of the bottom edge", "palm, right end of the bottom edge", "left finger", "right finger")

#: The side each finger closes toward (+1: toward +x), by finger name.
SIDES = {"left": 1.0, "right": -1.0}


@dataclass(frozen=True, slots=True, eq=False)
class ChainHand:
    """A described hand and its workpiece.  Build it with :func:`make_chain_hand`.

    Attributes
    ----------
    description : qsplan.hands.description.HandDescription
    workpiece : ndarray, shape (k, 2)
        Counter-clockwise about the centroid (m); vertex 0 the left end of the bottom edge.
    workpiece_mass : float
        kg.
    mu : float
        Friction coefficient of every contact (scenes may override it).
    vertex_order, vertex_of_user : tuple of int
        Internal and user vertex numbering (:class:`qsplan.hands.geometry.workpiece.PreparedWorkpiece`).
    """

    description: object
    workpiece: np.ndarray
    workpiece_mass: float
    mu: float
    vertex_order: tuple
    vertex_of_user: tuple

    @property
    def manipulator(self):
        return self.description.manipulator

    @property
    def joint_names(self) -> tuple:
        return tuple(self.description.joint_names)

    @property
    def gravity(self) -> float:
        return float(self.description.manipulator.gravity)

    @property
    def rest_height(self) -> float:
        """Height (m) of the centre of mass when the bottom edge lies on the palm (the palm's top is ``y = 0``)."""
        return float(-self.workpiece[:, 1].min())

    @property
    def palm_halfwidth(self) -> float:
        """Half the palm's top width about x = 0 (m): the nearer end of its top edge."""
        lo, hi = self.description.palm_top
        return float(min(-lo, hi))

    def finger_joints(self, finger: int) -> tuple:
        """The manipulator joint indices of finger 0 (left) or 1 (right), base to tip."""
        return tuple(int(j) for j in self.description.fingers[finger].joints)

    def free_joints(self) -> np.ndarray:
        """Indices of the joints that are not a finger's closing (last) joint."""
        closing = {self.finger_joints(f)[-1] for f in range(2)}
        return np.array([j for j in range(len(self.joint_names)) if j not in closing], dtype=int)

    def pose(self, x) -> np.ndarray:
        """Workpiece pose ``(x, rest height, 0)`` (m, m, rad), shape (3,)."""
        return np.array([float(x), self.rest_height, 0.0])

    def range_fields(self) -> list:
        """``[(field, value, kind)]``: the workpiece's span and mass, gravity and friction, which a task checks against
        its plausible ranges (``qsplan.planner.task.fields.TASK_RANGES``); the description's own numbers are checked by
        its file's ranges (:data:`qsplan.hands.description.model.HAND_RANGES`)."""
        return [("hand.workpiece (its width or height)", float(np.max(np.ptp(self.workpiece, axis=0))), "size"),
                ("hand.workpiece_mass", float(self.workpiece_mass), "mass"), ("hand.gravity", float(self.gravity), "gravity"),
                ("hand.mu", float(self.mu), "friction")]  # fmt: skip


def make_chain_hand(description, workpiece, workpiece_mass=0.2, mu=0.2, palm_edge=None) -> ChainHand:
    """Validate and build a :class:`ChainHand`.

    Parameters
    ----------
    description : qsplan.hands.description.HandDescription
    workpiece : array-like, shape (k, 2)
        Convex polygon (m) (:func:`qsplan.hands.geometry.workpiece.prepare_workpiece`).
    workpiece_mass : float
        kg, positive.
    mu : float
        Friction coefficient, nonnegative.
    palm_edge : int, optional
        The edge, as written, that rests on the palm.

    Raises
    ------
    SceneError
        Naming the field.
    """
    prepared = prepare_workpiece(workpiece, palm_edge)
    try:
        mass = float(workpiece_mass)
    except (TypeError, ValueError):
        raise SceneError(f"workpiece_mass: expected a number (kg); got {workpiece_mass!r}") from None
    if not np.isfinite(mass) or mass <= 0:
        raise SceneError(f"workpiece_mass: expected a positive finite number (kg); got {workpiece_mass!r}")
    names = tuple(f.name for f in description.fingers)
    if names != ("left", "right"):
        raise SceneError(f"description.fingers: expected the fingers 'left' and 'right'; got {names}")
    return ChainHand(description, prepared.vertices, mass, float(check_friction(mu, "mu")), prepared.vertex_order,
                     prepared.vertex_of_user)  # fmt: skip


def close_grasp(hand: ChainHand, x: float, q) -> tuple | None:
    """Close both fingers onto the workpiece at ``x`` from the free joints of ``q``.

    Parameters
    ----------
    x : float
        Workpiece x (m).
    q : array-like, shape (n_j,)
        Joint positions; the closing joints' entries are ignored.

    Returns
    -------
    (ndarray (n_j,), (ClosedFinger, ClosedFinger)) or None
        The closed configuration and each finger's contact; None where a finger touches nothing within its range.
    """
    desc = hand.description
    W = workpiece_world(hand, hand.pose(x))
    q = np.array(q, dtype=float)
    closed = []
    for f, side in enumerate((1.0, -1.0)):
        c = close_finger(desc.manipulator, q, hand.finger_joints(f), desc.joint_limits, W, side)
        if c is None:
            return None
        q[c.link] = c.value
        closed.append(c)
    return q, tuple(closed)


def chain_geometric_scene(hand: ChainHand, pose, q, effort_controlled, velocity, effort=None, mu=None):
    """The instant as a :class:`qsplan.mechanics.GeometricScene`.

    Parameters
    ----------
    pose : array-like, shape (3,)
        Workpiece ``(x, y, theta)`` (m, m, rad).
    q : array-like, shape (n_j,)
        Joint positions (rad or m).
    effort_controlled : array-like of bool, shape (n_j,)
    velocity : array-like, shape (n_j,)
        Velocities of the velocity-controlled joints (rad/s or m/s; ignored where effort-controlled).
    effort : array-like, shape (n_j,), optional
        Efforts of the effort-controlled joints (N m or N); default 0 (band computations ignore them).
    mu : float, optional
        Friction of every contact; default ``hand.mu``.
    """
    from qsplan.mechanics.model.geometric_scene import GeometricScene
    from qsplan.mechanics.model.geometry import CONTACT_TOL

    n = len(hand.joint_names)
    e = np.asarray(effort_controlled, dtype=bool).reshape(n)
    v = np.broadcast_to(np.asarray(velocity, dtype=float), (n,))
    eff = np.zeros(n) if effort is None else np.broadcast_to(np.asarray(effort, dtype=float), (n,))
    pose = np.asarray(pose, dtype=float)
    arrays = []
    for a in (workpiece_world(hand, pose), pose[:2], np.zeros(3), np.asarray(q, dtype=float), e,
              np.where(e, np.nan, v), np.where(e, eff, np.nan)):
        a = np.array(a, copy=True)
        a.setflags(write=False)
        arrays.append(a)
    V, com, extra, q, e, jv, je = arrays
    return GeometricScene(
        workpiece=V, com=com, mass=hand.workpiece_mass, extra_wrench=extra, manipulator=hand.manipulator,
        q=q, effort_controlled=e, joint_velocity=jv, joint_effort=je,
        mu=hand.mu if mu is None else float(check_friction(mu, "mu")), contact_mu=(), contact_tolerance=CONTACT_TOL,
    )  # fmt: skip


def chain_contacts(hand: ChainHand, gs) -> list:
    """The contacts of ``gs`` checked to be a grasp: two on the palm, then one on the left finger and one on the right.

    Raises
    ------
    SceneError
        Naming what the polygons give instead.
    """
    from qsplan.mechanics.model.geometric_scene import find_scene_contacts

    found = find_scene_contacts(gs)
    finger_of = {j: f for f in range(2) for j in hand.finger_joints(f)}
    where = [-1 if c.body < 0 else finger_of.get(c.body, -2) for c in found]
    if where != [-1, -1, 0, 1]:
        names = [gs.body_name(c.body) for c in found]
        raise SceneError(f"contacts: expected palm, palm, a left-finger link, a right-finger link (one contact per "
                         f"finger); found {names} at q = {np.round(gs.q, 6).tolist()}")  # fmt: skip
    return found


def chain_scene(hand: ChainHand, pose, q, effort_controlled, velocity, effort=None, mu=None):
    """The :class:`qsplan.mechanics.Scene` of a grasp (contacts palm, palm, left, right; see :func:`chain_contacts`).

    Parameters are those of :func:`chain_geometric_scene`."""
    from qsplan.mechanics.model.geometric_scene import scene_from_geometric_scene

    gs = chain_geometric_scene(hand, pose, q, effort_controlled, velocity, effort, mu)
    return scene_from_geometric_scene(gs, chain_contacts(hand, gs))


def chain_polygons(hand: ChainHand, pose, q) -> dict:
    """World polygons (m) for drawing and collision checks: ``{"palm", "workpiece", <joint name>...}`` -> (k, 2)."""
    from qsplan.mechanics.model.manipulator import link_polygons

    man = hand.manipulator
    out = {"palm": np.asarray(man.base_shape, dtype=float), "workpiece": workpiece_world(hand, pose)}
    for joint, poly in zip(man.joints, link_polygons(man, np.asarray(q, dtype=float))):
        if poly is not None:
            out[joint.name] = np.asarray(poly.exterior.coords, dtype=float)[:-1]
    return out

