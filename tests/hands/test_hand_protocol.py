"""The hand protocol (qsplan.hands.protocol.Hand) as every bundled hand answers it: types and shapes of every method,
metadata round trips (the paper hand by today's keys), grasp labels and goals, collisions, and one error per
validation branch."""

import numpy as np
import pytest

from qsplan.hands.chains.hand import make_chain_hand
from qsplan.hands.chains.record import ChainRecord
from qsplan.hands.described.build import (described_from_chain, described_from_two_finger, hand_from_metadata,
                                          make_described_hand, record_of)  # fmt: skip
from qsplan.hands.description import load_hand
from qsplan.hands.formations.registry import ContactSlot, Formation
from qsplan.hands.paper_hand.grasps import Grasp, OnVertex, TipOnEdge
from qsplan.hands.described.records import hand_metadata
from qsplan.hands.paper_hand.accelerator import paper_state_scene, paper_states
from qsplan.hands.paper_hand.record import PaperRecord
from qsplan.hands.protocol import ChainGrasp, FingerContact, GraspSceneArrays, GraspStates, Hand, HandRecord
from qsplan.hands.paper_hand.two_finger import DEFAULT_WORKPIECE, default_hand, make_two_finger_hand
from qsplan.mechanics.errors import QsplanError, SceneError
from qsplan.mechanics.model.scene import Scene
from tests.hands.described_cases import chain_cases


def _hands():
    out = {f"{name}": (make_described_hand(desc, wp), centre) for name, (desc, wp, centre) in chain_cases().items()}
    out["paper_hand"] = (make_described_hand(load_hand("paper_hand"), DEFAULT_WORKPIECE), None)
    out["paper_hand generic"] = (make_described_hand(load_hand("paper_hand"), DEFAULT_WORKPIECE, accelerated=False), None)
    return out


@pytest.fixture(scope="module", params=sorted(_hands()))
def case(request):
    return _hands()[request.param]


def test_every_hand_answers_the_protocol_with_its_shapes(case):
    hand, centre = case
    assert isinstance(hand, Hand)
    n_j, k = len(hand.joint_names), len(hand.workpiece)
    assert hand.closing_joints == tuple(f[-1] for f in hand.finger_joints)
    assert sorted(hand.free_joints + hand.closing_joints) == list(range(n_j))
    assert hand.pose(0.01).shape == (3,) and hand.pose(0.01)[1] == hand.rest_height
    grasps = hand.grasp_candidates("palm_edge", None if centre is None else [centre])
    assert grasps
    xs = np.linspace(-0.02, 0.02, 21)
    states = max((hand.grasp_states("palm_edge", g, xs) for g in grasps), key=lambda s: s.ok.sum())
    assert isinstance(states, GraspStates) and states.ok.any()
    n = len(xs)
    assert states.q.shape == states.dq_dx.shape == (n, n_j) and states.poses.shape == (n, 3)
    assert states.points.shape == states.normals.shape == (n, 4, 2) and states.bodies.shape == (n, 4)
    assert states.touched.shape == states.touched_as_written.shape == states.finger_ok.shape == (n, 2)
    assert states.take([0, 2]).n == 2 and np.all(states.touched_as_written < k)
    arrays = hand.scene_arrays("palm_edge", states)
    m = len(arrays.idx)
    assert isinstance(arrays, GraspSceneArrays) and np.array_equal(arrays.idx, np.flatnonzero(states.ok))
    assert arrays.Wn.shape == arrays.Wt.shape == (m, 3, 4) and arrays.Jn.shape == arrays.Jt.shape == (m, 4, n_j)
    assert arrays.g_obj.shape == (m, 3) and arrays.g_man.shape == arrays.dq_dx.shape == (m, n_j)
    s = int(np.flatnonzero(arrays.ok)[0])
    e = np.arange(n_j) == hand.closing_joints[1]
    scene = hand.state_scene(arrays, s, e, arrays.dq_dx[s] * 0.01)
    assert isinstance(scene, Scene) and scene.Wn.shape == (3, 4) and scene.joint_names == hand.joint_names
    i = arrays.idx[s]
    one = hand.scene(states.poses[i], states.q[i], e, states.dq_dx[i] * 0.01, method="generic")
    for name in ("Wn", "Wt", "Jn", "Jt", "g_obj", "g_man", "joint_velocity"):
        np.testing.assert_allclose(getattr(scene, name), getattr(one, name), rtol=0, atol=1e-12, equal_nan=True)
    polys = hand.body_polygons(states.poses[i], states.q[i])
    assert set(polys) == {"palm", "workpiece", *hand.joint_names} and polys["workpiece"].shape == (k, 2)
    hit = hand.collide(states.poses[states.ok], states.q[states.ok])
    assert hit.shape == (states.ok.sum(),) and hit.dtype == bool
    for j, row in enumerate(np.flatnonzero(states.ok)):
        assert hit[j] == bool(hand.collisions(states.poses[row], states.q[row], first=True))
    opening = hand.opening(states.grasp, states.x[i], states.q[i])
    assert opening.shape == (n_j,) and set(np.unique(opening)) <= {-1.0, 0.0, 1.0}


def test_metadata_round_trips(case):
    """The hand comes back; its polygon, centred again about its centroid, moves by rounding (~1e-17 m), as with
    :func:`qsplan.hands.described.records.hand_from_metadata` today."""
    hand, _ = case
    meta = hand.metadata()
    again = hand_from_metadata(meta)
    assert again.joint_names == hand.joint_names and again.accelerated == hand.paper_form
    np.testing.assert_allclose(again.workpiece, hand.workpiece, rtol=0, atol=1e-15)
    assert {k: v for k, v in again.metadata().items() if k != "workpiece_vertices_m"} == \
        {k: v for k, v in meta.items() if k != "workpiece_vertices_m"}


def test_the_paper_hand_is_recorded_by_todays_keys():
    two = make_two_finger_hand([[0.0, 0.0], [0.09, 0.0], [0.07, 0.06], [0.02, 0.06]], 0.15, finger_length=0.08)
    hand = described_from_two_finger(two)
    assert hand.metadata() == hand_metadata(two) and hand.own_limits is None
    from_file = make_described_hand(load_hand("paper_hand"), DEFAULT_WORKPIECE)
    assert from_file.metadata() == hand_metadata(default_hand()) and from_file.own_limits is not None
    assert hand_from_metadata(from_file.metadata()).accelerated


def test_a_chain_hand_converts_and_keeps_its_description():
    desc, wp, _ = chain_cases()["two_link_hand"]
    hand = make_described_hand(desc, wp)
    again = described_from_chain(hand.chain)
    assert again.description is desc and again.metadata() == hand_metadata(hand.chain) and not again.accelerated


def test_chain_grasps_are_labelled_and_meet_goals_in_the_users_numbering():
    left = FingerContact(1, "left_distal", "vertex", 3, 2)
    right = FingerContact(3, "right_distal", "edge", 1, 0)
    g = ChainGrasp(left, right, (1.4, 1.74), ("left_proximal", "right_proximal"))
    assert g.label == "L left_distal vertex:2 / R right_distal edge:0 (left_proximal 1.4, right_proximal 1.74)"
    assert g.keys == ((1, "vertex", 3), (3, "edge", 1))
    assert g.matches("vertex:2", "edge:0") and g.matches("vertex", None) and g.matches()
    assert not g.matches("vertex:3") and not g.matches(None, "vertex") and not g.matches(None, "edge:0:1")
    assert hash(g) == hash(ChainGrasp(left, right, (1.4, 1.74), ("left_proximal", "right_proximal")))


def test_grasp_states_say_where_a_vertex_goal_is_met():
    hand = make_described_hand(load_hand("paper_hand"), DEFAULT_WORKPIECE)
    states = hand.grasp_states("palm_edge", Grasp(OnVertex(), OnVertex()), np.linspace(-0.03, 0.03, 61))
    assert states.ok.sum() > 30 and np.all(states.touched_as_written[states.ok] == (3, 2))
    np.testing.assert_array_equal(states.matches("vertex:3", "vertex:2"), states.ok)
    assert not states.matches("vertex:2").any() and not states.matches("edge:1").any()


# one error per validation branch

@pytest.fixture(scope="module")
def two_link():
    desc, wp, centre = chain_cases()["two_link_hand"]
    hand = make_described_hand(desc, wp)
    return hand, hand.grasp_candidates("palm_edge", [centre])[0]


def test_an_unknown_formation_is_named(two_link):
    hand, g = two_link
    with pytest.raises(QsplanError, match=r"formation: expected one of (\w+, )*palm_edge(, \w+)*; got 'nope'"):
        hand.grasp_states("nope", g, [0.0])


def test_a_formation_the_closing_does_not_serve_is_named(two_link):
    hand, g = two_link
    slots = (ContactSlot("palm:0", "palm", "vertex", 0, ""), ContactSlot("palm:1", "palm", "vertex", 1, ""),
             ContactSlot("left:a", "left", "any", None, ""), ContactSlot("left:b", "left", "any", None, ""),
             ContactSlot("right", "right", "any", None, ""))  # fmt: skip
    two = Formation("two_left", slots, "SSSSS", "last", "two contacts on the left finger")
    with pytest.raises(QsplanError, match="formation: 'two_left' is not served by the described hands' closing"):
        hand.grasp_states(two, g, [0.0])


def test_workpiece_positions_must_be_finite(two_link):
    hand, g = two_link
    with pytest.raises(QsplanError, match=r"xs: expected a finite 1-D array of workpiece x \(m\)"):
        hand.grasp_states("palm_edge", g, [0.0, np.nan])


def test_per_state_free_joints_need_their_shape(two_link):
    hand, g = two_link
    with pytest.raises(QsplanError, match=r"free: expected finite free-joint values of shape \(2, 2\)"):
        hand.grasp_states("palm_edge", g, [0.0, 0.01], free=np.zeros((2, 3)))


def test_a_grasp_gives_every_free_joint(two_link):
    hand, g = two_link
    with pytest.raises(QsplanError, match="grasp.free: expected 2 free-joint values; got 1"):
        hand.grasp_states("palm_edge", ChainGrasp(g.left, g.right, (1.4,), g.free_names[:1]), [0.0])


def test_a_chain_contact_is_on_the_closing_link(two_link):
    hand, g = two_link
    wrong = FingerContact(0, "left_proximal", g.left.kind, g.left.feature, g.left.written)
    with pytest.raises(QsplanError, match="grasp.left: expected a contact of the finger's closing link 'left_distal'"):
        hand.grasp_states("palm_edge", ChainGrasp(wrong, g.right, g.free, g.free_names), [0.0])


def test_placements_are_grasps_of_the_paper_hand_only(two_link):
    hand, _ = two_link
    with pytest.raises(QsplanError, match="grasp: 'L vertex / R vertex' is a grasp of the paper's hand"):
        hand.grasp_states("palm_edge", Grasp(OnVertex(), OnVertex()), [0.0])


def test_a_grasp_is_a_chain_grasp_or_placements(two_link):
    hand, _ = two_link
    with pytest.raises(QsplanError, match="grasp: expected a ChainGrasp or a Grasp; got str"):
        hand.grasp_states("palm_edge", "L vertex / R vertex", [0.0])


def test_a_placement_is_read_only_of_its_two_forms():
    generic = make_described_hand(load_hand("paper_hand"), DEFAULT_WORKPIECE, accelerated=False)
    with pytest.raises(QsplanError, match=r"grasp.right: expected an OnVertex or TipOnEdge placement \(branch 0 or 1\)"):
        generic.grasp_states("palm_edge", Grasp(OnVertex(), TipOnEdge(1, 2)), [0.0])


def test_candidate_free_joints_need_their_shape(two_link):
    hand, _ = two_link
    with pytest.raises(QsplanError, match=r"free: expected finite free-joint values, shape \(m, 2\)"):
        hand.grasp_candidates("palm_edge", [[1.4, 1.7, 0.0]])


def test_a_scene_method_is_named(two_link):
    hand, _ = two_link
    with pytest.raises(QsplanError, match="method: expected 'auto' or 'generic'; got 'fast'"):
        hand.scene(hand.pose(0.0), np.zeros(4), [True, False, False, False], np.zeros(4), method="fast")


def test_the_paper_accelerator_takes_one_effort_finger():
    hand = make_described_hand(load_hand("paper_hand"), DEFAULT_WORKPIECE)
    states = hand.grasp_states("palm_edge", Grasp(OnVertex(), OnVertex()), [0.0])
    arrays = hand.scene_arrays("palm_edge", states)
    with pytest.raises(QsplanError, match="effort_controlled: expected exactly one of the two fingers effort-controlled"):
        paper_state_scene(hand.paper, arrays, 0, [True, True], [0.0, 0.0])


def test_the_paper_accelerator_takes_placements():
    hand = make_described_hand(load_hand("paper_hand"), DEFAULT_WORKPIECE)
    with pytest.raises(QsplanError, match="grasp: expected a Grasp of the paper's hand"):
        paper_states(hand.paper, None, "L vertex / R vertex", np.array([0.0]))


def test_a_goal_is_a_placement_string():
    contact = FingerContact(1, "left_distal", "vertex", 3, 2)
    with pytest.raises(SceneError, match="goal_left: expected 'vertex', 'vertex:K'"):
        contact.matches("corner:2", "goal_left")


# the questions the planner asked through qsplan.hands.described.records, folded into the protocol (issue 32)

def _configuration(hand, centre):
    """A closed grasp's ``(pose, q)`` and its scene inputs (the right closing joint effort-controlled)."""
    grasps = hand.grasp_candidates("palm_edge", None if centre is None else [centre])
    states = max((hand.grasp_states("palm_edge", g, np.linspace(-0.02, 0.02, 21)) for g in grasps),
                 key=lambda s: s.ok.sum())  # fmt: skip
    i = int(np.flatnonzero(states.ok)[len(np.flatnonzero(states.ok)) // 2])
    e = np.arange(len(hand.joint_names)) == hand.closing_joints[1]
    return states.poses[i], states.q[i], e, np.where(e, 0.0, states.dq_dx[i] * 0.01)


def test_the_folded_questions_answer_as_the_interface_did(case):
    """Each member the planner now asks equals the interface function it replaced, asked of the same hand, exactly;
    and, to rounding, the same function asked of the hand's chain record (the polygon search, the accelerator's
    reference): the paper hand's closed forms and its description agree."""
    from qsplan.hands.described import records as old

    hand, centre = case
    chain = hand.chain
    pose, q, e, qd = _configuration(hand, centre)
    for quantity in ("q", "qd", "tau"):
        assert hand.joint_units(quantity) == old.joint_units(hand, quantity) == old.joint_units(chain, quantity)
        for name in hand.joint_names:
            assert hand.joint_unit(name, quantity) == old.joint_unit(hand, name, quantity)
    assert hand.joint_names == old.joint_names(hand) == old.joint_names(chain)
    assert hand.joint_kinds == old.joint_kinds(hand) == old.joint_kinds(chain)
    assert hand.finger_joint_names == old.finger_joint_names(hand) == old.finger_joint_names(chain)
    assert hand.finger_of_joint == old.finger_of_joint(hand) == old.finger_of_joint(chain)
    assert hand.finger_reach == old.finger_reach(hand) and hand.palm_thickness == old.palm_thickness(hand)
    assert hand.palm_thickness == pytest.approx(old.palm_thickness(chain), rel=0, abs=1e-15)
    assert hand.range_fields() == old.range_fields(hand)
    assert hand.description_table() == old.description_table(hand.description)
    recorded = hand.paper if hand.paper_form else chain  # the paper's form by its parameters, accelerated or not
    assert hand.metadata() == old.hand_metadata(recorded)
    if hand.accelerated or not hand.paper_form:
        assert hand.metadata() == old.hand_metadata(hand)
    ours, theirs = hand.manipulator, old.manipulator_of(hand)
    np.testing.assert_allclose(ours.base_shape, theirs.base_shape, rtol=0, atol=1e-15)
    for a, b in zip(ours.joints, theirs.joints, strict=True):
        assert (a.name, a.kind, a.parent) == (b.name, b.kind, b.parent) and a.link_mass == pytest.approx(b.link_mass)
        np.testing.assert_allclose(a.link_shape, b.link_shape, rtol=0, atol=1e-15)
        np.testing.assert_allclose(a.origin, b.origin, rtol=0, atol=1e-15)
    for reference in (hand, chain):
        np.testing.assert_allclose(hand.joint_axes(q), old.joint_axes(reference, q), rtol=0, atol=1e-15)
        polys, want = hand.body_polygons(pose, q), old.hand_body_polygons(reference, pose, q)
        assert polys.keys() == want.keys()
        for name in polys:
            np.testing.assert_allclose(polys[name], want[name], rtol=0, atol=1e-15)
        for method in ("auto", "generic"):
            one, two = hand.scene(pose, q, e, qd, method=method), old.scene_at(reference, pose, q, e, qd, method=method)
            assert one.contact_names == two.contact_names
            for field in ("Wn", "Wt", "Jn", "Jt", "g_obj", "g_man", "joint_velocity"):
                np.testing.assert_allclose(getattr(one, field), getattr(two, field), rtol=0, atol=1e-12, equal_nan=True)


def test_a_records_range_fields_are_its_described_hands():
    """At the door a task checks a record's numbers before it becomes a described hand (whose description checks would
    name other fields): the record and the described hand give the same fields, the paper's parameters first."""
    two = make_two_finger_hand([[0.0, 0.0], [0.09, 0.0], [0.07, 0.06], [0.02, 0.06]], 0.15, finger_length=0.08)
    fields = two.range_fields()
    assert described_from_two_finger(two).range_fields() == fields
    assert [f for f, *_ in fields][:2] == ["hand.finger_base", "hand.finger_length"] and fields[1][1] == 0.08
    desc, wp, _ = chain_cases()["two_link_hand"]
    chain = make_described_hand(desc, wp)
    assert chain.range_fields() == chain.chain.range_fields()
    assert [f for f, *_ in chain.range_fields()] == ["hand.workpiece (its width or height)", "hand.workpiece_mass",
                                                     "hand.gravity", "hand.mu"]  # fmt: skip


def test_a_joint_quantity_is_named():
    hand = make_described_hand(load_hand("paper_hand"), DEFAULT_WORKPIECE)
    with pytest.raises(QsplanError, match=r"quantity: expected one of q, qd, tau; got 'force'"):
        hand.joint_units("force")


def test_every_record_answers_the_record_protocol():
    """Each hand record's answerer has every member of :class:`qsplan.hands.protocol.HandRecord`, and a described hand
    picks one at construction, whichever record answers it."""
    paper, chain = default_hand(), make_chain_hand(load_hand("two_link_hand"), DEFAULT_WORKPIECE)
    for record in (PaperRecord(paper), ChainRecord(chain), record_of(paper), record_of(chain)):
        assert isinstance(record, HandRecord), type(record).__name__
    assert record_of(paper).hand is paper and record_of(chain).hand is chain
    assert isinstance(described_from_two_finger(paper).record, PaperRecord)
    assert isinstance(described_from_two_finger(paper, accelerated=False).record, ChainRecord)
    assert isinstance(make_described_hand(load_hand("paper_hand"), DEFAULT_WORKPIECE).record, PaperRecord)
    assert isinstance(make_described_hand(load_hand("two_link_hand"), DEFAULT_WORKPIECE).record, ChainRecord)
