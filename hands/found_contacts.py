"""Every contact the polygons show at a configuration, in one canonical order, as a scene (issue 23).

A plan's rows may hold the workpiece in any formation: on its palm edge, pivoting on a palm vertex, a finger flush
on one of its edges.  Whoever checks a row from the task alone (the certifier, the replays) needs the row's contacts
without the planner's closed forms: :func:`ordered_contacts` finds them with the mechanics' polygon search
(:func:`qsplan.mechanics.model.geometry.find_contacts`, through :func:`qsplan.hands.pivot_sweep.polygon_contacts`)
and orders them by a rule a reader can apply by eye, the **canonical order** a row's ``mode`` letters follow:

1. the palm's contacts, left to right (by the contact point's world ``x``);
2. then each finger in the hand's order (left, right), its contacts from its base outward (by the contact point's
   distance from the finger's joint).

On the palm edge this is the order of every earlier plan (``palm:0, palm:1, left, right``); at the flush instant
``palm:0, palm:1, left:base, left:tip, right``; on a pivot ``palm:1, left:base, left:tip, right``: the registered
formations' orders (:mod:`qsplan.hands.formations`).  :func:`row_contact_scene` builds the row's scene from them
(:func:`qsplan.hands.point_scene.points_scene`), and :func:`made_contacts` says which contacts a motion makes at its last row (a contact
open along the motion that reaches it is not part of that motion).  A hold at rest is proved in :func:`hold_scene`:
every contact present, the one made at that instant included.  Paper-form hands (fingers of one link).
Units SI (m, rad).
"""

from __future__ import annotations

import numpy as np

from qsplan.mechanics.errors import QsplanError
from qsplan.mechanics.model.geometry import CONTACT_TOL

__all__ = ["contact_names", "drawable_contacts", "hold_scene", "made_contacts", "ordered_contacts", "row_contact_scene",
           "slot_of"]


def ordered_contacts(hand, pose, q, tol: float = CONTACT_TOL) -> list:
    """The contacts the polygon search finds at ``pose``, ``q``, in the canonical order (module docstring):
    :class:`qsplan.mechanics.model.geometry.FoundContact` (``body`` -1 for the palm, else the finger's link).

    Raises
    ------
    SceneError
        A body penetrating the workpiece deeper than ``tol`` (naming it), or a corner on a corner.
    """
    from qsplan.hands.contact_sets import finger_link
    from qsplan.hands.interface import joint_axes
    from qsplan.hands.pivot_sweep import polygon_contacts

    found = polygon_contacts(hand, pose, q, tol)
    axes = joint_axes(hand, np.asarray(q, dtype=float))
    fingers = [finger_link(hand, b) for b in ("left", "right")]

    def key(c):
        if c.body < 0:
            return (0, 0, float(c.point[0]))
        return (1, fingers.index(c.body), float(np.hypot(*(c.point - axes[c.body]))))

    return sorted(found, key=key)


def contact_names(hand, pose, contacts) -> tuple:
    """Names of ``contacts`` (canonical order): a palm contact ``palm:K`` (K the internal workpiece vertex at its
    point, ``palm:edge`` for a palm corner on a workpiece edge); a finger's ``left``/``right`` when it has one
    contact, ``left:base``/``left:tip`` with two, ``left:1``, ``left:2``, ... with more."""
    from qsplan.hands.contact_sets import finger_link
    from qsplan.hands.workpiece import workpiece_world

    W = workpiece_world(hand, pose)
    out = []
    for c in contacts:
        if c.body < 0:
            d = np.hypot(*(W - c.point).T)
            out.append(f"palm:{int(np.argmin(d))}" if d.min() <= CONTACT_TOL else "palm:edge")
    for side in ("left", "right"):
        mine = [c for c in contacts if c.body == finger_link(hand, side)]
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
    (:func:`qsplan.hands.point_scene.points_scene`), without those flagged in ``drop`` (bool, shape (n_found,):
    contacts :func:`made_contacts` made at this row); ``found``: :func:`ordered_contacts` there, when already searched.

    Raises
    ------
    SceneError
        As :func:`ordered_contacts`; QsplanError when no contact is left.
    """
    from qsplan.hands.point_scene import points_scene

    found = ordered_contacts(hand, pose, q) if found is None else found
    names = contact_names(hand, pose, found)
    keep = np.ones(len(found), dtype=bool) if drop is None else ~np.asarray(drop, dtype=bool)
    if not keep.any():
        raise QsplanError("contacts: the workpiece touches nothing at this configuration")
    found = [c for c, k in zip(found, keep) if k]
    names = [n for n, k in zip(names, keep) if k]
    return points_scene(hand, pose, q, [c.point for c in found], [c.normal for c in found],
                        [c.body for c in found], names, effort_controlled, velocity, effort, mu)  # fmt: skip


def hold_scene(hand, pose, q, effort_controlled, effort=None, method: str = "auto"):
    """The scene a hold at rest is proved in (:func:`qsplan.mechanics.bands.hold.prove_hold`): the one rule of the
    planner's holds and the certifier's.

    At rest every contact present can push: a hold's admissible motions must keep every one of them closed or
    opening.  A hand that reorients (:attr:`qsplan.hands.protocol.Hand.reorients`, any formation) therefore has every
    contact the polygons show at ``pose``, ``q`` (:func:`ordered_contacts`), a contact made at this instant included:
    the mode of the motion that reaches a phase's last row leaves such a contact out (:func:`made_contacts`; it opens
    along that motion), a hold at the same instant does not.  Any other hand has its formation's four contacts
    (:func:`qsplan.hands.interface.scene_at` by ``method``).  The velocity-controlled joints are held (velocity 0);
    ``effort``: the effort-controlled joints' efforts (N m or N; a proof takes its torques apart).

    Raises
    ------
    SceneError
        As :func:`ordered_contacts` or :func:`~qsplan.hands.interface.scene_at`; QsplanError when no contact is found.
    """
    from qsplan.hands.interface import scene_at

    e = np.asarray(effort_controlled, dtype=bool)
    held = np.zeros(e.size)  # the velocity-controlled joints still; an effort-controlled joint's velocity is not used
    if hand.reorients:
        return row_contact_scene(hand, pose, q, e, held, effort=effort)
    return scene_at(hand, pose, q, e, held, effort=effort, method=method)


def drawable_contacts(hand, pose, q) -> list:
    """The contacts to draw at ``pose``, ``q``: a hand that reorients, as the polygons show them (any formation,
    :func:`ordered_contacts`); any other, its grasp's (:func:`qsplan.hands.interface.contacts_at`)."""
    from qsplan.hands.interface import contacts_at

    return ordered_contacts(hand, pose, q) if hand.reorients else contacts_at(hand, pose, q)


def slot_of(name: str, slots) -> int | None:
    """Which of ``slots`` (a formation's contact names, e.g. the palm edge's ``palm:0, palm:1, left, right``) the
    canonical contact ``name`` sits on: a palm contact on the slot of its own name, a finger's (``left:base``,
    ``left:tip``) on that finger's; None where ``slots`` has none (a palm contact under another vertex)."""
    body = name.split(":")[0]
    key = name if body == "palm" else body
    return list(slots).index(key) if key in slots else None
