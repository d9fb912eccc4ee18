"""Named contact sets at any workpiece pose (qsplan.hands.contacts.sets) and the demo hand's pivot in closed form
(tests/reference/paper_pivot.py): conventions, the flush instant (against an independent root and the generic
search's), the pivot manifold, the polygon search's contacts along it."""

from __future__ import annotations

from functools import lru_cache

import numpy as np
import pytest
from scipy.optimize import brentq

from qsplan.hands.contacts.sets import (ContactSpec, body_ring, contact_set_scene, finger_inner_edge, finger_link,
                                        flush_contacts, locate_contacts, palm_top_edge)  # fmt: skip
from qsplan.hands.contacts.found import polygon_contacts
from qsplan.hands.paper_hand.segments import flush_angle
from qsplan.hands.paper_hand.scene import hand_geometric_scene
from qsplan.hands.geometry.workpiece import rotation, workpiece_world
from qsplan.mechanics import QsplanError
from qsplan.mechanics.model.geometric_scene import find_scene_contacts, scene_from_geometric_scene
from qsplan.mechanics.model.manipulator import link_poses
from qsplan.planner.task.task import load_task, task_paths

from tests.reference.paper_pivot import (PIVOT, TRANSITION, flush_instant, pivot_configurations, pivot_contacts,
                                         pivot_scene, same_contacts, transition_contacts, transition_scene)  # fmt: skip

#: Round-off of closed-form geometry (m, rad): a few ulps of 0.1 m scenes.
GEOMETRY_ATOL = 1e-12
#: Step (rad or m per unit rate) of the central differences that check rates, and their agreement: O(h^2) ~ 1e-10.
FD_STEP, FD_ATOL = 1e-5, 1e-8


@lru_cache(maxsize=None)
def _task(name="demo_task"):
    return load_task(task_paths()[name])


def _hand():
    return _task().hand


def test_flush_instant_reproduces_the_issue_and_an_independent_root():
    hand = _hand()
    fi = flush_instant(hand)
    # the issue's numbers, to the digits it prints
    assert fi.x == pytest.approx(-0.042209, abs=5e-7)
    assert np.degrees(fi.q) == pytest.approx([85.43, 135.17], abs=5e-3)
    assert (fi.edge, fi.right_vertex) == (3, 2)
    # independent: the root of segment 1's flush angle (the tangency closed form), and the tangency's joints there
    paper = hand.paper
    # (past the flush the workpiece soon reaches the left joint's axis, where the tangency is undefined: a tight bracket)
    root = brentq(lambda x: flush_angle(paper, [x, paper.rest_height, 0.0]), fi.x - 5e-6, fi.x + 5e-3, xtol=1e-15)
    assert fi.x == pytest.approx(root, abs=1e-12)
    lim = hand.description.joint_limits
    assert np.all((lim[:, 0] < fi.q) & (fi.q < lim[:, 1]))
    # the generic search's flush instant (Newton's method on the five gap constraints) is the same configuration
    from qsplan.hands.formations.pivots import pivot_formations

    pivot, start = pivot_formations(hand)[0]
    assert (pivot.flush, pivot.edge, pivot.other.vertex) == ("left", fi.edge, fi.right_vertex)
    np.testing.assert_allclose(start, [*fi.pose, *fi.q], atol=GEOMETRY_ATOL)


def test_flush_instant_scene_is_the_polygon_search_scene():
    hand, fi = _hand(), flush_instant(_hand())
    for effort_joint in ("right", "left"):
        scene = transition_scene(hand, fi, effort_joint)
        gs = hand_geometric_scene(hand.paper, fi.pose, fi.q, effort_joint)
        found = find_scene_contacts(gs)
        assert [c.body for c in found] == [-1, -1, 0, 0, 1]  # five contacts: the flush finger gives two
        ref = scene_from_geometric_scene(gs, found)
        for name in ("Wn", "Wt", "Jn", "Jt", "g_obj", "g_man"):
            np.testing.assert_allclose(getattr(scene, name), getattr(ref, name), atol=GEOMETRY_ATOL)
        assert scene.contact_names == TRANSITION.contact_names
        assert same_contacts(locate_contacts(hand, fi.pose, fi.q, transition_contacts(hand, fi)),
                             polygon_contacts(hand, fi.pose, fi.q))


@pytest.mark.parametrize("theta_deg", [0.0, -20.0, -40.0])
def test_normals_point_into_the_workpiece(theta_deg):
    hand = _hand()
    c = pivot_configurations(hand, [np.radians(theta_deg)])
    found = locate_contacts(hand, c.pose[0], c.q[0], pivot_contacts(hand, c.pose[0], c.q[0]))
    W = workpiece_world(hand, c.pose[0])
    for p, n, spec in zip(found.points, found.normals, found.specs):
        # the contact's tangent line separates them: the workpiece on the normal's side, the body on the other
        assert np.hypot(*n) == pytest.approx(1.0)
        assert np.min((W - p) @ n) >= -GEOMETRY_ATOL and np.max((W - p) @ n) > 0.01
        body = body_ring(hand, spec.body, c.q[0])
        assert np.max((body - p) @ n) <= GEOMETRY_ATOL and np.min((body - p) @ n) < -0.005
    scene = pivot_scene(hand, c, 0)
    np.testing.assert_allclose(scene.Wt[:2], np.stack([-found.normals[:, 1], found.normals[:, 0]]), atol=0)
    r, n = found.points, found.normals
    np.testing.assert_allclose(scene.Wn[2], r[:, 0] * n[:, 1] - r[:, 1] * n[:, 0])


def _material_points(hand, pose, q, points, links):
    """Each contact point as a material point of the workpiece (body frame) and of its body (link frame)."""
    wp = (points - pose[:2]) @ rotation(pose[2])
    poses = link_poses(hand.manipulator, q)
    body = [p if k < 0 else (p - poses[k, :2]) @ rotation(poses[k, 2]) for p, k in zip(points, links)]
    return wp, body


def _moved(hand, pose, q, wp, body, links):
    poses = link_poses(hand.manipulator, q)
    a = wp @ rotation(pose[2]).T + pose[:2]
    b = np.array([p if k < 0 else rotation(poses[k, 2]) @ p + poses[k, :2] for p, k in zip(body, links)])
    return a, b


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_wrenches_and_jacobians_match_finite_differences_of_contact_motion(seed):
    """v_i = W_i^T nu - J_i thetadot (eq. 6) is the workpiece point's velocity relative to the body's, in (n, t)."""
    rng = np.random.default_rng(seed)
    hand, fi = _hand(), flush_instant(_hand())
    # the left tip contact: v3 on the finger at -20 deg, the fingertip's corner on v3's edge at -40 deg
    c = pivot_configurations(hand, np.radians([-20.0, -40.0]))
    cases = [(fi.pose, fi.q, transition_contacts(hand, fi))]
    cases += [(c.pose[i], c.q[i], pivot_contacts(hand, c.pose[i], c.q[i])) for i in range(2)]
    for pose, q, contacts in cases:
        scene = contact_set_scene(hand, pose, q, contacts, [False, True], [0.0, 0.0])
        found = locate_contacts(hand, pose, q, contacts)
        rate, qdot = rng.normal(size=3) * [0.01, 0.01, 0.1], rng.normal(size=2) * 0.1
        nu = np.array([rate[0] + rate[2] * pose[1], rate[1] - rate[2] * pose[0], rate[2]])  # twist at the world origin
        wp, body = _material_points(hand, pose, q, found.points, found.links)
        ahead = _moved(hand, pose + FD_STEP * rate, q + FD_STEP * qdot, wp, body, found.links)
        behind = _moved(hand, pose - FD_STEP * rate, q - FD_STEP * qdot, wp, body, found.links)
        rel = ((ahead[0] - ahead[1]) - (behind[0] - behind[1])) / (2 * FD_STEP)
        t = np.stack([-found.normals[:, 1], found.normals[:, 0]], axis=1)
        np.testing.assert_allclose(scene.Wn.T @ nu - scene.Jn @ qdot, np.sum(rel * found.normals, axis=1), atol=FD_ATOL)
        np.testing.assert_allclose(scene.Wt.T @ nu - scene.Jt @ qdot, np.sum(rel * t, axis=1), atol=FD_ATOL)


def test_flush_contacts_follow_the_overlap_ends():
    hand = _hand()
    fi = flush_instant(hand)
    inner = finger_inner_edge(hand, "left")
    base, tip = flush_contacts(hand, fi.pose, fi.q, "left", 3, inner)
    assert (base.workpiece, base.feature, tip.workpiece, tip.feature) == (("vertex", 0), ("edge", inner),
                                                                           ("vertex", 3), ("edge", inner))  # fmt: skip
    c = pivot_configurations(hand, np.radians([-30.0, -36.0]))  # either side of v3 passing the fingertip
    before = flush_contacts(hand, c.pose[0], c.q[0], "left", 3, inner)[1]
    after = flush_contacts(hand, c.pose[1], c.q[1], "left", 3, inner)[1]
    assert before.workpiece == ("vertex", 3)
    assert after.workpiece == ("edge", 3) and after.feature[0] == "vertex"
    L = hand.paper.finger_length
    corner = body_ring(hand, "left", c.q[1])[after.feature[1]]
    joint = hand.paper.pivots[0]
    assert np.hypot(*(corner - joint)) == pytest.approx(np.hypot(L, 0.5 * hand.paper.finger_width))


@pytest.mark.parametrize("theta_deg", [0.0, -10.0, -33.0, -45.0, -54.0])
def test_pivot_manifold_closed_form_residuals_and_rates(theta_deg):
    hand = _hand()
    paper = hand.paper
    th = np.radians(theta_deg)
    c = pivot_configurations(hand, [th])
    W, q = c.vertices[0], c.q[0]
    w = 0.5 * paper.finger_width
    u = np.array([[np.cos(a), np.sin(a)] for a in q])
    m = np.stack([-u[:, 1], u[:, 0]], axis=1)
    assert abs(W[1, 1]) < GEOMETRY_ATOL  # the pivot on the palm's top
    for v in (0, 3):  # the flush edge's ends on the left finger's inner edge line (y = -w in its frame)
        assert abs((W[v] - paper.pivots[0]) @ m[0] + w) < GEOMETRY_ATOL
    assert abs((W[2] - paper.pivots[1]) @ m[1] - w) < GEOMETRY_ATOL  # v2 on the right's (y = +w)
    assert np.all(W[[0, 2, 3], 1] >= -GEOMETRY_ATOL)
    ahead, behind = pivot_configurations(hand, [th + FD_STEP]), pivot_configurations(hand, [th - FD_STEP])
    np.testing.assert_allclose(c.dpose[0], (ahead.pose[0] - behind.pose[0]) / (2 * FD_STEP), atol=FD_ATOL)
    np.testing.assert_allclose(c.dq[0], (ahead.q[0] - behind.q[0]) / (2 * FD_STEP), atol=FD_ATOL)
    # the manifold's tangent keeps every contact (eq. 6 with v_n = 0 at all four)
    scene = pivot_scene(hand, c, 0)
    nu = np.array([c.dpose[0, 0] + c.pose[0, 1], c.dpose[0, 1] - c.pose[0, 0], 1.0])
    np.testing.assert_allclose(scene.Wn.T @ nu - scene.Jn @ c.dq[0], 0.0, atol=GEOMETRY_ATOL)


def test_pivot_starts_at_the_flush_instant():
    hand = _hand()
    fi, c = flush_instant(hand), pivot_configurations(hand, [0.0])
    np.testing.assert_allclose(c.pose[0], fi.pose, atol=GEOMETRY_ATOL)
    np.testing.assert_allclose(c.q[0], fi.q, atol=GEOMETRY_ATOL)


def test_pivot_contacts_are_the_formation_and_the_polygon_search_agrees():
    hand = _hand()
    c = pivot_configurations(hand, np.radians(np.arange(-1.0, -54.0, -2.0)))
    for i in range(len(c.theta)):
        contacts = pivot_contacts(hand, c.pose[i], c.q[i])
        assert tuple(s.name for s in contacts) == PIVOT.contact_names
        assert same_contacts(locate_contacts(hand, c.pose[i], c.q[i], contacts), polygon_contacts(hand, c.pose[i], c.q[i]))


def test_finger_features_of_the_paper_hand():
    hand = _hand()
    assert body_ring(hand, "palm", [1.0, 2.0])[palm_top_edge(hand)][1] == 0.0
    assert (finger_link(hand, "palm"), finger_link(hand, "left"), finger_link(hand, "right")) == (-1, 0, 1)


# --- validation: one check per branch ------------------------------------------------------------------------------


def _ok_spec(**kw):
    args = dict(name="c", body="left", workpiece="vertex:0", feature=("edge", 0))
    args.update(kw)
    return ContactSpec(**args)


@pytest.mark.parametrize("kw, match", [
    (dict(name=""), "contact name: expected a nonempty string"),
    (dict(body="thumb"), r"contact 'c'.body: expected one of palm, left, right"),
    (dict(workpiece=5), r"contact 'c'.workpiece: expected \(KIND, INDEX\)"),
    (dict(workpiece=("corner", 1)), r"contact 'c'.workpiece: the kind must be one of vertex, edge"),
    (dict(feature=("edge", -1)), r"contact 'c'.feature: the index must be a nonnegative integer"),
    (dict(feature="vertex:1"), "got two vertices: a vertex on a vertex has no normal"),
    (dict(workpiece="edge:3"), "got two edges: an edge flush on an edge is two contacts"),
])  # fmt: skip
def test_contact_spec_validation(kw, match):
    with pytest.raises(QsplanError, match=match):
        _ok_spec(**kw)


def test_locate_contacts_validation():
    hand, fi = _hand(), flush_instant(_hand())
    good = transition_contacts(hand, fi)
    with pytest.raises(QsplanError, match="contacts: expected a nonempty sequence of ContactSpec"):
        locate_contacts(hand, fi.pose, fi.q, [("left", "vertex:0", "edge:0")])
    with pytest.raises(QsplanError, match="contacts: names must be unique"):
        locate_contacts(hand, fi.pose, fi.q, [good[0], good[0]])
    with pytest.raises(QsplanError, match=r"contacts\[0\] \('c'\).workpiece: vertex 7 out of range; the polygon has 4 vert"):
        locate_contacts(hand, fi.pose, fi.q, [_ok_spec(workpiece="vertex:7")])
    with pytest.raises(QsplanError, match=r"contacts\[0\] \('c'\): the workpiece vertex is .* from the edge's line"):
        locate_contacts(hand, fi.pose, fi.q, [_ok_spec(workpiece="vertex:2")])
    with pytest.raises(QsplanError, match=r"pose: expected shape \(3\); got \(2,\)"):
        locate_contacts(hand, fi.pose[:2], fi.q, good)
    with pytest.raises(QsplanError, match="effort_controlled: expected 2 flags"):
        contact_set_scene(hand, fi.pose, fi.q, good, [True], [0.0, 0.0])
    with pytest.raises(QsplanError, match="body: expected one of palm, left, right"):
        finger_link(hand, "thumb")


def test_flush_contacts_validation():
    hand, fi = _hand(), flush_instant(_hand())
    inner = finger_inner_edge(hand, "left")
    with pytest.raises(QsplanError, match="workpiece_edge: edge 9 out of range"):
        flush_contacts(hand, fi.pose, fi.q, "left", 9, inner)
    with pytest.raises(QsplanError, match="are not flush: their normals are"):
        flush_contacts(hand, fi.pose, fi.q, "left", 0, inner)
    shifted = fi.pose + [0.001, 0.0, 0.0]
    with pytest.raises(QsplanError, match="lies .* m off workpiece edge 3's line"):
        flush_contacts(hand, shifted, fi.q, "left", 3, inner)
