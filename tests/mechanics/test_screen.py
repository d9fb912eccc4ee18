"""The reduced screen of the pruned search (issue 13, item 5): compiled kernel against its numpy reference,
both against the plain path's statuses, and the pruned search's solutions against the plain path's."""

from itertools import combinations
from math import comb

import numpy as np
import pytest

from qsplan.mechanics import make_scene, planted_scene, solve
from qsplan.mechanics.modes.contact_mode import codes_to_letters, combinations_array, enumerate_modes, letters_to_codes
from qsplan.mechanics.numerics import DEFAULT_TOLERANCES, Status
from qsplan.mechanics.parallel import first_difference
from qsplan.mechanics.solver import screen, search
from qsplan.mechanics.solver.batch import DEFAULT_BATCH, solve_batch
from qsplan.mechanics.solver.breaking_sets import feasible_breaking_sets
from qsplan.mechanics.solver.search import all_breaking_sets

#: (n_c, |tau_I|): dof = n_c, dof < n_c (large breaking sets), dof > n_c (few breaking contacts).
SHAPES = [(5, 2), (6, 3), (7, 1), (7, 4), (8, 5), (8, 8), (9, 6), (10, 3), (10, 9)]

needs_kernel = pytest.mark.skipif(not screen.KERNEL, reason="the compiled screen is not built")


def _planted(seed, n_c, n_e):
    return planted_scene(np.random.default_rng([seed, n_c, n_e]), n_c, n_e)


def _masks(sets, n_c):
    masks = np.zeros((len(sets), n_c), dtype=np.uint8)
    for i, B in enumerate(sets):
        masks[i, list(B)] = 1
    return masks


def _degenerate_scenes():
    """Zero sliding speeds, coincident contacts (singular P_AI and E_A), zero loads."""
    base = dict(
        Wn=[[0, 0, 0], [1, 1, 1], [-1, 1, 0]], Wt=[[-1, -1, -1], [0, 0, 0], [0, 0, 0]],
        Jn=[[0.0, 0.1], [0.0, 0.2], [0.1, 0.0]], Jt=[[-0.1, 0.0], [0.1, 0.3], [0.2, 0.1]], mu=[0.3, 0.3, 0.5],
        g_obj=[0, -1, 0], joint_velocity=[1.0, np.nan], effort_controlled=[False, True], joint_effort=[np.nan, 0.2],
    )  # fmt: skip
    yield make_scene(**base)
    yield make_scene(**{**base, "Jt": [[0.0, 0.0], [0.0, 0.0], [0.0, 0.0]]})
    yield make_scene(**{**base, "Wn": [[0, 0, 0], [1, 1, 1], [-1, -1, 0]], "Wt": [[-1, -1, 0], [0, 0, 1], [0, 0, 0]]})
    yield make_scene(**{**base, "g_obj": [0, 0, 0], "joint_effort": [np.nan, 0.0]})


def _scenes():
    for n_c, n_e in SHAPES:
        for seed in range(3):
            yield _planted(seed, n_c, n_e)[0]
    yield from _degenerate_scenes()


def test_kernel_is_built():
    assert screen.KERNEL, "qsplan.mechanics.solver.screen_kernel is missing: `pip install .` needs a C compiler"


@needs_kernel
@pytest.mark.parametrize("coulomb", [False, True])
def test_compiled_screen_decides_as_the_numpy_reference(coulomb):
    decided = 0
    for scene in _scenes():
        rs = screen.ReducedScene(scene, DEFAULT_TOLERANCES)
        masks = _masks(list(all_breaking_sets(scene.n_contacts, scene.dof)), scene.n_contacts)
        fast = screen.screen_sets(rs, masks, coulomb, compiled=True)
        slow = screen.screen_sets(rs, masks, coulomb, compiled=False)
        assert fast[1:] == slow[1:]  # counts: kinematic, Coulomb, modes (eq. 49)
        assert np.array_equal(fast[0], slow[0])  # the same kept modes, in the same order
        assert fast[3] == len(enumerate_modes(scene.n_contacts, scene.dof))
        decided += fast[1] + fast[2]
    assert decided > 1000


@pytest.mark.parametrize("compiled", [pytest.param(True, marks=needs_kernel), False])
def test_screened_modes_are_rejected_by_the_reference(compiled):
    """Every mode the screen rejects gets a non-feasible status from the plain batch test (eqs. 24-28)."""
    rejected = 0
    for scene in _scenes():
        n_c, dof = scene.n_contacts, scene.dof
        plain = solve(scene, search="all", workers=1, keep_statuses=True)
        status = dict(zip((m.letters for m in enumerate_modes(n_c, dof)), plain.statuses))
        rs = screen.ReducedScene(scene, DEFAULT_TOLERANCES)
        kept, n_kin, n_coul, total = screen.screen_sets(rs, _masks(list(all_breaking_sets(n_c, dof)), n_c),
                                                        compiled=compiled)  # fmt: skip
        kept = {codes_to_letters(row) for row in kept}
        assert total == len(status) and n_kin + n_coul == total - len(kept)
        assert all(st != Status.FEASIBLE for mode, st in status.items() if mode not in kept)
        rejected += total - len(kept)
    assert rejected > 1000


def test_kinematic_verdicts_are_the_references():
    """A mode rejected by eq. (15) in the reduced system penetrates in the reference too (or its P_AI is singular)."""
    flagged = 0
    for scene in _scenes():
        n_c, dof = scene.n_contacts, scene.dof
        plain = solve(scene, search="all", workers=1, keep_statuses=True)
        status = dict(zip((m.letters for m in enumerate_modes(n_c, dof)), plain.statuses))
        rs = screen.ReducedScene(scene, DEFAULT_TOLERANCES)
        for B in all_breaking_sets(n_c, dof):
            B = np.array(B, dtype=np.intp)
            A = np.setdiff1d(np.arange(n_c), B)
            P = combinations_array(A.size, dof - A.size)
            for verdict, positions in zip(screen.screen_set(rs, B, A, P), P):
                if verdict == screen.KINEMATIC:
                    letters = np.full(n_c, "S")
                    letters[B], letters[A[positions]] = "B", "R"
                    assert status["".join(letters)] in (Status.BREAKING_VIOLATED, Status.KINEMATICS_SINGULAR)
                    flagged += 1
    assert flagged > 500


#: ``tau`` (eq. 27) and the residuals come from matrix products whose last bit may depend on how many
#: modes numpy multiplies at once (search.TWICE_BELOW); everything solved per mode is compared bit for bit.
PRODUCT_RTOL = 1e-12


def _assert_same_solutions(got, want):
    assert [s.mode for s in got] == [s.mode for s in want]
    for a, b in zip(got, want):
        for field in ("qdot", "thetadot", "c_n", "c_t", "xi"):
            assert np.array_equal(getattr(a, field), getattr(b, field)), field
        assert a.on_boundary == b.on_boundary
        np.testing.assert_allclose(a.tau, b.tau, rtol=PRODUCT_RTOL, atol=PRODUCT_RTOL * np.abs(b.tau).max())
        assert a.residuals.keys() == b.residuals.keys()


def _plain_batch(letters, batch=DEFAULT_BATCH):
    """The letter codes of the batch that ``solve(search="all")`` tests mode ``letters`` in."""
    n_c = len(letters)
    R = [i for i, c in enumerate(letters) if c == "R"]
    S = [i for i, c in enumerate(letters) if c == "S"]
    rolling, sliding = combinations_array(n_c, len(R)), combinations_array(n_c - len(R), len(S))
    rest = [i for i in range(n_c) if i not in R]
    r_at = next(i for i, row in enumerate(rolling) if list(row) == R)
    s_at = next(i for i, row in enumerate(sliding) if [rest[j] for j in row] == S)
    per_r = sliding.shape[0]
    if per_r <= batch:  # several rolling sets a batch
        lo = r_at // (batch // per_r) * (batch // per_r)
        pieces = [(r, s) for r in rolling[lo : lo + batch // per_r] for s in sliding]
    else:
        lo = s_at // batch * batch
        pieces = [(rolling[r_at], s) for s in sliding[lo : lo + batch]]
    codes = np.zeros((len(pieces), n_c), dtype=np.uint8)
    for k, (r, s) in enumerate(pieces):
        others = [i for i in range(n_c) if i not in r]
        codes[k, list(r)] = 1
        codes[k, [others[j] for j in s]] = 2
    return codes


@pytest.mark.parametrize("n_c, n_e, seed", [
    (12, 9, 0), (12, 9, 7),
    # the same comparison on larger scenes (2-4 s each): in the slow run
    pytest.param(13, 10, 1, marks=pytest.mark.slow), pytest.param(14, 5, 1, marks=pytest.mark.slow),
    pytest.param(13, 13, 1, marks=pytest.mark.slow),
])  # fmt: skip
def test_pruned_solutions_are_the_plain_paths(n_c, n_e, seed):
    """Each feasible mode's solution equals the one the plain path computes in the batch it tests that mode in."""
    scene, planted = _planted(seed, n_c, n_e)
    for search_ in ("auto", "prune"):
        result = solve(scene, search=search_, workers=1)
        assert planted.letters in result.feasible_modes
        for sol in result.solutions:
            _, found = solve_batch(scene, _plain_batch(sol.mode.letters))
            _assert_same_solutions([sol], [f for f in found if f.mode.letters == sol.mode.letters])


@pytest.mark.parametrize("n_c, n_e", [(9, 6), (10, 7), (11, 8), (10, 2), (9, 9)])
def test_pruned_search_matches_the_plain_path(n_c, n_e):
    for seed in range(3):
        scene, _ = _planted(seed, n_c, n_e)
        plain = solve(scene, search="all", workers=1)
        for search_ in ("auto", "prune"):
            pruned = solve(scene, search=search_, workers=1)
            _assert_same_solutions(pruned.solutions, plain.solutions)
            assert sum(pruned.counts.values()) == plain.modes_tested  # eq. (49)
            assert pruned.counts[Status.FEASIBLE] == plain.counts[Status.FEASIBLE]
            for status in Status.ORDER:  # the tested modes keep their plain status; the others were all rejected
                assert pruned.counts[status] <= plain.counts[status]


@needs_kernel
@pytest.mark.parametrize("n_c, n_e, seed", [(12, 9, 7), (14, 11, 0), (13, 4, 1)])
def test_numpy_fallback_gives_the_same_result(monkeypatch, n_c, n_e, seed):
    """Without the compiled kernel (a build without a C compiler): the same solutions and counts."""
    scene, _ = _planted(seed, n_c, n_e)
    fast = solve(scene, search="prune", workers=1)
    monkeypatch.setattr(screen, "KERNEL", False)
    monkeypatch.setattr(search, "KERNEL", False)
    slow = solve(scene, search="prune", workers=1)
    assert first_difference(fast, slow) is None  # solutions, counts and all


def test_threads_do_not_change_the_result():
    scene, planted = planted_scene(np.random.default_rng([1995, 15, 12]), 15, 12)
    one = solve(scene, search="prune", workers=1)
    assert planted.letters in one.feasible_modes
    assert first_difference(solve(scene, search="prune", workers=2), one) is None
    everything = search.search_solve(scene, workers=2, sets=all_breaking_sets(15, scene.dof))
    _assert_same_solutions(everything.solutions, one.solutions)


def test_witnesses_keep_every_set_that_admits_equilibrium():
    for n_c, n_e in [(10, 7), (12, 9), (12, 4)]:
        for seed in range(2):
            scene, _ = _planted(seed, n_c, n_e)
            exact, solved = feasible_breaking_sets(scene)
            kept, fewer = feasible_breaking_sets(scene, witnesses=True)
            assert set(exact) <= set(kept) and fewer <= solved


def test_breaking_set_programmes_stream_their_levels():
    scene, _ = _planted(0, 12, 9)
    levels = []
    sets, _ = feasible_breaking_sets(scene, witnesses=True, on_level=levels.append)
    assert [B for level in levels for B in level] == sets


def test_all_breaking_sets_partition_the_modes():
    for n_c, dof in [(7, 6), (8, 3), (6, 9)]:
        sets = list(all_breaking_sets(n_c, dof))
        assert len(sets) == len(set(sets))
        assert sum(comb(n_c - len(B), len(B) + dof - n_c) for B in sets) == len(enumerate_modes(n_c, dof))


@needs_kernel
def test_kernel_refuses_arrays_of_the_wrong_size():
    rs = screen.ReducedScene(_planted(0, 5, 2)[0], DEFAULT_TOLERANCES)
    masks = np.zeros((1, 5), dtype=np.uint8)
    with pytest.raises(ValueError, match="arrays of the wrong size"):
        screen.compiled_screen(rs.M, rs.drive, rs.E, rs.rhs, rs.mu, masks, 6, rs.dof, 1e-6, 1e-6, 1e-6, 1e-8, True)
    assert screen.compiled_screen(rs.M, rs.drive, rs.E, rs.rhs, rs.mu, masks[:0], 5, rs.dof, 1e-6, 1e-6, 1e-6, 1e-8,
                                  True) == (b"", 0, 0, 0)  # fmt: skip


def test_kept_codes_are_modes_of_the_sets():
    scene, _ = _planted(2, 8, 5)
    sets = list(combinations(range(8), 3))[:20]
    codes, n_kin, n_coul, total = screen.screen_sets(screen.ReducedScene(scene, DEFAULT_TOLERANCES), _masks(sets, 8))
    assert codes.shape[0] + n_kin + n_coul == total == sum(comb(5, 3 + scene.dof - 8) for _ in sets)
    for row in codes:
        letters = codes_to_letters(row)
        assert tuple(i for i, c in enumerate(letters) if c == "B") in sets
        assert np.array_equal(letters_to_codes(letters), row)
