"""The two-finger hand of Fig. 9 (Section 5.2): a fixed palm, two single-link fingers, a polygonal workpiece.

The plane is vertical with gravity along -y.  The palm is a fixed slab whose top
surface is ``y = 0``.  Two fingers, thin rectangles of ``finger_length`` x
``finger_width`` (m), turn on revolute joints at ``(-finger_base, 0)`` ("left")
and ``(+finger_base, 0)`` ("right"); a joint angle is the finger's direction
measured counter-clockwise from +x (rad), so the left finger leans in at angles
below pi/2 and the right one at angles above pi/2.  Each finger's inner long
edge touches a vertex of the convex workpiece, whose bottom edge lies flat on
the palm (two palm contacts, at its ends).

:func:`finger_angles` puts each finger at the tangency with the workpiece (closed
form); :mod:`qsplan.hands.two_finger_scene` turns a configuration into a scene.  Contacts are
ordered palm (left end, right end of the bottom edge), left finger, right finger:
mode ``"SSSS"`` is the paper's 4S and ``"RBSS"`` its R2S (the left palm vertex rolls,
the workpiece turns counter-clockwise); with the default hand the R2S mode that
competes is ``"BSRS"`` (the workpiece rolls on the left finger and lifts its left
palm vertex).

All quantities are SI: m, kg, rad, rad/s, N, N m.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qsplan.mechanics.errors import SceneError
from qsplan.mechanics.model.friction import check_friction

__all__ = [
    "CONTACT_ROLES",
    "DEFAULT_WORKPIECE",
    "JOINT_NAMES",
    "TwoFingerHand",
    "default_hand",
    "finger_angle_rates",
    "finger_angles",
    "make_two_finger_hand",
    "workpiece_world",
]

#: Joint names, in joint order.
JOINT_NAMES = ("left", "right")

#: What each of the four contacts is, in the order the scene lists them.
CONTACT_ROLES = ("palm, left end of the bottom edge", "palm, right end of the bottom edge",
                 "left finger's inner edge on a workpiece vertex", "right finger's inner edge on a workpiece vertex")  # fmt: skip

#: Relative tolerance (of the workpiece's size) within which the two lowest
#: vertices count as one horizontal bottom edge; polygon coordinates are
#: decimal inputs, so 1e-9 of the size is rounding, not a tilt.
_FLAT_TOL = 1e-9


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

    Raises
    ------
    SceneError
        Naming the field: non-convex or degenerate workpiece, no level bottom edge,
        non-positive sizes.
    """
    from shapely.geometry import Polygon

    from qsplan.mechanics.model.geometry import check_polygon

    V = check_polygon(workpiece, "workpiece")
    poly = Polygon(V)
    if abs(poly.convex_hull.area - poly.area) > 1e-12 * poly.area or len(np.asarray(poly.convex_hull.exterior.coords)) - 1 != len(V):
        raise SceneError("workpiece: expected a convex polygon with no straight vertices (the fingers touch its corners)")
    if not poly.exterior.is_ccw:
        V = V[::-1]
    size = float(np.ptp(V, axis=0).max())
    order = np.argsort(V[:, 1], kind="stable")
    low = V[order[:2]]
    if abs(low[0, 1] - low[1, 1]) > _FLAT_TOL * size or abs(V[order[2], 1] - low[0, 1]) <= _FLAT_TOL * size:
        raise SceneError("workpiece: expected exactly two lowest vertices at the same height (the edge resting on the palm)")
    start = int(order[0] if V[order[0], 0] < V[order[1], 0] else order[1])
    V = np.roll(V, -start, axis=0)
    if V[1, 0] <= V[0, 0] or abs(V[1, 1] - V[0, 1]) > _FLAT_TOL * size:
        raise SceneError("workpiece: the bottom edge must run left to right from vertex 0 (counter-clockwise order)")
    c = np.asarray(poly.centroid.coords[0])
    V = V - c
    V.setflags(write=False)
    hand = TwoFingerHand(
        workpiece=V,
        workpiece_mass=_positive(workpiece_mass, "workpiece_mass", "kg"),
        finger_base=_positive(finger_base, "finger_base", "m"),
        finger_length=_positive(finger_length, "finger_length", "m"),
        finger_width=_positive(finger_width, "finger_width", "m"),
        finger_mass=_positive(finger_mass, "finger_mass", "kg", allow_zero=True),
        palm_halfwidth=_positive(palm_halfwidth, "palm_halfwidth", "m"),
        palm_thickness=_positive(palm_thickness, "palm_thickness", "m"),
        gravity=_positive(gravity, "gravity", "m/s^2", allow_zero=True),
        mu=float(check_friction(mu, "mu")),
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


def _rot(theta):
    c, s = np.cos(theta), np.sin(theta)
    return np.array([[c, -s], [s, c]])


def workpiece_world(hand: TwoFingerHand, pose) -> np.ndarray:
    """Workpiece vertices in the world (m), shape (k, 2), at ``pose = (x, y, theta)`` of its centre of mass."""
    pose = np.asarray(pose, dtype=float)
    return hand.workpiece @ _rot(pose[2]).T + pose[:2]


def _tangency(hand: TwoFingerHand, V: np.ndarray):
    """Finger angles (2,) touching the vertices ``V`` (k, 2) and the touching vertex of each (2,).

    A vertex ``v`` lies outside the left finger when ``sin(phi - alpha_v) >= c / rho_v``
    (``rho_v, alpha_v`` its polar coordinates about the joint, ``c`` half the finger
    width): the finger touches the vertex with the largest ``alpha_v + asin(c / rho_v)``.
    The right finger, mirrored, touches the smallest ``alpha_v - asin(c / rho_v)``.
    """
    c = 0.5 * hand.finger_width
    phis, idx = np.empty(2), np.empty(2, dtype=int)
    for k, (sign, pick) in enumerate(((1.0, np.argmax), (-1.0, np.argmin))):
        d = V - hand.pivots[k]
        rho = np.hypot(d[:, 0], d[:, 1])
        if np.any(rho <= c):
            raise SceneError(f"pose: the workpiece reaches the {JOINT_NAMES[k]} finger's joint axis")
        alpha = np.arctan2(d[:, 1], d[:, 0])
        if sign < 0:  # the right finger leans left: measure in [0, 2 pi) so that angles below its joint stay past pi
            alpha = np.mod(alpha, 2.0 * np.pi)
        cand = alpha + sign * np.arcsin(c / rho)
        i = int(pick(cand))
        phis[k], idx[k] = cand[i], i
    return phis, idx


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

    Differentiates :func:`finger_angles` in closed form: with the touching vertex at
    polar coordinates ``(rho, alpha)`` about the joint, ``phi = alpha +- asin(c / rho)``
    and ``dphi = dalpha -+ c drho / (rho sqrt(rho^2 - c^2))``.

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
    c = 0.5 * hand.finger_width
    out = np.empty(2)
    for k, sign in enumerate((1.0, -1.0)):
        p = V[idx[k]]
        r = p - pose[:2]
        v = rate[:2] + rate[2] * np.array([-r[1], r[0]])  # velocity of the touching vertex
        d = p - hand.pivots[k]
        rho2 = d @ d
        dalpha = (d[0] * v[1] - d[1] * v[0]) / rho2
        drho = (d @ v) / np.sqrt(rho2)
        out[k] = dalpha - sign * c * drho / (np.sqrt(rho2) * np.sqrt(rho2 - c * c))
    return out
