"""Lemke's complementary pivoting for the linear complementarity problem LCP(M, q).

Find ``z`` with ``w = M z + q >= 0``, ``z >= 0`` and ``w^T z = 0``.  Lemke's
method adds an artificial variable ``z0`` with a positive covering vector ``d``
(``w = M z + q + d z0``), starts from the almost-complementary basis in which
``z0`` just makes ``q + d z0 >= 0``, and pivots complementary pairs in and out
until ``z0`` leaves the basis (a solution) or the entering column has no
positive entry (ray termination: for copositive-plus ``M`` this proves the LCP
infeasible; for other ``M`` it only says the method failed).

Degenerate problems (ties in the minimum-ratio test) can make Lemke's method
cycle; the lexicographic minimum-ratio rule breaks every tie with the rows of
the basis inverse, which keeps the perturbed right-hand side
``q + (eps, eps^2, ...)`` nondegenerate, so no basis repeats and the method
terminates in finitely many pivots (Cottle, Pang & Stone, *The Linear
Complementarity Problem*, Sec. 4.4; Murty, *Linear Complementarity*, Ch. 2).
The PyPI package ``lemkelcp`` has no anti-cycling rule.

This module is the method only; :mod:`qsplan.mechanics.crosscheck.lcp` writes the quasistatic
problem as an LCP (after Pang, Trinkle & Lo, the paper's ref. [26]).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["LemkeResult", "lemke", "LemkeStatus", "DEFAULT_MAX_PIVOTS", "DEFAULT_PIVOT_TOL"]

#: Default pivot cap (None: ``50 n + 100``): Lemke's method needs a few times ``n`` pivots on the problems
#: met here; 50 n + 100 leaves ample room while bounding the exponential worst case.
DEFAULT_MAX_PIVOTS = None

#: Entries of the entering column below this (relative to the column's largest
#: entry) count as zero in the ratio test: rounding in a tableau of well-scaled
#: data is ~1e-14 relative, and a pivot on a smaller entry would amplify it.
DEFAULT_PIVOT_TOL = 1e-11


class LemkeStatus:
    """How Lemke's method ended."""

    SOLVED = "solved"
    RAY = "ray termination"  #: entering column has no positive entry
    ITERATION_LIMIT = "iteration limit"  #: ``max_pivots`` reached
    CYCLE = "cycle"  #: a basis repeated (only possible with ``rule="first"``)


@dataclass(frozen=True, slots=True, eq=False)
class LemkeResult:
    """Outcome of :func:`lemke`.

    Attributes
    ----------
    z : ndarray, shape (n,) or None
        The solution when ``status == "solved"``.
    w : ndarray, shape (n,) or None
        ``M z + q``.
    status : str
        A :class:`LemkeStatus` value.
    pivots : int
        Number of pivots performed.
    basis : tuple of int
        Final basic variables: ``0..n-1`` are ``w``, ``n..2n-1`` are ``z``, ``2n`` is ``z0``.
    """

    z: np.ndarray | None
    w: np.ndarray | None
    status: str
    pivots: int
    basis: tuple

    @property
    def solved(self) -> bool:
        return self.status == LemkeStatus.SOLVED


def _lexmin(T: np.ndarray, rows: np.ndarray, col: np.ndarray, keys: np.ndarray, rtol: float) -> int:
    """Row of ``rows`` minimising ``T[row, keys] / col[row]`` lexicographically.

    Ratios within ``rtol`` (relative to the key column's scale) count as tied and
    go on to the next key; the keys after the first are columns of the basis
    inverse, whose rows are independent, so the tie always breaks.
    """
    for k in keys:
        r = T[rows, k] / col[rows]
        scale = max(1.0, float(np.max(np.abs(T[:, k]))))
        rows = rows[r <= r.min() + rtol * scale]
        if rows.size == 1:
            break
    return int(rows[0])


def lemke(M, q, d=None, max_pivots: int | None = DEFAULT_MAX_PIVOTS, pivot_tol: float = DEFAULT_PIVOT_TOL,
          rule: str = "lexicographic") -> LemkeResult:  # fmt: skip
    """Solve LCP(M, q) by Lemke's method with the lexicographic minimum-ratio rule.

    Parameters
    ----------
    M : array-like, shape (n, n)
    q : array-like, shape (n,)
    d : array-like, shape (n,), optional
        Covering vector, entries > 0 (default all ones).
    max_pivots : int, optional
        Pivot cap (default ``50 n + 100``); reaching it gives status ``"iteration limit"``.
    pivot_tol : float
        Entries of the entering column up to ``pivot_tol`` times its largest
        entry are not pivoted on (see :data:`DEFAULT_PIVOT_TOL`).
    rule : {"lexicographic", "first"}
        Tie-breaking in the ratio test.  ``"first"`` takes the lowest row among
        tied ratios, the naive rule that can cycle on degenerate problems; it is
        here to show that, and detects a repeated basis (status ``"cycle"``).

    Returns
    -------
    LemkeResult

    Raises
    ------
    ValueError
        On mismatched shapes, non-finite data or a covering vector with an entry <= 0.
    """
    M = np.array(M, dtype=float)
    q = np.array(q, dtype=float).reshape(-1)
    n = q.size
    if M.shape != (n, n):
        raise ValueError(f"M: expected shape ({n}, {n}) to match q; got {M.shape}")
    d = np.ones(n) if d is None else np.array(d, dtype=float).reshape(-1)
    if d.shape != (n,) or np.any(d <= 0):
        raise ValueError(f"d: expected {n} positive entries; got {d.tolist()}")
    if not (np.all(np.isfinite(M)) and np.all(np.isfinite(q))):
        raise ValueError("M, q: expected finite numbers")
    if rule not in ("lexicographic", "first"):
        raise ValueError(f"rule: expected 'lexicographic' or 'first'; got {rule!r}")
    cap = 50 * n + 100 if max_pivots is None else int(max_pivots)
    if n == 0 or np.all(q >= 0):
        return LemkeResult(np.zeros(n), q.copy(), LemkeStatus.SOLVED, 0, tuple(range(n)))

    # Tableau B^{-1} [I, -M, -d | q]: columns 0..n-1 (w) hold B^{-1}, 2n is z0, 2n+1 the basic values.
    T = np.hstack([np.eye(n), -M, -d[:, None], q[:, None]])
    Z0, RHS = 2 * n, 2 * n + 1
    basis = np.arange(n)
    keys = np.concatenate([[RHS], np.arange(n)])  # lexicographic keys: values, then rows of B^{-1}
    rtol = 1e-13 if rule == "lexicographic" else 0.0
    seen = set()

    def pivot(r, c):
        T[r] /= T[r, c]
        others = np.arange(n) != r
        T[others] -= np.outer(T[others, c], T[r])
        T[r, c] = 1.0
        T[others, c] = 0.0

    # Initial pivot: z0 enters, the row with the most negative q_i / d_i leaves.
    rows = np.arange(n)
    if rule == "lexicographic":
        r = _lexmin(T, rows, d, keys, rtol)
    else:
        r = int(np.argmin(q / d))
    leaving = basis[r]
    basis[r] = Z0
    pivot(r, Z0)
    pivots = 1
    while pivots < cap:
        entering = leaving + n if leaving < n else leaving - n  # complement of the leaving variable
        col = T[:, entering]
        big = float(np.max(np.abs(col)))
        cand = np.flatnonzero(col > pivot_tol * max(big, 1.0))
        if cand.size == 0:
            return LemkeResult(None, None, LemkeStatus.RAY, pivots, tuple(int(b) for b in basis))
        ratios = T[cand, RHS] / col[cand]
        rmin = ratios.min()
        z0_row = np.flatnonzero(basis[cand] == Z0)
        if z0_row.size and ratios[z0_row[0]] <= rmin + 1e-13 * max(1.0, abs(rmin)):
            r = int(cand[z0_row[0]])  # z0 can leave: take it, the method ends with a solution
        elif rule == "lexicographic":
            r = _lexmin(T, cand, col, keys, rtol)
        else:
            r = int(cand[np.flatnonzero(ratios <= rmin)[0]])
        leaving = int(basis[r])
        basis[r] = entering
        pivot(r, entering)
        pivots += 1
        if leaving == Z0:
            x = np.zeros(2 * n + 1)
            x[basis] = np.maximum(T[:, RHS], 0.0)  # basic values are >= 0 up to rounding
            z = x[n : 2 * n]
            return LemkeResult(z, M @ z + q, LemkeStatus.SOLVED, pivots, tuple(int(b) for b in basis))
        if rule == "first":
            key = (tuple(sorted(int(b) for b in basis)), leaving)
            if key in seen:
                return LemkeResult(None, None, LemkeStatus.CYCLE, pivots, tuple(int(b) for b in basis))
            seen.add(key)
    return LemkeResult(None, None, LemkeStatus.ITERATION_LIMIT, pivots, tuple(int(b) for b in basis))
