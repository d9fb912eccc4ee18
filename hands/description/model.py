"""A hand described by data: a palm and two serial fingers of revolute and prismatic joints (issue 15).

The paper's hand (Section 5.2, Fig. 9) is one instance: a palm and two single-link revolute
fingers.  A :class:`HandDescription` holds any hand of that shape that the mechanics can model
(:class:`qsplan.mechanics.model.manipulator.Manipulator`: a planar tree of joints with link
polygons): a fixed palm whose top edge is ``y = 0`` (the workpiece rests there), and two fingers,
``"left"`` then ``"right"``, each a serial chain from the palm to its tip, with each joint's
limits and speed.

:func:`make_hand_description` is the one validator: the file loader
(:mod:`qsplan.hands.description.files`) and the two-finger form
(:mod:`qsplan.hands.description.two_finger_form`) build through it, every number inside its plausible
range (:data:`HAND_RANGES`).  Errors are :class:`~qsplan.mechanics.errors.SceneError` naming the field
path, e.g. ``fingers[0].joints[1].limits: expected [lo, hi] with lo < hi (rad); got [2, 1]``.

All quantities are SI: m, kg, rad (m for a prismatic joint), rad/s (m/s), m/s^2.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from shapely.geometry import Polygon

from qsplan.mechanics.errors import SceneError
from qsplan.mechanics.model.fields import in_range, number, short_repr, vector
from qsplan.mechanics.model.geometry import check_polygon
from qsplan.mechanics.model.manipulator import JOINT_KINDS, Manipulator, link_poses, make_joint, make_manipulator

__all__ = [
    "FINGER_NAMES",
    "PALM_TOP_TOL",
    "HAND_RANGES",
    "JOINT_KEYS",
    "LINK_KEYS",
    "FingerChain",
    "HandDescription",
    "make_hand_description",
    "joint_frames",
]

#: The fingers of a hand, in order.
FINGER_NAMES = ("left", "right")

#: How far (m) the palm's highest vertices may lie from ``y = 0``: decimal coordinates written in a
#: file are exact to ~1e-17 m at hand scale, so 1e-12 m is rounding, not a tilted palm.
PALM_TOP_TOL = 1e-12

#: Plausible range ``(lo, hi, unit)`` of every number of a hand; outside it a value is a mistake (a unit
#: slip, a typo), not a hand (100 t links were planned at -35,140 N m, 1e5 rad limits drawn).  Where the
#: paper hand's parameter form has the quantity, the numbers are ``TASK_RANGES``'
#: (:mod:`qsplan.planner.task.fields`): a file may not allow what a task's ``[hand]`` refuses.
HAND_RANGES = {
    # the parameter form's palm [-P, P] x [-T, 0], P and T from a millimetre to a metre (TASK_RANGES' size)
    "palm_vertex": (-1.0, 1.0, "m"),
    "palm_width": (2e-3, 2.0, "m"),  # 2 P
    "palm_thickness": (1e-3, 1.0, "m"),  # T
    # a finger's first joint above the palm's lowest point (from under the palm no finger reaches the
    # workpiece on top) and at most a metre (size) above it
    "palm_joint_height": (0.0, 1.0, "m"),
    # a joint's origin x, y: within a metre of the previous joint, whose link is at most a metre long
    # (size); a first joint's x on a palm at most a metre either side (position)
    "joint_offset": (-1.0, 1.0, "m"),
    "origin_angle": (-2.0 * np.pi, 2.0 * np.pi, "rad"),  # a frame turned up to a full turn (bundled jaw: 3.40 rad)
    # a link's polygon and centre of mass within a metre of its joint, the link a millimetre to a metre (size)
    "link_vertex": (-1.0, 1.0, "m"),
    "link_size": (1e-3, 1.0, "m"),  # the longer side of the link's bounding box
    "com_offset": (-1.0, 1.0, "m"),
    "revolute_limit": (-np.pi, np.pi, "rad"),  # joint_limit: a half turn either way
    "prismatic_limit": (-1.0, 1.0, "m"),  # a slide of at most a metre either way (position)
    "revolute_speed": (1e-3, 10.0, "rad/s"),  # joint_speed: slower is holding still; 10 is a fast servo
    # workpiece_speed: a jaw carries the workpiece along; beyond 0.5 m/s its inertia breaks the quasistatic model
    "prismatic_speed": (1e-4, 0.5, "m/s"),
    "link_mass": (0.0, 100.0, "kg"),  # finger_mass
    "gravity": (0.0, 100.0, "m/s^2"),  # gravity: Earth's 9.81; 100 is 10 g
    "joints_per_finger": (1, 6, "joints"),  # a human finger has four; the planner's state holds every free joint
    "polygon_vertices": (3, 64, "vertices"),  # as a task's workpiece: collision checks visit every edge
}

#: The fields of a joint table, and of its link table.
JOINT_KEYS = ("name", "type", "origin", "limits", "speed", "link")
LINK_KEYS = ("polygon", "mass", "com")
_FINGER_KEYS = ("name", "joints")
_UNITS = {"revolute": "rad", "prismatic": "m"}


@dataclass(frozen=True, slots=True, eq=False)
class FingerChain:
    """One finger: a serial chain of joints from the palm to the tip.

    Attributes
    ----------
    name : str
        ``"left"`` or ``"right"``.
    joints : tuple of int
        Indices of the finger's joints in the manipulator, base to tip.
    """

    name: str
    joints: tuple


@dataclass(frozen=True, slots=True, eq=False)
class HandDescription:
    """A palm and two fingers.  Build it with :func:`make_hand_description` (which validates).

    Attributes
    ----------
    name : str
    manipulator : Manipulator
        All joints, the left finger's first (base to tip), then the right finger's; ``base_shape``
        is the palm polygon (world frame, m, top edge on ``y = 0``); ``gravity`` (m/s^2 along -y).
    fingers : tuple of FingerChain, shape (2,)
        Left, right.
    joint_limits : ndarray, shape (n_j, 2)
        ``[lo, hi]`` of each joint, ``lo < hi`` (rad; m for a prismatic joint); read-only.
    joint_speeds : ndarray, shape (n_j,)
        Largest speed of each joint, positive (rad/s; m/s for a prismatic joint); read-only.
    source : str
        Where it came from: a file path, ``"bundled:<name>"`` or ``"inline"``.
    """

    name: str
    manipulator: Manipulator
    fingers: tuple
    joint_limits: np.ndarray
    joint_speeds: np.ndarray
    source: str

    @property
    def n_joints(self) -> int:
        return self.manipulator.n_joints

    @property
    def joint_names(self) -> tuple:
        """Joint names, in joint order."""
        return self.manipulator.joint_names

    @property
    def joint_kinds(self) -> tuple:
        """``"revolute"`` or ``"prismatic"`` per joint."""
        return tuple(j.kind for j in self.manipulator.joints)

    @property
    def joint_units(self) -> tuple:
        """Unit of each joint's position: ``"rad"`` (revolute) or ``"m"`` (prismatic)."""
        return tuple(_UNITS[k] for k in self.joint_kinds)

    @property
    def finger_of_joint(self) -> tuple:
        """The name of the finger (``"left"``/``"right"``) of each joint, in joint order."""
        out = [""] * self.n_joints
        for finger in self.fingers:
            for i in finger.joints:
                out[i] = finger.name
        return tuple(out)

    @property
    def palm(self) -> np.ndarray:
        """The palm polygon, world frame (m), shape (k, 2); read-only."""
        return _frozen(self.manipulator.base_shape)

    @property
    def palm_top(self) -> tuple:
        """``(lo, hi)``: the x-extent (m) of the palm's top edge ``y = 0``."""
        p = self.palm
        xs = p[p[:, 1] == 0.0, 0]
        return float(xs.min()), float(xs.max())

    @property
    def mid_limits(self) -> np.ndarray:
        """Each joint at the middle of its limits (rad or m), shape (n_j,)."""
        return self.joint_limits.mean(axis=1)


def joint_frames(desc: HandDescription, q) -> np.ndarray:
    """World poses of the joint frames (fixed to each joint's parent link) at ``q``.

    A revolute joint's frame shares its origin with its link's frame; a prismatic joint's frame
    is where its link's frame is at ``q_i = 0``, and the link slides along the frame's +x.

    Parameters
    ----------
    desc : HandDescription
    q : array-like, shape (n_j,)
        Joint positions (rad or m).

    Returns
    -------
    ndarray, shape (n_j, 3)
        ``(x, y, angle)`` of each joint frame (m, m, rad).
    """
    poses = link_poses(desc.manipulator, q).copy()
    q = np.asarray(q, dtype=float)
    for i, kind in enumerate(desc.joint_kinds):
        if kind == "revolute":
            poses[i, 2] -= q[i]
        else:
            poses[i, :2] -= q[i] * np.array([np.cos(poses[i, 2]), np.sin(poses[i, 2])])
    return poses


def _frozen(a) -> np.ndarray:
    a = np.array(a, dtype=float, copy=True)
    a.setflags(write=False)
    return a


def _path(prefix: str, key: str) -> str:
    return f"{prefix}.{key}" if prefix else key


def _plain(value):
    """numpy arrays as lists, so that the Python API takes what a file gives."""
    return value.tolist() if isinstance(value, np.ndarray) else value


def check_unknown(table, allowed, prefix: str) -> None:
    """Refuse a key of ``table`` outside ``allowed``, naming its path (``prefix.key``)."""
    unknown = sorted(set(table) - set(allowed), key=str)
    if unknown:
        key = str(unknown[0]) if len(str(unknown[0])) <= 40 else short_repr(str(unknown[0]))  # a 4 MB key: one short line
        raise SceneError(f"{_path(prefix, key)}: unknown field; expected some of {', '.join(allowed)}")


def _table(value, field: str) -> dict:
    if not isinstance(value, dict):
        raise SceneError(f"{field}: expected a table; got {short_repr(value)}")
    return value


def _required(table: dict, key: str, prefix: str, what: str):
    if key not in table:
        raise SceneError(f"{_path(prefix, key)}: missing ({what})")
    return table[key]


def _ranged(value, field: str, kind: str, shift: float = 0.0, where: str = "", slips: bool = True):
    """``value`` inside ``HAND_RANGES[kind]`` (moved by ``shift``): :func:`in_range`, which names a unit slip."""
    lo, hi, unit = HAND_RANGES[kind]
    source = f"qsplan.hands.description.model.HAND_RANGES[{kind!r}]{where}"
    return in_range(value, field, lo + shift, hi + shift, unit, source, SceneError, slips)


def _polygon(value, field: str, kind: str) -> np.ndarray:
    """A polygon whose vertices lie in ``HAND_RANGES[kind]`` (m)."""
    value = _plain(value)
    if not isinstance(value, (list, tuple)):
        raise SceneError(f"{field}: expected a polygon, a list of [x, y] vertices (m); got {short_repr(value)}")
    if len(value) > HAND_RANGES["polygon_vertices"][1]:  # fewer than 3 distinct ones: check_polygon says so
        _ranged(len(value), f"{field} (its number of vertices)", "polygon_vertices")
    vertices = [_ranged(vector(_plain(p), f"{field}[{i}]", 2, np.inf), f"{field}[{i}]", kind) for i, p in enumerate(value)]
    return check_polygon(np.array(vertices).reshape(-1, 2), field)


def _palm(palm, prefix: str) -> np.ndarray:
    """The palm polygon (given as a polygon or as a ``{polygon}`` table), its top vertices snapped to ``y = 0``."""
    field = _path(prefix, "palm")
    if isinstance(palm, dict):
        check_unknown(palm, ("polygon",), field)
        field = _path(field, "polygon")
        palm = _required(palm, "polygon", _path(prefix, "palm"), "the palm polygon [[x, y], ...] (m)")
    v = _polygon(palm, field, "palm_vertex")
    top = np.abs(v[:, 1]) <= PALM_TOP_TOL
    y_max = float(v[:, 1].max())
    if abs(y_max) > PALM_TOP_TOL:
        raise SceneError(f"{field}: expected the top edge on y = 0 (the workpiece rests there); got max y = {y_max:g} m")
    if top.sum() < 2:
        raise SceneError(f"{field}: expected a horizontal top edge on y = 0; only the vertex {v[top][0].tolist()} "
                         "reaches it")
    edges = int(np.sum(top & np.roll(top, -1)))
    if edges != top.sum() - 1:
        raise SceneError(f"{field}: expected one horizontal top edge on y = 0; got {top.sum() - edges} separate pieces")
    _ranged(float(np.ptp(v[:, 0])), f"{field} (its width)", "palm_width", slips=False)
    _ranged(-float(v[:, 1].min()), f"{field} (its thickness below y = 0)", "palm_thickness", slips=False)
    v = v.copy()
    v[top, 1] = 0.0
    return v


def _joint(jd, f: str, parent: int, index: int, seen: dict, palm_bottom: float):
    """One joint table -> (Joint, limits (2,), speed); ``seen`` maps names to their field paths.

    ``palm_bottom``: the palm's lowest y (m), below which a first joint (``parent == -1``) may not sit.
    """
    jd = _table(jd, f)
    check_unknown(jd, JOINT_KEYS, f)
    name = _required(jd, "name", f, "a name unique in the hand")
    if not isinstance(name, str) or not name.strip():
        raise SceneError(f"{f}.name: expected a non-empty string; got {short_repr(name)}")
    if name == "palm":
        raise SceneError(f"{f}.name: 'palm' is reserved for the palm; choose another name")
    if name in seen:
        raise SceneError(f"{f}.name: expected a unique name; {name!r} is also {seen[name]}.name")
    seen[name] = f
    kind = _required(jd, "type", f, "'revolute' or 'prismatic'")
    if kind not in JOINT_KINDS:
        raise SceneError(f"{f}.type: expected 'revolute' or 'prismatic'; got {short_repr(kind)}")
    unit = _UNITS[kind]
    origin = vector(_plain(_required(jd, "origin", f, "[x, y, angle] (m, m, rad) in the previous link's frame")),
                    f"{f}.origin", 3, np.inf)  # fmt: skip
    _ranged(origin[0], f"{f}.origin[0]", "joint_offset")
    if parent == -1:
        _ranged(origin[1], f"{f}.origin[1]", "palm_joint_height", palm_bottom, f" above the palm's bottom y = {palm_bottom:g} m")
    else:
        _ranged(origin[1], f"{f}.origin[1]", "joint_offset")
    _ranged(origin[2], f"{f}.origin[2]", "origin_angle")
    limits = vector(_plain(_required(jd, "limits", f, f"[lo, hi] ({unit})")), f"{f}.limits", 2, np.inf)
    if not limits[0] < limits[1]:
        raise SceneError(f"{f}.limits: expected [lo, hi] with lo < hi ({unit}); got [{limits[0]:g}, {limits[1]:g}]")
    _ranged(limits, f"{f}.limits", f"{kind}_limit")
    speed = number(_required(jd, "speed", f, f"the joint's largest speed ({unit}/s)"), f"{f}.speed", np.inf)
    _ranged(speed, f"{f}.speed", f"{kind}_speed")  # positive
    lf = f"{f}.link"
    link = _table(_required(jd, "link", f, "the link's polygon"), lf)
    check_unknown(link, LINK_KEYS, lf)
    shape = _polygon(_required(link, "polygon", lf, "[[x, y], ...] (m) in the link frame"), f"{lf}.polygon", "link_vertex")
    lower, upper = shape.min(axis=0), shape.max(axis=0)
    _ranged(float(np.max(upper - lower)), f"{lf}.polygon (the longer side of its bounding box)", "link_size", slips=False)
    mass = _ranged(number(link.get("mass", 0.0), f"{lf}.mass", np.inf), f"{lf}.mass", "link_mass")  # nonnegative
    if "com" in link:
        com = _ranged(vector(_plain(link["com"]), f"{lf}.com", 2, np.inf), f"{lf}.com", "com_offset")
        if np.any(com < lower - PALM_TOP_TOL) or np.any(com > upper + PALM_TOP_TOL):  # to decimal rounding
            raise SceneError(f"{lf}.com: expected a point of the polygon's bounding box [{lower[0]:g}, {upper[0]:g}] x "
                             f"[{lower[1]:g}, {upper[1]:g}] m (a centre of mass lies in its body); got {com.tolist()}")
    else:
        com = np.array(Polygon(shape).centroid.coords[0])
    return make_joint(name, kind, parent, origin, mass, com, shape, index=index), limits, speed


def make_hand_description(name, palm, fingers, gravity=9.81, source="inline", *, field="") -> HandDescription:
    """Validate and build a :class:`HandDescription`.

    Parameters
    ----------
    name : str
        Non-empty.
    palm : array-like, shape (k, 2), or dict
        The palm polygon (world frame, m), or a table ``{"polygon": ...}`` as in a hand file.  A simple
        polygon whose highest vertices lie on ``y = 0`` (within :data:`PALM_TOP_TOL`) and form one
        horizontal top edge (they are set to exactly 0).
    fingers : sequence of dict, length 2
        ``{"name": "left", "joints": [...]}`` then ``{"name": "right", ...}``.  Each joint is a dict
        ``{"name", "type", "origin", "limits", "speed", "link"}``: ``type`` ``"revolute"`` or
        ``"prismatic"`` (slides along its frame's +x); ``origin`` ``[x, y, angle]`` (m, m, rad) in the
        previous link's frame (the first joint's: the palm's = the world); ``limits`` ``[lo, hi]``, ``lo < hi``
        (rad, or m); ``speed`` > 0 (rad/s, or m/s); ``link`` ``{"polygon", "mass", "com"}`` with the
        polygon (link frame, m), the mass (kg, >= 0, default 0) and the centre of mass (link frame, m,
        default the polygon's centroid).  Joint names are unique in the hand; ``"palm"`` is reserved.
        Every number, size and count inside :data:`HAND_RANGES`.
    gravity : float
        m/s^2 along -y, >= 0.
    source : str
        Recorded in :attr:`HandDescription.source`.
    field : str
        Prefix of the field paths in errors (``"hand"`` inside a task; ``""`` at a file's top level).

    Raises
    ------
    SceneError
        Naming the field path, e.g. ``hand.fingers[1].joints[0].type: expected 'revolute' or 'prismatic'; got 'ball'``.
    """
    if not isinstance(name, str) or not name.strip():
        raise SceneError(f"{_path(field, 'name')}: expected a non-empty string; got {short_repr(name)}")
    if not isinstance(source, str):
        raise SceneError(f"source: expected a string; got {short_repr(source)}")
    g = _ranged(number(gravity, _path(field, "gravity"), np.inf), _path(field, "gravity"), "gravity")  # along -y
    palm = _palm(palm, field)
    ff = _path(field, "fingers")
    fingers = _plain(fingers)
    if not isinstance(fingers, (list, tuple)) or len(fingers) != 2:
        got = f"{len(fingers)}" if isinstance(fingers, (list, tuple)) else short_repr(fingers)
        raise SceneError(f"{ff}: expected two fingers, 'left' then 'right'; got {got}")
    joints, limits, speeds, chains, seen = [], [], [], [], {}
    for k, (fd, expected) in enumerate(zip(fingers, FINGER_NAMES)):
        f = f"{ff}[{k}]"
        fd = _table(fd, f)
        check_unknown(fd, _FINGER_KEYS, f)
        got = _required(fd, "name", f, f"{expected!r}")
        if got != expected:
            raise SceneError(f"{f}.name: expected {expected!r} (fingers are 'left' then 'right'); got {short_repr(got)}")
        jds = _plain(_required(fd, "joints", f, "a list of joints, base to tip"))
        if not isinstance(jds, (list, tuple)) or not jds:
            raise SceneError(f"{f}.joints: expected a non-empty list of joints, base to tip; got {short_repr(jds)}")
        _ranged(len(jds), f"{f}.joints (their number)", "joints_per_finger")
        indices = []
        for m, jd in enumerate(jds):
            parent = indices[-1] if indices else -1
            joint, lim, speed = _joint(jd, f"{f}.joints[{m}]", parent, len(joints), seen, float(palm[:, 1].min()))
            indices.append(len(joints))
            joints.append(joint)
            limits.append(lim)
            speeds.append(speed)
        chains.append(FingerChain(expected, tuple(indices)))
    man = make_manipulator(joints, base_shape=palm, gravity=g)
    return HandDescription(name.strip(), man, tuple(chains), _frozen(np.reshape(limits, (-1, 2))), _frozen(speeds), source)
