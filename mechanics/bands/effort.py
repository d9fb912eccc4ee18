"""Effort bands: the efforts of one effort-controlled joint for which a contact mode is feasible.

With one effort-controlled joint, the kinematics of a mode (eq. 24) do not
depend on the effort or on friction, and the wrench intensities are affine in
the effort: ``c_A(tau) = Q_AI^{-1} ([-g_obj; -g_man_I] + tau e)`` (eq. 26).
Every Coulomb inequality of eq. (28) is then ``s_r(tau) = s0_r + tau s1_r >= 0``,
a half-line of efforts, and the band is their intersection (Section 5.2,
Figs. 10-12).

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
  polynomial's roots (critical points and sign changes), not from samples.

:func:`sampled_band` keeps the paper's method (intersection over a list of mu)
for comparison.
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import product

import numpy as np

from qsplan.mechanics.errors import SceneError
from qsplan.mechanics.modes.contact_mode import ContactMode
from qsplan.mechanics.numerics import DEFAULT_TOLERANCES, Status, Tolerances
from qsplan.mechanics.model.scene import Scene
from qsplan.mechanics.solver.batch import ScenePool, equilibrium_matrix, single_mode_kinematics

__all__ = [
    "Band",
    "ModeKinematics",
    "band_kinematics",
    "band_rows",
    "effort_band",
    "effort_bands",
    "guaranteed_band_box",
    "guaranteed_band_shared",
    "sampled_band",
    "possible_band_box",
]


@dataclass(frozen=True, slots=True)
class Band:
    """An interval of efforts ``[lower, upper]`` of the effort-controlled joint (N m or N).

    Attributes
    ----------
    mode : str
        Mode letters.
    joint : int
        0-based index of the effort-controlled joint.
    lower, upper : float
        Band edges; ``-inf`` / ``inf`` for an unbounded side (never a large number).
    feasible : bool
        False when no effort works (empty band, kinematics fail, or degenerate).
    reason : str or None
        Why it is infeasible, or a remark on how it was computed.
    method : str
        ``"point"``, ``"box-vertices"``, ``"shared-roots"``, ``"sampled"`` or ``"possible-superset"``.
    exact : bool
        True when the band is exact; False when conservative (narrower than or
        equal to the true guaranteed band, or for ``possible_band_box`` wider).
    """

    mode: str
    joint: int
    lower: float
    upper: float
    feasible: bool
    reason: str | None = None
    method: str = "point"
    exact: bool = True

    @property
    def width(self) -> float:
        """``upper - lower`` (inf when unbounded, 0 when infeasible)."""
        return self.upper - self.lower if self.feasible else 0.0

    def contains(self, tau: float) -> bool:
        """Whether ``tau`` lies in the band (edges included)."""
        return self.feasible and self.lower <= tau <= self.upper

    def to_dict(self) -> dict:
        """The ``qsplan band --json`` document: ``null`` for an unbounded side."""
        d = {
            "mode": self.mode,
            "feasible": self.feasible,
            "lower": None if not np.isfinite(self.lower) else float(self.lower),
            "upper": None if not np.isfinite(self.upper) else float(self.upper),
        }
        if not self.feasible:
            d["lower"] = d["upper"] = None
            d["reason"] = self.reason
        d["method"] = self.method
        d["exact"] = self.exact
        return d


@dataclass(frozen=True, slots=True, eq=False)
class ModeKinematics:
    """A mode's mu- and effort-independent kinematic solution, or why it has none."""

    mode: ContactMode
    status: str
    pool: ScenePool
    kin: object  # solver.Kinematics with one row, or None

    @property
    def ok(self) -> bool:
        return self.status == Status.FEASIBLE


def _check_one_effort_joint(scene: Scene) -> int:
    E = scene.effort_joints
    if E.size != 1:
        raise SceneError(
            f"joints: effort bands need exactly one effort-controlled joint; the scene has {E.size}"
        )
    return int(E[0])


def band_kinematics(scene: Scene, mode: ContactMode, tol: Tolerances = DEFAULT_TOLERANCES) -> ModeKinematics:
    """Run the kinematic stage (eqs. 24-25, 16) for one mode."""
    return ModeKinematics(*single_mode_kinematics(scene, mode, tol))


def band_rows(scene: Scene, mk: ModeKinematics, mu_rows) -> tuple:
    """Coulomb slacks of eq. (28) as affine functions of the effort, at each mu row.

    Parameters
    ----------
    scene : Scene
        With exactly one effort-controlled joint.
    mk : ModeKinematics
        With ``mk.ok``.
    mu_rows : array-like, shape (N, n_c)

    Returns
    -------
    s0, s1 : ndarray, shape (N, r)
        ``s(tau) = s0 + tau * s1`` for the mode's r Coulomb rows: ``mu c_n + c_t`` and
        ``mu c_n - c_t`` and ``c_n`` per rolling contact, ``c_n`` per sliding contact.
    det : ndarray, shape (N,)
        ``det Q_AI`` (sign and size tell singularity).
    scale : ndarray, shape (N,)
        Force scale of each row set (N), for tolerances.
    """
    mu_rows = np.atleast_2d(np.asarray(mu_rows, dtype=float))
    N, n_c = mu_rows.shape[0], scene.n_contacts
    kin = mk.kin.take(np.zeros(N, dtype=int))
    Q = equilibrium_matrix(mk.pool, kin, mu_rows)
    det = np.linalg.det(Q)
    E = mk.pool.E
    r0 = np.concatenate([-scene.g_obj, -scene.g_man[E]])
    e = np.zeros_like(r0)
    e[3] = 1.0
    bad = ~np.isfinite(det) | (det == 0)
    Qs = Q.copy()
    Qs[bad] = np.eye(Q.shape[1])
    sol = np.linalg.solve(Qs, np.broadcast_to(np.column_stack([r0, e]), (N, r0.size, 2)))  # (N, k, 2)
    idx, contact = kin.idx, kin.contact
    rows_n = idx < n_c
    letters = mk.mode.letters
    out0, out1 = [], []
    for c in range(n_c):
        if letters[c] == "B":
            continue
        jn = int(np.flatnonzero(rows_n[0] & (contact[0] == c))[0])
        cn = sol[:, jn, :]  # (N, 2): value at tau = 0, slope
        if letters[c] == "R":
            jt = int(np.flatnonzero(~rows_n[0] & (contact[0] == c))[0])
            ct = sol[:, jt, :]
            m = mu_rows[:, c : c + 1]
            for sgn in (1.0, -1.0):
                row = m * cn + sgn * ct
                out0.append(row[:, 0])
                out1.append(row[:, 1])
            out0.append(cn[:, 0])  # c_n >= 0 (eq. 9); implied by the cone rows only when mu > 0
            out1.append(cn[:, 1])
        else:
            out0.append(cn[:, 0])
            out1.append(cn[:, 1])
    s0 = np.column_stack(out0)
    s1 = np.column_stack(out1)
    scale = np.maximum(np.max(np.abs(sol[:, :, 0]), axis=1), np.max(np.abs(r0)))
    s0[bad] = np.nan
    s1[bad] = np.nan
    return s0, s1, det, scale


def _intersect_rows(s0, s1, scale, tol: Tolerances):
    """Band edges of ``s0 + tau s1 >= 0`` over rows, per mu row: lower, upper, ok (N,)."""
    ftol = tol.force * scale[:, None]
    big = np.max(np.abs(s1), axis=1, keepdims=True)
    flat = np.abs(s1) <= tol.force * big  # effort does not move this row (relative to the mode's largest slope)
    with np.errstate(divide="ignore", invalid="ignore"):
        edge = -s0 / s1
    lower = np.max(np.where(~flat & (s1 > 0), edge, -np.inf), axis=1)
    upper = np.min(np.where(~flat & (s1 < 0), edge, np.inf), axis=1)
    flat_ok = np.all(~flat | (s0 >= -ftol), axis=1)
    ok = flat_ok & (lower <= upper) & np.all(np.isfinite(s0), axis=1)
    return lower, upper, ok


def effort_bands(scene: Scene, mode: ContactMode, mu_rows, tol: Tolerances = DEFAULT_TOLERANCES):
    """Bands of ``mode`` at many friction points at once.

    Returns
    -------
    lower, upper : ndarray, shape (N,)
    ok : ndarray of bool, shape (N,)
        False where the band is empty, the kinematics fail or ``Q_AI`` is singular.
    """
    _check_one_effort_joint(scene)
    mu_rows = np.atleast_2d(np.asarray(mu_rows, dtype=float))
    mk = band_kinematics(scene, mode, tol)
    N = mu_rows.shape[0]
    if not mk.ok:
        return np.full(N, np.nan), np.full(N, np.nan), np.zeros(N, dtype=bool)
    s0, s1, det, scale = band_rows(scene, mk, mu_rows)
    lower, upper, ok = _intersect_rows(s0, s1, scale, tol)
    return lower, upper, ok


def effort_band(scene: Scene, mode: ContactMode, mu=None, tol: Tolerances = DEFAULT_TOLERANCES) -> Band:
    """The band of ``mode`` at the scene's friction (or at ``mu``), eq. (28).

    Parameters
    ----------
    scene : Scene
        Exactly one effort-controlled joint; its commanded effort is ignored.
    mode : ContactMode
    mu : array-like, shape (n_c,), optional
    """
    joint = _check_one_effort_joint(scene)
    mk = band_kinematics(scene, mode, tol)
    if not mk.ok:
        return Band(mode.letters, joint, np.nan, np.nan, False, f"kinematics: {mk.status}")
    mu = scene.mu if mu is None else np.broadcast_to(np.asarray(mu, float), (scene.n_contacts,))
    s0, s1, det, scale = band_rows(scene, mk, mu[None])
    if not np.isfinite(s0).all():
        return Band(mode.letters, joint, np.nan, np.nan, False, "equilibrium_singular")
    lower, upper, ok = _intersect_rows(s0, s1, scale, tol)
    if not ok[0]:
        return Band(mode.letters, joint, np.nan, np.nan, False, "coulomb: no effort satisfies eq. (28)")
    return Band(mode.letters, joint, float(lower[0]), float(upper[0]), True)


def _box_vertices(scene: Scene, mode: ContactMode, lo, hi) -> np.ndarray:
    n_c = scene.n_contacts
    lo = np.broadcast_to(np.asarray(lo, float), (n_c,))
    hi = np.broadcast_to(np.asarray(hi, float), (n_c,))
    if np.any(lo > hi) or np.any(lo < 0) or not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi))):
        raise SceneError(f"mu range: expected 0 <= lo <= hi, finite; got lo={lo.tolist()}, hi={hi.tolist()}")
    free = [c for c in range(n_c) if mode.letters[c] != "B" and hi[c] > lo[c]]
    verts = np.tile(lo, (2 ** len(free), 1))
    for k, bits in enumerate(product((0, 1), repeat=len(free))):
        for c, b in zip(free, bits):
            verts[k, c] = hi[c] if b else lo[c]
    return verts


def guaranteed_band_box(scene: Scene, mode: ContactMode, lo, hi, tol: Tolerances = DEFAULT_TOLERANCES) -> Band:
    """Efforts for which ``mode`` is feasible for **every** mu with ``lo <= mu_i <= hi`` (exact).

    Parameters
    ----------
    lo, hi : float or array-like, shape (n_c,)
        Independent intervals per contact (breaking contacts' mu do not matter).
    """
    joint = _check_one_effort_joint(scene)
    verts = _box_vertices(scene, mode, lo, hi)
    mk = band_kinematics(scene, mode, tol)
    if not mk.ok:
        return Band(mode.letters, joint, np.nan, np.nan, False, f"kinematics: {mk.status}", "box-vertices")
    s0, s1, det, scale = band_rows(scene, mk, verts)
    if not (np.all(det > 0) or np.all(det < 0)):
        return Band(
            mode.letters, joint, np.nan, np.nan, False,
            "equilibrium_singular: det Q_AI changes sign inside the mu box (the mode is degenerate there)",
            "box-vertices",
        )  # fmt: skip
    lower, upper, ok = _intersect_rows(s0, s1, scale, tol)
    if not ok.all():
        return Band(mode.letters, joint, np.nan, np.nan, False, "coulomb: no effort works at some vertex of the mu box", "box-vertices")
    lo_, up_ = float(lower.max()), float(upper.min())
    if lo_ > up_:
        return Band(mode.letters, joint, np.nan, np.nan, False, "coulomb: vertex bands do not overlap", "box-vertices")
    return Band(mode.letters, joint, lo_, up_, True, None, "box-vertices")


def possible_band_box(scene: Scene, mode: ContactMode, lo, hi, tol: Tolerances = DEFAULT_TOLERANCES) -> Band:
    """An interval containing every effort for which ``mode`` is feasible for **some** mu in the box.

    Used to preclude a competing mode: outside this interval the mode is
    infeasible for every mu in the box.  Each Coulomb row alone is exactly
    feasible for some mu iff it holds at some vertex (``max`` of a multilinear
    function); requiring every row separately gives a superset of the true set
    (``exact=False``: conservative for precluding).  When ``det Q_AI`` changes sign
    in the box, the mode may be feasible for any effort near the singularity:
    the whole line is returned.
    """
    joint = _check_one_effort_joint(scene)
    verts = _box_vertices(scene, mode, lo, hi)
    mk = band_kinematics(scene, mode, tol)
    if not mk.ok:
        return Band(mode.letters, joint, np.nan, np.nan, False, f"kinematics: {mk.status}", "possible-superset", True)
    s0, s1, det, scale = band_rows(scene, mk, verts)
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


def sampled_band(scene: Scene, mode: ContactMode, mu_rows, tol: Tolerances = DEFAULT_TOLERANCES) -> Band:
    """The paper's method: intersect the point bands over the listed mu (e.g. 0, 0.01, ..., 0.2).

    Parameters
    ----------
    mu_rows : array-like, shape (N, n_c) or (N,)
        Friction points; a 1-D array gives one shared coefficient per sample.
    """
    joint = _check_one_effort_joint(scene)
    mu_rows = np.asarray(mu_rows, dtype=float)
    if mu_rows.ndim == 1:
        mu_rows = np.repeat(mu_rows[:, None], scene.n_contacts, axis=1)
    lower, upper, ok = effort_bands(scene, mode, mu_rows, tol)
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


def guaranteed_band_shared(scene: Scene, mode: ContactMode, lo: float, hi: float, tol: Tolerances = DEFAULT_TOLERANCES) -> Band:
    """Efforts for which ``mode`` is feasible for every shared coefficient ``mu`` in ``[lo, hi]`` (exact).

    With one coefficient shared by all contacts, ``det Q_AI`` is a polynomial of
    degree ``n_S`` in mu and ``det Q_AI * s_r`` one of degree ``n_S + 1``; both are
    recovered exactly from ``n_S + 2`` evaluations at Chebyshev points.  Each row
    bounds the effort by ``-N0_r(mu) / N1_r(mu)``; its extremes over the interval
    are taken at the ends, at the real roots of ``N0' N1 - N0 N1'`` and in the
    limits at roots of ``N1`` (where the bound leaves to infinity, harmlessly if
    the row holds there and fatally if not).  A root of ``det Q_AI`` inside the
    interval means a degenerate mode: nothing is guaranteed.
    """
    joint = _check_one_effort_joint(scene)
    if not (np.isfinite(lo) and np.isfinite(hi)) or lo < 0 or lo > hi:
        raise SceneError(f"mu range: expected 0 <= lo <= hi, finite; got {lo}, {hi}")
    mk = band_kinematics(scene, mode, tol)
    if not mk.ok:
        return Band(mode.letters, joint, np.nan, np.nan, False, f"kinematics: {mk.status}", "shared-roots")
    if hi == lo:
        b = effort_band(scene, mode, np.full(scene.n_contacts, lo), tol)
        return Band(b.mode, joint, b.lower, b.upper, b.feasible, b.reason, "shared-roots")
    deg = len(mode.sliding) + 1
    nodes = 0.5 * (lo + hi) + 0.5 * (hi - lo) * np.cos(np.pi * (np.arange(deg + 1) + 0.5) / (deg + 1))
    s0, s1, det, scale = band_rows(scene, mk, np.repeat(nodes[:, None], scene.n_contacts, axis=1))
    pdet = _poly_fit_exact(nodes, det, deg)
    P = np.polynomial.Polynomial
    roots_det = [r.real for r in P(pdet).roots() if abs(r.imag) < 1e-12 and lo <= r.real <= hi]
    if roots_det or np.any(det == 0):
        return Band(mode.letters, joint, np.nan, np.nan, False,
                    f"equilibrium_singular: det Q_AI vanishes at mu = {roots_det[0] if roots_det else nodes[det == 0][0]:.6g}",
                    "shared-roots")  # fmt: skip
    lower, upper = -np.inf, np.inf
    fscale = float(np.max(scale))
    for r in range(s0.shape[1]):
        n0 = P(_poly_fit_exact(nodes, s0[:, r] * det, deg))
        n1 = P(_poly_fit_exact(nodes, s1[:, r] * det, deg))
        d = P(pdet)
        cand = [lo, hi]
        crit = (n0.deriv() * n1 - n0 * n1.deriv()).roots()
        cand += [c.real for c in np.atleast_1d(crit) if abs(c.imag) < 1e-9 and lo < c.real < hi]
        zeros1 = [c.real for c in np.atleast_1d(n1.roots()) if abs(c.imag) < 1e-12 and lo <= c.real <= hi]
        for z in zeros1:
            # at a root of the slope the row holds for every effort iff s0 >= 0 there
            if n0(z) / d(z) < -tol.force * fscale:
                return Band(mode.letters, joint, np.nan, np.nan, False,
                            f"coulomb: row {r} fails for every effort at mu = {z:.6g}", "shared-roots")  # fmt: skip
        for c in cand:
            sl = n1(c) / d(c)
            if abs(sl) <= tol.force * max(1e-300, float(np.max(np.abs(s1[:, r])))):
                if n0(c) / d(c) < -tol.force * fscale:
                    return Band(mode.letters, joint, np.nan, np.nan, False, f"coulomb: row {r} fails at mu = {c:.6g}", "shared-roots")
                continue
            e = -n0(c) / n1(c)
            if sl > 0:
                lower = max(lower, e)
            else:
                upper = min(upper, e)
    if lower > upper:
        return Band(mode.letters, joint, np.nan, np.nan, False, "coulomb: no effort works for every mu in the range", "shared-roots")
    return Band(mode.letters, joint, float(lower), float(upper), True, None, "shared-roots")
