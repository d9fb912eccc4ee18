"""Every contact the polygons show at a configuration, in one canonical order, as a scene (issue 23).

A plan's rows may hold the workpiece in any formation: on its palm edge, pivoting on a palm vertex, a finger flush
on one of its edges.  Whoever checks a row from the task alone (the certifier, the replays) needs the row's contacts
without the planner's closed forms: :func:`ordered_contacts` finds them with the mechanics' polygon search
(:func:`qsplan.mechanics.model.geometry.find_contacts`, through :func:`polygon_contacts`: the palm and every link of either finger)
and orders them by a rule a reader can apply by eye, the **canonical order** a row's ``mode`` letters follow:

1. the palm's contacts, left to right (by the contact point's world ``x``);
2. then each finger in the hand's order (left, right), its contacts from its base outward (by the contact point's
   distance from the finger's joint).

On the palm edge this is the order of every earlier plan (``palm:0, palm:1, left, right``); at the flush instant
``palm:0, palm:1, left:base, left:tip, right``; on a pivot ``palm:1, left:base, left:tip, right``: the registered
formations' orders (:mod:`qsplan.hands.formations.registry`).  :func:`row_contact_scene` builds the row's scene from
them (:func:`qsplan.hands.contacts.point_scene.points_scene`), and :func:`made_contacts` says which contacts a motion
makes at its last row (a contact open along the motion that reaches it is not part of that motion).  A hold at rest is
proved in :func:`hold_scene`: every contact present, the one made at that instant included.  Paper-form hands (fingers
of one link). Units SI (m, rad).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qsplan.mechanics.errors import QsplanError
from qsplan.mechanics.model.geometry import CONTACT_TOL

__all__ = ["TrackedContacts", "contact_names", "drawable_contacts", "polygon_contacts", "track_contacts", "hold_scene",
           "lifted_contacts", "lifted_scene", "made_contacts", "ordered_contacts", "row_contact_scene", "slot_of"]


def polygon_contacts(hand, pose, q, tol: float = CONTACT_TOL) -> list:
    """The contacts the mechanics' polygon search (:func:`qsplan.mechanics.find_contacts`, the reference) finds
    between the workpiece and the palm and every link of either finger at ``pose``, ``q``: FoundContact, body -1
    for the palm, else the link (its joint's index).

    Raises
    ------
    SceneError
        A body penetrating the workpiece deeper than ``tol`` (naming it), or a corner on a corner.
    """
    from shapely.geometry import Polygon

    from qsplan.mechanics.model.geometry import find_contacts

    polys = hand.body_polygons(np.asarray(pose, dtype=float), np.asarray(q, dtype=float))
    bodies = [(-1, Polygon(polys["palm"]))]
    names = {-1: "palm"}
    for k, joint in enumerate(hand.joint_names):
        if joint in polys:
            bodies.append((k, Polygon(polys[joint])))
            names[k] = joint
    return find_contacts(Polygon(polys["workpiece"]), bodies, tol=tol, body_names=names)


def ordered_contacts(hand, pose, q, tol: float = CONTACT_TOL) -> list:
    """The contacts the polygon search finds at ``pose``, ``q``, in the canonical order (module docstring):
    :class:`qsplan.mechanics.model.geometry.FoundContact` (``body`` -1 for the palm, else the finger's link).

    Raises
    ------
    SceneError
        A body penetrating the workpiece deeper than ``tol`` (naming it), or a corner on a corner.
    """
    found = polygon_contacts(hand, pose, q, tol)
    axes = hand.joint_axes(np.asarray(q, dtype=float))
    place = {j: (f, i) for f, chain in enumerate(_finger_joints(hand)) for i, j in enumerate(chain)}

    def key(c):  # the palm left to right; each finger (left, right), its links base to tip, each from its joint out
        if c.body < 0:
            return (0, 0, 0, float(c.point[0]))
        f, i = place[c.body]
        return (1, f, i, float(np.hypot(*(c.point - axes[c.body]))))

    return sorted(found, key=key)


def _finger_joints(hand) -> tuple:
    """Each finger's joints (indices), base to tip: left, right."""
    names = list(hand.joint_names)
    return tuple(tuple(names.index(n) for n in chain) for chain in hand.finger_joint_names)


def contact_names(hand, pose, contacts) -> tuple:
    """Names of ``contacts`` (canonical order): a palm contact ``palm:K`` (K the internal workpiece vertex at its
    point, ``palm:edge`` for a palm corner on a workpiece edge); a finger's ``left``/``right`` when it has one
    contact, ``left:base``/``left:tip`` with two, ``left:1``, ``left:2``, ... with more."""
    from qsplan.hands.geometry.workpiece import workpiece_world

    W = workpiece_world(hand, pose)
    out = []
    fingers = _finger_joints(hand)
    for c in contacts:
        if c.body < 0:
            d = np.hypot(*(W - c.point).T)
            out.append(f"palm:{int(np.argmin(d))}" if d.min() <= CONTACT_TOL else "palm:edge")
    for f, side in enumerate(("left", "right")):
        mine = [c for c in contacts if c.body in fingers[f]]
        if len(mine) == 1:
            out.append(side)
        elif len(mine) == 2:
            out += [f"{side}:base", f"{side}:tip"]
        else:
            out += [f"{side}:{i + 1}" for i in range(len(mine))]
    return tuple(out)


def made_contacts(hand, before, after, contacts) -> np.ndarray:
    """Which of ``contacts`` (found at configuration ``after``) a motion from ``before`` makes only at ``after``:
    each contact found at ``before`` claims the nearest contact of its body at ``after``; the unclaimed ones were
    open along the motion.  ``before``, ``after``: ``(pose, q)``.  Returns bool, shape (n_c,)."""
    prev = ordered_contacts(hand, *before)
    made = np.ones(len(contacts), dtype=bool)
    for p in prev:
        mine = [i for i, c in enumerate(contacts) if c.body == p.body and made[i]]
        if mine:
            made[min(mine, key=lambda i: np.hypot(*(contacts[i].point - p.point)))] = False
    return made


def row_contact_scene(hand, pose, q, effort_controlled, velocity, effort=None, mu=None, drop=None, found=None):
    """The scene of every contact found at ``pose``, ``q`` in the canonical order
    (:func:`qsplan.hands.contacts.point_scene.points_scene`), without those flagged in ``drop`` (bool, shape (n_found,):
    contacts :func:`made_contacts` made at this row); ``found``: :func:`ordered_contacts` there, when already searched.

    Raises
    ------
    SceneError
        As :func:`ordered_contacts`; QsplanError when no contact is left.
    """
    from qsplan.hands.contacts.point_scene import points_scene

    found = ordered_contacts(hand, pose, q) if found is None else found
    names = contact_names(hand, pose, found)
    keep = np.ones(len(found), dtype=bool) if drop is None else ~np.asarray(drop, dtype=bool)
    if not keep.any():
        raise QsplanError("contacts: the workpiece touches nothing at this configuration")
    found = [c for c, k in zip(found, keep) if k]
    names = [n for n, k in zip(names, keep) if k]
    return points_scene(hand, pose, q, [c.point for c in found], [c.normal for c in found],
                        [c.body for c in found], names, effort_controlled, velocity, effort, mu)  # fmt: skip


def hold_scene(hand, pose, q, effort_controlled, effort=None):
    """The scene a hold at rest is proved in (:func:`qsplan.mechanics.bands.hold.prove_hold`): the one rule of the
    planner's holds and the certifier's.

    At rest every contact present can push: a hold's admissible motions must keep every one of them closed or
    opening, so the scene has every contact the polygons show at ``pose``, ``q`` (:func:`ordered_contacts`), a contact
    made at this instant included: the mode of the motion that reaches a phase's last row leaves such a contact out
    (:func:`made_contacts`; it opens along that motion), a hold at the same instant does not.  The velocity-controlled
    joints are held (velocity 0); ``effort``: the effort-controlled joints' efforts (N m or N; a proof takes its
    torques apart).

    Raises
    ------
    SceneError
        As :func:`ordered_contacts`; QsplanError when no contact is found.
    """
    e = np.asarray(effort_controlled, dtype=bool)
    held = np.zeros(e.size)  # the velocity-controlled joints still; an effort-controlled joint's velocity is not used
    return row_contact_scene(hand, pose, q, e, held, effort=effort)


def lifted_scene(hand, pose, q, finger: str):
    """The scene a hold with ``finger`` (``"left"`` or ``"right"``) lifted is proved in
    (:func:`qsplan.mechanics.bands.friction_hold.prove_friction_hold`): the one rule of the planner's finger replaced
    mid-turn and the certifier's.  Every contact the polygons show at ``pose``, ``q`` except ``finger``'s (while it
    leaves, moves and closes again it pushes nothing: a contact it keeps at zero force while receding is a motion of
    the others), every joint held (velocity 0, none torque-controlled).

    Raises
    ------
    SceneError
        As :func:`ordered_contacts`; QsplanError when only ``finger`` touches the workpiece.
    """
    found, _, lifted = lifted_contacts(hand, pose, q, finger)
    n_j = len(hand.joint_names)
    return row_contact_scene(hand, pose, q, np.zeros(n_j, dtype=bool), np.zeros(n_j), drop=lifted, found=found)


def lifted_contacts(hand, pose, q, finger: str) -> tuple:
    """``(found, names, lifted)``: every contact the polygons show at ``pose``, ``q`` (:func:`ordered_contacts`), their
    names (:func:`contact_names`) and which are ``finger``'s (bool, shape (n_found,)): what lifting it leaves.

    Raises
    ------
    SceneError
        As :func:`ordered_contacts`.
    """
    found = ordered_contacts(hand, pose, q)
    names = contact_names(hand, pose, found)
    return found, names, np.array([n.split(":")[0] == finger for n in names], dtype=bool)


def drawable_contacts(hand, pose, q) -> list:
    """The contacts to draw at ``pose``, ``q``: as the polygons show them (:func:`ordered_contacts`)."""
    return ordered_contacts(hand, pose, q)


@dataclass(frozen=True, slots=True)
class TrackedContacts:
    """Contacts found once by the polygon search, followed by their features at later configurations: each a vertex
    of one body on an edge of the other (``(body link or -1 for the palm, workpiece vertex or None, workpiece edge or
    None, body vertex or None, body edge or None)``), located again in closed form (:meth:`scene`), for a simulation
    whose contact set does not change (the replay of one phase).  The names are those at the configuration found.
    """

    names: tuple
    features: tuple

    def scene(self, hand, pose, q, effort_controlled, velocity, effort=None, mu=None):
        """The scene of these contacts at ``pose``, ``q`` (:func:`qsplan.hands.contacts.point_scene.points_scene`)."""
        from qsplan.hands.contacts.point_scene import points_scene

        polys = _polygons(hand, pose, q)
        W = polys[None]
        points, normals = [], []
        for link, wv, we, bv, be in self.features:
            B = polys[link]
            if wv is not None:  # a workpiece vertex on a body edge: the edge's outward normal (into the workpiece)
                points.append(W[wv])
                normals.append(_outward_normal(B, be))
            else:  # a body vertex on a workpiece edge: the edge's inward normal
                points.append(B[bv])
                normals.append(-_outward_normal(W, we))
        return points_scene(hand, pose, q, points, normals, [f[0] for f in self.features], self.names,
                            effort_controlled, velocity, effort, mu)  # fmt: skip


def _polygons(hand, pose, q) -> dict:
    """``{None: workpiece, -1: palm, link: link polygon}`` in the world (m)."""
    polys = hand.body_polygons(np.asarray(pose, dtype=float), np.asarray(q, dtype=float))
    out = {None: np.asarray(polys["workpiece"], float), -1: np.asarray(polys["palm"], float)}
    out.update((k, np.asarray(polys[n], float)) for k, n in enumerate(hand.joint_names) if n in polys)
    return out


def _outward_normal(P, k) -> np.ndarray:
    """Edge ``k``'s (vertex ``k`` to ``k + 1``) outward unit normal of the ring ``P``."""
    d = P[(k + 1) % len(P)] - P[k]
    x, y = P[:, 0], P[:, 1]
    ccw = float(x[:-1] @ y[1:] - x[1:] @ y[:-1] + x[-1] * y[0] - x[0] * y[-1]) > 0.0
    m = np.array([d[1], -d[0]]) if ccw else np.array([-d[1], d[0]])
    return m / np.hypot(*m)


def _nearest_edge(P, point) -> int:
    """The edge of the ring ``P`` nearest ``point``."""
    a, b = P, np.roll(P, -1, axis=0)
    d = b - a
    s = np.clip(np.sum((point - a) * d, axis=1) / np.sum(d * d, axis=1), 0.0, 1.0)
    return int(np.argmin(np.hypot(*(a + s[:, None] * d - point).T)))


def track_contacts(hand, pose, q, drop=None) -> TrackedContacts:
    """The contacts the polygons show at ``pose``, ``q`` (:func:`ordered_contacts`, canonical order, without those
    flagged in ``drop``), as features to follow (:class:`TrackedContacts`): where a contact's point is a workpiece
    vertex (within the contact tolerance) it is that vertex on the body's nearest edge, else the body's vertex on the
    workpiece's nearest edge (an end of a flush overlap is whichever vertex bounds it)."""
    found = ordered_contacts(hand, pose, q)
    keep = np.ones(len(found), bool) if drop is None else ~np.asarray(drop, bool)
    names = [n for n, k in zip(contact_names(hand, pose, found), keep) if k]
    polys = _polygons(hand, pose, q)
    W = polys[None]
    features = []
    for c in (c for c, k in zip(found, keep) if k):
        B = polys[c.body]
        dw, db = np.hypot(*(W - c.point).T), np.hypot(*(B - c.point).T)
        if dw.min() <= CONTACT_TOL and (c.kind != "edge-vertex" or db.min() > CONTACT_TOL):
            features.append((c.body, int(np.argmin(dw)), None, None, _nearest_edge(B, c.point)))
        else:
            features.append((c.body, None, _nearest_edge(W, c.point), int(np.argmin(db)), None))
    return TrackedContacts(tuple(names), tuple(features))


def slot_of(name: str, slots) -> int | None:
    """Which of ``slots`` (a formation's contact names, e.g. the palm edge's ``palm:0, palm:1, left, right``) the
    canonical contact ``name`` sits on: a palm contact on the slot of its own name, a finger's (``left:base``,
    ``left:tip``) on that finger's; None where ``slots`` has none (a palm contact under another vertex)."""
    body = name.split(":")[0]
    key = name if body == "palm" else body
    return list(slots).index(key) if key in slots else None
