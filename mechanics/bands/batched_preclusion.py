"""Competitor preclusion for a batch of states and many competitors at once (Section 5.2, Figs. 12-13).

:func:`competitor_hulls` is :func:`qsplan.mechanics.bands.preclusion.competitor_torques` for every
competing mode at every state of a :class:`qsplan.mechanics.bands.batched.StateBatch`, each state
with its own effort interval.  The branch and bound starts from one root cell (the whole friction
set); its control values, point bands and lower bounds are computed for all (competitor, state)
pairs at once, by the reference's own functions
(:func:`~qsplan.mechanics.bands.preclusion.extreme_lower_bounds`,
:func:`~qsplan.mechanics.bands.preclusion.point_bands`,
:func:`~qsplan.mechanics.bands.guaranteed.bernstein_matrix`; the rows of every competitor in one
factorisation, :func:`qsplan.mechanics.bands.batched_modes.batch_rows_many`).  Where the root cell
resolves both searches (the smallest and the largest possibly-feasible effort: the control values
do not depend on the interval, so one evaluation serves both) the answer is the reference's; the
other pairs run the per-state search.  The answers are arrays (:class:`HullArrays`), turned into
:class:`~qsplan.mechanics.bands.preclusion.CompetitorTorques` only where asked.  With a box of disturbance
wrenches the root cell is the friction set times the wrench box, its control values at the wrench vertices in
:class:`qsplan.mechanics.bands.cells.FrictionCells`' order (the same numbers as the per-state search's root).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qsplan.mechanics.bands.batched import StateBatch, take_states
from qsplan.mechanics.bands.batched_modes import BatchKinematics, batch_kinematics, batch_rows_many
from qsplan.mechanics.bands.disturbance import check_wrench_box, wrench_vertex_parts, wrench_vertex_rows
from qsplan.mechanics.bands.guaranteed import bernstein_matrix, shared_coordinate, shared_coordinates, shared_nodes
from qsplan.mechanics.bands.preclusion import (
    MAX_CELLS,
    PRECLUSION_RTOL,
    CompetitorTorques,
    competitor_torques,
    extreme_lower_bounds,
    friction_set,
    point_bands,
    wrench_extremes,
)
from qsplan.mechanics.errors import SceneError
from qsplan.mechanics.modes.contact_mode import mode_from_letters
from qsplan.mechanics.numerics import DEFAULT_TOLERANCES, Status, Tolerances

__all__ = ["HullArrays", "RootStats", "competitor_hulls", "competitor_torques_batch"]


class RootStats:
    """Counts of competitor searches resolved by the batched root cell and sent to the per-state search."""

    def __init__(self):
        self.root = 0
        self.fallback = 0

    @property
    def share_fallback(self) -> float:
        n = self.root + self.fallback
        return self.fallback / n if n else 0.0


@dataclass(frozen=True, slots=True, eq=False)
class HullArrays:
    """One competitor's :class:`~qsplan.mechanics.bands.preclusion.CompetitorTorques` at every state of a batch.

    Attributes
    ----------
    mode : str
    lower, upper : ndarray, shape (S,)
        The hull (N m or N); NaN where ``empty``.
    empty, exact : ndarray of bool, shape (S,)
    cells : ndarray of int, shape (S,)
    status : ndarray of int8, shape (S,)
        The competitor's kinematic status (``Status.ORDER`` codes; not 0: empty, never feasible).
    searched : dict of int to CompetitorTorques
        The states the root cell left open, with the per-state search's answer.
    """

    mode: str
    lower: np.ndarray
    upper: np.ndarray
    empty: np.ndarray
    exact: np.ndarray
    cells: np.ndarray
    status: np.ndarray
    searched: dict

    def torques(self, s: int) -> CompetitorTorques:
        """The :class:`~qsplan.mechanics.bands.preclusion.CompetitorTorques` of state ``s``."""
        if s in self.searched:
            return self.searched[s]
        if self.status[s]:
            return CompetitorTorques(self.mode, np.nan, np.nan, True, True, f"kinematics: {Status.ORDER[int(self.status[s])]}")
        if self.empty[s]:  # proved: the root cell admits no effort of the interval
            return CompetitorTorques(self.mode, np.nan, np.nan, True, True, None, int(self.cells[s]))
        return CompetitorTorques(self.mode, float(self.lower[s]), float(self.upper[s]), False, bool(self.exact[s]), None,
                                 int(self.cells[s]))  # fmt: skip


def _vertices(bk: BatchKinematics, lo, hi) -> np.ndarray:
    """The root cell's friction points (box): its vertices over the free contacts, preclusion's vertex order, (2^d, n_c)."""
    free = [c for c in range(lo.size) if bk.mode.letters[c] != "B" and hi[c] > lo[c]]
    d = len(free)
    bits = ((np.arange(2**d)[:, None] >> np.arange(d)[None]) & 1).astype(bool)
    mu = np.tile(lo, (2**d, 1))
    mu[:, free] = np.where(bits, hi[free][None], lo[free][None])
    return mu


def _grouped(parts) -> list:
    """``[(job indices, stacked arrays)]``: the jobs' arrays ``parts`` (one tuple per job) concatenated along the state
    axis over the jobs whose arrays have one shape past it, in job order."""
    groups = {}
    for j, arrays in enumerate(parts):
        groups.setdefault(tuple(a.shape[1:] for a in arrays), []).append(j)
    return [(js, tuple(np.concatenate([parts[j][i] for j in js]) for i in range(len(parts[js[0]])))) for js in groups.values()]


def _root_cells(jobs, lo, hi, shared: bool, box=None) -> list:
    """Control values of the root cell and the rows at its friction points, the jobs ``(batch, bk)`` whose cells have
    one shape stacked: ``[(job indices, (det (m, K), lo0, hi0, N1 (m, K, R), s0, s1 (m, P, R), scale (m, P)))]``,
    ``m`` the states of those jobs in job order.  With a wrench box ``box`` the rows at the friction points are taken
    at each of its vertices, wrench-major (:class:`qsplan.mechanics.bands.cells.FrictionCells`' order), and the control
    values are each row's smallest and largest ``N0`` over them (``lo0``, ``hi0``; ``det`` and ``N1`` do not depend on
    the wrench: :func:`~qsplan.mechanics.bands.preclusion.extreme_lower_bounds` takes them so, the bound of every
    control point); without one, ``lo0`` is ``hi0`` is ``N0``.  Box friction stacks the jobs' rows before the wrench
    vertices multiply them (elementwise: the same numbers, less to copy)."""
    loads = box is not None
    verts = None if box is None else box.vertices()
    if not shared:
        out = []
        for js, rows in _grouped(batch_rows_many([(b, bk, _vertices(bk, lo, hi)) for b, bk in jobs], loads=loads)):
            s0, s1, det, scale = rows[:4]
            N1 = s1 * det[..., None]
            if box is None:
                N0 = s0 * det[..., None]
                out.append((js, (det, N0, N0, N1, s0, s1, scale)))
                continue
            s0, s1, scale = wrench_vertex_parts(s0, s1, scale, rows[4], verts)  # (m, W, K, R), s1 (m, 1, K, R)
            lo0, hi0 = wrench_extremes(s0[:, w] * det[..., None] for w in range(len(verts)))  # N0 = s0 det at each
            out.append((js, (det, lo0, hi0, N1, s0, s1, scale)))
        return out
    nodes = [shared_nodes(bk.mode, lo, hi) for _, bk in jobs]
    at_nodes = batch_rows_many([(b, bk, np.repeat(nd[:, None], b.n_c, axis=1)) for (b, bk), nd in zip(jobs, nodes)], loads=loads)
    a, b = np.array([lo]), np.array([hi])
    pts = np.stack([a, 0.5 * (a + b), b], axis=1)
    at_points = batch_rows_many([(bt, bk, np.repeat(pts.reshape(-1, 1), bt.n_c, axis=1)) for bt, bk in jobs], loads=loads)
    out = []
    for (_, bk), nd, node_rows, point_rows in zip(jobs, nodes, at_nodes, at_points):
        s0, s1, det = node_rows[:3]
        deg = nd.size - 1
        V = np.vander(shared_coordinates(bk.mode), deg + 1, increasing=True)
        V = np.broadcast_to(V, (det.shape[0], deg + 1, deg + 1))
        cdet = np.linalg.solve(V, det[..., None])[..., 0]  # power-basis coefficients in t (shared_coordinate)
        cN0 = np.linalg.solve(V, s0 * det[..., None])
        cN1 = np.linalg.solve(V, s1 * det[..., None])
        Mb = bernstein_matrix(deg, shared_coordinate(a, lo, hi), shared_coordinate(b, lo, hi))  # (1, K, j); as the reference's
        det_c = np.concatenate([Mb @ c for c in cdet])
        N0 = np.concatenate([Mb @ c for c in cN0])
        N1 = np.concatenate([Mb @ c for c in cN1])
        if box is None:
            p0, p1, _, scale = point_rows
        else:
            cN2 = np.linalg.solve(V, (node_rows[4] * det[..., None, None]).reshape(det.shape + (-1,)))
            N2 = np.concatenate([(Mb @ c).reshape(N0.shape[1:] + (3,))[None] for c in cN2])
            K = det_c.shape[1]
            N0 = wrench_vertex_rows(N0, N1, det_c, None, N2, verts)[0]
            lo0, hi0 = wrench_extremes(N0[:, w * K : (w + 1) * K] for w in range(len(verts)))
            p0, p1, _, scale = wrench_vertex_rows(*point_rows, verts)
            out.append((det_c, lo0, hi0, N1, p0, p1, scale))
            continue
        out.append((det_c, N0, N0, N1, p0, p1, scale))
    return _grouped(out)


def _root_search(cell, lo_, hi_, flip, atol, tol):
    """The first step of the per-state search at every state: ``(value, resolved)`` (S,) each."""
    det, lo0, hi0, N1, pl, pu, pok = cell
    sign = -1.0 if flip else 1.0
    if flip:
        pl, pu = -pu, -pl
    lo2, hi2, at2 = lo_[:, None], hi_[:, None], atol[:, None]
    feas = pok & (pl <= pu) & (np.maximum(pl, lo2) <= np.minimum(pu, hi2) + at2)
    incumbent = np.min(np.where(feas, np.clip(pl, lo2, hi2), np.inf), axis=1)
    lb, _ = extreme_lower_bounds(det, lo0, hi0, sign * N1, lo_, hi_, tol)
    possible = lb < np.inf
    done = possible & (lb >= np.minimum(incumbent, hi_) - atol)
    floor = np.where(done, lb, np.inf)
    return sign * np.minimum(incumbent, floor), ~(possible & ~done)


def _root_searches(groups, gl, gh, atol, tol):
    """Both searches of the root cell (the smallest possible effort, then the largest above it) for every job, the
    jobs whose cells have one shape stacked (:func:`_root_cells`' groups): ``(low, upper, resolved)`` per job, (S,)
    each (``upper`` meaningful where ``low`` is finite or ``-inf``, and the search resolved)."""
    out = [None] * len(gl)
    for js, (det, lo0, hi0, N1, s0, s1, scale) in groups:
        g_lo, g_hi, at = (np.concatenate([v[j] for j in js]) for v in (gl, gh, atol))
        m = s0.shape[0]  # the points' rows (m, P, R), or (m, W, K, R) with s1 (m, 1, K, R): point_bands broadcasts
        pl, pu, pok = (x.reshape(m, -1) for x in point_bands(s0, s1, scale, tol))
        cell = (det, lo0, hi0, N1, pl, pu, pok)
        low, ok1 = _root_search(cell, g_lo, g_hi, False, at, tol)
        # the largest possible effort, above the smallest: only where that exists (elsewhere the hull is empty or
        # the per-state search takes over, whatever this search says)
        more = ok1 & (low != np.inf)
        up, resolved = low.copy(), ok1.copy()
        if more.any():
            neg_up, ok2 = _root_search(tuple(c[more] for c in cell), -g_hi[more], -low[more], True, at[more], tol)
            up[more] = np.where(neg_up != -np.inf, neg_up, low[more])  # nothing above low within atol: the point low
            resolved[more] = ok2
        at_ = 0
        for j in js:
            part = slice(at_, at_ + gl[j].size)
            at_ += gl[j].size
            out[j] = (low[part], np.maximum(up[part], low[part]), resolved[part])
    return out


def competitor_hulls(batch: StateBatch, kin: dict, comps, lo, hi, g_lo, g_hi, shared=False, tol: Tolerances = DEFAULT_TOLERANCES,
                     rtol: float = PRECLUSION_RTOL, max_cells: int = MAX_CELLS, stats: RootStats | None = None,
                     states=None, disturbance=None) -> dict:  # fmt: skip
    """:func:`qsplan.mechanics.bands.preclusion.competitor_torques` of every competitor at every state.

    Parameters
    ----------
    kin : dict of str to BatchKinematics
        Each competitor's kinematic stage on ``batch`` (:func:`qsplan.mechanics.bands.batched_modes.modes_kinematics`).
    comps : sequence of str
        The competitors (keys of ``kin``).
    g_lo, g_hi : array-like, shape (S,)
        Each state's effort interval (N m or N).
    states : ndarray of int, optional
        The states to judge (default all); the others come back empty.
    stats : RootStats, optional
        Counts the searches the root cell resolved and those searched one at a time.
    disturbance : WrenchBox or (array-like, array-like), optional
        A box of external wrenches on the workpiece (as :func:`~qsplan.mechanics.bands.preclusion.competitor_torques`).

    Returns
    -------
    dict of str to HullArrays
    """
    S = batch.size
    box = check_wrench_box(disturbance)
    g_lo = np.broadcast_to(np.asarray(g_lo, dtype=float), (S,))
    g_hi = np.broadcast_to(np.asarray(g_hi, dtype=float), (S,))
    lo_a, hi_a = friction_set(lo, hi, batch.n_c, shared)
    states = np.arange(S) if states is None else np.asarray(states, dtype=int)
    if not np.all(g_lo[states] <= g_hi[states]):
        k = int(states[np.flatnonzero(~(g_lo[states] <= g_hi[states]))[0]])
        raise SceneError(f"effort interval: expected g_lo <= g_hi; got {g_lo[k]}, {g_hi[k]}")
    c_shared, c_lo, c_hi = shared, lo_a, hi_a
    if shared and hi_a == lo_a:
        c_shared, c_lo, c_hi = False, np.full(batch.n_c, lo_a), np.full(batch.n_c, hi_a)
    out, jobs, lives = {}, [], []
    for c in comps:
        bk = kin[c]
        status = np.zeros(S, np.int8)
        status[states] = bk.status[states]
        out[c] = HullArrays(c, np.full(S, np.nan), np.full(S, np.nan), np.ones(S, bool), np.ones(S, bool), np.zeros(S, int), status, {})
        live = states[bk.ok[states]]
        if live.size:
            jobs.append((take_states(batch, live), bk.take(live)))
            lives.append((c, live))
    if not jobs:
        return out
    finite = lambda x: np.where(np.isfinite(x), np.abs(x), 0.0)  # noqa: E731
    gl = [g_lo[live] for _, live in lives]
    gh = [g_hi[live] for _, live in lives]
    atol = [rtol * np.maximum(np.maximum(finite(a), finite(b)), 1.0) for a, b in zip(gl, gh)]
    found = _root_searches(_root_cells(jobs, c_lo, c_hi, c_shared, box), gl, gh, atol, tol)
    for (c, live), (low, up, resolved), a, b in zip(lives, found, gl, gh):
        h = out[c]
        bounded = resolved & (low != np.inf)
        h.lower[live] = np.where(bounded, low, np.nan)
        h.upper[live] = np.where(bounded, up, np.nan)
        h.empty[live] = ~bounded
        h.cells[live] = np.where(bounded, 2, 1)
        if stats is not None:
            stats.root += int(resolved.sum())
            stats.fallback += int((~resolved).sum())
        for j in np.flatnonzero(~resolved):  # the root cell leaves it open: the per-state search
            s = int(live[j])
            ct = competitor_torques(batch.scenes[s], c, lo, hi, float(a[j]), float(b[j]), shared, tol, rtol, max_cells, disturbance=box)
            h.searched[s] = ct
            h.lower[s], h.upper[s], h.empty[s], h.exact[s], h.cells[s] = ct.lower, ct.upper, ct.empty, ct.exact, ct.cells
    return out


def competitor_torques_batch(batch: StateBatch, mode, lo, hi, g_lo, g_hi, shared=False, tol: Tolerances = DEFAULT_TOLERANCES,
                             rtol: float = PRECLUSION_RTOL, max_cells: int = MAX_CELLS, stats: RootStats | None = None,
                             bk: BatchKinematics | None = None, disturbance=None) -> list:  # fmt: skip
    """:func:`qsplan.mechanics.bands.preclusion.competitor_torques` at every state of ``batch``.

    Parameters
    ----------
    g_lo, g_hi : array-like, shape (S,)
        Each state's effort interval (N m or N).
    stats : RootStats, optional
        Counts the states the root cell resolved and those searched one at a time.
    bk : BatchKinematics, optional
        ``mode``'s kinematic stage on ``batch`` if already computed (the same arrays :func:`batch_kinematics` gives).
    disturbance : WrenchBox or (array-like, array-like), optional
        As in :func:`competitor_hulls`.

    Returns
    -------
    list of CompetitorTorques, length S
    """
    mode = mode_from_letters(mode)
    S = batch.size
    friction_set(lo, hi, batch.n_c, shared)
    g_lo = np.broadcast_to(np.asarray(g_lo, dtype=float), (S,))
    g_hi = np.broadcast_to(np.asarray(g_hi, dtype=float), (S,))
    if not np.all(g_lo <= g_hi):
        k = int(np.flatnonzero(~(g_lo <= g_hi))[0])
        raise SceneError(f"effort interval: expected g_lo <= g_hi; got {g_lo[k]}, {g_hi[k]}")
    bk = batch_kinematics(batch, mode, tol) if bk is None else bk
    h = competitor_hulls(batch, {mode.letters: bk}, [mode.letters], lo, hi, g_lo, g_hi, shared, tol, rtol, max_cells, stats,
                         disturbance=disturbance)  # fmt: skip
    return [h[mode.letters].torques(s) for s in range(S)]
