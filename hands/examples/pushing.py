"""A polygonal workpiece pushed across a floor by a point finger, as a :class:`qsplan.mechanics.motion.system.MotionSystem`.

The plane is vertical, gravity along -y; the floor is the line ``y = 0``.  The
workpiece is a convex polygon (vertices about its centre of mass, counter-
clockwise) with weight ``weight``.  The finger is a point tip on one
velocity-controlled prismatic joint: tip ``= finger_origin + s * finger_axis``,
driven at ``finger_speed``.  Potential contacts: the finger tip on one edge of the
polygon (``pushed_edge``) and the floor under each of ``floor_vertices``.

A contact appears when its gap closes: the tip reaches the edge's line, or a
vertex reaches the floor (both located as events by the simulator).  While the
finger slides, the contact point moves along the edge (it is always the tip);
while a vertex slides, it moves along the floor.  The run stops if the tip leaves
the edge's segment (``limits``).

The contact geometry on the integrator's hot path is computed here with numpy
(points on lines, and signed gaps, which contact detection alone does not give);
shapely validates the polygon.  :meth:`PushedPolygon.geometry_document` exports any
instant to the geometric scene form, where :func:`qsplan.mechanics.model.geometry.find_contacts`
and :mod:`qsplan.mechanics.model.geometric_scene` rebuild the same scene (the tests check it).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from qsplan.mechanics import QsplanError, Scene, point_wrench
from qsplan.mechanics.motion.system import Friction, make_friction, rigid_body_rates

__all__ = ["PushedPolygon", "make_pushed_polygon", "tilted_box_example", "polygon_world"]


def _rot(theta):
    c, s = np.cos(theta), np.sin(theta)
    return np.array([[c, -s], [s, c]])


def polygon_world(vertices, x) -> np.ndarray:
    """Vertices (m) in the world at pose ``x[:3] = (x_c, y_c, theta)``, shape (m, 2)."""
    return np.asarray(vertices, dtype=float) @ _rot(x[2]).T + np.asarray(x[:2], dtype=float)


@dataclass(frozen=True, slots=True, eq=False)
class PushedPolygon:
    """Polygon on the floor ``y = 0`` pushed by a point finger; state ``[x_c, y_c, theta, s]``.

    Build it with :func:`make_pushed_polygon`.

    Attributes
    ----------
    vertices : ndarray, shape (m, 2)
        Body-frame vertices about the centre of mass (m), counter-clockwise, convex.
    finger_origin : ndarray, shape (2,)
        World position of the tip at joint position ``s = 0`` (m).
    finger_axis : ndarray, shape (2,)
        Unit direction of the prismatic joint.
    finger_speed : float
        Joint velocity (m/s).
    pushed_edge : int
        Edge ``k`` (from vertex ``k`` to ``k + 1``) the tip touches.
    floor_vertices : tuple of int
        Vertices that may touch the floor.
    friction : Friction
        Over the potential contacts: the finger first, then the floor vertices.
    weight : float
        N, at the centre of mass.
    """

    vertices: np.ndarray
    finger_origin: np.ndarray
    finger_axis: np.ndarray
    finger_speed: float
    pushed_edge: int
    floor_vertices: tuple
    friction: Friction
    weight: float
    state_names: ClassVar[tuple] = ("x_c (m)", "y_c (m)", "theta (rad)", "s (m)")

    @property
    def contact_names(self) -> tuple:
        return ("finger",) + tuple(f"floor@v{i}" for i in self.floor_vertices)

    @property
    def limit_names(self) -> tuple:
        k = self.pushed_edge
        nxt = (k + 1) % len(self.vertices)
        return (f"finger tip leaves edge {k} past vertex {k}", f"finger tip leaves edge {k} past vertex {nxt}")

    def tip(self, x) -> np.ndarray:
        """Finger tip in the world (m), shape (2,)."""
        return self.finger_origin + x[3] * self.finger_axis

    def _edge(self, x):
        P = polygon_world(self.vertices, x)
        a, b = P[self.pushed_edge], P[(self.pushed_edge + 1) % len(P)]
        d = b - a
        L = float(np.hypot(*d))
        inward = np.array([-d[1], d[0]]) / L  # counter-clockwise polygon: interior on the left
        return P, a, d / L, L, inward

    def gaps(self, x) -> np.ndarray:
        """Signed gaps (m): tip to the pushed edge's line, each floor vertex's height; shape (n_p,)."""
        P, a, _, _, inward = self._edge(x)
        return np.concatenate([[-(self.tip(x) - a) @ inward], P[list(self.floor_vertices), 1]])

    def limits(self, x) -> np.ndarray:
        """Position of the tip along the pushed edge from each end (m), shape (2,)."""
        _, a, u, L, _ = self._edge(x)
        lam = float((self.tip(x) - a) @ u)
        return np.array([lam, L - lam])

    def scene(self, x, contacts) -> Scene:
        """The instant at ``x`` with the potential contacts ``contacts`` (eq. 1 about the world origin).

        Built directly (no :func:`qsplan.mechanics.make_scene` checks): the inputs are validated
        by :func:`make_pushed_polygon` and the simulator never passes a non-finite state.
        """
        x = np.asarray(x, dtype=float)
        P, _, _, _, inward = self._edge(x)
        r, n, jn, jt = [], [], [], []
        for c in contacts:
            if c == 0:
                nn = inward
                r.append(self.tip(x))
                tt = np.array([-nn[1], nn[0]])
                jn.append(self.finger_axis @ nn)
                jt.append(self.finger_axis @ tt)
            else:
                nn = np.array([0.0, 1.0])
                r.append(P[self.floor_vertices[c - 1]])
                jn.append(0.0)  # the floor is not a joint
                jt.append(0.0)
            n.append(nn)
        r, n = np.array(r), np.array(n)
        t = np.stack([-n[:, 1], n[:, 0]], axis=1)
        Wn = np.vstack([n.T, r[:, 0] * n[:, 1] - r[:, 1] * n[:, 0]])  # eq. (1)
        Wt = np.vstack([t.T, r[:, 0] * t[:, 1] - r[:, 1] * t[:, 0]])
        names = self.contact_names
        return Scene(
            Wn=Wn, Wt=Wt, Jn=np.array(jn)[:, None], Jt=np.array(jt)[:, None],
            mu=self.friction.static[list(contacts)], g_obj=point_wrench(x[:2], (0.0, -self.weight)),
            g_man=np.zeros(1), effort_controlled=np.zeros(1, dtype=bool), joint_velocity=np.array([self.finger_speed]),
            joint_effort=np.full(1, np.nan), joint_names=("finger",), contact_names=tuple(names[c] for c in contacts),
        )  # fmt: skip

    def rates(self, x, qdot, thetadot) -> np.ndarray:
        """``dx/dt``: the pose from ``qdot`` (:func:`qsplan.mechanics.motion.system.pose_rate`), ``s`` from ``thetadot``."""
        return rigid_body_rates(x, qdot, thetadot)

    def geometry_document(self, x, gravity=9.81, floor_extent=10.0) -> dict:
        """The instant at ``x`` in the geometric scene form of :mod:`qsplan.mechanics.model.geometric_scene`.

        The floor becomes the palm (a box under ``y = 0``, ``floor_extent`` m each side
        of the origin), the finger a prismatic joint whose link is a narrow triangle with
        its apex at the tip, and the workpiece mass is ``weight / gravity``.  Loading it
        (:func:`qsplan.mechanics.scene_from_dict`) finds the contacts with
        :func:`qsplan.mechanics.model.geometry.find_contacts`: the same points, normals and Jacobian
        rows as :meth:`scene` gives for the contacts in contact (tests check it), though
        ordered palm first and with one friction coefficient (the finger's static one).
        """
        x = np.asarray(x, dtype=float)
        angle = float(np.arctan2(self.finger_axis[1], self.finger_axis[0]))
        L = floor_extent
        return {
            "gravity": float(gravity),
            "mu": float(self.friction.static[0]),
            "workpiece": {"polygon": polygon_world(self.vertices, x).tolist(), "com": x[:2].tolist(),
                          "mass": self.weight / gravity},  # fmt: skip
            "palm": {"polygon": [[-L, -1.0], [L, -1.0], [L, 0.0], [-L, 0.0]]},
            "joints": [{
                "name": "finger", "type": "prismatic", "parent": -1,
                "origin": [float(self.finger_origin[0]), float(self.finger_origin[1]), angle], "q": float(x[3]),
                "control": "velocity", "velocity": self.finger_speed,
                "link": {"polygon": [[0.0, 0.0], [-0.05, 0.008], [-0.05, -0.008]]},  # apex = tip, body behind it
            }],  # fmt: skip
        }


def make_pushed_polygon(vertices, finger_origin, finger_axis, finger_speed, pushed_edge, floor_vertices,
                        mu_static, mu_kinetic, weight=1.0) -> PushedPolygon:  # fmt: skip
    """Validate and build a :class:`PushedPolygon`.

    Parameters
    ----------
    vertices : array-like, shape (m, 2)
        Convex polygon about its centre of mass (m); reordered counter-clockwise if needed.
    finger_origin, finger_axis : array-like, shape (2,)
        Tip at ``s = 0`` (m) and joint direction (normalised here).
    finger_speed : float
        m/s.
    pushed_edge : int
    floor_vertices : sequence of int
    mu_static, mu_kinetic : array-like, shape (1 + len(floor_vertices),)
        Finger first, then the floor vertices in order.
    weight : float
        N, positive.
    """
    from shapely.geometry import Polygon
    from shapely.geometry.polygon import orient

    V = np.array(vertices, dtype=float)
    if V.ndim != 2 or V.shape[1] != 2 or V.shape[0] < 3 or not np.all(np.isfinite(V)):
        raise QsplanError(f"vertices: expected at least 3 finite 2-D points, shape (m, 2); got shape {V.shape}")
    poly = Polygon(V)
    if not poly.is_valid or poly.area <= 0 or abs(poly.convex_hull.area - poly.area) > 1e-12 * poly.area:
        raise QsplanError("vertices: expected a simple convex polygon with positive area")
    if not poly.exterior.is_ccw:
        V = np.array(orient(poly, 1.0).exterior.coords)[:-1]
    d = np.array(finger_axis, dtype=float).reshape(-1)
    if d.shape != (2,) or not np.all(np.isfinite(d)) or np.hypot(*d) < 1e-12:
        raise QsplanError(f"finger_axis: expected a finite nonzero 2-vector; got {finger_axis!r}")
    o = np.array(finger_origin, dtype=float).reshape(-1)
    if o.shape != (2,) or not np.all(np.isfinite(o)):
        raise QsplanError(f"finger_origin: expected a finite 2-vector; got {finger_origin!r}")
    if not (np.isfinite(finger_speed) and finger_speed != 0):
        raise QsplanError(f"finger_speed: expected a finite nonzero speed (m/s); got {finger_speed!r}")
    if not (0 <= int(pushed_edge) < len(V)):
        raise QsplanError(f"pushed_edge: expected an edge index in [0, {len(V)}); got {pushed_edge!r}")
    fv = tuple(int(i) for i in floor_vertices)
    if any(not 0 <= i < len(V) for i in fv) or len(set(fv)) != len(fv):
        raise QsplanError(f"floor_vertices: expected distinct vertex indices in [0, {len(V)}); got {floor_vertices!r}")
    friction = make_friction(mu_static, mu_kinetic)
    if friction.static.size != 1 + len(fv):
        raise QsplanError(
            f"mu_static: expected {1 + len(fv)} coefficients (finger, then floor vertices); got {friction.static.size}"
        )
    if not (np.isfinite(weight) and weight > 0):
        raise QsplanError(f"weight: expected a positive finite weight (N); got {weight!r}")
    d = d / np.hypot(*d)
    for arr in (V, o, d):
        arr.setflags(write=False)
    return PushedPolygon(V, o, d, float(finger_speed), int(pushed_edge), fv, friction, float(weight))


def tilted_box_example(width=0.3, height=0.2, tilt=np.radians(10.0), tip_fraction=0.3, push_angle=np.radians(45.0),
                       speed=0.05, mu_finger=(1.5, 1.2), mu_floor=(0.6, 0.5), weight=1.0):  # fmt: skip
    """A box tilted on its bottom-right corner, pushed down-right on its left face until it lands.

    The box (``width`` x ``height``, m) rests on vertex 1 (bottom right) with its bottom
    edge tilted ``tilt`` (rad) up to the left, so vertex 0 (bottom left) is in the air.
    The finger tip touches the left face (edge 3) ``tip_fraction`` of the way from
    vertex 3 down to vertex 0 and moves at ``speed`` (m/s) along ``push_angle`` (rad)
    below the horizontal.  With the default friction (static, kinetic) the finger
    sticks while vertex 1 slides (mode ``R-S``): the box turns down onto the floor;
    vertex 0 lands (a contact appears) and the mode changes to ``SSS`` (the box slides
    flat while the tip slides down the face) until the tip passes vertex 0.

    Returns
    -------
    system : PushedPolygon
    x0 : ndarray, shape (4,)
        Pose of the box (centre, angle) and finger joint ``s = 0``.
    """
    w, h = float(width), float(height)
    V = np.array([[-w / 2, -h / 2], [w / 2, -h / 2], [w / 2, h / 2], [-w / 2, h / 2]])
    theta = -float(tilt)
    centre = -_rot(theta) @ V[1]  # vertex 1 at the world origin, on the floor
    x0 = np.array([centre[0], centre[1], theta, 0.0])
    P = polygon_world(V, x0)
    tip = P[3] + float(tip_fraction) * (P[0] - P[3])
    axis = (np.cos(push_angle), -np.sin(push_angle))
    mu_s = (mu_finger[0], mu_floor[0], mu_floor[0])
    mu_k = (mu_finger[1], mu_floor[1], mu_floor[1])
    system = make_pushed_polygon(V, tip, axis, speed, 3, (0, 1), mu_s, mu_k, weight)
    return system, x0
