"""Force margins in the effort bands (eq. 28 made strict) against the all-modes solver.

The independent check: at sampled efforts and friction, :func:`qsplan.mechanics.solve` (every
mode, its own equilibrium solve) gives the desired mode's forces ``c_n, c_t``; the margins are
read off them here (``c_n`` of loaded contacts, ``mu c_n -+ c_t`` of rolling ones), not from the
band code's rows.
"""

from itertools import product

import numpy as np
import pytest

from qsplan.mechanics import QsplanError, planted_scene, solve
from qsplan.mechanics.bands.effort import ForceMargin, check_force_margin, effort_band, effort_bands, row_margins
from qsplan.mechanics.bands.guaranteed import guaranteed_band_box, guaranteed_band_shared, sampled_band
from qsplan.mechanics.modes.contact_mode import ContactMode

EDGE_RTOL = 1e-6  # efforts this close (relative to the band's scale) to an edge are not judged inside/outside
FORCE_RTOL = 1e-7  # forces compared relative to the scene's force scale


def _scenes(n, seed, n_contacts=(2, 6)):
    rng = np.random.default_rng(seed)
    for _ in range(n):
        yield (rng,) + planted_scene(rng, int(rng.integers(*n_contacts)), 1)


def _margin_for(scene, mode, rng):
    """A margin of 5-30 % of the planted solution's smallest loaded normal force (N)."""
    sol = solve(scene, residuals=False, workers=1, search="all").solution(mode.letters)
    loaded = [c for c, l in enumerate(mode.letters) if l != "B"]
    cn = float(np.min(sol.c_n[loaded]))
    return ForceMargin(rng.uniform(0.05, 0.3) * cn, rng.uniform(0.0, 0.2) * cn), max(1.0, float(np.max(np.abs(sol.c_n))))


def _tightest(scene, mode, tau, mu, fm):
    """min over rows of (row - its margin) from the solver's forces, or -inf when the mode is not feasible."""
    s = scene.with_inputs(joint_effort=np.where(scene.effort_controlled, tau, np.nan)).with_mu(mu)
    sol = solve(s, residuals=False, workers=1, search="all").solution(mode.letters)
    if sol is None:
        return -np.inf
    rows = []
    for c, letter in enumerate(mode.letters):
        if letter == "B":
            continue
        rows.append(sol.c_n[c] - fm.normal)
        if letter == "R":
            rows += [mu[c] * sol.c_n[c] + sol.c_t[c] - fm.slack, mu[c] * sol.c_n[c] - sol.c_t[c] - fm.slack]
    return min(rows)


def _vertices(mode, lo, hi):
    free = [c for c in range(len(mode.letters)) if mode.letters[c] != "B" and hi[c] > lo[c]]
    verts = np.tile(lo, (2 ** len(free), 1))
    for k, bits in enumerate(product((0, 1), repeat=len(free))):
        for c, b in zip(free, bits):
            verts[k, c] = hi[c] if b else lo[c]
    return verts


def _efforts(band, tau0, rng):
    lo = band.lower if np.isfinite(band.lower) else tau0 - 20
    hi = band.upper if np.isfinite(band.upper) else tau0 + 20
    span = max(1.0, hi - lo)
    return np.concatenate([np.linspace(lo - 0.3 * span, hi + 0.3 * span, 9), rng.uniform(lo, hi, 3)]), span


def test_zero_margin_reproduces_every_band_bit_for_bit():
    zero = ForceMargin()
    for rng, scene, mode in _scenes(25, 11):
        lo, hi = scene.mu * 0.8, scene.mu * 1.2
        m = float(scene.mu.mean())
        pairs = [
            (effort_band(scene, mode), effort_band(scene, mode, force_margin=zero)),
            (guaranteed_band_box(scene, mode, lo, hi), guaranteed_band_box(scene, mode, lo, hi, force_margin=zero)),
            (guaranteed_band_shared(scene, mode, 0.7 * m, 1.3 * m),
             guaranteed_band_shared(scene, mode, 0.7 * m, 1.3 * m, force_margin=(0.0, 0.0))),
            (sampled_band(scene, mode, np.linspace(lo, hi, 7)), sampled_band(scene, mode, np.linspace(lo, hi, 7), force_margin=zero)),
        ]  # fmt: skip
        for a, b in pairs:
            assert a == b  # dataclass equality: every field, edges bit for bit (NaN edges compare by identity of reason)


def test_margin_rows_follow_band_rows_order():
    fm = ForceMargin(0.5, 0.25)
    assert row_margins(ContactMode("RSB"), fm).tolist() == [0.25, 0.25, 0.5, 0.5]
    assert row_margins(ContactMode("BSR"), fm).tolist() == [0.5, 0.25, 0.25, 0.5]
    assert row_margins(ContactMode("BB"), fm).size == 0


def test_point_band_with_margin_matches_the_solver():
    judged = 0
    for rng, scene, mode in _scenes(15, 12):
        fm, fscale = _margin_for(scene, mode, rng)
        band = effort_band(scene, mode, force_margin=fm)
        plain = effort_band(scene, mode)
        if not band.feasible:
            continue
        assert plain.lower <= band.lower and band.upper <= plain.upper  # a margin only narrows
        tau0 = scene.joint_effort[scene.effort_controlled][0]
        taus, span = _efforts(band, tau0, rng)
        for tau in taus:
            if min(abs(tau - band.lower), abs(tau - band.upper)) < EDGE_RTOL * span:
                continue
            t = _tightest(scene, mode, tau, scene.mu, fm)
            assert (t >= -FORCE_RTOL * fscale) == band.contains(tau), (tau, t, band)
            judged += 1
        for edge in (band.lower, band.upper):  # at a finite edge the tightest row sits on its margin
            if np.isfinite(edge):
                assert _tightest(scene, mode, edge, scene.mu, fm) == pytest.approx(0.0, abs=1e-6 * fscale)
    assert judged > 60


def test_box_band_with_margin_is_exact_against_the_solver():
    checked = 0
    for rng, scene, mode in _scenes(30, 13, (2, 5)):
        lo, hi = scene.mu * 0.8, scene.mu * 1.2
        fm, fscale = _margin_for(scene, mode, rng)
        g = guaranteed_band_box(scene, mode, lo, hi, force_margin=fm)
        if not g.feasible:
            continue
        g0 = guaranteed_band_box(scene, mode, lo, hi)
        assert g0.lower <= g.lower and g.upper <= g0.upper
        verts = _vertices(mode, lo, hi)
        mus = np.vstack([verts, rng.uniform(lo, hi, size=(4, scene.n_contacts))])
        tau0 = scene.joint_effort[scene.effort_controlled][0]
        taus, span = _efforts(g, tau0, rng)
        for tau in taus:
            if min(abs(tau - g.lower), abs(tau - g.upper)) < EDGE_RTOL * span:
                continue
            worst = min(_tightest(scene, mode, tau, mu, fm) for mu in mus)
            # inside: every friction keeps the margins; outside: some friction (a vertex) breaks one
            assert (worst >= -FORCE_RTOL * fscale) == g.contains(tau), (tau, worst, g)
        for edge in (g.lower, g.upper):
            if np.isfinite(edge):
                worst = min(_tightest(scene, mode, edge, mu, fm) for mu in verts)
                assert worst == pytest.approx(0.0, abs=1e-6 * fscale)
        checked += 1
    assert checked >= 10


@pytest.mark.slow
def test_shared_band_with_margin_matches_dense_sampling_and_the_solver():
    checked = 0
    for rng, scene, mode in _scenes(30, 14):
        m = float(scene.mu.mean())
        lo, hi = 0.7 * m, 1.3 * m
        fm, fscale = _margin_for(scene, mode, rng)
        g = guaranteed_band_shared(scene, mode, lo, hi, force_margin=fm)
        dense = sampled_band(scene, mode, np.linspace(lo, hi, 2001), force_margin=fm)
        if not g.feasible:
            assert not dense.feasible or "singular" in (g.reason or "")
            continue
        assert dense.feasible
        assert g.lower >= dense.lower - 1e-9 and g.upper <= dense.upper + 1e-9  # sampling only misses the worst mu
        span = 1.0 if not np.isfinite(g.upper - g.lower) else max(1.0, g.upper - g.lower)
        assert g.lower == pytest.approx(dense.lower, abs=1e-4 * span) or np.isinf(g.lower)
        assert g.upper == pytest.approx(dense.upper, abs=1e-4 * span) or np.isinf(g.upper)
        grid = np.linspace(lo, hi, 41)
        fine = np.linspace(lo, hi, 2001)
        l, u, _ = effort_bands(scene, mode, np.repeat(fine[:, None], scene.n_contacts, axis=1), force_margin=fm)
        for edge, inward, k in ((g.lower, 1.0, np.nanargmax(l)), (g.upper, -1.0, np.nanargmin(u))):
            if not np.isfinite(edge):
                continue
            worst = min(_tightest(scene, mode, edge + inward * 1e-6 * span, np.full(scene.n_contacts, mu), fm) for mu in grid)
            assert worst >= -FORCE_RTOL * fscale  # just inside: the margins hold at every sampled shared mu
            # just outside: a shared mu breaks a margin (the solver at the grid and the sampled worst mu)
            worst = min(_tightest(scene, mode, edge - inward * 1e-3 * span, np.full(scene.n_contacts, mu), fm)
                        for mu in np.append(grid, fine[k]))  # fmt: skip
            assert worst < 0
        checked += 1
    assert checked >= 10


def test_effort_bands_take_the_margin_per_friction_row():
    rng, scene, mode = next(_scenes(1, 15))
    fm, _ = _margin_for(scene, mode, rng)
    mus = rng.uniform(scene.mu * 0.8, scene.mu * 1.2, size=(6, scene.n_contacts))
    l, u, ok = effort_bands(scene, mode, mus, force_margin=fm)
    for k in range(6):
        b = effort_band(scene, mode, mus[k], force_margin=fm)
        assert ok[k] == b.feasible
        if ok[k]:
            assert (l[k], u[k]) == (b.lower, b.upper)


def test_a_slack_margin_empties_rolling_bands_that_reach_zero_friction():
    for rng, scene, mode in _scenes(40, 16):
        if "R" not in mode.letters:
            continue
        lo, hi = np.zeros(scene.n_contacts), scene.mu
        assert not guaranteed_band_box(scene, mode, lo, hi, force_margin=ForceMargin(0.0, 1e-3)).feasible
        return
    pytest.skip("no rolling mode among the planted scenes")


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"normal": -0.1}, r"force_margin\.normal: expected a nonnegative finite force \(N\); got -0\.1"),
        ({"slack": float("nan")}, r"force_margin\.slack: expected a nonnegative finite force"),
        ({"normal": float("inf")}, r"force_margin\.normal"),
        ({"slack": "0.1"}, r"force_margin\.slack: .* got '0\.1'"),
        ({"normal": True}, r"force_margin\.normal: .* got True"),
    ],
)
def test_bad_force_margin(kwargs, match):
    with pytest.raises(QsplanError, match=match):
        ForceMargin(**kwargs)


def test_check_force_margin():
    assert check_force_margin(None) == ForceMargin() and check_force_margin(None).is_zero
    assert check_force_margin((0.1, 0.2)) == ForceMargin(0.1, 0.2)
    assert ForceMargin(0.05, 0).to_dict() == {"min_normal_force_N": 0.05, "min_coulomb_slack_N": 0.0}
    with pytest.raises(QsplanError, match="force_margin: expected a ForceMargin or"):
        check_force_margin(0.1)
    scene, mode = planted_scene(np.random.default_rng(0), 3, 1)
    with pytest.raises(QsplanError, match=r"force_margin\.normal"):
        guaranteed_band_box(scene, mode, 0.1, 0.2, force_margin=(-1.0, 0.0))
