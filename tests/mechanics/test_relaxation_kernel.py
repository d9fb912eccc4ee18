"""The breaking sets' equilibrium relaxation solved by the compiled kernel (issue 33) against HiGHS, the plain
path (one HiGHS programme per candidate), and the pruned search's solutions against the plain path's."""

from itertools import combinations

import numpy as np
import pytest

from qsplan.mechanics import make_scene, planted_scene
from qsplan.mechanics.numerics import DEFAULT_TOLERANCES
from qsplan.mechanics.parallel import first_difference
from qsplan.mechanics.solver import breaking_sets as bs
from qsplan.mechanics.solver.search import search_solve

needs_relax = pytest.mark.skipif(bs.compiled_relax is None, reason="the compiled kernel is not built")

#: Equilibrium residual and cone violation (units of the largest load) allowed of a force the kernel calls
#: feasible, checked from the relaxation's rows: RELAX_RESIDUAL, the kernel's own acceptance.
FORCE_TOL = bs.RELAX_RESIDUAL


def _planted(seed, n_c, n_e, **kw):
    return planted_scene(np.random.default_rng([seed, n_c, n_e]), n_c, n_e, **kw)[0]


def _scenes():
    """Planted scenes of several shapes, friction above and below 1 (the kernel's two cone forms), zero friction."""
    for n_c, n_e, seed in [(6, 3, 0), (7, 1, 1), (8, 5, 2), (9, 6, 0), (10, 7, 1), (10, 3, 2), (11, 8, 0)]:
        yield _planted(seed, n_c, n_e)
    yield _planted(3, 8, 5, mu_range=(0.9, 1.6))
    yield _planted(4, 7, 4, mu_range=(0.0, 0.0))


def _sets(n_c, cap=400):
    sets = [B for b in range(n_c + 1) for B in combinations(range(n_c), b)]
    if len(sets) > cap:
        pick = np.random.default_rng(n_c).choice(len(sets), cap, replace=False)
        sets = [sets[i] for i in sorted(pick)]
    return sets


@needs_relax
def test_kernel_verdicts_are_highs_verdicts_and_its_forces_balance():
    """Every set the kernel decides, HiGHS (a fresh model each) decides alike where it decides; the kernel's
    forces balance the loads in the widened cones (checked from the rows, not the kernel)."""
    decided = undecided = 0
    for scene in _scenes():
        rel = bs.equilibrium_relaxation(scene, DEFAULT_TOLERANCES)
        sets = _sets(scene.n_contacts)
        fast = bs._decide(rel, sets, compiled=True)
        warm = bs._Programme(rel)
        for B, (ok, force) in zip(sets, fast):
            ref_ok, ref_force = warm.solve(B)
            if ref_ok != ok or (ref_ok and ref_force is None):  # a warm-started HiGHS may stop short: a fresh model
                ref = bs._Programme(rel)
                ref_ok, ref_force = ref.solve(B)
            if ref_force is None and ref_ok:
                undecided += 1  # HiGHS proved nothing either way
                continue
            assert ok == ref_ok, (B, ok, ref_ok)
            decided += 1
            if ok and not rel.trivial:
                assert np.abs(force[[j for i in B for j in (2 * i, 2 * i + 1)]]).max(initial=0.0) == 0.0
                assert np.abs(rel.A_eq @ force - rel.b_eq).max() <= FORCE_TOL
                assert (rel.A_ub @ force - rel.b_ub).max() <= FORCE_TOL
    assert decided > 2000 and undecided <= decided // 100


@needs_relax
def test_kernel_leaves_nothing_to_highs_on_planted_scenes(monkeypatch):
    """The kernel decides the candidates itself, HiGHS being only the fallback (none reach it on these scenes;
    a rounding-sensitive certificate elsewhere may: at most 1 %)."""
    calls, solved = [], 0
    monkeypatch.setattr(bs._Programme, "solve", lambda self, B: calls.append(B) or (True, None))
    for n_c, n_e, seed in [(12, 9, 7), (12, 4, 1), (14, 11, 0)]:
        solved += bs.feasible_breaking_sets(_planted(seed, n_c, n_e), witnesses=True, compiled=True)[1]
    assert solved > 300 and len(calls) <= solved // 100


@pytest.mark.parametrize("witnesses", [False, True])
@pytest.mark.parametrize("n_c, n_e, seed", [(10, 7, 1), (12, 9, 7), (12, 4, 1), (13, 13, 5)])
def test_fast_breaking_sets_keep_what_the_plain_path_keeps(n_c, n_e, seed, witnesses):
    """The plain path (HiGHS, one programme per candidate, no witnesses) against the fast one: the same exact
    sets, and with witnesses a superset of them."""
    scene = _planted(seed, n_c, n_e)
    plain, solved = bs.feasible_breaking_sets(scene, compiled=False)
    fast, programmes = bs.feasible_breaking_sets(scene, compiled=None, witnesses=witnesses)
    if witnesses:
        assert set(plain) <= set(fast) and programmes <= solved
    else:
        assert fast == plain


def _assert_same_search(scene):
    """The pruned search on the fast sets and on the plain path's sets: the same solutions, bit for bit."""
    fast = search_solve(scene, workers=1)
    plain_sets, _ = bs.feasible_breaking_sets(scene, compiled=False)
    plain = search_solve(scene, workers=1, sets=plain_sets)
    assert fast.feasible_modes == plain.feasible_modes
    assert first_difference(fast.solutions, plain.solutions) is None
    return fast


@pytest.mark.parametrize("n_c, n_e, seed", [(11, 8, 0), (12, 9, 7), (13, 4, 1), (13, 13, 5)])
def test_pruned_search_on_fast_sets_finds_the_plain_paths_modes(n_c, n_e, seed):
    _assert_same_search(_planted(seed, n_c, n_e))


@pytest.mark.slow
@pytest.mark.parametrize("n_c, n_e, seed", [(16, 13, 0), (16, 8, 2), (18, 15, 4)])
def test_pruned_search_on_fast_sets_finds_the_plain_paths_modes_larger(n_c, n_e, seed):
    _assert_same_search(_planted(seed, n_c, n_e))


@needs_relax
def test_kernel_on_degenerate_relaxations():
    """Zero loads (every set admits c = 0), a contact with no equilibrium column, zero friction."""
    base = dict(
        Wn=[[0, 0, 0], [1, 1, 1], [-1, 1, 0]], Wt=[[-1, -1, -1], [0, 0, 0], [0, 0, 0]],
        Jn=[[0.0, 0.1], [0.0, 0.2], [0.1, 0.0]], Jt=[[-0.1, 0.0], [0.1, 0.3], [0.2, 0.1]], mu=[0.3, 0.3, 0.5],
        g_obj=[0, -1, 0], joint_velocity=[1.0, np.nan], effort_controlled=[False, True], joint_effort=[np.nan, 0.2],
    )  # fmt: skip
    scenes = [
        make_scene(**base),
        make_scene(**{**base, "g_obj": [0, 0, 0], "joint_effort": [np.nan, 0.0]}),
        make_scene(**{**base, "Wn": [[0, 0, 0], [1, 1, 0], [-1, 1, 0]], "Wt": [[-1, -1, 0], [0, 0, 0], [0, 0, 0]],
                      "Jn": [[0.0, 0.1], [0.0, 0.2], [0.0, 0.0]], "Jt": [[-0.1, 0.0], [0.1, 0.3], [0.0, 0.0]]}),
        make_scene(**{**base, "mu": [0.0, 0.0, 0.0]}),
    ]  # fmt: skip
    for scene in scenes:
        rel = bs.equilibrium_relaxation(scene, DEFAULT_TOLERANCES)
        sets = [B for b in range(4) for B in combinations(range(3), b)]
        fast = [ok for ok, _ in bs._decide(rel, sets, compiled=True)]
        assert fast == [ok for ok, _ in bs._decide(rel, sets, compiled=False)]
        if rel.trivial:
            assert all(fast)


@needs_relax
def test_kernel_refuses_arrays_of_the_wrong_size():
    rel = bs.equilibrium_relaxation(_planted(0, 5, 2), DEFAULT_TOLERANCES)
    c = rel.columns()
    masks = np.zeros((1, 5), dtype=np.uint8)
    args = [c["G"], c["ub"], c["gnorm"], c["owner"], c["dir"], c["shift"], c["base"], c["b"], masks]
    rest = [5, c["G"].shape[1], c["G"].shape[0], 100, 1e-11, 1e-11, 1e-9, 1e-9, 1e9]
    with pytest.raises(ValueError, match="arrays of the wrong size"):
        bs.compiled_relax(*args, 6, *rest[1:])
    status, forces = bs.compiled_relax(*args[:-1], masks[:0], *rest)
    assert status == b"" and forces == b""


@needs_relax
def test_pruned_modes_command_never_imports_highspy_or_scipy(tmp_path):
    """Issue 33: with the kernel built, ``qsplan modes`` prunes without HiGHS (~14 ms of import) or scipy."""
    import json
    import subprocess
    import sys

    from qsplan.mechanics.model.scene_io_write import scene_to_dict

    path = tmp_path / "planted.json"
    path.write_text(json.dumps(scene_to_dict(_planted(7, 12, 9))))
    code = (f"from qsplan.planner.cli.main import main\nassert main(['modes', {str(path)!r}, '--json', '--search', "
            "'prune', '--workers', '1']) == 0\nimport sys\n"
            "print('loaded:', *sorted(m for m in ('highspy', 'scipy') if m in sys.modules))")  # fmt: skip
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.splitlines()[-1] == "loaded:"
