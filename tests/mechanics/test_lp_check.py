"""The LP force check against the solver's reference (eqs. 2-3, 7-11, 26-28), a closed form, and validation."""

import numpy as np
import pytest

from qsplan.mechanics import ContactMode, ModeError, Status, check_mode, enumerate_modes, make_scene, planted_scene
from qsplan.mechanics.model.contact import wrench_matrices
from qsplan.mechanics.crosscheck.lp_check import LP_TOL, lp_mode_feasible

N_SCENES = 200
BOUNDARY = 1e-7  # |margin| below this: the verdict is a matter of tolerance, skipped and counted
FORCE_TOL = 1e-7  # agreement of LP and solver forces, relative to max(1, load scale)


def _kinematic_xi(scene, mode):
    """Sliding directions (eq. 16) from the mode's kinematic rows (eq. 13), solved by lstsq."""
    E, V = scene.effort_joints, scene.velocity_joints
    rows, rhs = [], []
    for i in mode.rolling:
        for W, J in ((scene.Wn, scene.Jn), (scene.Wt, scene.Jt)):
            rows.append(np.concatenate([W[:, i], -J[i, E]]))
            rhs.append(J[i, V] @ scene.joint_velocity[V])
    for i in mode.sliding:
        rows.append(np.concatenate([scene.Wn[:, i], -scene.Jn[i, E]]))
        rhs.append(scene.Jn[i, V] @ scene.joint_velocity[V])
    z = np.linalg.lstsq(np.array(rows), np.array(rhs), rcond=None)[0]
    thetadot = np.nan_to_num(scene.joint_velocity)
    thetadot[E] = z[3:]
    v_t = scene.Wt.T @ z[:3] - scene.Jt @ thetadot
    xi = np.zeros(scene.n_contacts)
    xi[list(mode.sliding)] = np.sign(v_t[list(mode.sliding)])
    return xi


def _planted(seed):
    rng = np.random.default_rng(seed)
    for _ in range(N_SCENES):
        n_c = int(rng.integers(3, 8))
        n_e = int(rng.integers(0, 4))
        yield planted_scene(rng, n_c, n_e)[0]


def _smallest_slack(scene, mode, c_n, c_t):
    """Smallest slack of the friction inequalities the LP maximises (eqs. 9-10)."""
    mu, out = scene.mu, []
    for i in mode.rolling:
        out += [mu[i] * c_n[i] + c_t[i], mu[i] * c_n[i] - c_t[i]] + ([c_n[i]] if mu[i] == 0 else [])
    out += [c_n[i] for i in mode.sliding]
    return min(out)


@pytest.mark.slow
def test_lp_agrees_with_reference_on_planted_scenes():
    compared = boundary = feasible = 0
    for scene in _planted(1995):
        E = scene.effort_joints
        for mode in enumerate_modes(scene.n_contacts, scene.dof):
            ref = check_mode(scene, mode)
            if ref.status not in (Status.FEASIBLE, Status.COULOMB_VIOLATED):
                continue
            xi = _kinematic_xi(scene, mode)
            if ref.feasible:
                np.testing.assert_array_equal(xi, ref.solution.xi)
            lp = lp_mode_feasible(scene, mode, xi)
            if abs(lp.margin) < BOUNDARY:
                boundary += 1
                continue
            compared += 1
            assert lp.feasible == ref.feasible, (mode.letters, lp.margin, ref.status)
            if not ref.feasible:
                continue
            feasible += 1
            sol, L = ref.solution, lp.scale
            # eqs. (2) and (3), effort-controlled rows, and the mode's force conditions (9)-(11)
            np.testing.assert_allclose(scene.Wn @ lp.c_n + scene.Wt @ lp.c_t, -scene.g_obj, atol=1e-9 * L)
            np.testing.assert_allclose(
                (scene.Jn.T @ lp.c_n + scene.Jt.T @ lp.c_t)[E], (scene.joint_effort - scene.g_man)[E], atol=1e-9 * L
            )
            B, S = list(mode.breaking), list(mode.sliding)
            assert np.all(lp.c_n[B] == 0) and np.all(lp.c_t[B] == 0)
            np.testing.assert_allclose(lp.c_t[S], -scene.mu[S] * xi[S] * lp.c_n[S], atol=1e-12 * L)
            # Q_AI is nonsingular for a feasible mode: the forces are unique and must be the solver's
            atol = FORCE_TOL * max(1.0, L)
            np.testing.assert_allclose(lp.c_n, sol.c_n, atol=atol)
            np.testing.assert_allclose(lp.c_t, sol.c_t, atol=atol)
            expected = min(_smallest_slack(scene, mode, sol.c_n, sol.c_t) / L, 1.0)
            assert lp.margin == pytest.approx(expected, abs=FORCE_TOL)
    assert compared > 1000 and feasible > N_SCENES  # not vacuous: every planted mode is among them
    assert boundary < 0.01 * compared


def test_planted_mode_is_lp_feasible():
    rng = np.random.default_rng(7)
    for _ in range(50):
        scene, mode = planted_scene(rng, int(rng.integers(3, 8)), int(rng.integers(0, 4)))
        lp = lp_mode_feasible(scene, mode, _kinematic_xi(scene, mode))
        assert lp.feasible and lp.margin > 0


# --- a closed form: a block on a floor pushed sideways, every contact sliding ----------------


def _pushed_block(h, mu):
    """Floor contacts at (-1, 0), (1, 0), a frictionless pusher at (-1, h) pushing +x; unit weight.

    All three slide (mode SSS, floor slip in +x).  Equilibrium: pusher force mu, floor normals
    c1 = (1 - h mu) / 2, c2 = (1 + h mu) / 2; the block tips (c1 < 0) when h mu > 1.
    """
    Wn, Wt = wrench_matrices([[-1, 0], [1, 0], [-1, h]], [[0, 1], [0, 1], [1, 0]])
    scene = make_scene(Wn, Wt, np.zeros((3, 1)), np.zeros((3, 1)), [mu, mu, 0.0], [0, -1, 0], joint_velocity=[1.0])
    xi = np.array([np.sign(Wt[0, 0]), np.sign(Wt[0, 1]), 1.0])  # friction on the block points -x
    return scene, xi


@pytest.mark.parametrize("h, mu", [(0.5, 0.5), (1.0, 0.3), (3.0, 0.5), (1.0, 1.2)])
def test_pushed_block_closed_form(h, mu):
    scene, xi = _pushed_block(h, mu)
    lp = lp_mode_feasible(scene, ContactMode("SSS"), xi)
    c_n = np.array([(1 - h * mu) / 2, (1 + h * mu) / 2, mu])
    np.testing.assert_allclose(lp.c_n, c_n, atol=1e-12)
    np.testing.assert_allclose(lp.c_t, -mu * xi * c_n * [1, 1, 0], atol=1e-12)
    assert lp.scale == 1.0
    assert lp.margin == pytest.approx(min(c_n), abs=1e-12)
    assert lp.feasible == (h * mu <= 1)


def test_tipping_point_is_feasible_within_tolerance():
    scene, xi = _pushed_block(2.0, 0.5)  # h mu = 1: c1 = 0, on the boundary
    lp = lp_mode_feasible(scene, "SSS", xi)
    assert abs(lp.margin) <= LP_TOL and lp.feasible


def test_indeterminate_forces_get_the_largest_margin():
    # Two rolling floor contacts and a breaking pusher: 4 unknowns, 3 equations (Q_AI not square).
    scene, _ = _pushed_block(0.5, 0.5)
    lp = lp_mode_feasible(scene, "RRB", np.zeros(3))
    assert lp.feasible
    np.testing.assert_allclose(lp.c_n, [0.5, 0.5, 0.0], atol=1e-12)  # the weight shared evenly, no friction
    assert lp.margin == pytest.approx(0.25)  # mu c_n - |c_t| = 0.5 * 0.5


def test_inconsistent_equalities_are_infeasible():
    scene, _ = _pushed_block(0.5, 0.5)
    lp = lp_mode_feasible(scene, "BBS", np.ones(3))  # a horizontal pusher alone cannot hold the weight
    assert not lp.feasible and lp.margin == -np.inf and lp.c_n is None


def test_frictionless_rolling_contact_must_push():
    # Eq. (9) asks c_n >= 0 at a rolling contact; with mu = 0 the cone rows of eq. (7) no longer imply it.
    # Block on a frictionless floor, weight at x = 2 outside the supports (-1, 0), (1, 0): mode RS needs
    # c_n = (-0.5, 1.5), a pulling floor, so it is infeasible.
    Wn, Wt = wrench_matrices([[-1, 0], [1, 0]], [[0, 1], [0, 1]])
    scene = make_scene(Wn, Wt, np.zeros((2, 1)), np.zeros((2, 1)), [0.0, 0.0], [0, -1, -2], joint_velocity=[1.0])
    lp = lp_mode_feasible(scene, "RS", [0, 1])
    np.testing.assert_allclose(lp.c_n, [-0.5, 1.5], atol=1e-12)
    assert lp.scale == 2.0 and lp.margin == pytest.approx(-0.25) and not lp.feasible


# --- validation --------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "mode, xi, match",
    [
        ("SSSS", np.ones(4), r"mode: expected 3 letters"),
        ("SSS", np.ones(4), r"xi: expected shape \(3,\)"),
        ("SSS", [1.0, 0.0, 1.0], r"xi\[1\]: expected \+1 or -1 at sliding contact 1"),
        ("SSS", [1.0, 0.5, 1.0], r"xi\[1\]: expected \+1 or -1"),
        ("SXS", np.ones(3), r"mode: expected letters R, S or B"),
    ],
)
def test_validation(mode, xi, match):
    scene, _ = _pushed_block(0.5, 0.5)
    with pytest.raises(ModeError, match=match):
        lp_mode_feasible(scene, mode, xi)


def test_negative_tolerance_rejected():
    scene, xi = _pushed_block(0.5, 0.5)
    with pytest.raises(ValueError, match="tol: expected a nonnegative"):
        lp_mode_feasible(scene, "SSS", xi, tol=-1.0)
