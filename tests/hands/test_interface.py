"""Any hand through one interface (issue 15): the paper's hand answered by its own code, chain hands by their
description, the metadata round trip, and bad input named."""

import json

import numpy as np
import pytest

from qsplan.hands.chains.hand import chain_polygons, chain_scene, close_grasp, make_chain_hand
from qsplan.hands.description import hand_from_table, joint_frames, load_hand
from qsplan.hands.described.records import (
    JOINT_UNITS,
    contacts_at,
    description_table,
    finger_joint_names,
    finger_of_joint,
    finger_reach,
    hand_body_polygons,
    hand_from_metadata,
    hand_metadata,
    is_chain_hand,
    joint_axes,
    joint_kinds,
    joint_names,
    joint_units,
    link_width,
    manipulator_of,
    palm_thickness,
    scene_at,
)
from qsplan.hands.paper_hand.two_finger import DEFAULT_WORKPIECE, default_hand, finger_angles
from qsplan.hands.paper_hand.scene import hand_manipulator, hand_polygons, hand_scene
from qsplan.mechanics import QsplanError

#: The hexagon the parallel-jaw gripper holds by its side corners (m, as written).
HEXAGON = [[0.0, 0.0], [0.06, 0.0], [0.08, 0.05], [0.05, 0.09], [0.01, 0.09], [-0.02, 0.05]]

#: Free joints of the two-link hand's grasps (rad; the distal entries are closed onto the workpiece).
FREE = [1.4, 0.0, 1.9, 0.0]


@pytest.fixture(scope="module")
def paper():
    return default_hand()


@pytest.fixture(scope="module")
def two_link():
    return make_chain_hand(load_hand("two_link_hand"), DEFAULT_WORKPIECE)


@pytest.fixture(scope="module")
def jaws():
    return make_chain_hand(load_hand("parallel_jaw"), HEXAGON)


def _same_scene(a, b):
    for name in ("Wn", "Wt", "Jn", "Jt", "mu", "g_obj", "g_man", "effort_controlled", "joint_velocity", "joint_effort"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
    assert a.joint_names == b.joint_names and a.contact_names == b.contact_names


def test_the_papers_hand_is_answered_by_its_own_code(paper):
    pose = np.array([0.004, paper.rest_height, 0.0])
    q = finger_angles(paper, pose)[0]
    assert not is_chain_hand(paper)
    assert manipulator_of(paper) is hand_manipulator(paper)
    assert joint_names(paper) == ("left", "right") and joint_kinds(paper) == ("revolute", "revolute")
    assert joint_units(paper) == ("rad", "rad") and joint_units(paper, "tau") == ("N m", "N m")
    assert finger_joint_names(paper) == (("left",), ("right",))
    assert finger_of_joint(paper) == {"left": "left", "right": "right"}
    assert palm_thickness(paper) == paper.palm_thickness and link_width(paper) == paper.finger_width
    assert finger_reach(paper) == paper.finger_length
    np.testing.assert_array_equal(joint_axes(paper, q), paper.pivots)
    polys, ref = hand_body_polygons(paper, pose, q), hand_polygons(paper, pose, q)
    assert list(polys) == list(ref) and all(np.array_equal(polys[k], ref[k]) for k in ref)
    for k, e in enumerate(("left", "right")):
        mask = np.array([k == 0, k == 1])
        for method in ("auto", "generic"):
            got = scene_at(paper, pose, q, mask, [0.2, -0.3], effort=[0.7, -0.4], method=method)
            _same_scene(got, hand_scene(paper, pose, q, e, velocity=[-0.3, 0.2][k], effort=[0.7, -0.4][k], method=method))
    assert [c.body for c in contacts_at(paper, pose, q)] == [-1, -1, 0, 1]


def test_chain_hands_are_answered_by_their_description(two_link, jaws):
    q, _ = close_grasp(two_link, 0.0, FREE)
    pose = two_link.pose(0.0)
    assert is_chain_hand(two_link) and manipulator_of(two_link) is two_link.manipulator
    assert joint_names(two_link) == ("left_proximal", "left_distal", "right_proximal", "right_distal")
    assert finger_joint_names(two_link) == (("left_proximal", "left_distal"), ("right_proximal", "right_distal"))
    assert finger_of_joint(two_link)["right_distal"] == "right"
    assert joint_units(two_link, "qd") == ("rad/s",) * 4
    assert joint_kinds(jaws) == ("prismatic", "prismatic")
    assert [joint_units(jaws, k) for k in ("q", "qd", "tau")] == [("m", "m"), ("m/s", "m/s"), ("N", "N")]
    assert JOINT_UNITS["prismatic"] == {"q": "m", "qd": "m/s", "tau": "N"}
    assert palm_thickness(two_link) == pytest.approx(0.02) and link_width(two_link) == pytest.approx(0.012)
    assert finger_reach(two_link) == pytest.approx(2 * np.hypot(0.07, 0.006))
    np.testing.assert_array_equal(joint_axes(two_link, q), joint_frames(two_link.description, q)[:, :2])
    polys, ref = hand_body_polygons(two_link, pose, q), chain_polygons(two_link, pose, q)
    assert list(polys) == ["palm", "workpiece", *joint_names(two_link)]
    assert all(np.array_equal(polys[k], ref[k]) for k in ref)
    e = np.array([False, False, False, True])
    _same_scene(scene_at(two_link, pose, q, e, [0.0, 0.1, 0.0, 0.0], effort=[0, 0, 0, 0.3]),
                chain_scene(two_link, pose, q, e, [0.0, 0.1, 0.0, 0.0], effort=[0, 0, 0, 0.3]))
    assert [c.body for c in contacts_at(two_link, pose, q)] == [-1, -1, 1, 3]


@pytest.mark.parametrize("name, workpiece", [("two_link_hand", DEFAULT_WORKPIECE), ("parallel_jaw", HEXAGON)])
def test_metadata_records_a_chain_hand_fully(name, workpiece):
    hand = make_chain_hand(load_hand(name), workpiece, workpiece_mass=0.3, mu=0.4)
    meta = json.loads(json.dumps(hand_metadata(hand), allow_nan=False))  # through JSON, as plan.json holds it
    assert meta["description_source"] == f"bundled:{name}"
    back = hand_from_metadata(meta)
    assert is_chain_hand(back) and back.workpiece_mass == 0.3 and back.mu == 0.4
    np.testing.assert_allclose(back.workpiece, hand.workpiece, rtol=0, atol=1e-15)
    a, b = hand.description, back.description
    np.testing.assert_array_equal(a.joint_limits, b.joint_limits)
    np.testing.assert_array_equal(a.joint_speeds, b.joint_speeds)
    assert a.joint_names == b.joint_names and a.joint_kinds == b.joint_kinds and a.name == b.name
    assert [f.joints for f in a.fingers] == [f.joints for f in b.fingers]
    for ja, jb in zip(a.manipulator.joints, b.manipulator.joints):
        for field in ("origin", "link_com", "link_shape"):
            np.testing.assert_array_equal(np.asarray(getattr(ja, field)), np.asarray(getattr(jb, field)), err_msg=field)
        assert ja.link_mass == jb.link_mass and ja.parent == jb.parent
    np.testing.assert_array_equal(a.palm, b.palm)
    assert description_table(hand) == description_table(hand_from_table(description_table(hand), field=""))


def test_metadata_of_the_papers_hand_is_its_parameters(paper):
    meta = hand_metadata(paper)
    assert list(meta) == ["workpiece_vertices_m", "workpiece_mass_kg", "finger_base_m", "finger_length_m",
                          "finger_width_m", "finger_mass_kg", "palm_halfwidth_m", "gravity_m_s2"]  # fmt: skip
    back = hand_from_metadata(json.loads(json.dumps(meta)))
    assert not is_chain_hand(back)
    for key in ("finger_base", "finger_length", "finger_width", "finger_mass", "palm_halfwidth", "gravity"):
        assert getattr(back, key) == getattr(paper, key)
    np.testing.assert_allclose(back.workpiece, paper.workpiece, rtol=0, atol=1e-15)


def _metadata(mutate):
    meta = json.loads(json.dumps(hand_metadata(make_chain_hand(load_hand("two_link_hand"), DEFAULT_WORKPIECE))))
    mutate(meta)
    return meta


@pytest.mark.parametrize("call, match", [
    (lambda p, c: scene_at(p, p.pose(0.0) if hasattr(p, "pose") else [0, 0.05, 0], None, [True, True], [0, 0]),
     "^effort_controlled: expected exactly one"),
    (lambda p, c: joint_names(object()), "^hand: expected a TwoFingerHand or a ChainHand; got object"),
    (lambda p, c: joint_units(c, "speed"), "^quantity: expected one of q, qd, tau"),
    (lambda p, c: hand_body_polygons(c, c.pose(0.0), None), "^q: expected the joint positions"),
    (lambda p, c: description_table(p), "^hand: a TwoFingerHand is recorded by its parameters"),
    (lambda p, c: hand_from_metadata([1]), "^hand: expected the metadata's hand table"),
    (lambda p, c: hand_from_metadata(_metadata(lambda m: m.pop("workpiece_mass_kg"))),
     "^hand.workpiece_mass_kg: missing"),
    (lambda p, c: hand_from_metadata(_metadata(lambda m: m["description"]["fingers"][0]["joints"][0].update(type="ball"))),
     r"^hand.description.fingers\[0\].joints\[0\].type: expected 'revolute' or 'prismatic'"),
    (lambda p, c: hand_from_metadata({"workpiece_vertices_m": DEFAULT_WORKPIECE}), "^hand.workpiece_mass_kg: missing"),
])  # fmt: skip
def test_bad_input_is_named(paper, two_link, call, match):
    with pytest.raises(QsplanError, match=match):
        call(paper, two_link)
