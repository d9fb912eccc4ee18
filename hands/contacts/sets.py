"""Scenes of a hand at any workpiece pose with an explicit, named contact set (issue 23; Section 3, eqs. 1-5).

A contact is named by what touches (:class:`ContactSpec`): the body (``"palm"``, or the ``"left"`` or ``"right"``
finger's last link), the workpiece's feature (a vertex or an edge of its polygon, the hand's internal numbering,
``hand.workpiece``) and the body's feature (a vertex or an edge of the body's polygon, its ring as the hand
writes it: the palm's ``base_shape``, the link's ``link_shape``).  One feature is a vertex and the other an edge:
a vertex on an edge.  A body edge lying flush on a workpiece edge is **two** contacts, at the ends of their
overlap; :func:`flush_contacts` says which features those ends are at a configuration.

The paper's conventions: the normal ``n_i`` points into the workpiece (the body edge's outward normal for a
workpiece vertex on it, the workpiece edge's inward normal for a body vertex on it), ``t_i`` is ``n_i`` turned
by +90 degrees, ``W_i = [[n_i, t_i], [r_i x n_i, r_i x t_i]]`` about the world origin (eq. 1) and
``J_i = [n_i^T; t_i^T] J_p`` with ``J_p`` the body point's Jacobian (eq. 5, zero rows on the palm), so that
``v_i = W_i^T nu - J_i thetadot`` (eq. 6) is the workpiece point's velocity relative to the body's, in
``(n_i, t_i)``, with ``nu`` the workpiece's twist at the world origin.  The matrices come from the mechanics'
one implementation (:func:`qsplan.mechanics.wrench_matrices`, :func:`qsplan.mechanics.model.manipulator.contact_jacobian`).
Units SI (m, rad, kg, N, N m).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qsplan.hands.formations.registry import BODIES
from qsplan.mechanics.errors import QsplanError
from qsplan.mechanics.model.geometry import CONTACT_TOL

__all__ = ["FACING_TOL", "FEATURE_KINDS", "FLUSH_ANGLE_TOL", "ContactSet", "ContactSpec", "body_ring", "contact_set_scene",
           "finger_inner_edge", "finger_link", "flush_contacts", "locate_contacts", "palm_top_edge"]

#: What a feature is: a polygon's vertex, or its edge from that vertex to the next.
FEATURE_KINDS = ("vertex", "edge")

#: Angle (rad) within which a body edge and a workpiece edge count as parallel, i.e. flush (:func:`flush_contacts`):
#: the contact tolerance (:data:`qsplan.mechanics.model.geometry.CONTACT_TOL`, 1e-6 m) over a 1 cm edge; closed-form
#: flush configurations are parallel to ~1e-15 rad.
FLUSH_ANGLE_TOL = 1e-4

#: Tolerance on a unit normal's components (dimensionless) when finding the edge facing a direction
#: (:func:`palm_top_edge`, :func:`finger_inner_edge`): hand files write axis-aligned rectangles in decimals.
FACING_TOL = 1e-9


def _feature(value, field: str) -> tuple:
    """``(kind, index)`` from ``("vertex", 3)`` or ``"vertex:3"``, checked."""
    if isinstance(value, str) and value.count(":") == 1:
        kind, _, index = value.partition(":")
        value = (kind, int(index)) if index.strip().isdigit() else (kind, index)
    if not (isinstance(value, (tuple, list)) and len(value) == 2):
        raise QsplanError(f"{field}: expected (KIND, INDEX) or 'KIND:INDEX' with KIND one of {', '.join(FEATURE_KINDS)}; "
                          f"got {value!r}")  # fmt: skip
    kind, index = value
    if kind not in FEATURE_KINDS:
        raise QsplanError(f"{field}: the kind must be one of {', '.join(FEATURE_KINDS)}; got {kind!r}")
    if isinstance(index, (bool, np.bool_)) or not isinstance(index, (int, np.integer)) or index < 0:
        raise QsplanError(f"{field}: the index must be a nonnegative integer; got {index!r}")
    return str(kind), int(index)


@dataclass(frozen=True, slots=True)
class ContactSpec:
    """One contact of a contact set: a vertex of one body on an edge of the other.

    Attributes
    ----------
    name : str
        Its name in the scene (``Scene.contact_names``), reports and plots.
    body : str
        One of :data:`qsplan.hands.formations.registry.BODIES`: the palm, or a finger's last link.
    workpiece : (str, int)
        ``("vertex", k)`` or ``("edge", k)`` (edge ``k`` runs from vertex ``k`` to ``k + 1``); ``"vertex:k"`` is
        accepted and stored as the pair.  The hand's internal numbering.
    feature : (str, int)
        The body's feature, the same form, numbered along the body's polygon as the hand writes it.

    Raises
    ------
    QsplanError
        Naming the contact and the field: an unknown body or feature kind, a bad index, or not exactly one vertex
        and one edge (two vertices have no normal; two edges are the two contacts of :func:`flush_contacts`).
    """

    name: str
    body: str
    workpiece: tuple
    feature: tuple

    def __post_init__(self):
        if not isinstance(self.name, str) or not self.name:
            raise QsplanError(f"contact name: expected a nonempty string; got {self.name!r}")
        where = f"contact {self.name!r}"
        if self.body not in BODIES:
            raise QsplanError(f"{where}.body: expected one of {', '.join(BODIES)}; got {self.body!r}")
        wp = _feature(self.workpiece, f"{where}.workpiece")
        ft = _feature(self.feature, f"{where}.feature")
        if wp[0] == ft[0]:
            why = ("a vertex on a vertex has no normal" if wp[0] == "vertex" else
                   "an edge flush on an edge is two contacts, at the ends of the overlap (flush_contacts)")
            plural = "vertices" if wp[0] == "vertex" else "edges"
            raise QsplanError(f"{where}: expected a vertex on an edge (one feature of each kind); got two {plural}: {why}")
        object.__setattr__(self, "workpiece", wp)
        object.__setattr__(self, "feature", ft)

    @property
    def workpiece_vertex(self) -> bool:
        """Whether the workpiece's vertex touches the body's edge (else the body's vertex the workpiece's edge)."""
        return self.workpiece[0] == "vertex"


@dataclass(frozen=True, slots=True, eq=False)
class ContactSet:
    """A contact set located at one configuration (:func:`locate_contacts`).

    Attributes
    ----------
    specs : tuple of ContactSpec
        In scene order.
    points : ndarray, shape (n_c, 2)
        Contact points ``r_i``, world frame (m): the touching vertex.
    normals : ndarray, shape (n_c, 2)
        Unit normals into the workpiece (eq. 1).
    links : ndarray of int, shape (n_c,)
        The manipulator link carrying each body's point; -1 for the palm.
    gaps : ndarray, shape (n_c,)
        Signed distance (m) of the touching vertex from its edge's line, positive outside the edge's polygon.
    along : ndarray, shape (n_c,)
        Position (m) of the vertex's foot along its edge, from the edge's first vertex.
    edge_lengths : ndarray, shape (n_c,)
        Each contact edge's length (m).
    """

    specs: tuple
    points: np.ndarray
    normals: np.ndarray
    links: np.ndarray
    gaps: np.ndarray
    along: np.ndarray
    edge_lengths: np.ndarray

    @property
    def names(self) -> tuple:
        return tuple(s.name for s in self.specs)


def _ccw(P) -> bool:
    x, y = P[:, 0], P[:, 1]
    return float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y)) > 0.0


def finger_link(hand, body: str) -> int:
    """The manipulator link (joint index) of a finger's last link; -1 for the palm."""
    if body not in BODIES:
        raise QsplanError(f"body: expected one of {', '.join(BODIES)}; got {body!r}")
    if body == "palm":
        return -1
    return hand.joint_names.index(hand.finger_joint_names[BODIES.index(body) - 1][-1])


def body_ring(hand, body: str, q) -> np.ndarray:
    """The body's polygon in the world at joint positions ``q`` (m), shape (k, 2), its rows as the hand writes them."""
    from qsplan.hands.geometry.workpiece import rotation
    from qsplan.mechanics.model.manipulator import link_poses

    man = hand.manipulator
    link = finger_link(hand, body)
    if link < 0:
        if man.base_shape is None:
            raise QsplanError("body: the hand has no palm polygon")
        return np.asarray(man.base_shape, dtype=float)
    shape = man.joints[link].link_shape
    if shape is None:
        raise QsplanError(f"body: the {body} finger's last link has no polygon")
    x, y, angle = link_poses(man, q)[link]
    return np.asarray(shape, dtype=float) @ rotation(angle).T + [x, y]


def _outward(P, k):
    """Edge ``k`` of polygon ``P``: its start, unit direction, length and outward unit normal."""
    a, b = P[k], P[(k + 1) % len(P)]
    d = b - a
    length = float(np.hypot(*d))
    e = d / length
    m = np.array([e[1], -e[0]]) if _ccw(P) else np.array([-e[1], e[0]])
    return a, e, length, m


def _frozen(a):
    a = np.array(a, copy=True)
    a.setflags(write=False)
    return a


def _configuration(hand, pose, q):
    from qsplan.hands.geometry.workpiece import workpiece_world
    from qsplan.mechanics.model.scene import check_finite_array

    pose = check_finite_array(pose, "pose", (3,))
    q = check_finite_array(q, "q", (len(hand.joint_names),))
    return pose, q, workpiece_world(hand, pose)


def locate_contacts(hand, pose, q, contacts, tol: float = CONTACT_TOL) -> ContactSet:
    """Where each contact of ``contacts`` is at workpiece ``pose`` and joints ``q``, checked to touch.

    Parameters
    ----------
    hand
        A hand of :mod:`qsplan.hands` (its ``workpiece``, manipulator and fingers).
    pose : array-like, shape (3,)
        Workpiece ``(x, y, theta)`` (m, m, rad).
    q : array-like, shape (n_j,)
        Joint positions (rad or m).
    contacts : sequence of ContactSpec
    tol : float
        m: how far a touching vertex may lie from its edge's line, and beyond its ends.

    Raises
    ------
    QsplanError
        Naming ``contacts[i]``: a feature index out of range for its polygon, or a vertex that does not touch its
        edge within ``tol`` (with the distance).
    """
    pose, q, W = _configuration(hand, pose, q)
    specs = tuple(contacts)
    if not specs or not all(isinstance(s, ContactSpec) for s in specs):
        raise QsplanError(f"contacts: expected a nonempty sequence of ContactSpec; got {contacts!r}")
    names = [s.name for s in specs]
    if len(set(names)) != len(names):
        raise QsplanError(f"contacts: names must be unique; got {names}")
    n = len(specs)
    points, normals, gaps, along, lengths = (np.empty((n, 2)), np.empty((n, 2)), np.empty(n), np.empty(n), np.empty(n))
    links = np.array([finger_link(hand, s.body) for s in specs])
    for i, s in enumerate(specs):
        B = body_ring(hand, s.body, q)
        where = f"contacts[{i}] ({s.name!r})"
        for field, (kind, index), P in (("workpiece", s.workpiece, W), ("feature", s.feature, B)):
            if index >= len(P):
                plural = "vertices" if kind == "vertex" else "edges"
                raise QsplanError(f"{where}.{field}: {kind} {index} out of range; the polygon has {len(P)} {plural}")
        vertex_poly, edge_poly = (W, B) if s.workpiece_vertex else (B, W)
        v = vertex_poly[(s.workpiece if s.workpiece_vertex else s.feature)[1]]
        a, e, length, m = _outward(edge_poly, (s.feature if s.workpiece_vertex else s.workpiece)[1])
        gaps[i], along[i], lengths[i] = (v - a) @ m, (v - a) @ e, length
        if abs(gaps[i]) > tol or not -tol <= along[i] <= length + tol:
            raise QsplanError(f"{where}: the {'workpiece' if s.workpiece_vertex else s.body} vertex is "
                              f"{gaps[i]:.3g} m from the edge's line and {along[i]:.4g} m along the edge "
                              f"(length {length:.4g} m); expected a touch within {tol:g} m")  # fmt: skip
        # into the workpiece: out of the body's edge, or into the workpiece's edge
        points[i], normals[i] = v, (m if s.workpiece_vertex else -m)
    return ContactSet(specs, _frozen(points), _frozen(normals), _frozen(links), _frozen(gaps), _frozen(along),
                      _frozen(lengths))  # fmt: skip


def contact_set_scene(hand, pose, q, contacts, effort_controlled, velocity, effort=None, mu=None,
                      tol: float = CONTACT_TOL):  # fmt: skip
    """The :class:`qsplan.mechanics.Scene` of the hand at ``pose``, ``q`` with exactly the contacts ``contacts``.

    Parameters
    ----------
    pose, q, contacts, tol
        As :func:`locate_contacts`.
    effort_controlled : array-like of bool, shape (n_j,)
    velocity : array-like, shape (n_j,)
        Velocities of the velocity-controlled joints (rad/s or m/s); ignored where effort-controlled.
    effort : array-like, shape (n_j,), optional
        Efforts of the effort-controlled joints (N m or N); default 0 (band computations ignore them).
    mu : float or array-like of shape (n_c,), optional
        Friction coefficients; default the hand's ``mu``.

    Returns
    -------
    Scene
        Contacts in the order and with the names of ``contacts``; ``W_n, W_t`` (eq. 1), ``J_n, J_t`` (eq. 5),
        ``g_obj`` the workpiece's weight at its centre of mass (the pose's point, eq. 2), ``g_man`` (eq. 3).
    """
    from qsplan.hands.contacts.point_scene import points_scene

    found = locate_contacts(hand, pose, q, contacts, tol)
    return points_scene(hand, pose, q, found.points, found.normals, found.links, found.names, effort_controlled,
                        velocity, effort, mu)


def flush_contacts(hand, pose, q, body: str, workpiece_edge: int, body_edge: int, names=None,
                   tol: float = CONTACT_TOL) -> tuple:  # fmt: skip
    """The two contacts of a body edge lying flush on a workpiece edge: the ends of their overlap.

    Each end is a workpiece vertex on the body's edge or a body vertex on the workpiece's edge, whichever bounds
    the overlap there (a workpiece vertex where both coincide within ``tol``).

    Parameters
    ----------
    pose, q, tol
        As :func:`locate_contacts`.
    body : str
    workpiece_edge, body_edge : int
        The edges (each from its vertex to the next).
    names : (str, str), optional
        The contacts' names; default ``"<body>:base"`` and ``"<body>:tip"``.

    Returns
    -------
    (ContactSpec, ContactSpec)
        Ordered along the body's edge (for a finger's inner edge: from its base toward its tip).

    Raises
    ------
    QsplanError
        The edges are not antiparallel within :data:`FLUSH_ANGLE_TOL` (facing), not on one line within ``tol``,
        or overlap by less than ``tol``.
    """
    pose, q, W = _configuration(hand, pose, q)
    B = body_ring(hand, body, q)
    we, be = _feature(("edge", workpiece_edge), "workpiece_edge"), _feature(("edge", body_edge), "body_edge")
    for field, index, P in (("workpiece_edge", we[1], W), ("body_edge", be[1], B)):
        if index >= len(P):
            raise QsplanError(f"{field}: edge {index} out of range; the polygon has {len(P)} edges")
    a, e, length, m = _outward(W, we[1])
    b0, _, _, mb = _outward(B, be[1])
    if float(m @ mb) > -np.cos(FLUSH_ANGLE_TOL):
        angle = float(np.degrees(np.arccos(np.clip(-(m @ mb), -1.0, 1.0))))
        raise QsplanError(f"body_edge: the {body} edge {be[1]} and workpiece edge {we[1]} are not flush: their normals "
                          f"are {angle:.4g} deg from opposite")  # fmt: skip
    b1 = B[(be[1] + 1) % len(B)]
    off = np.array([(b0 - a) @ m, (b1 - a) @ m])
    if np.max(np.abs(off)) > tol:
        raise QsplanError(f"body_edge: the {body} edge {be[1]} lies {np.max(np.abs(off)):.3g} m off workpiece edge "
                          f"{we[1]}'s line; expected within {tol:g} m")  # fmt: skip
    s0, s1 = (b0 - a) @ e, (b1 - a) @ e  # the body edge's ends along the workpiece edge
    if min(max(s0, s1), length) - max(min(s0, s1), 0.0) < tol:
        raise QsplanError(f"body_edge: the {body} edge {be[1]} and workpiece edge {we[1]} overlap by less than {tol:g} m")
    names = (f"{body}:base", f"{body}:tip") if names is None else tuple(names)
    out = []
    for name, s, other, vertex in zip(names, (s0, s1), (s1, s0), (be[1], (be[1] + 1) % len(B))):
        # the overlap's end toward this body vertex: the vertex itself inside the workpiece edge, else the
        # workpiece edge's end it passes
        if s >= other and s >= length - tol:
            out.append(ContactSpec(name, body, ("vertex", (we[1] + 1) % len(W)), be))
        elif s < other and s <= tol:
            out.append(ContactSpec(name, body, ("vertex", we[1]), be))
        else:
            out.append(ContactSpec(name, body, we, ("vertex", vertex)))
    return tuple(out)


def palm_top_edge(hand) -> int:
    """The palm polygon's edge whose outward normal is ``+y`` (the surface the workpiece rests on)."""
    return _edge_facing(body_ring(hand, "palm", None), (0.0, 1.0), "palm")


def finger_inner_edge(hand, body: str) -> int:
    """The edge of a finger's last link facing the other finger: of the link's polygon at mid-range joints, the edge
    whose outward normal points most toward the other finger's side (world ``+x`` for the left finger, ``-x`` for
    the right one).  The paper's form (Fig. 9): the link frame's ``-y`` edge of the left finger, ``+y`` of the right;
    a jaw: its face toward the other jaw."""
    from qsplan.hands.geometry.workpiece import rotation
    from qsplan.mechanics.model.manipulator import link_poses

    link = finger_link(hand, body)
    if link < 0:
        raise QsplanError(f"body: expected 'left' or 'right'; got {body!r}")
    man = hand.manipulator
    shape = man.joints[link].link_shape
    if shape is None:
        raise QsplanError(f"body: the {body} finger's last link has no polygon")
    P = np.asarray(shape, dtype=float)
    lim = np.asarray(hand.description.joint_limits, dtype=float)
    angle = link_poses(man, 0.5 * (lim[:, 0] + lim[:, 1]))[link][2]
    toward = np.array([1.0, 0.0]) if body == "left" else np.array([-1.0, 0.0])
    normals = np.array([_outward(P, k)[3] @ rotation(angle).T for k in range(len(P))])
    return int(np.argmax(normals @ toward))


def _edge_facing(P, direction, body) -> int:
    """The edge of ``P`` whose outward normal is ``direction`` (to :data:`FACING_TOL`)."""
    for k in range(len(P)):
        if np.allclose(_outward(P, k)[3], direction, atol=FACING_TOL):
            return k
    raise QsplanError(f"body: the {body} polygon has no edge facing {tuple(direction)}")
