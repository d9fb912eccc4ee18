"""Regions of contact modes in mu-space, exactly (Section 4, Appendices A and B).

Once the kinematic stage has fixed the sliding directions ``xi`` (eq. 16),
a mode's equilibrium-and-Coulomb test (26)-(28) is a system of polynomial
inequalities in the friction coefficients.  With ``D(mu) = det Q_AI(mu)`` and
``c_A = N(mu) / D(mu)`` (Cramer's rule, eqs. 46-47), each Coulomb slack of
(28) is ``P_i(mu) / D(mu)`` with

* ``P_i = N_{n,i}`` at a sliding contact (``c_in >= 0``), and
* ``P_i = mu_i N_{n,i} +/- N_{t,i}`` at a rolling contact (``mu_i c_in +/- c_it >= 0``),

all multilinear in the mu of the mode's rolling and sliding contacts and
linear in the effort inputs ``tau_I``.  The region of the mode is

    { D > 0 and P_i >= 0 for all i }  or  { D < 0 and P_i <= 0 for all i },

which for 3S modes is eqs. (35)-(36) with Appendix A's coefficients (50)-(57)
(:func:`~qsplan.mechanics.muspace.appendices.region_3s`) and for RS modes eqs. (40)-(41)
with Appendix B's (58)-(60) (:func:`~qsplan.mechanics.muspace.appendices.region_rs`).  :func:`mode_region` builds the same object for any mode
(2R, R2S, 4S, ..., Sections 4.4-4.6) from the column expansion of
:mod:`qsplan.mechanics.muspace.multilinear`; one code path serves all modes and the appendix
forms are a cross-check.

Boundaries.  ``P_i = 0`` belongs to the region (the paper's non-strict
inequalities; the solver accepts it within ``Tolerances.force``).  ``D = 0`` does
not: ``Q_AI`` is singular there, utility condition (31) fails and the solver
reports ``equilibrium_singular``; the forces grow without bound as ``D -> 0``.
Within a relative ``1e-9`` of either zero set the exact test and the solver's
toleranced one may differ (:meth:`MuRegion.near_boundary` flags those points).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qsplan.mechanics.modes.contact_mode import ContactMode, codes_to_letters
from qsplan.mechanics.muspace.multilinear import Multilinear, column_expansion
from qsplan.mechanics.muspace.zero_sets import ZeroBranch, bilinear_zero_set
from qsplan.mechanics.numerics import DEFAULT_TOLERANCES, Status, Tolerances
from qsplan.mechanics.model.scene import Scene
from qsplan.mechanics.modes.kinematics import Kinematics, ScenePool, check_mode_fits, single_mode_kinematics

__all__ = [
    "MuRegion",
    "BoundaryCurve",
    "EquilibriumPolynomials",
    "mode_kinematics",
    "polynomials_from_kinematics",
    "bounds_region",
    "equilibrium_polynomials",
    "mode_region",
    "region_from_polynomials",
    "empty_region",
]



def mode_kinematics(scene: Scene, mode, tol: Tolerances = DEFAULT_TOLERANCES) -> tuple[str, Kinematics | None]:
    """The mu-independent kinematic stage (eqs. 24-25, 16) of one mode.

    Returns
    -------
    status : str
        ``Status.FEASIBLE`` when the mode passed (then its region may be non-empty).
    kin : Kinematics or None
        One row, with the sliding directions ``xi``; None when the mode failed.
    """
    _, status, _, kin = single_mode_kinematics(scene, mode, tol)
    return status, kin


@dataclass(frozen=True, slots=True, eq=False)
class EquilibriumPolynomials:
    """``Q_AI(mu) = U + V diag(mu_S)`` of one mode and its multilinear expansion (eqs. 26, 46-47).

    Attributes
    ----------
    mode : ContactMode
    xi : ndarray, shape (n_c,)
        Sliding directions (eq. 16).
    col_contact : ndarray of int, shape (k,)
        Contact of each column of ``Q_AI`` (the solver's order: normal rows of the
        rolling and sliding contacts, then tangential rows of the rolling ones).
    col_normal : ndarray of bool, shape (k,)
        Column is a normal (not a tangential) constraint.
    sliding : tuple of int
        Sliding contacts, the variables of ``det_coef`` / ``adj_coef`` (bit i = sliding[i]).
    U, V : ndarray, shape (k, k)
        ``Q_AI = U + sum_i mu_{sliding[i]} V[:, col_i] e_{col_i}^T``.
    det_coef : ndarray, shape (2**n_S,)
    adj_coef : ndarray, shape (2**n_S, k, k)
        ``adj Q_AI(mu) = sum_b adj_coef[b] mu^b``.
    rhs0 : ndarray, shape (k,)
        ``[-g_obj; -g_man_I]``; the right-hand side of (26) is ``rhs0 + [0; tau_I]``.
    """

    mode: ContactMode
    xi: np.ndarray
    col_contact: np.ndarray
    col_normal: np.ndarray
    sliding: tuple
    U: np.ndarray
    V: np.ndarray
    det_coef: np.ndarray
    adj_coef: np.ndarray
    rhs0: np.ndarray

    def rhs(self, tau_e) -> np.ndarray:
        """Right-hand side of eq. (26) for efforts ``tau_e`` (shape (n_e,)), shape (k,)."""
        r = self.rhs0.copy()
        r[3:] += np.asarray(tau_e, dtype=float)
        return r

    def denominator(self) -> Multilinear:
        """``det Q_AI(mu)``."""
        return Multilinear(self.sliding, self.det_coef)

    def numerators(self, tau_e) -> tuple:
        """``N_j(mu)`` with ``c_A[j] = N_j / det Q_AI`` (eqs. 46-47), one per column; linear in ``tau_e``."""
        coef = self.adj_coef @ self.rhs(tau_e)  # (2**n_S, k)
        return tuple(Multilinear(self.sliding, coef[:, j]) for j in range(coef.shape[1]))

    def column(self, contact: int, normal: bool) -> int:
        """Column of ``Q_AI`` (index into ``c_A``) of a contact's normal or tangential constraint."""
        return int(np.flatnonzero((self.col_contact == contact) & (self.col_normal == normal))[0])


def polynomials_from_kinematics(scene: Scene, pool: ScenePool, kin: Kinematics, row: int) -> EquilibriumPolynomials:
    n_c = scene.n_contacts
    E = pool.E
    idx, contact, slide = kin.idx[row], kin.contact[row], kin.slide[row]
    xi = kin.xi[row]
    rows = np.hstack([pool.Wrows, pool.Jrows[:, E]])  # (2 n_c, 3 + n_e): a column of Q_AI per row
    U = rows[idx].T.copy()
    V = np.zeros_like(U)
    cols = np.flatnonzero(slide)
    V[:, cols] = -(xi[contact[cols]])[None, :] * rows[idx[cols] + n_c].T  # eq. (18)-(20): -mu xi w_t
    det_coef, adj_coef = column_expansion(U, V, cols)
    rhs0 = np.concatenate([-scene.g_obj, -scene.g_man[E]])
    mode = ContactMode(codes_to_letters(kin.codes[row]))
    return EquilibriumPolynomials(
        mode=mode, xi=xi.copy(), col_contact=contact.copy(), col_normal=idx < n_c,
        sliding=tuple(int(c) for c in contact[cols]), U=U, V=V, det_coef=det_coef, adj_coef=adj_coef, rhs0=rhs0,
    )  # fmt: skip


def equilibrium_polynomials(scene: Scene, mode, tol: Tolerances = DEFAULT_TOLERANCES) -> EquilibriumPolynomials | None:
    """The multilinear form of ``Q_AI`` of a mode (Sections 4.4-4.6); None if its kinematics fail."""
    status, kin = mode_kinematics(scene, mode, tol)
    return None if kin is None else polynomials_from_kinematics(scene, ScenePool(scene), kin, 0)


@dataclass(frozen=True, slots=True, eq=False)
class BoundaryCurve:
    """A piece of a region's boundary on a 2-D slice: where one inequality is tight.

    Attributes
    ----------
    mode : ContactMode
    label : str
        The inequality, e.g. ``"c_n3 >= 0"`` or ``"det Q_AI = 0"``.
    points : ndarray, shape (m, 2)
        Points ``(mu_x, mu_y)`` on the zero set of the boundary polynomial (exact up to rounding).
    """

    mode: ContactMode
    label: str
    points: np.ndarray


@dataclass(frozen=True, slots=True, eq=False)
class MuRegion:
    """The set of friction coefficients for which one mode is feasible (eqs. 28, 35-36, 40-41).

    Attributes
    ----------
    mode : ContactMode
    kinematic_status : str
        ``Status.FEASIBLE`` if the kinematic stage passed; otherwise the region is empty.
    xi : ndarray, shape (n_c,)
        Sliding directions (eq. 16); zeros when the kinematics failed.
    denominator : Multilinear
        ``D(mu)``: ``det Q_AI`` up to a sign fixed by the column order.
    numerators : tuple of Multilinear
        ``P_i(mu)``: the Coulomb slacks of (28) are ``P_i / D``.
    labels : tuple of str
        The inequality of each numerator.
    source : str
        Which formulas built it.
    """

    mode: ContactMode
    kinematic_status: str
    xi: np.ndarray
    denominator: Multilinear
    numerators: tuple
    labels: tuple
    source: str

    @property
    def variables(self) -> tuple:
        """Contacts whose mu the region depends on (0-based)."""
        vs = set(self.denominator.variables)
        for p in self.numerators:
            vs |= set(p.variables)
        return tuple(sorted(vs))

    def boundary_polynomials(self) -> tuple:
        """``(D, P_1, ..., P_m)``: the region's boundary lies in the union of their zero sets."""
        return (self.denominator, *self.numerators)

    def _values(self, mu):
        mu = np.asarray(mu, dtype=float)
        D = self.denominator(mu)
        P = np.stack([p(mu) for p in self.numerators], axis=-1) if self.numerators else np.zeros(D.shape + (0,))
        return D, P

    def contains(self, mu) -> np.ndarray:
        """Whether the mode is feasible at ``mu`` (shape (..., n_c)), exactly; returns bool (...).

        ``D = 0`` is outside, ``P_i = 0`` inside (see the module notes).
        """
        if self.kinematic_status != Status.FEASIBLE:
            return np.zeros(np.shape(mu)[:-1], dtype=bool)
        D, P = self._values(mu)
        return ((D > 0) & np.all(P >= 0, axis=-1)) | ((D < 0) & np.all(P <= 0, axis=-1))

    def slacks(self, mu) -> np.ndarray:
        """The Coulomb slacks ``B_A c_A`` of (28) at ``mu``, shape (..., m) (N)."""
        D, P = self._values(mu)
        with np.errstate(divide="ignore", invalid="ignore"):
            return P / D[..., None]

    def near_boundary(self, mu, rel: float = 1e-9) -> np.ndarray:
        """Points where a boundary polynomial is within ``rel`` of zero, relative to the sum of
        its terms' magnitudes (its rounding scale); shape (...)."""
        mu = np.asarray(mu, dtype=float)
        out = np.zeros(mu.shape[:-1], dtype=bool)
        if self.kinematic_status != Status.FEASIBLE:
            return out
        for p in self.boundary_polynomials():
            out |= np.abs(p(mu)) <= rel * p.abs_terms(mu)
        return out

    def boundary_curves(self, x: int, y: int, base_mu, xlim, ylim, n: int = 400) -> list:
        """The region's boundary on the slice through ``base_mu`` spanned by ``mu_x``, ``mu_y``.

        Each boundary polynomial restricted to the slice is bilinear; its zero set is
        computed exactly (:func:`~qsplan.mechanics.muspace.zero_sets.bilinear_zero_set`) and kept
        where it bounds the region: on ``P_i = 0`` where the other inequalities hold
        and ``D != 0``, on ``D = 0`` where all ``P_j`` share a sign.  Piece ends are
        refined by bisection on the curve.

        Parameters
        ----------
        x, y : int
            0-based contacts of the axes.
        base_mu : array-like, shape (n_c,)
        xlim, ylim : (float, float)
        n : int
            Samples per axis of each curve.

        Returns
        -------
        list of BoundaryCurve
        """
        if self.kinematic_status != Status.FEASIBLE:
            return []
        polys = self.boundary_polynomials()
        bil = np.array([p.bilinear(x, y, base_mu) for p in polys])  # (m+1, 4)
        labels = ("det Q_AI = 0", *(f"{lab.split('>=')[0].strip()} = 0" for lab in self.labels))
        out = []
        for ip in range(len(polys)):
            if not np.any(bil[ip, 1:]):
                continue  # constant on the slice: no curve (or everywhere, if 0)
            for br in bilinear_zero_set(bil[ip], xlim, ylim, n):
                for pts in _active_pieces(br, bil, ip):
                    out.append(BoundaryCurve(self.mode, labels[ip], pts))
        return out


def _bil_values(bil, pts):
    x, y = pts[:, 0, None], pts[:, 1, None]
    return bil[:, 0] + bil[:, 1] * x + bil[:, 2] * y + bil[:, 3] * x * y  # (m, n_poly)


def bounds_region(bil, ip, pts, rel=1e-12):
    """On the zero set of polynomial ``ip``: does the point bound the region?

    Parameters
    ----------
    bil : ndarray, shape (m, 1 + n_poly, 4)
        Bilinear coefficients ``[1, x, y, xy]`` of the denominator and the numerators at each point.
    ip : int
        0 for the denominator, ``1 + i`` for numerator ``i``.
    pts : ndarray, shape (m, 2)
    rel : float
        Relative tolerance of the other polynomials' signs.

    Returns
    -------
    ndarray of bool, shape (m,)
    """
    vals = _bil_values(bil, pts)
    scale = rel * (np.abs(bil[:, 0]) + np.abs(bil[:, 1] * pts[:, 0, None]) + np.abs(bil[:, 2] * pts[:, 1, None])
                   + np.abs(bil[:, 3] * pts[:, 0, None] * pts[:, 1, None]))  # fmt: skip
    D, P, sP = vals[:, 0], vals[:, 1:], scale[:, 1:]
    if ip == 0:
        return np.all(P >= -sP, axis=1) | np.all(P <= sP, axis=1)
    others = np.ones(P.shape[1], dtype=bool)
    others[ip - 1] = False
    sgn = np.sign(D)[:, None]
    return (np.abs(D) > scale[:, 0]) & np.all(sgn * P[:, others] >= -sP[:, others], axis=1)


def _active_pieces(br: ZeroBranch, bil, ip, iters: int = 60) -> list:
    t = br.t
    act = bounds_region(bil, ip, br.points(t))
    if not act.any():
        return []
    pieces = []
    idx = np.flatnonzero(act)
    for run in np.split(idx, np.flatnonzero(np.diff(idx) > 1) + 1):
        ts = list(t[run])
        for end, (inside, outside) in (("lo", (run[0], run[0] - 1)), ("hi", (run[-1], run[-1] + 1))):
            if 0 <= outside < t.size:
                a, b = t[inside], t[outside]
                for _ in range(iters):  # bisection for where the piece ends on the curve
                    m = 0.5 * (a + b)
                    if bounds_region(bil, ip, br.points(np.array([m])))[0]:
                        a = m
                    else:
                        b = m
                if end == "lo":
                    ts.insert(0, a)
                else:
                    ts.append(a)
        if len(ts) >= 2:
            pieces.append(br.points(np.array(ts)))
    return pieces


def _slack_numerators(eqp: EquilibriumPolynomials, tau_e):
    """The numerators ``P_i`` of the Coulomb slacks (28) and their labels, in contact order."""
    N = eqp.numerators(tau_e)
    polys, labels = [], []
    for i, letter in enumerate(eqp.mode.letters):
        if letter == "S":
            polys.append(N[eqp.column(i, True)])
            labels.append(f"c_n{i + 1} >= 0")
        elif letter == "R":
            raw = N[eqp.column(i, True)]
            nn, tt = raw.times(i), N[eqp.column(i, False)]
            polys += [nn + tt, nn - tt, raw]  # c_n >= 0 (eq. 9): implied by the cone rows only when mu_i > 0
            labels += [f"mu{i + 1} c_n{i + 1} + c_t{i + 1} >= 0", f"mu{i + 1} c_n{i + 1} - c_t{i + 1} >= 0", f"c_n{i + 1} >= 0"]
    return tuple(polys), tuple(labels)


def region_from_polynomials(eqp: EquilibriumPolynomials, tau_e) -> MuRegion:
    """The region of a kinematically admissible mode from its :class:`EquilibriumPolynomials`."""
    polys, labels = _slack_numerators(eqp, tau_e)
    return MuRegion(eqp.mode, Status.FEASIBLE, eqp.xi, eqp.denominator(), polys, labels, _GENERAL)


_GENERAL = "general: Cramer's rule on Q_AI (eqs. 26, 28, 46-47)"


def empty_region(mode: ContactMode, status: str, n_c: int, source: str = _GENERAL) -> MuRegion:
    """The empty region of a mode whose kinematic stage failed with ``status``."""
    return MuRegion(mode, status, np.zeros(n_c), Multilinear.constant(0.0), (), (), source)


def mode_region(scene: Scene, mode, tau_e=None, tol: Tolerances = DEFAULT_TOLERANCES) -> MuRegion:
    """The region of any mode from the general formulas (eqs. 26, 28, 46-47; Sections 4.4-4.6).

    Parameters
    ----------
    scene : Scene
        Its ``mu`` is ignored; its control-mode partition fixes the mode's size.
    mode : ContactMode or str
    tau_e : array-like, shape (n_e,), optional
        Efforts of the effort-controlled joints (default: the scene's); the
        numerators are linear in them.

    Returns
    -------
    MuRegion
        Empty (``kinematic_status`` says why) when the kinematic stage fails.
    """
    mode = check_mode_fits(scene, mode)
    status, kin = mode_kinematics(scene, mode, tol)
    if kin is None:
        return empty_region(mode, status, scene.n_contacts, _GENERAL)
    eqp = polynomials_from_kinematics(scene, ScenePool(scene), kin, 0)
    tau = np.nan_to_num(scene.joint_effort)[scene.effort_joints] if tau_e is None else np.asarray(tau_e, float)
    return region_from_polynomials(eqp, tau)
