"""Bands robust to a box of disturbance wrenches on the workpiece (eqs. 2, 26-28; the paper's ref. [39]).

A disturbance is an unknown external wrench ``w`` on the workpiece, added to the scene's ``g_obj``
(eq. 2: ``W c + g_obj + w = 0``), about the same point (the world origin) and in its units
(N, N, N m), anywhere in a box ``lo <= w <= hi`` (:class:`WrenchBox`).  A band robust to it holds
the desired mode feasible for every friction of the set **and** every wrench of the box, and keeps
every competing mode infeasible for all of them.

Why the vertex argument extends (the proof, equation by equation):

* eq. (26) with ``g_obj + w``: ``c_A = Q_AI^{-1} ([-g_obj - w; -g_man_I] + tau e)``.  ``Q_AI`` does not
  depend on ``w`` (nor on ``tau``), so with friction fixed ``c_A`` is affine in ``(tau, w)`` jointly, and so
  is every Coulomb row of eq. (28): ``s_r = s0_r + tau s1_r + s2_r . w`` (:func:`qsplan.mechanics.bands.effort.
  band_rows` with ``loads=True`` gives ``s2``, the rows' change per unit of each wrench component).
* By Cramer's rule ``det Q_AI * c_A = adj(Q_AI) (...)``: ``adj`` is multilinear in the sliding contacts'
  mu (eqs. 17-20) and the right-hand side affine in ``w``, so ``N_r = det Q_AI * s_r`` is multilinear in
  ``(mu, w)`` jointly (a rolling contact's mu multiplies its own rows, eq. 21) and affine in ``tau``; over one
  shared coefficient it is a polynomial in mu whose coefficients are affine in ``w``.
* **Desired mode** ("for every mu and every w"): for fixed mu the rows are affine in ``w``, so they hold on
  the whole wrench box iff at its ``2^3`` vertices.  Hence the guaranteed band is the intersection of the
  bands over the wrench vertices of the friction-only guarantee: box friction, the vertex bands over the
  product of the friction box and the wrench box (``det Q_AI`` keeping its sign is checked on the friction
  vertices, as before; it does not depend on ``w``); shared friction, the polynomial-root band of
  :func:`qsplan.mechanics.bands.guaranteed.guaranteed_band_shared` at each wrench vertex, intersected
  (each row only at the vertices that can be its worst: where its slope ``s2_rj`` keeps one sign over the
  range, proved by Bernstein coefficients, the vertex with ``w_j`` at the other end gives a larger ``s_r``
  at every mu and effort and cuts nothing more).  Exact, like the friction-only bands.  A force margin
  (``s_r >= m_r``) keeps it exact (the margin is a constant; the rows stay affine in ``w``).
* **Competitors** ("infeasible for every mu and every w"): whether a competitor is possible for *some*
  ``(mu, w)`` is a projection, not a vertex question: for fixed mu its feasible ``(tau, w)`` form a
  polyhedron, and its extreme efforts need not sit at a vertex of the wrench box (two rows pulling a wrench
  component opposite ways meet inside).  Two exact tools take it instead:
  (a) the wrench is three more dimensions of the branch and bound of
  :mod:`qsplan.mechanics.bands.preclusion`: a cell is a friction cell times a wrench cell, its control values
  the values at the product's vertices (box friction) or the Bernstein coefficients at each wrench vertex
  (shared friction); both bound ``N_r`` on the cell with the same weights for every row (multilinear in
  ``(mu, w)``; a polynomial in mu times affine in ``w``), so every bound, incumbent and certificate argument
  of that module holds unchanged, and bisection along the wrench sides converges as along the friction ones;
  (b) a certificate (:mod:`qsplan.mechanics.bands.certificates`) over the control values covers the whole
  wrench cell at once, and at a fixed friction it is exact: the competitor is infeasible for every
  ``(tau, w)`` of ``[a, b] x box`` iff ``max_x min_r s_r(x) < 0`` over that compact convex set, and by the
  minimax theorem (``min_r s_r = min_{y in simplex} y . s``, bilinear) iff some row weights ``y`` make
  ``y . s < 0`` on the whole set, i.e. at its vertices: exactly what the certificate's programme asks.
  The search is exact to its tolerance when it finishes and conservative (labelled) when it runs out of cells.

With ``disturbance`` None or a box of zeros (:func:`check_wrench_box` returns None) every function takes its
path without disturbance: today's answers bit for bit.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qsplan.mechanics.errors import QsplanError

__all__ = ["MAX_DISTURBANCE", "WrenchBox", "check_wrench_box", "load_columns", "loaded_reason", "shift_rows",
           "worst_over_wrenches", "wrench_vertex_parts", "wrench_vertex_rows"]  # fmt: skip

#: Largest magnitude of a disturbance component (N or N m).  A hand-held workpiece meets inertial and contact
#: disturbances of grams to kilograms times g; a component above 1e6 is a unit mistake (mN or N mm given as N),
#: and it would swamp the rows' relative tolerance (``Tolerances.force``, 1e-9 of the load) with rounding.
MAX_DISTURBANCE = 1e6

_UNITS = ("N", "N", "N m")


@dataclass(frozen=True, slots=True)
class WrenchBox:
    """A box of external wrenches on the workpiece: ``lo <= w <= hi`` componentwise (N, N, N m).

    About the same point as the scene's ``g_obj`` (the world origin, eq. 2), added to it.

    Attributes
    ----------
    lo, hi : tuple of 3 floats
        Lower and upper corners (force x, force y in N; moment in N m); given as array-like, shape (3,).

    Raises
    ------
    QsplanError
        A corner of the wrong shape, non-finite, above :data:`MAX_DISTURBANCE` in magnitude, or ``lo > hi``
        (the message names the field and component).
    """

    lo: tuple
    hi: tuple

    def __post_init__(self):
        corners = {}
        for name in ("lo", "hi"):
            try:
                v = np.asarray(getattr(self, name), dtype=float)
            except (TypeError, ValueError):
                raise QsplanError(f"disturbance.{name}: expected 3 numbers (N, N, N m); got {getattr(self, name)!r}") from None
            if v.shape != (3,):
                raise QsplanError(f"disturbance.{name}: expected shape (3,) (N, N, N m); got shape {v.shape}")
            if not np.all(np.isfinite(v)):
                raise QsplanError(f"disturbance.{name}: expected finite numbers; got {v.tolist()}")
            big = np.flatnonzero(np.abs(v) > MAX_DISTURBANCE)
            if big.size:
                i = int(big[0])
                limit = f"{MAX_DISTURBANCE:g} {_UNITS[i]}"
                raise QsplanError(f"disturbance.{name}[{i}]: expected magnitude <= {limit}; got {float(v[i])!r}")
            corners[name] = v
        bad = np.flatnonzero(corners["lo"] > corners["hi"])
        if bad.size:
            i = int(bad[0])
            lo_i, hi_i = float(corners["lo"][i]), float(corners["hi"][i])
            raise QsplanError(f"disturbance: expected lo <= hi; got lo[{i}] = {lo_i!r} > hi[{i}] = {hi_i!r}")
        for name, v in corners.items():
            object.__setattr__(self, name, tuple(float(x) + 0.0 for x in v))  # + 0.0: no negative zero

    @property
    def is_zero(self) -> bool:
        """Both corners zero: no disturbance."""
        return not any(self.lo) and not any(self.hi)

    @property
    def free(self) -> tuple:
        """The components whose interval has width (``hi > lo``), in order."""
        return tuple(i for i in range(3) if self.hi[i] > self.lo[i])

    def vertices(self) -> np.ndarray:
        """The box's vertices over :attr:`free`, shape (2^d, 3): vertex ``k`` takes ``hi`` at free component
        ``i`` where bit ``i`` of ``k`` is set (the vertex order of :mod:`qsplan.mechanics.bands.preclusion`)."""
        lo, hi, free = np.array(self.lo), np.array(self.hi), list(self.free)
        bits = ((np.arange(2 ** len(free))[:, None] >> np.arange(len(free))[None]) & 1).astype(bool)
        verts = np.tile(lo, (bits.shape[0], 1))
        verts[:, free] = np.where(bits, hi[free], lo[free])
        return verts

    def to_dict(self) -> dict:
        """``{"lo": [...], "hi": [...], "units": ["N", "N", "N m"]}`` for exports."""
        return {"lo": list(self.lo), "hi": list(self.hi), "units": list(_UNITS)}


def check_wrench_box(disturbance) -> WrenchBox | None:
    """A :class:`WrenchBox` from None, a WrenchBox or a pair ``(lo, hi)``; None for no disturbance (None or zeros).

    Raises
    ------
    QsplanError
        Anything else, or a box :class:`WrenchBox` rejects.
    """
    if disturbance is None:
        return None
    if not isinstance(disturbance, WrenchBox):
        if not (isinstance(disturbance, (tuple, list)) and len(disturbance) == 2):
            raise QsplanError(f"disturbance: expected a WrenchBox or (lo, hi), each 3 numbers (N, N, N m); got {disturbance!r}")
        disturbance = WrenchBox(*disturbance)
    return None if disturbance.is_zero else disturbance


def load_columns(r0, loads: bool = False) -> np.ndarray:
    """The right-hand sides of eq. (26), shape (k, 2) or with ``loads`` (k, 5): at zero effort (``r0``), per unit
    effort (``e``), and per unit of each component of an extra wrench ``w`` on the workpiece (``g_obj + w``
    enters as ``-w``: N, N, N m).  ``r0`` (k,) or (S, k): then (S, k, 2 or 5)."""
    r0 = np.asarray(r0, dtype=float)
    e = np.zeros(r0.shape[-1])
    e[3] = 1.0
    cols = [r0, np.broadcast_to(e, r0.shape)]
    if loads:
        cols += [np.broadcast_to(-np.eye(r0.shape[-1])[j], r0.shape) for j in range(3)]
    return np.stack(cols, axis=-1)


def loaded_reason(reason, box: WrenchBox | None):
    """A band's reason, naming the disturbance where it decided (Coulomb rows failing; kinematics and
    singularity do not depend on the load)."""
    if box is None or reason is None or not reason.startswith("coulomb"):
        return reason
    return f"{reason}, with every wrench of the disturbance box"


def shift_rows(s0, s2, wrenches):
    """``s0 + s2 . w`` at every wrench: shape (..., W, N, r) from ``s0`` (..., N, r), ``s2`` (..., N, r, 3) and
    ``wrenches`` (W, 3) or (..., W, 3).

    Elementwise, in one fixed order of operations, so any batch of states gives each state's own bits.
    """
    w = np.asarray(wrenches, dtype=float)
    out = s0[..., None, :, :]
    for j in range(3):
        out = out + s2[..., None, :, :, j] * w[..., :, None, None, j]
    return out


def wrench_vertex_rows(s0, s1, det, scale, s2, wrenches):
    """:func:`qsplan.mechanics.bands.effort.band_rows`' output at every (wrench, friction point) pair, wrench-major.

    Parameters
    ----------
    s0, s1 : ndarray, shape (..., N, r)
    det, scale : ndarray, shape (..., N)
        ``scale`` may be None (then None is returned for it).
    s2 : ndarray, shape (..., N, r, 3)
        ``band_rows(..., loads=True)``' slopes in the wrench.
    wrenches : ndarray, shape (W, 3) or (..., W, 3)

    Returns
    -------
    s0, s1 : ndarray, shape (..., W N, r)
        Row ``w N + n``: the rows at friction point ``n`` under wrench ``w``.
    det, scale : ndarray, shape (..., W N)
        ``scale``: the force scale of the rows or the wrench's largest component, whichever is larger (N),
        for the tolerances (``Tolerances.force`` is relative to the largest load).
    """
    rows, s1w, scale = wrench_vertex_parts(s0, s1, scale, s2, wrenches)
    lead, (W, N, r) = rows.shape[:-3], rows.shape[-3:]
    flat = lambda a: a.reshape(lead + (W * N,) + a.shape[len(lead) + 2 :])  # noqa: E731
    s1w = np.broadcast_to(s1w, lead + (W, N, r))
    detw = np.broadcast_to(det[..., None, :], lead + (W, N))
    if scale is not None:
        scale = flat(np.broadcast_to(scale, lead + (W, N)))
    return flat(rows), flat(s1w), flat(detw), scale


def wrench_vertex_parts(s0, s1, scale, s2, wrenches):
    """:func:`wrench_vertex_rows`' ``s0``, ``s1`` and ``scale`` with the wrench axis apart and nothing repeated:
    ``s0`` (..., W, N, r), ``s1`` (..., 1, N, r) (it does not depend on the wrench: a view) and ``scale`` (..., W, N)
    (None if ``scale`` is), for the functions that take them broadcast
    (:func:`qsplan.mechanics.bands.effort.intersect_rows`)."""
    w = np.asarray(wrenches, dtype=float)
    rows = shift_rows(s0, s2, w)
    if scale is not None:
        size = np.max(np.abs(w), axis=-1)[..., :, None]  # (..., W, 1)
        scale = np.maximum(scale[..., None, :], size)
    return rows, s1[..., None, :, :], scale


def worst_over_wrenches(lower, upper, ok, W: int):
    """Per friction point, the band that holds at all ``W`` wrenches: ``lower, upper, ok`` (..., N) from the
    per-pair bands (..., W N) of :func:`wrench_vertex_rows`' rows."""
    shape = lower.shape[:-1] + (W, lower.shape[-1] // W)
    lo_, up_ = lower.reshape(shape).max(axis=-2), upper.reshape(shape).min(axis=-2)
    return lo_, up_, ok.reshape(shape).all(axis=-2) & (lo_ <= up_)
