"""The quasistatic LCP (qsplan.mechanics.crosscheck.lcp): its solutions are the model's, and solve_lcp's mode is feasible."""

import numpy as np
import pytest

from qsplan.hands.examples.paper import PAPER_SCENES
from qsplan.mechanics import planted_scene, scene_from_dict, solve
from qsplan.mechanics.crosscheck.lcp import LcpStatus, quasistatic_lcp, solve_lcp
from qsplan.mechanics.modes.solution import relative_velocity


def lcp_point(scene, sol):
    """The LCP variable ``z`` that a mode solution of the model (eqs. 2-11) corresponds to."""
    M, q, v_scale, f_scale = quasistatic_lcp(scene)
    u = np.concatenate([sol.qdot, sol.thetadot[scene.effort_joints]]) / v_scale
    _, v_t = relative_velocity(scene, sol.qdot, sol.thetadot)
    rolling = np.array([c == "R" for c in sol.mode.letters])
    lam = np.where(rolling, 0.0, np.abs(v_t)) / v_scale  # slip magnitude; a breaking contact's too
    x = np.concatenate([sol.c_n, np.maximum(sol.c_t, 0), np.maximum(-sol.c_t, 0)]) / f_scale
    z = np.concatenate([np.maximum(u, 0), np.maximum(-u, 0), x, lam])
    return M, q, z


def paper_scenes():
    yield "eq37", scene_from_dict(PAPER_SCENES["eq37"](mu=0.3))
    for mu in (0.1, 0.3, 0.8):
        yield f"eq42 mu={mu}", scene_from_dict(PAPER_SCENES["eq42"](mu=mu))
    for mu in ((0.1, 0.5), (0.6, 0.2), (0.3, 0.3)):
        yield f"rod mu={mu}", scene_from_dict(PAPER_SCENES["rod"](mu=mu))


def planted(n_c, seed):
    return planted_scene(np.random.default_rng([seed, n_c]), n_c, n_effort=n_c - 3, n_joints=n_c - 1)


@pytest.mark.parametrize("n_c, seed", [(n, s) for n in (3, 4, 5, 6) for s in range(3)])
def test_every_enumerated_mode_solves_the_lcp(n_c, seed):
    # the derivation, checked the other way: each feasible mode of the enumerative solver is an LCP solution
    scene, _ = planted(n_c, seed)
    result = solve(scene)
    assert result.solutions
    for sol in result.solutions:
        M, q, z = lcp_point(scene, sol)
        w = M @ z + q
        assert np.min(z) >= 0
        assert np.min(w) >= -1e-9, sol.mode.letters
        assert abs(w @ z) <= 1e-9, sol.mode.letters


@pytest.mark.parametrize("name, scene", list(paper_scenes()), ids=[n for n, _ in paper_scenes()])
def test_paper_scenes_lcp_mode_is_enumerated(name, scene):
    enumerated = solve(scene).feasible_modes
    res = solve_lcp(scene)
    if res.solved:
        assert res.mode.letters in enumerated
        assert res.solution.max_residual < 1e-9
    else:
        assert res.mode is None and res.status in vars(LcpStatus).values()


def test_paper_eq42_finds_one_of_the_three_modes():
    # Fig. 6 at mu = 0.5: 3S, R1S3 and R2S1 at once; the LCP returns one of them
    scene = scene_from_dict(PAPER_SCENES["eq42"](mu=0.5))
    res = solve_lcp(scene)
    assert res.solved and res.mode.letters in {"SSS", "RBS", "SRB"}


def test_planted_scenes_lcp_modes_are_in_the_full_set():
    found = in_set = misses = 0
    for n_c in (3, 4, 5, 6, 7):
        for seed in range(12):
            scene, planted_mode = planted(n_c, seed)
            enumerated = solve(scene).feasible_modes
            assert planted_mode.letters in enumerated
            res = solve_lcp(scene)
            if res.solved:
                found += 1
                in_set += res.mode.letters in enumerated
                assert res.solution.max_residual < 1e-8
            else:
                misses += 1  # a mode exists (the planted one) but Lemke's method did not reach it
    assert in_set == found  # a verified mode is always one the enumeration finds
    assert misses <= 0.2 * (found + misses), (found, misses)


def test_jammed_scene_gives_no_mode():
    # eq. (42) at mu = 0.1 jams (no feasible mode); the LCP must not invent one
    scene = scene_from_dict(PAPER_SCENES["eq42"](mu=0.1))
    assert solve(scene).jammed
    res = solve_lcp(scene)
    assert res.mode is None and not res.solved


def test_iteration_cap_reported():
    scene, _ = planted(5, 0)
    res = solve_lcp(scene, max_pivots=1)
    assert res.status == LcpStatus.ITERATION_LIMIT and res.mode is None


def test_cli_modes_method_lcp(tmp_path, capsys):
    import json

    from qsplan.planner.cli.main import main

    path = tmp_path / "eq42.json"
    path.write_text(json.dumps(PAPER_SCENES["eq42"](mu=0.5)))
    assert main(["modes", str(path), "--method", "lcp", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["method"] == "lcp" and doc["status"] == "solved"
    (mode,) = doc["feasible"]
    enumerated = solve(scene_from_dict(PAPER_SCENES["eq42"](mu=0.5))).feasible_modes
    assert mode["mode"] in enumerated
    assert main(["modes", str(path), "--method", "lcp"]) == 0
    assert "verified by check_mode" in capsys.readouterr().out
    assert main(["modes", str(path), "--method", "simplex"]) == 2
    assert "invalid choice" in capsys.readouterr().err
