"""Bands batched over states against the per-state reference (issue 13, point 2).

Every batched function of :mod:`qsplan.mechanics.bands.batched` and
:mod:`qsplan.mechanics.bands.batched_robust` is compared with the per-state function it
batches, on the demo hand's segment-1 samples (box and shared friction, with and without a
force margin) and on seeded random raw scenes (as in ``test_band_safety.py``), batched together
by shape: every flag and reason equal, every number equal to 1e-12 relative (the batched path
does the same floating-point operations, so in practice they are bit-identical, which
``tests/planner/test_api.py`` relies on).  The cases are checked to include unbounded and empty
bands, failed kinematics and competitor searches the root cell does not resolve.
"""

import numpy as np
import pytest

from qsplan.hands import default_hand, first_segment, sample_segment
from qsplan.mechanics import enumerate_modes, planted_scene
from qsplan.mechanics.bands.batched import (
    batch_kinematics,
    effort_bands_batch,
    guaranteed_bands_box,
    guaranteed_bands_shared,
    point_bands_batch,
    state_batch,
)
from qsplan.mechanics.bands.batched_robust import RootStats, admissible_competitors_batch, competitor_torques_batch, robust_bands
from qsplan.mechanics.bands.effort import ForceMargin, effort_band, effort_bands
from qsplan.mechanics.bands.guaranteed import guaranteed_band_box, guaranteed_band_shared
from qsplan.mechanics.bands.preclusion import competitor_torques
from qsplan.mechanics.bands.robust import admissible_competitors, robust_band
from qsplan.mechanics.errors import SceneError
from qsplan.mechanics.modes.contact_mode import ContactMode
from qsplan.mechanics.modes.kinematics import single_mode_kinematics

RTOL = 1e-12
SEED = 12
N_RANDOM = 96
MU_SEG = (0.0, 0.2)
MU_RAND = (0.1, 0.4)
MARGIN = ForceMargin(0.05, 0.02)


def same(a, b) -> bool:
    """Equal flags and strings, numbers equal to RTOL relative (NaN = NaN, inf = inf)."""
    if isinstance(a, (float, np.floating)) or isinstance(b, (float, np.floating)):
        a, b = float(a), float(b)
        if np.isnan(a) or np.isnan(b) or np.isinf(a) or np.isinf(b):
            return (np.isnan(a) and np.isnan(b)) or a == b
        return abs(a - b) <= RTOL * max(abs(a), abs(b))
    if isinstance(a, np.ndarray):
        return a.shape == b.shape and all(same(x, y) for x, y in zip(a.ravel().tolist(), b.ravel().tolist()))
    if isinstance(a, (tuple, list)):
        return len(a) == len(b) and all(same(x, y) for x, y in zip(a, b))
    if isinstance(a, dict):
        return a.keys() == b.keys() and all(same(a[k], b[k]) for k in a)
    return a == b


def band_key(b):
    return (b.mode, b.joint, b.lower, b.upper, b.feasible, b.reason, b.method, b.exact)


def torque_key(t):
    return (t.mode, t.lower, t.upper, t.empty, t.exact, t.reason, t.cells)


def robust_key(r):
    return (r.mode, r.lower, r.upper, r.feasible, r.exact, r.split, r.reason, r.competitors, r.mu_range, r.shared,
            band_key(r.desired), {c: torque_key(t) for c, t in r.precluded.items()})  # fmt: skip


@pytest.fixture(scope="module")
def segment():
    samples = sample_segment(first_segment(default_hand()), 100)
    return samples.scenes, samples.segment.mode


@pytest.fixture(scope="module")
def random_scenes():
    """``(scene, planted letters, shared)`` for seeded raw scenes of 4-6 contacts and 2-3 joints."""
    out = []
    for k in range(N_RANDOM):
        rng = np.random.default_rng([SEED, k])
        n_c = int(rng.integers(4, 7))
        scene, planted = planted_scene(rng, n_c, 1, n_joints=int(rng.integers(2, 4)))
        out.append((scene, planted.letters, bool(k % 2)))
    return out


def by_shape(cases):
    groups = {}
    for scene, letters, shared in cases:
        groups.setdefault((scene.n_contacts, scene.effort_controlled.tobytes()), []).append((scene, letters, shared))
    return list(groups.values())


@pytest.mark.parametrize("shared", [False, True])
@pytest.mark.parametrize("margin", [None, MARGIN])
def test_robust_bands_of_the_segment_are_the_per_state_ones(segment, shared, margin):
    scenes, mode = segment
    stats = RootStats()
    got = robust_bands(scenes, mode, MU_SEG, shared=shared, force_margin=margin, stats=stats)
    ref = [robust_band(s, mode, MU_SEG, shared=shared, force_margin=margin) for s in scenes]
    for k, (g, r) in enumerate(zip(got, ref)):
        assert same(robust_key(g), robust_key(r)), k
    assert stats.root > 0
    if shared and margin is None:  # the shared band reaches mu-independent infinity on part of the segment
        assert any(np.isposinf(r.upper) for r in ref)


@pytest.mark.slow
def test_robust_bands_of_random_scenes_batched_by_shape_are_the_per_state_ones(random_scenes):
    """Per group of one shape: the planted mode of its first scene, and the modes whose guaranteed band is
    unbounded at some scene (the hard cases for preclusion); competitors found per state (default) or given."""
    stats = RootStats()
    n_unbounded = n_empty = n_kin = 0
    for g, group in enumerate(by_shape(random_scenes)):
        scenes = [s for s, _, _ in group]
        batch = state_batch(scenes)
        unbounded = [m.letters for m in enumerate_modes(batch.n_c, scenes[0].dof)
                     if any(b.feasible and not np.isfinite(b.width) for b in guaranteed_bands_box(batch, m, *MU_RAND))]  # fmt: skip
        for mode in [group[0][1]] + unbounded[:2]:
            for shared, margin, comps in ((False, None, None), (True, None, None), (g % 2 == 0, MARGIN, "union")):
                if comps == "union":
                    comps = admissible_competitors(scenes, mode)
                got = robust_bands(scenes, mode, MU_RAND, shared=shared, competitors=comps, force_margin=margin, stats=stats)
                for k, r in enumerate(got):
                    ref = robust_band(scenes[k], mode, MU_RAND, shared=shared, competitors=comps, force_margin=margin)
                    assert same(robust_key(r), robust_key(ref)), (mode, k, shared, margin)
                    n_unbounded += bool(ref.feasible and not np.isfinite(ref.width))
                    n_empty += bool(ref.desired.feasible and not ref.feasible)
                    n_kin += (ref.reason or "").startswith("kinematics")
    assert n_unbounded > 0 and n_empty > 0 and n_kin > 0
    assert stats.fallback > 0 and stats.root > stats.fallback


def test_guaranteed_and_point_bands_are_the_per_state_ones(segment, random_scenes):
    scenes, mode = segment
    groups = [[(s, mode) for s in scenes]] + [[(s, letters) for s, letters, _ in g] for g in by_shape(random_scenes)]
    n_infeasible = 0
    for group in groups:
        batch = state_batch([s for s, _ in group])
        for letters in sorted({ContactMode(m) for _, m in group}, key=lambda m: m.letters)[:4]:
            lo, hi = MU_SEG if group[0][0] is scenes[0] else MU_RAND
            for margin in (None, MARGIN):
                box = guaranteed_bands_box(batch, letters, lo, hi, force_margin=margin)
                sh = guaranteed_bands_shared(batch, letters, lo, hi, force_margin=margin)
                pt = point_bands_batch(batch, letters, np.full(batch.n_c, hi), force_margin=margin)
                point = guaranteed_bands_shared(batch, letters, hi, hi, force_margin=margin)  # a point range
                for k, (s, _) in enumerate(group):
                    assert same(band_key(box[k]), band_key(guaranteed_band_box(s, letters, lo, hi, force_margin=margin)))
                    assert same(band_key(sh[k]), band_key(guaranteed_band_shared(s, letters, lo, hi, force_margin=margin)))
                    assert same(band_key(pt[k]), band_key(effort_band(s, letters, np.full(batch.n_c, hi), force_margin=margin)))
                    assert same(band_key(point[k]), band_key(guaranteed_band_shared(s, letters, hi, hi, force_margin=margin)))
                    n_infeasible += not box[k].feasible
    assert n_infeasible > 0


def test_effort_bands_and_kinematics_of_every_mode_are_the_per_state_ones(random_scenes):
    rng = np.random.default_rng(SEED)
    for group in by_shape(random_scenes)[:4]:
        scenes = [s for s, _, _ in group]
        batch = state_batch(scenes)
        mus = rng.uniform(0.0, 0.5, size=(7, batch.n_c))
        per_state, union = admissible_competitors_batch(batch, group[0][1])
        assert union == admissible_competitors(scenes, group[0][1])
        for k, s in enumerate(scenes):
            assert per_state[k] == admissible_competitors([s], group[0][1])
        for m in enumerate_modes(batch.n_c, scenes[0].dof):
            bk = batch_kinematics(batch, m)
            lower, upper, ok = effort_bands_batch(batch, m, mus)
            for k, s in enumerate(scenes):
                _, status, _, kin = single_mode_kinematics(s, m)
                assert bk.status_name(k) == status
                if kin is not None:
                    np.testing.assert_array_equal(bk.xi[k], kin.xi[0])
                ref = effort_bands(s, m, mus)
                assert same((lower[k], upper[k], ok[k]), ref)


def test_competitor_torques_with_per_state_intervals_are_the_per_state_ones(segment):
    """Unbounded, bounded, point and empty effort intervals, box and shared friction."""
    scenes, _ = segment
    batch = state_batch(scenes)
    rng = np.random.default_rng(SEED)
    g_lo = np.where(rng.uniform(size=batch.size) < 0.3, -np.inf, rng.uniform(-1.0, 0.5, batch.size))
    g_hi = np.where(rng.uniform(size=batch.size) < 0.3, np.inf, g_lo + rng.uniform(0.0, 1.0, batch.size))
    g_hi[::17] = g_lo[::17] = np.where(np.isfinite(g_lo[::17]), g_lo[::17], 0.0)  # point intervals
    for shared, lo, hi in ((False, 0.0, 0.2), (True, 0.0, 0.2), (True, 0.1, 0.1)):
        for c in ("RBSS", "SBRS", "BSRS", "BSSR", "BBRR"):
            got = competitor_torques_batch(batch, c, lo, hi, g_lo, g_hi, shared)
            for k, s in enumerate(scenes):
                ref = competitor_torques(s, c, lo, hi, float(g_lo[k]), float(g_hi[k]), shared)
                assert same(torque_key(got[k]), torque_key(ref)), (c, k, shared)


def test_batches_check_their_states(segment, random_scenes):
    scenes, _ = segment
    with pytest.raises(SceneError, match="expected at least one scene"):
        state_batch([])
    other = next(s for s, _, _ in random_scenes if s.n_contacts != scenes[0].n_contacts)
    with pytest.raises(SceneError, match="scene 1 has .* contacts"):
        state_batch([scenes[0], other])
    with pytest.raises(SceneError, match="effort interval"):
        competitor_torques_batch(state_batch(scenes[:2]), "RBSS", 0.0, 0.2, [1.0, 0.0], [0.0, 1.0])
