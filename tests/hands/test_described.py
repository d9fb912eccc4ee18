"""Described hands' generic path (qsplan.hands.described.hand) against today's chain path, one state at a time.

At seeded random workpiece x and free joints of the bundled two-link hand and parallel jaws and a mixed hand, the
batched ``grasp_states`` and ``scene_arrays`` equal :func:`qsplan.hands.chains.hand.close_grasp` (closed joints,
contact keys, points, normals, the flush and no-contact verdicts) and :func:`qsplan.hands.chains.hand.chain_scene`
(the polygon search: which states have the formation's four contacts, and their ``W_n, W_t, J_n, J_t, g_obj,
g_man``) to 1e-12; ``dq_dx`` equals eq. 6 solved at the reference scene and finite differences of the closing."""

import numpy as np
import pytest

from qsplan.hands.chains.hand import chain_scene, close_grasp
from qsplan.hands.chains.closing import separation
from qsplan.hands.described.build import make_described_hand
from qsplan.hands.formations.registry import formation
from qsplan.hands.protocol import FLUSH, NO_CONTACT, OTHER_CONTACT, SINGULAR, ChainGrasp, FingerContact
from qsplan.mechanics.errors import QsplanError
from tests.hands.described_cases import chain_cases

#: Agreement of the batched generic path with the per-state chain path (m, rad, N, N m): the same closed forms and
#: equations on the same numbers, only the order of a few floating-point operations differs.
TOL = 1e-12

#: Step (m) of the central differences of the closing, and their agreement with ``dq_dx`` (rad/m or m/m): the
#: truncation error is O(h^2) of rates ~10 rad/m, the rounding ~1e-16 / h.
FD_STEP, FD_TOL = 1e-6, 1e-6

_FIELDS = ("Wn", "Wt", "Jn", "Jt", "g_obj", "g_man")


def _sample(hand, centre, n, rng):
    """Seeded random workpiece x (m) on the palm and free joints (about ``centre``, within their limits)."""
    lo, hi = hand.palm_range
    xs = rng.uniform(max(lo, -0.06), min(hi, 0.06), n)
    free = np.zeros((n, 0))
    if hand.free_joints:
        lim = hand.description.joint_limits[list(hand.free_joints)]
        free = np.clip(np.asarray(centre) + rng.uniform(-0.3, 0.3, (n, len(centre))), lim[:, 0], lim[:, 1])
    return xs, free


def _grasp(hand, keys, free):
    contacts = []
    for link, kind, feature in keys:
        written = (hand.user_edges if kind == "edge" else hand.user_vertices)[feature]
        contacts.append(FingerContact(link, hand.joint_names[link], kind, feature, int(written)))
    return ChainGrasp(*contacts, tuple(float(v) for v in free), tuple(hand.joint_names[j] for j in hand.free_joints))


def _reference(hand, x, free):
    """The chain path at one state: ``(q, keys, flush, scene or the error)`` or None where a finger closes onto nothing."""
    q0 = np.zeros(len(hand.joint_names))
    q0[list(hand.free_joints)] = free
    out = close_grasp(hand.chain, x, q0)
    if out is None:
        return None
    q, closed = out
    try:
        scene = chain_scene(hand.chain, hand.pose(x), q, np.arange(len(q)) == 0, np.zeros(len(q)))
    except QsplanError as exc:
        scene = exc
    return q, tuple(c.key for c in closed), any(c.flush for c in closed), closed, scene


@pytest.fixture(scope="module", params=sorted(chain_cases()))
def judged(request):
    """A chain case judged both ways at 300 seeded states, grouped by the reference's contact keys."""
    desc, workpiece, centre = chain_cases()[request.param]
    hand = make_described_hand(desc, workpiece)
    xs, free = _sample(hand, centre, 300, np.random.default_rng(1995))
    refs = [_reference(hand, x, f) for x, f in zip(xs, free)]
    return hand, xs, free, refs


def test_the_generic_states_are_the_chain_paths(judged):
    hand, xs, free, refs = judged
    form = formation("palm_edge")
    groups = {}
    for i, ref in enumerate(refs):
        if ref is not None:
            groups.setdefault(ref[1], []).append(i)
    assert sum(len(g) for g in groups.values()) > 50
    a_grasp = _grasp(hand, next(iter(groups)), free[0])
    states = hand.grasp_states(form, a_grasp, xs, free=free)  # every state judged against one grasp's keys
    for i, ref in enumerate(refs):
        expected = NO_CONTACT if ref is None else (OTHER_CONTACT if ref[1] != a_grasp.keys else (FLUSH if ref[2] else 0))
        assert states.reason[i] in ((expected, SINGULAR) if expected == 0 else (expected,)), i
    for keys, rows in groups.items():
        rows = np.array(rows)
        states = hand.grasp_states(form, _grasp(hand, keys, free[rows[0]]), xs[rows], free=free[rows])
        for k, i in enumerate(rows):
            q, _, flush, closed, _ = refs[i]
            assert states.ok[k] == (not flush) or states.reason[k] == SINGULAR
            np.testing.assert_allclose(states.q[k], q, rtol=0, atol=TOL)
            for f, c in enumerate(closed):
                np.testing.assert_allclose(states.points[k, 2 + f], c.point, rtol=0, atol=TOL)
                np.testing.assert_allclose(states.normals[k, 2 + f], c.normal, rtol=0, atol=TOL)
                assert states.bodies[k, 2 + f] == c.link and states.touched[k, f] == c.feature


def test_the_generic_scene_arrays_are_the_polygon_searchs(judged):
    hand, xs, free, refs = judged
    form = formation("palm_edge")
    checked = 0
    for keys in {r[1] for r in refs if r is not None}:
        rows = np.array([i for i, r in enumerate(refs) if r is not None and r[1] == keys])
        states = hand.grasp_states(form, _grasp(hand, keys, free[rows[0]]), xs[rows], free=free[rows])
        arrays = hand.scene_arrays(form, states, np.arange(len(rows)))
        for k, i in enumerate(rows):
            _, _, flush, _, scene = refs[i]
            has_scene = not flush and not isinstance(scene, Exception)
            if has_scene:  # eq. 6 at the reference scene: each closing joint's rate per unit x (free joints held)
                jn = [scene.Jn[2 + f, j] for f, j in enumerate(hand.closing_joints)]
                has_scene = min(abs(v) for v in jn) >= 1e-12
            assert arrays.ok[k] == has_scene, (i, arrays.reasons[k], scene)
            if not has_scene:
                continue
            checked += 1
            for name in _FIELDS:
                np.testing.assert_allclose(getattr(arrays, name)[k], getattr(scene, name), rtol=0, atol=TOL, err_msg=name)
            for f, j in enumerate(hand.closing_joints):
                assert arrays.dq_dx[k, j] == pytest.approx(scene.Wn[0, 2 + f] / scene.Jn[2 + f, j], rel=TOL, abs=TOL)
            assert np.all(arrays.dq_dx[k, list(hand.free_joints)] == 0.0)
            s = hand.state_scene(arrays, k, np.arange(len(hand.joint_names)) == 0, np.zeros(len(hand.joint_names)))
            assert s.contact_names == scene.contact_names and s.joint_names == scene.joint_names
    assert checked > 30


def test_dq_dx_is_the_closings_derivative(judged):
    hand, xs, free, refs = judged
    form = formation("palm_edge")
    keys = max({r[1] for r in refs if r is not None}, key=lambda k: sum(r is not None and r[1] == k for r in refs))
    rows = np.array([i for i, r in enumerate(refs) if r is not None and r[1] == keys and not r[2]])
    g = _grasp(hand, keys, free[rows[0]])
    mid = hand.grasp_states(form, g, xs[rows], free=free[rows])
    plus = hand.grasp_states(form, g, xs[rows] + FD_STEP, free=free[rows])
    minus = hand.grasp_states(form, g, xs[rows] - FD_STEP, free=free[rows])
    ok = mid.ok & plus.ok & minus.ok
    assert ok.sum() > 20
    fd = (plus.q[ok] - minus.q[ok]) / (2.0 * FD_STEP)
    np.testing.assert_allclose(mid.dq_dx[ok], fd, rtol=FD_TOL, atol=FD_TOL)


def test_opening_moves_each_closing_link_off_the_workpiece(judged):
    hand, xs, free, refs = judged
    form = formation("palm_edge")
    keys = next(r[1] for r in refs if r is not None and not r[2])
    rows = np.array([i for i, r in enumerate(refs) if r is not None and r[1] == keys and not r[2]])[:10]
    g = _grasp(hand, keys, free[rows[0]])
    states = hand.grasp_states(form, g, xs[rows], free=free[rows])
    for k in np.flatnonzero(states.ok):
        d = hand.opening(g, states.x[k], states.q[k])
        assert set(np.unique(d)) <= {-1.0, 0.0, 1.0} and np.all(d[list(hand.free_joints)] == 0.0)
        step = np.where(np.array(hand.joint_kinds) == "revolute", 0.01, 0.001)  # rad, m
        polys = hand.body_polygons(states.poses[k], states.q[k] + d * step)
        for j in hand.closing_joints:
            P, W = polys[hand.joint_names[j]], polys["workpiece"]
            assert separation(P[::-1] if _cw(P) else P, W) > 1e-5  # opened by at least 10 microns


def _cw(P) -> bool:
    x, y = P[:, 0], P[:, 1]
    return np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y) < 0


def test_the_contact_check_decides_as_the_polygon_search(judged):
    """With the closed-form check switched off every state takes the polygon search: the same verdicts and arrays."""
    from dataclasses import replace

    hand, xs, free, refs = judged
    searched = replace(hand, contact_view=None, closings={})
    form = formation("palm_edge")
    for keys in {r[1] for r in refs[:120] if r is not None}:
        rows = np.array([i for i, r in enumerate(refs[:120]) if r is not None and r[1] == keys])
        g = _grasp(hand, keys, free[rows[0]])
        fast = hand.scene_arrays(form, hand.grasp_states(form, g, xs[rows], free=free[rows]))
        slow = searched.scene_arrays(form, searched.grasp_states(form, g, xs[rows], free=free[rows]))
        np.testing.assert_array_equal(fast.ok, slow.ok)
        assert len(slow.fallback) == slow.ok.sum()
        for name in (*_FIELDS, "dq_dx"):
            a, b = getattr(fast, name)[fast.ok], getattr(slow, name)[slow.ok]
            np.testing.assert_allclose(a, b, rtol=0, atol=TOL, err_msg=name)


def test_a_contact_near_a_corner_is_left_to_the_polygon_search():
    """The two-link hand's right fingertip corner 2 microns from a workpiece vertex: within the check's margins, so the
    polygon search builds the scene (and says it is the formation's)."""
    desc, workpiece, centre = chain_cases()["two_link_hand"]
    hand = make_described_hand(desc, workpiece)
    lo, hi = hand.palm_range
    keys = ((1, "vertex", 3), (3, "edge", 2))  # left distal on vertex 3, right distal corner on edge 2 (internal)
    g = _grasp(hand, keys, centre)
    states = hand.grasp_states("palm_edge", g, np.arange(lo, hi, 5e-4))
    arrays = hand.scene_arrays("palm_edge", states)
    assert arrays.fallback
    for k, scene in arrays.fallback.items():
        ref = _reference(hand, states.x[arrays.idx[k]], np.array(centre))[-1]
        for name in _FIELDS:
            np.testing.assert_allclose(getattr(arrays, name)[k], getattr(ref, name), rtol=0, atol=TOL)
            np.testing.assert_allclose(getattr(scene, name), getattr(ref, name), rtol=0, atol=TOL)
