"""Certificates in the competitor preclusion (issue 21, item 13): exact where the old search ran out of cells.

* closed-form cells: rows that fail at different vertices are certified infeasible together, an interior
  friction where every row holds is never certified away, and a certified bound stops at the true minimum;
* seeded raw scenes (the band-safety scenes of ``test_band_safety.py`` with other seeds) where a competitor
  whose ``det Q_AI`` keeps its sign over the friction box used up its cell budget: the band is now exact,
  checked against the all-modes solver (at the box vertices and a friction grid, efforts inside the band
  and just outside it), and the old answer (no certificates) was conservative there;
* a competitor with one determinant sign whose possible efforts reach beyond the hull of its vertex
  bands (why the vertex bands alone would be optimistic), and its hull still covers them;
* the batched path (root cell batched, open searches per state) gives the per-state answers.
"""

from itertools import product

import numpy as np
import pytest
from scipy.optimize import minimize

from qsplan.mechanics import effort_bands, enumerate_modes, robust_band, scene_from_dict, scene_to_dict, solve
from qsplan.mechanics.bands import preclusion
from qsplan.mechanics.bands.batched import state_batch
from qsplan.mechanics.bands.batched_robust import robust_band_arrays, robust_bands
from qsplan.mechanics.bands.certificates import certified_lower_bounds
from qsplan.mechanics.bands.effort import band_kinematics, band_rows
from qsplan.mechanics.bands.preclusion import cell_lower_bounds, competitor_torques
from qsplan.mechanics.numerics import DEFAULT_TOLERANCES
from tests.mechanics.test_band_safety import MU_BOX, check_band, scene_case
from tests.mechanics.test_bands_batched import robust_key, same
from tests.mechanics.test_bands_batched_arrays import assert_arrays_are_bands

#: ``(seed, scene, desired mode, competitor)``: a competitor with one sign of det Q_AI on the box used up
#: its cells (4,000) without precluding itself; with certificates it is proved infeasible inside the band.
CASES = [(13, 84, "RBBBR", "SBSSS"), (21, 28, "BRRBBB", "SSSBBS"), (21, 90, "RBBR", "SSSS")]
#: Friction grid levels per contact for the solver's check (with the box's vertices).
GRID = 3
#: Efforts judged inside a band, as fractions of the way from one edge to the other.
INSIDE = (0.02, 0.5, 0.98)


def _one_cell(N0, N1):
    """One cell's control values: ``det`` 1 at every vertex, rows ``N0 + tau N1`` (K, R)."""
    N0, N1 = np.asarray(N0, float)[None], np.asarray(N1, float)[None]
    return np.ones(N0.shape[:2]), N0, N1


def test_rows_failing_at_different_vertices_are_certified_together():
    # on mu in [0, 1]: row 0 = 1 - 4 mu >= 0 only for mu <= 1/4, row 1 = -3 + 4 mu only for mu >= 3/4
    det, N0, N1 = _one_cell([[1.0, -3.0], [-3.0, 1.0]], np.zeros((2, 2)))
    lb, steady = cell_lower_bounds(det, N0, N1, -1.0, 1.0, DEFAULT_TOLERANCES)
    assert steady[0] and lb[0] == -1.0  # each row alone holds at some vertex: the per-row bound proves nothing
    lifted, used = certified_lower_bounds(det, N0, N1, lb, 1.0, steady, DEFAULT_TOLERANCES)
    assert lifted[0] == np.inf and used == 1  # no effort at all: one combination of the rows proves it


def test_a_friction_inside_the_cell_where_every_row_holds_is_never_certified_away():
    # row 0 = 1 - 2 mu, row 1 = -1 + 2 mu: at no vertex do both hold, at mu = 1/2 both do (for every effort)
    det, N0, N1 = _one_cell([[1.0, -1.0], [-1.0, 1.0]], np.zeros((2, 2)))
    lb, steady = cell_lower_bounds(det, N0, N1, -1.0, 1.0, DEFAULT_TOLERANCES)
    lifted, _ = certified_lower_bounds(det, N0, N1, lb, 1.0, steady, DEFAULT_TOLERANCES)
    assert lifted[0] == lb[0] == -1.0


def test_a_certified_bound_stops_at_the_true_smallest_effort():
    # row 0 = tau - 1 - 2 mu, row 1 = tau - 3 + 2 mu: both hold from tau = 2 on (at mu = 1/2, inside the cell)
    det, N0, N1 = _one_cell([[-1.0, -3.0], [-3.0, -1.0]], np.ones((2, 2)))
    lb, steady = cell_lower_bounds(det, N0, N1, -10.0, 10.0, DEFAULT_TOLERANCES)
    assert lb[0] == pytest.approx(1.0, abs=1e-8)  # each row alone from tau = 1 at its best vertex
    # a proof over efforts [1, 1.9] reaches, in closed form, to the true smallest effort and not beyond
    lifted, _ = certified_lower_bounds(det, N0, N1, lb, 1.9, steady, DEFAULT_TOLERANCES)
    assert 2.0 - 1e-6 < lifted[0] <= 2.0
    # no proof over a window that holds feasible efforts ([1, 3]: some control value allows 3): the bound stays
    lifted, _ = certified_lower_bounds(det, N0, N1, lb, 10.0, steady, DEFAULT_TOLERANCES)
    assert lifted[0] == lb[0]


def test_no_certificate_where_det_changes_sign():
    det, N0, N1 = _one_cell([[1.0, -3.0], [-3.0, 1.0]], np.zeros((2, 2)))
    det = np.array([[1.0, -1.0]])
    lb, steady = cell_lower_bounds(det, N0, N1, -1.0, 1.0, DEFAULT_TOLERANCES)
    lifted, used = certified_lower_bounds(det, N0, N1, lb, 1.0, steady, DEFAULT_TOLERANCES)
    assert not steady[0] and used == 0 and lifted[0] == lb[0]


def _friction_points(scene):
    """The box's vertices over every contact and a grid of :data:`GRID` levels per contact, (N, n_c)."""
    lo, hi = MU_BOX
    levels = np.linspace(lo, hi, GRID)
    return np.array(list(product(levels, repeat=scene.n_contacts)))


def _solver_safe(scene, mode, competitors, tau, mus):
    """The all-modes solver at every friction of ``mus``: ``mode`` feasible and no competitor feasible."""
    for mu in mus:
        s = scene.with_inputs(joint_effort=np.where(scene.effort_controlled, tau, np.nan)).with_mu(mu)
        feasible = set(solve(s, residuals=False, workers=1, search="all").feasible_modes)
        if mode not in feasible or feasible & set(competitors):
            return False
    return True


def _steady_on_box(scene, mode):
    """``det Q_AI`` of ``mode`` has one sign at every vertex of the box, hence on all of it (multilinear)."""
    lo, hi = MU_BOX
    verts = np.array(list(product((lo, hi), repeat=scene.n_contacts)))
    _, _, det, _ = band_rows(scene, band_kinematics(scene, mode), verts)
    return bool(np.all(det > 0) or np.all(det < 0))


@pytest.mark.slow
@pytest.mark.parametrize(("seed", "k", "mode", "competitor"), CASES)
def test_band_is_exact_where_a_steady_competitor_used_up_its_cells(monkeypatch, seed, k, mode, competitor):
    scene, modes, shared = scene_case(k, seed)
    assert mode in modes and not shared and _steady_on_box(scene, competitor)
    band = robust_band(scene, mode, MU_BOX)
    assert band.feasible and band.exact and competitor not in band.precluded  # proved infeasible on the whole band
    unsafe, confirmed = check_band(scene, band, shared, np.random.default_rng([seed, k, 1]))
    assert unsafe == [] and confirmed  # solver inside, witnesses just outside every finite edge
    mus = _friction_points(scene)
    comps = [m.letters for m in enumerate_modes(scene.n_contacts, scene.dof) if m.letters != mode]
    # the old search (no certificates): conservative there, narrower or no band, and said so
    monkeypatch.setattr(preclusion, "MAX_CERTIFICATES", 0)
    old = robust_band(scene, mode, MU_BOX)
    assert not old.exact and "cell budget exhausted" in old.precluded[competitor].reason
    if old.feasible:
        assert band.lower <= old.lower and old.upper <= band.upper and band.width > old.width
        gained = old.lower - band.lower if old.lower > band.lower else band.upper - old.upper
        edge = band.lower if old.lower > band.lower else old.upper
        taus = [edge + f * gained for f in INSIDE]
    else:
        taus = [band.lower + f * band.width for f in INSIDE]
    for tau in taus:  # efforts the old answer refused: safe at every friction of the grid
        assert _solver_safe(scene, mode, comps, tau, mus), tau


def test_batched_path_gives_the_per_state_answers():
    """Each case's scene and two variants of it (loads scaled by 1 +- 1e-3) in one batch: the root cell batched,
    the searches it leaves open (those with certificates) per state; every answer as the per-state one."""
    for seed, k, mode, _ in CASES:
        scene, _, _ = scene_case(k, seed)
        doc = scene_to_dict(scene)
        scenes = [scene] + [scene_from_dict({**doc, "g_obj": [f * g for g in doc["g_obj"]]}) for f in (1 - 1e-3, 1 + 1e-3)]
        got = robust_bands(scenes, mode, MU_BOX)
        refs = [robust_band(s, mode, MU_BOX) for s in scenes]
        for j, (g, r) in enumerate(zip(got, refs)):
            assert same(robust_key(g), robust_key(r)), (seed, k, j)
        assert refs[0].exact and refs[0].feasible
        assert_arrays_are_bands(robust_band_arrays(state_batch(scenes), mode, MU_BOX), got, refs)


def test_vertex_bands_alone_would_be_optimistic_for_a_competitor():
    """Scene 86 of seed 21: competitor SBRBS of mode SRSBB has det Q_AI < 0 on the whole box, yet it is
    feasible at efforts above the largest upper edge of its vertex bands, at a friction inside the box."""
    scene, _, _ = scene_case(86, 21)
    c, lo, hi = "SBRBS", *MU_BOX
    assert _steady_on_box(scene, c)
    verts = np.array(list(product((lo, hi), repeat=scene.n_contacts)))
    l, u, ok = effort_bands(scene, c, verts)
    vertex_top = float(np.max(u[ok]))
    free = [i for i, letter in enumerate(c) if letter != "B"]

    def neg_upper(x):
        mu = np.full(scene.n_contacts, lo)
        mu[free] = np.clip(x, lo, hi)
        l, u, ok = effort_bands(scene, c, mu[None])
        return -float(u[0]) if ok[0] else 10.0

    starts = np.random.default_rng(1).uniform(lo, hi, (20, len(free)))
    best = min((minimize(neg_upper, x0, method="Nelder-Mead", options=dict(xatol=1e-12, fatol=1e-14, maxiter=4000))
                for x0 in starts), key=lambda r: r.fun)  # fmt: skip
    mu = np.full(scene.n_contacts, lo)
    mu[free] = np.clip(best.x, lo, hi)
    tau = 0.5 * (vertex_top - best.fun)  # halfway between the vertex bands' top and the top found inside
    assert tau > vertex_top + 1e-3
    s = scene.with_inputs(joint_effort=np.where(scene.effort_controlled, tau, np.nan)).with_mu(mu)
    assert c in solve(s, residuals=False, workers=1, search="all").feasible_modes
    ct = competitor_torques(scene, c, lo, hi, -np.inf, np.inf)
    assert ct.upper >= tau  # the hull covers it: conservative (exact or labelled), never optimistic
