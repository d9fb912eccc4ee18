"""A described hand's grasp at many workpiece positions, by the generic path (Section 3, eqs. 1, 5, 6).

At each workpiece x (pose ``(x, rest_height, 0)``) the free joints take the grasp's values and each
finger's closing joint closes onto the workpiece (:func:`qsplan.hands.chains.closing_batch.close_finger_batch`,
all states at once); a state is a configuration of the grasp where both fingers touch the grasp's
features, neither flush (:func:`qsplan.planner` judged the same with
:func:`qsplan.hands.chains.hand.close_grasp`, one state at a time).  The contacts follow the formation
(:mod:`qsplan.hands.formations.registry`): its palm contacts at the workpiece vertices it names, with the
inward normal of the edge resting on the palm, then each finger's.  ``dq_dx`` keeps every finger contact
closed while the workpiece moves along +x with the free joints held: eq. 6 with equality,
``W_n^T nu - J_n qdot = 0`` at each finger contact, solved for its closing joint's rate.

A :class:`qsplan.hands.paper_hand.grasps.Grasp` of the paper's hand (placements) is read as the contact keys it
stands for: an inner edge on a vertex, a fingertip corner on an edge (:func:`requirement`).  Units SI.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from qsplan.hands.chains.closing_batch import ccw_ring, close_finger_batch, edge_normals, link_poses_batch
from qsplan.hands.chains.arrays import contact_jacobians
from qsplan.hands.protocol import (CONTACT_KINDS, FLUSH, NO_CONTACT, NO_PLACEMENT, OTHER_CONTACT, SINGULAR, ChainGrasp,
                                   GraspStates)  # fmt: skip
from qsplan.mechanics.errors import QsplanError

__all__ = ["CLOSINGS_KEPT", "SINGULAR_TOL", "Closing", "check_formation", "close_states", "closing_key", "closing_of",
           "formation_contacts", "generic_states", "requirement", "workpiece_states"]

#: ``|J_n|`` (m per unit joint rate) of a finger contact's closing-joint column below which the joint cannot move
#: the contact along its normal (eq. 6 has no rate): ``qsplan.planner``'s closing rates use the same 1e-12, some
#: 1e-10 of a bundled link's length.
SINGULAR_TOL = 1e-12


#: Closings a hand keeps (:func:`close_states`): a table of grasps closes each free-joint row along one grid of x once,
#: and every grasp of the row reads it; a few rows' worth, each some 100 kB for 500 states.
CLOSINGS_KEPT = 8


def check_formation(formation) -> tuple:
    """``(palm slots, their workpiece vertices, (left slot, right slot))`` of a formation the generic path serves: palm
    contacts at named workpiece vertices and one contact per finger, each finger's last joint closing.

    Raises
    ------
    QsplanError
        Naming the formation and what it asks that the generic path does not do.
    """
    palm = formation.palm_contacts
    left, right = formation.finger_contacts
    vertices = tuple(formation.contacts[i].index for i in palm)
    if len(left) != 1 or len(right) != 1 or any(formation.contacts[i].feature != "vertex" or v is None
                                                for i, v in zip(palm, vertices)):  # fmt: skip
        raise QsplanError(f"formation: {formation.name!r} is not served by the described hands' closing (palm contacts "
                          "at named workpiece vertices and exactly one contact per finger)")  # fmt: skip
    return palm, vertices, (left[0], right[0])


def workpiece_states(hand, xs) -> tuple:
    """``(poses (n, 3), W (n, k, 2))``: the workpiece on the palm at ``xs`` (m), its world vertices as
    :func:`qsplan.hands.geometry.workpiece.workpiece_world` gives them (the turn by 0 is exact)."""
    poses = np.column_stack([xs, np.full(len(xs), hand.rest_height), np.zeros(len(xs))])
    return poses, hand.workpiece[None] + poses[:, None, :2]


def _paper_features(hand, finger: int) -> tuple:
    """``(inner edge, inner corner, outer corner)`` of the paper finger ``finger``'s link ring (counter-clockwise):
    the edge facing the other finger (outward normal ``-y`` in the link frame for the left finger, ``+y`` for the
    right one) and the tip corners ``(L, -+w)``, ``(L, +-w)`` (:class:`qsplan.hands.paper_hand.grasps.TipOnEdge`)."""
    ring = ccw_ring(hand.manipulator.joints[hand.closing_joints[finger]].link_shape)
    m, _ = edge_normals(ring)
    s = -1.0 if finger == 0 else 1.0
    edge = int(np.argmax(s * m[:, 1]))
    tip = np.flatnonzero(ring[:, 0] == ring[:, 0].max())
    inner = int(tip[np.argmax(s * ring[tip, 1])])
    outer = int(tip[np.argmin(s * ring[tip, 1])])
    return edge, inner, outer


def requirement(hand, grasp) -> tuple:
    """Per finger ``(kind, feature, link feature)`` the grasp asks of the closing (kind 0 a link corner on a workpiece
    edge, 1 a workpiece vertex on a link edge; internal numbering; None: any), left then right.

    Raises
    ------
    QsplanError
        A paper :class:`~qsplan.hands.paper_hand.grasps.Grasp` on a hand of another form, or an index out of range
        (named).
    """
    from qsplan.hands.paper_hand.grasps import Grasp, OnVertex, TipOnEdge, internal_edge, internal_vertex

    if isinstance(grasp, ChainGrasp):
        out = []
        for f, c in enumerate((grasp.left, grasp.right)):
            if c.link != hand.closing_joints[f] or c.kind not in CONTACT_KINDS:
                raise QsplanError(f"grasp.{('left', 'right')[f]}: expected a contact of the finger's closing link "
                                  f"{hand.joint_names[hand.closing_joints[f]]!r}; got {c}")  # fmt: skip
            out.append((1 - CONTACT_KINDS.index(c.kind), c.feature, None))
        return tuple(out)
    if not isinstance(grasp, Grasp):
        raise QsplanError(f"grasp: expected a ChainGrasp or a Grasp; got {type(grasp).__name__}")
    if not hand.paper_form:
        raise QsplanError(f"grasp: {grasp.label!r} is a grasp of the paper's hand; this hand closes ChainGrasps")
    out = []
    for f, pl in enumerate((grasp.left, grasp.right)):
        field = f"grasp.{('left', 'right')[f]}"
        edge, inner, outer = _paper_features(hand, f)
        if isinstance(pl, OnVertex):
            out.append((1, None if pl.vertex is None else internal_vertex(hand, pl.vertex, f"{field}.vertex"), edge))
        elif isinstance(pl, TipOnEdge) and pl.branch in (0, 1):
            out.append((0, internal_edge(hand, pl.edge, f"{field}.edge"), inner if pl.branch == 0 else outer))
        else:
            raise QsplanError(f"{field}: expected an OnVertex or TipOnEdge placement (branch 0 or 1); got {pl!r}")
    return tuple(out)


def _free_values(hand, grasp, n: int, free) -> np.ndarray:
    """The free joints' values (n, n_free): ``free`` per state, else the grasp's."""
    n_free = len(hand.free_joints)
    if free is None:
        values = np.asarray(getattr(grasp, "free", ()), dtype=float).reshape(-1)
        if values.size != n_free:
            raise QsplanError(f"grasp.free: expected {n_free} free-joint values; got {values.size}")
        return np.broadcast_to(values, (n, n_free))
    values = np.asarray(free, dtype=float)
    if values.shape != (n, n_free) or not np.all(np.isfinite(values)):
        raise QsplanError(f"free: expected finite free-joint values of shape ({n}, {n_free}) (rad or m); got shape "
                          f"{values.shape}")  # fmt: skip
    return values


@dataclass(eq=False)
class Closing:
    """Both fingers closed at ``n`` states (:func:`closing_of`); read-only arrays.

    Attributes
    ----------
    poses : ndarray, shape (n, 3)
        Workpiece poses (m, m, rad).
    W : ndarray, shape (n, k, 2)
        The workpiece's world vertices (m).
    q : ndarray, shape (n, n_j)
        The free joints as given, the closing joints closed (NaN where a finger touches nothing).
    closed : (ClosedFingers, ClosedFingers)
        Left, right.
    decisions : dict
        Per formation name, the contact decisions of its states (:mod:`qsplan.hands.described.scenes`), made once.
    """

    poses: np.ndarray
    W: np.ndarray
    q: np.ndarray
    closed: tuple
    decisions: dict = field(default_factory=dict)


def closing_key(xs, free) -> tuple:
    """The key of the closing at ``xs`` (n,) from ``free`` (n, n_free) in :attr:`DescribedHand.closings`."""
    xs, free = np.ascontiguousarray(xs, dtype=float), np.ascontiguousarray(free, dtype=float)
    return (xs.tobytes(), free.tobytes(), free.shape)


def closing_of(hand, xs, free) -> Closing:
    """Both fingers closed at ``xs`` (n,) from the free joints ``free`` (n, n_free) (:class:`Closing`).

    The last :data:`CLOSINGS_KEPT` closings are kept on the hand
    (:attr:`qsplan.hands.described.hand.DescribedHand.closings`): the grasps closed at the same states (every candidate
    of a free-joint row, along one grid) share one closing.
    """
    key = closing_key(xs, free)
    kept = hand.closings.get(key)
    if kept is not None:
        return kept
    poses, W = workpiece_states(hand, np.asarray(xs, dtype=float))
    q = np.zeros((len(xs), len(hand.joint_names)))
    q[:, list(hand.free_joints)] = free
    closed = []
    for f, side in enumerate((1.0, -1.0)):
        c = close_finger_batch(hand.manipulator, q, hand.finger_joints[f], hand.description.joint_limits, W, side)
        q[:, c.link] = c.value
        closed.append(c)
    for a in (poses, W, q, *(getattr(c, f) for c in closed for f in c.__slots__ if f != "link")):
        a.setflags(write=False)
    while len(hand.closings) >= CLOSINGS_KEPT:
        hand.closings.pop(next(iter(hand.closings)))
    hand.closings[key] = out = Closing(poses, W, q, tuple(closed))
    return out


def close_states(hand, xs, free) -> tuple:
    """``(poses, W, q, closed)`` of :func:`closing_of`."""
    c = closing_of(hand, xs, free)
    return c.poses, c.W, c.q, c.closed


def formation_contacts(formation, W, closed) -> tuple:
    """The formation's contacts at the closed states: ``points, normals`` (n, n_c, 2) and ``bodies`` (n, n_c): the
    palm's at its workpiece vertices with the inward normal of the edge on the palm (vertex 0 to 1), each finger's
    at its closing contact (NaN where it touches nothing)."""
    palm, vertices, fingers = check_formation(formation)
    n, n_c = len(W), formation.n_contacts
    points, normals = np.full((n, n_c, 2), np.nan), np.full((n, n_c, 2), np.nan)
    bodies = np.full((n, n_c), -1)
    bottom = -edge_normals(W)[0][:, 0]
    for i, v in zip(palm, vertices):
        points[:, i], normals[:, i] = W[:, v], bottom
    for i, c in zip(fingers, closed):
        points[:, i], normals[:, i], bodies[:, i] = c.point, c.normal, c.link
    return points, normals, bodies


def generic_states(hand, formation, grasp, xs, free=None) -> GraspStates:
    """The grasp at workpiece ``xs`` (n,) by the generic path (see the module docstring).

    Parameters
    ----------
    hand : qsplan.hands.described.hand.DescribedHand
    formation : qsplan.hands.formations.registry.Formation
    grasp : ChainGrasp or qsplan.hands.paper_hand.grasps.Grasp
    xs : ndarray, shape (n,)
        Workpiece x (m).
    free : ndarray, shape (n, n_free), optional
        Each state's free joints (rad or m); default the grasp's.

    Returns
    -------
    GraspStates
    """
    _, _, fingers = check_formation(formation)
    req = requirement(hand, grasp)
    n = len(xs)
    poses, W, q, closed = close_states(hand, xs, _free_values(hand, grasp, n, free))
    keys = np.zeros((n, 2), bool)
    for f, (c, (kind, feature, link_feature)) in enumerate(zip(closed, req)):
        keys[:, f] = c.found & (c.kind == kind)
        if feature is not None:
            keys[:, f] &= c.feature == feature
        if link_feature is not None:
            keys[:, f] &= c.link_feature == link_feature
    found = np.column_stack([c.found for c in closed])
    flush = np.column_stack([c.flush for c in closed])
    finger_ok = keys & ~flush
    mismatch = OTHER_CONTACT if isinstance(grasp, ChainGrasp) else NO_PLACEMENT
    # as the per-state judge: a finger closing onto nothing, then other features, then a flush link
    reason = np.select([~found.all(axis=1), ~keys.all(axis=1), flush.any(axis=1)], [NO_CONTACT, mismatch, FLUSH], 0)
    reason = reason.astype(np.int8)
    points, normals, bodies = formation_contacts(formation, W, closed)
    dq = np.full(q.shape, np.nan)
    ok = reason == 0
    rows = np.flatnonzero(ok)
    if rows.size:
        at = list(fingers)
        Jn, _ = contact_jacobians(hand.manipulator, link_poses_batch(hand.manipulator, q[rows]), points[rows][:, at],
                                  normals[rows][:, at], bodies[rows][:, at])  # fmt: skip
        unit = normals[rows][:, at] / np.linalg.norm(normals[rows][:, at], axis=2)[..., None]  # Wn's normal (eq. 1)
        rate = np.zeros((rows.size, q.shape[1]))
        singular = np.zeros(rows.size, bool)
        for f, k in enumerate(hand.closing_joints):
            jn = Jn[:, f, k]
            singular |= np.abs(jn) < SINGULAR_TOL
            with np.errstate(divide="ignore", invalid="ignore"):
                rate[:, k] = unit[:, f, 0] / jn
        dq[rows] = np.where(singular[:, None], np.nan, rate)
        reason[rows[singular]] = SINGULAR
        ok = reason == 0
    touched = np.column_stack([c.feature for c in closed])
    kinds = np.column_stack([c.kind for c in closed])
    written = np.where(kinds == 0, hand.user_edges[touched], hand.user_vertices[touched])
    tip = np.array([k == 0 for k, _, _ in req])
    return GraspStates(formation, grasp, np.asarray(xs, float), poses, q, ok, reason, finger_ok, touched, written, tip,
                       points, normals, bodies, dq)  # fmt: skip
