"""Reorienting the workpiece in the paper's hand: the flush instant, its transition scene, the pivot manifold (issue 23).

Section 5.2's plan ends its first 4S segment "when the left finger achieves edge-to-edge contact with the workpiece
(along the longest edge)".  Along the palm-edge slide (the bottom edge on the palm, theta = 0) that happens at one
workpiece x, the **flush instant** (:func:`flush_instant`): the left finger's inner edge lies along the edge, whose
two ends touch it.  Its scene has five contacts (:func:`transition_contacts`: palm under vertex 0 and vertex 1, the
left finger at both ends of the flush overlap, the right finger), in which the transition mode ``BSSSS`` (vertex 0
lifts, the workpiece pivots on vertex 1) is judged.

The **pivot** that follows keeps the pivot vertex on the palm (sliding), the left finger flush on that edge (two
contacts) and the right finger on its vertex: a one-parameter manifold in the workpiece's angle theta, solved in
closed form by :func:`pivot_configurations` (no iteration):

* the pivot vertex on the palm's top: ``y = -(R(theta) v_p)_y``;
* the left finger along the edge: ``q_left = psi + theta`` (``psi`` the edge's angle in the body frame, lower end to
  upper end), and the edge's line at half the finger's width from the joint on its inner side,
  ``(R v_lo + (x, y) - a_left) . m = -w`` with ``m = (-sin q_left, cos q_left)``: linear in ``x``;
* the right finger's inner edge on its vertex: :func:`qsplan.hands.two_finger.tangency_angles` at that vertex.

Their derivatives in theta are in closed form too (``dq_left/dtheta = 1``; :func:`qsplan.hands.two_finger.tangency_rates`
for the right finger).  The paper's form only (two single-link revolute fingers, Fig. 9).  Units SI (m, rad).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qsplan.hands.contact_sets import (ContactSpec, contact_set_scene, finger_inner_edge, flush_contacts,
                                       palm_top_edge)  # fmt: skip
from qsplan.hands.formations import formation
from qsplan.mechanics.errors import QsplanError
from qsplan.mechanics.model.geometry import CONTACT_TOL

__all__ = ["PIVOT_FORMATION", "THETA_RATE", "TRANSITION_FORMATION", "FlushInstant", "PivotConfigurations",
           "flush_instant", "left_sides", "paper_form", "pivot_configurations", "pivot_contacts", "pivot_scene", "transition_contacts",
           "transition_scene"]

#: The workpiece's turning rate (rad/s) the transition and pivot scenes are built for: negative, clockwise (the
#: workpiece tips right onto its pivot vertex).  Bands depend on its sign only: the quasistatic model is positively
#: homogeneous in the velocities (eqs. 6-11; the tests scale it).  0.05 rad/s turns 55 deg in about 19 s.
THETA_RATE = -0.05

#: The registered formations (:mod:`qsplan.hands.formations`) of the flush instant (its contacts and the transition
#: mode) and of the pivot (its contacts and 4S).
TRANSITION_FORMATION = "flush_to_pivot_v1"
PIVOT_FORMATION = "pivot_v1"


@dataclass(frozen=True, slots=True, eq=False)
class FlushInstant:
    """The palm-edge slide's configuration where the left finger lies flush along a workpiece edge.

    Attributes
    ----------
    x : float
        Workpiece x (m); the pose is ``(x, rest_height, 0)``.
    pose : ndarray, shape (3,)
        ``(x, y, theta)`` (m, m, rad).
    q : ndarray, shape (2,)
        Joint angles (rad), left then right.
    edge : int
        The flush workpiece edge (internal numbering, from vertex ``edge`` to ``edge + 1``).
    right_vertex : int
        The workpiece vertex on the right finger's inner edge.
    """

    x: float
    pose: np.ndarray
    q: np.ndarray
    edge: int
    right_vertex: int


@dataclass(frozen=True, slots=True, eq=False)
class PivotConfigurations:
    """The pivot manifold at ``n`` angles (:func:`pivot_configurations`).

    Attributes
    ----------
    theta : ndarray, shape (n,)
        Workpiece angle (rad), counter-clockwise.
    pose : ndarray, shape (n, 3)
        ``(x, y, theta)`` (m, m, rad).
    q : ndarray, shape (n, 2)
        Joint angles (rad), left then right; nan where the right finger cannot reach its vertex.
    dpose : ndarray, shape (n, 3)
        ``d pose / d theta`` (m/rad, m/rad, 1).
    dq : ndarray, shape (n, 2)
        ``d q / d theta`` (rad/rad): 1 for the left finger.
    vertices : ndarray, shape (n, k, 2)
        The workpiece's world vertices (m).
    pivot, edge, right_vertex : int
        The pivot vertex, the left finger's flush edge, the right finger's vertex (internal numbering).
    """

    theta: np.ndarray
    pose: np.ndarray
    q: np.ndarray
    dpose: np.ndarray
    dq: np.ndarray
    vertices: np.ndarray
    pivot: int
    edge: int
    right_vertex: int


def paper_form(hand):
    """The hand's paper-form record (:class:`qsplan.hands.two_finger.TwoFingerHand`: finger length, width, joints).

    Raises
    ------
    QsplanError
        The hand is not of the paper's form."""
    paper = getattr(hand, "paper", hand)
    if paper is None or not hasattr(paper, "finger_base"):
        raise QsplanError("hand: the reorientation mechanics need the paper's form (two single-link revolute fingers, "
                          "Fig. 9)")  # fmt: skip
    return paper


def left_sides(hand) -> tuple:
    """The workpiece edges (internal numbering) the left finger can lie flush along: those running downward
    counter-clockwise (lower end below upper end, the edge's angle in (0, pi)), longest first (the paper's Section
    5.2: "along the longest edge"); () when none."""
    V = paper_form(hand).workpiece
    d = V - np.roll(V, -1, axis=0)  # upper end (vertex k) minus lower end (vertex k + 1)
    psi = np.arctan2(d[:, 1], d[:, 0])
    ks = np.flatnonzero((psi > 0.0) & (psi < np.pi))
    return tuple(int(k) for k in sorted(ks, key=lambda k: (-np.hypot(*d[k]), k)))


def _flush_edge(paper, edge):
    """``(edge, lower end, upper end, psi)``: the edge the left finger lies along (default the longest left side,
    :func:`left_sides`), checked to lean right."""
    V = paper.workpiece
    if edge is None:
        sides = left_sides(paper)
        if not sides:
            raise QsplanError("edge: the workpiece has no left side (an edge whose lower end is below its upper end) "
                              "for the left finger to lie flush along")  # fmt: skip
        edge = sides[0]
    k = edge
    if isinstance(k, (bool, np.bool_)) or not isinstance(k, (int, np.integer)) or not 0 <= k < len(V):
        raise QsplanError(f"edge: expected a workpiece edge in [0, {len(V)}); got {edge!r}")
    lo, hi = V[(k + 1) % len(V)], V[k]  # counter-clockwise: a left side runs downward
    psi = float(np.arctan2(hi[1] - lo[1], hi[0] - lo[0]))
    if not 0.0 < psi < np.pi:
        raise QsplanError(f"edge: workpiece edge {k} is not a left side (its lower end is not below its upper end)")
    return int(k), lo, hi, psi


def _flush_x(paper, lo, q_left, rotated_lo, y):
    """Workpiece x putting the edge's line (through ``rotated_lo + (x, y)``, angle ``q_left``) at half the finger's
    width from the left joint, on the finger's inner side."""
    m = np.stack([-np.sin(q_left), np.cos(q_left)], axis=-1)
    rel = rotated_lo + np.stack([np.zeros_like(y), y], axis=-1) - paper.pivots[0]
    return (-0.5 * paper.finger_width - np.sum(rel * m, axis=-1)) / m[..., 0]


def _right_angles(paper, W, vertex):
    """Right joint angles (rad) putting its inner edge on workpiece vertex ``vertex`` of ``W`` (n, k, 2)."""
    from qsplan.hands.two_finger import tangency_angles

    phi, _, _ = tangency_angles(paper, W[:, [vertex]])
    return phi[:, 1]


def flush_instant(hand, edge=None) -> FlushInstant:
    """The palm-edge slide's flush instant: the workpiece x where the left finger lies flush along ``edge``.

    Parameters
    ----------
    hand
        A paper-form hand (a :class:`qsplan.hands.described.DescribedHand` of that form, or its record).
    edge : int, optional
        The workpiece edge (internal numbering); default the longest left side (:func:`left_sides`).

    Returns
    -------
    FlushInstant
        In closed form: ``q_left = psi``, and ``x`` from the edge's line at half the finger's width from the joint.

    Raises
    ------
    QsplanError
        Not the paper's form; ``edge`` out of range or not a left side; either end of the edge not along the
        finger's inner edge.
    """
    paper = paper_form(hand)
    k, lo, hi, psi = _flush_edge(paper, edge)
    y = paper.rest_height
    x = float(_flush_x(paper, lo, np.array(psi), lo, np.array(y)))
    pose = np.array([x, y, 0.0])
    W = paper.workpiece + pose[:2]
    u = np.array([np.cos(psi), np.sin(psi)])
    along = (np.array([lo, hi]) + pose[:2] - paper.pivots[0]) @ u
    if not (along.min() > 0.0 and along.max() < paper.finger_length):
        raise QsplanError(f"edge: workpiece edge {k} lies {along.min():.4g} to {along.max():.4g} m along the left finger "
                          f"at the flush instant; expected within its length {paper.finger_length:g} m")  # fmt: skip
    from qsplan.hands.two_finger import tangency_angles

    phi, idx, _ = tangency_angles(paper, W[None])
    q = np.array([psi, phi[0, 1]])
    q.setflags(write=False)
    pose.setflags(write=False)
    return FlushInstant(x, pose, q, k, int(idx[0, 1]))


def _named(hand, name, pose, q, edge, right_vertex, pivot=None) -> tuple:
    """The contacts of the registered formation ``name`` at a configuration, in its order: its palm slots (their
    vertices on the palm's top; ``pivot`` for a single one, when given), its two left slots (the flush overlap's ends
    on ``edge``), its right slot (``right_vertex`` on the right finger's inner edge)."""
    f = formation(name)
    left, right = f.finger_contacts
    if len(left) != 2 or len(right) != 1:
        raise QsplanError(f"formation: {name!r} is not a flush formation (two left contacts, one right)")
    top, out = palm_top_edge(hand), {}
    for i in f.palm_contacts:
        vertex = f.contacts[i].index if pivot is None else pivot
        out[i] = ContactSpec(f.contacts[i].name, "palm", ("vertex", vertex), ("edge", top))
    names = tuple(f.contacts[i].name for i in left)
    out.update(zip(left, flush_contacts(hand, pose, q, "left", edge, finger_inner_edge(hand, "left"), names)))
    out[right[0]] = ContactSpec(f.contacts[right[0]].name, "right", ("vertex", right_vertex),
                                ("edge", finger_inner_edge(hand, "right")))  # fmt: skip
    return tuple(out[i] for i in range(f.n_contacts))


def transition_contacts(hand, instant: FlushInstant) -> tuple:
    """The flush instant's five contacts, in the order of formation :data:`TRANSITION_FORMATION`: ``palm:0``,
    ``palm:1`` (the bottom edge's ends on the palm), ``left:base``, ``left:tip`` (the ends of the flush overlap,
    :func:`qsplan.hands.contact_sets.flush_contacts`), ``right`` (its vertex on the right finger's inner edge)."""
    return _named(hand, TRANSITION_FORMATION, instant.pose, instant.q, instant.edge, instant.right_vertex)


def _velocities(effort_joint, dq, theta_rate):
    if effort_joint not in ("left", "right"):
        raise QsplanError(f"effort_joint: expected 'left' or 'right'; got {effort_joint!r}")
    if not (isinstance(theta_rate, (int, float, np.floating)) and np.isfinite(theta_rate) and theta_rate != 0.0):
        raise QsplanError(f"theta_rate: expected a nonzero finite rate (rad/s); got {theta_rate!r}")
    e = np.array([effort_joint == "left", effort_joint == "right"])
    return e, np.asarray(dq, dtype=float) * float(theta_rate)


def transition_scene(hand, instant: FlushInstant, effort_joint: str = "right", theta_rate: float = THETA_RATE, mu=None):
    """The flush instant's five-contact scene, ``effort_joint`` torque-controlled and the other finger driven at its
    pivot-manifold rate for the workpiece turning at ``theta_rate`` (rad/s; the pivot's start,
    :func:`pivot_configurations` at theta = 0).

    Raises
    ------
    QsplanError
        ``effort_joint`` not ``"left"`` or ``"right"``, ``theta_rate`` zero or not finite.
    """
    start = pivot_configurations(hand, [0.0], edge=instant.edge, right_vertex=instant.right_vertex)
    e, v = _velocities(effort_joint, start.dq[0], theta_rate)
    return contact_set_scene(hand, instant.pose, instant.q, transition_contacts(hand, instant), e, v, mu=mu)


def pivot_configurations(hand, theta, pivot: int = 1, edge=None, right_vertex: int = 2) -> PivotConfigurations:
    """The pivot manifold (see the module docstring) at angles ``theta``, in closed form.

    Parameters
    ----------
    hand
        A paper-form hand.
    theta : array-like, shape (n,)
        Workpiece angles (rad).
    pivot : int
        The workpiece vertex on the palm (internal numbering).
    edge : int, optional
        The edge the left finger lies flush along; default the longest one.
    right_vertex : int
        The workpiece vertex on the right finger's inner edge.

    Returns
    -------
    PivotConfigurations
    """
    from qsplan.hands.two_finger import tangency_rates
    from qsplan.hands.workpiece import rotation

    paper = paper_form(hand)
    V = paper.workpiece
    for name, value in (("pivot", pivot), ("right_vertex", right_vertex)):
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)) or not 0 <= value < len(V):
            raise QsplanError(f"{name}: expected a workpiece vertex in [0, {len(V)}); got {value!r}")
    k, lo, _, psi = _flush_edge(paper, edge)
    theta = np.atleast_1d(np.asarray(theta, dtype=float))
    if theta.ndim != 1 or not np.all(np.isfinite(theta)):
        raise QsplanError(f"theta: expected a finite 1-D array of workpiece angles (rad); got shape {theta.shape}")
    R = np.stack([rotation(t) for t in theta])  # (n, 2, 2)
    RV = np.einsum("nij,kj->nki", R, V)  # the turned body-frame vertices (n, k, 2)
    perp = np.stack([-RV[..., 1], RV[..., 0]], axis=-1)  # d(R v)/d theta
    y = -RV[:, pivot, 1]
    q_left = psi + theta
    x = _flush_x(paper, lo, q_left, RV[:, (k + 1) % len(V)], y)
    W = RV + np.stack([x, y], axis=-1)[:, None, :]
    q = np.column_stack([q_left, _right_angles(paper, W, right_vertex)])
    # d/dtheta of the left-finger condition f(x, theta) = x m_x + (R v_lo + (0, y) - a) . m + w = 0, dm/dq = -u
    u = np.stack([np.cos(q_left), np.sin(q_left)], axis=-1)
    m = np.stack([-u[:, 1], u[:, 0]], axis=-1)
    dy = -perp[:, pivot, 1]
    i_lo = (k + 1) % len(V)
    rel = RV[:, i_lo] + np.column_stack([np.zeros_like(y), y]) - paper.pivots[0]
    df = -x * u[:, 0] + np.sum((perp[:, i_lo] + np.column_stack([np.zeros_like(dy), dy])) * m, axis=1) \
        - np.sum(rel * u, axis=1)
    dx = -df / m[:, 0]
    dpose = np.column_stack([dx, dy, np.ones_like(theta)])
    v_right = dpose[:, None, :2] + perp[:, [right_vertex]]  # the right vertex's velocity per unit theta rate
    d = W[:, [right_vertex, right_vertex]] - paper.pivots  # (n, 2 fingers, 2): only the right finger's is used
    dq = np.column_stack([np.ones_like(theta), tangency_rates(paper, d, np.repeat(v_right, 2, axis=1))[:, 1]])
    return PivotConfigurations(theta, np.column_stack([x, y, theta]), q, dpose, dq, W, int(pivot), k, int(right_vertex))


def pivot_contacts(hand, pose, q, pivot: int = 1, edge=None, right_vertex: int = 2) -> tuple:
    """The pivot's four contacts at one configuration, in the order of formation :data:`PIVOT_FORMATION`:
    ``palm:1`` (the pivot vertex on the palm), ``left:base``, ``left:tip`` (the flush overlap's ends, whichever
    features they are there), ``right``."""
    k = _flush_edge(paper_form(hand), edge)[0]
    return _named(hand, PIVOT_FORMATION, pose, q, k, right_vertex, pivot)


def pivot_scene(hand, configurations: PivotConfigurations, i: int, effort_joint: str = "right",
                theta_rate: float = THETA_RATE, mu=None, tol: float = CONTACT_TOL):  # fmt: skip
    """The pivot's scene at sample ``i`` of ``configurations``: ``effort_joint`` torque-controlled, the other finger
    driven at its manifold rate for the workpiece turning at ``theta_rate`` (rad/s)."""
    c = configurations
    e, v = _velocities(effort_joint, c.dq[i], theta_rate)
    contacts = pivot_contacts(hand, c.pose[i], c.q[i], c.pivot, c.edge, c.right_vertex)
    return contact_set_scene(hand, c.pose[i], c.q[i], contacts, e, v, mu=mu, tol=tol)
