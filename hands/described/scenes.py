"""A described hand's scenes at many states of a grasp: the contacts the closing knows, checked (Section 3, eqs. 1-5).

At a state of :func:`qsplan.hands.described.states.generic_states` the formation's contacts are known:
the workpiece's bottom edge on the palm and each finger's closing contact.  :func:`contacts_decided`
checks, for every state at once and with margins, that the polygon search
(:func:`qsplan.mechanics.model.geometry.find_contacts`, the reference) would find exactly these and
nothing else: each known contact within ``NEAR`` contact tolerances; every other (body vertex, workpiece
edge) and (workpiece vertex, body edge) pair of the palm and every link beyond ``FAR``; no workpiece
edge at a known vertex contact facing the body's edge (an edge-edge contact, whose normal the search
takes from the workpiece); a link with no contact apart from the workpiece (separating axis).  The
margins are those of the paper hand's closed form (:data:`qsplan.hands.paper_hand.analytic.NEAR`,
:data:`~qsplan.hands.paper_hand.analytic.FAR`), so rounding never decides which contacts a scene has.
Where the search surely finds no scene of the formation (a link without a contact overlapping the
workpiece; a second feature pair of a finger touching well apart from its contact) the state is refused
without it.  :func:`generic_scene_arrays` builds the model's arrays of the decided states in one batch
(:func:`qsplan.hands.chains.arrays.scene_arrays_of`) and the few others by the polygon search (as
:func:`qsplan.hands.chains.hand.chain_scene`), which says what the polygons give.  Units SI.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qsplan.hands.chains.arrays import scene_arrays_of
from qsplan.hands.chains.closing_batch import ccw_ring, edge_normals, following, link_poses_batch, separation_batch
from qsplan.hands.described.states import SINGULAR_TOL, check_formation
from qsplan.hands.protocol import SINGULAR, STATE_REASONS, GraspSceneArrays
from qsplan.hands.paper_hand.analytic import FAR, NEAR
from qsplan.mechanics.errors import QsplanError
from qsplan.mechanics.model.geometry import CONTACT_TOL

__all__ = ["ContactView", "contact_view", "contacts_decided", "generic_scene_arrays", "state_scene_of"]

#: A vertex whose turn is below this relative size is straight: the polygon search drops it
#: (:mod:`qsplan.mechanics.model.geometry`, 1e-12), which the pair test below does not; a hand with one takes the
#: polygon search at every state.  A thousand times coarser than the search's own test, to be safe.
_STRAIGHT_TOL = 1e-9


@dataclass(frozen=True, slots=True, eq=False)
class ContactView:
    """A hand's bodies as :func:`contacts_decided` tests them: each counter-clockwise, convex, no straight vertex.

    Attributes
    ----------
    palm : ndarray, shape (p, 2)
        World frame (m).
    top : int
        The palm edge on ``y = 0`` (its index in ``palm``).
    links : tuple of (int, ndarray (k, 2))
        Each link with a shape: its joint index and ring (its frame, m).
    names : tuple of str
        Each joint's name.
    finger : tuple of int
        Each joint's finger (0 left, 1 right).
    closing : (int, int)
        Each finger's closing joint.
    """

    palm: np.ndarray
    top: int
    links: tuple
    names: tuple
    finger: tuple
    closing: tuple


def _plain_convex(ring) -> bool:
    """Whether the counter-clockwise ``ring`` (k, 2) is strictly convex, every turn clear of :data:`_STRAIGHT_TOL`."""
    d_prev, d_next = ring - np.roll(ring, 1, axis=0), np.roll(ring, -1, axis=0) - ring
    turn = d_prev[:, 0] * d_next[:, 1] - d_prev[:, 1] * d_next[:, 0]
    return bool(np.all(turn > _STRAIGHT_TOL * np.linalg.norm(d_prev, axis=1) * np.linalg.norm(d_next, axis=1)))


def contact_view(desc) -> ContactView | None:
    """The :class:`ContactView` of a hand description, or None where a body is not convex or has a straight vertex
    (then every state takes the polygon search)."""
    man = desc.manipulator
    palm = ccw_ring(man.base_shape)
    links = tuple((i, ccw_ring(j.link_shape)) for i, j in enumerate(man.joints) if j.link_shape is not None)
    if not _plain_convex(palm) or not all(_plain_convex(r) for _, r in links):
        return None
    top = np.flatnonzero((palm[:, 1] == 0.0) & (np.roll(palm, -1, axis=0)[:, 1] == 0.0))
    finger = tuple(("left", "right").index(name) for name in desc.finger_of_joint)
    closing = tuple(int(f.joints[-1]) for f in desc.fingers)
    return ContactView(palm, int(top[0]), links, man.joint_names, finger, closing) if top.size == 1 else None


def _segment_distances(P, A, B) -> np.ndarray:
    """Distances (m) from points ``P`` (m, a, 2) to segments ``A -> B`` (m, b, 2), shape (m, a, b)."""
    d = (B - A)[:, None]
    rel = P[:, :, None] - A[:, None]
    t = np.clip(np.sum(rel * d, axis=3) / np.sum(d * d, axis=3), 0.0, 1.0)
    return np.hypot(rel[..., 0] - t * d[..., 0], rel[..., 1] - t * d[..., 1])


def _facing(W, edges, e0, e1, normal, near, far) -> np.ndarray:
    """Where a workpiece edge of ``edges`` (m,) may face the body edge ``e0 -> e1`` (m, 2) with both ends of their
    overlap near its line (``normal`` (m, 2) its unit normal into the workpiece): an edge-edge contact the polygon
    search could see (its test, loosened by the margins: a superset)."""
    r, k = np.arange(len(W)), W.shape[1]
    f0, f1 = W[r, edges], W[r, (edges + 1) % k]
    u = f1 - f0
    size = np.hypot(u[:, 0], u[:, 1])
    u = u / size[:, None]
    se0, se1 = np.sum((e0 - f0) * u, axis=1), np.sum((e1 - f0) * u, axis=1)
    lo, hi = np.maximum(0.0, np.minimum(se0, se1)), np.minimum(size, np.maximum(se0, se1))
    off, slope = np.sum((f0 - e0) * normal, axis=1), np.sum(u * normal, axis=1)
    return (hi - lo >= near) & (np.maximum(off + lo * slope, off + hi * slope) <= far)


def contacts_decided(view: ContactView, formation, touched, edge, points, W, link_poses,
                     tol: float = CONTACT_TOL) -> tuple:  # fmt: skip
    """Where the polygon search finds exactly the formation's contacts at ``m`` closed states (see the module docstring).

    Parameters
    ----------
    view : ContactView
    formation : qsplan.hands.formations.registry.Formation
        Checked by :func:`qsplan.hands.described.states.check_formation`.
    touched : ndarray of int, shape (m, 2)
        Each finger's workpiece feature (internal numbering): a vertex, or where ``edge`` an edge.
    edge : ndarray of bool, shape (m, 2)
        Each finger touches with a link corner on a workpiece edge.
    points : ndarray, shape (m, n_c, 2)
        The formation's contact points (m), every finger touching.
    W : ndarray, shape (m, k, 2)
        The workpiece at each state, world (m).
    link_poses : ndarray, shape (m, n_j, 3)
    tol : float
        The polygon search's contact tolerance (m).

    Returns
    -------
    decided : ndarray of bool, shape (m,)
        The search finds exactly the known contacts.
    refused : ndarray of object, shape (m,)
        Where the search finds no scene of the formation, why (else None): a link without a contact overlapping the
        workpiece (separating axes: the search finds a penetration or another contact), or a feature pair of a
        finger's link within ``NEAR`` tolerances other than its contact, more than ``FAR + 1`` tolerances from it (the
        search finds a second contact on the finger: points closer than a tolerance are one contact).
    """
    near, far = NEAR * tol, FAR * tol
    _, vertices, fingers = check_formation(formation)
    m, k = W.shape[:2]
    r = np.arange(m)
    W1 = following(W)
    palm = np.broadcast_to(view.palm, (m,) + view.palm.shape)
    d_wv = _segment_distances(W, palm, following(palm))  # (m, k, p)
    known = np.zeros(d_wv.shape, bool)
    known[:, list(vertices), view.top] = True
    ok = np.all(np.where(known, d_wv <= near, d_wv > far), axis=(1, 2))
    ok &= np.all(_segment_distances(palm, W, W1) > far, axis=(1, 2))
    e0, e1 = (np.broadcast_to(view.palm[i % len(view.palm)], (m, 2)) for i in (view.top, view.top + 1))
    for v in vertices:  # the workpiece edges at the palm contacts, but the one lying on the palm
        for e in ((v - 1) % k, v):
            if {e, (e + 1) % k} != set(vertices):
                ok &= ~_facing(W, np.full(m, e), e0, e1, np.broadcast_to((0.0, 1.0), (m, 2)), near, far)
    slot_of = {j: (f, i) for f, (i, j) in enumerate(zip(fingers, view.closing))}
    refused = np.full(m, None, dtype=object)
    for j, ring in view.links:
        c, s = np.cos(link_poses[:, j, 2])[:, None], np.sin(link_poses[:, j, 2])[:, None]
        R = np.stack([c * ring[None, :, 0] - s * ring[None, :, 1], s * ring[None, :, 0] + c * ring[None, :, 1]], axis=2)
        R = R + link_poses[:, j, None, :2]
        R1 = following(R)
        d_wv, d_bv = _segment_distances(W, R, R1), _segment_distances(R, W, W1)  # (m, k, l), (m, l, k)
        known_w, known_b = np.zeros(d_wv.shape, bool), np.zeros(d_bv.shape, bool)
        f, slot = slot_of.get(j, (None, None))
        far_w = far_b = np.ones((m, 1, 1), bool)  # where a pair's vertex lies far from the link's contact
        if f is None:  # no contact on this link: apart from the workpiece
            sep = separation_batch(R, W)
            for i in np.flatnonzero((sep <= 0.0) & (refused == None)):  # noqa: E711 (elementwise)
                refused[i] = (f"link {j} ({view.names[j]!r}) overlaps the workpiece ({-sep[i]:.6g} m deep on a "
                              "separating axis)")  # fmt: skip
            ok &= sep > 0.0
        else:
            feature, tip = touched[:, f], edge[:, f]
            # a link corner on workpiece edge ``feature``: the nearest corner; a workpiece vertex on a link edge: the
            # nearest edge, and no workpiece edge at the vertex facing it
            lf = np.where(tip, np.argmin(d_bv[r, :, feature], axis=1), np.argmin(d_wv[r, feature], axis=1))
            known_b[r[tip], lf[tip], feature[tip]] = True
            known_w[r[~tip], feature[~tip], lf[~tip]] = True
            normal = edge_normals(R)[0][r, lf]
            for e in ((feature - 1) % k, feature):
                ok &= tip | ~_facing(W, e, R[r, lf], R1[r, lf], normal, near, far)
            point = points[:, slot]
            far_w = (np.hypot(*(W - point[:, None]).transpose(2, 0, 1)) > far + tol)[:, :, None]
            far_b = (np.hypot(*(R - point[:, None]).transpose(2, 0, 1)) > far + tol)[:, :, None]
        ok &= np.all(np.where(known_w, d_wv <= near, d_wv > far), axis=(1, 2))
        ok &= np.all(np.where(known_b, d_bv <= near, d_bv > far), axis=(1, 2))
        second = np.any(~known_w & (d_wv <= near) & far_w, axis=(1, 2))
        second |= np.any(~known_b & (d_bv <= near) & far_b, axis=(1, 2))
        for i in np.flatnonzero(second & (refused == None)):  # noqa: E711 (elementwise)
            side = ("left", "right")[view.finger[j]]
            refused[i] = f"a second contact on the {side} finger (link {j}, {view.names[j]!r})"
    return ok & (refused == None), refused  # noqa: E711 (elementwise)


def _decisions(hand, formation, states, at) -> tuple:
    """:func:`contacts_decided` at the states ``at`` (int array) of ``states`` (every one ok): once per closing for
    every closed state of it where the closing was kept (the grasps of one closing share it), else here."""
    from qsplan.hands.described.states import closing_key, formation_contacts

    closing = hand.closings.get(closing_key(states.x, states.q[:, list(hand.free_joints)]))
    if closing is None:
        sub = states.take(at)
        W = sub.poses[:, None, :2] + hand.workpiece[None]
        edge = np.broadcast_to(states.tip, (len(at), 2))
        return contacts_decided(hand.contact_view, formation, sub.touched, edge, sub.points, W,
                                link_poses_batch(hand.manipulator, sub.q))  # fmt: skip
    if formation.name not in closing.decisions:
        left, right = closing.closed
        rows = np.flatnonzero(left.found & right.found & ~left.flush & ~right.flush)
        decided, refused = np.zeros(len(closing.q), bool), np.full(len(closing.q), None, dtype=object)
        if rows.size:
            points = formation_contacts(formation, closing.W[rows], [c.take(rows) for c in closing.closed])[0]
            touched = np.column_stack([left.feature[rows], right.feature[rows]])
            edge = np.column_stack([left.kind[rows] == 0, right.kind[rows] == 0])
            poses = link_poses_batch(hand.manipulator, closing.q[rows])
            decided[rows], refused[rows] = contacts_decided(hand.contact_view, formation, touched, edge, points,
                                                            closing.W[rows], poses)  # fmt: skip
        closing.decisions[formation.name] = (decided, refused)
    decided, refused = closing.decisions[formation.name]
    return decided[at], refused[at]


def _words(n: int) -> str:
    from qsplan.hands.paper_hand.accelerator import NUMBER_WORDS

    return NUMBER_WORDS.get(n, str(n))


def _contact_name(hand, body: int, i: int) -> str:
    """A scene's contact name, as the polygon search's scenes give it (``"palm:0"``, ``"left_distal:2"``)."""
    return f"{'palm' if body < 0 else hand.joint_names[body]}:{i}"


def _searched(hand, formation, pose, q) -> tuple:
    """``(scene, bodies (n_c,))`` the polygon search gives at one state, its contacts in the formation's order.

    Raises
    ------
    QsplanError
        Naming what the polygons give instead of the formation's contacts (or why they give none).
    """
    from qsplan.hands.chains.hand import chain_geometric_scene
    from qsplan.mechanics.model.geometric_scene import find_scene_contacts, scene_from_geometric_scene

    palm, _, fingers = check_formation(formation)
    n_j = len(hand.joint_names)
    gs = chain_geometric_scene(hand.chain, pose, q, np.zeros(n_j, bool), np.zeros(n_j))
    found = find_scene_contacts(gs)
    finger_of = {j: f for f in range(2) for j in hand.finger_joints[f]}
    where = [-1 if c.body < 0 else finger_of[c.body] for c in found]
    if where != [-1] * len(palm) + [0] * (len(fingers) > 0) + [1] * (len(fingers) > 1):
        names = [gs.body_name(c.body) for c in found]
        raise QsplanError(f"contacts: expected {formation.n_contacts} ({', '.join(formation.contact_names)}); found "
                          f"{names} at q = {np.round(gs.q, 6).tolist()}")  # fmt: skip
    order = list(palm) + list(fingers)  # the search lists the palm's first, then by link: left, right
    contacts = [None] * len(found)
    for slot, c in zip(order, found):
        contacts[slot] = c
    return scene_from_geometric_scene(gs, contacts), np.array([c.body for c in contacts])


def generic_scene_arrays(hand, formation, states, idx=None) -> GraspSceneArrays:
    """The scene arrays of ``states`` (:class:`qsplan.hands.protocol.GraspStates`) at ``idx`` (default: where ok), by the
    generic path: the closing's contacts where :func:`contacts_decided` says the polygons give them, the polygon
    search elsewhere (see the module docstring).

    Returns
    -------
    GraspSceneArrays
        ``ok`` False where the state is not ok or the polygons give another contact set (``reasons`` says which).
    """
    idx = np.flatnonzero(states.ok) if idx is None else np.asarray(idx, dtype=int).reshape(-1)
    sub = states.take(idx)
    m, n_c, n_j = len(idx), formation.n_contacts, len(hand.joint_names)
    Wn, Wt = np.full((m, 3, n_c), np.nan), np.full((m, 3, n_c), np.nan)
    Jn, Jt = np.full((m, n_c, n_j), np.nan), np.full((m, n_c, n_j), np.nan)
    g_obj, g_man = np.full((m, 3), np.nan), np.full((m, n_j), np.nan)
    bodies, dq = sub.bodies.copy(), sub.dq_dx.copy()
    ok = sub.ok.copy()
    reasons = [None if o else STATE_REASONS.get(int(c)) for o, c in zip(ok, sub.reason)]
    rows = np.flatnonzero(ok)
    link_poses = link_poses_batch(hand.manipulator, sub.q[rows])
    decided, refused = np.zeros(rows.size, bool), np.full(rows.size, None, dtype=object)
    if hand.contact_view is not None and rows.size:
        decided, refused = _decisions(hand, formation, states, idx[rows])
        for i in np.flatnonzero(refused != None):  # noqa: E711 (elementwise)
            ok[rows[i]], reasons[rows[i]] = False, f"no {_words(n_c)}-contact scene: {refused[i]}"
    at = rows[decided]
    if at.size:
        arrays = scene_arrays_of(hand.manipulator, hand.workpiece_mass, sub.poses[at], link_poses[decided],
                                 sub.points[at], sub.normals[at], bodies[at])  # fmt: skip
        for a, v in zip((Wn, Wt, Jn, Jt, g_obj, g_man), arrays):
            a[at] = v
    fallback = {}
    _, _, fingers = check_formation(formation)
    # rare: the polygon search decides (a contact near a corner, a link near the workpiece)
    for k in rows[~decided & (refused == None)].tolist():  # noqa: E711 (elementwise)
        try:
            scene, bodies[k] = _searched(hand, formation, sub.poses[k], sub.q[k])
        except QsplanError as exc:
            ok[k], reasons[k] = False, f"no {_words(n_c)}-contact scene: {exc}"
            continue
        for a, name in zip((Wn, Wt, Jn, Jt, g_obj, g_man), ("Wn", "Wt", "Jn", "Jt", "g_obj", "g_man")):
            a[k] = getattr(scene, name)
        for i, j in zip(fingers, hand.closing_joints):  # eq. 6 with equality at these contacts (see generic_states)
            jn = scene.Jn[i, j]
            if abs(jn) < SINGULAR_TOL:
                ok[k], reasons[k] = False, STATE_REASONS[SINGULAR]
            else:
                dq[k, j] = scene.Wn[0, i] / jn
        if ok[k]:
            fallback[k] = scene
    return GraspSceneArrays(idx, Wn, Wt, Jn, Jt, g_obj, g_man, bodies, dq, ok, tuple(reasons), fallback)


def state_scene_of(hand, arrays: GraspSceneArrays, s: int, effort_controlled, velocity, effort=None, mu=None):
    """The :class:`qsplan.mechanics.Scene` of state ``s`` of ``arrays`` with the joint inputs given: the polygon search's
    own scene where it built one, else from the arrays (eqs. 1-5; contacts named as the polygon search names them).

    Parameters
    ----------
    effort_controlled : array-like of bool, shape (n_j,)
    velocity, effort : array-like, shape (n_j,)
        Velocities (rad/s or m/s) of the velocity-controlled joints and efforts (N m or N) of the others (default 0).
    mu : float, optional
        Friction of every contact; default ``hand.mu``.
    """
    from dataclasses import replace

    from qsplan.mechanics.model.friction import check_friction
    from qsplan.mechanics.model.scene import make_scene

    n_j = len(hand.joint_names)
    e = np.asarray(effort_controlled, dtype=bool).reshape(n_j)
    v = np.broadcast_to(np.asarray(velocity, dtype=float), (n_j,))
    tau = np.zeros(n_j) if effort is None else np.broadcast_to(np.asarray(effort, dtype=float), (n_j,))
    mu = hand.mu if mu is None else float(check_friction(mu, "mu"))
    n_c = arrays.Wn.shape[2]
    inputs = {"effort_controlled": e, "joint_velocity": np.where(e, np.nan, v), "joint_effort": np.where(e, tau, np.nan)}
    if s in arrays.fallback:
        base = arrays.fallback[s]
        frozen = {}
        for key, value in {**inputs, "mu": np.full(n_c, mu)}.items():
            value = np.array(value)
            value.setflags(write=False)
            frozen[key] = value
        return replace(base, **frozen)
    names = [_contact_name(hand, int(b), i) for i, b in enumerate(arrays.bodies[s])]
    return make_scene(arrays.Wn[s], arrays.Wt[s], arrays.Jn[s], arrays.Jt[s], np.full(n_c, mu), arrays.g_obj[s],
                      g_man=arrays.g_man[s], joint_names=hand.joint_names, contact_names=names, **inputs)  # fmt: skip
