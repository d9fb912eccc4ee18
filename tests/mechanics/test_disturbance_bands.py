"""Bands robust to a box of disturbance wrenches (issue 24, item 2): the disturbance path against its references.

* a zero box (or None) gives today's bands bit for bit, per state and batched;
* the batched twins give the per-state answers bit for bit under a box;
* a box that is one point is the scene with ``g_obj`` shifted by that wrench (an independent path: no wrench slopes);
* the band holds at every wrench of the box and is the intersection over its vertices (eq. 26 affine in the load);
  a competitor's possible efforts are a projection, whose extreme can lie inside the box (shown, solver-confirmed);
* the band shrinks as the box grows, and a box larger than it can absorb leaves none, saying so;
* validation: one ``pytest.raises`` per branch.

The all-modes solver checks at the vertices of friction box x wrench box are in ``test_disturbance_safety.py``.
"""

import dataclasses
import re

import numpy as np
import pytest
from scipy.optimize import minimize

from qsplan.hands import default_hand, first_segment, sample_segment
from qsplan.mechanics import QsplanError, enumerate_modes, planted_scene, solve
from qsplan.mechanics.bands.batched import (
    effort_bands_batch,
    guaranteed_bands_box,
    guaranteed_bands_shared,
    point_bands_batch,
    state_batch,
)
from qsplan.mechanics.bands.batched_robust import competitor_torques_batch, robust_band_arrays, robust_bands
from qsplan.mechanics.bands.disturbance import MAX_DISTURBANCE, WrenchBox, check_wrench_box
from qsplan.mechanics.bands.effort import ForceMargin, band_kinematics, band_rows, effort_band, effort_bands
from qsplan.mechanics.bands.guaranteed import guaranteed_band_box, guaranteed_band_shared, possible_band_box, sampled_band
from qsplan.mechanics.bands.preclusion import PRECLUSION_RTOL, competitor_torques
from qsplan.mechanics.bands.robust import robust_band

MU_SEG = (0.0, 0.2)
MU_RAND = (0.1, 0.4)
SEED = 12
BOX = WrenchBox((-0.1, -0.1, -2e-3), (0.1, 0.1, 2e-3))  # N, N, N m: ~5 % of the demo workpiece's weight
ZEROS = (WrenchBox((0, 0, 0), (0, 0, 0)), ((0.0, 0.0, 0.0), [0, 0, 0]), (np.zeros(3), np.zeros(3)))
#: A point box against the shifted scene: the same numbers by two routes (wrench slopes vs a new ``g_obj``), so
#: equal to rounding of the rows (~1e-15 relative) amplified by ``Q_AI``'s conditioning; 1e-9 of the band's scale.
SHIFT_RTOL = 1e-9
#: Cells per competitor search where the test only compares the batched and per-state searches (bit for bit).
CELLS = 200
LIMIT = re.escape(f"{MAX_DISTURBANCE:g}")


def bits(x):
    """A value's exact bit pattern, recursively (dataclasses, containers, arrays, floats)."""
    if dataclasses.is_dataclass(x):
        return tuple((f.name, bits(getattr(x, f.name))) for f in dataclasses.fields(x))
    if isinstance(x, dict):
        return tuple(sorted((k, bits(v)) for k, v in x.items()))
    if isinstance(x, (list, tuple)):
        return tuple(bits(v) for v in x)
    if isinstance(x, np.ndarray):
        return (x.dtype.str, x.shape, x.tobytes())
    if isinstance(x, (float, np.floating)):
        return np.float64(x).tobytes()
    return repr(x)


def shifted(scene, w):
    """The scene with the wrench ``w`` (3,) added to ``g_obj`` (eq. 2)."""
    return dataclasses.replace(scene, g_obj=np.asarray(scene.g_obj + np.asarray(w, float)))


@pytest.fixture(scope="module")
def segment():
    samples = sample_segment(first_segment(default_hand()), 24)
    return samples.scenes, samples.segment.mode


@pytest.fixture(scope="module")
def random_groups():
    """Seeded raw scenes of 4-6 contacts and 2-3 joints, grouped by shape (one batch each), each with a mode that has a
    guaranteed band over :data:`MU_RAND` without disturbance (the planted one if it has one; the scene's planted mode
    where none has)."""
    groups = {}
    for k in range(48):
        rng = np.random.default_rng([SEED, k])
        n_c = int(rng.integers(4, 7))
        scene, planted = planted_scene(rng, n_c, 1, n_joints=int(rng.integers(2, 4)))
        modes = [planted.letters] + [m.letters for m in enumerate_modes(n_c, scene.dof) if m.letters != planted.letters]
        mode = next((m for m in modes if guaranteed_band_box(scene, m, *MU_RAND).feasible), planted.letters)
        groups.setdefault((n_c, scene.effort_controlled.tobytes()), []).append((scene, mode))
    return list(groups.values())


def box_for(scene, rng, rel=0.01):
    """A wrench box of about ``rel`` of the scene's load per component, off centre."""
    half = rng.uniform(0.5, 1.0, 3) * rel * max(float(np.max(np.abs(scene.g_obj))), 1.0)
    centre = rng.uniform(-0.5, 0.5, 3) * half
    return WrenchBox(centre - half, centre + half)


@pytest.mark.parametrize("n_groups", [1, pytest.param(None, marks=pytest.mark.slow)])
def test_zero_box_gives_todays_bands_bit_for_bit(segment, random_groups, n_groups):
    scenes, mode = segment
    groups = random_groups[:n_groups]
    cases = [(s, mode, MU_SEG) for s in scenes[:: 12 if n_groups else 3]] + [(s, m, MU_RAND) for g in groups for s, m in g[:2]]
    for scene, m, (lo, hi) in cases:
        mus = np.random.default_rng(0).uniform(lo, hi, (4, scene.n_contacts))
        calls = [
            lambda d: effort_band(scene, m, disturbance=d),
            lambda d: effort_bands(scene, m, mus, force_margin=ForceMargin(0.01, 0.0), disturbance=d),
            lambda d: guaranteed_band_box(scene, m, lo, hi, disturbance=d),
            lambda d: guaranteed_band_shared(scene, m, lo, hi, disturbance=d),
            lambda d: possible_band_box(scene, m, lo, hi, disturbance=d),
            lambda d: sampled_band(scene, m, np.linspace(lo, hi, 5), disturbance=d),
            lambda d: competitor_torques(scene, m, lo, hi, -10.0, 10.0, disturbance=d),
            lambda d: robust_band(scene, m, (lo, hi), disturbance=d),
            lambda d: robust_band(scene, m, (lo, hi), shared=True, disturbance=d),
        ]
        for call in calls:
            today = bits(call(None))
            assert all(bits(call(z)) == today for z in ZEROS)
    for group, m, mu in [([s for s in scenes], mode, MU_SEG)] + [([s for s, _ in g], g[0][1], MU_RAND) for g in groups]:
        batch = state_batch(group)
        calls = [
            lambda d: robust_bands(group, m, mu, disturbance=d),
            lambda d: robust_bands(group, m, mu, shared=True, disturbance=d),
            lambda d: robust_band_arrays(batch, m, mu, disturbance=d),
            lambda d: guaranteed_bands_box(batch, m, *mu, disturbance=d),
            lambda d: guaranteed_bands_shared(batch, m, *mu, disturbance=d),
            lambda d: effort_bands_batch(batch, m, np.full((3, batch.n_c), mu[1]), disturbance=d),
            lambda d: point_bands_batch(batch, m, mu[0], disturbance=d),
            lambda d: competitor_torques_batch(batch, m, *mu, -10.0, 10.0, disturbance=d),
        ]
        for call in calls:
            today = bits(call(None))
            assert all(bits(call(z)) == today for z in ZEROS)


@pytest.mark.parametrize("n_groups", [4, pytest.param(None, marks=pytest.mark.slow)])
@pytest.mark.parametrize("shared", [False, True])
def test_batched_bands_under_a_box_are_the_per_state_ones(segment, random_groups, shared, n_groups):
    scenes, mode = segment
    got = robust_bands(scenes, mode, MU_SEG, shared=shared, disturbance=BOX)
    assert bits(got) == bits([robust_band(s, mode, MU_SEG, shared=shared, disturbance=BOX) for s in scenes])
    margin = ForceMargin(0.05, 0.02)  # N: with a force margin too
    with_margin = robust_bands(scenes[::4], mode, MU_SEG, shared=shared, force_margin=margin, disturbance=BOX)
    assert bits(with_margin) == bits([robust_band(s, mode, MU_SEG, shared=shared, force_margin=margin, disturbance=BOX) for s in scenes[::4]])
    assert all(a.feasible <= b.feasible for a, b in zip(with_margin, got[::4]))
    arrays = robust_band_arrays(state_batch(scenes), mode, MU_SEG, shared=shared, disturbance=BOX)
    np.testing.assert_array_equal(arrays.lower, [r.lower for r in got])
    np.testing.assert_array_equal(arrays.upper, [r.upper for r in got])
    np.testing.assert_array_equal(arrays.exact, [r.exact for r in got])
    n_feasible = n_searched = 0
    for g, group in enumerate(random_groups[:n_groups]):
        group_scenes = [s for s, _ in group]
        batch, rng = state_batch(group_scenes), np.random.default_rng([SEED, g])
        box = box_for(group_scenes[0], rng)
        for m in dict.fromkeys(letters for _, letters in group[:2]):
            got = robust_bands(group_scenes, m, MU_RAND, shared=shared, disturbance=box)
            ref = [robust_band(s, m, MU_RAND, shared=shared, disturbance=box) for s in group_scenes]
            assert bits(got) == bits(ref), (g, m)
            n_feasible += sum(r.feasible for r in ref)
            one, many = (guaranteed_band_shared, guaranteed_bands_shared) if shared else (guaranteed_band_box, guaranteed_bands_box)
            assert bits(many(batch, m, *MU_RAND, disturbance=box)) == bits([one(s, m, *MU_RAND, disturbance=box) for s in group_scenes])
            mus = rng.uniform(*MU_RAND, (3, batch.n_c))
            assert bits(effort_bands_batch(batch, m, mus, disturbance=box)) == bits(
                tuple(np.stack(x) for x in zip(*[effort_bands(s, m, mus, disturbance=box) for s in group_scenes])))
            points = point_bands_batch(batch, m, mus[0], disturbance=box)
            assert bits(points) == bits([effort_band(s, m, mus[0], disturbance=box) for s in group_scenes])
            # every mode a competitor here, on a wide interval: searches the root cell leaves open, a budget that bounds them
            cts = competitor_torques_batch(batch, m, *MU_RAND, -20.0, 20.0, shared=shared, max_cells=CELLS, disturbance=box)
            ref = [competitor_torques(s, m, *MU_RAND, -20.0, 20.0, shared=shared, max_cells=CELLS, disturbance=box) for s in group_scenes]
            assert bits(cts) == bits(ref)
            n_searched += sum(c.cells > 2 for c in cts)
    assert n_feasible > 3 and n_searched > 0  # bands, and searches beyond the batched root cell


@pytest.mark.parametrize("shared", [False, True])
def test_a_point_box_is_the_scene_with_g_obj_shifted(random_groups, shared):
    """``WrenchBox(w, w)`` (a known constant load) through the wrench slopes equals the scene whose ``g_obj`` is moved."""
    n = 0
    for g, group in enumerate(random_groups[:4]):
        for scene, m in group[:3]:
            w = np.random.default_rng([SEED, g, n]).uniform(-0.05, 0.05, 3) * max(float(np.max(np.abs(scene.g_obj))), 1.0)
            a = robust_band(scene, m, MU_RAND, shared=shared, disturbance=(w, w))
            b = robust_band(shifted(scene, w), m, MU_RAND, shared=shared)
            assert a.feasible == b.feasible and a.desired.feasible == b.desired.feasible
            scale = max([abs(x) for x in (a.desired.lower, a.desired.upper) if np.isfinite(x)] + [1.0])
            pairs = [((a.desired.lower, b.desired.lower), SHIFT_RTOL), ((a.desired.upper, b.desired.upper), SHIFT_RTOL),
                     ((a.lower, b.lower), PRECLUSION_RTOL), ((a.upper, b.upper), PRECLUSION_RTOL)]  # fmt: skip
            for (x, y), rtol in pairs:  # a competitor's hull is found to its search's tolerance, by either route
                assert (np.isnan(x) and np.isnan(y)) or x == y or abs(x - y) <= rtol * scale
            n += a.feasible
    assert n > 3


def test_a_point_band_under_a_box_is_the_intersection_over_its_vertices(random_groups):
    """At fixed friction the band for every wrench of the box is the intersection of the bands of the shifted scenes
    at its 8 vertices, and lies inside the band at every interior wrench (eq. 26 is affine in the load)."""
    checked = 0
    for g, group in enumerate(random_groups):
        scene, m = group[0]
        rng = np.random.default_rng([SEED, g])
        box = box_for(scene, rng, rel=0.02)
        mu = rng.uniform(*MU_RAND, scene.n_contacts)
        b = effort_band(scene, m, mu, disturbance=box)
        vertex = [effort_band(shifted(scene, v), m, mu) for v in box.vertices()]
        assert len(vertex) == 8
        if not b.feasible:
            assert not all(v.feasible for v in vertex) or max(v.lower for v in vertex) > min(v.upper for v in vertex)
            continue
        scale = max([abs(b.lower), abs(b.upper), 1.0] if np.isfinite(b.width) else [1.0])
        assert b.lower == pytest.approx(max(v.lower for v in vertex), abs=SHIFT_RTOL * scale)
        assert b.upper == pytest.approx(min(v.upper for v in vertex), abs=SHIFT_RTOL * scale)
        for w in rng.uniform(box.lo, box.hi, (20, 3)):
            inner = effort_band(shifted(scene, w), m, mu)
            assert inner.lower <= b.lower + SHIFT_RTOL * scale and b.upper <= inner.upper + SHIFT_RTOL * scale
        checked += 1
    assert checked > 5


@pytest.mark.parametrize("guaranteed", [guaranteed_band_box, guaranteed_band_shared])
def test_a_guaranteed_band_under_a_box_is_the_intersection_over_its_vertices(random_groups, guaranteed):
    """Over uncertain friction too: the band for every wrench of the box is the intersection of the guaranteed bands
    of the scenes shifted to its 8 vertices (shared friction: with the dominated vertices of each row left out)."""
    checked = 0
    for g, group in enumerate(random_groups):
        for scene, m in group[:3]:
            box = box_for(scene, np.random.default_rng([SEED, g, checked]), rel=0.02)
            b = guaranteed(scene, m, *MU_RAND, disturbance=box)
            vertex = [guaranteed(shifted(scene, v), m, *MU_RAND) for v in box.vertices()]
            lower, upper = max(v.lower for v in vertex), min(v.upper for v in vertex)
            assert b.feasible == (all(v.feasible for v in vertex) and lower <= upper)
            if b.feasible:
                scale = max([abs(x) for x in (b.lower, b.upper) if np.isfinite(x)] + [1.0])
                assert b.lower == lower or abs(b.lower - lower) <= SHIFT_RTOL * scale
                assert b.upper == upper or abs(b.upper - upper) <= SHIFT_RTOL * scale
                if guaranteed is guaranteed_band_box:  # the paper's sampling at the friction vertices: the same band
                    bits_ = (np.arange(2**scene.n_contacts)[:, None] >> np.arange(scene.n_contacts)) & 1
                    s = sampled_band(scene, m, np.where(bits_, MU_RAND[1], MU_RAND[0]), disturbance=box)
                    assert (s.lower, s.upper) == (b.lower, b.upper)
                checked += 1
    assert checked > 10


def test_the_possible_superset_contains_every_loaded_point_band(random_groups):
    checked = 0
    for g, group in enumerate(random_groups):
        scene, m = group[0]
        rng = np.random.default_rng([SEED, g, 1])
        box = box_for(scene, rng, rel=0.05)
        p = possible_band_box(scene, m, *MU_RAND, disturbance=box)
        for _ in range(30):
            mu, w = rng.uniform(*MU_RAND, scene.n_contacts), rng.uniform(box.lo, box.hi)
            b = effort_band(shifted(scene, w), m, mu)
            if b.feasible:
                assert p.feasible and p.lower <= b.lower + SHIFT_RTOL * max(1.0, abs(b.lower)) or p.lower == b.lower == -np.inf
                assert b.upper <= p.upper + SHIFT_RTOL * max(1.0, abs(b.upper)) or b.upper == p.upper == np.inf
                checked += 1
    assert checked > 50


def _interior_case():
    """Scene 2 of seed 7 (three contacts) and its mode RBR, a box of 5-30 % of its load per component."""
    rng = np.random.default_rng([7, 2])
    n_c = int(rng.integers(3, 6))
    scene, _ = planted_scene(rng, n_c, 1, n_joints=int(rng.integers(2, 4)))
    half = rng.uniform(0.05, 0.3, 3) * max(float(np.max(np.abs(scene.g_obj))), 1.0)
    return scene, "RBR", WrenchBox(-half, half)


def test_a_competitors_extreme_can_lie_inside_the_wrench_box():
    """Whether a competitor is possible for *some* wrench is a projection: here RBR is possible below the lowest
    effort any vertex of the wrench box allows it (at any friction), at an interior wrench the solver confirms.
    Precluding it from the vertices alone would have been optimistic; the search over wrench cells finds it."""
    scene, mode, box = _interior_case()
    ct = competitor_torques(scene, mode, *MU_RAND, -np.inf, np.inf, disturbance=box)
    at_vertices = [competitor_torques(scene, mode, *MU_RAND, -np.inf, np.inf, disturbance=(v, v)) for v in box.vertices()]
    assert ct.exact and all(v.exact for v in at_vertices)
    vertex_low = min(v.lower for v in at_vertices if not v.empty)
    assert ct.lower < vertex_low - 0.1
    tau = 0.5 * (ct.lower + vertex_low)  # below every vertex's hull, inside the box's
    mk, n_c = band_kinematics(scene, mode), scene.n_contacts

    def slack(x):  # the competitor's smallest Coulomb slack at (mu, w), from the shifted scene's own rows
        mu, w = np.clip(x[:n_c], *MU_RAND), np.clip(x[n_c:], box.lo, box.hi)
        s0, s1, _, scale = band_rows(shifted(scene, w), mk, mu[None])
        return float(np.min(s0[0] + tau * s1[0]) / scale[0])

    best = max((minimize(lambda x: -slack(x), np.concatenate([np.full(n_c, m), 0.5 * v]), method="Nelder-Mead",
                         options=dict(xatol=1e-12, fatol=1e-14, maxiter=3000)) for v in box.vertices() for m in (0.25,)),
               key=lambda r: -r.fun)  # fmt: skip
    mu, w = np.clip(best.x[:n_c], *MU_RAND), np.clip(best.x[n_c:], box.lo, box.hi)
    assert slack(best.x) > 0
    inside = (w > np.array(box.lo) + 1e-6) & (w < np.array(box.hi) - 1e-6)
    assert inside.any()  # a component strictly inside its interval
    s = shifted(scene, w).with_inputs(joint_effort=np.where(scene.effort_controlled, tau, np.nan)).with_mu(mu)
    assert mode in solve(s, residuals=False, workers=1, search="all").feasible_modes


def test_a_search_out_of_cells_is_conservative_and_says_so():
    scene, mode, box = _interior_case()
    full = competitor_torques(scene, mode, *MU_RAND, -np.inf, np.inf, disturbance=box)
    short = competitor_torques(scene, mode, *MU_RAND, -np.inf, np.inf, disturbance=box, max_cells=8)
    assert full.exact and not short.exact and "budget" in short.reason
    assert short.lower <= full.lower and full.upper <= short.upper  # wider: safe for precluding


@pytest.mark.parametrize("shared", [False, True])
def test_the_band_shrinks_as_the_box_grows_until_none_is_left(segment, shared):
    scenes, mode = segment
    scene = scenes[0]
    bands = [robust_band(scene, mode, MU_SEG, shared=shared, disturbance=(-f * np.array(BOX.hi), f * np.array(BOX.hi)))
             for f in (0.0, 0.25, 0.5, 1.0, 2.0, 4.0)]  # fmt: skip
    assert all(b.feasible and b.exact and not b.split for b in bands[:5])
    for a, b in zip(bands, bands[1:]):
        if b.feasible:
            assert a.lower <= b.lower and b.upper <= a.upper
    assert bands[0].lower < bands[3].lower < bands[4].lower
    if not shared:
        assert bands[3].upper < bands[0].upper
    huge = robust_band(scene, mode, MU_SEG, shared=shared, disturbance=(-10 * np.array(BOX.hi), 10 * np.array(BOX.hi)))
    if shared:  # one coefficient at all four contacts: squeezing harder absorbs any bounded wrench here, at a price
        assert huge.feasible and huge.upper == np.inf and huge.lower > bands[4].lower
    else:  # +-1 N on a 1.96 N workpiece: more than the band can absorb, and the reason says so
        assert not huge.feasible and "disturbance box" in huge.reason


def test_desired_bands_of_random_scenes_shrink_as_the_box_grows(random_groups):
    nested = 0
    for g, group in enumerate(random_groups):
        scene, m = group[0]
        base = box_for(scene, np.random.default_rng([SEED, g, 2]), rel=0.01)
        for guaranteed in (guaranteed_band_box, guaranteed_band_shared):
            prev = guaranteed(scene, m, *MU_RAND)
            for f in (0.5, 1.0, 2.0, 4.0):
                b = guaranteed(scene, m, *MU_RAND, disturbance=(f * np.array(base.lo), f * np.array(base.hi)))
                if b.feasible:
                    assert prev.feasible and prev.lower <= b.lower and b.upper <= prev.upper
                    nested += 1
                prev = b
    assert nested > 20


@pytest.mark.parametrize(
    ("lo", "hi", "match"),
    [
        ((0.0, 0.0), (1.0, 1.0, 1.0), r"disturbance\.lo: expected shape \(3,\)"),
        (np.zeros((3, 1)), np.ones(3), r"disturbance\.lo: expected shape \(3,\)"),
        ((0.0, 0.0, 0.0), ("a", 0.0, 0.0), r"disturbance\.hi: expected 3 numbers"),
        ((0.0, np.nan, 0.0), (1.0, 1.0, 1.0), r"disturbance\.lo: expected finite numbers"),
        ((0.0, 0.0, 0.0), (1.0, np.inf, 1.0), r"disturbance\.hi: expected finite numbers"),
        ((-2 * MAX_DISTURBANCE, 0.0, 0.0), (1.0, 1.0, 1.0), rf"disturbance\.lo\[0\]: expected magnitude <= {LIMIT} N; got"),
        ((0.0, 0.0, 0.0), (1.0, 1.0, 1.5 * MAX_DISTURBANCE), rf"disturbance\.hi\[2\]: expected magnitude <= {LIMIT} N m; got"),
        ((0.0, 1.0, 0.0), (1.0, 0.5, 1.0), r"disturbance: expected lo <= hi; got lo\[1\] = 1.0 > hi\[1\] = 0.5"),
    ],
)
def test_bad_wrench_box(lo, hi, match):
    with pytest.raises(QsplanError, match=match):
        WrenchBox(lo, hi)


@pytest.mark.parametrize("value", [(1.0, 2.0, 3.0), "box", [np.zeros(3)], 0.5])
def test_bad_disturbance_argument(value):
    with pytest.raises(QsplanError, match=r"disturbance: expected a WrenchBox or \(lo, hi\)"):
        check_wrench_box(value)


def test_every_public_function_checks_its_disturbance(segment):
    scenes, mode = segment
    bad = ((0.0, 0.0, 0.0), (1.0, -1.0, 0.0))
    batch = state_batch(scenes[:2])
    for call in (
        lambda: robust_band(scenes[0], mode, MU_SEG, disturbance=bad),
        lambda: guaranteed_band_box(scenes[0], mode, *MU_SEG, disturbance=bad),
        lambda: competitor_torques(scenes[0], "RBSS", *MU_SEG, 0.0, 1.0, disturbance=bad),
        lambda: robust_band_arrays(batch, mode, MU_SEG, disturbance=bad),
        lambda: guaranteed_bands_shared(batch, mode, *MU_SEG, disturbance=bad),
    ):
        with pytest.raises(QsplanError, match=r"disturbance: expected lo <= hi"):
            call()


def test_wrench_box_value_type():
    box = WrenchBox([-1, -2, -0.5], np.array([1.0, 2.0, 0.5]))
    assert box.lo == (-1.0, -2.0, -0.5) and box == WrenchBox((-1, -2, -0.5), (1, 2, 0.5))
    assert hash(box) == hash(WrenchBox(box.lo, box.hi))  # a value: usable as a key
    assert check_wrench_box(box) is box and check_wrench_box((box.lo, box.hi)) == box
    assert check_wrench_box(None) is None and check_wrench_box(ZEROS[0]) is None
    v = box.vertices()
    assert v.shape == (8, 3) and {tuple(x) for x in v} == {(a, b, c) for a in (-1, 1) for b in (-2, 2) for c in (-0.5, 0.5)}
    np.testing.assert_array_equal(v[0], box.lo)
    np.testing.assert_array_equal(v[1], (1.0, -2.0, -0.5))  # bit i of the vertex index: component i at its upper end
    flat = WrenchBox((0.0, 1.0, 0.0), (0.0, 1.0, 2.0))  # a known constant force and an uncertain moment
    assert flat.free == (2,) and flat.vertices().tolist() == [[0.0, 1.0, 0.0], [0.0, 1.0, 2.0]]
    assert box.to_dict() == {"lo": [-1.0, -2.0, -0.5], "hi": [1.0, 2.0, 0.5], "units": ["N", "N", "N m"]}
