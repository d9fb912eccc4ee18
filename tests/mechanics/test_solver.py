"""The all-modes solver against the paper, closed forms, the one-mode reference and the full model."""

import numpy as np
import pytest

from qsplan.hands.examples.paper import eq37_scene, eq42_scene, rod_scene
from qsplan.mechanics import (
    ContactMode,
    Status,
    check_mode,
    enumerate_modes,
    make_scene,
    model_residuals,
    planted_scene,
    scene_from_dict,
    solve,
)
from qsplan.mechanics.muspace.maps import feasibility_map

RESIDUAL_TOL = 1e-9  # the acceptance bound on eqs. 2-11


def _random_scenes(n, seed, n_effort_max=3, contacts=(3, 7)):
    rng = np.random.default_rng(seed)
    for _ in range(n):
        nc = int(rng.integers(*contacts))
        ne = int(rng.integers(0, min(n_effort_max, 2 * nc - 3) + 1))
        ne = min(ne, 2 * nc - 3)
        yield planted_scene(rng, nc, ne)


# --- the paper's examples, sampled over mu-space -------------------------------------------


def _names(mm):
    return sorted({mm.modes[j].name for j in np.flatnonzero(mm.feasible.any(axis=0))})


def test_eq37_only_3S_and_R1S2_with_jams():
    scene = scene_from_dict(eq37_scene())
    rng = np.random.default_rng(37)
    mm = feasibility_map(scene, rng.uniform(0, 2, size=(20_000, 3)))
    assert _names(mm) == ["3S", "R1S2"]
    assert mm.jammed.mean() > 0.05  # "Jam" regions (Fig. 3)


def test_eq37_3S_shrinks_with_mu3_R1S2_unchanged():
    scene = scene_from_dict(eq37_scene())
    rng = np.random.default_rng(3)
    pts = rng.uniform(0, 2, size=(5000, 3))
    areas = []
    for mu3 in (0.0, 0.5, 1.0, 2.0):
        pts[:, 2] = mu3
        mm = feasibility_map(scene, pts)
        names = [m.name for m in mm.modes]
        areas.append((mm.feasible[:, names.index("3S")], mm.feasible[:, names.index("R1S2")]))
    for (s_lo, r_lo), (s_hi, r_hi) in zip(areas, areas[1:]):
        assert np.all(s_hi <= s_lo) and s_hi.sum() < s_lo.sum()  # 3S region shrinks (nested)
        assert np.array_equal(r_lo, r_hi)  # R1S2 independent of mu3


def test_eq42_exactly_four_modes_three_at_once_none_near_origin():
    scene = scene_from_dict(eq42_scene())
    rng = np.random.default_rng(42)
    mm = feasibility_map(scene, rng.uniform(0, 1.5, size=(20_000, 3)))
    assert _names(mm) == sorted(["3S", "R1S3", "R2S1", "R3S1"])
    counts = mm.feasible.sum(axis=1)
    assert counts.max() == 3 and (counts == 3).mean() > 0.3  # three at once over large regions
    near = feasibility_map(scene, rng.uniform(0, 0.08, size=(2000, 3)))
    assert near.jammed.all()  # friction is needed to maintain equilibrium


@pytest.mark.parametrize("l1,l2", [(1.0, 0.6), (0.3, 0.9), (0.5, 0.5)])
def test_rod_R2S1_exactly_when_l1mu2_ge_l2mu1(l1, l2):
    scene = scene_from_dict(rod_scene(l1=l1, l2=l2))
    rng = np.random.default_rng(7)
    mu = rng.uniform(0, 1, size=(5000, 2))
    mu[:50, 1] = mu[:50, 0] * l2 / l1  # points exactly on the line: both RS modes (paper: "above or on")
    mm = feasibility_map(scene, mu)
    names = [m.name for m in mm.modes]
    r2s1, r1s2 = mm.feasible[:, names.index("R2S1")], mm.feasible[:, names.index("R1S2")]
    line = l1 * mu[:, 1] - l2 * mu[:, 0]
    assert np.array_equal(r2s1[50:], line[50:] > 0)
    assert np.array_equal(r1s2[50:], line[50:] < 0)
    assert r2s1[:50].all() and r1s2[:50].all() and mm.boundary[:50].any()
    assert _names(mm) == ["R1S2", "R2S1"]  # 2S, 2R and breaking modes never


def test_rod_forces_closed_form():
    l1, l2, w, mu1, mu2 = 0.7, 0.4, 2.0, 0.5, 0.2
    res = solve(scene_from_dict(rod_scene(l1=l1, l2=l2, mu=(mu1, mu2), weight=w)))
    sol = res.solution("RS")  # R1S2: contact 1 rolls with support 1, contact 2 slides
    assert sol is not None and l1 * mu2 < l2 * mu1
    np.testing.assert_allclose(sol.c_n, [w * l2 / (l1 + l2), w * l1 / (l1 + l2)], rtol=1e-12)
    np.testing.assert_allclose(sol.c_t, [-mu2 * w * l1 / (l1 + l2), mu2 * w * l1 / (l1 + l2)], rtol=1e-12)
    np.testing.assert_allclose(sol.qdot, [0.1, 0.0, 0.0], atol=1e-15)  # the rod moves with support 1
    assert list(sol.xi) == [0, -1]


# --- against the reference, the full model, and invariances --------------------------------


def test_vectorized_matches_reference_mode_by_mode():
    n_checked = 0
    for scene, _ in _random_scenes(60, seed=11):
        res = solve(scene, keep_statuses=True, batch=17)  # small batches exercise the batching
        modes = enumerate_modes(scene.n_contacts, scene.dof)
        for mode, status in zip(modes, res.statuses):
            ref = check_mode(scene, mode)
            assert ref.status == status, (mode.letters, ref.status, status)
            if ref.feasible:
                got = res.solution(mode.letters)
                for f in ("qdot", "thetadot", "c_n", "c_t", "tau"):
                    np.testing.assert_allclose(getattr(got, f), getattr(ref.solution, f), atol=1e-10, rtol=1e-9)
                np.testing.assert_array_equal(got.xi, ref.solution.xi)
            n_checked += 1
    assert n_checked > 1000


@pytest.mark.parametrize("n_effort", [0, 1, 2, 3])
def test_planted_mode_found_and_every_solution_satisfies_the_full_model(n_effort):
    rng = np.random.default_rng(100 + n_effort)
    worst = 0.0
    for _ in range(40):
        nc = int(rng.integers(max(3, (3 + n_effort + 1) // 2), 8))
        scene, planted = planted_scene(rng, nc, n_effort)
        res = solve(scene)
        assert planted.letters in res.feasible_modes
        for sol in res.solutions:
            r = model_residuals(scene, sol)
            assert r == sol.residuals
            worst = max(worst, max(r.values()))
    assert worst < RESIDUAL_TOL


def test_results_invariant_under_moving_the_world_origin():
    rng = np.random.default_rng(5)
    for scene, _ in _random_scenes(30, seed=5):
        origin = rng.uniform(-3, 3, size=2)
        a, b = solve(scene), solve(scene.moved_origin(origin))
        assert a.feasible_modes == b.feasible_modes and a.counts == b.counts
        for sa, sb in zip(a.solutions, b.solutions):
            for f in ("thetadot", "c_n", "c_t", "tau"):
                np.testing.assert_allclose(getattr(sa, f), getattr(sb, f), atol=1e-9)
            # qdot: same angular velocity; linear velocity is that of the point at the new origin
            w = sa.qdot[2]
            np.testing.assert_allclose(sb.qdot, [sa.qdot[0] - w * origin[1], sa.qdot[1] + w * origin[0], w], atol=1e-9)


def test_mirror_symmetry_of_the_rod():
    # swapping the supports (mirror x -> -x) swaps the modes
    a = solve(scene_from_dict(rod_scene(l1=0.8, l2=0.5, mu=(0.4, 0.2))))
    b = solve(scene_from_dict(rod_scene(l1=0.5, l2=0.8, mu=(0.2, 0.4))))
    assert a.feasible_modes == ["RS"] and b.feasible_modes == ["SR"]
    np.testing.assert_allclose(a.solutions[0].c_n, b.solutions[0].c_n[::-1])


# --- degenerate cases: reported and counted, never feasible --------------------------------


def _two_contact_scene(**kw):
    base = dict(
        Wn=[[0, 0], [1, 1], [-1, 1]], Wt=[[-1, -1], [0, 0], [0, 0]],
        Jn=[[0.0], [0.0]], Jt=[[-0.1], [0.1]], mu=[0.3, 0.3], g_obj=[0, -1, 0], joint_velocity=[1.0],
    )  # fmt: skip
    base.update(kw)
    return make_scene(**base)


def test_zero_sliding_speed_is_degenerate_not_feasible():
    # supports not moving: no sliding direction is defined for the sliding contact
    scene = _two_contact_scene(Jt=[[0.0], [0.0]])
    res = solve(scene)
    assert res.no_feasible_mode and res.counts[Status.ZERO_SLIDING_SPEED] == 2 and res.degenerate == 2
    assert not res.jammed  # undecided modes: not a proven jam (one definition for text and JSON)


def test_coincident_contacts_make_kinematics_singular():
    # both contacts at the same point with the same normal: W_A has rank < 3 (eq. 30)
    scene = _two_contact_scene(Wn=[[0, 0], [1, 1], [0, 0]], Wt=[[-1, -1], [0, 0], [0, 0]])
    res = solve(scene)
    assert res.counts[Status.KINEMATICS_SINGULAR] == 2 and res.no_feasible_mode and not res.jammed


def test_breaking_contact_that_does_not_separate_is_degenerate():
    # three contacts; contact 3 duplicates contact 2's normal row but moves with it: v_n = 0 exactly
    scene = make_scene(
        Wn=[[0, 0, 0], [1, 1, 1], [-1, 1, 1]], Wt=[[-1, -1, -1], [0, 0, 0], [0, 0, 1]],
        Jn=[[0.0], [0.0], [0.0]], Jt=[[-0.1], [0.1], [0.3]], mu=[0.3, 0.3, 0.3], g_obj=[0, -1, 0],
        joint_velocity=[1.0],
    )  # fmt: skip
    res = solve(scene, keep_statuses=True)
    modes = [m.letters for m in enumerate_modes(3, 3)]
    assert res.statuses[modes.index("RSB")] == Status.BREAKING_ZERO_SPEED
    assert "RSB" not in res.feasible_modes


def test_singular_equilibrium_is_degenerate():
    # 3S where the three friction-cone edges meet in a point: W_Amu singular (eq. 31) though W_A is not
    n = np.array([[0.0, 1.0], [np.sin(2.0), np.cos(2.0)], [np.sin(-2.0), np.cos(-2.0)]])
    r = np.array([[0.0, -1.0], -n[1], -n[2]])
    from qsplan.mechanics import wrench_matrices

    Wn, Wt = wrench_matrices(r, n)  # normals all through the origin
    scene = make_scene(Wn, Wt, [[0.0], [0.0], [0.0]], [[1.0], [1.0], [1.0]], [0.0, 0.0, 0.0], [0, 0, 1.0], joint_velocity=[1.0])
    res = solve(scene, keep_statuses=True)
    assert res.statuses[0] in (Status.KINEMATICS_SINGULAR, Status.EQUILIBRIUM_SINGULAR)
    assert res.statuses[0] in Status.DEGENERATE and "SSS" not in res.feasible_modes


def test_solution_values_frozen():
    scene, _ = planted_scene(np.random.default_rng(0), 3, 0)
    with pytest.raises(ValueError):
        scene.Wn[0, 0] = 1.0
    with pytest.raises(AttributeError):
        scene.mu = np.zeros(3)


def test_mode_must_fit_the_partition():
    scene, _ = planted_scene(np.random.default_rng(0), 4, 1)
    with pytest.raises(ValueError, match="applicable constraints"):
        check_mode(scene, ContactMode("SSSB"))


def test_frictionless_rolling_contact_cannot_pull():
    # eq. (9): c_n >= 0 at a rolling contact even when mu = 0 (the cone rows of eq. 7 then say only c_t = 0).
    # Block on a floor, weight outside the supports: RS would need the floor to pull (c_n1 = -0.5).
    from qsplan.mechanics import wrench_matrices
    from qsplan.mechanics.muspace.appendices import region_rs

    Wn, Wt = wrench_matrices([[-1, 0], [1, 0]], [[0, 1], [0, 1]])
    scene = make_scene(Wn, Wt, [[0.0], [0.0]], [[-1.0], [0.0]], [0.0, 0.0], [0, -1, -2], joint_velocity=[1.0])
    res = solve(scene, keep_statuses=True)
    assert "RS" not in res.feasible_modes
    assert check_mode(scene, ContactMode("RS")).status == Status.COULOMB_VIOLATED
    assert not region_rs(scene, "RS").contains(np.array([[0.0, 0.0]]))[0]
    mm = feasibility_map(scene, [[0.0, 0.0], [0.0, 0.3]])
    names = [m.letters for m in mm.modes]
    assert not mm.feasible[0, names.index("RS")]


def test_text_and_json_share_one_definition_of_jammed():
    from qsplan.planner.reports.solve_report import format_solve_result, solve_result_to_dict

    undecided = solve(_two_contact_scene(Jt=[[0.0], [0.0]]))  # no feasible mode, two undecided
    doc, text = solve_result_to_dict(undecided), format_solve_result(undecided)
    assert doc["jammed"] is False and doc["no_feasible_mode"] is True and doc["undecided"] == 2
    assert "not a proven jam" in text and "the scene jams" not in text
    proven = solve(scene_from_dict(eq42_scene(mu=0.1)))  # eq. (42) at mu = 0.1 jams
    assert proven.jammed and proven.degenerate == 0
    assert solve_result_to_dict(proven)["jammed"] is True and "the scene jams" in format_solve_result(proven)
