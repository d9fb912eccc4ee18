"""The pruned mode search against the plain batch solve (every mode tested) and the one-mode reference."""

import json
from itertools import combinations

import numpy as np
import pytest

from qsplan.hands.examples.paper import eq37_scene, eq42_scene, rod_scene
from qsplan.mechanics import ContactMode, QsplanError, check_mode, count_modes, make_scene, planted_scene, scene_from_dict, solve
from qsplan.mechanics.solver.breaking_sets import _Programme, equilibrium_relaxation, feasible_breaking_sets
from qsplan.mechanics.solver.search import PRUNED, PRUNED_KINEMATIC, codes_with_breaking_sets
from qsplan.mechanics.modes.contact_mode import codes_to_letters, enumerate_modes, mode_order_key
from qsplan.mechanics.numerics import DEFAULT_TOLERANCES, Status

SOLUTION_TOL = 1e-12  # both paths solve the same matrices: only the batch composition differs


def _assert_same(scene, workers=1):
    """Pruned and plain results agree mode by mode; returns the pruned result."""
    plain = solve(scene, search="all", workers=1, keep_statuses=True)
    pruned = solve(scene, search="prune", workers=workers)
    assert pruned.feasible_modes == plain.feasible_modes
    for a, b in zip(pruned.solutions, plain.solutions):
        for f in ("qdot", "thetadot", "c_n", "c_t", "tau"):
            np.testing.assert_allclose(getattr(a, f), getattr(b, f), rtol=0, atol=SOLUTION_TOL * (1 + np.abs(getattr(b, f)).max()))
        assert a.on_boundary == b.on_boundary
    total = count_modes(scene.n_contacts, scene.dof)
    assert pruned.modes_tested == total and sum(pruned.counts.values()) == total  # eq. (49)
    # every tested mode keeps the plain status; the pruned ones were all infeasible there
    for status in Status.ORDER:
        assert pruned.counts[status] <= plain.counts[status]
    assert pruned.counts[Status.FEASIBLE] == plain.counts[Status.FEASIBLE]
    pruned_kin = plain.counts[Status.BREAKING_VIOLATED] - pruned.counts[Status.BREAKING_VIOLATED]
    assert pruned.counts[PRUNED_KINEMATIC] <= pruned_kin + plain.counts[Status.KINEMATICS_SINGULAR]
    return pruned, plain


def _planted(seed, n_c, n_e):
    return planted_scene(np.random.default_rng([seed, n_c, n_e]), n_c, n_e)


@pytest.mark.parametrize("n_c", range(3, 11))
def test_pruned_search_matches_the_plain_solve_on_planted_scenes(n_c):
    for n_e in sorted({0, max(0, n_c - 3), min(2 * n_c - 3, n_c)}):
        for seed in range(3):
            scene, planted = _planted(seed, n_c, n_e)
            pruned, _ = _assert_same(scene)
            assert planted.letters in pruned.feasible_modes


def test_pruned_search_matches_on_n12_and_prunes_most_modes():
    scene, planted = _planted(7, 12, 9)
    pruned, plain = _assert_same(scene, workers=2)
    assert planted.letters in pruned.feasible_modes
    assert pruned.counts[PRUNED] > 0.5 * pruned.modes_tested  # the point of the search
    for s in pruned.solutions:
        assert check_mode(scene, s.mode).feasible


@pytest.mark.parametrize("mu", [0.1, 0.3, 0.7])
def test_paper_examples(mu):
    for doc in (eq37_scene(mu), eq42_scene(mu), rod_scene(mu=(mu, 0.5 * mu))):
        _assert_same(scene_from_dict(doc))


def test_two_finger_hand_scenes():
    from qsplan.hands.paper_hand.segments import first_segment
    from qsplan.hands.paper_hand.two_finger import default_hand
    from qsplan.hands.paper_hand.scene import hand_scene

    hand = default_hand()
    segment = first_segment(hand, duration=10.0)
    for s in (0.0, 0.5, 1.0):
        for effort_joint in ("left", "right"):
            scene = hand_scene(hand, segment.pose(s)[0], effort_joint=effort_joint, velocity=0.1, effort=0.05)
            _assert_same(scene)


def test_degenerate_scenes_are_never_pruned_into_feasible():
    # two supports that do not move (zero sliding speed) and coincident contacts (singular P_AI)
    base = dict(
        Wn=[[0, 0], [1, 1], [-1, 1]], Wt=[[-1, -1], [0, 0], [0, 0]],
        Jn=[[0.0], [0.0]], Jt=[[-0.1], [0.1]], mu=[0.3, 0.3], g_obj=[0, -1, 0], joint_velocity=[1.0],
    )  # fmt: skip
    for kw in ({}, {"Jt": [[0.0], [0.0]]}, {"Wn": [[0, 0], [1, 1], [0, 0]]}):
        _assert_same(make_scene(**{**base, **kw}))


def test_zero_loads_prune_nothing():
    scene, _ = _planted(1, 6, 2)
    free = make_scene(scene.Wn, scene.Wt, scene.Jn, scene.Jt, scene.mu, np.zeros(3), g_man=np.zeros(scene.n_joints),
                      effort_controlled=scene.effort_controlled, joint_velocity=scene.joint_velocity,
                      joint_effort=np.where(scene.effort_controlled, 0.0, np.nan))  # fmt: skip
    pruned, _ = _assert_same(free)
    assert pruned.counts[PRUNED] == 0


def test_breaking_sets_partition_the_modes_in_enumeration_order():
    n_c, dof = 7, 6
    all_sets = [B for b in range(n_c + 1) for B in combinations(range(n_c), b)]
    codes = codes_with_breaking_sets(n_c, dof, all_sets)
    letters = sorted((codes_to_letters(c) for c in codes), key=mode_order_key)
    assert letters == [m.letters for m in enumerate_modes(n_c, dof)]


def test_pruned_breaking_sets_are_monotone_and_checked_by_both_programmes():
    scene, _ = _planted(3, 8, 4)
    rel = equilibrium_relaxation(scene, DEFAULT_TOLERANCES)
    fast, slow = _Programme(rel), _Programme(rel)
    slow.highs = None  # scipy.optimize.linprog path
    sets = [B for b in range(5) for B in combinations(range(8), b)]
    verdict = {B: fast(B) for B in sets}
    assert verdict == {B: slow(B) for B in sets}
    assert not all(verdict.values())  # something is pruned on this scene
    for B, ok in verdict.items():  # a superset of an infeasible set is infeasible
        if not ok:
            assert not any(verdict.get(tuple(sorted(B + (i,)))) for i in range(8) if i not in B)
    found, _ = feasible_breaking_sets(scene)
    assert set(found) == {B for B, ok in verdict.items() if ok and len(B) >= max(0, 8 - scene.dof)}


def test_bad_search_argument():
    scene, _ = _planted(0, 3, 0)
    with pytest.raises(QsplanError, match="search"):
        solve(scene, search="fast")


def test_cli_stats_and_search(tmp_path, capsys):
    from qsplan.mechanics.model.scene_io_write import scene_to_dict
    from qsplan.planner.cli.main import main

    scene, planted = _planted(5, 9, 6)
    path = tmp_path / "s.json"
    path.write_text(json.dumps(scene_to_dict(scene)))
    docs = {}
    for search in ("all", "prune"):
        assert main(["modes", str(path), "--json", "--stats", "--workers", "1", "--search", search]) == 0
        out, err = capsys.readouterr()
        docs[search] = json.loads(out)
        assert "peak memory" in err and "tested" in err and "\n" == err[-1] and err.count("\n") == 1
    assert [f["mode"] for f in docs["all"]["feasible"]] == [f["mode"] for f in docs["prune"]["feasible"]]
    assert planted.letters in [f["mode"] for f in docs["prune"]["feasible"]]
    assert main(["modes", str(path), "--search", "fast"]) == 2
    assert "--search" in capsys.readouterr().err


def test_reduced_penetration_flags_only_modes_the_reference_rejects():
    from qsplan.mechanics.modes.kinematics import ScenePool, velocity_scale
    from qsplan.mechanics.solver.search import PENETRATION_MARGIN, _codes, _rolling_sets, penetrates

    flagged_any = 0
    for seed in range(4):
        scene, _ = _planted(seed, 8, 5)
        n_c, dof = scene.n_contacts, scene.dof
        letters = [m.letters for m in enumerate_modes(n_c, dof)]
        status = dict(zip(letters, solve(scene, search="all", workers=1, keep_statuses=True).statuses))
        pool = ScenePool(scene)
        for b in range(n_c + 1):
            for B in combinations(range(n_c), b):
                if not 0 <= b + dof - n_c <= n_c - b:
                    continue
                A, R = _rolling_sets(n_c, dof, B)
                flags = penetrates(pool, np.array(B, dtype=np.intp), A, R, PENETRATION_MARGIN * velocity_scale(scene))
                for code, flag in zip(_codes(n_c, A, R), flags):
                    if flag:
                        flagged_any += 1
                        assert status[codes_to_letters(code)] in (Status.BREAKING_VIOLATED, Status.KINEMATICS_SINGULAR)
    assert flagged_any > 100


@pytest.mark.slow
def test_n16_planted_scene_same_set_as_the_plain_path():
    # 5,196,627 modes; the plain path takes ~15 s on 2 cores, the pruned search ~0.5 s
    scene, planted = planted_scene(np.random.default_rng([1995, 16, 13]), 16, 13, 15,
                                   mode=ContactMode("RRSRBSRSSBSSBBSS"))  # fmt: skip
    pruned = solve(scene, search="prune", workers=2)
    plain = solve(scene, search="all", workers=2)
    assert pruned.feasible_modes == plain.feasible_modes and planted.letters in pruned.feasible_modes
    assert sum(pruned.counts.values()) == pruned.modes_tested == 5_196_627
    assert pruned.counts[PRUNED] + pruned.counts[PRUNED_KINEMATIC] > 0.99 * pruned.modes_tested


# --- the choice of search (issue 12: a collapse on the default path) ---------------------------


def test_auto_gives_up_pruning_when_breaking_sets_are_large(monkeypatch):
    """One effort joint: breaking sets of >= 22 of 26 contacts, where the unbounded Apriori climb took > 120 s and
    418 MB.  ``auto`` climbs on a budget of programmes, gives up within it, and tests every mode (counted, not
    timed)."""
    from qsplan.mechanics.solver import search

    climbs = []
    climb = search.feasible_breaking_sets

    def counted(*args, **kwargs):
        sets, programmes = climb(*args, **kwargs)
        climbs.append((kwargs.get("max_programmes"), sets is None, programmes))
        return sets, programmes

    monkeypatch.setattr(search, "feasible_breaking_sets", counted)
    scene, planted = planted_scene(np.random.default_rng([1995, 26, 1]), 26, 1)
    auto = solve(scene, workers=1)
    assert planted.letters in auto.feasible_modes and auto.counts.get(PRUNED, 0) == 0  # every mode tested
    assert len(climbs) == 1
    budget, gave_up, programmes = climbs[0]
    assert budget is not None and gave_up and programmes <= budget


def test_auto_prunes_where_it_pays():
    scene, planted = _planted(7, 12, 9)  # 73,789 modes: screened, programmes or not (few are tested)
    auto = solve(scene, workers=1)
    untested = sum(v for k, v in auto.counts.items() if k.startswith("pruned"))
    assert untested > 0.5 * auto.modes_tested and planted.letters in auto.feasible_modes


def test_explicit_prune_bounds_its_memory(monkeypatch):
    from qsplan.mechanics.solver import breaking_sets

    monkeypatch.setattr(breaking_sets, "MAX_LEVEL_SETS", 300)
    scene, _ = planted_scene(np.random.default_rng([1995, 26, 1]), 26, 1)
    with pytest.raises(QsplanError, match="search: the pruned search would test more than 300 breaking sets of 2 contacts"):
        solve(scene, search="prune", workers=1)


def test_breaking_set_budget_gives_up():
    scene, _ = planted_scene(np.random.default_rng([1995, 26, 1]), 26, 1)
    sets, programmes = feasible_breaking_sets(scene, max_programmes=100)
    assert sets is None and programmes <= 100


def test_long_work_announces_itself_on_stderr(monkeypatch, tmp_path, capsys):
    from qsplan.mechanics.model.scene_io_write import scene_to_dict
    from qsplan.planner.cli import modes
    from qsplan.planner.cli.main import main

    scene, _ = planted_scene(np.random.default_rng([1995, 26, 1]), 26, 1)
    path = tmp_path / "n26.json"
    path.write_text(json.dumps(scene_to_dict(scene)))
    assert main(["modes", str(path), "--json", "--workers", "1"]) == 0
    quiet = capsys.readouterr()
    monkeypatch.setattr(modes, "LONG_WORK_SECONDS", 0.0)
    monkeypatch.setattr(modes, "PROGRESS_SECONDS", 0.0)
    assert main(["modes", str(path), "--json", "--workers", "1"]) == 0
    loud = capsys.readouterr()
    assert quiet.err == "" and json.loads(loud.out) == json.loads(quiet.out)  # stdout unchanged
    lines = loud.err.splitlines()
    assert lines[0].startswith("qsplan modes: 23,075 modes (eq. 49: n_c = 26, 4 constraints per mode)")
    assert any(" of 23,075 modes done (" in line for line in lines[1:])
