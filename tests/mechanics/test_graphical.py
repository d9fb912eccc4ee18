"""Corollary 1 (Fig. 4): the geometric test agrees with the algebra of Appendices A and B."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from qsplan.hands.examples.paper import eq37_scene, eq42_scene, rod_scene
from qsplan.mechanics import ModeError, QsplanError, enumerate_modes, scene_from_dict, wrench_matrices
from qsplan.mechanics.muspace.graphical import (
    active_wrenches,
    contact_points,
    graphical_test,
    graphical_test_mode,
    line_of_action,
)
from qsplan.mechanics.numerics import Status
from qsplan.mechanics.muspace.appendices import appendix_a, appendix_b, region_3s, region_rs

CONFIGS = 1500


def _config(rng):
    r = rng.uniform(-1, 1, (3, 2))
    th = rng.uniform(0, 2 * np.pi, 3)
    Wn, Wt = wrench_matrices(r, np.column_stack([np.cos(th), np.sin(th)]))
    g = np.r_[rng.normal(size=2), rng.normal()]
    return Wn, Wt, g


def _algebra_3s(Wn, Wt, g, xi, mu):
    """Inequalities (35)-(36) with Appendix A's coefficients; also a margin to skip boundary cases."""
    co = appendix_a(Wn, Wt, g, xi)
    m1, m2, m3 = mu
    D = co.A * m1 * m2 * m3 + co.B[0] * m2 * m3 + co.B[1] * m1 * m3 + co.B[2] * m1 * m2 + co.C @ mu + co.D
    P = np.array([co.E[i] * np.prod(np.delete(mu, i)) + sum(co.F[i, j] * mu[j] for j in range(3) if j != i) + co.G[i]
                  for i in range(3)])  # fmt: skip
    feasible = (D > 0 and np.all(P >= 0)) or (D < 0 and np.all(P <= 0))
    return feasible, min(abs(D), *np.abs(P))


def _algebra_rs(w_rn, w_rt, w_sn, w_st, g, xi_s, mu_r, mu_s):
    """Inequalities (40)-(41) with Appendix B's coefficients."""
    co = appendix_b(w_rn, w_rt, w_sn, w_st, g, xi_s)
    D = co.A * mu_s + co.B
    P = np.array([co.D3, co.C1 * mu_r * mu_s + co.D1 * mu_r - co.C2 * mu_s - co.D2,
                  co.C1 * mu_r * mu_s + co.D1 * mu_r + co.C2 * mu_s + co.D2])  # fmt: skip
    feasible = (D > 0 and np.all(P >= 0)) or (D < 0 and np.all(P <= 0))
    return feasible, min(abs(D), *np.abs(P))


def test_graphical_agrees_with_appendix_a_on_random_3s_configurations():
    rng = np.random.default_rng(10)
    agree = skipped = feasible = 0
    for _ in range(CONFIGS):
        Wn, Wt, g = _config(rng)
        xi, mu = rng.choice([-1.0, 1.0], 3), rng.uniform(0, 1.5, 3)
        alg, margin = _algebra_3s(Wn, Wt, g, xi, mu)
        gt = graphical_test(Wn - Wt * (xi * mu), g)
        if margin < 1e-9 or gt.degenerate:
            skipped += 1
            continue
        assert gt.feasible == alg
        assert not gt.feasible or gt.negative_span  # condition 2 implies condition 1
        agree += 1
        feasible += alg
    assert agree >= 1000 and skipped <= 5 and 50 < feasible < agree - 50, (agree, skipped, feasible)


def test_graphical_agrees_with_appendix_b_on_random_rs_configurations():
    rng = np.random.default_rng(11)
    agree = skipped = feasible = 0
    for _ in range(CONFIGS):
        Wn, Wt, g = _config(rng)
        xi_s, mu_r, mu_s = rng.choice([-1.0, 1.0]), rng.uniform(0.01, 1.5), rng.uniform(0, 1.5)
        alg, margin = _algebra_rs(Wn[:, 0], Wt[:, 0], Wn[:, 1], Wt[:, 1], g, xi_s, mu_r, mu_s)
        W = np.column_stack([Wn[:, 0] + mu_r * Wt[:, 0], Wn[:, 0] - mu_r * Wt[:, 0], Wn[:, 1] - xi_s * mu_s * Wt[:, 1]])
        gt = graphical_test(W, g)
        if margin < 1e-9 or gt.degenerate:
            skipped += 1
            continue
        assert gt.feasible == alg
        # p12, where the rolling contact's two cone edges meet, is the rolling contact
        np.testing.assert_allclose(gt.vertices[0], contact_points_from(Wn[:, 0], Wt[:, 0]), atol=1e-9)
        agree += 1
        feasible += alg
    assert agree >= 1000 and skipped <= 5 and 50 < feasible < agree - 50, (agree, skipped, feasible)


def contact_points_from(wn, wt):
    A = np.array([[wn[1], -wn[0]], [wt[1], -wt[0]]])
    return np.linalg.solve(A, [wn[2], wt[2]])


@settings(max_examples=300, deadline=None, derandomize=True)
@given(
    pts=st.lists(st.floats(-2, 2), min_size=6, max_size=6),
    angles=st.lists(st.floats(0, 2 * np.pi), min_size=3, max_size=3),
    mu=st.lists(st.floats(0, 2), min_size=3, max_size=3),
    xi=st.lists(st.sampled_from([-1.0, 1.0]), min_size=3, max_size=3),
    g=st.lists(st.floats(-3, 3), min_size=3, max_size=3),
)
def test_property_graphical_is_nonnegative_intensities(pts, angles, mu, xi, g):
    """Feasible exactly when W_Amu c = -g has c >= 0 (eq. 26 with B_A = I, eq. 33)."""
    th = np.array(angles)
    Wn, Wt = wrench_matrices(np.reshape(pts, (3, 2)), np.column_stack([np.cos(th), np.sin(th)]))
    W = Wn - Wt * (np.array(xi) * np.array(mu))
    g = np.array(g)
    if np.hypot(g[0], g[1]) < 1e-6 or np.linalg.cond(W) > 1e8:  # (near-)pure moments have no usable line of action
        return
    gt = graphical_test(W, g)
    c = np.linalg.solve(W, -g)
    if gt.degenerate or np.min(np.abs(c)) < 1e-7 * (1 + np.max(np.abs(c))):
        return
    assert gt.feasible == bool(np.all(c >= 0))
    assert gt.moment_sense.tolist() == [bool(c[2] >= 0), bool(c[0] >= 0), bool(c[1] >= 0)]


@pytest.mark.parametrize("example,hi", [(eq37_scene, 2.0), (eq42_scene, 1.5)])
def test_scene_level_graphical_equals_regions(example, hi):
    scene = scene_from_dict(example())
    rng = np.random.default_rng(12)
    checked = 0
    for m in enumerate_modes(3, 3):
        reg = region_3s(scene, m) if m.kind == "3S" else region_rs(scene, m)
        if reg.kinematic_status != Status.FEASIBLE:
            with pytest.raises(ModeError, match="kinematic stage fails"):
                graphical_test_mode(scene, m)
            continue
        for mu in rng.uniform(0.01, hi, size=(150, 3)):
            if reg.near_boundary(mu[None])[0]:
                continue
            assert graphical_test_mode(scene, m, mu).feasible == reg.contains(mu[None])[0], (m, mu)
            checked += 1
    assert checked >= 300


def test_parallel_lines_use_the_point_at_infinity():
    """Two parallel upward supports and a third pushing sideways: vertices at infinity are handled."""
    # columns: force (0, 1) at x = 1, force (0, 1) at x = -2, force (1, 0) at y = 0.5
    W = np.array([[0.0, 0.0, 1.0], [1.0, 1.0, 0.0], [1.0, -2.0, -0.5]])
    feasible = []
    for g in ([-0.5, -1.0, 0.2], [0.5, -1.0, 0.0], [-0.3, -1.0, 3.0], [-0.3, -1.0, -3.0]):
        g = np.array(g)
        c = np.linalg.solve(W, -g)
        gt = graphical_test(W, g)
        assert np.isnan(gt.vertices[0]).all() and not gt.degenerate
        assert gt.feasible == bool(np.all(c >= 0))
        feasible.append(gt.feasible)
    assert feasible == [True, False, False, False]


def test_degenerate_concurrent_lines():
    r = np.array([[1.0, 0.0], [-0.5, 0.8], [-0.5, -0.8]])
    Wn, Wt = wrench_matrices(r, -r)  # all normals through the origin
    assert graphical_test(Wn, np.array([0.0, -1.0, 0.0])).degenerate
    assert not graphical_test(Wn, np.array([0.0, -1.0, 0.0])).feasible


def test_line_of_action_and_contact_points():
    w = np.array([1.0, 2.0, 3.0])
    line = line_of_action(w)
    assert line.point[0] * w[1] - line.point[1] * w[0] == pytest.approx(w[2])
    assert line.moment_about(line.point + 5 * line.direction) == pytest.approx(0.0, abs=1e-12)
    with pytest.raises(QsplanError, match="pure moment"):
        line_of_action([0.0, 0.0, 1.0])
    rod = scene_from_dict(rod_scene(l1=1.0, l2=0.6))
    np.testing.assert_allclose(contact_points(rod), [[-1.0, 0.0], [0.6, 0.0]], atol=1e-12)


def test_active_wrenches_validation():
    scene = scene_from_dict(eq42_scene())
    W = active_wrenches(scene, "SSS", [0.1, 0.2, 0.3])
    assert W.shape == (3, 3)
    with pytest.raises(ModeError, match="applicable constraints"):
        active_wrenches(scene, "RRB")
    with pytest.raises(ModeError, match="kinematic stage fails"):
        active_wrenches(scene, "RSB")
