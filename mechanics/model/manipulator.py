"""The manipulator: a planar kinematic tree of revolute and prismatic joints (Section 3, eqs. 3 and 5).

Joint ``i`` is mounted on the link of joint ``parent`` (-1: the fixed base) at
``origin = (x, y, angle)`` in that link's frame.  A revolute joint turns its
child link about the joint frame's origin by ``q_i`` (rad); a prismatic joint
slides it along the joint frame's x axis by ``q_i`` (m).  Link ``i`` is the link
moved by joint ``i``; its frame is the joint frame moved by ``q_i``.

The manipulator enters the paper's model through the contact Jacobian rows
``J_i = [j_in; j_it]`` (eq. 5: the velocity of the manipulator's contact point
in the contact frame) and ``g_man`` (eq. 3: ``J^T c = tau - g_man``).  With only
link weights, ``g_man = -sum_k Jp(com_k)^T (0, -m_k g) = dV/dq`` for the
potential ``V = sum_k m_k g y_com,k``: a motionless arm with no contact force
needs ``tau = g_man``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from dataclasses import field as dataclass_field

import numpy as np
from shapely.geometry import Polygon

from qsplan.mechanics.model.contact import tangent_from_normal
from qsplan.mechanics.errors import SceneError
from qsplan.mechanics.model.geometry import check_polygon
from qsplan.mechanics.model.scene import check_finite_array

__all__ = [
    "JOINT_KINDS",
    "Joint",
    "Manipulator",
    "make_joint",
    "make_manipulator",
    "check_joint_positions",
    "link_poses",
    "point_jacobian",
    "contact_jacobian",
    "gravity_efforts",
    "link_polygons",
    "base_polygon",
]

JOINT_KINDS = ("revolute", "prismatic")


@dataclass(frozen=True, slots=True, eq=False)
class Joint:
    """One joint and the link it moves.

    Attributes
    ----------
    name : str
    kind : str
        ``"revolute"`` (q in rad) or ``"prismatic"`` (q in m).
    parent : int
        Index of the joint whose link carries this joint, -1 for the fixed base.
    origin : ndarray, shape (3,)
        Joint frame ``(x, y, angle)`` in the parent link frame at q = 0 (m, m, rad).
    link_mass : float
        Mass of the moved link (kg).
    link_com : ndarray, shape (2,)
        Centre of mass of the link, link frame (m).
    link_shape : tuple of (float, float), or None
        Polygon vertices of the link, link frame (m); None for a link that never touches.
    """

    name: str
    kind: str
    parent: int
    origin: np.ndarray
    link_mass: float = 0.0
    link_com: np.ndarray = dataclass_field(default_factory=lambda: np.zeros(2))
    link_shape: tuple | None = None


@dataclass(frozen=True, slots=True, eq=False)
class Manipulator:
    """A planar tree of joints.  Build it with :func:`make_manipulator` (which validates).

    Attributes
    ----------
    joints : tuple of Joint
        Parents precede children.
    base_shape : tuple of (float, float), or None
        Polygon of the fixed base (e.g. a palm), world frame (m).
    gravity : float
        Gravitational acceleration (m/s^2) acting along -y.
    """

    joints: tuple
    base_shape: tuple | None = None
    gravity: float = 9.81

    @property
    def n_joints(self) -> int:
        return len(self.joints)

    @property
    def joint_names(self) -> tuple:
        return tuple(j.name for j in self.joints)


def _frozen(a) -> np.ndarray:
    a = np.array(a, dtype=float, copy=True)
    a.setflags(write=False)
    return a


def _finite(value, field: str, unit: str) -> float:
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise SceneError(f"{field}: expected a number ({unit}); got {value!r}")
    if not np.isfinite(value):
        raise SceneError(f"{field}: expected a finite number ({unit}); got {value!r}")
    return float(value)


def _shape(value, field: str):
    if value is None:
        return None
    return tuple((float(x), float(y)) for x, y in check_polygon(value, field))


def make_joint(
    name, kind, parent, origin, link_mass=0.0, link_com=(0.0, 0.0), link_shape=None, *, index=None
) -> Joint:
    """Validate and build a :class:`Joint` (fields as in the class).

    ``index`` is the joint's position in the manipulator: it checks that the
    parent precedes it and prefixes error messages with ``joints[index]``.

    Raises
    ------
    SceneError
        Naming the field: non-string name, unknown kind, bad parent, non-finite
        or wrong-shape origin or com, negative mass, invalid link polygon.
    """
    f = "joint" if index is None else f"joints[{index}]"
    if not isinstance(name, str) or not name:
        raise SceneError(f"{f}.name: expected a non-empty string; got {name!r}")
    if kind not in JOINT_KINDS:
        raise SceneError(f"{f}.kind: expected 'revolute' or 'prismatic'; got {kind!r}")
    if isinstance(parent, (bool, np.bool_)) or not isinstance(parent, (int, np.integer)):
        raise SceneError(f"{f}.parent: expected an integer joint index (-1 for the base); got {parent!r}")
    upper = index if index is not None else np.inf
    if not -1 <= parent < upper:
        below = f"an index below {index}" if index is not None else "a nonnegative index"
        raise SceneError(f"{f}.parent: expected -1 or {below}; got {parent}")
    origin = check_finite_array(origin, f"{f}.origin", (3,))
    mass = _finite(link_mass, f"{f}.link_mass", "kg")
    if mass < 0:
        raise SceneError(f"{f}.link_mass: expected a nonnegative mass (kg); got {mass}")
    com = check_finite_array((0.0, 0.0) if link_com is None else link_com, f"{f}.link_com", (2,))
    return Joint(name, kind, int(parent), _frozen(origin), mass, _frozen(com), _shape(link_shape, f"{f}.link_shape"))


def make_manipulator(joints, base_shape=None, gravity=9.81) -> Manipulator:
    """Validate and build a :class:`Manipulator`.

    Parameters
    ----------
    joints : sequence of Joint
        Parents must precede children; names must be unique.
    base_shape : array-like, shape (k, 2), optional
        Fixed base polygon, world frame (m).
    gravity : float
        Magnitude (m/s^2) of gravity along -y; nonnegative.

    Raises
    ------
    SceneError
        Naming the field, e.g. ``joints[2].parent: expected -1 or an index below 2; got 5``.
    """
    if isinstance(joints, (str, bytes)) or not hasattr(joints, "__len__"):
        raise SceneError(f"joints: expected a sequence of Joint; got {joints!r}")
    checked = []
    seen = {}
    for i, j in enumerate(joints):
        if not isinstance(j, Joint):
            raise SceneError(f"joints[{i}]: expected a Joint; got {type(j).__name__}")
        checked.append(make_joint(j.name, j.kind, j.parent, j.origin, j.link_mass, j.link_com, j.link_shape, index=i))
        if j.name in seen:
            raise SceneError(f"joints[{i}].name: expected a unique name; {j.name!r} is also joints[{seen[j.name]}].name")
        seen[j.name] = i
    g = _finite(gravity, "gravity", "m/s^2")
    if g < 0:
        raise SceneError(f"gravity: expected a nonnegative magnitude (m/s^2, acting along -y); got {g}")
    return Manipulator(tuple(checked), _shape(base_shape, "base_shape"), g)


def check_joint_positions(man: Manipulator, q, field: str = "q") -> np.ndarray:
    """Joint positions as a float array of shape (n_j,); raise :class:`SceneError` naming ``field``."""
    return check_finite_array(q, field, (man.n_joints,))


def _check_link(man: Manipulator, link) -> int:
    if isinstance(link, (bool, np.bool_)) or not isinstance(link, (int, np.integer)) or not 0 <= link < man.n_joints:
        raise SceneError(f"link: expected a link index in [0, {man.n_joints}); got {link!r}")
    return int(link)


def _paths(man: Manipulator) -> np.ndarray:
    """``paths[k, i]`` is True when joint ``i`` lies on the path from the base to link ``k``, shape (n_j, n_j)."""
    n = man.n_joints
    paths = np.zeros((n, n), dtype=bool)
    for i, j in enumerate(man.joints):
        if j.parent >= 0:
            paths[i] = paths[j.parent]
        paths[i, i] = True
    return paths


def _revolute(man: Manipulator) -> np.ndarray:
    return np.array([j.kind == "revolute" for j in man.joints], dtype=bool)


def _poses(man: Manipulator, q: np.ndarray) -> np.ndarray:
    # The tree is walked joint by joint (parents first); n_j <= 20, so plain floats beat numpy here.
    out = []
    for j, qi in zip(man.joints, q.tolist()):
        px, py, pa = (0.0, 0.0, 0.0) if j.parent < 0 else out[j.parent]
        ox, oy, oa = j.origin.tolist()
        c, s = math.cos(pa), math.sin(pa)
        x, y, a = px + c * ox - s * oy, py + s * ox + c * oy, pa + oa
        if j.kind == "revolute":
            a += qi
        else:
            x, y = x + math.cos(a) * qi, y + math.sin(a) * qi
        out.append((x, y, a))
    return np.array(out, dtype=float).reshape(len(out), 3)


def link_poses(man: Manipulator, q) -> np.ndarray:
    """World poses of all link frames.

    Parameters
    ----------
    man : Manipulator
    q : array-like, shape (n_j,)
        Joint positions (rad or m).

    Returns
    -------
    ndarray, shape (n_j, 3)
        ``(x, y, angle)`` of each link frame (m, m, rad; angles not wrapped).
    """
    return _poses(man, check_joint_positions(man, q))


def _jacobian_columns(man, poses, points):
    """Linear-velocity Jacobians of world ``points`` (m, 2), each as if fixed to every link; shape (m, 2, n_j)."""
    rev = _revolute(man)
    rel = points[:, None, :] - poses[None, :, :2]  # (m, n_j, 2): lever arms from the revolute axes
    rot = np.stack([-rel[..., 1], rel[..., 0]], axis=1)  # z x (p - o_i): (m, 2, n_j)
    axis = np.stack([np.cos(poses[:, 2]), np.sin(poses[:, 2])])  # prismatic axes in world: (2, n_j)
    return np.where(rev[None, None, :], rot, axis[None])


def point_jacobian(man: Manipulator, q, link, point) -> np.ndarray:
    """Linear-velocity Jacobian ``Jp`` of a point fixed to a link.

    Parameters
    ----------
    man : Manipulator
    q : array-like, shape (n_j,)
        Joint positions (rad or m).
    link : int
        Index of the link carrying the point.
    point : array-like, shape (2,)
        The point's current position, WORLD frame (m).

    Returns
    -------
    ndarray, shape (2, n_j)
        ``d point / dt = Jp @ qdot`` (m/s); columns of joints not on the path
        from the base to ``link`` are zero.
    """
    q = check_joint_positions(man, q)
    link = _check_link(man, link)
    point = check_finite_array(point, "point", (2,))
    cols = _jacobian_columns(man, _poses(man, q), point[None])[0]
    return np.where(_paths(man)[link][None, :], cols, 0.0)


def contact_jacobian(man: Manipulator, q, link, point, normal) -> np.ndarray:
    """Contact Jacobian rows ``J_i = [j_in; j_it] = [n^T Jp; t^T Jp]`` (eq. 5).

    Parameters
    ----------
    man : Manipulator
    q : array-like, shape (n_j,)
    link : int
        Link carrying the manipulator's contact point.
    point : array-like, shape (2,)
        Contact point, world frame (m).
    normal : array-like, shape (2,)
        Contact normal pointing into the workpiece; normalised here. ``t`` is
        ``n`` rotated by +90 degrees.

    Returns
    -------
    ndarray, shape (2, n_j)
        Rows ``j_in``, ``j_it`` (m/s per unit joint velocity).
    """
    normal = check_finite_array(normal, "normal", (2,))
    length = np.hypot(*normal)
    if length < 1e-12:
        raise SceneError(f"normal: expected a nonzero direction into the workpiece; got {normal.tolist()}")
    n = normal / length
    return np.vstack([n, tangent_from_normal(n)]) @ point_jacobian(man, q, link, point)


def _to_world(poses, local):
    """World coordinates of link-frame points: ``poses`` (m, 3), ``local`` (m, 2) -> (m, 2)."""
    c, s = np.cos(poses[:, 2]), np.sin(poses[:, 2])
    return poses[:, :2] + np.stack([c * local[:, 0] - s * local[:, 1], s * local[:, 0] + c * local[:, 1]], axis=1)


def gravity_efforts(man: Manipulator, q) -> np.ndarray:
    """Joint efforts ``g_man`` induced by the link weights (eq. 3).

    ``g_man = -sum_k Jp(com_k)^T (0, -m_k g) = dV/dq`` with ``V = sum_k m_k g y_com,k``,
    so that ``J^T c = tau - g_man`` holds for a motionless arm with ``tau = g_man``
    when ``c = 0``.

    Parameters
    ----------
    man : Manipulator
    q : array-like, shape (n_j,)

    Returns
    -------
    ndarray, shape (n_j,)
        N m for revolute joints, N for prismatic joints.
    """
    q = check_joint_positions(man, q)
    poses = _poses(man, q)
    mass = np.array([j.link_mass for j in man.joints])
    if man.n_joints == 0 or not np.any(mass):
        return np.zeros(man.n_joints)
    coms = _to_world(poses, np.array([j.link_com for j in man.joints]))
    jy = _jacobian_columns(man, poses, coms)[:, 1, :] * _paths(man)  # d y_com,k / d q_i: (n_j links, n_j joints)
    return (mass * man.gravity) @ jy


def link_polygons(man: Manipulator, q) -> list:
    """World-frame shapely polygons of the links (None where a link has no shape).

    Parameters
    ----------
    man : Manipulator
    q : array-like, shape (n_j,)

    Returns
    -------
    list of shapely.Polygon or None, length n_j
    """
    poses = link_poses(man, q)
    out = []
    for pose, j in zip(poses, man.joints):
        if j.link_shape is None:
            out.append(None)
        else:
            local = np.asarray(j.link_shape, dtype=float)
            out.append(Polygon(_to_world(np.broadcast_to(pose, (len(local), 3)), local)))
    return out


def base_polygon(man: Manipulator):
    """The fixed base polygon (world frame) as a shapely Polygon, or None."""
    return None if man.base_shape is None else Polygon(man.base_shape)
