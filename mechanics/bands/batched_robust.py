"""Competitor preclusion and robust bands for a batch of states at once (Section 5.2, Figs. 12-13).

:func:`competitor_torques_batch` is :func:`qsplan.mechanics.bands.preclusion.competitor_torques`
at every state of a :class:`qsplan.mechanics.bands.batched.StateBatch`, each with its own effort
interval.  The branch and bound starts from one root cell (the whole friction set); its control
values, point bands and lower bounds are computed for all states at once, by the reference's own
functions (:func:`~qsplan.mechanics.bands.preclusion.cell_lower_bounds`,
:func:`~qsplan.mechanics.bands.preclusion.point_bands`,
:func:`~qsplan.mechanics.bands.preclusion.bernstein_matrix`).  Where the root cell resolves both
searches (the smallest and the largest possibly-feasible effort: the control values do not depend
on the interval, so one evaluation serves both) the answer is the reference's; the other states
run the per-state search.  :func:`robust_bands` then cuts the hulls out with
:func:`qsplan.mechanics.bands.robust.assemble_robust_band`, the reference's own assembly.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from qsplan.mechanics.bands.batched import (
    BatchKinematics,
    StateBatch,
    batch_kinematics,
    batch_rows,
    guaranteed_bands_box,
    guaranteed_bands_shared,
    map_batches,
    take_states,
)
from qsplan.mechanics.bands.guaranteed import shared_nodes
from qsplan.mechanics.bands.preclusion import (
    MAX_CELLS,
    PRECLUSION_RTOL,
    CompetitorTorques,
    bernstein_matrix,
    cell_lower_bounds,
    competitor_torques,
    friction_set,
    point_bands,
)
from qsplan.mechanics.bands.robust import assemble_robust_band, check_mu_pair
from qsplan.mechanics.errors import SceneError
from qsplan.mechanics.modes.contact_mode import enumerate_modes, mode_from_letters
from qsplan.mechanics.numerics import DEFAULT_TOLERANCES, Tolerances

__all__ = ["RootStats", "admissible_competitors_batch", "competitor_torques_batch", "robust_bands"]


class RootStats:
    """Counts of competitor searches resolved by the batched root cell and sent to the per-state search."""

    def __init__(self):
        self.root = 0
        self.fallback = 0

    @property
    def share_fallback(self) -> float:
        n = self.root + self.fallback
        return self.fallback / n if n else 0.0


def _root_cell(batch: StateBatch, bk, lo, hi, shared: bool, tol: Tolerances):
    """Control values and point bands of the root cell at every state: det (S, K), N0, N1 (S, K, R), pl, pu, pok (S, P)."""
    n_c = batch.n_c
    if shared:
        nodes = shared_nodes(bk.mode, lo, hi)
        deg = nodes.size - 1
        s0, s1, det, _ = batch_rows(batch, bk, np.repeat(nodes[:, None], n_c, axis=1))
        V = np.broadcast_to(np.vander(nodes, deg + 1, increasing=True), (batch.size, deg + 1, deg + 1))
        cdet = np.linalg.solve(V, det[..., None])[..., 0]  # power-basis coefficients in mu
        cN0 = np.linalg.solve(V, s0 * det[..., None])
        cN1 = np.linalg.solve(V, s1 * det[..., None])
        a, b = np.array([lo]), np.array([hi])
        M = bernstein_matrix(deg, a, b)  # (1, K, j); products shaped as the reference's, so bit-identical
        det_c = np.concatenate([M @ c for c in cdet])
        N0 = np.concatenate([M @ c for c in cN0])
        N1 = np.concatenate([M @ c for c in cN1])
        pts = np.stack([a, 0.5 * (a + b), b], axis=1)
        s0, s1, _, scale = batch_rows(batch, bk, np.repeat(pts.reshape(-1, 1), n_c, axis=1))
        P = 3
    else:
        free = [c for c in range(n_c) if bk.mode.letters[c] != "B" and hi[c] > lo[c]]
        d = len(free)
        bits = ((np.arange(2**d)[:, None] >> np.arange(d)[None]) & 1).astype(bool)  # preclusion's vertex order
        mu = np.tile(lo, (2**d, 1))
        mu[:, free] = np.where(bits, hi[free][None], lo[free][None])
        s0, s1, det_c, scale = batch_rows(batch, bk, mu)
        N0 = s0 * det_c[..., None]
        N1 = s1 * det_c[..., None]
        P = 2**d
    S, R = s0.shape[0], s0.shape[2]
    pl, pu, pok = point_bands(s0.reshape(-1, R), s1.reshape(-1, R), scale.reshape(-1), tol)
    return det_c, N0, N1, pl.reshape(S, P), pu.reshape(S, P), pok.reshape(S, P)


def _root_search(cell, lo_, hi_, flip, atol, tol):
    """The first step of the per-state search at every state: ``(value, resolved)`` (S,) each."""
    det, N0, N1, pl, pu, pok = cell
    sign = -1.0 if flip else 1.0
    if flip:
        pl, pu = -pu, -pl
    lo2, hi2, at2 = lo_[:, None], hi_[:, None], atol[:, None]
    feas = pok & (pl <= pu) & (np.maximum(pl, lo2) <= np.minimum(pu, hi2) + at2)
    incumbent = np.min(np.where(feas, np.clip(pl, lo2, hi2), np.inf), axis=1)
    lb, _ = cell_lower_bounds(det, N0, sign * N1, lo_, hi_, tol)
    possible = lb < np.inf
    done = possible & (lb >= np.minimum(incumbent, hi_) - atol)
    floor = np.where(done, lb, np.inf)
    return sign * np.minimum(incumbent, floor), ~(possible & ~done)


def competitor_torques_batch(batch: StateBatch, mode, lo, hi, g_lo, g_hi, shared=False, tol: Tolerances = DEFAULT_TOLERANCES,
                             rtol: float = PRECLUSION_RTOL, max_cells: int = MAX_CELLS, stats: RootStats | None = None,
                             bk: BatchKinematics | None = None) -> list:  # fmt: skip
    """:func:`qsplan.mechanics.bands.preclusion.competitor_torques` at every state of ``batch``.

    Parameters
    ----------
    g_lo, g_hi : array-like, shape (S,)
        Each state's effort interval (N m or N).
    stats : RootStats, optional
        Counts the states the root cell resolved and those searched one at a time.
    bk : BatchKinematics, optional
        ``mode``'s kinematic stage on ``batch`` if already computed (the same arrays :func:`batch_kinematics` gives).

    Returns
    -------
    list of CompetitorTorques, length S
    """
    mode = mode_from_letters(mode)
    n_c, S = batch.n_c, batch.size
    g_lo = np.broadcast_to(np.asarray(g_lo, dtype=float), (S,))
    g_hi = np.broadcast_to(np.asarray(g_hi, dtype=float), (S,))
    lo_a, hi_a = friction_set(lo, hi, n_c, shared)
    if not np.all(g_lo <= g_hi):
        k = int(np.flatnonzero(~(g_lo <= g_hi))[0])
        raise SceneError(f"effort interval: expected g_lo <= g_hi; got {g_lo[k]}, {g_hi[k]}")
    bk = batch_kinematics(batch, mode, tol) if bk is None else bk
    out = [None] * S
    for s in np.flatnonzero(~bk.ok):
        out[s] = CompetitorTorques(mode.letters, np.nan, np.nan, True, True, f"kinematics: {bk.status_name(s)}")
    live = np.flatnonzero(bk.ok)
    if not live.size:
        return out
    c_shared, c_lo, c_hi = shared, lo_a, hi_a
    if shared and hi_a == lo_a:
        c_shared, c_lo, c_hi = False, np.full(n_c, lo_a), np.full(n_c, hi_a)
    sub = take_states(batch, live)
    bks = _take_kin(bk, live)
    cell = _root_cell(sub, bks, c_lo, c_hi, c_shared, tol)
    gl, gh = g_lo[live], g_hi[live]
    finite = lambda x: np.where(np.isfinite(x), np.abs(x), 0.0)  # noqa: E731
    atol = rtol * np.maximum(np.maximum(finite(gl), finite(gh)), 1.0)
    low, ok1 = _root_search(cell, gl, gh, False, atol, tol)
    neg_up, ok2 = _root_search(cell, -gh, -np.where(low == np.inf, gh, low), True, atol, tol)
    for j, s in enumerate(live):
        if not ok1[j] or (low[j] != np.inf and not ok2[j]):
            out[s] = competitor_torques(batch.scenes[s], mode, lo, hi, float(gl[j]), float(gh[j]), shared, tol, rtol, max_cells)
            if stats is not None:
                stats.fallback += 1
            continue
        if stats is not None:
            stats.root += 1
        if low[j] == np.inf:  # proved: the root cell admits no effort of the interval
            out[s] = CompetitorTorques(mode.letters, np.nan, np.nan, True, True, None, 1)
            continue
        up = neg_up[j] if neg_up[j] != -np.inf else low[j]
        out[s] = CompetitorTorques(mode.letters, float(low[j]), float(max(up, low[j])), False, True, None, 2)
    return out


def _take_kin(bk, rows):
    return bk if rows.size == bk.status.size else replace(bk, status=bk.status[rows], xi=bk.xi[rows])


def admissible_competitors_batch(batch: StateBatch, mode, tol: Tolerances = DEFAULT_TOLERANCES, kin: dict | None = None) -> tuple:
    """Per state, the modes other than ``mode`` kinematically admissible there, in enumeration order;
    and the union (:func:`qsplan.mechanics.bands.robust.admissible_competitors` of the whole batch).
    ``kin``, if given, receives each mode's :class:`BatchKinematics` (the competitors' preclusion reuses them).

    Returns
    -------
    per_state : list of tuple of str, length S
    union : tuple of str
    """
    mode = mode_from_letters(mode)
    s0 = batch.scenes[0]
    kin = {} if kin is None else kin
    for m in enumerate_modes(s0.n_contacts, s0.dof):
        if m.letters != mode.letters:
            kin[m.letters] = batch_kinematics(batch, m, tol)
    oks = [(c, bk.ok) for c, bk in kin.items()]
    per_state = [tuple(c for c, ok in oks if ok[s]) for s in range(batch.size)]
    return per_state, tuple(c for c, ok in oks if ok.any())


def robust_bands(scenes, mode, mu_range, *, shared: bool = False, competitors=None, force_margin=None,
                 stats: RootStats | None = None) -> list:  # fmt: skip
    """:func:`qsplan.mechanics.bands.robust.robust_band` at every scene, batched (same results).

    Scenes are grouped by :func:`qsplan.mechanics.bands.batched.batch_signature`; each group is one batch.
    ``stats`` (:class:`RootStats`) counts the competitor searches the batched root cell resolved.

    Returns
    -------
    list of RobustBand, one per scene
    """
    lo, hi = check_mu_pair(mu_range)
    mode = mode_from_letters(mode)

    def per_batch(batch):
        kin = {}
        if competitors is None:
            per_state, union = admissible_competitors_batch(batch, mode, kin=kin)
        else:
            union = tuple(competitors)
            per_state = [union] * batch.size
        guaranteed = guaranteed_bands_shared if shared else guaranteed_bands_box
        desired = guaranteed(batch, mode, lo, hi, force_margin=force_margin)
        torques = [{} for _ in desired]
        idx = np.flatnonzero([d.feasible for d in desired])
        if idx.size:
            sub = take_states(batch, idx)
            g_lo = np.array([desired[s].lower + 0.0 for s in idx])  # + 0.0: no negative zero
            g_hi = np.array([desired[s].upper + 0.0 for s in idx])
            for c in union:
                bk = _take_kin(kin[c], idx) if c in kin else None
                for s, ct in zip(idx, competitor_torques_batch(sub, c, lo, hi, g_lo, g_hi, shared, stats=stats, bk=bk)):
                    torques[s][c] = ct
        return [assemble_robust_band(mode, d, comps, t, (lo, hi), shared) for d, comps, t in zip(desired, per_state, torques)]

    return map_batches(scenes, per_batch)
