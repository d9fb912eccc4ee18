"""One small dense linear programme on HiGHS (``highspy``), without ``scipy.optimize``.

``scipy.optimize.linprog(method="highs")`` runs the same solver, but importing ``scipy.optimize`` costs
~0.5 s (most of a ``qsplan verify``), for programmes of a few variables that HiGHS solves in ~0.1 ms.
:func:`solve_lp` takes ``linprog``'s arguments (dense), sets HiGHS as ``linprog`` does (presolve on, dual
simplex, its default feasibility tolerances) and answers with ``linprog``'s status codes; where HiGHS
cannot tell an unbounded programme from an infeasible one after presolve, it solves again without presolve
(``linprog`` gives up there: its status 4).  The solver is built with file descriptor 1 silenced
(:func:`qsplan.mechanics.quiet.quiet_highs`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qsplan.mechanics.errors import QsplanError
from qsplan.mechanics.quiet import quiet_highs

__all__ = ["LPResult", "solve_lp"]


@dataclass(frozen=True, slots=True, eq=False)
class LPResult:
    """The answer of :func:`solve_lp`, as ``scipy.optimize.linprog`` names it.

    Attributes
    ----------
    status : int
        0 optimal, 2 infeasible, 3 unbounded, 4 no answer (a numerical failure or an iteration limit).
    x : ndarray, shape (n,), or None
        The optimal point (status 0); None otherwise.
    fun : float
        The optimal objective; NaN without one.
    message : str
        HiGHS's model status, for a person.
    """

    status: int
    x: np.ndarray | None
    fun: float
    message: str


def _highspy():
    try:
        import highspy
    except ImportError as exc:  # a dependency of qsplan (pyproject.toml): a broken installation
        raise QsplanError(f"solve_lp: highspy (HiGHS) is not installed ({exc}); reinstall qsplan") from None
    return highspy


def _rows(*blocks):
    """Dense blocks stacked, as HiGHS's compressed rows ``(starts, index, values)`` (scipy.sparse costs ~0.15 s of
    import)."""
    A = np.vstack([b for b in blocks if b is not None and b.size])
    nz = A != 0
    starts = np.concatenate([[0], np.cumsum(nz.sum(axis=1))[:-1]]).astype(np.int32)
    return A.shape[0], starts, np.nonzero(nz)[1].astype(np.int32), A[nz]


def solve_lp(c, A_ub=None, b_ub=None, A_eq=None, b_eq=None, bounds=None, *, presolve: bool = True) -> LPResult:
    """Minimise ``c . x`` subject to ``A_ub x <= b_ub``, ``A_eq x = b_eq`` and ``lo <= x <= hi``.

    Parameters
    ----------
    c : array-like, shape (n,)
    A_ub, A_eq : array-like, shape (r, n), optional
    b_ub, b_eq : array-like, shape (r,), optional
    bounds : sequence of (lo, hi), length n, optional
        None for an infinite side; default every variable free (``linprog``'s default is ``x >= 0``: every caller
        here states its bounds).
    presolve : bool
        HiGHS's presolve (on, as ``linprog``).

    Returns
    -------
    LPResult
    """
    highspy = _highspy()
    c = np.asarray(c, dtype=float).reshape(-1)
    n = c.size
    inf = highspy.kHighsInf
    lo, hi = np.full(n, -inf), np.full(n, inf)
    for j, (a, b) in enumerate(bounds if bounds is not None else ()):
        lo[j] = -inf if a is None or a == -np.inf else float(a)
        hi[j] = inf if b is None or b == np.inf else float(b)
    ub = None if A_ub is None else np.asarray(A_ub, dtype=float).reshape(-1, n)
    eq = None if A_eq is None else np.asarray(A_eq, dtype=float).reshape(-1, n)
    row_lo, row_hi = [], []
    if ub is not None:
        row_lo.append(np.full(len(ub), -inf))
        row_hi.append(np.asarray(b_ub, dtype=float).reshape(-1))
    if eq is not None:
        row_lo.append(np.asarray(b_eq, dtype=float).reshape(-1))
        row_hi.append(row_lo[-1])
    h = quiet_highs(highspy)
    h.setOptionValue("simplex_strategy", 1)  # dual simplex, as linprog(method="highs")
    h.setOptionValue("presolve", "on" if presolve else "off")
    h.addVars(n, lo, hi)
    h.changeColsCost(n, np.arange(n, dtype=np.int32), c)
    if row_lo:
        r, starts, index, values = _rows(ub, eq)
        h.addRows(r, np.concatenate(row_lo), np.concatenate(row_hi), int(values.size), starts, index, values)
    h.run()
    status = h.getModelStatus()
    ms = highspy.HighsModelStatus
    if status == ms.kUnboundedOrInfeasible and presolve:  # presolve cannot tell: the solver can
        return solve_lp(c, A_ub, b_ub, A_eq, b_eq, bounds, presolve=False)
    message = h.modelStatusToString(status)
    if status == ms.kOptimal:
        x = np.array(h.getSolution().col_value, dtype=float)
        return LPResult(0, x, float(c @ x), message)
    code = {ms.kInfeasible: 2, ms.kUnbounded: 3}.get(status, 4)
    return LPResult(code, None, np.nan, message)
