"""Closing a finger of any chain onto the workpiece (qsplan.hands.chains.closing, qsplan.hands.chains.hand).

Checked against independent references: the paper hand's closed-form tangency (finger_angles), and
shapely's distance and intersection of the closed link with the workpiece."""

import numpy as np
import pytest
from shapely.geometry import Polygon

from qsplan.hands.chains.hand import chain_polygons, chain_scene, close_grasp, make_chain_hand
from qsplan.hands.chains.closing import close_finger, separation
from qsplan.hands.description import load_hand
from qsplan.hands.paper_hand.two_finger import DEFAULT_WORKPIECE, default_hand, finger_angles, workpiece_world
from qsplan.hands.paper_hand.scene import hand_manipulator
from qsplan.mechanics.errors import SceneError

#: The hexagon the parallel jaws hold by its side corners.
HEXAGON = [[0.0, 0.0], [0.06, 0.0], [0.08, 0.05], [0.05, 0.09], [0.01, 0.09], [-0.02, 0.05]]


def test_closing_is_the_paper_hands_tangency():
    hand = default_hand()
    man, limits = hand_manipulator(hand), np.array([[0.05, 3.09], [0.05, 3.09]])
    for x in np.linspace(-0.04, 0.04, 41):
        pose = np.array([x, hand.rest_height, 0.0])
        q, vertex = finger_angles(hand, pose)
        W = workpiece_world(hand, pose)
        for f, side in ((0, 1.0), (1, -1.0)):
            c = close_finger(man, np.zeros(2), [f], limits, W, side)
            assert c is not None and c.kind == "vertex" and c.feature == vertex[f]
            assert c.value == pytest.approx(q[f], abs=1e-12)
            assert not c.flush


def test_separation_matches_shapely():
    rng = np.random.default_rng(3)
    square = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    for _ in range(200):
        B = square * rng.uniform(0.2, 1.0) + rng.uniform(-1.5, 1.5, 2)
        s, a, b = separation(square, B), Polygon(square), Polygon(B)
        if s > 1e-9:
            assert s <= a.distance(b) + 1e-12  # an axis gap is at most the distance (equal for axis-aligned boxes)
            assert s == pytest.approx(a.distance(b), abs=1e-12) or a.distance(b) > 0
        elif s < -1e-9:
            assert a.intersection(b).area > 0


@pytest.mark.parametrize("proximal", [1.2, 1.4, 1.6, 1.8])
def test_two_link_fingers_close_onto_the_workpiece(proximal):
    hand = make_chain_hand(load_hand("two_link_hand"), DEFAULT_WORKPIECE)
    q, closed = close_grasp(hand, 0.0, [proximal, 0.0, 3.14 - proximal, 0.0])
    polys = chain_polygons(hand, hand.pose(0.0), q)
    W = Polygon(polys["workpiece"])
    for name in ("left_distal", "right_distal"):
        link = Polygon(polys[name])
        assert link.distance(W) < 1e-9  # touching (shapely, independent of the closed forms)
        assert link.intersection(W).area < 1e-12  # not overlapping
    for name in ("left_proximal", "right_proximal"):
        assert Polygon(polys[name]).distance(W) > 1e-4
    scene = chain_scene(hand, hand.pose(0.0), q, np.arange(4) == 3, np.zeros(4))
    assert scene.contact_names == ("palm:0", "palm:1", "left_distal:2", "right_distal:3")
    for f, c in enumerate(closed):  # the contact the closing reports is the one the polygon search finds
        np.testing.assert_allclose(scene.Wn[:2, 2 + f], c.normal, atol=1e-9)


def test_two_link_fingers_choose_where_they_touch():
    hand = make_chain_hand(load_hand("two_link_hand"), DEFAULT_WORKPIECE)
    kinds = {close_grasp(hand, 0.0, [p, 0.0, 1.74, 0.0])[1][0].key for p in (1.2, 1.8)}
    assert kinds == {(1, "vertex", 3), (1, "edge", 3)}  # inner edge on the top-left corner, or the tip on the left side


def test_parallel_jaws_close_onto_the_hexagons_corners():
    hand = make_chain_hand(load_hand("parallel_jaw"), HEXAGON)
    q, (left, right) = close_grasp(hand, 0.0, [0.0, 0.0])
    assert (left.kind, right.kind) == ("vertex", "vertex")
    polys = chain_polygons(hand, hand.pose(0.0), q)
    for name in hand.joint_names:
        assert Polygon(polys[name]).distance(Polygon(polys["workpiece"])) < 1e-9


def test_bad_workpiece_mass_is_named():
    with pytest.raises(SceneError, match="workpiece_mass"):
        make_chain_hand(load_hand("two_link_hand"), DEFAULT_WORKPIECE, workpiece_mass=-1.0)
