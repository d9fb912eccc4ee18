"""Roots of many polynomials at once, each exactly as :func:`numpy.polynomial.polynomial.polyroots` finds it.

The shared-coefficient bands (:mod:`qsplan.mechanics.bands.guaranteed`) find the roots of a few small polynomials
per row and per state; one ``polyroots`` call costs ~0.1 ms of Python around a microsecond of LAPACK.
:func:`roots_batch` builds the same companion matrices (``polycompanion``: trailing zero coefficients trimmed,
ones on the subdiagonal, ``-c[:-1] / c[-1]`` in the last column), stacks those of one size and calls
:func:`numpy.linalg.eigvals` once per size: the same LAPACK routine on the same matrices, so the same roots, bit
for bit (a test compares them), sorted as ``polyroots`` sorts them.  :func:`critical_polynomial` builds the
slope polynomials whose roots they seek, with numpy's arithmetic and without its per-call overhead.
"""

from __future__ import annotations

import numpy as np

__all__ = ["critical_polynomial", "roots_batch"]


def roots_batch(coefs) -> list:
    """The roots of each polynomial of ``coefs`` (power coefficients, lowest first), as ``polyroots`` gives them.

    Parameters
    ----------
    coefs : sequence of array-like, shape (k_i,)

    Returns
    -------
    list of ndarray
        One array per polynomial: complex, or real when every root of its size's stack is real (``eigvals``' rule;
        the values are the same either way).
    """
    out = [None] * len(coefs)
    groups = {}
    for k, c in enumerate(coefs):
        c = np.asarray(c, dtype=float)
        nz = np.flatnonzero(c)
        c = c[: (nz[-1] + 1 if nz.size else 1)]  # polyroots' as_series trims trailing zeros
        if c.size < 2:
            out[k] = np.array([], dtype=float)
        elif c.size == 2:
            out[k] = np.array([-c[0] / c[1]])
        else:
            groups.setdefault(c.size, []).append((k, c))
    for size, items in groups.items():
        n = size - 1
        C = np.stack([c for _, c in items])
        mats = np.zeros((len(items), n, n))
        sub = np.arange(1, n)
        mats[:, sub, sub - 1] = 1.0
        mats[:, :, -1] -= C[:, :-1] / C[:, -1:]
        roots = np.linalg.eigvals(mats)
        roots.sort(axis=-1)
        for (k, _), r in zip(items, roots):
            out[k] = r
    return out


def critical_polynomial(n0, n1) -> np.ndarray:
    """``N0' N1 - N0 N1'`` (power coefficients): where the row's bound ``-N0 / N1`` is extreme.  The same arithmetic
    as ``polysub(polymul(polyder(n0), n1), polymul(n0, polyder(n1)))`` (trailing zeros trimmed where numpy trims
    them), without its per-call overhead: the same coefficients, bit for bit (``test_roots_batch``)."""

    def trim(c):
        nz = np.flatnonzero(c)
        return c[: nz[-1] + 1] if nz.size else c[:1]

    def der(c):
        return c[1:] * np.arange(1, c.size) if c.size > 1 else c[:1] * 0

    def mul(a, b):
        return trim(np.convolve(trim(a), trim(b)))

    a, b = trim(mul(der(n0), n1)), trim(mul(n0, der(n1)))
    if a.size > b.size:
        out = a.copy()
        out[: b.size] -= b
    else:
        out = -b
        out[: a.size] += a
    return trim(out)
