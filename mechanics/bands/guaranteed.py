"""Effort bands over uncertain friction: guaranteed, possible and sampled (eq. 28, Section 5.2).

Over uncertain friction the guarantee is exact:

* **independent coefficients in a box** (:func:`guaranteed_band_box`): ``Q_AI`` is
  affine in each sliding contact's mu, so ``det Q_AI`` and ``det Q_AI * s_r`` are
  multilinear in the mu's (rolling contacts' mu enter ``B_A`` linearly) and affine
  in tau.  Where ``det Q_AI`` keeps its sign on the box (checked at the vertices,
  which suffices for a multilinear function), ``s_r >= 0`` on the whole box iff it
  holds at the ``2^m`` vertices: the guaranteed band is the intersection of the
  vertex bands, exactly.  Where the sign changes, ``Q_AI`` is singular inside the
  box, the mode is degenerate there, and nothing is guaranteed (reported).
* **one shared coefficient** (:func:`guaranteed_band_shared`): each band edge is a
  ratio of polynomials in mu; its extremes over ``[lo, hi]`` are found from the
  polynomial's roots (critical points and sign changes), not from samples.  The
  polynomials are fitted in ``t`` (``[lo, hi]`` mapped onto ``[-1, 1]``), so any
  range wider than zero, however narrow, is fitted as well as ``[0, 1]``.

A box of disturbance wrenches (``disturbance=``, :mod:`qsplan.mechanics.bands.disturbance`) keeps both
exact: with friction fixed the rows are affine in the wrench (eq. 26), so the box's vertices decide "every
wrench": the box band's vertices are those of the friction box times the wrench box, and the shared band
is the intersection of the root bands at the wrench vertices (each row at the vertices that can be its
worst: where a row's slope in a wrench component keeps its sign over the range, the other end is dominated).

A force margin (:class:`qsplan.mechanics.bands.effort.ForceMargin`: ``s_r >= m_r``
with a constant ``m_r`` instead of ``s_r >= 0``) keeps both exact: where ``det Q_AI``
keeps its sign, ``s_r - m_r >= 0`` iff ``det (s_r - m_r) = det s_r - m_r det`` has
the sign of ``det``, a difference of two multilinear (shared: polynomial) functions,
so vertices (roots) still decide.  Competitors (:func:`possible_band_box`) take no
margin: precluding them is about feasibility, not about how far inside it they are.

:func:`sampled_band` keeps the paper's method (intersection over a list of mu)
for comparison.
"""

from __future__ import annotations

from itertools import product
from math import comb

import numpy as np

from qsplan.mechanics.bands.disturbance import check_wrench_box, loaded_reason, wrench_vertex_rows
from qsplan.mechanics.bands.roots import critical_polynomial, roots_batch
from qsplan.mechanics.bands.effort import (
    Band,
    band_kinematics,
    band_rows,
    check_force_margin,
    check_one_effort_joint,
    effort_band,
    effort_bands,
    intersect_rows,
)
from qsplan.mechanics.model.friction import check_mu_range
from qsplan.mechanics.model.scene import Scene
from qsplan.mechanics.modes.contact_mode import ContactMode
from qsplan.mechanics.modes.kinematics import check_mode_fits
from qsplan.mechanics.numerics import DEFAULT_TOLERANCES, Tolerances

__all__ = [
    "CRITICAL_IMAG_TOL",
    "ROOT_IMAG_TOL",
    "guaranteed_band_box",
    "guaranteed_band_shared",
    "possible_band_box",
    "sampled_band",
    "bernstein_matrix",
    "shared_band_from_rows",
    "shared_band_over_wrenches",
    "shared_coordinate",
    "shared_coordinates",
    "shared_nodes",
]

#: A root of ``det Q_AI`` or of a row's slope polynomial whose imaginary part is below this counts as
#: real.  In units of the range's half-width (the polynomials are in ``t``, :func:`shared_coordinate`;
#: before, 1e-12 in units of mu): well above the ~1e-15 rounding of a simple root of these well-scaled
#: polynomials.
ROOT_IMAG_TOL = 1e-12

#: The same for the critical points of a row's effort bound, looser: a double critical point splits into a
#: pair ~sqrt(rounding) ~ 1e-8 apart, and a spurious candidate only adds an effort that must hold anyway.
CRITICAL_IMAG_TOL = 1e-9


def _box_vertices(scene: Scene, mode: ContactMode, lo, hi) -> np.ndarray:
    n_c = scene.n_contacts
    lo, hi = check_mu_range(lo, hi, n=n_c)
    free = [c for c in range(n_c) if mode.letters[c] != "B" and hi[c] > lo[c]]
    verts = np.tile(lo, (2 ** len(free), 1))
    for k, bits in enumerate(product((0, 1), repeat=len(free))):
        for c, b in zip(free, bits):
            verts[k, c] = hi[c] if b else lo[c]
    return verts


def guaranteed_band_box(scene: Scene, mode: ContactMode, lo, hi, tol: Tolerances = DEFAULT_TOLERANCES, *,
                        force_margin=None, disturbance=None) -> Band:  # fmt: skip
    """Efforts for which ``mode`` is feasible for **every** mu with ``lo <= mu_i <= hi`` (exact).

    Parameters
    ----------
    lo, hi : float or array-like, shape (n_c,)
        Independent intervals per contact (breaking contacts' mu do not matter).
    force_margin : ForceMargin or (float, float), optional
        Minimum normal force and Coulomb slack (N) kept for every mu in the box (default none).
    disturbance : WrenchBox or (array-like, array-like), optional
        A box of external wrenches on the workpiece (N, N, N m, added to ``g_obj``): the band holds for every
        one too; the vertices are then those of the friction box times the wrench box (exact,
        :mod:`qsplan.mechanics.bands.disturbance`).
    """
    joint = check_one_effort_joint(scene)
    mode = check_mode_fits(scene, mode)
    force_margin = None if force_margin is None else check_force_margin(force_margin)
    box = check_wrench_box(disturbance)
    verts = _box_vertices(scene, mode, lo, hi)
    mk = band_kinematics(scene, mode, tol)
    if not mk.ok:
        return Band(mode.letters, joint, np.nan, np.nan, False, f"kinematics: {mk.status}", "box-vertices")
    rows = band_rows(scene, mk, verts, force_margin, loads=box is not None)
    s0, s1, det, scale = rows if box is None else wrench_vertex_rows(*rows, box.vertices())  # det: per friction vertex
    if not (np.all(det > 0) or np.all(det < 0)):
        return Band(
            mode.letters, joint, np.nan, np.nan, False,
            "equilibrium_singular: det Q_AI changes sign inside the mu box (the mode is degenerate there)",
            "box-vertices",
        )  # fmt: skip
    lower, upper, ok = intersect_rows(s0, s1, scale, tol)
    if not ok.all():
        why = "coulomb: no effort works at some vertex of the mu box"
        return Band(mode.letters, joint, np.nan, np.nan, False, loaded_reason(why, box), "box-vertices")
    lo_, up_ = float(lower.max()), float(upper.min())
    if lo_ > up_:
        why = loaded_reason("coulomb: vertex bands do not overlap", box)
        return Band(mode.letters, joint, np.nan, np.nan, False, why, "box-vertices")
    return Band(mode.letters, joint, lo_, up_, True, None, "box-vertices")


def possible_band_box(scene: Scene, mode: ContactMode, lo, hi, tol: Tolerances = DEFAULT_TOLERANCES, *, disturbance=None) -> Band:
    """An interval containing every effort for which ``mode`` is feasible for **some** mu in the box.

    Used to preclude a competing mode: outside this interval the mode is
    infeasible for every mu in the box.  Each Coulomb row alone is exactly
    feasible for some mu iff it holds at some vertex (``max`` of a multilinear
    function); requiring every row separately gives a superset of the true set
    (``exact=False``: conservative for precluding).  When ``det Q_AI`` changes sign
    in the box, the mode may be feasible for any effort near the singularity:
    the whole line is returned.  With ``disturbance`` (a wrench box, as in :func:`guaranteed_band_box`)
    "some mu" is "some mu and some wrench": each row is multilinear in both, so the vertices of the
    product box decide it alike.
    """
    joint = check_one_effort_joint(scene)
    mode = check_mode_fits(scene, mode)
    box = check_wrench_box(disturbance)
    verts = _box_vertices(scene, mode, lo, hi)
    mk = band_kinematics(scene, mode, tol)
    if not mk.ok:
        return Band(mode.letters, joint, np.nan, np.nan, False, f"kinematics: {mk.status}", "possible-superset", True)
    rows = band_rows(scene, mk, verts, loads=box is not None)
    s0, s1, det, scale = rows if box is None else wrench_vertex_rows(*rows, box.vertices())
    if not (np.all(det > 0) or np.all(det < 0)):
        return Band(mode.letters, joint, -np.inf, np.inf, True, "det Q_AI changes sign in the box", "possible-superset", False)
    ftol = tol.force * scale[:, None]
    big = np.max(np.abs(s1), axis=1, keepdims=True)
    flat = np.abs(s1) <= tol.force * big
    with np.errstate(divide="ignore", invalid="ignore"):
        edge = -s0 / s1
    lower, upper = -np.inf, np.inf
    for r in range(s0.shape[1]):
        # {tau : exists vertex v with s0 + tau s1 >= 0}: union of half-lines
        if np.any(flat[:, r] & (s0[:, r] >= -ftol[:, 0])):
            continue  # holds for every tau at some vertex
        lo_r = np.min(np.where(~flat[:, r] & (s1[:, r] > 0), edge[:, r], np.inf))
        up_r = np.max(np.where(~flat[:, r] & (s1[:, r] < 0), edge[:, r], -np.inf))
        if up_r >= lo_r:
            continue  # the half-lines cover the line
        if np.isinf(lo_r) and np.isinf(up_r):
            return Band(mode.letters, joint, np.nan, np.nan, False, "coulomb: infeasible at every vertex", "possible-superset", False)
        # the row's set is (-inf, up_r] U [lo_r, inf); keep the hull side that is a half-line
        if np.isinf(up_r):
            lower = max(lower, lo_r)
        elif np.isinf(lo_r):
            upper = min(upper, up_r)
        # else: two half-lines with a gap (up_r, lo_r); the interval hull is the whole line (superset)
    if lower > upper:
        return Band(mode.letters, joint, np.nan, np.nan, False, "coulomb: rows exclude each other", "possible-superset", False)
    return Band(mode.letters, joint, float(lower), float(upper), True, None, "possible-superset", False)


def sampled_band(scene: Scene, mode: ContactMode, mu_rows, tol: Tolerances = DEFAULT_TOLERANCES, *,
                 force_margin=None, disturbance=None) -> Band:  # fmt: skip
    """The paper's method: intersect the point bands over the listed mu (e.g. 0, 0.01, ..., 0.2).

    Parameters
    ----------
    mu_rows : array-like, shape (N, n_c) or (N,)
        Friction points; a 1-D array gives one shared coefficient per sample.
    force_margin, disturbance : optional
        As in :func:`guaranteed_band_box` (the disturbance's vertices are checked at every sample: exact there).
    """
    joint = check_one_effort_joint(scene)
    mode = check_mode_fits(scene, mode)
    mu_rows = np.asarray(mu_rows, dtype=float)
    if mu_rows.ndim == 1:
        mu_rows = np.repeat(mu_rows[:, None], scene.n_contacts, axis=1)
    lower, upper, ok = effort_bands(scene, mode, mu_rows, tol, force_margin=force_margin, disturbance=disturbance)
    if not ok.all():
        return Band(mode.letters, joint, np.nan, np.nan, False, "infeasible at some sample", "sampled", False)
    lo_, up_ = float(lower.max()), float(upper.min())
    if lo_ > up_:
        return Band(mode.letters, joint, np.nan, np.nan, False, "sample bands do not overlap", "sampled", False)
    return Band(mode.letters, joint, lo_, up_, True, None, "sampled", False)


def _poly_fit_exact(x, y, degree):
    """Coefficients (numpy.polynomial order) of the degree-``degree`` polynomial through the points."""
    V = np.vander(x, degree + 1, increasing=True)
    return np.linalg.solve(V, y)


def guaranteed_band_shared(scene: Scene, mode: ContactMode, lo: float, hi: float, tol: Tolerances = DEFAULT_TOLERANCES,
                           *, force_margin=None, disturbance=None) -> Band:  # fmt: skip
    """Efforts for which ``mode`` is feasible for every shared coefficient ``mu`` in ``[lo, hi]`` (exact).

    With one coefficient shared by all contacts, ``det Q_AI`` is a polynomial of
    degree ``n_S`` in mu and ``det Q_AI * s_r`` one of degree ``n_S + 1``; both are
    recovered exactly from ``n_S + 2`` evaluations at Chebyshev points.  Each row
    bounds the effort by ``-N0_r(mu) / N1_r(mu)``; its extremes over the interval
    are taken at the ends, at the real roots of ``N0' N1 - N0 N1'`` and in the
    limits at roots of ``N1`` (where the bound leaves to infinity, harmlessly if
    the row holds there and fatally if not).  A root of ``det Q_AI`` inside the
    interval means a degenerate mode: nothing is guaranteed.  With ``force_margin``
    (as in :func:`guaranteed_band_box`) ``N0_r`` is ``det Q_AI (s0_r - m_r)``, of the same degree.
    With ``disturbance`` (a wrench box, as in :func:`guaranteed_band_box`): the intersection of these
    bands over the wrench box's vertices (:func:`shared_band_over_wrenches`; exact).
    """
    joint = check_one_effort_joint(scene)
    mode = check_mode_fits(scene, mode)
    force_margin = None if force_margin is None else check_force_margin(force_margin)
    box = check_wrench_box(disturbance)
    lo, hi = check_mu_range(lo, hi)
    mk = band_kinematics(scene, mode, tol)
    if not mk.ok:
        return Band(mode.letters, joint, np.nan, np.nan, False, f"kinematics: {mk.status}", "shared-roots")
    if hi == lo:
        b = effort_band(scene, mode, np.full(scene.n_contacts, lo), tol, force_margin=force_margin, disturbance=box)
        return Band(b.mode, joint, b.lower, b.upper, b.feasible, b.reason, "shared-roots")
    nodes = shared_nodes(mode, lo, hi)
    rows = band_rows(scene, mk, np.repeat(nodes[:, None], scene.n_contacts, axis=1), force_margin, loads=box is not None)
    if box is not None:
        return shared_band_over_wrenches(mode, joint, nodes, *rows, box, lo, hi, tol)
    return shared_band_from_rows(mode, joint, nodes, *rows, lo, hi, tol)


def shared_band_over_wrenches(mode: ContactMode, joint: int, nodes, s0, s1, det, scale, s2, box, lo: float, hi: float,
                              tol: Tolerances = DEFAULT_TOLERANCES) -> Band:  # fmt: skip
    """:func:`shared_band_from_rows` at every vertex of the wrench box ``box``, intersected: the efforts that hold
    ``mode`` for every shared mu in ``[lo, hi]`` and every wrench of the box (``band_rows(..., loads=True)``' output
    at :func:`shared_nodes`).  Exact: for fixed mu the rows are affine in the wrench (eq. 26), so its box's
    vertices decide "every wrench"; at each vertex the roots decide "every mu"."""
    verts = box.vertices()
    s0w, _, _, scalew = wrench_vertex_rows(s0, s1, det, scale, s2, verts)
    W, n = verts.shape[0], nodes.size
    keep = _worst_vertices(mode, s2, det, box)
    b = _shared_band(mode, joint, nodes, s0w.reshape(W, n, -1), s1, det, scalew.reshape(W, n), lo, hi, tol, keep)
    return Band(b.mode, joint, b.lower, b.upper, b.feasible, loaded_reason(b.reason, box), "shared-roots")


def _worst_vertices(mode: ContactMode, s2, det, box) -> np.ndarray:
    """Which wrench vertices can be a row's worst somewhere in the range, (W, r) of bool (``s2`` at the nodes).

    Exact pruning: where the slope ``s2_rj`` of row ``r`` in wrench component ``j`` keeps one sign over the whole
    range, the vertex with ``w_j`` at the other end is dominated (``s_r`` there is larger by ``s2_rj (hi_j - lo_j)
    >= 0`` for every mu and effort, eq. 26), so it cuts nothing the kept one does not.  The sign is proved by the
    Bernstein coefficients of ``det Q_AI * s2_rj`` (all of one sign: so is the polynomial) and the sign of ``det``
    (constant, else the mode is singular and no row is looked at).
    """
    n = det.size
    V = np.vander(shared_coordinates(mode), n, increasing=True)
    coef = np.linalg.solve(V, (s2 * det[:, None, None]).reshape(n, -1))  # power basis in t, (n, 3 r)
    B = (bernstein_matrix(n - 1, np.array([-1.0]), np.array([1.0]))[0] @ coef).reshape((n,) + s2.shape[1:])
    B = B * np.sign(det[0])
    rising, falling = np.all(B >= 0, axis=0), np.all(B <= 0, axis=0) & ~np.all(B == 0, axis=0)  # (r, 3)
    verts, hi = box.vertices(), np.array(box.hi)
    at_hi = verts == hi  # (W, 3)
    dominated = (at_hi[:, None, :] & rising[None]) | (~at_hi[:, None, :] & falling[None])
    free = np.zeros(3, bool)
    free[list(box.free)] = True
    return ~np.any(dominated & free, axis=2) | ~np.isfinite(B).all() | (det[0] == 0)


def shared_coordinates(mode: ContactMode) -> np.ndarray:
    """The ``n_S + 2`` Chebyshev points of ``[-1, 1]``: :func:`shared_nodes` in the coordinate of :func:`shared_coordinate`.

    The polynomials of the shared coefficient are fitted in this coordinate, not in mu: at the
    Chebyshev points of ``[-1, 1]`` the fit is well conditioned for any range, where powers of mu
    on a narrow range (``[0.3, 0.30001]``, ``[0, 1e-100]``) made it singular.
    """
    deg = len(mode.sliding) + 1
    return np.cos(np.pi * (np.arange(deg + 1) + 0.5) / (deg + 1))


def shared_nodes(mode: ContactMode, lo: float, hi: float) -> np.ndarray:
    """The ``n_S + 2`` Chebyshev points of ``[lo, hi]`` at which :func:`guaranteed_band_shared` evaluates the rows."""
    return 0.5 * (lo + hi) + 0.5 * (hi - lo) * shared_coordinates(mode)


def shared_coordinate(mu, lo: float, hi: float):
    """``t = (2 mu - lo - hi) / (hi - lo)`` (``lo < hi``): ``[lo, hi]`` onto ``[-1, 1]``, the polynomials' variable."""
    return (2.0 * np.asarray(mu, dtype=float) - (lo + hi)) / (hi - lo)


def shared_band_from_rows(mode: ContactMode, joint: int, nodes, s0, s1, det, scale, lo: float, hi: float,
                          tol: Tolerances = DEFAULT_TOLERANCES) -> Band:  # fmt: skip
    """:func:`guaranteed_band_shared` from the rows at :func:`shared_nodes` (:func:`band_rows`' output, (deg + 1, r)).

    The polynomials are in ``t`` (:func:`shared_coordinate`), their extremes sought on ``[-1, 1]``.
    """
    return _shared_band(mode, joint, nodes, s0[None], s1, det, scale[None], lo, hi, tol)


def _shared_band(mode: ContactMode, joint: int, nodes, s0s, s1, det, scales, lo: float, hi: float, tol: Tolerances,
                 keep=None) -> Band:  # fmt: skip
    """:func:`shared_band_from_rows` for the rows ``s0s`` (V, deg + 1, r) with their ``scales`` (V, deg + 1) that share
    ``s1`` and ``det`` (the rows under each wrench of a box: eq. 26 moves only ``s0``): the intersection of their bands.
    ``det Q_AI`` and each row's slope polynomial are fitted and their roots found once.  ``keep`` (V, r) of bool: the
    (set, row) pairs to look at (default all; :func:`_worst_vertices` drops dominated ones)."""
    deg = len(mode.sliding) + 1
    t = shared_coordinates(mode)
    mu_of = lambda x: 0.5 * (lo + hi) + 0.5 * (hi - lo) * x  # noqa: E731 - for messages
    pdet = _poly_fit_exact(t, det, deg)
    roots_det = [r.real for r in roots_batch([pdet])[0] if abs(r.imag) < ROOT_IMAG_TOL and -1.0 <= r.real <= 1.0]
    if roots_det or np.any(det == 0):
        return Band(mode.letters, joint, np.nan, np.nan, False,
                    f"equilibrium_singular: det Q_AI vanishes at mu = {mu_of(roots_det[0]) if roots_det else nodes[det == 0][0]:.6g}",
                    "shared-roots")  # fmt: skip
    # every polynomial first, their roots in one batch per size (the same roots as one polyroots call each), then
    # the rows in order: the first failing row is reported, as a row-by-row pass would
    R, V = s1.shape[1], len(s0s)
    n1s = [_poly_fit_exact(t, s1[:, r] * det, deg) for r in range(R)]
    look = [(r, v) for r in range(R) for v in range(V) if keep is None or keep[v, r]]
    n0s = {(r, v): _poly_fit_exact(t, s0s[v][:, r] * det, deg) for r, v in look}
    crits = [critical_polynomial(n0s[rv], n1s[rv[0]]) for rv in look]
    found = roots_batch(n1s + crits)
    zeros1 = [[c.real for c in np.atleast_1d(z) if abs(c.imag) < ROOT_IMAG_TOL and -1.0 <= c.real <= 1.0]
              for z in found[:R]]  # fmt: skip
    crit_of = dict(zip(look, found[R:]))
    val = np.polynomial.polynomial.polyval
    lower, upper = -np.inf, np.inf
    fscales = [float(np.max(scale)) for scale in scales]
    for r, v in look:
        n1, n0, fscale = n1s[r], n0s[(r, v)], fscales[v]
        flat = tol.force * max(1e-300, float(np.max(np.abs(s1[:, r]))))
        cand = [-1.0, 1.0]
        cand += [c.real for c in np.atleast_1d(crit_of[(r, v)]) if abs(c.imag) < CRITICAL_IMAG_TOL and -1.0 < c.real < 1.0]
        for z in zeros1[r]:
            # at a root of the slope the row holds for every effort iff s0 >= 0 there
            if val(z, n0) / val(z, pdet) < -tol.force * fscale:
                return Band(mode.letters, joint, np.nan, np.nan, False,
                            f"coulomb: row {r} fails for every effort at mu = {mu_of(z):.6g}", "shared-roots")  # fmt: skip
        for c in cand:
            sl = val(c, n1) / val(c, pdet)
            if abs(sl) <= flat:
                if val(c, n0) / val(c, pdet) < -tol.force * fscale:
                    return Band(mode.letters, joint, np.nan, np.nan, False, f"coulomb: row {r} fails at mu = {mu_of(c):.6g}",
                                "shared-roots")  # fmt: skip
                continue
            e = -val(c, n0) / val(c, n1)
            if sl > 0:
                lower = max(lower, e)
            else:
                upper = min(upper, e)
    if lower > upper:
        return Band(mode.letters, joint, np.nan, np.nan, False, "coulomb: no effort works for every mu in the range", "shared-roots")
    return Band(mode.letters, joint, float(lower), float(upper), True, None, "shared-roots")


def bernstein_matrix(n: int, a, b) -> np.ndarray:
    """(m, n + 1, n + 1): the Bernstein coefficients on ``[a, b]`` (m,) of a degree-``n`` polynomial from its power coefficients."""
    h = b - a
    # T[m, j, i]: coefficient of t^i in (a + h t)^j
    j = np.arange(n + 1)
    C = np.array([[comb(jj, ii) for ii in range(n + 1)] for jj in range(n + 1)], dtype=float)
    expo = j[:, None] - j[None, :]
    T = C[None] * np.where(expo[None] >= 0, a[:, None, None] ** np.maximum(expo, 0)[None], 0.0) * h[:, None, None] ** j[None, None, :]
    # Bernstein: beta_k = sum_{i<=k} C(k,i)/C(n,i) d_i
    Bm = np.array([[comb(k, i) / comb(n, i) if i <= k else 0.0 for i in range(n + 1)] for k in range(n + 1)])
    return np.einsum("ki,mji->mkj", Bm, T)  # (m, K, j): control value k from power coefficient j
