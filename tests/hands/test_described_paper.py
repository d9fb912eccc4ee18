"""The paper's hand two ways: its closed forms (the accelerator) and the generic path (accelerated=False).

For every bundled task on the paper's hand (its finger and palm parameters, its workpiece) and every grasp of
:func:`qsplan.hands.paper_hand.grasp_geometry.candidate_grasps`, at 401 workpiece positions along the palm: the same
configurations (the generic closing closes within the joint limits, which the closed forms leave to the planner:
compared inside them), the same scenes' verdicts (the closed form's check or the polygon search, against the
generic check or the polygon search), and q, contacts, dq_dx and every scene array to 1e-9."""

import numpy as np
import pytest

from qsplan.hands.described.build import described_from_two_finger, make_described_hand
from qsplan.hands.description import load_hand
from qsplan.hands.paper_hand.grasp_geometry import candidate_grasps
from qsplan.hands.paper_hand.grasps import Grasp, OnVertex, TipOnEdge
from tests.hands.described_cases import paper_task_hands

#: Agreement of the two paths (m, rad, rad/m, N, N m): the closed forms and the generic closing compute the same
#: tangencies and corners by different formulas (asin against acos, a finger angle against a link placement).
TOL = 1e-9

_FIELDS = ("Wn", "Wt", "Jn", "Jt", "g_obj", "g_man")


@pytest.mark.parametrize("stem", sorted(paper_task_hands()))
def test_the_generic_path_gives_the_closed_forms_numbers(stem):
    two = paper_task_hands()[stem]
    fast, generic = described_from_two_finger(two), described_from_two_finger(two, accelerated=False)
    assert fast.accelerated and not generic.accelerated
    lim = generic.description.joint_limits
    xs = np.linspace(*fast.palm_range, 401)
    grasps = candidate_grasps(two)
    assert fast.grasp_candidates("palm_edge") == grasps
    compared = 0
    for g in grasps:
        a, b = fast.grasp_states("palm_edge", g, xs), generic.grasp_states("palm_edge", g, xs)
        inside = np.all((a.q >= lim[:, 0]) & (a.q <= lim[:, 1]), axis=1)
        np.testing.assert_array_equal(a.ok & inside, b.ok, err_msg=g.label)
        every = np.arange(len(xs))
        sa, sb = fast.scene_arrays("palm_edge", a, every), generic.scene_arrays("palm_edge", b, every)
        both = sa.ok & inside
        np.testing.assert_array_equal(both, sb.ok, err_msg=g.label)
        for name in ("q", "points", "normals", "dq_dx"):
            np.testing.assert_allclose(getattr(a, name)[both], getattr(b, name)[both], rtol=0, atol=TOL, err_msg=name)
        np.testing.assert_array_equal(a.touched[both], b.touched[both])
        for name in _FIELDS:
            np.testing.assert_allclose(getattr(sa, name)[both], getattr(sb, name)[both], rtol=0, atol=TOL, err_msg=name)
        compared += int(both.sum())
    assert compared > 100


def test_a_finger_flush_along_a_side_is_refused_both_ways():
    """The left finger upright along the pentagon's upright left side (x = -0.049 m): the closed form touches the side's
    top vertex, the generic closing its bottom one (the tangencies of both ends agree to rounding, ~1e-8 rad); both then
    refuse the scene, whose polygons give two contacts on the finger (the generic check without a polygon search)."""
    pentagon = [[0.0, 0.0], [0.070, 0.0], [0.070, 0.060], [0.035, 0.090], [0.0, 0.060]]
    fast = make_described_hand(load_hand("paper_hand"), pentagon)
    generic = make_described_hand(load_hand("paper_hand"), pentagon, accelerated=False)
    g, x = Grasp(OnVertex(), TipOnEdge(2)), np.array([-0.049])
    a, b = fast.grasp_states("palm_edge", g, x), generic.grasp_states("palm_edge", g, x)
    assert a.ok[0] and b.ok[0] and a.touched[0, 0] != b.touched[0, 0]
    sa, sb = fast.scene_arrays("palm_edge", a), generic.scene_arrays("palm_edge", b)
    assert not sa.ok[0] and "found ['palm', 'palm', 'left', 'left', 'right']" in sa.reasons[0]
    assert not sb.ok[0] and "a second contact on the left finger" in sb.reasons[0]


def test_the_paper_hand_keeps_its_grasps_and_scenes_when_accelerated():
    hand = make_described_hand(load_hand("paper_hand"), [[0.0, 0.0], [0.080, 0.0], [0.085, 0.080], [0.008, 0.100]])
    (g,) = hand.grasp_candidates()
    assert isinstance(g, Grasp) and g.label == "L vertex / R vertex"
    states = hand.grasp_states("palm_edge", g, np.linspace(-0.02, 0.02, 41))
    arrays = hand.scene_arrays("palm_edge", states)
    assert arrays.closed_form and arrays.ok.all()
    scene = hand.state_scene(arrays, 3, [False, True], [0.1, 0.0])
    assert scene.contact_names == ("palm:0", "palm:1", "left:2", "right:3")
    ref = hand.scene(states.poses[arrays.idx[3]], states.q[arrays.idx[3]], [False, True], [0.1, 0.0])
    for name in (*_FIELDS, "joint_velocity", "effort_controlled"):
        np.testing.assert_array_equal(getattr(scene, name), getattr(ref, name))
