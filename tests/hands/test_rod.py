"""The rod of Figs. 7-8: simulator against the closed form, bouncing, equal friction, ambiguity, Zeno."""

import numpy as np
import pytest

from qsplan.hands.examples.paper import rod_scene
from qsplan.hands.examples.rod import (
    check_rod_inputs,
    make_rod_system,
    rod_closed_form,
    rod_distances,
    rod_initial_state,
    simulate_rod,
)
from qsplan.mechanics import QsplanError, scene_from_dict, solve
from qsplan.mechanics.motion.simulator import MotionOptions

ACCEPT = 1e-6  # the bound on switch times and positions

CASES = {
    "bouncing": dict(l1=1.0, l2=0.6, mu_static=(0.5, 0.5), mu_kinetic=(0.4, 0.4), speed=0.1, duration=20.0),
    "unequal": dict(l1=1.0, l2=0.4, mu_static=(0.6, 0.5), mu_kinetic=(0.45, 0.3), speed=0.2, duration=3.2),
    "starts_RS": dict(l1=0.3, l2=1.1, mu_static=(0.7, 0.4), mu_kinetic=(0.5, 0.35), speed=0.05, duration=12.0),
    "fast_zeno": dict(l1=1.0, l2=0.4, mu_static=(0.6, 0.6), mu_kinetic=(0.3, 0.3), speed=0.1, duration=20.0),
}


def _table(motion):
    rows = []
    for s in motion.segments:
        L = rod_distances(np.array([s.x_start, s.x_end]))
        rows.append([s.t_start, s.t_end, L[0, 0], L[0, 1], L[1, 0], L[1, 1]])
    return np.array(rows)


def _cf_table(cf):
    return np.array([[c.t_start, c.t_end, c.l1_start, c.l2_start, c.l1_end, c.l2_end] for c in cf.segments])


@pytest.fixture(scope="module")
def runs():
    return {k: (simulate_rod(**p), rod_closed_form(**p)) for k, p in CASES.items()}


@pytest.mark.parametrize("case", list(CASES))
def test_switches_match_the_closed_form(runs, case):
    motion, cf = runs[case]
    assert [s.label for s in motion.segments] == [c.mode for c in cf.segments]
    assert (motion.stopped.kind if motion.stopped else None) == cf.stopped
    err = np.max(np.abs(_table(motion) - _cf_table(cf)))
    assert err < ACCEPT
    assert err < 1e-9  # in fact at rounding level: the rates are constant within a mode


@pytest.mark.parametrize("case", ["bouncing", "unequal"])
def test_switches_do_not_change_when_the_step_is_halved(case):
    p = {**CASES[case], "duration": 7.9} if case == "bouncing" else CASES[case]  # ~30 switches, before Zeno
    h = (p["l1"] + p["l2"]) / (2 * p["speed"]) / 37
    a = simulate_rod(**p, options=MotionOptions(max_step=h))
    b = simulate_rod(**p, options=MotionOptions(max_step=h / 2))
    assert [s.label for s in a.segments] == [s.label for s in b.segments]
    assert np.max(np.abs(_table(a) - _table(b))) < 1e-9


def test_bouncing_alternates_and_the_line_chases_the_corners(runs):
    motion, cf = runs["bouncing"]
    labels = [s.label for s in motion.segments]
    assert labels[0] == "SR" and all(x != y for x, y in zip(labels, labels[1:]))  # supports alternate
    (m1R, m2R), (m1S, m2S) = (0.5, 0.5), (0.4, 0.4)
    for seg in motion.segments[:-1]:
        l1, l2 = rod_distances(seg.states[-1:])[0]
        if seg.label == "SR":  # ends with the line through the upper-left corner (mu_1S, mu_2R)
            assert l1 * m2R == pytest.approx(l2 * m1S, rel=1e-9)
        else:  # ... the lower-right corner (mu_1R, mu_2S)
            assert l1 * m2S == pytest.approx(l2 * m1R, rel=1e-9)
    for seg in motion.segments:  # the rolling support keeps its distance; the sum shrinks at 2V
        L = rod_distances(seg.states)
        rolling = 1 if seg.label == "SR" else 0
        np.testing.assert_allclose(L[:, rolling], L[0, rolling], atol=1e-12)
        np.testing.assert_allclose(L.sum(axis=1), 1.6 - 0.2 * seg.times, atol=1e-12)


def test_zeno_stop_at_the_meeting_instant(runs):
    motion, cf = runs["bouncing"]
    assert motion.stopped.kind == "zeno" and cf.stopped == "zeno"
    assert cf.t_star == pytest.approx(8.0)
    assert motion.switch_times[-1] < 8.0 and motion.stopped.time == pytest.approx(8.0, abs=1e-5)
    assert "converge to about t = 8 s" in motion.stopped.message
    # the cycle ratio of the sum l1 + l2 is a / b
    s = 1.6 - 0.2 * motion.switch_times
    np.testing.assert_allclose(s[2::2] / s[:-2:2], (0.4 / 0.5) / (0.5 / 0.4), rtol=1e-7)


@pytest.mark.parametrize("l1,l2,mu,slider", [(1.0, 0.6, (0.3, 0.3), "SR"), (0.5, 1.0, (0.3, 0.4), "RS")])
def test_equal_static_and_kinetic_farther_support_slides_until_the_line(l1, l2, mu, slider):
    motion = simulate_rod(l1, l2, mu, mu, 0.1, 20.0)
    assert [s.label for s in motion.segments] == [slider]
    assert motion.stopped.kind == "no_persistent_mode"
    assert set(motion.stopped.candidates) == {"RS", "SR"}
    e1, e2 = rod_distances(motion.stopped.state[None])[0]
    assert e1 * mu[1] == pytest.approx(e2 * mu[0], rel=1e-9)
    if mu[0] == mu[1]:
        assert e1 == pytest.approx(e2, rel=1e-9)  # the distances equalise
    cf = rod_closed_form(l1, l2, mu, mu, 0.1, 20.0)
    assert cf.stopped == "no_persistent_mode" and cf.segments[0].t_end == pytest.approx(motion.stopped.time, abs=1e-12)


def test_ambiguous_start_is_reported_and_resolved_by_the_initial_mode():
    p = dict(l1=1.0, l2=0.9, mu_static=(0.5, 0.5), mu_kinetic=(0.4, 0.4), speed=0.1, duration=20.0)
    motion = simulate_rod(**p)
    assert motion.segments == () and motion.stopped.kind == "ambiguous" and motion.stopped.time == 0.0
    assert motion.stopped.candidates == ("RS", "SR")
    assert rod_closed_form(**p).stopped == "ambiguous"
    for start in ("RS", "SR"):
        q = {**p, "duration": 7.0}
        m = simulate_rod(**q, initial_mode=start, options=MotionOptions(max_step=0.1))
        cf = rod_closed_form(**q, initial_mode=start)
        assert m.segments[0].label == start
        n = 6
        np.testing.assert_allclose(_table(m)[:n], _cf_table(cf)[:n], atol=1e-9)


def test_start_on_the_boundary_takes_the_mode_that_persists():
    # rho0 = a = mu_1S / mu_2R = 0.8: SR is feasible but fails at once, RS persists
    motion = simulate_rod(0.8, 1.0, (0.5, 0.5), (0.4, 0.4), 0.1, 1.0)
    assert motion.segments[0].label == "RS"
    assert rod_closed_form(0.8, 1.0, (0.5, 0.5), (0.4, 0.4), 0.1, 1.0).segments[0].mode == "RS"


def test_short_duration_reaches_the_end_inside_a_segment():
    motion = simulate_rod(1.0, 0.6, (0.5, 0.5), (0.4, 0.4), 0.1, 1.5)
    assert motion.stopped is None and [s.label for s in motion.segments] == ["SR"]
    np.testing.assert_allclose(rod_distances(motion.segments[0].states[-1:])[0], [1.0 - 0.3, 0.6], atol=1e-12)


def test_rod_system_matches_the_paper_scene_and_weight_only_scales_forces():
    system = make_rod_system((0.3, 0.3), (0.3, 0.3), 0.1)
    scene = system.scene(rod_initial_state(1.0, 0.6), (0, 1))
    ref = scene_from_dict(rod_scene(1.0, 0.6, (0.3, 0.3), 0.1))
    np.testing.assert_allclose(scene.Wn, ref.Wn, atol=1e-15)
    np.testing.assert_allclose(scene.Wt, ref.Wt, atol=1e-15)
    a, b = solve(scene).solutions, solve(ref).solutions
    assert [s.mode.letters for s in a] == [s.mode.letters for s in b] == ["SR"]
    np.testing.assert_allclose(a[0].qdot, b[0].qdot, atol=1e-15)
    np.testing.assert_allclose(a[0].c_n, b[0].c_n, atol=1e-15)
    heavy = simulate_rod(1.0, 0.6, (0.5, 0.5), (0.4, 0.4), 0.1, 5.0, weight=7.0)
    light = simulate_rod(1.0, 0.6, (0.5, 0.5), (0.4, 0.4), 0.1, 5.0)
    np.testing.assert_allclose(_table(heavy), _table(light), atol=1e-12)
    np.testing.assert_allclose(heavy.segments[0].solution.c_n, 7.0 * light.segments[0].solution.c_n)


@pytest.mark.parametrize(
    "args,match",
    [
        ((0.0, 1.0, (0.5, 0.5), (0.4, 0.4), 0.1), "l1: expected a positive"),
        ((1.0, -1.0, (0.5, 0.5), (0.4, 0.4), 0.1), "l2: expected a positive"),
        ((1.0, 1.0, (0.5, 0.5), (0.4, 0.4), 0.0), "speed: expected a positive"),
        ((1.0, 1.0, (0.5,), (0.4, 0.4), 0.1), "mu_static: expected 2 coefficients"),
        ((1.0, 1.0, (0.5, 0.5), (0.6, 0.4), 0.1), r"friction.kinetic\[0\]: expected at most"),
        ((1.0, 1.0, (0.5, -0.5), (0.4, 0.4), 0.1), r"friction.static\[1\]"),
    ],
)
def test_rod_inputs_rejected(args, match):
    with pytest.raises(QsplanError, match=match):
        check_rod_inputs(*args)


def test_closed_form_needs_positive_static_friction_and_initial_mode_is_checked():
    with pytest.raises(QsplanError, match="positive static coefficients"):
        rod_closed_form(1.0, 0.6, (0.0, 0.5), (0.0, 0.4), 0.1, 1.0)
    with pytest.raises(QsplanError, match="initial_mode: expected 'RS' or 'SR'"):
        simulate_rod(1.0, 0.6, (0.5, 0.5), (0.4, 0.4), 0.1, 1.0, initial_mode="SS")


def test_switch_times_follow_the_geometric_sequence_of_the_docstring(runs):
    """t_k = (s0 - s_k) / (2V) with s_1 = (1 + a) l2_0 and s alternately scaled by r_RS, r_SR."""
    motion, _ = runs["bouncing"]
    a, b, V, s0 = 0.4 / 0.5, 0.5 / 0.4, 0.1, 1.6
    r_rs, r_sr = a * (1 + b) / (b * (1 + a)), (1 + a) / (1 + b)
    s = [(1 + a) * 0.6]
    for k in range(1, len(motion.switch_times)):
        s.append(s[-1] * (r_rs if k % 2 else r_sr))
    np.testing.assert_allclose(motion.switch_times, (s0 - np.array(s)) / (2 * V), atol=1e-9)
