"""The two-finger hand of Fig. 9 and its segment 1: geometry, contacts, kinematics, bands against brute force."""

from itertools import product

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from qsplan.hands.paper_hand.segments import FLUSH_CLEARANCE, first_segment, flush_angle, sample_segment
from qsplan.hands.paper_hand.two_finger import (
    CONTACT_ROLES,
    DEFAULT_WORKPIECE,
    default_hand,
    finger_angle_rates,
    finger_angles,
    make_two_finger_hand,
    workpiece_world,
)
from qsplan.hands.paper_hand.scene import hand_contacts, hand_geometric_scene, hand_polygons, hand_scene
from qsplan.mechanics import ContactMode, SceneError, check_mode, solve
from qsplan.mechanics.bands.effort import effort_band, effort_bands
from qsplan.mechanics.bands.guaranteed import guaranteed_band_box

EDGE = 1e-6  # efforts this close to a band edge are not judged (the edge itself is feasible, eq. 28's >=)
SSSS, BSRS = ContactMode("SSSS"), ContactMode("BSRS")


@pytest.fixture(scope="module")
def hand():
    return default_hand()


@pytest.fixture(scope="module")
def segment(hand):
    return first_segment(hand, duration=10.0)


@pytest.fixture(scope="module")
def samples(segment):
    return sample_segment(segment, 21)


def _pose(segment, s):
    return segment.pose(s)[0]


def test_default_hand_dimensions(hand):
    assert hand.longest_edge == 3  # the left side, from vertex 3 down to vertex 0
    assert hand.edge_lengths[3] == pytest.approx(np.hypot(0.008, 0.100))
    assert np.allclose(hand.workpiece.mean(axis=0), 0.0, atol=0.01)  # about its centroid
    assert hand.rest_height == pytest.approx(-hand.workpiece[:, 1].min())
    assert hand.finger_base == 0.09 and hand.finger_length == 0.16 and hand.finger_width == 0.012
    assert hand.finger_mass == 0.0 and hand.workpiece_mass == 0.2
    # the same polygon placed anywhere, in either orientation, gives the same hand
    other = make_two_finger_hand(np.array(DEFAULT_WORKPIECE[::-1]) + [3.0, 7.0], finger_base=0.09, finger_length=0.16)
    assert np.allclose(other.workpiece, hand.workpiece)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"workpiece": [(0, 0), (1, 0), (0.2, 0.2), (0, 1)]}, "convex"),
        ({"workpiece": [(0, 0), (1, 0.1), (1, 1), (0, 1)]}, "two lowest vertices"),
        ({"workpiece": [(0, 0), (1, 0), (0.5, 0)]}, "workpiece"),
        ({"finger_length": 0.0}, "finger_length"),
        ({"finger_width": -0.01}, "finger_width"),
        ({"finger_width": 0.2, "finger_length": 0.1}, "finger_width"),
        ({"workpiece_mass": 0.0}, "workpiece_mass"),
        ({"finger_mass": -1.0}, "finger_mass"),
        ({"gravity": float("nan")}, "gravity"),
        ({"mu": -0.1}, "mu"),
        ({"finger_base": "far"}, "finger_base"),
    ],
)
def test_validation_names_the_field(kwargs, match):
    args = {"workpiece": DEFAULT_WORKPIECE, **kwargs}
    with pytest.raises(SceneError, match=match):
        make_two_finger_hand(**args)


def test_bad_inputs_of_segments_and_scenes(hand, segment):
    with pytest.raises(SceneError, match="finger_length"):
        finger_angles(make_two_finger_hand(DEFAULT_WORKPIECE, finger_base=0.09, finger_length=0.05), segment.pose_start)
    with pytest.raises(SceneError, match="effort_joint"):
        hand_scene(hand, segment.pose_start, effort_joint="thumb")
    with pytest.raises(SceneError, match="duration"):
        first_segment(hand, duration=0.0)
    with pytest.raises(SceneError, match="flush_clearance"):
        first_segment(hand, flush_clearance=0.0)
    with pytest.raises(SceneError, match="samples"):
        sample_segment(segment, 1)
    # a workpiece whose longest edge is not its left side cannot run segment 1
    with pytest.raises(SceneError, match="longest edge"):
        first_segment(make_two_finger_hand([(0, 0), (0.2, 0), (0.1, 0.05)], finger_base=0.2, finger_length=0.3))


@settings(max_examples=30, deadline=None)
@given(s=st.floats(0.0, 1.0))
def test_fingers_touch_without_penetrating(hand, segment, s):
    pose = _pose(segment, s)
    q, touching = finger_angles(hand, pose)
    V = workpiece_world(hand, pose)
    c = 0.5 * hand.finger_width
    for k, sign in enumerate((1.0, -1.0)):
        d = V - hand.pivots[k]
        inner = sign * np.array([np.sin(q[k]), -np.cos(q[k])])  # the finger's inner side normal
        gap = d @ inner - c  # distance of every vertex outside the finger's inner edge line (m)
        assert gap[touching[k]] == pytest.approx(0.0, abs=1e-12)
        assert np.all(gap >= -1e-12)
        along = d[touching[k]] @ np.array([np.cos(q[k]), np.sin(q[k])])
        assert 0.0 < along < hand.finger_length


def test_contacts_found_from_the_geometry(hand, segment):
    pose = _pose(segment, 0.4)
    gs = hand_geometric_scene(hand, pose)
    found = hand_contacts(gs)
    assert [c.body for c in found] == [-1, -1, 0, 1] and len(CONTACT_ROLES) == 4
    V = workpiece_world(hand, pose)
    q, touching = finger_angles(hand, pose)
    assert np.allclose(found[0].point, V[0]) and np.allclose(found[1].point, V[1])
    assert np.allclose(found[0].normal, [0, 1]) and np.allclose(found[1].normal, [0, 1])
    assert np.allclose(found[2].point, V[touching[0]], atol=1e-9)
    assert np.allclose(found[2].normal, [np.sin(q[0]), -np.cos(q[0])])  # left finger pushes right and down
    assert np.allclose(found[3].normal, [-np.sin(q[1]), np.cos(q[1])])  # right finger pushes left and down
    scene = hand_scene(hand, pose)
    assert scene.contact_names == ("palm:0", "palm:1", "left:2", "right:3")
    assert scene.joint_names == ("left", "right") and list(scene.effort_controlled) == [False, True]
    polys = hand_polygons(hand, pose)
    assert set(polys) == {"palm", "left", "right", "workpiece"}


def test_a_flush_finger_is_a_different_contact_set(hand):
    flush = first_segment(hand, flush_clearance=1e-9)  # the far vertex 1e-10 m off the finger: touching
    with pytest.raises(SceneError, match="one contact per finger"):
        hand_scene(hand, flush.pose_end)


def test_joint_rates_are_the_derivative_of_the_angles(hand, segment):
    rate = segment.pose_rate
    h = 1e-6
    for s in (0.0, 0.3, 0.7, 1.0):
        pose = _pose(segment, s)
        dq = (finger_angles(hand, pose + h * rate)[0] - finger_angles(hand, pose - h * rate)[0]) / (2 * h)
        assert np.allclose(finger_angle_rates(hand, pose, rate), dq, rtol=1e-6, atol=1e-9)
    # a rotating workpiece too
    pose, spin = _pose(segment, 0.5), np.array([0.001, -0.002, 0.05])
    dq = (finger_angles(hand, pose + h * spin)[0] - finger_angles(hand, pose - h * spin)[0]) / (2 * h)
    assert np.allclose(finger_angle_rates(hand, pose, spin), dq, rtol=1e-6, atol=1e-9)


def test_segment_one_ends_short_of_flush(hand, segment):
    assert flush_angle(hand, segment.pose_end) == pytest.approx(FLUSH_CLEARANCE, abs=1e-9)
    assert flush_angle(hand, segment.pose_start) > 0.3
    assert segment.pose_end[0] < segment.pose_start[0] and segment.pose_end[1] == segment.pose_start[1]
    assert segment.mode == "SSSS" and segment.effort_joint == "right"


def test_quasistatic_solution_reproduces_the_translation(samples):
    """solve() of 4S at path points, with a torque inside its band: the workpiece translates as the path says."""
    seg = samples.segment
    checked = 0
    for k in range(0, len(samples), 4):
        scene = samples.scenes[k]
        band = effort_band(scene, SSSS)
        tau = band.lower + 0.5 * (min(band.upper, band.lower + 1.0) - band.lower)
        result = solve(scene.with_inputs(joint_effort=[np.nan, tau]))
        sol = result.solution("SSSS")
        assert sol is not None
        assert np.allclose(sol.qdot, seg.pose_rate, atol=1e-12)  # about the world origin: pure translation
        assert np.allclose(sol.thetadot, samples.qd[k], rtol=1e-9, atol=1e-12)
        assert np.all(sol.xi[:2] == 1)  # the palm contacts slide left: workpiece -x, tangent t = (-1, 0)
        checked += 1
    assert checked >= 5


def test_bands_on_hand_scenes_match_brute_force(samples):
    """The 4S and R2S bands of eq. (28) against check_mode on a grid of torques, at mu = 0 and 0.2."""
    rng = np.random.default_rng(9)
    judged = 0
    for k in range(0, len(samples), 5):
        for mode, mu in ((SSSS, 0.0), (SSSS, 0.2), (BSRS, 0.2)):
            scene = samples.scenes[k].with_mu(mu)
            band = effort_band(scene, mode)
            lo = band.lower if band.feasible and np.isfinite(band.lower) else -2.0
            hi = band.upper if band.feasible and np.isfinite(band.upper) else 50.0
            for tau in np.r_[np.linspace(lo - 1, hi + 1, 25), rng.uniform(-1, 60, 10)]:
                if band.feasible and min(abs(tau - band.lower), abs(tau - band.upper)) < EDGE:
                    continue
                feas = check_mode(scene.with_inputs(joint_effort=[np.nan, tau]), mode).feasible
                assert feas == band.contains(tau), (k, mode.letters, mu, tau, band)
                judged += 1
    assert judged > 300


def _vertices(lo, hi, n_c):
    return np.array([[hi if b else lo for b in bits] for bits in product((0, 1), repeat=n_c)])


@settings(max_examples=25, deadline=None)
@given(s=st.floats(0.0, 1.0), lo=st.floats(0.0, 0.3), width=st.floats(0.0, 0.3))
def test_guaranteed_box_band_on_the_hand_is_the_dense_intersection(segment, s, lo, width):
    """Never wider than the intersection over dense samples of the box; equal to it once the vertices are in."""
    hi = lo + width
    scene = hand_scene(segment.hand, _pose(segment, s), velocity=finger_angle_rates(segment.hand, _pose(segment, s),
                                                                                     segment.pose_rate)[0])  # fmt: skip
    g = guaranteed_band_box(scene, SSSS, lo, hi)
    rng = np.random.default_rng(int(1e6 * s) + 7)
    dense = rng.uniform(lo, hi, size=(3000, 4))
    l, u, ok = effort_bands(scene, SSSS, dense)
    if not g.feasible:
        l2, u2, ok2 = effort_bands(scene, SSSS, np.vstack([dense, _vertices(lo, hi, 4)]))
        assert not ok2.all() or l2.max() > u2.min() or "changes sign" in g.reason
        return
    assert ok.all()
    assert g.lower >= l.max() - 1e-9 and g.upper <= u.min() + 1e-9
    l2, u2, _ = effort_bands(scene, SSSS, np.vstack([dense, _vertices(lo, hi, 4)]))
    assert g.lower == pytest.approx(l2.max(), abs=1e-9)
    assert g.upper == pytest.approx(u2.min(), abs=1e-9, rel=1e-9) or (np.isinf(g.upper) and np.isinf(u2.min()))
