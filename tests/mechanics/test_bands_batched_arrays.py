"""The band tables' batched path against the per-state references it replaces (issue 13, the tables' speed).

* :func:`~qsplan.mechanics.bands.batched_robust.robust_band_arrays` (no object per state) against
  :func:`~qsplan.mechanics.bands.batched_robust.robust_bands` and the per-state
  :func:`~qsplan.mechanics.bands.robust.robust_band`, on the demo hand's segment and seeded random scenes
  (unbounded, empty, inexact and split bands, competitor searches the root cell leaves open);
* :func:`~qsplan.mechanics.bands.batched_robust.assemble_band_arrays` against
  :func:`~qsplan.mechanics.bands.robust.assemble_robust_band` on seeded synthetic hulls (edges touching within the
  tolerance, hulls inside, over and beyond the band, unbounded sides, undecided competitors);
* :func:`~qsplan.mechanics.bands.batched_modes.batch_rows_many` (every job in one factorisation, matrices shared by
  friction points equal at the sliding contacts) against :func:`~qsplan.mechanics.bands.effort.band_rows` state
  by state, and :func:`~qsplan.mechanics.bands.batched_modes.modes_kinematics` against the one-mode stage;
* a batch from arrays (:func:`~qsplan.mechanics.bands.batched.batch_from_arrays`, scenes built on use) against
  :func:`~qsplan.mechanics.bands.batched.state_batch`.

Everything is compared bit for bit (NaN = NaN) against the batched object path and the one-state functions the
batched path calls; against the per-state robust band to 1e-12 relative, as ``test_bands_batched.py`` does.
"""

import numpy as np
import pytest

from qsplan.hands import default_hand, first_segment, sample_segment
from qsplan.mechanics import enumerate_modes, planted_scene
from qsplan.mechanics.bands.batched import LazyScenes, batch_from_arrays, guaranteed_bands_box, state_batch, take_states
from qsplan.mechanics.bands.batched_modes import batch_kinematics, batch_rows_many, modes_kinematics
from qsplan.mechanics.bands.batched_preclusion import HullArrays, RootStats
from qsplan.mechanics.bands.batched_robust import assemble_band_arrays, robust_band_arrays, robust_bands
from qsplan.mechanics.bands.effort import Band, ForceMargin, band_kinematics, band_rows
from qsplan.mechanics.bands.robust import TOUCH_RTOL, assemble_robust_band, robust_band
from qsplan.mechanics.modes.contact_mode import ContactMode
from qsplan.mechanics.modes.kinematics import single_mode_kinematics
from qsplan.mechanics.numerics import Status

SEED = 13
N_RANDOM = 96
MU_SEG = (0.0, 0.2)
MU_RAND = (0.1, 0.4)
MARGIN = ForceMargin(0.05, 0.02)
RTOL = 1e-12
N_SYNTHETIC = 4000


def same_bits(a, b) -> bool:
    a, b = np.asarray(a), np.asarray(b)
    if a.dtype.kind == "f" or b.dtype.kind == "f":
        a, b = np.asarray(a, float), np.asarray(b, float)
        return a.shape == b.shape and bool(np.all((a == b) | (np.isnan(a) & np.isnan(b))))
    return a.shape == b.shape and bool(np.array_equal(a, b))


def close(a: float, b: float) -> bool:
    if np.isnan(a) or np.isnan(b) or np.isinf(a) or np.isinf(b):
        return (np.isnan(a) and np.isnan(b)) or a == b
    return abs(a - b) <= RTOL * max(abs(a), abs(b))


@pytest.fixture(scope="module")
def segment():
    samples = sample_segment(first_segment(default_hand()), 80)
    return list(samples.scenes), samples.segment.mode


@pytest.fixture(scope="module")
def random_groups():
    """Seeded raw scenes of 4-6 contacts and 2-3 joints, grouped by shape: ``[(scenes, planted letters)]``."""
    groups = {}
    for k in range(N_RANDOM):
        rng = np.random.default_rng([SEED, k])
        scene, planted = planted_scene(rng, int(rng.integers(4, 7)), 1, n_joints=int(rng.integers(2, 4)))
        groups.setdefault((scene.n_contacts, scene.effort_controlled.tobytes()), []).append((scene, planted.letters))
    return [([s for s, _ in g], g[0][1]) for g in groups.values()]


def assert_arrays_are_bands(arrays, bands, refs=None):
    """``RobustArrays`` against ``RobustBand`` objects: bit for bit; against the per-state ``refs`` to RTOL."""
    for k, b in enumerate(bands):
        assert (arrays.feasible[k], arrays.exact[k], arrays.split[k]) == (b.feasible, b.exact, b.split), k
        assert same_bits(arrays.lower[k], b.lower) and same_bits(arrays.upper[k], b.upper), k
        assert arrays.desired_feasible[k] == b.desired.feasible
        if b.desired.feasible:
            assert same_bits(arrays.desired_lower[k], b.desired.lower) and same_bits(arrays.desired_upper[k], b.desired.upper)
        if refs is not None:
            r = refs[k]
            assert (r.feasible, r.exact, r.split) == (b.feasible, b.exact, b.split), k
            assert close(r.lower, arrays.lower[k]) and close(r.upper, arrays.upper[k]), k


@pytest.mark.parametrize("shared", [False, True])
@pytest.mark.parametrize("margin", [None, MARGIN])
def test_robust_band_arrays_of_the_segment(segment, shared, margin):
    scenes, mode = segment
    arrays = robust_band_arrays(state_batch(scenes), mode, MU_SEG, shared=shared, force_margin=margin)
    bands = robust_bands(scenes, mode, MU_SEG, shared=shared, force_margin=margin)
    refs = [robust_band(s, mode, MU_SEG, shared=shared, force_margin=margin) for s in scenes[::4]]
    assert_arrays_are_bands(arrays, bands)
    assert_arrays_are_bands(type(arrays)(*(getattr(arrays, f)[::4] for f in arrays.__slots__)), bands[::4], refs)


@pytest.mark.slow
def test_robust_band_arrays_of_random_scenes(random_groups):
    """The planted mode and the modes unbounded somewhere (the hard cases for preclusion), competitors per state
    or given; the cases cover unbounded, empty, inexact and split bands and per-state searches."""
    stats = RootStats()
    seen = dict(unbounded=0, empty=0, inexact=0, split=0)
    for g, (scenes, planted) in enumerate(random_groups):
        batch = state_batch(scenes)
        unbounded = [m.letters for m in enumerate_modes(batch.n_c, scenes[0].dof)
                     if any(b.feasible and not np.isfinite(b.width) for b in guaranteed_bands_box(batch, m, *MU_RAND))]  # fmt: skip
        for mode in [planted] + unbounded[:2]:
            for shared, margin, comps in ((False, None, None), (True, None, None), (g % 2 == 0, MARGIN, "all")):
                if comps == "all":
                    comps = [m.letters for m in enumerate_modes(batch.n_c, scenes[0].dof) if m.letters != mode]
                kw = dict(shared=shared, competitors=comps, force_margin=margin)
                arrays = robust_band_arrays(batch, mode, MU_RAND, stats=stats, **kw)
                bands = robust_bands(scenes, mode, MU_RAND, **kw)
                assert_arrays_are_bands(arrays, bands, [robust_band(s, mode, MU_RAND, **kw) for s in scenes])
                seen["unbounded"] += int(np.sum(arrays.feasible & ~np.isfinite(arrays.upper - arrays.lower)))
                seen["empty"] += int(np.sum(arrays.desired_feasible & ~arrays.feasible))
                seen["inexact"] += int(np.sum(~arrays.exact))
                seen["split"] += int(np.sum(arrays.split))
    assert all(seen.values()), seen
    assert stats.fallback > 0 and stats.root > stats.fallback


def _hull(rng, lo, hi):
    """A random competitor hull ``(lower, upper)`` against the band ``[lo, hi]``: inside, over an edge, touching one
    within the tolerance, beyond it, or unbounded."""
    span = (hi - lo) if np.isfinite(hi - lo) else 1.0
    base = lo if np.isfinite(lo) else (hi - 1.0 if np.isfinite(hi) else 0.0)
    a, b = np.sort(base + span * rng.uniform(-0.5, 1.5, 2))
    kind = rng.integers(6)
    if kind == 1:
        a = -np.inf
    elif kind == 2:
        b = np.inf
    elif kind == 3 and np.isfinite(lo):  # touching the lower edge within the tolerance
        a, b = lo - span, lo + rng.choice([0.5, 2.0]) * TOUCH_RTOL * max(abs(lo), 1.0)
    elif kind == 4 and np.isfinite(hi):
        a, b = hi - rng.choice([0.5, 2.0]) * TOUCH_RTOL * max(abs(hi), 1.0), hi + span
    return a, b


def test_assemble_band_arrays_is_the_per_state_assembly():
    rng = np.random.default_rng(SEED)
    ill = [Status.ORDER.index(s) for s in sorted(Status.ILL_CONDITIONED)]
    other = Status.ORDER.index("breaking_violated")
    S, comps = N_SYNTHETIC, ("RBSS", "SBRS", "BSRS", "SSRB")
    lo = np.where(rng.uniform(size=S) < 0.2, -np.inf, rng.normal(size=S))
    lo[::11] = -0.0  # negative zero edges
    hi = np.where(rng.uniform(size=S) < 0.2, np.inf, np.where(np.isfinite(lo), lo, 0.0) + rng.exponential(size=S))
    feasible = rng.uniform(size=S) < 0.9
    exact = rng.uniform(size=S) < 0.95
    hulls, admissible = [], {}
    for c in comps:
        status = np.where(rng.uniform(size=S) < 0.1, rng.choice(ill + [other], size=S), 0).astype(np.int8)
        empty = (status != 0) | (rng.uniform(size=S) < 0.3)
        bounds = np.array([_hull(rng, a, b) for a, b in zip(lo, hi)])
        h = HullArrays(c, np.where(empty, np.nan, bounds[:, 0]), np.where(empty, np.nan, bounds[:, 1]), empty,
                       rng.uniform(size=S) < 0.9, np.where(empty, 1, 2), status, {})  # fmt: skip
        hulls.append(h)
        admissible[c] = rng.uniform(size=S) < 0.8
    for per_state in (admissible, None):
        arrays = assemble_band_arrays(np.where(feasible, lo, np.nan), np.where(feasible, hi, np.nan), feasible, exact, hulls,
                                      per_state)  # fmt: skip
        counts = np.zeros(3, int)
        for s in range(S):
            desired = (Band("SSSS", 0, float(lo[s]), float(hi[s]), True, None, "box-vertices", bool(exact[s])) if feasible[s]
                       else Band("SSSS", 0, np.nan, np.nan, False, "coulomb", "box-vertices", bool(exact[s])))  # fmt: skip
            mine = comps if per_state is None else tuple(c for c in comps if per_state[c][s])
            ref = assemble_robust_band("SSSS", desired, mine, {h.mode: h.torques(s) for h in hulls} if feasible[s] else {},
                                       MU_RAND, False)  # fmt: skip
            assert (arrays.feasible[s], arrays.exact[s], arrays.split[s]) == (ref.feasible, ref.exact, ref.split), s
            assert same_bits(arrays.lower[s], ref.lower) and same_bits(arrays.upper[s], ref.upper), s
            counts += (ref.split, ref.desired.feasible and not ref.feasible, ref.feasible and not ref.exact)
        assert np.all(counts > 0), counts


def test_batch_rows_many_is_band_rows_state_by_state(segment, random_groups):
    """Every competitor of the segment's mode at its box vertices (rolling contacts share matrices), at per-state
    friction points, and the random scenes' modes, in one call; each against the per-state rows."""
    scenes, mode = segment
    batch = state_batch(scenes)
    rng = np.random.default_rng(SEED)
    jobs, refs = [], []
    for m in enumerate_modes(batch.n_c, scenes[0].dof):
        bk = batch_kinematics(batch, m)
        live = np.flatnonzero(bk.ok)
        if not live.size:
            continue
        lo, hi = np.full(batch.n_c, 0.05), np.full(batch.n_c, 0.3)
        bits = (np.arange(2**batch.n_c)[:, None] >> np.arange(batch.n_c)[None]) & 1
        verts = np.where(bits.astype(bool), hi, lo)
        per_state = rng.uniform(0.0, 0.5, size=(live.size, 5, batch.n_c))
        for mu in (verts, per_state):
            jobs.append((take_states(batch, live), bk.take(live), mu))
            refs.append([(scenes[s], m, mu if mu.ndim == 2 else mu[j]) for j, s in enumerate(live)])
    for scenes_g, letters in random_groups[:3]:
        b = state_batch(scenes_g)
        bk = batch_kinematics(b, letters)
        live = np.flatnonzero(bk.ok)
        if live.size:
            mu = rng.uniform(0.0, 0.6, size=(9, b.n_c))
            jobs.append((take_states(b, live), bk.take(live), mu))
            refs.append([(scenes_g[s], letters, mu) for s in live])
    assert len(jobs) > 6
    margin = MARGIN
    for (s0, s1, det, scale), ref in zip(batch_rows_many(jobs, margin), refs):
        for j, (scene, m, mu) in enumerate(ref):
            r0, r1, rdet, rscale = band_rows(scene, band_kinematics(scene, ContactMode(getattr(m, "letters", m))), mu, margin)
            assert same_bits(s0[j], r0) and same_bits(s1[j], r1) and same_bits(det[j], rdet) and same_bits(scale[j], rscale)


def test_modes_kinematics_is_the_one_mode_stage(random_groups):
    for scenes, _ in random_groups[:4]:
        batch = state_batch(scenes)
        modes = enumerate_modes(batch.n_c, scenes[0].dof)
        kin = modes_kinematics(batch, modes)
        assert list(kin) == [m.letters for m in modes]
        for m in modes[:: max(1, len(modes) // 12)]:
            for k, s in enumerate(scenes):
                _, status, _, one = single_mode_kinematics(s, m)
                assert kin[m.letters].status_name(k) == status
                if one is not None:
                    assert same_bits(kin[m.letters].xi[k], one.xi[0])


def test_a_batch_from_arrays_is_the_stacked_batch_and_builds_scenes_on_use(segment):
    scenes, mode = segment
    made = []

    def build(s):
        made.append(s)
        return scenes[s]

    stack = lambda name: np.stack([getattr(s, name) for s in scenes])  # noqa: E731
    lazy = LazyScenes(len(scenes), build)
    batch = batch_from_arrays(lazy, *(stack(f) for f in ("Wn", "Wt", "Jn", "Jt", "g_obj", "g_man", "joint_velocity")))
    ref = state_batch(scenes)
    for f in ("joint", "E", "V", "Wrows", "Jrows", "M", "log_row_norm", "drive", "vtol", "r0", "velocity"):
        assert same_bits(getattr(batch, f), getattr(ref, f)), f
    arrays = robust_band_arrays(batch, mode, MU_SEG, force_margin=MARGIN)
    assert_arrays_are_bands(arrays, robust_bands(scenes, mode, MU_SEG, force_margin=MARGIN))
    assert made == [0]  # the first scene gives the partition; no per-state search needed one more
    sub = take_states(batch, np.array([5, 2, 7]))
    assert isinstance(sub.scenes, LazyScenes) and len(sub.scenes) == 3
    assert sub.scenes[1] is scenes[2] and sub.scenes[0] is scenes[5] and made == [0, 2, 5]
