"""Precluding a competing contact mode over uncertain friction (Section 5.2, Figs. 12-13).

To guarantee a desired mode the effort must keep it feasible for every friction
coefficient in the uncertainty set (:func:`qsplan.mechanics.guaranteed_band_box`,
:func:`qsplan.mechanics.guaranteed_band_shared`) **and** make every competing mode
infeasible for every one of them.  :func:`competitor_torques` finds, inside a
given effort interval ``G``, the hull ``[lower, upper]`` of the efforts for which
a competing mode is feasible for *some* friction in the set; subtracting it from
``G`` precludes the mode.

Method (branch and bound over friction cells, exact to a tolerance):

* A competing mode's Coulomb rows are ``s_r = N_r(mu, tau) / det Q_AI(mu)`` with
  ``N_r`` and ``det Q_AI`` multilinear in the mu's (box) or polynomials of degree
  ``n_S + 1`` in one shared mu, and ``N_r`` affine in the effort (eqs. 26-28).
* On a cell (a sub-box, or a sub-interval of the shared coefficient) the range of
  a multilinear function lies between its vertex values, and that of a polynomial
  between its Bernstein coefficients.  Where ``det`` keeps its sign, row ``r`` can
  hold somewhere in the cell only for efforts where some control value of
  ``sgn(det) N_r`` is nonnegative: a union of half-lines; the cell's possible
  efforts lie in the intersection over rows.  Where ``det`` changes sign (the
  mode is singular inside the cell), a pair of rows whose numerators keep
  opposite signs on the whole cell still excludes the effort.
* Where ``det`` keeps its sign on a cell and the per-row bound leaves the cell open, a
  certificate (:mod:`qsplan.mechanics.bands.certificates`: a combination of rows negative at
  every control value, found by a small linear programme) proves efforts infeasible on the
  whole cell at once, rows that fail at different vertices included (tried once a search has
  spent :data:`CERTIFY_AFTER` cells, within :data:`~qsplan.mechanics.bands.certificates.MAX_CERTIFICATES`).
* Cells are bisected best-first, each along the side where its control values
  change most.  Every evaluated friction point whose band (from the model, eq. 28)
  is not empty gives a truly feasible effort (an incumbent); cells whose bound
  cannot beat the incumbent by more than the tolerance are dropped.  The reported
  end is the smallest bound left, so it never lies inside the competitor's true
  set: the result is exact to ``tol`` when the search finishes, and conservative
  (wider) when it runs out of its cell budget, which is said in the result.
* With a box of disturbance wrenches (:mod:`qsplan.mechanics.bands.disturbance`) the competitor is
  possible if some friction **and some wrench** of the box admit it: a projection, whose extreme may lie
  inside the wrench box.  The wrench is three more sides of every cell
  (:class:`qsplan.mechanics.bands.cells.FrictionCells`): ``N_r`` is multilinear in (friction, wrench), so
  the control values at the product cell's vertices bound it with common weights, and every argument
  below holds unchanged; a certificate covers the whole wrench cell at once (exact at fixed friction).
* Unbounded sides are explicit: a cell may admit arbitrarily low efforts (bound
  ``-inf``: every row falls with the effort at some control point); such a cell
  is kept and, if the budget runs out, reported as ``-inf`` (conservative), never
  dropped.  The end is proved infinite only by a friction point whose band is
  itself unbounded on that side.  "Nothing possible" and "possible to infinity"
  are different answers (``empty`` against an infinite ``lower`` / ``upper``).

The hull may contain efforts where the competitor is infeasible (if its feasible
efforts are not an interval): precluding the hull is then conservative.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qsplan.mechanics.bands.cells import FrictionCells, point_bands
from qsplan.mechanics.bands.certificates import MAX_CERTIFICATES, certified_lower_bounds
from qsplan.mechanics.bands.disturbance import check_wrench_box
from qsplan.mechanics.bands.effort import band_kinematics
from qsplan.mechanics.errors import SceneError
from qsplan.mechanics.model.friction import check_mu_range
from qsplan.mechanics.modes.contact_mode import mode_from_letters
from qsplan.mechanics.numerics import DEFAULT_TOLERANCES, Tolerances

__all__ = ["CERTIFY_AFTER", "MAX_CELLS", "PRECLUSION_RTOL", "CompetitorTorques", "cell_lower_bounds", "competitor_torques",
           "extreme_lower_bounds", "friction_set", "point_bands", "wrench_extremes"]

#: Relative tolerance of the branch and bound (of the effort interval's largest finite
#: edge, or 1 N m): the search stops when no cell can lower the bound by more.  The
#: reported edge is always on the safe side, so the tolerance only costs band width;
#: 1e-6 of the torque scale is far below any torque controller's resolution.
PRECLUSION_RTOL = 1e-6

#: Cells evaluated per search before it stops with a conservative answer.  The default
#: hand's competitors resolve in one or two cells (their extremes sit at vertices of the
#: friction box); random scenes take up to a few hundred; near a singular set of the
#: competitor (``det Q_AI`` changing sign) cells never resolve, and the budget bounds the time.
MAX_CELLS = 4000

#: Cells a search evaluates before it tries certificates (:mod:`qsplan.mechanics.bands.certificates`) on the
#: cells left open, a small share of :data:`MAX_CELLS`: searches the root cell leaves open mostly end within a
#: few dozen cells by bisection alone, and those that certificates rescue ran for thousands.  Measured: the
#: demo hand's segment 1 (200 states, shared friction) spent 41 programmes for no change at 0, 6 at 16, none
#: at 64; on 15 hard bands of the band-safety scenes 64 gives the answers of 0 (256 loses two exact bands).
CERTIFY_AFTER = 64

@dataclass(frozen=True, slots=True)
class CompetitorTorques:
    """Efforts inside ``G`` for which a competing mode may be feasible (N m or N).

    Attributes
    ----------
    mode : str
    lower, upper : float
        Hull of the competitor's possibly-feasible efforts inside ``G``; ``-inf`` / ``inf`` where
        it reaches an unbounded side of ``G``; NaN when it is infeasible for every effort in ``G``
        and every friction in the set (and every wrench of the disturbance box, if any).
    empty : bool
        The competitor is precluded on the whole of ``G`` (proved).
    exact : bool
        Both ends were found to the tolerance, an infinite end proved by a friction point whose
        band is unbounded there (False: budget exhausted, the hull is wider).
    reason : str or None
        ``"kinematics: ..."`` when the mode fails kinematically (never feasible), or why
        the answer is conservative.
    cells : int
        Friction cells evaluated.
    """

    mode: str
    lower: float
    upper: float
    empty: bool
    exact: bool
    reason: str | None = None
    cells: int = 0


def cell_lower_bounds(det, N0, N1, g_lo, g_hi, tol: Tolerances, wrenches: int = 1):
    """Smallest effort in ``[g_lo, g_hi]`` each cell may admit (inf: none), shape (m,).

    ``g_lo, g_hi``: floats, or arrays of shape (m,) (one interval per cell: the batched path).

    ``wrenches``: the control points come in that many blocks, one per vertex of the cell's wrench part, wrench-major
    (:class:`qsplan.mechanics.bands.cells.FrictionCells`' order), over which ``det`` and ``N1`` repeat (they do not
    depend on the wrench, eq. 26).  Every quantity below is then a correctly rounded difference ``(+-e - N0)`` divided
    by a slope the blocks share, reduced by a maximum or a minimum over the control points, or a comparison of ``N0``
    with ``+-e``: each monotone in ``N0``, so its extreme over the blocks sits at the block where ``N0`` is largest or
    smallest, bit for bit.  The bound is computed on each row's largest and smallest ``N0`` over the blocks (``e``,
    the magnitudes' largest, too): ``wrenches`` times fewer values, the same answer as ``wrenches=1``.
    """
    if wrenches == 1:
        return extreme_lower_bounds(det, N0, N0, N1, g_lo, g_hi, tol)
    K = N0.shape[1] // wrenches  # each row's extremes over the wrench blocks (the docstring): the same bound
    lo0, hi0 = wrench_extremes(N0[:, w * K : (w + 1) * K] for w in range(wrenches))
    return extreme_lower_bounds(det[:, :K], lo0, hi0, N1[:, :K], g_lo, g_hi, tol)


def wrench_extremes(blocks) -> tuple:
    """Elementwise smallest and largest of ``blocks`` (arrays of one shape): ``(lo0, hi0)``, NaN and infinities kept
    (``np.minimum`` and ``np.maximum`` propagate NaN)."""
    blocks = iter(blocks)
    lo0 = hi0 = next(blocks)
    for x in blocks:
        lo0, hi0 = np.minimum(lo0, x), np.maximum(hi0, x)
    return lo0, hi0


def extreme_lower_bounds(det, lo0, hi0, N1, g_lo, g_hi, tol: Tolerances):
    """:func:`cell_lower_bounds` from each row's smallest and largest ``N0`` over the cell's wrench vertices (``lo0``,
    ``hi0`` (m, K, R), the same array without a wrench box), ``det`` (m, K) and ``N1`` (m, K, R) at one of them."""
    m, K, R = hi0.shape
    g_lo, g_hi = (np.broadcast_to(np.asarray(g, dtype=float), (m,))[:, None] for g in (g_lo, g_hi))
    fin0 = np.isfinite(hi0) if lo0 is hi0 else np.isfinite(hi0) & np.isfinite(lo0)
    fin0 = fin0.reshape(m, K * R)  # per cell, flat: faster reductions
    fin1 = np.isfinite(N1).reshape(m, K * R)
    finite = np.all(np.isfinite(det), axis=1) & np.all(fin0, axis=1) & np.all(fin1, axis=1)
    pos, neg = np.all(det > 0, axis=1), np.all(det < 0, axis=1)
    steady = finite & (pos | neg)
    # the largest magnitudes (non-finite values counted as 0, so no NaN is left to skip: max, not nanmax)
    big = np.abs(np.where(fin0, hi0.reshape(m, K * R), 0.0))
    if lo0 is not hi0:
        big = np.maximum(big, np.abs(np.where(fin0, lo0.reshape(m, K * R), 0.0)))
    e = tol.force * np.max(big, axis=1)[:, None, None]  # (m,1,1)
    e = np.maximum(e, 1e-300)
    bscale = np.max(np.abs(np.where(fin1, N1.reshape(m, K * R), 0.0)), axis=1)[:, None, None]
    with np.errstate(divide="ignore", invalid="ignore"):
        # --- det keeps its sign: per-row union of half-lines (np.putmask: np.where's values, without its branch per
        # element, which masks as unpredictable as the rows' signs make ~5x slower)
        sg = np.where(neg, -1.0, 1.0)[:, None, None]
        a = sg * np.where(neg[:, None, None], lo0, hi0)  # sgn(det) N0, each row's largest over the wrench blocks
        b = sg * N1
        flat = np.abs(b) <= tol.force * bscale
        start = (-e - a) / b  # [start, inf) where b > 0
        end = start.copy()  # (-inf, end] where b < 0
        np.putmask(start, flat | ~(b > 0), np.inf)
        np.putmask(end, flat | ~(b < 0), -np.inf)
        lo_r = start.min(axis=1)  # (m, R)
        up_r = end.max(axis=1)
        whole = np.any(flat & (a >= -e), axis=1) | (up_r >= lo_r)
        cand = np.concatenate([g_lo, lo_r], axis=1)  # (m, R+1)
        # a row's half-lines (-inf, up_r] and [lo_r, inf) exist only where finite: with g_lo = -inf
        # the candidate -inf lies in the first only when some control point has a falling row
        below = (cand[:, :, None] <= up_r[:, None, :]) & (up_r[:, None, :] > -np.inf)
        above = (cand[:, :, None] >= lo_r[:, None, :]) & (lo_r[:, None, :] < np.inf)
        inside = whole[:, None, :] | below | above
        valid = np.all(inside, axis=2) & (cand >= g_lo) & (cand <= g_hi)
        steady_lb = np.min(np.where(valid, cand, np.inf), axis=1)
        # --- det changes sign: rows r, q with N_r > 0 and N_q < 0 on the whole cell exclude the effort;
        # only where it does (the other cells take steady_lb): the same values, much less work
        sub = np.flatnonzero(finite & ~steady)
        straddle_lb = np.full(m, np.inf)
        if sub.size:
            # N_r > e (Pos) asks it of the row's smallest N0, N_q < -e (Neg) of its largest
            a_pos, a_neg, b, e, bscale, gl, gh = lo0[sub], hi0[sub], N1[sub], e[sub], bscale[sub], g_lo[sub], g_hi[sub]
            flat = np.abs(b) <= tol.force * bscale
            up_pos = ~flat & (b > 0)
            dn_pos = ~flat & (b < 0)
            p_lo = (e - a_pos) / b  # a + tau b > e: tau above it where b > 0, below where b < 0
            p_up = p_lo.copy()
            np.putmask(p_lo, ~up_pos, -np.inf)
            np.putmask(p_up, ~dn_pos, np.inf)
            p_lo, p_up = p_lo.max(axis=1), p_up.min(axis=1)  # (m, R)
            p_up = np.where(np.any(flat & (a_pos <= e), axis=1), -np.inf, p_up)
            n_lo = (-e - a_neg) / b  # a + tau b < -e: tau below it where b > 0, above where b < 0
            n_up = n_lo.copy()
            np.putmask(n_lo, ~dn_pos, -np.inf)
            np.putmask(n_up, ~up_pos, np.inf)
            n_lo, n_up = n_lo.max(axis=1), n_up.min(axis=1)
            n_up = np.where(np.any(flat & (a_neg >= -e), axis=1), -np.inf, n_up)
            E_lo = np.maximum(p_lo[:, :, None], n_lo[:, None, :])  # (m, R, R): Pos_r & Neg_q
            E_up = np.minimum(p_up[:, :, None], n_up[:, None, :])
            offdiag = ~np.eye(R, dtype=bool)[None]
            live = offdiag & (E_lo < E_up)
            # a pair live at no cell excludes nothing and offers only the candidate inf: dropped
            pairs = np.flatnonzero(live.reshape(sub.size, -1).any(axis=0))
            E_lo = np.where(live, E_lo, np.nan).reshape(sub.size, -1)[:, pairs]
            E_up = np.where(live, E_up, np.nan).reshape(sub.size, -1)[:, pairs]
            cand = np.concatenate([gl, np.nan_to_num(E_up, nan=np.inf)], axis=1)
            # an exclusion interval unbounded below excludes the candidate -inf too
            strictly = ((cand[:, :, None] > E_lo[:, None, :]) | (E_lo[:, None, :] == -np.inf)) & (cand[:, :, None] < E_up[:, None, :])
            valid = ~np.any(strictly, axis=2) & (cand >= gl) & (cand <= gh)
            straddle_lb[sub] = np.min(np.where(valid, cand, np.inf), axis=1)
    out = np.where(steady, steady_lb, np.where(finite, straddle_lb, g_lo[:, 0]))
    return out, steady


def _search(cells: FrictionCells, lo_, hi_, flip, atol, budget, tol):
    """Smallest effort of ``[lo_, hi_]`` possibly feasible; with ``flip`` the efforts are negated
    (pass ``-hi, -lo`` to find the largest).

    Returns ``(value, exact, cells used, met a singular cell, met a singular point)`` with ``value`` (in the
    unflipped sign) ``+inf`` (``-inf`` with ``flip``) when no effort of the interval is possible: nothing
    feasible; ``-inf`` (``+inf`` with ``flip``) when the possible efforts reach the interval's
    unbounded end, proved (a friction point whose band is unbounded there: ``exact``) or not
    excluded (``exact`` False).  A cell whose bound is ``-inf`` is a safe answer and is kept, never dropped.

    A cell left open with a control value that is not a number (``Q_AI`` singular at a vertex:
    :func:`qsplan.mechanics.bands.effort.band_rows`; or in the fit of a shared coefficient's polynomials)
    can never be resolved: its bound is the interval's start, and every cell bisected from it keeps that
    vertex (the shared path: those coefficients).  The search then ends at once with the answer it would
    give when its budget ran out, the interval's start, conservative (``exact`` False).
    """
    sign = -1.0 if flip else 1.0
    clo, chi = cells.root
    incumbent, floor, used, exact, straddling, proofs = np.inf, np.inf, 0, True, False, 0
    singular = False
    while clo.shape[0]:
        det, N0, N1, pl, pu, pok, spread = cells.evaluate(clo, chi)
        used += clo.shape[0]
        if flip:
            pl, pu = -pu, -pl
        # a friction point whose band is not empty and reaches the interval (to atol) is a feasible
        # effort: an incumbent; a band unbounded below on an interval unbounded below proves -inf.
        # pok alone admits bands empty by rounding-sized overlaps of nearly singular rows: not a proof.
        feas = pok & (pl <= pu) & (np.maximum(pl, lo_) <= np.minimum(pu, hi_) + atol)
        if feas.any():
            incumbent = min(incumbent, float(np.min(np.where(feas, np.clip(pl, lo_, hi_), np.inf))))
        lb, steady = cell_lower_bounds(det, N0, sign * N1, lo_, hi_, tol, cells.wrench_blocks)
        target = min(incumbent, hi_) - atol  # no proof needed above it: where a certificate's work ends
        if used > CERTIFY_AFTER and proofs < MAX_CERTIFICATES and np.any(steady & (lb < target)):
            lb, n = certified_lower_bounds(det, N0, sign * N1, lb, target, steady, tol, MAX_CERTIFICATES - proofs)
            lb[lb > hi_], proofs = np.inf, proofs + n
        possible = lb < np.inf  # lb is +inf for a cell where nothing is possible, and may be -inf
        straddling |= bool(np.any(~steady & possible))
        # a cell that cannot beat the incumbent, or the interval's far end, by more than atol is resolved
        done = possible & (lb >= min(incumbent, hi_) - atol)
        floor = min(floor, float(np.min(lb[done], initial=np.inf)))
        keep = possible & ~done
        undecided = ~(np.all(np.isfinite(det), axis=1) & np.all(np.isfinite(N0), axis=(1, 2))
                      & np.all(np.isfinite(N1), axis=(1, 2)))  # fmt: skip
        if np.any(keep & undecided):  # never resolved (the docstring): the answer the budget would give, now
            floor = min(floor, float(np.min(lb[keep])))
            exact, singular = False, True
            break
        clo, chi, spread = clo[keep], chi[keep], spread[keep]
        if not clo.shape[0]:
            break
        if used + 2 * clo.shape[0] > budget:
            floor = min(floor, float(np.min(lb[keep])))
            exact = False
            break
        clo, chi = cells.split(clo, chi, spread)
    value = min(incumbent, floor)
    return sign * value, exact, used, straddling, singular


def friction_set(lo, hi, n_c: int, shared: bool):
    """The friction set checked by :func:`qsplan.mechanics.model.friction.check_mu_range`: floats, or shape (n_c,) (a box)."""
    if shared:
        return check_mu_range(lo, hi)
    return tuple(np.array(v) for v in check_mu_range(lo, hi, n=n_c))


def competitor_torques(scene, mode, lo, hi, g_lo, g_hi, shared=False, tol: Tolerances = DEFAULT_TOLERANCES,
                       rtol: float = PRECLUSION_RTOL, max_cells: int = MAX_CELLS, *, disturbance=None) -> CompetitorTorques:  # fmt: skip
    """Efforts in ``[g_lo, g_hi]`` for which ``mode`` is feasible for some friction in the set (and some wrench of
    the disturbance box).

    Parameters
    ----------
    scene : Scene
        Exactly one effort-controlled joint.
    mode : ContactMode or str
        The competing mode.
    lo, hi : float or array-like, shape (n_c,)
        The friction set: independent coefficients ``lo_i <= mu_i <= hi_i`` (a box), or with
        ``shared=True`` one coefficient ``lo <= mu <= hi`` for every contact (floats).
    g_lo, g_hi : float
        The effort interval of interest (N m or N); ``-inf`` / ``inf`` allowed.
    shared : bool
    tol : Tolerances
    rtol : float
        :data:`PRECLUSION_RTOL`.
    max_cells : int
        :data:`MAX_CELLS`.
    disturbance : WrenchBox or (array-like, array-like), optional
        A box of external wrenches on the workpiece (N, N, N m, added to ``g_obj``): the wrench is three
        more sides of every cell (:mod:`qsplan.mechanics.bands.disturbance`, :mod:`qsplan.mechanics.bands.cells`).

    Returns
    -------
    CompetitorTorques
    """
    mode = mode_from_letters(mode)
    n_c = scene.n_contacts
    box = check_wrench_box(disturbance)
    lo_a, hi_a = friction_set(lo, hi, n_c, shared)
    if not g_lo <= g_hi:
        raise SceneError(f"effort interval: expected g_lo <= g_hi; got {g_lo}, {g_hi}")
    mk = band_kinematics(scene, mode, tol)
    if not mk.ok:
        return CompetitorTorques(mode.letters, np.nan, np.nan, True, True, f"kinematics: {mk.status}")
    if shared and hi_a == lo_a:
        shared, lo_a, hi_a = False, np.full(n_c, lo_a), np.full(n_c, hi_a)
    cells = FrictionCells(scene, mk, lo_a, hi_a, shared, tol, box)
    finite = [abs(x) for x in (g_lo, g_hi) if np.isfinite(x)]
    atol = rtol * max(finite + [1.0])
    low, ex1, n1, st1, sg1 = _search(cells, g_lo, g_hi, False, atol, max_cells, tol)
    if low == np.inf:  # proved: no cell admits an effort of the interval
        return CompetitorTorques(mode.letters, np.nan, np.nan, True, True, None, n1)
    # the largest possibly-feasible effort, searched above the smallest one only
    up, ex2, n2, st2, sg2 = _search(cells, -g_hi, -low, True, atol, max_cells, tol)
    if up == -np.inf:  # nothing above low within atol: the set is (numerically) the point low
        up = low
    exact = ex1 and ex2
    reason = None
    if sg1 or sg2:
        reason = ("the mode is singular (Q_AI's Hadamard ratio below Tolerances.singular) at a point of the friction "
                  "set: its feasibility there is not decided")  # fmt: skip
    elif not exact:
        reason = "cell budget exhausted" + ("; the mode is singular (det Q_AI changes sign) inside the friction set" if st1 or st2 else "")
    return CompetitorTorques(mode.letters, float(low), float(max(up, low)), False, exact, reason, n1 + n2)
