"""Contact frames and wrench matrices (eq. 1)."""

import numpy as np
import pytest

from qsplan.mechanics import SceneError, cross2, shift_wrenches, tangent_from_normal, wrench_matrices, wrench_matrix


def test_cross2_is_planar_cross_product():
    assert cross2([1.0, 0.0], [0.0, 1.0]) == 1.0
    assert cross2([0.0, 1.0], [1.0, 0.0]) == -1.0
    rng = np.random.default_rng(0)
    a, b = rng.normal(size=(2, 50, 2))
    full = np.cross(np.c_[a, np.zeros(50)], np.c_[b, np.zeros(50)])[:, 2]
    np.testing.assert_allclose(cross2(a, b), full)


def test_tangent_is_normal_rotated_plus_90_degrees():
    n = np.array([[1.0, 0.0], [0.0, 1.0], [np.sqrt(0.5), np.sqrt(0.5)]])
    t = tangent_from_normal(n)
    np.testing.assert_allclose(t, [[0, 1], [-1, 0], [-np.sqrt(0.5), np.sqrt(0.5)]])
    # n x t points out of the plane (+z)
    assert np.all(cross2(n, t) > 0)


def test_wrench_matrix_hand_computed():
    # Contact at (2, 1) with normal +y: w_n = [0, 1, 2*1 - 1*0] = [0, 1, 2]; t = (-1, 0): w_t = [-1, 0, 2*0 - 1*(-1)] = [-1, 0, 1]
    W = wrench_matrix([2.0, 1.0], [0.0, 3.0])
    np.testing.assert_allclose(W, [[0, -1], [1, 0], [2, 1]])


def test_wrench_rows_give_contact_point_velocity():
    # W_i^T qdot is the velocity of the workpiece point at r in the contact frame (eq. 5).
    rng = np.random.default_rng(1)
    for _ in range(20):
        r, n, qdot = rng.normal(size=2), rng.normal(size=2), rng.normal(size=3)
        W = wrench_matrix(r, n)
        v_point = qdot[:2] + qdot[2] * np.array([-r[1], r[0]])
        nh = n / np.linalg.norm(n)
        np.testing.assert_allclose(W.T @ qdot, [nh @ v_point, tangent_from_normal(nh) @ v_point], atol=1e-12)


def test_shift_wrenches_matches_recomputation_about_new_origin():
    rng = np.random.default_rng(2)
    r, n = rng.normal(size=(5, 2)), rng.normal(size=(5, 2))
    origin = rng.normal(size=2)
    Wn, Wt = wrench_matrices(r, n)
    Wn2, Wt2 = wrench_matrices(r - origin, n)
    np.testing.assert_allclose(shift_wrenches(Wn, origin), Wn2, atol=1e-12)
    np.testing.assert_allclose(shift_wrenches(Wt, origin), Wt2, atol=1e-12)


@pytest.mark.parametrize("n", [[0.0, 0.0], [np.nan, 1.0], [1e-15, 0.0]])
def test_degenerate_normals_rejected(n):
    with pytest.raises(SceneError, match="normal"):
        wrench_matrices([[0.0, 0.0]], [n])
