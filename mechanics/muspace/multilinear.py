"""Multilinear polynomials in the friction coefficients (Sections 4.1-4.6).

For a contact mode whose sliding directions ``xi`` are fixed by the kinematic
stage, ``Q_AI(mu) = U + V diag(mu)`` (eqs. 18-20, 26): the column of a sliding
contact *i* is ``u_i - mu_i xi_i v_i`` and no other column holds ``mu_i``.  The
determinant is multilinear in its columns, so ``det Q_AI`` and every cofactor
are multilinear in the sliding contacts' mu (affine in each one separately):

    det Q_AI(mu) = sum_T  mu^T  det(Q_T),     mu^T = prod_{i in T} mu_i,

where ``Q_T`` is ``U`` with the columns of the contacts in ``T`` replaced by
their mu-coefficient columns (:func:`column_expansion`).  Appendix A's
coefficients ``A, B_i, C_i, D`` are exactly these ``det(Q_T)``.

A multilinear polynomial in ``n`` variables has ``2^n`` coefficients ``a_T``
and is fixed by its values on the corners ``{0, 1}^n``: with ``p(1_S)`` the
value where the variables in ``S`` are 1 and the others 0,

    a_T = sum_{S subset T} (-1)^{|T| - |S|} p(1_S)       (Moebius inversion),
    p(1_S) = sum_{T subset S} a_T                         (its inverse, :func:`corner_values`).

:func:`moebius` implements the first; the tests check that it recovers the
column expansion from ``2^n`` evaluations of ``det Q_AI`` at the corners.

Coefficients are stored flat, shape ``(2**n,)``: index ``b`` holds the
coefficient of the monomial whose variables are the set bits of ``b`` (bit
``i`` is ``variables[i]``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qsplan.mechanics.errors import QsplanError

__all__ = [
    "Multilinear",
    "monomials",
    "moebius",
    "corner_values",
    "restrict_coef",
    "column_expansion",
    "adjugate",
]


def monomials(mu, variables) -> np.ndarray:
    """All monomials ``mu^T`` over subsets ``T`` of ``variables``.

    Parameters
    ----------
    mu : array-like, shape (..., n_c)
    variables : sequence of int, length n
        0-based contact indices.

    Returns
    -------
    ndarray, shape (..., 2**n)
        Column ``b`` is the product of ``mu[..., variables[i]]`` over the set bits ``i`` of ``b``.
    """
    mu = np.asarray(mu, dtype=float)
    M = np.ones(mu.shape[:-1] + (1,))
    for v in variables:
        M = np.concatenate([M, M * mu[..., v, None]], axis=-1)
    return M


def _axes_view(coef: np.ndarray, n: int) -> np.ndarray:
    """``coef`` (2**n, ...) viewed with one axis of length 2 per variable; variable i is axis n-1-i."""
    return coef.reshape((2,) * n + coef.shape[1:])


def moebius(values) -> np.ndarray:
    """Coefficients of a multilinear polynomial from its values on the corners ``{0, 1}^n``.

    Parameters
    ----------
    values : array-like, shape (2**n, ...)
        ``values[b]`` is the polynomial at the corner whose coordinates are the bits of ``b``.

    Returns
    -------
    ndarray, shape (2**n, ...)
        ``a_T = sum_{S subset T} (-1)^{|T|-|S|} p(1_S)``.
    """
    a = np.array(values, dtype=float, copy=True)
    n = _bits(a.shape[0])
    v = _axes_view(a, n)
    for ax in range(n):
        idx1 = [slice(None)] * v.ndim
        idx0 = [slice(None)] * v.ndim
        idx1[ax], idx0[ax] = 1, 0
        v[tuple(idx1)] -= v[tuple(idx0)]
    return a


def corner_values(coef) -> np.ndarray:
    """Values on the corners ``{0, 1}^n`` of the polynomial with coefficients ``coef`` (inverse of :func:`moebius`)."""
    a = np.array(coef, dtype=float, copy=True)
    n = _bits(a.shape[0])
    v = _axes_view(a, n)
    for ax in range(n):
        idx1 = [slice(None)] * v.ndim
        idx0 = [slice(None)] * v.ndim
        idx1[ax], idx0[ax] = 1, 0
        v[tuple(idx1)] += v[tuple(idx0)]
    return a


def restrict_coef(coef, variables, mu, keep) -> tuple[tuple, np.ndarray]:
    """Substitute ``mu[v]`` for the variables ``v`` not in ``keep`` in coefficient arrays.

    Parameters
    ----------
    coef : array-like, shape (2**n, ...)
        Coefficients over ``variables`` (several polynomials along the trailing axes).
    variables : sequence of int, length n
    mu : array-like, shape (n_c,)
    keep : collection of int

    Returns
    -------
    kept : tuple of int
        The variables that remain, increasing.
    coef : ndarray, shape (2**len(kept), ...)
    """
    coef = np.asarray(coef, dtype=float)
    mu = np.asarray(mu, dtype=float)
    n, tail = len(variables), coef.shape[1:]
    v = _axes_view(coef, n)  # axis 0 is the highest variable
    kept = []
    for i in reversed(range(n)):
        if variables[i] in keep:
            kept.append(variables[i])
            v = np.moveaxis(v, 0, v.ndim - len(tail) - 1)
        else:
            v = v[0] + mu[variables[i]] * v[1]
    # the kept axes now trail the remaining (substituted) ones in decreasing variable order and
    # precede the tail; C-order flattening gives the lowest kept variable bit 0, as wanted.
    return tuple(reversed(kept)), np.ascontiguousarray(v).reshape((1 << len(kept),) + tail)


def _bits(size: int) -> int:
    n = int(size).bit_length() - 1
    if size < 1 or 1 << n != size:
        raise QsplanError(f"coef: expected 2**n coefficients; got {size}")
    return n


@dataclass(frozen=True, slots=True, eq=False)
class Multilinear:
    """A real polynomial affine in each of its variables separately.

    Attributes
    ----------
    variables : tuple of int
        0-based contact indices (``mu_{i+1}`` in the paper), strictly increasing.
    coef : ndarray, shape (2**n,)
        Coefficient of ``prod_{bits i of b} mu[variables[i]]`` at index ``b``.
    """

    variables: tuple
    coef: np.ndarray

    def __post_init__(self):
        c = np.array(self.coef, dtype=float).reshape(-1)
        if c.size != 1 << len(self.variables):
            n = len(self.variables)
            raise QsplanError(f"coef: expected {1 << n} coefficients for {n} variables; got {c.size}")
        if list(self.variables) != sorted(set(self.variables)):
            raise QsplanError(f"variables: expected strictly increasing contact indices; got {self.variables}")
        c.setflags(write=False)
        object.__setattr__(self, "variables", tuple(int(v) for v in self.variables))
        object.__setattr__(self, "coef", c)

    @classmethod
    def from_terms(cls, variables, terms: dict) -> "Multilinear":
        """Build from ``{(v, w, ...): coefficient}`` with ``v, w`` in ``variables`` (missing terms are 0)."""
        variables = tuple(variables)
        coef = np.zeros(1 << len(variables))
        for key, value in terms.items():
            b = sum(1 << variables.index(v) for v in key)
            coef[b] += value
        return cls(variables, coef)

    @classmethod
    def constant(cls, value: float) -> "Multilinear":
        return cls((), np.array([float(value)]))

    def __call__(self, mu) -> np.ndarray:
        """Values at ``mu`` of shape (..., n_c); returns shape (...)."""
        return monomials(mu, self.variables) @ self.coef

    def abs_terms(self, mu) -> np.ndarray:
        """``sum_T |a_T mu^T|`` at ``mu`` (..., n_c): the scale of the rounding error of a value."""
        return np.abs(monomials(mu, self.variables)) @ np.abs(self.coef)

    @property
    def is_zero(self) -> bool:
        return not np.any(self.coef)

    def coefficient(self, *variables) -> float:
        """Coefficient of the monomial ``prod mu_v`` over ``variables`` (0 if a variable is absent)."""
        if any(v not in self.variables for v in variables):
            return 0.0
        return float(self.coef[sum(1 << self.variables.index(v) for v in set(variables))])

    def embed(self, variables) -> "Multilinear":
        """The same polynomial over a superset ``variables`` of its own (increasing)."""
        variables = tuple(variables)
        pos = [variables.index(v) for v in self.variables]
        coef = np.zeros(1 << len(variables))
        for b, a in enumerate(self.coef):
            coef[sum(1 << p for i, p in enumerate(pos) if b >> i & 1)] = a
        return Multilinear(variables, coef)

    def times(self, v: int) -> "Multilinear":
        """``mu_v * self``; ``v`` must not already occur in a monomial with a nonzero coefficient."""
        variables = tuple(sorted(set(self.variables) | {v}))
        p = self.embed(variables)
        i = variables.index(v)
        has = (np.arange(p.coef.size) >> i) & 1 == 1
        if np.any(p.coef[has]):
            raise QsplanError(f"times: mu{v + 1} already occurs; the product would not be multilinear")
        coef = np.zeros_like(p.coef)
        coef[np.flatnonzero(~has) | (1 << i)] = p.coef[~has]
        return Multilinear(variables, coef)

    def _binary(self, other, sign):
        variables = tuple(sorted(set(self.variables) | set(other.variables)))
        return Multilinear(variables, self.embed(variables).coef + sign * other.embed(variables).coef)

    def __add__(self, other: "Multilinear") -> "Multilinear":
        return self._binary(other, 1.0)

    def __sub__(self, other: "Multilinear") -> "Multilinear":
        return self._binary(other, -1.0)

    def __neg__(self) -> "Multilinear":
        return Multilinear(self.variables, -self.coef)

    def scaled(self, factor: float) -> "Multilinear":
        return Multilinear(self.variables, factor * self.coef)

    def restrict(self, mu, keep) -> "Multilinear":
        """Substitute ``mu[v]`` for every variable ``v`` not in ``keep``.

        Parameters
        ----------
        mu : array-like, shape (n_c,)
        keep : sequence of int
            Contacts that stay variables.
        """
        kept, coef = restrict_coef(self.coef, self.variables, mu, keep)
        return Multilinear(kept, coef)

    def bilinear(self, x: int, y: int, mu) -> np.ndarray:
        """Coefficients ``(a, b, c, d)`` of ``a + b mu_x + c mu_y + d mu_x mu_y`` on a slice.

        Parameters
        ----------
        x, y : int
            0-based contacts of the two free coefficients (distinct).
        mu : array-like, shape (n_c,)
            Values of the other coefficients.
        """
        r = self.restrict(mu, (x, y))
        return np.array([r.coefficient(), r.coefficient(x), r.coefficient(y), r.coefficient(x, y)])

    def __str__(self) -> str:
        parts = []
        for b, a in enumerate(self.coef):
            if a == 0:
                continue
            mon = " ".join(f"mu{self.variables[i] + 1}" for i in range(len(self.variables)) if b >> i & 1)
            parts.append(f"{a:+.6g}" + (f" {mon}" if mon else ""))
        return " ".join(parts) if parts else "0"


def adjugate(A) -> np.ndarray:
    """Adjugate ``adj(A)`` (``adj(A) A = det(A) I``) of square matrices, singular ones included.

    Computed from the SVD ``A = U S V^T`` as ``det(U) det(V) V adj(S) U^T`` with
    ``adj(S) = diag(prod_{j != i} s_j)``, which stays accurate when ``A`` is singular.

    Parameters
    ----------
    A : array-like, shape (..., k, k)

    Returns
    -------
    ndarray, shape (..., k, k)
    """
    A = np.asarray(A, dtype=float)
    k = A.shape[-1]
    if k == 1:
        return np.ones_like(A)
    U, s, Vt = np.linalg.svd(A)
    adj_s = _prod_others(s)
    sign = np.linalg.det(U) * np.linalg.det(Vt)
    return sign[..., None, None] * np.einsum("...ji,...j,...kj->...ik", Vt, adj_s, U)


def column_expansion(U, V, columns) -> tuple[np.ndarray, np.ndarray]:
    """Multilinear coefficients of ``det`` and ``adj`` of ``Q(mu) = U + sum_i mu_i V[:, c_i] e_{c_i}^T``.

    Parameters
    ----------
    U : array-like, shape (k, k)
        ``Q`` at ``mu = 0``.
    V : array-like, shape (k, k)
        Column ``c_i`` is the mu-coefficient of column ``c_i`` of ``Q``; other columns ignored.
    columns : sequence of int, length n
        Column ``columns[i]`` is affine in variable ``i`` (bit ``i``).

    Returns
    -------
    det_coef : ndarray, shape (2**n,)
        ``det Q(mu) = sum_b det_coef[b] mu^b``; ``det_coef[b] = det(Q_b)`` with the
        columns of the set bits replaced by their V columns.
    adj_coef : ndarray, shape (2**n, k, k)
        ``adj Q(mu)[j, :] = sum_b adj_coef[b, j, :] mu^b``; row ``j`` of a column
        affine in variable ``i`` has no monomial containing ``i`` (Cramer's rule:
        ``(adj Q r)_j = det(Q with column j replaced by r)``).
    """
    U = np.asarray(U, dtype=float)
    V = np.asarray(V, dtype=float)
    n, k = len(columns), U.shape[0]
    Qs = np.broadcast_to(U, (1 << n, k, k)).copy()
    b = np.arange(1 << n)
    for i, c in enumerate(columns):
        on = (b >> i) & 1 == 1
        Qs[on, :, c] = V[:, c]
    det_coef = np.linalg.det(Qs)
    adj_coef = adjugate(Qs)
    # Structural zeros (a missing variable, parallel columns) come out as rounding noise; snap
    # values below the rounding level, a few k eps times their Hadamard bound, to exact zeros.
    norms = np.linalg.norm(Qs, axis=1)  # column norms, (2**n, k)
    eps = 4 * k * np.finfo(float).eps
    det_coef[np.abs(det_coef) <= eps * np.prod(norms, axis=1)] = 0.0
    # adj[j, l] is a cofactor of a matrix without column j: bounded by the other columns' norms
    adj_coef[np.abs(adj_coef) <= eps * _prod_others(norms)[:, :, None]] = 0.0
    for i, c in enumerate(columns):
        on = (b >> i) & 1 == 1
        adj_coef[on, c, :] = 0.0  # column c replaced by the right-hand side: no mu_i left in row c
    return det_coef, adj_coef


def _prod_others(x):
    """``prod_{j != i} x[..., j]`` without division, shape of ``x``."""
    ones = np.ones(x.shape[:-1] + (1,))
    pre = np.cumprod(np.concatenate([ones, x[..., :-1]], axis=-1), axis=-1)
    suf = np.cumprod(np.concatenate([ones, x[..., :0:-1]], axis=-1), axis=-1)[..., ::-1]
    return pre * suf
