"""Zero sets of bilinear polynomials ``a + b x + c y + d x y`` in a window (Section 4, Figs. 3, 6, 8).

On a 2-D slice of mu-space every region boundary of a mode (``det Q_AI = 0`` or a
Coulomb slack numerator ``= 0``, :mod:`qsplan.mechanics.muspace.regions`) is the zero
set of a polynomial bilinear in the slice's two friction coefficients; this module
computes it exactly, branch by branch.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["ZeroBranch", "bilinear_zero_set"]


@dataclass(frozen=True, slots=True, eq=False)
class ZeroBranch:
    """One connected piece of the zero set of ``a + b x + c y + d x y`` inside a window.

    Attributes
    ----------
    coef : ndarray, shape (4,)
        ``(a, b, c, d)`` whose ``y(t)`` below parametrizes the branch (the polynomial's
        own coefficients, except for the horizontal line of a degenerate pair).
    kind : str
        ``"y_of_x"``: points ``(t, y(t))`` with ``y(t) = -(a + b t) / (c + d t)``;
        ``"x_const"``: the vertical line ``x = x0`` at points ``(x0, t)``.
    t : ndarray, shape (m,)
        Increasing parameter samples; every sample lies on the curve and in the window.
    x0 : float
        The abscissa of a vertical line (``kind == "x_const"``).
    """

    coef: np.ndarray
    kind: str
    t: np.ndarray
    x0: float = float("nan")

    def points(self, t=None) -> np.ndarray:
        """Curve points at parameters ``t`` (default the samples), shape (m, 2)."""
        t = self.t if t is None else np.asarray(t, dtype=float)
        if self.kind == "x_const":
            return np.column_stack([np.full(t.shape, self.x0), t])
        a, b, c, d = self.coef
        return np.column_stack([t, -(a + b * t) / (c + d * t)])


def bilinear_zero_set(coef, xlim, ylim, n: int = 400) -> list[ZeroBranch]:
    """The zero set of ``p(x, y) = a + b x + c y + d x y`` inside a window, exactly.

    The zero set is a hyperbola with asymptotes ``x = -c/d``, ``y = -b/d`` (``d != 0``,
    ``bc != ad``), a pair of axis-parallel lines (``bc = ad``), a line (``d = 0``),
    empty, or the whole plane (all coefficients 0, reported as no branch).  Each
    branch is a graph over x (or a vertical line), monotone on hyperbola branches;
    it is sampled uniformly in x and at the abscissae of uniform y samples, so steep
    parts are resolved too, and the window crossings are exact.

    Parameters
    ----------
    coef : array-like, shape (4,)
    xlim, ylim : (float, float)
    n : int
        Samples per axis.

    Returns
    -------
    list of ZeroBranch
    """
    a, b, c, d = (float(v) for v in coef)
    (xlo, xhi), (ylo, yhi) = (float(v) for v in xlim), (float(v) for v in ylim)
    ys = np.linspace(ylo, yhi, n)
    out = []

    def graph(lo, hi):
        lo, hi = max(lo, xlo), min(hi, xhi)
        if not lo < hi:
            return
        with np.errstate(divide="ignore", invalid="ignore"):
            tx = -(a + c * ys) / (b + d * ys)  # abscissae of the y samples: resolves steep parts
        t = np.unique(np.concatenate([np.linspace(lo, hi, n), tx[np.isfinite(tx) & (tx >= lo) & (tx <= hi)]]))
        with np.errstate(divide="ignore", invalid="ignore"):
            y = -(a + b * t) / (c + d * t)
        idx = np.flatnonzero(np.isfinite(y) & (y >= ylo) & (y <= yhi))
        for r in np.split(idx, np.flatnonzero(np.diff(idx) > 1) + 1):
            if r.size >= 2:
                out.append(ZeroBranch(np.array([a, b, c, d]), "y_of_x", t[r]))

    def vertical(x0):
        if xlo <= x0 <= xhi and ylo < yhi:
            out.append(ZeroBranch(np.array([a, b, c, d]), "x_const", ys.copy(), float(x0)))

    if d != 0.0:
        x0 = -c / d
        if b * c - a * d == 0.0:  # (c + d x)(y + b/d): two lines
            vertical(x0)
            yl = -b / d
            if ylo <= yl <= yhi:
                out.append(ZeroBranch(np.array([-yl, 0.0, 1.0, 0.0]), "y_of_x", np.linspace(xlo, xhi, n)))
        else:
            graph(-np.inf, np.nextafter(x0, -np.inf))
            graph(np.nextafter(x0, np.inf), np.inf)
    elif c != 0.0:
        graph(-np.inf, np.inf)
    elif b != 0.0:
        vertical(-a / b)
    return out
