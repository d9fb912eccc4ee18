"""Certificates that a competing mode is infeasible on a whole friction cell and effort interval (eqs. 17-28).

Proof.  By eq. (17) a sliding contact's tangential force is ``-mu xi c_n``, so each column of
``W_Amu`` and ``J_Amu`` (eqs. 18-20), hence of ``Q_AI`` (eq. 26), is affine in at most one sliding
contact's mu and ``det Q_AI`` is multilinear in them; a rolling contact's mu enters only its own rows
of ``B_A`` (eq. 21), linearly.  By Cramer's rule on eq. (26), ``det Q_AI * c_A`` is multilinear too and
affine in the effort, and so is every Coulomb row of eq. (28) times the determinant,
``N_r = det Q_AI * s_r`` (over one shared coefficient: a polynomial in it).  On a friction cell where
``det Q_AI`` keeps one sign ``sigma`` (all its control values have it; below), row ``r`` holds
exactly where ``sigma N_r >= 0``.  At any friction of the cell and any effort of ``[a, b]``,
``N_r`` is a convex combination, with weights that are the same for every row, of its *control
values*: the values at the cell's vertices (a multilinear function is the product-weighted mean of
its vertex values) or its Bernstein coefficients on the cell (a polynomial), each at the effort ends
``a`` and ``b`` (affine in the effort).  Hence for row weights ``y >= 0``, ``sum(y) = 1``:

    sum_r y_r sigma N_r < -e  at every control value and effort end
    =>  at every friction of the cell and effort of [a, b] some row has sigma N_r < -e,

so the competitor is infeasible there beyond the tolerance ``e`` of
:func:`qsplan.mechanics.bands.preclusion.cell_lower_bounds`.  (The same convex-combination argument
gives the sign of ``det Q_AI`` on the cell from its control values.)  The per-row bound of that
function is the case of ``y`` a unit vector; a combination proves much more on large cells, where the
competitor's rows fail at *different* vertices.  One small linear programme finds ``y``; the proof is
then checked in closed form (``max_k (a_k + tau b_k) < -e`` holds on an interval of efforts), so the
programme's own tolerances never enter the answer.

Why not the vertex bands alone: for a *competitor* the question is whether some friction makes every
row hold at once, and that friction need not be a vertex even where ``det Q_AI`` keeps its sign.  In
``tests/mechanics/test_band_certificates.py`` a competitor whose determinant is negative on the whole
box is feasible (checked by the all-modes solver) at an effort 0.0017 N m beyond the hull of its vertex
bands, at a friction inside the box; taking the vertex hull would have been optimistic.  (For the
*desired* mode the quantifier is "every friction", which does reduce to the vertices:
:func:`qsplan.mechanics.bands.guaranteed.guaranteed_band_box`.)

Only lower bounds of the cells' possible efforts are raised, each by a proof, and a cell whose
programme proves nothing keeps its bound: the search stays exact to its tolerance, or conservative
and labelled so (never a hull narrower than the competitor's true one).
"""

from __future__ import annotations

import numpy as np

from qsplan.mechanics.numerics import Tolerances
from qsplan.mechanics.quiet import quiet_highs

__all__ = ["CERTIFICATE_ROUNDS", "MAX_CERTIFICATES", "T_FLOOR", "certified_lower_bounds"]

#: Programmes per cell and search step: each raises the cell's bound to where its combination of rows
#: stops proving infeasibility, and the next starts from there; a programme that proves nothing ends the
#: cell's turn (it is split instead: smaller cells admit more proofs).  On the hard bands of
#: tests/mechanics/test_band_certificates.py 1, 2 and 3 rounds gave the same answers.
CERTIFICATE_ROUNDS = 3

#: Programmes per search (one end of one competitor's hull), ~0.3-1 ms each with highspy.  A competitor
#: that comes within 2.5e-4 (relative) of the effort interval without entering it took 108 programmes
#: (scene 90 of seed 21 in tests/mechanics/test_band_certificates.py); one whose extreme lies strictly
#: inside the friction box is not certified by any number of them (the per-row search ends it or runs out
#: of cells, as before), so the budget bounds what they add: ~0.1 s a search.  256 changed 2 of 955
#: bands of the band-safety scenes (seeds 12, 13, 21) by more than rounding, for 25 % more time on the hard ones.
MAX_CERTIFICATES = 128

#: Lower bound of the programme's objective ``t``: any negative value will do as a certificate (it is
#: checked in closed form afterwards); a bound keeps the programme bounded (the rows are scaled to 1).
T_FLOOR = -2.0


class _Programme:
    """The programme of :func:`_weights` on one HiGHS object (``highspy``), else ``scipy.optimize.linprog``."""

    def __init__(self):
        try:
            import highspy
        except ImportError:
            self.hs = None
        else:
            self.hs = highspy
        self.highs = None

    def solve(self, A, R):
        """``(y, t)`` minimising ``t`` with ``A (y, t) <= 0``, ``y >= 0``, ``sum(y) = 1``, ``t >= T_FLOOR``; None if not optimal."""
        n = R + 1
        equal = np.append(np.ones(R), 0.0)[None]
        if self.hs is None:
            from scipy.optimize import linprog

            cost = np.append(np.zeros(R), 1.0)
            res = linprog(cost, A_ub=A, b_ub=np.zeros(A.shape[0]), A_eq=equal, b_eq=[1.0],
                          bounds=[(0, None)] * R + [(T_FLOOR, None)], method="highs")  # fmt: skip
            return res.x if res.status == 0 else None
        hs = self.hs
        if self.highs is None:
            self.highs = quiet_highs(hs)  # highspy prints a banner on descriptor 1 when built (qsplan.mechanics.quiet)
            self.highs.setOptionValue("presolve", "off")  # tiny dense programmes: presolve costs ~40 % and saves nothing
        h, inf = self.highs, hs.kHighsInf
        h.clearModel()
        h.addVars(n, np.append(np.zeros(R), T_FLOOR), np.full(n, inf))
        h.changeColCost(R, 1.0)
        M = np.vstack([A, equal])
        nz = M != 0  # compressed rows by hand, as in qsplan.mechanics.solver.breaking_sets
        starts = np.concatenate([[0], np.cumsum(nz.sum(axis=1))[:-1]]).astype(np.int32)
        h.addRows(M.shape[0], np.append(np.full(A.shape[0], -inf), 1.0), np.append(np.zeros(A.shape[0]), 1.0),
                  int(nz.sum()), starts, np.nonzero(nz)[1].astype(np.int32), M[nz])  # fmt: skip
        h.run()
        if h.getModelStatus() != hs.HighsModelStatus.kOptimal:
            return None
        return np.array(h.getSolution().col_value)


def _weights(programme, C0, C1, a, b):
    """Row weights ``y`` (R,) minimising the largest ``y . (C0_k + tau C1_k)`` over control points ``k``
    and effort ends ``tau`` in ``{a, b}`` (towards an infinite end the combination must not grow),
    or None when the programme finds none below 0."""
    K, R = C0.shape
    rows = []
    for end, direction in ((a, -1.0), (b, 1.0)):
        if np.isfinite(end):
            rows.append(np.hstack([C0 + end * C1, -np.ones((K, 1))]))
        else:
            rows.append(np.hstack([direction * C1, np.zeros((K, 1))]))
    if not (np.isfinite(a) or np.isfinite(b)):
        rows.append(np.hstack([C0, -np.ones((K, 1))]))  # anchored at tau = 0
    x = programme.solve(np.vstack(rows), R)
    if x is None or not x[-1] < 0:
        return None
    y = np.maximum(x[:R], 0.0)
    return y / y.sum() if y.sum() > 0 else None


def _certified_from(C0, C1, y, start, e) -> float:
    """The end of the efforts ``[start, end)`` on which ``y`` proves the cell infeasible: ``start`` itself
    when it proves nothing there, ``inf`` when it proves every effort from ``start`` on."""
    a, b = C0 @ y, C1 @ y  # (K,): the combination at each control point, affine in the effort
    if np.isfinite(start):
        if not np.all(a + start * b < -e):
            return start
    elif not np.all((b > 0) | ((b == 0) & (a < -e))):  # towards -inf every control value falls below -e
        return start
    with np.errstate(divide="ignore"):
        return float(np.min(np.where(b > 0, (-e - a) / b, np.inf)))


def _first_open(C0, C1, start, e) -> float:
    """The smallest effort from ``start`` on at which some control point meets every row (``a + tau b >= -e``):
    no combination of rows can be below ``-e`` there, so no certificate reaches past it (``inf``: none)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        edge = (-e - C0) / C1
    rise, fall = C1 > 0, C1 < 0
    lo = np.max(np.where(rise, edge, -np.inf), axis=1)
    hi = np.min(np.where(fall, edge, np.inf), axis=1)
    flat_ok = np.all(rise | fall | (C0 >= -e), axis=1)
    lo = np.maximum(lo, start)
    return float(np.min(np.where(flat_ok & (lo <= hi), lo, np.inf)))


def certified_lower_bounds(det, N0, N1, lb, target, steady, tol: Tolerances, budget: int = MAX_CERTIFICATES):
    """Each cell's lower bound of possible efforts, raised by certificates (see the module docstring).

    Parameters
    ----------
    det : ndarray, shape (m, K)
    N0, N1 : ndarray, shape (m, K, R)
        Control values of ``det Q_AI`` and of the rows ``N_r = N0_r + tau N1_r`` on each cell (in the
        search's effort sign), as :func:`qsplan.mechanics.bands.preclusion.cell_lower_bounds` takes them.
    lb : ndarray, shape (m,)
        That function's bounds; only cells with ``steady`` and ``lb < target`` are worked on, lowest first.
    target : float
        Efforts at or above it need no proof (the search's incumbent or the interval's end, less its tolerance).
    steady : ndarray of bool, shape (m,)
        ``det Q_AI`` keeps its sign on the cell (all its control values share it: a multilinear function
        and a polynomial in Bernstein form lie between their control values).
    budget : int
        Most programmes to solve.

    Returns
    -------
    lb : ndarray, shape (m,)
        ``>=`` the given bounds; ``inf`` where no effort from the given bound on is possible.
    used : int
        Programmes solved.
    """
    out = np.array(lb, dtype=float, copy=True)
    todo = np.flatnonzero(steady & (out < target))
    programme, used = _Programme(), 0
    for i in todo[np.argsort(out[todo], kind="stable")]:
        sg = 1.0 if det[i, 0] > 0 else -1.0
        C0, C1 = sg * N0[i], sg * N1[i]
        if not (np.all(np.isfinite(C0)) and np.all(np.isfinite(C1))):
            continue
        scale = max(float(np.max(np.abs(C0))), 1e-300)
        e = max(tol.force * scale, 1e-300) / scale  # cell_lower_bounds' tolerance on this cell, scaled
        C0, C1 = C0 / scale, C1 / scale
        for _ in range(CERTIFICATE_ROUNDS):
            if used >= budget:
                return out, used
            start = out[i]
            end = min(target, _first_open(C0, C1, start, e))  # the widest window a proof may cover
            if not end > start:
                break
            if not np.isfinite(end):  # nothing allowed above: a window of the effort's scale (a proof may reach further)
                end = start + max(1.0, abs(start)) if np.isfinite(start) else 0.0
            y = _weights(programme, C0, C1, start, end)
            used += 1
            out[i] = start if y is None else max(start, _certified_from(C0, C1, y, start, e))
            if not out[i] > start or out[i] >= target:  # nothing proved (the cell is split instead), or done
                break
    return out, used
