"""Exact mu-space regions: Appendix A/B and the general multilinear form agree with the solver."""

import numpy as np
import pytest

from qsplan.hands.examples.paper import eq37_scene, eq42_scene, rod_scene
from qsplan.mechanics import ContactMode, ModeError, QsplanError, SceneError, enumerate_modes, planted_scene, scene_from_dict, solve
from qsplan.mechanics.muspace.multilinear import (
    Multilinear,
    adjugate,
    column_expansion,
    corner_values,
    moebius,
    monomials,
    restrict_coef,
)
from qsplan.mechanics.muspace.maps import feasibility_map, polynomial_map
from qsplan.mechanics.muspace.zero_sets import bilinear_zero_set
from qsplan.mechanics.muspace.slices import boundary_agreement, mu_slice
from qsplan.mechanics.numerics import Status
from qsplan.mechanics.muspace.appendices import appendix_a, appendix_b, region_3s, region_rs
from qsplan.mechanics.muspace.regions import MuRegion, equilibrium_polynomials, mode_kinematics, mode_region

POINTS_PER_TYPE = 10_000


# --- multilinear polynomials -----------------------------------------------------------------


def _brute(coef, variables, mu):
    return sum(
        a * np.prod([mu[..., v] for i, v in enumerate(variables) if b >> i & 1], axis=0) for b, a in enumerate(coef)
    )


def test_monomials_and_evaluation():
    rng = np.random.default_rng(1)
    p = Multilinear((0, 2, 3), rng.normal(size=8))
    mu = rng.uniform(size=(7, 4))
    np.testing.assert_allclose(p(mu), _brute(p.coef, p.variables, mu))
    assert monomials(mu, ()).shape == (7, 1)
    assert Multilinear.from_terms((1, 4), {(): 2.0, (4,): -1.0, (1, 4): 3.0}).coefficient(4, 1) == 3.0
    assert str(Multilinear.from_terms((0,), {(0,): -2.0})) == "-2 mu1"


def test_moebius_recovers_coefficients_from_corner_values():
    """a_T = sum_{S subset T} (-1)^{|T|-|S|} p(1_S): 2^n evaluations fix a multilinear polynomial."""
    rng = np.random.default_rng(2)
    for n in range(6):
        coef = rng.normal(size=(1 << n, 2))
        bits = [np.array([b >> i & 1 for i in range(n)], float) for b in range(1 << n)]
        corners = np.array([_brute(coef[:, 0], range(n), c) for c in bits])
        np.testing.assert_allclose(corners, corner_values(coef)[:, 0], atol=1e-12)
        np.testing.assert_allclose(moebius(corner_values(coef)), coef, atol=1e-12)


def test_restrict_embed_times_arithmetic():
    rng = np.random.default_rng(3)
    p = Multilinear((0, 2, 3), rng.normal(size=8))
    q = Multilinear((1, 2), rng.normal(size=4))
    mu = rng.uniform(size=(5, 5))
    for keep in [(0, 3), (2,), (), (0, 2, 3), (3, 0)]:
        r = p.restrict(mu[0], keep)
        m2 = mu.copy()
        for v in p.variables:
            if v not in keep:
                m2[:, v] = mu[0, v]
        np.testing.assert_allclose(r(m2), p(m2))
        kept, c2 = restrict_coef(np.column_stack([p.coef, -p.coef]), p.variables, mu[0], keep)
        assert kept == r.variables
        np.testing.assert_allclose(c2[:, 1], -r.coef)
    np.testing.assert_allclose((p + q)(mu), p(mu) + q(mu))
    np.testing.assert_allclose((p - q)(mu), p(mu) - q(mu))
    np.testing.assert_allclose(q.times(4)(mu), q(mu) * mu[:, 4])
    np.testing.assert_allclose(q.embed((0, 1, 2))(mu), q(mu))
    a, b, c, d = p.bilinear(0, 3, mu[0])
    m2 = np.tile(mu[0], (5, 1))
    m2[:, 0], m2[:, 3] = mu[:, 0], mu[:, 3]
    np.testing.assert_allclose(p(m2), a + b * mu[:, 0] + c * mu[:, 3] + d * mu[:, 0] * mu[:, 3])
    with pytest.raises(QsplanError, match="times"):
        q.times(2)
    with pytest.raises(QsplanError, match="coef"):
        Multilinear((0, 1), np.ones(3))
    with pytest.raises(QsplanError, match="variables"):
        Multilinear((2, 1), np.ones(4))


def _cofactor_adjugate(A):
    k = A.shape[0]
    C = np.zeros_like(A)
    for i in range(k):
        for j in range(k):
            C[i, j] = (-1) ** (i + j) * np.linalg.det(np.delete(np.delete(A, i, 0), j, 1))
    return C.T


@pytest.mark.parametrize("rank", [4, 3, 2])
def test_adjugate_including_singular(rank):
    rng = np.random.default_rng(rank)
    A = rng.normal(size=(4, rank)) @ rng.normal(size=(rank, 4))
    np.testing.assert_allclose(adjugate(A), _cofactor_adjugate(A), atol=1e-12)


def test_column_expansion_is_det_and_adjugate_and_matches_moebius():
    rng = np.random.default_rng(4)
    U, V = rng.normal(size=(5, 5)), rng.normal(size=(5, 5))
    cols = [0, 2, 3]
    det_coef, adj_coef = column_expansion(U, V, cols)
    for mu in rng.uniform(0, 2, size=(20, 3)):
        Q = U.copy()
        Q[:, cols] += mu * V[:, cols]
        M = monomials(mu, range(3))
        assert M @ det_coef == pytest.approx(np.linalg.det(Q), rel=1e-12, abs=1e-12)
        np.testing.assert_allclose(np.einsum("b,bij->ij", M, adj_coef), _cofactor_adjugate(Q), atol=1e-11)
    corners = []
    for b in range(8):
        Q = U.copy()
        Q[:, cols] += np.array([b >> i & 1 for i in range(3)]) * V[:, cols]
        corners.append(np.linalg.det(Q))
    np.testing.assert_allclose(moebius(corners), det_coef, atol=1e-12)


def _on_curve(coef, pts):
    a, b, c, d = coef
    x, y = pts[:, 0], pts[:, 1]
    return a + b * x + c * y + d * x * y


@pytest.mark.parametrize(
    "coef,branches",
    [
        ((1.0, -2.0, -3.0, 4.0), 2),  # hyperbola, asymptotes x = 0.75, y = 0.5 inside the window
        ((-0.5, 1.0, 0.0, 0.0), 1),  # vertical line x = 0.5
        ((-0.5, 0.0, 1.0, 0.0), 1),  # horizontal line
        ((0.5, -1.0, -1.0, 2.0), 2),  # (2x - 1)(y - 0.5): a degenerate pair of lines
        ((1.0, 0.0, 0.0, 0.0), 0),  # constant: empty
        ((0.0, 0.0, 0.0, 0.0), 0),  # zero: reported as no branch
        ((5.0, 1.0, 1.0, 0.0), 0),  # line outside the window
    ],
)
def test_bilinear_zero_set(coef, branches):
    out = bilinear_zero_set(coef, (0.0, 1.5), (0.0, 1.5), n=200)
    assert len(out) == branches
    for br in out:
        pts = br.points()
        assert np.all((pts >= -1e-12) & (pts <= 1.5 + 1e-12))
        np.testing.assert_allclose(_on_curve(coef, pts), 0.0, atol=1e-12)


# --- Appendix A and B against the solver ------------------------------------------------------


def _random_points(rng, scene_source, kind, target, mu_hi=1.5, per_scene=60):
    """Compare analytic regions of modes of ``kind`` with the solver until ``target`` points."""
    stats = dict(points=0, feasible=0, excluded=0, disagree=0, scenes=0)
    while stats["points"] < target:
        scene = scene_source(rng)
        modes = [m for m in enumerate_modes(scene.n_contacts, scene.dof) if m.kind == kind]
        regs = [(j, region_3s(scene, m) if kind == "3S" else region_rs(scene, m)) for j, m in enumerate(modes)]
        regs = [(j, r) for j, r in regs if r.kinematic_status == Status.FEASIBLE]
        if not regs:
            continue
        stats["scenes"] += 1
        pts = rng.uniform(0, mu_hi, size=(per_scene, scene.n_contacts))
        mm = feasibility_map(scene, pts)
        cols = {m.letters: j for j, m in enumerate(mm.modes)}
        for _, reg in regs:
            j = cols[reg.mode.letters]
            near = reg.near_boundary(pts) | mm.boundary[:, j] | mm.degenerate[:, j]
            ours = reg.contains(pts)
            stats["points"] += pts.shape[0]
            stats["excluded"] += int(near.sum())
            stats["feasible"] += int(mm.feasible[:, j].sum())
            stats["disagree"] += int(((ours != mm.feasible[:, j]) & ~near).sum())
    return stats


def _planted(rng, mode=None):
    return planted_scene(rng, 3, 0, mode=mode, mu_range=(0.05, 1.2))[0]


def test_appendix_a_agrees_with_solver_on_10000_points():
    rng = np.random.default_rng(50)
    source = lambda r: _planted(r, ContactMode("SSS") if r.uniform() < 0.5 else None)  # noqa: E731
    st = _random_points(rng, source, "3S", POINTS_PER_TYPE)
    assert st["points"] >= POINTS_PER_TYPE and st["disagree"] == 0, st
    assert 0.05 * st["points"] < st["feasible"] < 0.95 * st["points"], st  # both sides exercised
    assert st["excluded"] <= st["points"] // 1000, st


def test_appendix_b_agrees_with_solver_on_10000_points():
    rng = np.random.default_rng(51)
    st = _random_points(rng, _planted, "RS", POINTS_PER_TYPE)
    assert st["points"] >= POINTS_PER_TYPE and st["disagree"] == 0, st
    assert 0.05 * st["points"] < st["feasible"] < 0.95 * st["points"], st
    assert st["excluded"] <= st["points"] // 1000, st


def test_appendix_coefficients_equal_the_general_expansion():
    """Appendix A's determinants are the column expansion of W_Amu; B's up to the column order's sign."""
    rng = np.random.default_rng(52)
    checked = 0
    while checked < 40:
        scene = _planted(rng)
        for m in enumerate_modes(3, 3):
            gen = mode_region(scene, m)
            ana = region_3s(scene, m) if m.kind == "3S" else region_rs(scene, m)
            assert gen.kinematic_status == ana.kinematic_status
            if gen.kinematic_status != Status.FEASIBLE:
                assert not gen.contains(rng.uniform(0, 1, (5, 3))).any()
                continue
            vs = gen.variables
            assert ana.variables == vs
            D_gen, D_ana = gen.denominator.embed(vs), ana.denominator.embed(vs)
            sign = 1.0 if m.kind == "3S" else np.sign(D_gen.coef @ D_ana.coef)
            scale = np.max(np.abs(D_ana.coef)) + 1.0
            np.testing.assert_allclose(sign * D_gen.coef, D_ana.coef, atol=1e-12 * scale)
            ours = {lab: p for lab, p in zip(gen.labels, gen.numerators)}
            assert set(ours) == set(ana.labels)
            for lab, p in zip(ana.labels, ana.numerators):
                q = ours[lab].embed(vs).coef * sign
                np.testing.assert_allclose(q, p.embed(vs).coef, atol=1e-12 * (np.max(np.abs(p.coef)) + 1.0))
            checked += 1


def test_appendix_a_by_hand():
    """Eq. (34) at one point: c_n from the coefficients equals the solution of W_Amu c_n = -g."""
    rng = np.random.default_rng(5)
    wn, wt, g = rng.normal(size=(3, 3)), rng.normal(size=(3, 3)), rng.normal(size=3)
    xi, mu = np.array([1.0, -1.0, 1.0]), np.array([0.3, 0.7, 0.2])
    co = appendix_a(wn, wt, g, xi)
    m1, m2, m3 = mu
    den = co.A * m1 * m2 * m3 + co.B[0] * m2 * m3 + co.B[1] * m1 * m3 + co.B[2] * m1 * m2 + co.C @ mu + co.D
    num = [co.E[i] * np.prod(np.delete(mu, i)) + sum(co.F[i, j] * mu[j] for j in range(3) if j != i) + co.G[i] for i in range(3)]
    np.testing.assert_allclose(np.array(num) / den, np.linalg.solve(wn - wt * (xi * mu), -g))
    cb = appendix_b(wn[:, 0], wt[:, 0], wn[:, 1], wt[:, 1], g, -1.0)
    c = np.linalg.solve(np.column_stack([wn[:, 0], wt[:, 0], wn[:, 1] + 0.4 * wt[:, 1]]), -g)
    d = cb.A * 0.4 + cb.B
    np.testing.assert_allclose([(cb.C1 * 0.4 + cb.D1) / d, (cb.C2 * 0.4 + cb.D2) / d, cb.D3 / d], c)


@pytest.mark.parametrize("example", [eq37_scene, eq42_scene])
def test_paper_examples_regions_equal_solver_grid(example):
    scene = scene_from_dict(example())
    xs = np.linspace(0, 2, 41)
    pts = np.stack(np.meshgrid(xs, xs, [0.0, 0.5, 1.5]), -1).reshape(-1, 3)
    mm = feasibility_map(scene, pts)
    for j, m in enumerate(mm.modes):
        ana = region_3s(scene, m) if m.kind == "3S" else region_rs(scene, m)
        near = ana.near_boundary(pts) | mm.boundary[:, j]
        assert not ((ana.contains(pts) != mm.feasible[:, j]) & ~near).any(), m


# --- general (compliant) modes ----------------------------------------------------------------


@pytest.mark.parametrize("n_c,n_e,kinds", [(4, 1, {"2R", "R2S", "4S"}), (5, 2, {"2RS", "R3S", "5S"})])
def test_general_modes_agree_with_solver(n_c, n_e, kinds):
    rng = np.random.default_rng(60 + n_c)
    stats = dict(points=0, feasible=0, excluded=0, disagree=0)
    seen = set()
    for s in range(24):
        scene, planted = planted_scene(rng, n_c, n_e, mu_range=(0.05, 1.0))
        pts = rng.uniform(0, 1.2, size=(120, n_c))
        pts[0] = scene.mu  # the planted point: its mode is feasible there
        mm = feasibility_map(scene, pts)
        pm = polynomial_map(scene, pts)
        np.testing.assert_array_equal(pm.feasible, mm.feasible)
        np.testing.assert_array_equal(pm.degenerate, mm.degenerate)
        for j, m in enumerate(mm.modes):
            if mm.kinematic_status[j] != Status.FEASIBLE:
                continue
            reg = mode_region(scene, m)
            near = reg.near_boundary(pts) | mm.boundary[:, j] | mm.degenerate[:, j]
            stats["points"] += len(pts)
            stats["excluded"] += int(near.sum())
            stats["feasible"] += int(mm.feasible[:, j].sum())
            stats["disagree"] += int(((reg.contains(pts) != mm.feasible[:, j]) & ~near).sum())
            if mm.feasible[:, j].any():
                seen.add(m.kind)
    assert stats["disagree"] == 0 and stats["feasible"] > 0, stats
    assert stats["excluded"] <= stats["points"] // 1000, stats
    assert seen == kinds, (seen, stats)  # every compliant mode type was feasible somewhere


def test_numerators_are_linear_in_the_efforts():
    rng = np.random.default_rng(7)
    scene, planted = planted_scene(rng, 4, 1, mu_range=(0.1, 0.8))
    eqp = equilibrium_polynomials(scene, planted)
    t0, t1 = np.array([0.0]), np.array([1.0])
    n0, n1, n2 = eqp.numerators(t0), eqp.numerators(t1), eqp.numerators(2.5 * t1)
    for a, b, c in zip(n0, n1, n2):
        np.testing.assert_allclose(c.coef, a.coef + 2.5 * (b.coef - a.coef), atol=1e-12)
    tau = scene.joint_effort[scene.effort_joints] + 0.3
    reg = mode_region(scene, planted, tau_e=tau)
    other = scene.with_inputs(joint_effort=np.where(scene.effort_controlled, np.nan_to_num(scene.joint_effort) + 0.3, np.nan))
    pts = rng.uniform(0, 1.2, size=(200, 4))
    mm = feasibility_map(other, pts)
    j = [m.letters for m in mm.modes].index(planted.letters)
    near = reg.near_boundary(pts) | mm.boundary[:, j]
    assert not ((reg.contains(pts) != mm.feasible[:, j]) & ~near).any()


# --- boundaries -------------------------------------------------------------------------------


def test_boundary_semantics():
    """P_i = 0 is inside (non-strict (35)); D = 0 is outside (Q_AI singular, eq. 31)."""
    x_minus_y = Multilinear.from_terms((0, 1), {(0,): 1.0, (1,): -1.0})
    one_minus_x = Multilinear.from_terms((0, 1), {(): 1.0, (0,): -1.0})
    reg = MuRegion(ContactMode("SS"), Status.FEASIBLE, np.zeros(2), one_minus_x, (x_minus_y,), ("c_n1 >= 0",), "test")
    pts = np.array([[0.5, 0.5], [0.5, 0.6], [0.5, 0.4], [1.0, 0.5], [1.5, 1.6], [1.5, 1.4]])
    assert reg.contains(pts).tolist() == [True, False, True, False, True, False]
    assert reg.near_boundary(pts).tolist() == [True, False, False, True, False, False]


def test_solver_on_the_rod_line_flags_both_modes_on_boundary():
    scene = scene_from_dict(rod_scene(l1=1.0, l2=0.5))
    res = solve(scene.with_mu([0.4, 0.2]))  # l1 mu2 = l2 mu1 exactly
    assert res.feasible_modes == ["RS", "SR"] and all(s.on_boundary for s in res.solutions)


def test_boundary_curves_lie_on_zero_sets_and_bound_the_region():
    scene = scene_from_dict(eq42_scene())
    xs = np.linspace(0, 1.5, 81)
    for mu3 in (0.1, 0.6):
        sl = mu_slice(scene, 0, 1, xs, xs, base_mu=[0, 0, mu3])
        curves = sl.boundary_curves()
        assert curves
        for c in curves:
            reg = sl.regions[sl.modes.index(c.mode)]
            polys = {"det Q_AI = 0": reg.denominator}
            polys.update({lab.split(">=")[0].strip() + " = 0": p for lab, p in zip(reg.labels, reg.numerators)})
            mu = np.tile(sl.base_mu, (len(c.points), 1))
            mu[:, :2] = c.points
            p = polys[c.label]
            assert np.all(np.abs(p(mu)) <= 1e-12 * p.abs_terms(mu) + 1e-15)
            # just off the curve, on either side, membership differs (away from the piece's ends)
            mid = c.points[len(c.points) // 2]
            h = 1e-6
            normal = np.array([p.bilinear(0, 1, sl.base_mu)[1], p.bilinear(0, 1, sl.base_mu)[2]])
            normal = normal + p.bilinear(0, 1, sl.base_mu)[3] * mid[::-1]
            normal /= np.linalg.norm(normal)
            a, b = (np.r_[mid + s * h * normal, mu3] for s in (1, -1))
            assert reg.contains(a[None])[0] != reg.contains(b[None])[0], c.label
            if c.label != "det Q_AI = 0":  # on a Coulomb boundary the solver accepts the mode, flagged
                sol = solve(scene.with_mu(np.r_[mid, mu3])).solution(c.mode.letters)
                assert sol is not None and sol.on_boundary, c.label
        ag = boundary_agreement(sl)
        assert ag.agrees and ag.label_changes > 0 and ag.explained == ag.label_changes


def test_rod_boundary_is_the_line_through_the_origin():
    scene = scene_from_dict(rod_scene(l1=1.0, l2=0.6))
    xs = np.linspace(0, 1, 51)
    sl = mu_slice(scene, 0, 1, xs, xs)
    pts = np.vstack([c.points for c in sl.boundary_curves()])
    assert np.max(np.abs(1.0 * pts[:, 1] - 0.6 * pts[:, 0])) < 1e-12
    assert np.min(np.linalg.norm(pts, axis=1)) < 1e-12 and np.max(pts[:, 0]) == pytest.approx(1.0)
    ag = boundary_agreement(sl)
    assert ag.agrees and ag.excluded > 0  # cells centred on the line are counted, not compared


# --- slices and the fast path -----------------------------------------------------------------


def test_slice_cells_layout_and_methods_agree():
    scene = scene_from_dict(eq42_scene())
    xs, ys = np.linspace(0, 1.5, 7), np.linspace(0.1, 1.2, 5)
    a = mu_slice(scene, 2, 0, xs, ys, base_mu=[9.0, 0.3, 9.0])
    b = mu_slice(scene, 2, 0, xs, ys, base_mu=[9.0, 0.3, 9.0], method="solver")
    np.testing.assert_array_equal(a.mumap.feasible, b.mumap.feasible)
    cells = a.cells()
    assert len(cells) == ys.size and len(cells[0]) == xs.size
    for j in (0, 3):
        for i in (0, 4, 6):
            assert cells[j][i] == sorted(solve(scene.with_mu([ys[j], 0.3, xs[i]])).feasible_modes)


def test_polynomial_map_equals_solver_on_the_paper_examples():
    for example, hi in ((eq37_scene, 2.0), (eq42_scene, 1.5)):
        scene = scene_from_dict(example())
        pts = np.random.default_rng(8).uniform(0, hi, size=(3000, 3))
        mm, pm = feasibility_map(scene, pts), polynomial_map(scene, pts)
        np.testing.assert_array_equal(pm.feasible, mm.feasible)
        np.testing.assert_array_equal(pm.boundary, mm.boundary)
        for i in range(0, 3000, 300):
            assert mm.labels(i) == sorted(solve(scene.with_mu(pts[i])).feasible_modes)


# --- validation -------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "call,match",
    [
        (lambda s: region_3s(s, "RBS"), "Appendix A covers 3S"),
        (lambda s: region_rs(s, "SSS"), "Appendix B covers RS"),
        (lambda s: mode_region(s, "SS"), "expected 3 letters"),
        (lambda s: mode_region(s, "RRB"), "applicable constraints"),
        (lambda s: mode_kinematics(s, "XYZ"), "letters R, S or B"),
        (lambda s: mu_slice(s, 0, 0, [0, 1], [0, 1]), "y: expected a contact other than x"),
        (lambda s: mu_slice(s, 3, 0, [0, 1], [0, 1]), "x: expected a contact index"),
        (lambda s: mu_slice(s, 0, 1, [1], [0, 1]), "xs: expected at least 2"),
        (lambda s: mu_slice(s, 0, 1, [0, 1], [1, -1]), "ys: expected finite nonnegative"),
        (lambda s: mu_slice(s, 0, 1, [0, 1], [0, 1], base_mu=[0, 0]), "base_mu"),
        (lambda s: mu_slice(s, 0, 1, [0, 1], [0, 1], method="magic"), "method"),
        (lambda s: polynomial_map(s, np.zeros((2, 2))), "mu_points"),
    ],
)
def test_validation(call, match):
    with pytest.raises((ModeError, SceneError), match=match):
        call(scene_from_dict(eq42_scene()))


def test_empty_region_when_kinematics_fail():
    scene = scene_from_dict(eq42_scene())
    reg = region_rs(scene, "RSB")  # R1S2: breaking contact 3 would penetrate
    assert reg.kinematic_status == Status.BREAKING_VIOLATED
    assert not reg.contains(np.full((4, 3), 0.5)).any() and reg.boundary_curves(0, 1, [0, 0, 0.5], (0, 1), (0, 1)) == []
    assert equilibrium_polynomials(scene, "RSB") is None


@pytest.mark.parametrize("example", [eq37_scene, eq42_scene])
def test_points_on_coulomb_boundaries(example):
    """Solve P_i(mu) = 0 for one coefficient (P_i is affine in each): the point is flagged near the
    boundary, and where the other inequalities hold the solver accepts the mode on its boundary."""
    scene = scene_from_dict(example())
    rng = np.random.default_rng(9)
    on_active = 0
    for m in enumerate_modes(3, 3):
        reg = region_3s(scene, m) if m.kind == "3S" else region_rs(scene, m)
        if reg.kinematic_status != Status.FEASIBLE:
            continue
        for p in reg.numerators:
            if not p.variables:
                continue
            v = p.variables[-1]
            pts = rng.uniform(0, 1.5, size=(400, 3))
            r = np.array([p.restrict(q, (v,)).coef for q in pts])  # alpha + beta mu_v
            with np.errstate(divide="ignore", invalid="ignore"):
                pts[:, v] = -r[:, 0] / r[:, 1]
            pts = pts[np.isfinite(pts[:, v]) & (pts[:, v] >= 0) & (pts[:, v] <= 3)]
            assert reg.near_boundary(pts).all()
            mm = feasibility_map(scene, pts)
            j = [q.letters for q in mm.modes].index(m.letters)
            signed = np.sign(reg.denominator(pts))[:, None] * np.stack([q(pts) for q in reg.numerators], axis=-1)
            others = np.all(signed[:, [q is not p for q in reg.numerators]] > 1e-6, axis=1)
            assert mm.feasible[others, j].all() and mm.boundary[others, j].all()
            on_active += int(others.sum())
    assert on_active > 100
