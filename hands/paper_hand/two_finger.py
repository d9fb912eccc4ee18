"""The two-finger hand of Fig. 9 (Section 5.2): a fixed palm, two single-link fingers, a polygonal workpiece.

The plane is vertical with gravity along -y.  The palm is a fixed slab whose top
surface is ``y = 0``.  Two fingers, thin rectangles of ``finger_length`` x
``finger_width`` (m), turn on revolute joints at ``(-finger_base, 0)`` ("left")
and ``(+finger_base, 0)`` ("right"); a joint angle is the finger's direction
measured counter-clockwise from +x (rad), so the left finger leans in at angles
below pi/2 and the right one at angles above pi/2.  The convex workpiece's bottom edge
lies flat on the palm (two palm contacts, at its ends); :func:`finger_angles` puts each
finger's inner long edge on a workpiece vertex (the tangency, closed form), and
:mod:`qsplan.hands.paper_hand.grasps` adds fingertips on edges.  Contacts are
ordered palm (left end, right end of the bottom edge), left finger, right finger:
mode ``"SSSS"`` is the paper's 4S and ``"RBSS"`` its R2S (the left palm vertex rolls,
the workpiece turns counter-clockwise); with the default hand the R2S mode that
competes is ``"BSRS"`` (the workpiece rolls on the left finger and lifts its left
palm vertex).

All quantities are SI: m, kg, rad, rad/s, N, N m.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from qsplan.mechanics.errors import SceneError
from qsplan.mechanics.model.friction import check_friction
from qsplan.hands.geometry.workpiece import prepare_workpiece, workpiece_world

__all__ = [
    "CONTACT_ROLES",
    "DEFAULT_WORKPIECE",
    "JOINT_NAMES",
    "TwoFingerHand",
    "default_hand",
    "finger_angle_rates",
    "finger_angles",
    "hand_manipulator",
    "make_two_finger_hand",
    "tangency_angles",
    "tangency_rates",
    "workpiece_world",
]

#: Joint names, in joint order.
JOINT_NAMES = ("left", "right")

#: What each of the four contacts is, in the order the scene lists them.
CONTACT_ROLES = ("palm, left end of the bottom edge", "palm, right end of the bottom edge",
                 "left finger's inner edge on a workpiece vertex", "right finger's inner edge on a workpiece vertex")  # fmt: skip

@dataclass(frozen=True, slots=True, eq=False)
class TwoFingerHand:
    """A palm, two fingers and a workpiece.  Build it with :func:`make_two_finger_hand`.

    Attributes
    ----------
    workpiece : ndarray, shape (k, 2)
        Convex workpiece, counter-clockwise, in its body frame with the centre of
        mass (the centroid: uniform density) at the origin (m).  Vertex 0 is the left
        end of the bottom edge, vertex 1 its right end.
    workpiece_mass : float
        kg.
    finger_base : float
        Joints at ``(-finger_base, 0)`` and ``(+finger_base, 0)`` (m).
    finger_length, finger_width : float
        Finger rectangle (m): from the joint axis along the finger, centred on it.
    finger_mass : float
        Mass of each finger (kg), centred at half its length; 0 ignores their weight (the paper's Fig. 10).
    palm_halfwidth, palm_thickness : float
        The palm slab spans ``[-palm_halfwidth, palm_halfwidth] x [-palm_thickness, 0]`` (m).
    gravity : float
        m/s^2 along -y.
    mu : float
        Friction coefficient of every contact (scenes may override it).
    vertex_order : tuple of int, shape (k,), optional
        Internal vertex ``i`` is the vertex ``vertex_order[i]`` of the polygon as the user wrote it
        (:func:`make_two_finger_hand` re-orders it); None: the identity (a hand built directly).
    vertex_of_user : tuple of int, shape (k_user,), optional
        The internal vertex of each row of the polygon as written (a repeated row, such as a closing
        copy of the first, maps to the vertex it repeats); None: the identity.
    """

    workpiece: np.ndarray
    workpiece_mass: float
    finger_base: float
    finger_length: float
    finger_width: float
    finger_mass: float
    palm_halfwidth: float
    palm_thickness: float
    gravity: float
    mu: float
    vertex_order: tuple | None = None
    vertex_of_user: tuple | None = None

    @property
    def rest_height(self) -> float:
        """Height (m) of the centre of mass when the bottom edge lies on the palm."""
        return float(-self.workpiece[:, 1].min())

    @property
    def edge_lengths(self) -> np.ndarray:
        """Length (m) of edge ``i`` (vertex ``i`` to ``i + 1``), shape (k,)."""
        return np.linalg.norm(np.roll(self.workpiece, -1, axis=0) - self.workpiece, axis=1)

    @property
    def longest_edge(self) -> int:
        """Index of the longest edge."""
        return int(np.argmax(self.edge_lengths))

    @property
    def pivots(self) -> np.ndarray:
        """Joint axes in the world (m), shape (2, 2): left, right."""
        return np.array([[-self.finger_base, 0.0], [self.finger_base, 0.0]])

    @property
    def joint_names(self) -> tuple:
        """``("left", "right")`` (:data:`JOINT_NAMES`), as every hand record names its joints."""
        return JOINT_NAMES

    @property
    def manipulator(self):
        """The fingers as a :class:`~qsplan.mechanics.model.manipulator.Manipulator` (:func:`hand_manipulator`, cached):
        the record's bodies, which the collision checks read of any hand record."""
        return hand_manipulator(self)

    def range_fields(self) -> list:
        """``[(field, value, kind)]``: the numbers a task checks against its plausible ranges (``kind`` a key of
        ``qsplan.planner.task.fields.TASK_RANGES``): the finger sizes and the palm, the workpiece's span and mass, the
        finger mass, gravity and friction, in that order (the first out of range is the one reported)."""
        out = [(f"hand.{name}", float(getattr(self, name)), "size")
               for name in ("finger_base", "finger_length", "finger_width", "palm_halfwidth", "palm_thickness")]  # fmt: skip
        out.append(("hand.workpiece (its width or height)", float(np.max(np.ptp(self.workpiece, axis=0))), "size"))
        out.append(("hand.workpiece_mass", float(self.workpiece_mass), "mass"))
        out.append(("hand.finger_mass", float(self.finger_mass), "finger_mass"))
        return out + [("hand.gravity", float(self.gravity), "gravity"), ("hand.mu", float(self.mu), "friction")]


@lru_cache(maxsize=16)
def hand_manipulator(hand: TwoFingerHand):
    """The two fingers as a :class:`qsplan.mechanics.Manipulator` (joints "left", "right"; palm as the base).

    Built once per hand (cached: hands and manipulators are immutable)."""
    from qsplan.mechanics.model.manipulator import make_joint, make_manipulator

    L, w = hand.finger_length, 0.5 * hand.finger_width
    shape = [(0.0, -w), (L, -w), (L, w), (0.0, w)]
    joints = [
        make_joint(name, "revolute", -1, (x, 0.0, 0.0), hand.finger_mass, (0.5 * L, 0.0), shape, index=i)
        for i, (name, x) in enumerate(zip(JOINT_NAMES, (-hand.finger_base, hand.finger_base)))
    ]
    P, T = hand.palm_halfwidth, hand.palm_thickness
    palm = [(-P, -T), (P, -T), (P, 0.0), (-P, 0.0)]
    return make_manipulator(joints, base_shape=palm, gravity=hand.gravity)


def _positive(value, field, unit, allow_zero=False) -> float:
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise SceneError(f"{field}: expected a number ({unit}); got {value!r}") from None
    if not np.isfinite(x) or x < 0 or (x == 0 and not allow_zero):
        what = "nonnegative" if allow_zero else "positive"
        raise SceneError(f"{field}: expected a {what} finite number ({unit}); got {value!r}")
    return x


def make_two_finger_hand(
    workpiece,
    workpiece_mass=0.2,
    finger_base=0.09,
    finger_length=0.15,
    finger_width=0.012,
    finger_mass=0.0,
    palm_halfwidth=0.16,
    palm_thickness=0.02,
    gravity=9.81,
    mu=0.2,
    palm_edge=None,
) -> TwoFingerHand:
    """Validate and build a :class:`TwoFingerHand`.

    Parameters
    ----------
    workpiece : array-like, shape (k, 2)
        Convex polygon (m), any placement and orientation; it is re-expressed about
        its centroid, counter-clockwise, starting at the left end of its bottom edge.
        Its two lowest vertices must be level (the edge that rests on the palm).
    workpiece_mass, finger_mass : float
        kg; the workpiece's positive, the fingers' nonnegative.
    finger_base, finger_length, finger_width, palm_halfwidth, palm_thickness : float
        m, positive.
    gravity : float
        m/s^2 along -y, nonnegative.
    mu : float
        Friction coefficient, nonnegative.
    palm_edge : int, optional
        The edge (0-based, numbered as written: edge ``K`` runs from vertex ``K`` to ``K + 1``) that
        rests on the palm: the polygon is turned to lay it level at the bottom, and its centroid must
        lie over it.  None: the polygon as given, whose two lowest vertices must be level.

    Raises
    ------
    SceneError
        Naming the field: non-convex or degenerate workpiece, no level bottom edge, non-positive
        sizes, a ``palm_edge`` out of range or that the workpiece cannot rest on.
    """
    prepared = prepare_workpiece(workpiece, palm_edge)
    hand = TwoFingerHand(
        workpiece=prepared.vertices,
        workpiece_mass=_positive(workpiece_mass, "workpiece_mass", "kg"),
        finger_base=_positive(finger_base, "finger_base", "m"),
        finger_length=_positive(finger_length, "finger_length", "m"),
        finger_width=_positive(finger_width, "finger_width", "m"),
        finger_mass=_positive(finger_mass, "finger_mass", "kg", allow_zero=True),
        palm_halfwidth=_positive(palm_halfwidth, "palm_halfwidth", "m"),
        palm_thickness=_positive(palm_thickness, "palm_thickness", "m"),
        gravity=_positive(gravity, "gravity", "m/s^2", allow_zero=True),
        mu=float(check_friction(mu, "mu")),
        vertex_order=prepared.vertex_order,
        vertex_of_user=prepared.vertex_of_user,
    )
    if hand.finger_width >= hand.finger_length:
        raise SceneError(f"finger_width: expected less than finger_length ({hand.finger_length} m); got {hand.finger_width}")
    return hand


#: The workpiece of the default hand (m, before centring): an irregular quadrilateral 8 cm wide
#: at the base and 10 cm tall whose longest edge (10.03 cm) is its left side, leaning right.
DEFAULT_WORKPIECE = ((0.0, 0.0), (0.080, 0.0), (0.085, 0.080), (0.008, 0.100))


def default_hand(**overrides) -> TwoFingerHand:
    """The hand of our Figs. 10-13 (the paper does not give its dimensions; these are ours).

    Palm 0.32 m wide, top at ``y = 0``; finger joints at ``x = -0.09`` and ``+0.09`` m;
    fingers 0.16 m x 0.012 m, massless (as the paper's identically-zero lower bound
    of Fig. 10 implies); workpiece :data:`DEFAULT_WORKPIECE`, 0.2 kg; ``mu = 0.2``;
    ``g = 9.81`` m/s^2.  Keyword arguments override :func:`make_two_finger_hand`'s.
    """
    args = {"workpiece": DEFAULT_WORKPIECE, "finger_base": 0.09, "finger_length": 0.16, **overrides}
    return make_two_finger_hand(**args)


def tangency_angles(hand: TwoFingerHand, V: np.ndarray):
    """Finger angles touching the workpiece vertices ``V`` with their inner edges, batched over states.

    A vertex ``v`` lies outside the left finger when ``sin(phi - alpha_v) >= c / rho_v``
    (``rho_v, alpha_v`` its polar coordinates about the joint, ``c`` half the finger
    width): the finger touches the vertex with the largest ``alpha_v + asin(c / rho_v)``.
    The right finger, mirrored, touches the smallest ``alpha_v - asin(c / rho_v)``.

    Parameters
    ----------
    V : ndarray, shape (n, k, 2)
        World vertices of the workpiece in ``n`` states (m).

    Returns
    -------
    phi : ndarray, shape (n, 2)
        Left and right joint angles (rad), left in ``(-pi, 3 pi / 2]``, right in ``(-pi / 2, 2 pi)``; nan where not reached.
    vertex : ndarray of int, shape (n, 2)
        The touching vertex of each finger.
    reached : ndarray of bool, shape (n, 2)
        False where a vertex lies within ``c`` of the finger's joint axis (no tangent exists).
    """
    c, n = 0.5 * hand.finger_width, V.shape[0]
    phis, idx, reached = np.empty((n, 2)), np.empty((n, 2), dtype=int), np.empty((n, 2), dtype=bool)
    for k, (sign, pick) in enumerate(((1.0, np.argmax), (-1.0, np.argmin))):
        d = V - hand.pivots[k]
        rho = np.hypot(d[..., 0], d[..., 1])
        reached[:, k] = np.all(rho > c, axis=1)
        alpha = np.arctan2(d[..., 1], d[..., 0])
        if sign < 0:  # the right finger leans left: measure in [0, 2 pi) so that angles below its joint stay past pi
            alpha = np.mod(alpha, 2.0 * np.pi)
        with np.errstate(invalid="ignore", divide="ignore"):
            cand = alpha + sign * np.arcsin(c / rho)
        i = pick(cand, axis=1)
        phis[:, k], idx[:, k] = cand[np.arange(n), i], i
    phis[~reached] = np.nan
    return phis, idx, reached


def tangency_rates(hand: TwoFingerHand, d: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Joint rates (rad/s) that keep each finger's inner edge on its touching vertex, batched over states.

    With the vertex at polar coordinates ``(rho, alpha)`` about the joint, ``phi = alpha +- asin(c / rho)``
    (:func:`tangency_angles`), so ``dphi = dalpha -+ c drho / (rho sqrt(rho^2 - c^2))``.

    Parameters
    ----------
    d, v : ndarray, shape (n, 2, 2)
        The touching vertex of each finger (left, right) relative to its joint axis (m), and its velocity (m/s).

    Returns
    -------
    ndarray, shape (n, 2)
    """
    c = 0.5 * hand.finger_width
    sign = np.array([1.0, -1.0])
    rho2 = _dot(d, d)
    dalpha = (d[..., 0] * v[..., 1] - d[..., 1] * v[..., 0]) / rho2
    drho = _dot(d, v) / np.sqrt(rho2)
    return dalpha - sign * c * drho / (np.sqrt(rho2) * np.sqrt(rho2 - c * c))


def _dot(a, b):
    """Dot products over the last axis as ``a @ b`` computes one (matmul: the same rounding for one state or n)."""
    return (a[..., None, :] @ b[..., :, None])[..., 0, 0]


def _tangency(hand: TwoFingerHand, V: np.ndarray):
    """:func:`tangency_angles` of one state ``V`` (k, 2): angles (2,) and touching vertices (2,)."""
    phis, idx, reached = tangency_angles(hand, V[None])
    for k in range(2):
        if not reached[0, k]:
            raise SceneError(f"pose: the workpiece reaches the {JOINT_NAMES[k]} finger's joint axis")
    return phis[0], idx[0]


def finger_angles(hand: TwoFingerHand, pose) -> tuple:
    """Joint angles that put both fingers' inner edges on the workpiece at ``pose``.

    Parameters
    ----------
    hand : TwoFingerHand
    pose : array-like, shape (3,)
        Workpiece ``(x, y, theta)`` (m, m, rad).

    Returns
    -------
    q : ndarray, shape (2,)
        Left and right joint angles (rad).
    vertices : ndarray of int, shape (2,)
        The workpiece vertex each finger touches.

    Raises
    ------
    SceneError
        If a touching vertex lies beyond a finger's length (the tip would touch).
    """
    V = workpiece_world(hand, pose)
    q, idx = _tangency(hand, V)
    for k in range(2):
        along = (V[idx[k]] - hand.pivots[k]) @ np.array([np.cos(q[k]), np.sin(q[k])])
        if not 0.0 < along < hand.finger_length:
            raise SceneError(
                f"finger_length: the {JOINT_NAMES[k]} finger ({hand.finger_length} m) does not reach the workpiece "
                f"vertex {idx[k]} it must touch ({along:.4g} m along it)"
            )
    return q, idx


def finger_angle_rates(hand: TwoFingerHand, pose, pose_rate) -> np.ndarray:
    """Joint velocities (rad/s), shape (2,), that keep both fingers touching while the workpiece moves.

    Differentiates :func:`finger_angles` in closed form (:func:`tangency_rates`).

    Parameters
    ----------
    pose : array-like, shape (3,)
        ``(x, y, theta)`` (m, m, rad).
    pose_rate : array-like, shape (3,)
        ``(xdot, ydot, thetadot)`` of the centre of mass (m/s, m/s, rad/s).
    """
    pose = np.asarray(pose, dtype=float)
    rate = np.asarray(pose_rate, dtype=float)
    V = workpiece_world(hand, pose)
    _, idx = _tangency(hand, V)
    p = V[idx]
    r = p - pose[:2]
    v = rate[:2] + rate[2] * np.stack([-r[:, 1], r[:, 0]], axis=1)  # velocity of the touching vertices
    return tangency_rates(hand, (p - hand.pivots)[None], v[None])[0]
