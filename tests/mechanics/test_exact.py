"""Exact rational ground truth (qsplan.mechanics.crosscheck.exact) against the float reference check_mode."""

from fractions import Fraction

import numpy as np
import pytest

from qsplan.hands.examples.paper import PAPER_SCENES
from qsplan.mechanics import check_mode, make_scene, planted_scene, scene_from_dict, solve
from qsplan.mechanics.model.contact import wrench_matrices
from qsplan.mechanics.crosscheck.exact import exact_check_mode, exact_feasible_modes, solve_exact
from qsplan.mechanics.modes.contact_mode import ContactMode
from qsplan.mechanics.numerics import Status


@pytest.mark.parametrize("n_c, seed", [(n, s) for n in (3, 4, 5) for s in range(6)])
def test_exact_statuses_agree_with_float_reference(n_c, seed):
    scene, planted = planted_scene(np.random.default_rng([seed, n_c]), n_c, n_effort=n_c - 3, n_joints=n_c - 1)
    exact = exact_feasible_modes(scene)
    assert exact[planted.letters].feasible
    for letters, ex in exact.items():
        fl = check_mode(scene, ContactMode(letters))
        assert ex.status == fl.status, letters
        if ex.feasible:
            np.testing.assert_allclose([float(x) for x in ex.c_n], fl.solution.c_n, rtol=1e-9, atol=1e-12)
            np.testing.assert_allclose([float(x) for x in ex.c_t], fl.solution.c_t, rtol=1e-9, atol=1e-12)
            np.testing.assert_allclose([float(x) for x in ex.qdot], fl.solution.qdot, rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize("name, mu", [("eq37", 0.3), ("eq42", 0.5), ("eq42", 0.1), ("rod", (0.1, 0.5))])
def test_exact_feasible_set_of_paper_scenes(name, mu):
    scene = scene_from_dict(PAPER_SCENES[name](mu=mu))
    exact = [m for m, c in exact_feasible_modes(scene).items() if c.feasible]
    assert exact == solve(scene).feasible_modes


def test_solve_exact_and_exact_singularity():
    A = [[Fraction(1), Fraction(2)], [Fraction(3), Fraction(4)]]
    assert solve_exact(A, [Fraction(5), Fraction(6)]) == [Fraction(-4), Fraction(9, 2)]
    assert solve_exact([[Fraction(1), Fraction(2)], [Fraction(2), Fraction(4)]], [Fraction(1), Fraction(1)]) is None


def test_concurrent_normals_are_exactly_singular():
    # three normal lines through the origin: the 3S kinematics (eq. 24) are exactly singular
    r = np.array([[1.0, 0.0], [0.0, 1.0], [-1.0, -1.0]])
    n = np.array([[-1.0, 0.0], [0.0, -1.0], [1.0, 1.0]])
    Wn, Wt = wrench_matrices(r, n)
    scene = make_scene(Wn, Wt, [[1.0], [0.5], [0.25]], [[0.5], [1.0], [-1.0]], [0.5] * 3, [0.0, -1.0, 0.0],
                       joint_velocity=[1.0])  # fmt: skip
    assert exact_check_mode(scene, ContactMode("SSS")).status == Status.KINEMATICS_SINGULAR
    # a 2^-40 shift of one contact makes it regular, which exact arithmetic sees
    r[2, 0] += 2.0**-40
    Wn, Wt = wrench_matrices(r, n)
    scene = make_scene(Wn, Wt, [[1.0], [0.5], [0.25]], [[0.5], [1.0], [-1.0]], [0.5] * 3, [0.0, -1.0, 0.0],
                       joint_velocity=[1.0])  # fmt: skip
    assert exact_check_mode(scene, ContactMode("SSS")).status != Status.KINEMATICS_SINGULAR


def test_ill_conditioned_verdict_names_measure_and_threshold():
    from qsplan.mechanics.numerics import DEFAULT_TOLERANCES, conditioning_verdict

    r = np.array([[1.0, 0.0], [0.0, 1.0], [-1.0, -1.0]])
    n = np.array([[-1.0, 0.0], [0.0, -1.0], [1.0, 1.0]])
    Wn, Wt = wrench_matrices(r, n)
    scene = make_scene(Wn, Wt, [[1.0], [0.5], [0.25]], [[0.5], [1.0], [-1.0]], [0.5] * 3, [0.0, -1.0, 0.0],
                       joint_velocity=[1.0])  # fmt: skip
    # exactly singular (checked exactly), and the float solver declines it instead of guessing
    assert exact_check_mode(scene, ContactMode("SSS")).status == Status.KINEMATICS_SINGULAR
    assert check_mode(scene, ContactMode("SSS")).ill_conditioned
    verdict = conditioning_verdict(solve(scene).counts)
    assert verdict.startswith("ill-conditioned: 1 mode(s)")
    assert "Hadamard ratio" in verdict and f"{DEFAULT_TOLERANCES.singular:g}" in verdict
    well, _ = planted_scene(np.random.default_rng(3), 4, n_effort=1, n_joints=3)
    assert conditioning_verdict(solve(well).counts) is None
