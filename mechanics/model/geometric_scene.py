"""The geometric scene form: polygons and a joint tree in, a :class:`Scene` out (Section 3, eqs. 1-5).

Instead of wrench columns and Jacobian rows, the document describes the
workpiece, an optional fixed palm and a planar tree of joints with link
polygons; contacts are found from the geometry (:func:`qsplan.mechanics.model.geometry.find_contacts`)
and ``W_n, W_t`` (eq. 1), ``J_n, J_t`` (eq. 5), ``g_obj`` (eq. 2) and ``g_man``
(eq. 3) are computed.  Schema (TOML shown; JSON has the same structure)::

    name = "two fingers"           # optional, also "description"
    gravity = 9.81                 # m/s^2 along -y; optional, default 9.81, >= 0
    contact_tolerance = 1e-6       # m; optional, default CONTACT_TOL, > 0
    mu = 0.3                       # friction of every found contact; optional, default 0

    [workpiece]                    # required
    polygon = [[x, y], ...]        # world frame, m, >= 3 vertices, simple, no holes
    com = [x, y]                   # centre of mass, world frame, m
    mass = 1.0                     # kg, >= 0; weight m g along -y at com
    extra_wrench = [fx, fy, m]     # optional extra external wrench about the world origin (N, N, N m)

    [palm]                         # optional fixed body (the manipulator's base)
    polygon = [[x, y], ...]        # world frame, m

    [[joints]]                     # required, at least one; parents before children
    name = "left"                  # optional, default "j<index>"; unique; "palm" is reserved
    type = "revolute"              # or "prismatic"
    parent = -1                    # -1 (the base) or the name of an earlier joint
    origin = [x, y, angle]         # joint frame in the parent link frame at q = 0 (m, m, rad)
    q = 0.3                        # optional, default 0 (rad or m)
    control = "velocity"           # or "effort"
    velocity = 0.5                 # rad/s or m/s; required when control = "velocity"
    effort = 1.2                   # N m or N; required when control = "effort"
    link = { polygon = [[x, y], ...], mass = 0.1, com = [x, y] }   # optional; link frame (m, kg)

    [[contact_mu]]                 # optional per-contact friction overrides
    index = 0                      # 0-based, in the order of the found contacts
    mu = 0.2

Contacts are ordered as :func:`~qsplan.mechanics.model.geometry.find_contacts` orders them
(palm first, then links by index; along the workpiece boundary within a body) and
named ``"<body>:<index>"`` with the palm or joint name and the 0-based contact
index, e.g. ``"palm:0"``, ``"left:2"``.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from shapely.geometry import Polygon

from qsplan.mechanics.model.contact import point_wrench, wrench_matrices
from qsplan.mechanics.model.fields import check_keys, number, vector
from qsplan.mechanics.model.friction import check_friction
from qsplan.mechanics.errors import SceneError
from qsplan.mechanics.model.geometry import CONTACT_TOL, FoundContact, check_polygon, find_contacts
from qsplan.mechanics.model.manipulator import (
    JOINT_KINDS,
    Manipulator,
    base_polygon,
    check_joint_positions,
    contact_jacobian,
    gravity_efforts,
    link_polygons,
    make_joint,
    make_manipulator,
)
from qsplan.mechanics.model.scene import Scene, make_scene

__all__ = [
    "GeometricScene",
    "geometric_scene_from_dict",
    "find_scene_contacts",
    "scene_from_geometric_scene",
    "scene_from_geometry",
]

_TOP_KEYS = {"name", "description", "gravity", "contact_tolerance", "mu", "workpiece", "palm", "joints", "contact_mu"}
_WORKPIECE_KEYS = {"polygon", "com", "mass", "extra_wrench"}
_PALM_KEYS = {"polygon"}
_JOINT_KEYS = {"name", "type", "parent", "origin", "q", "control", "velocity", "effort", "link"}
_LINK_KEYS = {"polygon", "mass", "com"}
_CONTACT_MU_KEYS = {"index", "mu"}
_PALM = "palm"


@dataclass(frozen=True, slots=True, eq=False)
class GeometricScene:
    """A validated geometric scene: the workpiece, the manipulator at ``q`` and the joint inputs.

    Attributes
    ----------
    workpiece : ndarray, shape (k, 2)
        Workpiece polygon, world frame (m).
    com : ndarray, shape (2,)
        Workpiece centre of mass, world frame (m).
    mass : float
        Workpiece mass (kg).
    extra_wrench : ndarray, shape (3,)
        Further external wrench on the workpiece about the world origin (N, N, N m).
    manipulator : Manipulator
        Joints, links, palm (``base_shape``) and gravity (m/s^2 along -y).
    q : ndarray, shape (n_j,)
        Joint positions (rad or m).
    effort_controlled : ndarray of bool, shape (n_j,)
    joint_velocity, joint_effort : ndarray, shape (n_j,)
        Inputs; NaN where the joint has the other control mode.
    mu : float
        Friction coefficient of every found contact unless overridden.
    contact_mu : tuple of (int, float)
        Overrides ``(contact index, mu)``.
    contact_tolerance : float
        Contact tolerance (m) passed to :func:`~qsplan.mechanics.model.geometry.find_contacts`.
    """

    workpiece: np.ndarray
    com: np.ndarray
    mass: float
    extra_wrench: np.ndarray
    manipulator: Manipulator
    q: np.ndarray
    effort_controlled: np.ndarray
    joint_velocity: np.ndarray
    joint_effort: np.ndarray
    mu: float
    contact_mu: tuple
    contact_tolerance: float

    def with_q(self, q) -> "GeometricScene":
        """The same scene with the joints at ``q`` (shape (n_j,))."""
        return replace(self, q=_frozen(check_joint_positions(self.manipulator, q)))

    def body_name(self, body: int) -> str:
        """``"palm"`` for -1, else the name of the joint moving link ``body``."""
        return _PALM if body < 0 else self.manipulator.joints[body].name


def _frozen(a) -> np.ndarray:
    a = np.array(a, copy=True)
    a.setflags(write=False)
    return a


def _nonnegative(value, field: str, what: str) -> float:
    x = number(value, field)
    if x < 0:
        raise SceneError(f"{field}: expected a nonnegative {what}; got {x}")
    return x


def _polygon(value, field: str) -> np.ndarray:
    if not isinstance(value, (list, tuple)):
        raise SceneError(f"{field}: expected a list of [x, y] vertices; got {value!r}")
    return check_polygon(np.array([vector(p, f"{field}[{i}]", 2) for i, p in enumerate(value)]).reshape(-1, 2), field)


def _table(doc, key, allowed, field=None) -> dict:
    field = field or key
    if key not in doc:
        raise SceneError(f"{field}: missing")
    check_keys(doc[key], allowed, field)
    return doc[key]


def _required(d, key, field):
    if key not in d:
        raise SceneError(f"{field}.{key}: missing")
    return d[key]


def _parse_joint(jd, i, names):
    f = f"joints[{i}]"
    check_keys(jd, _JOINT_KEYS, f)
    name = jd.get("name", f"j{i}")
    if not isinstance(name, str) or not name:
        raise SceneError(f"{f}.name: expected a non-empty string; got {name!r}")
    if name == _PALM:
        raise SceneError(f"{f}.name: {_PALM!r} is reserved for the palm; choose another name")
    if name in names:
        raise SceneError(f"{f}.name: expected a unique name; {name!r} is also joints[{names.index(name)}].name")
    kind = _required(jd, "type", f)
    if kind not in JOINT_KINDS:
        raise SceneError(f"{f}.type: expected 'revolute' or 'prismatic'; got {kind!r}")
    parent = _required(jd, "parent", f)
    if parent == -1 and not isinstance(parent, bool):
        parent_index = -1
    elif isinstance(parent, str) and parent in names:
        parent_index = names.index(parent)
    else:
        raise SceneError(f"{f}.parent: expected -1 (the base) or the name of an earlier joint {names}; got {parent!r}")
    origin = vector(_required(jd, "origin", f), f"{f}.origin", 3)
    q = number(jd.get("q", 0.0), f"{f}.q")
    control = _required(jd, "control", f)
    if control not in ("velocity", "effort"):
        raise SceneError(f"{f}.control: expected 'velocity' or 'effort'; got {control!r}")
    if control not in jd:
        raise SceneError(f"{f}.{control}: missing (a {control}-controlled joint needs its {control})")
    inputs = {key: number(jd[key], f"{f}.{key}") if key in jd else np.nan for key in ("velocity", "effort")}
    link = jd.get("link", {})
    check_keys(link, _LINK_KEYS, f"{f}.link")
    shape = _polygon(link["polygon"], f"{f}.link.polygon") if "polygon" in link else None
    mass = _nonnegative(link.get("mass", 0.0), f"{f}.link.mass", "mass (kg)")
    com = vector(link.get("com", [0.0, 0.0]), f"{f}.link.com", 2)
    joint = make_joint(name, kind, parent_index, origin, mass, com, shape, index=i)
    return joint, q, control == "effort", inputs["velocity"], inputs["effort"]


def geometric_scene_from_dict(spec: dict) -> GeometricScene:
    """Validate a geometric-form document (see the module docstring) into a :class:`GeometricScene`.

    Raises
    ------
    SceneError
        Naming the field with its path, e.g. ``joints[1].type: expected
        'revolute' or 'prismatic'; got 'ball'``; unknown fields are named too.
    """
    check_keys(spec, _TOP_KEYS, "scene")
    for key in ("name", "description"):
        if key in spec and not isinstance(spec[key], str):
            raise SceneError(f"{key}: expected a string; got {spec[key]!r}")
    gravity = _nonnegative(spec.get("gravity", 9.81), "gravity", "magnitude (m/s^2, acting along -y)")
    tol = number(spec.get("contact_tolerance", CONTACT_TOL), "contact_tolerance")
    if tol <= 0:
        raise SceneError(f"contact_tolerance: expected a positive distance (m); got {tol}")
    mu = check_friction(number(spec.get("mu", 0.0), "mu"), "mu")

    wp = _table(spec, "workpiece", _WORKPIECE_KEYS)
    polygon = _polygon(_required(wp, "polygon", "workpiece"), "workpiece.polygon")
    com = vector(_required(wp, "com", "workpiece"), "workpiece.com", 2)
    mass = _nonnegative(_required(wp, "mass", "workpiece"), "workpiece.mass", "mass (kg)")
    extra = vector(wp.get("extra_wrench", [0.0, 0.0, 0.0]), "workpiece.extra_wrench", 3)
    palm = None
    if "palm" in spec:
        palm = _polygon(_required(_table(spec, "palm", _PALM_KEYS), "polygon", "palm"), "palm.polygon")

    joint_docs = spec.get("joints")
    if not isinstance(joint_docs, list) or not joint_docs:
        raise SceneError(f"joints: expected a non-empty list of joints; got {joint_docs!r}")
    joints, names, qs, effort, jvel, jeff = [], [], [], [], [], []
    for i, jd in enumerate(joint_docs):
        joint, q, e, v, t = _parse_joint(jd, i, names)
        joints.append(joint)
        names.append(joint.name)
        qs.append(q)
        effort.append(e)
        jvel.append(np.nan if e else v)
        jeff.append(t if e else np.nan)
    man = make_manipulator(joints, base_shape=palm, gravity=gravity)

    overrides = spec.get("contact_mu", [])
    if not isinstance(overrides, list):
        raise SceneError(f"contact_mu: expected a list of {{index, mu}} tables; got {overrides!r}")
    contact_mu, seen = [], {}
    for k, od in enumerate(overrides):
        f = f"contact_mu[{k}]"
        check_keys(od, _CONTACT_MU_KEYS, f)
        index = _required(od, "index", f)
        if isinstance(index, bool) or not isinstance(index, int) or index < 0:
            raise SceneError(f"{f}.index: expected a nonnegative integer contact index; got {index!r}")
        if index in seen:
            raise SceneError(f"{f}.index: contact {index} already overridden by contact_mu[{seen[index]}]")
        seen[index] = k
        contact_mu.append((index, check_friction(number(_required(od, "mu", f), f"{f}.mu"), f"{f}.mu")))

    return GeometricScene(
        workpiece=_frozen(polygon),
        com=_frozen(com),
        mass=mass,
        extra_wrench=_frozen(extra),
        manipulator=man,
        q=_frozen(np.array(qs, dtype=float)),
        effort_controlled=_frozen(np.array(effort, dtype=bool)),
        joint_velocity=_frozen(np.array(jvel, dtype=float)),
        joint_effort=_frozen(np.array(jeff, dtype=float)),
        mu=mu,
        contact_mu=tuple(contact_mu),
        contact_tolerance=tol,
    )


def find_scene_contacts(gs: GeometricScene) -> list[FoundContact]:
    """Contacts between the workpiece and the palm and links at ``gs.q`` (see :func:`~qsplan.mechanics.model.geometry.find_contacts`)."""
    man = gs.manipulator
    bodies = [] if man.base_shape is None else [(-1, base_polygon(man))]
    bodies += [(k, p) for k, p in enumerate(link_polygons(man, gs.q)) if p is not None]
    names = {-1: _PALM, **{k: j.name for k, j in enumerate(man.joints)}}
    return find_contacts(Polygon(gs.workpiece), bodies, tol=gs.contact_tolerance, body_names=names)


def scene_from_geometric_scene(gs: GeometricScene, contacts=None) -> Scene:
    """The :class:`Scene` (eqs. 1-5) of a geometric scene.

    Parameters
    ----------
    gs : GeometricScene
    contacts : list of FoundContact, optional
        Precomputed :func:`find_scene_contacts` result.

    Returns
    -------
    Scene
        ``W_n, W_t`` from the contact points and normals (eq. 1); ``J_n, J_t``
        from :func:`~qsplan.mechanics.model.manipulator.contact_jacobian` (zero rows on the
        palm, eq. 5); ``g_obj`` = the workpiece weight at ``com`` plus
        ``extra_wrench`` (eq. 2); ``g_man`` = the link weights' joint efforts (eq. 3).

    Raises
    ------
    SceneError
        If no contact is found, a ``contact_mu`` index is out of range, or the
        geometry is ambiguous or penetrating (from ``find_contacts``).
    """
    man = gs.manipulator
    contacts = find_scene_contacts(gs) if contacts is None else list(contacts)
    n_c = len(contacts)
    if n_c == 0:
        raise SceneError(
            f"contacts: none found between the workpiece and the palm or links "
            f"(within contact_tolerance {gs.contact_tolerance:g} m)"
        )
    Wn, Wt = wrench_matrices([c.point for c in contacts], [c.normal for c in contacts])
    Jn = np.zeros((n_c, man.n_joints))
    Jt = np.zeros((n_c, man.n_joints))
    for i, c in enumerate(contacts):
        if c.body >= 0:
            Jn[i], Jt[i] = contact_jacobian(man, gs.q, c.body, c.point, c.normal)
    mu = np.full(n_c, gs.mu)
    for k, (index, m) in enumerate(gs.contact_mu):
        if index >= n_c:
            raise SceneError(f"contact_mu[{k}].index: expected a contact index below {n_c} ({n_c} contacts found); got {index}")
        mu[index] = m
    g_obj = point_wrench(gs.com, (0.0, -gs.mass * man.gravity)) + gs.extra_wrench
    return make_scene(
        Wn, Wt, Jn, Jt, mu, g_obj,
        g_man=gravity_efforts(man, gs.q),
        effort_controlled=gs.effort_controlled,
        joint_velocity=gs.joint_velocity,
        joint_effort=gs.joint_effort,
        joint_names=man.joint_names,
        contact_names=[f"{gs.body_name(c.body)}:{i}" for i, c in enumerate(contacts)],
    )  # fmt: skip


def scene_from_geometry(spec: dict) -> Scene:
    """Build a :class:`Scene` from a geometric-form document (schema in the module docstring).

    Raises
    ------
    SceneError
        Naming the offending field with its path.
    """
    return scene_from_geometric_scene(geometric_scene_from_dict(spec))
