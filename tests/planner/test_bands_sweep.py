"""Torque bands along segment 1 (Figs. 10-13) and the preclusion of competing modes, against brute force."""

import numpy as np
import pytest

from qsplan.hands.paper_hand.segments import first_segment, sample_segment
from qsplan.hands.paper_hand.two_finger import default_hand
from qsplan.mechanics import ModeError, QsplanError, SceneError, planted_scene, solve
from qsplan.mechanics.bands.effort import band_kinematics, effort_bands
from qsplan.mechanics.modes.contact_mode import enumerate_modes
from qsplan.mechanics.bands.robust import subtract_hull
from qsplan.planner.torque.sweep import (
    competing_modes,
    guaranteed_sweep,
    narrowest,
    point_band_sweep,
    sampled_guaranteed_sweep,
    segment_bands,
)
from qsplan.planner.torque.command import choose_command
from qsplan.mechanics.bands.preclusion import competitor_torques

N = 21  # samples along the segment: every 0.5 s


@pytest.fixture(scope="module")
def samples():
    return sample_segment(first_segment(default_hand(), duration=10.0), N)


@pytest.fixture(scope="module")
def box(samples):
    return segment_bands(samples, (0.0, 0.2), shared=False)


@pytest.fixture(scope="module")
def shared(samples):
    return segment_bands(samples, (0.0, 0.2), shared=True)


# --- competitor preclusion against brute force -------------------------------------------------


def _competitors(seed, n_scenes):
    rng = np.random.default_rng(seed)
    for _ in range(n_scenes):
        scene, _ = planted_scene(rng, int(rng.integers(3, 5)), 1)
        for m in enumerate_modes(scene.n_contacts, scene.dof):
            if band_kinematics(scene, m).ok:
                yield rng, scene, m


def test_competitor_hull_contains_every_feasible_effort_box():
    """Conservative always: every (effort, friction) sample where the competitor is feasible lies in the hull."""
    nontrivial = 0
    for rng, scene, m in _competitors(11, 12):
        lo, hi = 0.5 * scene.mu, 1.5 * scene.mu
        c = competitor_torques(scene, m, lo, hi, -5.0, 5.0)
        mus = np.vstack([rng.uniform(lo, hi, size=(4000, scene.n_contacts)), lo, hi])
        l, u, ok = effort_bands(scene, m, mus)
        ok &= np.maximum(l, -5.0) <= np.minimum(u, 5.0)
        if not ok.any():
            continue
        nontrivial += 1
        assert not c.empty
        assert c.lower <= np.maximum(l[ok], -5.0).min() + 1e-9
        assert c.upper >= np.minimum(u[ok], 5.0).max() - 1e-9
    assert nontrivial >= 10


def test_competitor_hull_is_exact_for_one_shared_coefficient():
    """Against dense 1-D sampling: contains it, and matches it where the search finished."""
    nontrivial = 0
    for _, scene, m in _competitors(12, 12):
        lo, hi = 0.5 * scene.mu.mean(), 1.5 * scene.mu.mean()
        c = competitor_torques(scene, m, lo, hi, -5.0, 5.0, shared=True)
        l, u, ok = effort_bands(scene, m, np.repeat(np.linspace(lo, hi, 20001)[:, None], scene.n_contacts, axis=1))
        ok &= np.maximum(l, -5.0) <= np.minimum(u, 5.0)
        if not ok.any():
            assert c.empty or not c.exact or c.upper - c.lower < 1e-3
            continue
        nontrivial += 1
        sl, su = np.maximum(l[ok], -5.0).min(), np.minimum(u[ok], 5.0).max()
        assert c.lower <= sl + 1e-9 and c.upper >= su - 1e-9
        if c.exact:
            assert c.lower == pytest.approx(sl, abs=1e-3) and c.upper == pytest.approx(su, abs=1e-3)
    assert nontrivial >= 10


def test_competitor_inputs_are_checked():
    scene, _ = planted_scene(np.random.default_rng(0), 3, 1)
    m = next(iter(enumerate_modes(3, 4)))
    with pytest.raises(SceneError, match="mu range"):
        competitor_torques(scene, m, 0.3, 0.1, 0.0, 1.0)
    with pytest.raises(SceneError, match="mu range"):
        competitor_torques(scene, m, -0.1, 0.1, 0.0, 1.0, shared=True)
    with pytest.raises(SceneError, match="effort interval"):
        competitor_torques(scene, m, 0.1, 0.2, 1.0, 0.0)
    with pytest.raises(ModeError):
        competitor_torques(scene, "RR", 0.1, 0.2, 0.0, 1.0)


# --- the segment's bands --------------------------------------------------------------------------


def test_figure_10_frictionless(box):
    f = box.frictionless
    assert f.feasible.all() and f.exact.all()
    assert np.all(f.lower == 0.0) and not np.any(np.signbit(f.lower))  # identically zero, as in the paper
    spans = f.infinite_upper_spans()
    assert len(spans) == 1 and spans[0][0] == 0.0 and 3.5 < spans[0][1] < 4.5  # infinite, then finite
    assert np.all(np.diff(f.upper[np.isfinite(f.upper)]) < 0)
    assert f.upper[-1] == pytest.approx(0.66166, rel=1e-4)


def test_figure_11_and_12_at_mu_high(box):
    hi = box.at_high_mu
    assert hi.feasible.all() and np.all(np.diff(hi.lower) > 0) and hi.lower[0] == pytest.approx(0.05411, rel=1e-3)
    assert hi.infinite_upper_spans()[0][0] == 0.0
    comps = box.competitors_at_high_mu
    assert set(comps) == {"RBSS", "SBRS", "BSRS", "BSSR"}
    r2s = comps["BSRS"]
    assert r2s.feasible.any() and not r2s.feasible[0] and r2s.feasible[-1]
    # the R2S band begins exactly where the 4S band ends: the regions touch, they do not overlap
    both = r2s.feasible & hi.feasible
    assert np.allclose(r2s.lower[both], hi.upper[both], rtol=1e-9)
    assert np.all(np.isposinf(r2s.upper[r2s.feasible]))
    assert not any(comps[c].feasible.any() for c in ("RBSS", "SBRS", "BSSR"))


def test_figure_13_guaranteed_band_is_inside_every_point_band(box, shared, samples):
    for sb in (box, shared):
        g = sb.guaranteed.band
        assert g.feasible.all() and g.exact.all() and not sb.guaranteed.split.any()
        for mu in (0.0, 0.05, 0.2):
            p = point_band_sweep(samples, mu)
            assert np.all(g.lower >= p.lower - 1e-9) and np.all(g.upper <= p.upper + 1e-9)
    # independent coefficients ask more than one shared coefficient
    assert np.all(box.guaranteed.band.lower >= shared.guaranteed.band.lower - 1e-9)
    assert np.all(box.guaranteed.band.upper <= shared.guaranteed.band.upper + 1e-9)
    k, w = narrowest(box.guaranteed.band)
    assert k == N - 1 and w == pytest.approx(0.25934, rel=1e-4)
    k, w = narrowest(shared.guaranteed.band)
    assert k == N - 1 and w == pytest.approx(0.54144, rel=1e-4)


def test_sampled_method_is_never_narrower_than_exact(shared, samples):
    """The paper's sampling checks fewer frictions: its band contains the exact one, and converges to it."""
    exact = shared.guaranteed.band
    for n in (3, 21, 201):
        s = sampled_guaranteed_sweep(samples, np.linspace(0.0, 0.2, n))
        assert np.all(s.lower <= exact.lower + 1e-12) and np.all(s.upper >= exact.upper - 1e-9)
    assert np.allclose(s.lower, exact.lower, rtol=1e-9)
    finite = np.isfinite(exact.upper)
    assert np.allclose(s.upper[finite], exact.upper[finite], rtol=1e-4)


def test_guaranteed_torques_give_only_the_desired_mode(box, samples):
    """The full solver at random friction in the box and random torques in the guaranteed band: 4S alone."""
    rng = np.random.default_rng(4)
    g = box.guaranteed.band
    for k in range(0, N, 2):
        for _ in range(3):
            tau = rng.uniform(g.lower[k], g.upper[k])
            scene = samples.scenes[k].with_mu(rng.uniform(0.0, 0.2, size=4))
            assert solve(scene.with_inputs(joint_effort=[np.nan, tau])).feasible_modes == ["SSSS"]


def test_command_inside_the_band(box, shared):
    for sb in (box, shared):
        g = sb.guaranteed.band
        assert np.all(sb.command >= g.lower) and np.all(sb.command <= g.upper)
        dist = np.minimum(sb.command - g.lower, g.upper - sb.command)
        assert np.allclose(sb.margin, dist)
    assert box.safety_margin == pytest.approx(0.5 * narrowest(box.guaranteed.band)[1])


def test_competing_modes_and_bad_inputs(samples):
    assert competing_modes(samples) == ("RBSS", "SBRS", "BSRS", "BSSR")
    with pytest.raises(QsplanError, match="mu range"):
        guaranteed_sweep(samples, (0.2, 0.1))
    with pytest.raises(QsplanError, match="mu"):
        point_band_sweep(samples, -0.1)
    with pytest.raises(QsplanError, match="mu samples"):
        sampled_guaranteed_sweep(samples, np.zeros((3, 2)))
    with pytest.raises(QsplanError, match="paper samples"):
        segment_bands(samples, paper_samples=0)


@pytest.mark.parametrize(
    "lower, upper, command, margin",
    [
        (1.0, 3.0, 2.0, 1.0),
        (1.0, np.inf, 1.25, 0.25),
        (-np.inf, 3.0, 2.75, 0.25),
        (-np.inf, np.inf, 0.0, np.inf),
        (np.nan, np.nan, np.nan, np.nan),
    ],
)
def test_choose_command_rules(lower, upper, command, margin):
    c, m = choose_command([lower], [upper], 0.25)
    assert np.allclose(c, command, equal_nan=True) and np.allclose(m, margin, equal_nan=True)


def test_choose_command_caps_the_margin():
    c, m = choose_command([0.0, 0.0], [100.0, 1.0], 0.25, max_margin=0.5)
    assert np.allclose(c, [0.5, 0.5]) and np.allclose(m, [0.5, 0.5])
    with pytest.raises(QsplanError, match="safety margin"):
        choose_command([0.0], [1.0], 0.0)
    with pytest.raises(QsplanError, match="max margin"):
        choose_command([0.0], [1.0], 0.25, max_margin=0.1)


@pytest.mark.parametrize(
    "c_lo, c_hi, expected",
    [
        (np.nan, np.nan, (0.0, 10.0, False)),  # precluded everywhere
        (10.0, 12.0, (0.0, 10.0, False)),  # touches the upper edge only
        (-3.0, 0.0, (0.0, 10.0, False)),  # touches the lower edge only
        (7.0, 12.0, (0.0, 7.0, False)),  # cuts the top
        (-1.0, 2.0, (2.0, 10.0, False)),  # cuts the bottom
        (3.0, 4.0, (4.0, 10.0, True)),  # splits: the larger piece is kept
        (-1.0, 11.0, (np.nan, np.nan, False)),  # covers everything
    ],
)
def test_subtracting_a_competitor(c_lo, c_hi, expected):
    a, b, split = subtract_hull(0.0, 10.0, c_lo, c_hi, 1e-9)
    assert np.allclose([a, b], expected[:2], equal_nan=True) and split == expected[2]
