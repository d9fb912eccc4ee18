"""Effort bands (eq. 28) against brute force over efforts and friction."""

import numpy as np
import pytest

from qsplan.mechanics import SceneError, check_mode, planted_scene
from qsplan.mechanics.bands.effort import effort_band, effort_bands
from qsplan.mechanics.bands.guaranteed import guaranteed_band_box, guaranteed_band_shared, possible_band_box, sampled_band

EDGE = 1e-6  # efforts this close to a band edge are not judged (the edge itself is feasible, eq. 28's >=)


def _scenes(n, seed):
    rng = np.random.default_rng(seed)
    for _ in range(n):
        yield (rng,) + planted_scene(rng, int(rng.integers(2, 6)), 1)


def _feasible_at(scene, mode, tau, mu=None):
    s = scene.with_inputs(joint_effort=np.where(scene.effort_controlled, tau, np.nan))
    if mu is not None:
        s = s.with_mu(mu)
    return check_mode(s, mode).feasible


def test_point_band_matches_brute_force_over_efforts():
    judged = 0
    for rng, scene, mode in _scenes(40, 1):
        band = effort_band(scene, mode)
        assert band.feasible  # the planted effort works
        tau0 = scene.joint_effort[scene.effort_controlled][0]
        assert band.contains(tau0)
        lo = band.lower if np.isfinite(band.lower) else tau0 - 50
        hi = band.upper if np.isfinite(band.upper) else tau0 + 50
        for tau in np.concatenate([np.linspace(lo - 5, hi + 5, 41), rng.uniform(lo - 1, hi + 1, 10)]):
            if min(abs(tau - band.lower), abs(tau - band.upper)) < EDGE:
                continue
            assert _feasible_at(scene, mode, tau) == band.contains(tau)
            judged += 1
    assert judged > 1000


def test_unbounded_sides_are_inf_not_large_numbers():
    seen = False
    for _, scene, mode in _scenes(80, 2):
        b = effort_band(scene, mode)
        for edge in (b.lower, b.upper):
            assert np.isinf(edge) or abs(edge) < 1e6
        seen |= np.isinf(b.lower) or np.isinf(b.upper)
        d = b.to_dict()
        assert (d["lower"] is None) == np.isinf(b.lower) and (d["upper"] is None) == np.isinf(b.upper)
    assert seen


def test_box_band_equals_intersection_over_dense_samples_and_is_never_wider():
    checked = 0
    for rng, scene, mode in _scenes(40, 3):
        lo, hi = scene.mu * 0.8, scene.mu * 1.2
        g = guaranteed_band_box(scene, mode, lo, hi)
        samples = rng.uniform(lo, hi, size=(4000, scene.n_contacts))
        l, u, ok = effort_bands(scene, mode, samples)
        if not g.feasible:
            if "changes sign" in (g.reason or ""):
                continue
            # no guarantee: the sampled intersection may still be nonempty, but never wider than a real one
            continue
        assert ok.all()
        # never wider than the sampled intersection (a sampled set is a subset of the box)
        assert g.lower >= l.max() - 1e-9 and g.upper <= u.min() + 1e-9
        # and equal to it once the vertices are among the samples (vertex theory)
        from itertools import product

        free = [c for c in range(scene.n_contacts) if mode.letters[c] != "B"]
        verts = np.tile(lo, (2 ** len(free), 1))
        for k, bits in enumerate(product((0, 1), repeat=len(free))):
            for c, b in zip(free, bits):
                verts[k, c] = hi[c] if b else lo[c]
        l2, u2, ok2 = effort_bands(scene, mode, np.vstack([samples, verts]))
        assert g.lower == pytest.approx(l2.max(), abs=1e-9) and g.upper == pytest.approx(u2.min(), abs=1e-9)
        # every effort inside the guaranteed band is feasible at every sample (brute force on a few)
        for tau in np.linspace(max(g.lower, -1e3), min(g.upper, 1e3), 5)[1:-1]:
            for mu in samples[:20]:
                assert _feasible_at(scene, mode, tau, mu)
        checked += 1
    assert checked >= 15


def test_shared_band_matches_dense_1d_sampling():
    checked = 0
    for rng, scene, mode in _scenes(40, 4):
        m = float(scene.mu.mean())
        lo, hi = 0.7 * m, 1.3 * m
        g = guaranteed_band_shared(scene, mode, lo, hi)
        dense = sampled_band(scene, mode, np.linspace(lo, hi, 4001))
        if not g.feasible:
            assert not dense.feasible or "singular" in (g.reason or "")
            continue
        assert dense.feasible
        # exact extremes lie outside the sampled ones (sampling can only miss the worst mu)
        assert g.lower >= dense.lower - 1e-9 and g.upper <= dense.upper + 1e-9
        span = 1.0 if not np.isfinite(g.upper - g.lower) else max(1.0, g.upper - g.lower)
        assert g.lower == pytest.approx(dense.lower, abs=1e-4 * span) or np.isinf(g.lower)
        assert g.upper == pytest.approx(dense.upper, abs=1e-4 * span) or np.isinf(g.upper)
        checked += 1
    assert checked >= 15


def test_possible_band_contains_every_feasible_effort():
    for rng, scene, mode in _scenes(25, 5):
        lo, hi = scene.mu * 0.5, scene.mu * 1.5
        p = possible_band_box(scene, mode, lo, hi)
        samples = rng.uniform(lo, hi, size=(500, scene.n_contacts))
        l, u, ok = effort_bands(scene, mode, samples)
        if not p.feasible:
            assert not ok.any()
            continue
        assert np.all(l[ok] >= p.lower - 1e-9) and np.all(u[ok] <= p.upper + 1e-9)


def test_band_needs_exactly_one_effort_joint():
    scene, mode = planted_scene(np.random.default_rng(0), 4, 2)
    with pytest.raises(SceneError, match="exactly one effort-controlled joint"):
        effort_band(scene, mode)


def test_bad_mu_range():
    scene, mode = planted_scene(np.random.default_rng(0), 3, 1)
    with pytest.raises(SceneError, match="mu range"):
        guaranteed_band_box(scene, mode, 0.5, 0.2)
    with pytest.raises(SceneError, match="mu range"):
        guaranteed_band_shared(scene, mode, -0.1, 0.2)
