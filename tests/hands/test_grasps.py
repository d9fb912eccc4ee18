"""Grasps of the two-finger hand: numbering as written, placements, configurations, scenes.

The inner-edge placement against ``finger_angles`` bit for bit; the fingertip's closed form against
its definition (the corner on the edge's line, the finger clear of the workpiece), finite differences
and the polygon search (the generic scene, to round-off); the mechanics (a 4S band exists somewhere).
"""

import numpy as np
import pytest

from qsplan.hands.paper_hand.batch_scenes import grasp_scenes, scene_arrays
from qsplan.hands.paper_hand.grasp_geometry import (TIP_MARGIN, candidate_grasps, grasp_configurations, palm_range,
                                                    tip_angles)  # fmt: skip
from qsplan.hands.paper_hand.grasps import (Grasp, OnVertex, TipOnEdge, internal_edge, internal_vertex, parse_grasp,
                                            parse_placement, user_edge, user_vertex)  # fmt: skip
from qsplan.hands.paper_hand.two_finger import (DEFAULT_WORKPIECE, default_hand, finger_angle_rates, finger_angles,
                                                make_two_finger_hand)  # fmt: skip
from qsplan.hands.paper_hand.analytic import grasp_contacts
from qsplan.hands.paper_hand.scene import hand_scene
from qsplan.mechanics import SceneError
from qsplan.hands.geometry.collision import find_collisions

from tests.hands.scenes import assert_same_scene


#: A house: its two roof edges (2 and 3) are the top edges a fingertip reaches from each side.
HOUSE = ((0.0, 0.0), (0.06, 0.0), (0.06, 0.03), (0.03, 0.065), (0.0, 0.03))
#: Fingers short enough for a tip to reach a side edge of the default workpiece with the workpiece between the joints
#: (with the default 0.16 m fingers a tip reaches a side only where the workpiece covers the other finger's joint).
SHORT = 0.11


def _random_polygon(rng):
    """A convex polygon with a level bottom edge (m)."""
    w = rng.uniform(0.04, 0.08)
    k = int(rng.integers(2, 5))
    ang = np.sort(rng.uniform(0.15, np.pi - 0.15, k))
    top = np.column_stack([0.5 * w - rng.uniform(0.6, 1.0) * 0.5 * w * np.cos(ang),
                           rng.uniform(0.03, 0.09) * np.sin(ang) + 0.005])  # fmt: skip
    return np.vstack([[(0.0, 0.0), (w, 0.0)], top[::-1]])


def _hands():
    hands = [default_hand(finger_length=SHORT), default_hand(finger_length=SHORT, finger_mass=0.03),
             make_two_finger_hand(HOUSE, finger_length=0.1), make_two_finger_hand(HOUSE[::-1], finger_length=0.1)]
    rng = np.random.default_rng(14)
    while len(hands) < 12:
        try:
            hands.append(make_two_finger_hand(_random_polygon(rng), finger_length=rng.uniform(0.08, 0.13),
                                              mu=rng.uniform(0.1, 0.5)))  # fmt: skip
        except SceneError:
            continue
    return hands


HANDS = _hands()


def _tip_grasps(hand):
    return [g for g in candidate_grasps(hand) if isinstance(g.left, TipOnEdge) or isinstance(g.right, TipOnEdge)]


# -- numbering as written -------------------------------------------------------------------------------------------


@pytest.mark.parametrize("polygon", [DEFAULT_WORKPIECE, DEFAULT_WORKPIECE[::-1], DEFAULT_WORKPIECE[2:] + DEFAULT_WORKPIECE[:2],
                                     DEFAULT_WORKPIECE + DEFAULT_WORKPIECE[:1], HOUSE[::-1]])  # fmt: skip
def test_user_and_internal_indices_round_trip(polygon):
    hand = make_two_finger_hand(polygon)
    P = np.asarray(polygon, float)
    k = len(hand.workpiece)
    shift = hand.workpiece - P[list(hand.vertex_order)]
    np.testing.assert_allclose(shift, shift[:1].repeat(k, axis=0), atol=1e-15)  # a translation: the same vertices
    for i in range(k):
        assert internal_vertex(hand, user_vertex(hand, i)) == i
        assert internal_edge(hand, user_edge(hand, i)) == i
    for K in range(k):
        e = internal_edge(hand, K)
        assert {internal_vertex(hand, K), internal_vertex(hand, (K + 1) % len(P))} == {e, (e + 1) % k}


def test_a_clockwise_polygon_numbers_edges_as_written():
    hand = make_two_finger_hand(DEFAULT_WORKPIECE[::-1])  # user vertex K is default vertex 3 - K
    assert hand.vertex_order == (3, 2, 1, 0)
    assert [internal_edge(hand, K) for K in range(4)] == [2, 1, 0, 3]  # user edge K: vertices 3-K, 2-K


@pytest.mark.parametrize("palm_edge", [0, 1, 2, 3])
def test_palm_edge_lays_that_edge_on_the_palm(palm_edge):
    hand = default_hand(palm_edge=palm_edge)
    assert internal_edge(hand, palm_edge) == 0
    assert hand.workpiece[0, 1] == hand.workpiece[1, 1] == hand.workpiece[:, 1].min()
    np.testing.assert_allclose(np.sort(hand.edge_lengths), np.sort(default_hand().edge_lengths), rtol=1e-12)


@pytest.mark.parametrize("palm_edge, match", [(4, r"palm_edge: expected an edge index in \[0, 4\)"),
                                              (True, "palm_edge: expected"), (-1, "palm_edge: expected")])  # fmt: skip
def test_palm_edge_is_validated(palm_edge, match):
    with pytest.raises(SceneError, match=match):
        default_hand(palm_edge=palm_edge)


def test_palm_edge_the_workpiece_cannot_rest_on():
    leaning = ((0.0, 0.0), (0.1, 0.0), (0.3, 0.02))  # its centroid (x = 0.133 m) is past the end of edge 0
    with pytest.raises(SceneError, match="palm_edge: the workpiece cannot rest on edge 0"):
        make_two_finger_hand(leaning, palm_edge=0)
    make_two_finger_hand(leaning, palm_edge=2)  # the long edge carries it


@pytest.mark.parametrize("call, match", [(lambda h: internal_vertex(h, 4), r"vertex: expected a vertex index"),
                                         (lambda h: internal_edge(h, -1), r"edge: expected an edge index"),
                                         (lambda h: user_edge(h, 7, "goal.edge"), r"goal.edge: expected")])  # fmt: skip
def test_index_errors_name_the_field(call, match):
    with pytest.raises(SceneError, match=match):
        call(default_hand())


# -- placements and grasps ------------------------------------------------------------------------------------------


@pytest.mark.parametrize("text, placement", [("vertex", OnVertex()), ("vertex:2", OnVertex(2)), ("edge:3", TipOnEdge(3)),
                                             ("edge:1:1", TipOnEdge(1, 1)), ("edge:1:0", TipOnEdge(1))])  # fmt: skip
def test_placements_parse_and_print(text, placement):
    assert parse_placement(text) == placement
    assert parse_placement(str(placement)) == placement


@pytest.mark.parametrize("text", ["edge", "edge:x", "vertex:1:1", "edge:1:2", "face:1", "edge:-1", 3])
def test_placement_parse_errors_name_the_field(text):
    with pytest.raises(SceneError, match="goal.left: expected"):
        parse_placement(text, "goal.left")


def test_grasp_labels_and_goals():
    g = Grasp(OnVertex(), TipOnEdge(2))
    assert g.label == "L vertex / R edge:2" and parse_grasp(g.label) == g
    assert g.matches() and g.matches("vertex:3", "edge:2") and g.matches(None, "edge:2:0")
    assert not g.matches("edge:2") and not g.matches(None, "edge:1") and not g.matches(None, "edge:2:1")
    with pytest.raises(SceneError, match="goal_right: expected"):
        g.matches(None, "edge")
    with pytest.raises(SceneError, match="grasp: expected 'L <placement> / R <placement>'"):
        parse_grasp("R vertex / L vertex")


def test_configurations_say_where_a_vertex_goal_is_met():
    hand = default_hand()
    c = grasp_configurations(hand, Grasp(OnVertex(), OnVertex()), np.linspace(-0.05, 0.05, 101))
    for K in range(4):
        where = c.matches(f"vertex:{K}", None)
        np.testing.assert_array_equal(where, c.ok & (c.touched_as_written[:, 0] == K))
        restricted = grasp_configurations(hand, Grasp(OnVertex(K), OnVertex()), c.x)
        np.testing.assert_array_equal(restricted.ok, where)
    assert not c.matches("edge:1").any()


# -- configurations -------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("h", range(len(HANDS)))
def test_inner_edge_configurations_are_finger_angles_bit_for_bit(h):
    hand = HANDS[h]
    c = grasp_configurations(hand, Grasp(OnVertex(), OnVertex()), np.linspace(*palm_range(hand), 97))
    for i, pose in enumerate(c.poses(hand.rest_height)):
        try:
            q, touched = finger_angles(hand, pose)
        except SceneError:
            assert not c.ok[i]
            continue
        np.testing.assert_array_equal(c.q[i], q)
        np.testing.assert_array_equal(c.touched[i], touched)
        np.testing.assert_array_equal(c.dq_dx[i], finger_angle_rates(hand, pose, (1.0, 0.0, 0.0)))
        if c.ok[i]:
            assert not [col for col in find_collisions(hand, pose, q) if "workpiece" in col.bodies]


def _tip_cases():
    """(hand, grasp, configurations) of every candidate tip grasp of :data:`HANDS`, with its valid states."""
    out = []
    for hand in HANDS:
        xs = np.linspace(*palm_range(hand), 241)
        for g in _tip_grasps(hand):
            c = grasp_configurations(hand, g, xs)
            out.append((hand, g, c))
    return out


TIP_CASES = _tip_cases()


def test_tip_placements_exist_on_side_and_top_edges():
    labels = {(id(h), g.label) for h, g, c in TIP_CASES if c.ok.any()}
    house, default = HANDS[2], HANDS[0]
    assert (id(default), "L edge:3 / R vertex") in labels and (id(default), "L vertex / R edge:1") in labels  # sides
    assert any(i == id(house) and ("edge:2" in lab or "edge:3" in lab) for i, lab in labels)  # the roof
    assert sum(c.ok.sum() for _, _, c in TIP_CASES) >= 300


def test_tip_corner_lies_on_its_edge_and_the_finger_clear_of_the_workpiece():
    checked = 0
    for hand, g, c in TIP_CASES:
        L, w = hand.finger_length, 0.5 * hand.finger_width
        for k, pl in enumerate((g.left, g.right)):
            if not isinstance(pl, TipOnEdge):
                continue
            e = internal_edge(hand, pl.edge)
            for i in np.flatnonzero(c.ok):
                W = hand.workpiece + [c.x[i], hand.rest_height]
                a, b = W[e], W[(e + 1) % len(W)]
                t = (b - a) / np.linalg.norm(b - a)
                phi = c.q[i, k]
                u, m = np.array([np.cos(phi), np.sin(phi)]), np.array([-np.sin(phi), np.cos(phi)])
                corners = [hand.pivots[k] + L * u + s * w * m for s in (-1.0, 1.0)]
                dist = [t[0] * (p - a)[1] - t[1] * (p - a)[0] for p in corners]  # positive inside the workpiece
                touching = int(np.argmin(np.abs(dist)))
                assert abs(dist[touching]) < 1e-12 and dist[1 - touching] < -TIP_MARGIN * 0.99
                assert touching == (0 if (k == 0) == (pl.branch == 0) else 1)  # branch 0: the inner corner
                np.testing.assert_allclose(c.points[i, 2 + k], corners[touching], atol=1e-15)
                assert u @ np.array([t[1], -t[0]]) < 0.0
                cols = find_collisions(hand, c.poses(hand.rest_height)[i], c.q[i])
                assert not [col for col in cols if "workpiece" in col.bodies and col.depth > 1e-6], cols
                checked += 1
    assert checked >= 300


def test_dq_dx_is_the_derivative_of_q():
    h = 1e-7
    for hand, g, c in TIP_CASES:
        inside = c.ok & np.r_[False, c.ok[:-1]] & np.r_[c.ok[1:], False]
        xs = c.x[inside]
        if not xs.size:
            continue
        hi, lo = (grasp_configurations(hand, g, xs + d) for d in (h, -h))
        both = hi.ok & lo.ok
        fd = (hi.q - lo.q)[both] / (2 * h)
        np.testing.assert_allclose(c.dq_dx[inside][both], fd, rtol=1e-5, atol=1e-5)


def test_tip_angles_branches_are_the_two_circle_line_solutions():
    hand = HANDS[0]
    xs = np.linspace(*palm_range(hand), 51)
    for finger in (0, 1):
        for edge in range(len(hand.workpiece)):
            phi0, *_ = tip_angles(hand, finger, edge, 0, xs)
            phi1, *_ = tip_angles(hand, finger, edge, 1, xs)
            both = np.isfinite(phi0)
            assert np.array_equal(both, np.isfinite(phi1))
            assert not np.any(np.isclose(np.mod(phi0 - phi1, 2 * np.pi)[both], 0.0))


def test_unknown_placement_index_names_the_field():
    with pytest.raises(SceneError, match="grasp.right.edge: expected an edge index"):
        grasp_configurations(default_hand(), Grasp(OnVertex(), TipOnEdge(9)), [0.0])


# -- scenes ---------------------------------------------------------------------------------------------------------


@pytest.mark.slow
def test_tip_scenes_analytic_equal_generic():
    used = 0
    rng = np.random.default_rng(5)
    for hand, g, c in TIP_CASES:
        scenes = grasp_scenes(hand, c, effort_joint="left", speed=-0.02)
        for i in np.flatnonzero(c.ok):
            pose, q = c.poses(hand.rest_height)[i], c.q[i]
            velocity = c.dq_dx[i, 1] * -0.02
            g_scene = hand_scene(hand, pose, q, "left", velocity=velocity, method="generic")
            auto = hand_scene(hand, pose, q, "left", velocity=velocity)
            assert_same_scene(auto, g_scene)
            found = grasp_contacts(hand, pose, q)
            if found is not None:
                used += 1
                np.testing.assert_array_equal(found.features[2:], c.touched[i])
                assert_same_scene(scenes[i], g_scene)
            # off the grasp: the finger turned a little into or away from the edge
            dq = np.zeros(2)
            dq[int(rng.integers(2))] = rng.choice([-1.0, 1.0]) * rng.choice([1e-9, 1e-6, 1e-4])
            try:
                off = hand_scene(hand, pose, q + dq, method="generic")
            except SceneError:
                with pytest.raises(SceneError):
                    hand_scene(hand, pose, q + dq)
                continue
            assert_same_scene(hand_scene(hand, pose, q + dq), off)
    assert used >= 300


def test_scene_arrays_are_the_scenes_stacked():
    hand, g, c = next((h, g, c) for h, g, c in TIP_CASES if c.ok.sum() > 5)
    arrays = scene_arrays(hand, c)
    scenes = grasp_scenes(hand, c, check=False)
    for i in np.flatnonzero(c.ok):
        for f in ("Wn", "Wt", "Jn", "Jt", "g_obj", "g_man"):
            np.testing.assert_allclose(getattr(arrays, f)[i], getattr(scenes[i], f), rtol=1e-14, atol=1e-15)


def test_a_tip_grasp_has_a_4s_band():
    from qsplan.mechanics import robust_band

    hand = HANDS[0]
    c = grasp_configurations(hand, Grasp(OnVertex(), TipOnEdge(1)), np.linspace(-0.042, -0.03, 7))
    assert c.ok.all()
    scenes = grasp_scenes(hand, c, effort_joint="right", speed=-0.01)
    widths = [robust_band(s, "SSSS", (0.0, 0.2)) for s in scenes]
    assert any(b.feasible and b.upper > b.lower for b in widths)
