"""The paper hand's pivot in closed form: a test-only reference for the generic formation search (issues 23, 32).

Section 5.2's plan ends its first 4S segment "when the left finger achieves edge-to-edge contact with the workpiece
(along the longest edge)".  Along the palm-edge slide (the bottom edge on the palm, theta = 0) that happens at one
workpiece x, the **flush instant** (:func:`flush_instant`): the left finger's inner edge lies along the edge, whose
two ends touch it.  Its five contacts (:data:`TRANSITION`: the palm under vertices 0 and 1, the left finger at both
ends of the flush overlap, the right finger on its vertex) carry the transition mode ``BSSSS`` (vertex 0 lifts, the
workpiece pivots on vertex 1).

The **pivot** that follows (:data:`PIVOT`, 4S) keeps the pivot vertex on the palm, the left finger flush on that edge
(two contacts) and the right finger on its vertex: a one-parameter manifold in the workpiece's angle theta, solved in
closed form by :func:`pivot_configurations` (no iteration):

* the pivot vertex on the palm's top: ``y = -(R(theta) v_p)_y``;
* the left finger along the edge: ``q_left = psi + theta`` (``psi`` the edge's angle in the body frame, lower end to
  upper end), and the edge's line at half the finger's width from the joint on its inner side,
  ``(R v_lo + (x, y) - a_left) . m = -w`` with ``m = (-sin q_left, cos q_left)``: linear in ``x``;
* the right finger's inner edge on its vertex: :func:`qsplan.hands.paper_hand.two_finger.tangency_angles` at that
  vertex.

Their derivatives in theta are in closed form too (``dq_left/dtheta = 1``;
:func:`qsplan.hands.paper_hand.two_finger.tangency_rates` for the right finger).  The library plans every turn by the
generic search (:mod:`qsplan.hands.formations.pivots`, :mod:`qsplan.hands.formations.manifold`,
:mod:`qsplan.planner.plan.turning`); this module is derived apart from it and serves only to check it.  Its two
formations are local values, not entries of the production registry
(:data:`qsplan.hands.formations.registry.FORMATIONS`).  The paper's form only (two single-link revolute fingers,
Fig. 9).  Units SI (m, rad).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qsplan.hands.contacts.sets import (ContactSpec, contact_set_scene, finger_inner_edge, flush_contacts,
                                        palm_top_edge)  # fmt: skip
from qsplan.hands.formations.registry import ContactSlot, Formation
from qsplan.mechanics.errors import QsplanError
from qsplan.mechanics.model.geometry import CONTACT_TOL

#: The workpiece's turning rate (rad/s) the transition and pivot scenes are built for: negative, clockwise (the
#: workpiece tips right onto its pivot vertex).  Bands depend on its sign only: the quasistatic model is positively
#: homogeneous in the velocities (eqs. 6-11; the tests scale it).
THETA_RATE = -0.05

_LEFT_BASE = ContactSlot("left:base", "left", "any", None, "the left finger flush: the overlap's end toward its base")
_LEFT_TIP = ContactSlot("left:tip", "left", "any", None, "the left finger flush: the overlap's end toward its tip")
_RIGHT = ContactSlot("right", "right", "any", None, "the right finger on its vertex")

#: The names issue 23's hand-built route registered for these two formations; retired by issue 32 (a plan stating
#: one is refused: tests/planner/test_certify_metadata.py).
RETIRED_NAMES = ("flush_to_pivot_v1", "pivot_v1")

#: The flush instant's five contacts in the canonical order, and the transition mode (vertex 0 lifts).
TRANSITION = Formation(
    name="paper_flush_instant",
    contacts=(ContactSlot("palm:0", "palm", "vertex", 0, "the bottom edge's left end on the palm"),
              ContactSlot("palm:1", "palm", "vertex", 1, "the bottom edge's right end on the palm"),
              _LEFT_BASE, _LEFT_TIP, _RIGHT),
    mode="BSSSS", closing="last", description="the paper hand's flush instant (test reference)")

#: The pivot's four contacts in the canonical order, and its mode (4S).
PIVOT = Formation(
    name="paper_pivot",
    contacts=(ContactSlot("palm:1", "palm", "vertex", 1, "the pivot vertex on the palm"), _LEFT_BASE, _LEFT_TIP, _RIGHT),
    mode="SSSS", closing="last", description="the paper hand's clockwise pivot on vertex 1 (test reference)")


@dataclass(frozen=True, slots=True, eq=False)
class FlushInstant:
    """The palm-edge slide's configuration where the left finger lies flush along workpiece ``edge``: ``x`` (m), the
    pose ``(x, y, 0)``, the joints ``q`` (rad, left then right), the right finger's vertex (internal numbering)."""

    x: float
    pose: np.ndarray
    q: np.ndarray
    edge: int
    right_vertex: int


@dataclass(frozen=True, slots=True, eq=False)
class PivotConfigurations:
    """The pivot manifold at ``n`` angles: ``theta`` (n,), ``pose`` (n, 3), ``q`` (n, 2), their rates ``dpose``,
    ``dq`` per unit theta, the world ``vertices`` (n, k, 2), and the pivot vertex, flush edge and right vertex."""

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
    """The hand's paper-form record (finger length, width, joints)."""
    paper = getattr(hand, "paper", hand)
    if paper is None or not hasattr(paper, "finger_base"):
        raise QsplanError("hand: the closed form needs the paper's form (two single-link revolute fingers, Fig. 9)")
    return paper


def left_sides(hand) -> tuple:
    """The workpiece edges (internal numbering) the left finger can lie flush along (the edge's angle, lower end to
    upper end, in (0, pi)), longest first."""
    V = paper_form(hand).workpiece
    d = V - np.roll(V, -1, axis=0)  # upper end (vertex k) minus lower end (vertex k + 1)
    psi = np.arctan2(d[:, 1], d[:, 0])
    ks = np.flatnonzero((psi > 0.0) & (psi < np.pi))
    return tuple(int(k) for k in sorted(ks, key=lambda k: (-np.hypot(*d[k]), k)))


def _flush_edge(paper, edge):
    """``(edge, lower end, upper end, psi)`` of the edge the left finger lies along (default the longest left side)."""
    V = paper.workpiece
    k = left_sides(paper)[0] if edge is None else int(edge)
    lo, hi = V[(k + 1) % len(V)], V[k]  # counter-clockwise: a left side runs downward
    psi = float(np.arctan2(hi[1] - lo[1], hi[0] - lo[0]))
    if not 0.0 < psi < np.pi:
        raise QsplanError(f"edge: workpiece edge {k} is not a left side")
    return k, lo, hi, psi


def _flush_x(paper, q_left, rotated_lo, y):
    """Workpiece x putting the edge's line (through ``rotated_lo + (x, y)``, angle ``q_left``) at half the finger's
    width from the left joint, on the finger's inner side."""
    m = np.stack([-np.sin(q_left), np.cos(q_left)], axis=-1)
    rel = rotated_lo + np.stack([np.zeros_like(y), y], axis=-1) - paper.pivots[0]
    return (-0.5 * paper.finger_width - np.sum(rel * m, axis=-1)) / m[..., 0]


def flush_instant(hand, edge=None) -> FlushInstant:
    """The palm-edge slide's flush instant along ``edge`` (default the longest left side), in closed form:
    ``q_left = psi``, ``x`` from the edge's line at half the finger's width from the joint."""
    from qsplan.hands.paper_hand.two_finger import tangency_angles

    paper = paper_form(hand)
    k, lo, _, psi = _flush_edge(paper, edge)
    y = paper.rest_height
    x = float(_flush_x(paper, np.array(psi), lo, np.array(y)))
    pose = np.array([x, y, 0.0])
    phi, idx, _ = tangency_angles(paper, (paper.workpiece + pose[:2])[None])
    return FlushInstant(x, pose, np.array([psi, phi[0, 1]]), k, int(idx[0, 1]))


def pivot_configurations(hand, theta, pivot: int = 1, edge=None, right_vertex: int = 2) -> PivotConfigurations:
    """The pivot manifold (the module docstring) at angles ``theta`` (rad), in closed form."""
    from qsplan.hands.paper_hand.two_finger import tangency_angles, tangency_rates
    from qsplan.hands.geometry.workpiece import rotation

    paper = paper_form(hand)
    V = paper.workpiece
    k, _, _, psi = _flush_edge(paper, edge)
    theta = np.atleast_1d(np.asarray(theta, dtype=float))
    R = np.stack([rotation(t) for t in theta])  # (n, 2, 2)
    RV = np.einsum("nij,kj->nki", R, V)  # the turned body-frame vertices (n, k, 2)
    perp = np.stack([-RV[..., 1], RV[..., 0]], axis=-1)  # d(R v)/d theta
    y = -RV[:, pivot, 1]
    q_left = psi + theta
    i_lo = (k + 1) % len(V)
    x = _flush_x(paper, q_left, RV[:, i_lo], y)
    W = RV + np.stack([x, y], axis=-1)[:, None, :]
    q = np.column_stack([q_left, tangency_angles(paper, W[:, [right_vertex]])[0][:, 1]])
    # d/dtheta of the left-finger condition f(x, theta) = x m_x + (R v_lo + (0, y) - a) . m + w = 0, dm/dq = -u
    u = np.stack([np.cos(q_left), np.sin(q_left)], axis=-1)
    m = np.stack([-u[:, 1], u[:, 0]], axis=-1)
    dy = -perp[:, pivot, 1]
    rel = RV[:, i_lo] + np.column_stack([np.zeros_like(y), y]) - paper.pivots[0]
    df = -x * u[:, 0] + np.sum((perp[:, i_lo] + np.column_stack([np.zeros_like(dy), dy])) * m, axis=1) \
        - np.sum(rel * u, axis=1)
    dpose = np.column_stack([-df / m[:, 0], dy, np.ones_like(theta)])
    v_right = dpose[:, None, :2] + perp[:, [right_vertex]]  # the right vertex's velocity per unit theta rate
    d = W[:, [right_vertex, right_vertex]] - paper.pivots  # (n, 2 fingers, 2): only the right finger's is used
    dq = np.column_stack([np.ones_like(theta), tangency_rates(paper, d, np.repeat(v_right, 2, axis=1))[:, 1]])
    return PivotConfigurations(theta, np.column_stack([x, y, theta]), q, dpose, dq, W, int(pivot), k, int(right_vertex))


def _named(hand, form, pose, q, edge, right_vertex, pivot=None) -> tuple:
    """The contacts of ``form`` (:data:`TRANSITION` or :data:`PIVOT`) at a configuration, in its order."""
    left, right = form.finger_contacts
    top, out = palm_top_edge(hand), {}
    for i in form.palm_contacts:
        vertex = form.contacts[i].index if pivot is None else pivot
        out[i] = ContactSpec(form.contacts[i].name, "palm", ("vertex", vertex), ("edge", top))
    names = tuple(form.contacts[i].name for i in left)
    out.update(zip(left, flush_contacts(hand, pose, q, "left", edge, finger_inner_edge(hand, "left"), names)))
    out[right[0]] = ContactSpec(form.contacts[right[0]].name, "right", ("vertex", right_vertex),
                                ("edge", finger_inner_edge(hand, "right")))  # fmt: skip
    return tuple(out[i] for i in range(form.n_contacts))


def transition_contacts(hand, instant: FlushInstant) -> tuple:
    """The flush instant's five contacts, in the order of :data:`TRANSITION`."""
    return _named(hand, TRANSITION, instant.pose, instant.q, instant.edge, instant.right_vertex)


def pivot_contacts(hand, pose, q, pivot: int = 1, edge=None, right_vertex: int = 2) -> tuple:
    """The pivot's four contacts at one configuration, in the order of :data:`PIVOT` (the flush overlap's ends,
    whichever features they are there)."""
    k = _flush_edge(paper_form(hand), edge)[0]
    return _named(hand, PIVOT, pose, q, k, right_vertex, pivot)


def _velocities(effort_joint, dq, theta_rate):
    e = np.array([effort_joint == "left", effort_joint == "right"])
    return e, np.asarray(dq, dtype=float) * float(theta_rate)


def transition_scene(hand, instant: FlushInstant, effort_joint: str = "right", theta_rate: float = THETA_RATE, mu=None):
    """The flush instant's five-contact scene, ``effort_joint`` torque-controlled and the other finger driven at its
    pivot-manifold rate for the workpiece turning at ``theta_rate`` (rad/s)."""
    start = pivot_configurations(hand, [0.0], edge=instant.edge, right_vertex=instant.right_vertex)
    e, v = _velocities(effort_joint, start.dq[0], theta_rate)
    return contact_set_scene(hand, instant.pose, instant.q, transition_contacts(hand, instant), e, v, mu=mu)


def pivot_scene(hand, configurations: PivotConfigurations, i: int, effort_joint: str = "right",
                theta_rate: float = THETA_RATE, mu=None, tol: float = CONTACT_TOL):  # fmt: skip
    """The pivot's scene at sample ``i`` of ``configurations``: ``effort_joint`` torque-controlled, the other finger
    driven at its manifold rate."""
    c = configurations
    e, v = _velocities(effort_joint, c.dq[i], theta_rate)
    contacts = pivot_contacts(hand, c.pose[i], c.q[i], c.pivot, c.edge, c.right_vertex)
    return contact_set_scene(hand, c.pose[i], c.q[i], contacts, e, v, mu=mu, tol=tol)


def pivot_band(hand, theta: float, effort_joint: str, mu_range, force_margin=None, theta_rate: float = THETA_RATE):
    """The robust 4S band (:func:`qsplan.mechanics.robust_band`) of the pivot at angle ``theta`` (rad)."""
    from qsplan.mechanics.bands.robust import robust_band

    scene = pivot_scene(hand, pivot_configurations(hand, [theta]), 0, effort_joint, theta_rate)
    return robust_band(scene, PIVOT.mode, mu_range, force_margin=force_margin)


def same_contacts(found, reference, tol: float = CONTACT_TOL) -> bool:
    """Whether ``reference`` (:func:`qsplan.hands.contacts.found.polygon_contacts`) is the located contact set
    ``found`` (:func:`qsplan.hands.contacts.sets.locate_contacts`): as many contacts, each of ``found`` matching one of
    the same body within ``tol`` (m) in its point and normal."""
    if len(reference) != len(found.specs):
        return False
    return all(any(c.body == link and np.hypot(*(c.point - p)) <= tol and np.hypot(*(c.normal - n)) <= tol
                   for c in reference) for p, n, link in zip(found.points, found.normals, found.links))  # fmt: skip
