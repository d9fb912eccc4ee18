"""Feasible contact modes over many friction coefficients at once (Section 4).

The kinematic stage of every mode (eqs. 24-25, 16) does not depend on mu, so
it runs once; only the equilibrium and Coulomb stage (26)-(28) is repeated, for
all kinematically admissible modes and all mu points together, in bounded
batches.  The answer at every point is exactly what :func:`mechanics.solve`
gives for the scene with that mu.

Two paths give that answer: :func:`feasibility_map` repeats the solver's
equilibrium stage (an LU solve per mode and point), :func:`polynomial_map`
evaluates each mode's multilinear form of ``c_A`` (Sections 4.4-4.6) and is
much faster.  :func:`mu_slice` maps a 2-D slice (the paper's Figs. 3, 6, 8)
together with the modes' exact regions, whose boundary curves are zero sets of
polynomials; :func:`boundary_agreement` checks the two against each other.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qsplan.mechanics.errors import SceneError
from qsplan.mechanics.modes.reference import velocity_scale
from qsplan.mechanics.modes.contact_mode import ContactMode, codes_to_letters, count_modes, iter_mode_batches
from qsplan.mechanics.numerics import DEFAULT_TOLERANCES, Status, Tolerances
from qsplan.mechanics.model.scene import Scene
from qsplan.mechanics.muspace.multilinear import monomials, restrict_coef
from qsplan.mechanics.parallel import chunk_count, map_chunks, split_range
from qsplan.mechanics.muspace.regions import _active, _polynomials_from_kinematics, empty_region, region_from_polynomials
from qsplan.mechanics.solver.batch import ScenePool, equilibrium_stage, kinematics_stage

__all__ = [
    "MuMap",
    "feasibility_map",
    "grid_points",
    "polynomial_map",
    "MuSlice",
    "mu_slice",
    "BoundaryAgreement",
    "boundary_agreement",
]

#: Rows (mode x mu point) per equilibrium batch; bounds memory to a few tens of MB.
MAP_BATCH = 1 << 16

#: Fewest mode x mu-point rows worth a chunk of their own in :func:`feasibility_map`:
#: ~0.1 s at the ~1.5e6 rows/s of one core, several times a local pool's start-up.
MIN_CHUNK_ROWS = 150_000

#: The same for the polynomial path of :func:`mu_slice`, split by modes.  It runs at
#: ~2e7 rows/s and is bound by memory bandwidth: two local workers ran 1.3x as fast
#: at 2000^2 points x 5 modes (benchmarks/bench_parallel.py), so a chunk must hold
#: ~0.5 s of work.
MIN_CHUNK_POLYNOMIAL_ROWS = 10_000_000


@dataclass(frozen=True, slots=True, eq=False)
class MuMap:
    """Which modes are feasible at each of N friction points.

    Attributes
    ----------
    modes : tuple of ContactMode
        Every mode tested, in enumeration order (eq. 49).
    kinematic_status : tuple of str
        Status of each mode from the mu-independent kinematic stage
        (``feasible`` means it passed kinematics).
    mu : ndarray, shape (N, n_c)
    feasible : ndarray of bool, shape (N, n_modes)
    degenerate : ndarray of bool, shape (N, n_modes)
        ``Q_AI`` singular at that point (eqs. 26, 31): reported, never feasible.
    boundary : ndarray of bool, shape (N, n_modes)
        Feasible only within the force tolerance (on a region's boundary).
    """

    modes: tuple
    kinematic_status: tuple
    mu: np.ndarray
    feasible: np.ndarray
    degenerate: np.ndarray
    boundary: np.ndarray

    def labels(self, i: int) -> list[str]:
        """Sorted letters of the modes feasible at point ``i``."""
        return sorted(self.modes[j].letters for j in np.flatnonzero(self.feasible[i]))

    @property
    def jammed(self) -> np.ndarray:
        """Points where no mode is feasible, shape (N,)."""
        return ~self.feasible.any(axis=1)

    @property
    def ambiguous(self) -> np.ndarray:
        """Points where several modes are feasible, shape (N,)."""
        return self.feasible.sum(axis=1) > 1


def _kinematics_all(scene: Scene, tol: Tolerances):
    """The mu-independent kinematic stage of every mode (eqs. 24-25, 16), once.

    Returns ``pool``, the modes, their kinematic statuses and, per batch,
    ``(columns of the live modes, their Kinematics)``.
    """
    pool = ScenePool(scene)
    vtol = tol.velocity * velocity_scale(scene)
    modes, kstatus, kins = [], [], []
    for codes in iter_mode_batches(scene.n_contacts, scene.dof):
        status, live, kin = kinematics_stage(scene, pool, codes, tol, vtol)
        modes.extend(ContactMode(codes_to_letters(c)) for c in codes)
        kstatus.extend(Status.ORDER[s] for s in status)
        kins.append((len(modes) - len(codes) + live, kin))
    return pool, modes, kstatus, kins


def _check_mu_points(scene: Scene, mu_points) -> np.ndarray:
    mu_points = np.asarray(mu_points, dtype=float)
    n_c = scene.n_contacts
    if mu_points.ndim != 2 or mu_points.shape[1] != n_c:
        raise SceneError(f"mu_points: expected shape (N, {n_c}); got {mu_points.shape}")
    if not np.all(np.isfinite(mu_points)) or np.any(mu_points < 0):
        raise SceneError("mu_points: expected finite nonnegative friction coefficients")
    return mu_points


def feasibility_map(scene: Scene, mu_points, tol: Tolerances = DEFAULT_TOLERANCES, batch: int = MAP_BATCH, *,
                    workers=None, scheduler=None) -> MuMap:  # fmt: skip
    """Feasible modes of ``scene`` at every row of ``mu_points``.

    Parameters
    ----------
    scene : Scene
        Its own ``mu`` is ignored.
    mu_points : array-like, shape (N, n_c)
        Nonnegative friction coefficients.
    tol : Tolerances
    batch : int
        Rows per equilibrium batch.
    workers : int or None
        Local processes (``None``: all cores, 1: in-process); the points are split into
        chunks of rows, each of at least :data:`MIN_CHUNK_ROWS` mode-point rows, so a
        small map stays in-process.  See :func:`mechanics.parallel.map_chunks`.
    scheduler : str or dask.distributed.Client, optional
        Send the chunks to a Dask cluster instead.

    Returns
    -------
    MuMap
        The same (bit for bit) however it was split: every row is computed alone.
    """
    mu_points = _check_mu_points(scene, mu_points)
    N = mu_points.shape[0]
    n_chunks = chunk_count(N * count_modes(scene.n_contacts, scene.dof), MIN_CHUNK_ROWS, workers=workers,
                           scheduler=scheduler)  # fmt: skip
    if N and (n_chunks > 1 or scheduler is not None):
        jobs = [(scene, mu_points[lo:hi], tol, batch) for lo, hi in split_range(N, n_chunks)]
        parts = map_chunks(_feasibility_chunk, jobs, workers=workers, scheduler=scheduler)
        stack = lambda f: np.concatenate([getattr(p, f) for p in parts])  # noqa: E731
        first = parts[0]
        return MuMap(first.modes, first.kinematic_status, mu_points, stack("feasible"), stack("degenerate"),
                     stack("boundary"))  # fmt: skip
    pool, modes, kstatus, kins = _kinematics_all(scene, tol)
    feasible = np.zeros((N, len(modes)), dtype=bool)
    degenerate = np.zeros_like(feasible)
    boundary = np.zeros_like(feasible)
    tau_e = np.nan_to_num(scene.joint_effort)[pool.E]
    for mode_cols, kin in kins:
        if mode_cols.size == 0:
            continue
        step = max(1, batch // mode_cols.size)
        for lo in range(0, N, step):
            pts = np.arange(lo, min(lo + step, N))
            rows_mode = np.tile(np.arange(mode_cols.size), pts.size)
            rows_pt = np.repeat(pts, mode_cols.size)
            st, _, _, _, bnd = equilibrium_stage(
                scene, pool, kin.take(rows_mode), mu_points[rows_pt],
                np.broadcast_to(tau_e, (rows_pt.size, tau_e.size)), tol,
            )  # fmt: skip
            cols = mode_cols[rows_mode]
            feasible[rows_pt, cols] = st == 0
            degenerate[rows_pt, cols] = st == Status.ORDER.index(Status.EQUILIBRIUM_SINGULAR)
            boundary[rows_pt, cols] = (st == 0) & bnd
    return MuMap(tuple(modes), tuple(kstatus), mu_points, feasible, degenerate, boundary)


def _feasibility_chunk(job) -> MuMap:
    """One chunk of rows of :func:`feasibility_map`, in the process that runs it."""
    scene, mu_points, tol, batch = job
    return feasibility_map(scene, mu_points, tol, batch, workers=1)


def grid_points(base_mu, x: int, y: int, xs, ys) -> np.ndarray:
    """Mu points of a 2-D slice: coefficient ``x`` takes ``xs``, ``y`` takes ``ys``, others ``base_mu``.

    Parameters
    ----------
    base_mu : array-like, shape (n_c,)
    x, y : int
        0-based contact indices of the two axes.
    xs, ys : array-like, shape (nx,), (ny,)

    Returns
    -------
    ndarray, shape (ny * nx, n_c)
        Row ``j * nx + i`` is the point (xs[i], ys[j]).
    """
    base = np.asarray(base_mu, dtype=float)
    xs, ys = np.asarray(xs, float), np.asarray(ys, float)
    pts = np.tile(base, (ys.size * xs.size, 1))
    X, Y = np.meshgrid(xs, ys)
    pts[:, x] = X.ravel()
    pts[:, y] = Y.ravel()
    return pts


# --- The polynomial fast path and exact slices (Sections 4.1-4.6) -----------------------------


def _polynomial_status(eqp, mu_points: np.ndarray, tau_e: np.ndarray, tol: Tolerances, batch: int):
    """Feasible / degenerate / boundary of one mode at every point, from its multilinear form.

    The decisions are the solver's (:func:`~mechanics.solver.equilibrium_stage`): the
    same Hadamard-ratio singularity test of ``Q_AI``, the same Coulomb slacks (28) and
    the same force tolerance; only ``c_A`` comes from ``N(mu) / det Q_AI(mu)`` evaluated
    as polynomials instead of an LU solve.
    """
    rhs = eqp.rhs(tau_e)
    k = rhs.size
    coef = np.column_stack([eqp.det_coef, eqp.adj_coef @ rhs])  # (2**n_S, 1 + k): det and numerators
    varying = [v for v in eqp.sliding if np.ptp(mu_points[:, v]) > 0]
    kept, coef = restrict_coef(coef, eqp.sliding, mu_points[0], varying)  # fold in the fixed mu
    slide_cols = np.flatnonzero(np.any(eqp.V != 0, axis=0))
    fixed_cols = np.setdiff1d(np.arange(k), slide_cols)
    row_const = np.sum(eqp.U[:, fixed_cols] ** 2, axis=1)  # squared row norms of Q_AI from mu-free columns
    rolling = [(i, eqp.column(i, True), eqp.column(i, False)) for i, c in enumerate(eqp.mode.letters) if c == "R"]
    sliding = [eqp.column(i, True) for i, c in enumerate(eqp.mode.letters) if c == "S"]
    rhs_scale = float(np.max(np.abs(rhs)))
    N = mu_points.shape[0]
    feasible = np.zeros(N, dtype=bool)
    degenerate = np.zeros(N, dtype=bool)
    boundary = np.zeros(N, dtype=bool)
    step = max(256, (batch * 64) // (coef.shape[0] + k + 1))  # bounds the monomial block to ~batch * 64 floats
    for lo in range(0, N, step):
        mu = mu_points[lo : lo + step]
        vals = (monomials(mu, kept) @ coef).T  # (1 + k, n): column-wise work below is cheapest
        det = vals[0]
        norms = np.ones(mu.shape[0])
        for r in range(k):  # Hadamard ratio of Q_AI, as the solver computes it
            sq = np.full(mu.shape[0], row_const[r])
            for j in slide_cols:
                sq += (eqp.U[r, j] + mu[:, eqp.col_contact[j]] * eqp.V[r, j]) ** 2
            norms *= np.sqrt(sq)
        with np.errstate(divide="ignore", invalid="ignore"):
            h = np.where(norms > 0, np.abs(det) / norms, 0.0)
            cA = vals[1:] / det
        q_sing = ~(h >= tol.singular)
        worst = np.full(mu.shape[0], np.inf)
        for i, a, t in rolling:  # Coulomb slacks (28), as the solver computes them
            mc = mu[:, i] * cA[a]
            worst = np.minimum(worst, np.minimum(np.minimum(mc + cA[t], mc - cA[t]), cA[a]))  # and c_n >= 0 (eq. 9)
        for a in sliding:
            worst = np.minimum(worst, cA[a])
        scale = np.full(mu.shape[0], rhs_scale)
        for row in cA:
            scale = np.maximum(scale, np.abs(row))
        ftol = tol.force * scale
        ok = ~q_sing & ~(worst < -ftol)
        feasible[lo : lo + step] = ok
        degenerate[lo : lo + step] = q_sing
        boundary[lo : lo + step] = ok & (worst <= ftol)
    return feasible, degenerate, boundary


def _polynomial_columns(scene: Scene, mu_points: np.ndarray, tol: Tolerances, batch: int, kinematics, columns):
    """``{column: (feasible, degenerate, boundary, region)}`` of the live modes in ``columns``."""
    pool, _, _, kins = kinematics
    tau_e = np.nan_to_num(scene.joint_effort)[pool.E]
    out = {}
    for mode_cols, kin in kins:
        for r, col in enumerate(mode_cols):
            if int(col) in columns:
                eqp = _polynomials_from_kinematics(scene, pool, kin, r)
                out[int(col)] = _polynomial_status(eqp, mu_points, tau_e, tol, batch) + (region_from_polynomials(eqp, tau_e),)
    return out


def _polynomial_chunk(job):
    """Some modes' columns of a slice's polynomial map, in the process that runs it."""
    scene, grid, tol, batch, columns = job
    return _polynomial_columns(scene, grid_points(*grid), tol, batch, _kinematics_all(scene, tol), columns)


def _polynomial_pass(scene: Scene, mu_points: np.ndarray, tol: Tolerances, batch: int, grid=None, workers=1,
                     scheduler=None):  # fmt: skip
    """The polynomial map and every mode's region; with ``grid`` (the arguments of
    :func:`grid_points`) the modes may be split into chunks, each evaluated whole."""
    kinematics = _kinematics_all(scene, tol)
    _, modes, kstatus, kins = kinematics
    live = [int(c) for mode_cols, _ in kins for c in mode_cols]
    N = mu_points.shape[0]
    n_chunks = chunk_count(N * len(live), MIN_CHUNK_POLYNOMIAL_ROWS, workers=workers, scheduler=scheduler)
    if grid is not None and live and (n_chunks > 1 or scheduler is not None):
        jobs = [(scene, grid, tol, batch, set(live[lo:hi])) for lo, hi in split_range(len(live), n_chunks)]
        columns = {}
        for part in map_chunks(_polynomial_chunk, jobs, workers=workers, scheduler=scheduler):
            columns.update(part)
    else:
        columns = _polynomial_columns(scene, mu_points, tol, batch, kinematics, set(live))
    feasible = np.zeros((N, len(modes)), dtype=bool)
    degenerate = np.zeros_like(feasible)
    boundary = np.zeros_like(feasible)
    regions = [None] * len(modes)
    for col, (f, d, b, region) in columns.items():
        feasible[:, col], degenerate[:, col], boundary[:, col], regions[col] = f, d, b, region
    for j, m in enumerate(modes):
        if regions[j] is None:
            regions[j] = empty_region(m, kstatus[j], scene.n_contacts)
    mumap = MuMap(tuple(modes), tuple(kstatus), mu_points, feasible, degenerate, boundary)
    return mumap, tuple(regions)


def polynomial_map(scene: Scene, mu_points, tol: Tolerances = DEFAULT_TOLERANCES, batch: int = MAP_BATCH) -> MuMap:
    """:func:`feasibility_map` through each mode's multilinear form: same answer, much faster.

    For a kinematically admissible mode ``c_A = adj(Q_AI) rhs / det Q_AI`` with
    ``det`` and ``adj`` multilinear in the sliding contacts' mu (Sections 4.4-4.6,
    :mod:`mechanics.multilinear`); coefficients that do not vary over the points are
    folded in first, so a 2-D slice costs a few multiply-adds per point and mode.
    The singularity test and the Coulomb tolerances are the solver's, so the map
    equals :func:`feasibility_map` (and :func:`mechanics.solve`) except, through
    rounding, at points within about ``1e-12`` relative of a tolerance threshold.

    Parameters
    ----------
    scene : Scene
        Its own ``mu`` is ignored.
    mu_points : array-like, shape (N, n_c)
    tol : Tolerances
    batch : int
        Bounds the memory of one evaluation batch.

    Returns
    -------
    MuMap
    """
    return _polynomial_pass(scene, _check_mu_points(scene, mu_points), tol, batch)[0]


@dataclass(frozen=True, slots=True, eq=False)
class MuSlice:
    """A 2-D slice of mu-space (the paper's Figs. 3, 6, 8): cell labels and exact regions.

    Attributes
    ----------
    x, y : int
        0-based contacts on the axes (``mu_{x+1}`` horizontal).
    xs, ys : ndarray, shape (nx,), (ny,)
    base_mu : ndarray, shape (n_c,)
        Values of the other coefficients (entries ``x`` and ``y`` unused).
    mumap : MuMap
        On :func:`grid_points` ``(base_mu, x, y, xs, ys)``: row ``j * nx + i`` is ``(xs[i], ys[j])``.
    regions : tuple of MuRegion
        One per mode of ``mumap.modes``, from the general formulas.
    """

    x: int
    y: int
    xs: np.ndarray
    ys: np.ndarray
    base_mu: np.ndarray
    mumap: MuMap
    regions: tuple

    @property
    def modes(self) -> tuple:
        return self.mumap.modes

    @property
    def feasible(self) -> np.ndarray:
        """Feasibility per cell and mode, shape (ny, nx, n_modes)."""
        return self.mumap.feasible.reshape(self.ys.size, self.xs.size, -1)

    def cells(self) -> list:
        """``cells[j][i]``: sorted letters of the modes feasible at ``(xs[i], ys[j])``."""
        f = self.mumap.feasible
        keys = np.packbits(f, axis=1, bitorder="little") if f.shape[1] else np.zeros((f.shape[0], 1), np.uint8)
        uniq, inverse = np.unique(keys, axis=0, return_inverse=True)
        sets = [sorted(self.modes[j].letters for j in np.flatnonzero(np.unpackbits(u, bitorder="little")[: f.shape[1]]))
                for u in uniq]  # fmt: skip
        inv = inverse.reshape(self.ys.size, self.xs.size).tolist()
        return [[list(sets[u]) for u in row] for row in inv]

    def boundary_curves(self, n: int = 400) -> list:
        """Exact boundaries of every mode's region in the window, list of BoundaryCurve."""
        xlim, ylim = (self.xs[0], self.xs[-1]), (self.ys[0], self.ys[-1])
        out = []
        for reg in self.regions:
            out += reg.boundary_curves(self.x, self.y, self.base_mu, xlim, ylim, n)
        return out


def _check_axis(value, n_c: int, field: str) -> int:
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)) or not 0 <= value < n_c:
        raise SceneError(f"{field}: expected a contact index in 0..{n_c - 1}; got {value!r}")
    return int(value)


def _check_axis_values(v, field: str) -> np.ndarray:
    v = np.asarray(v, dtype=float)
    if v.ndim != 1 or v.size < 2:
        raise SceneError(f"{field}: expected at least 2 increasing values; got shape {v.shape}")
    if not np.all(np.isfinite(v)) or np.any(v < 0) or np.any(np.diff(v) < 0):
        raise SceneError(f"{field}: expected finite nonnegative nondecreasing friction coefficients")
    return v


def mu_slice(scene: Scene, x: int, y: int, xs, ys, base_mu=None, method: str = "polynomial",
             tol: Tolerances = DEFAULT_TOLERANCES, *, workers=None, scheduler=None) -> MuSlice:  # fmt: skip
    """Feasible modes on a grid of a 2-D slice of mu-space, with the modes' exact regions.

    Parameters
    ----------
    scene : Scene
    x, y : int
        0-based contacts on the horizontal and vertical axes (distinct).
    xs, ys : array-like, shape (nx,), (ny,)
        Nondecreasing nonnegative values, at least 2 each.
    base_mu : array-like, shape (n_c,), optional
        The other coefficients (default the scene's ``mu``).
    method : {"polynomial", "solver"}
        ``"polynomial"``: :func:`polynomial_map`; ``"solver"``: :func:`feasibility_map`.
        Both give the solver's answer.
    workers : int or None
        Local processes (``None``: all cores, 1: in-process).  ``"polynomial"`` splits
        the modes into chunks (each of at least :data:`MIN_CHUNK_POLYNOMIAL_ROWS`
        mode-point rows), ``"solver"`` the points; a small slice stays in-process.
    scheduler : str or dask.distributed.Client, optional
        Send the chunks to a Dask cluster instead (:func:`mechanics.parallel.map_chunks`).

    Returns
    -------
    MuSlice
        The same (bit for bit) however it was split.
    """
    n_c = scene.n_contacts
    x, y = _check_axis(x, n_c, "x"), _check_axis(y, n_c, "y")
    if x == y:
        raise SceneError(f"y: expected a contact other than x = {x}; got {y}")
    xs, ys = _check_axis_values(xs, "xs"), _check_axis_values(ys, "ys")
    base = scene.mu if base_mu is None else np.asarray(base_mu, dtype=float)
    if base.shape != (n_c,) or not np.all(np.isfinite(base)) or np.any(base < 0):
        got = np.asarray(base_mu).tolist()
        raise SceneError(f"base_mu: expected {n_c} finite nonnegative friction coefficients; got {got}")
    pts = grid_points(base, x, y, xs, ys)
    if method == "polynomial":
        mumap, regions = _polynomial_pass(scene, pts, tol, MAP_BATCH, (base, x, y, xs, ys), workers, scheduler)
    elif method == "solver":
        mumap = feasibility_map(scene, pts, tol, workers=workers, scheduler=scheduler)
        _, regions = _polynomial_pass(scene, pts[:1], tol, MAP_BATCH)
    else:
        raise SceneError(f"method: expected 'polynomial' or 'solver'; got {method!r}")
    base = base.copy()
    base.setflags(write=False)
    return MuSlice(x, y, xs, ys, base, mumap, regions)


@dataclass(frozen=True, slots=True)
class BoundaryAgreement:
    """How well a slice's exact boundary curves separate its cell labels.

    Counted over pairs of adjacent cells and modes: a pair *changes* when the mode is
    feasible at one cell and not at the other; it is *crossed* when the mode's exact
    boundary (the active pieces of the zero sets of its boundary polynomials) meets the
    segment between the two cell centres an odd number of times.  Pairs with a cell
    centre on a boundary (within ``1e-9`` relative, or feasible only within the force
    tolerance) are left out and counted in ``excluded``.

    Attributes
    ----------
    excluded : int
    label_changes : int
    explained : int
        Changes that are crossed.
    unexplained : int
        Changes that are not crossed.
    spurious : int
        Crossings without a change.
    """

    excluded: int
    label_changes: int
    explained: int
    unexplained: int
    spurious: int

    @property
    def agrees(self) -> bool:
        return self.unexplained == 0 and self.spurious == 0


def _crossings(bil, ip, fixed, grid, horizontal: bool) -> np.ndarray:
    """Active roots of polynomial ``ip`` on the grid segments of each row (or column).

    Returns counts, shape (len(fixed), len(grid) - 1).
    """
    a, b, c, d = bil[ip]
    if horizontal:  # y = fixed: p = (a + c y) + (b + d y) x
        alpha, beta = a + c * fixed, b + d * fixed
    else:  # x = fixed: p = (a + b x) + (c + d x) y
        alpha, beta = a + b * fixed, c + d * fixed
    counts = np.zeros((fixed.size, grid.size - 1), dtype=np.int32)
    with np.errstate(divide="ignore", invalid="ignore"):
        root = -alpha / beta
    ok = np.isfinite(root) & (root >= grid[0]) & (root <= grid[-1])
    rows = np.flatnonzero(ok)
    if rows.size == 0:
        return counts
    pts = np.column_stack([root[rows], fixed[rows]] if horizontal else [fixed[rows], root[rows]])
    act = _active(bil, ip, pts)
    rows = rows[act]
    seg = np.clip(np.searchsorted(grid, root[rows], side="right") - 1, 0, grid.size - 2)
    np.add.at(counts, (rows, seg), 1)
    return counts


def boundary_agreement(sl: MuSlice) -> BoundaryAgreement:
    """Check a slice's cell labels against its exact region boundaries (see :class:`BoundaryAgreement`)."""
    f = sl.feasible
    shape = f.shape[:2]
    changes = explained = spurious = excluded = 0
    for j, reg in enumerate(sl.regions):
        fj = f[:, :, j]
        near = sl.mumap.boundary[:, j].reshape(shape) | reg.near_boundary(sl.mumap.mu).reshape(shape)
        keep_h = ~(near[:, 1:] | near[:, :-1])
        keep_v = ~(near[1:, :] | near[:-1, :])
        excluded += int((~keep_h).sum() + (~keep_v).sum())
        ch_h = (fj[:, 1:] != fj[:, :-1]) & keep_h  # (ny, nx-1)
        ch_v = (fj[1:, :] != fj[:-1, :]) & keep_v  # (ny-1, nx)
        cr_h = np.zeros(ch_h.shape, dtype=np.int32)
        cr_v = np.zeros(ch_v.T.shape, dtype=np.int32)
        if reg.kinematic_status == Status.FEASIBLE:
            bil = np.array([p.bilinear(sl.x, sl.y, sl.base_mu) for p in reg.boundary_polynomials()])
            for ip in range(bil.shape[0]):
                if np.any(bil[ip, 1:]):
                    cr_h += _crossings(bil, ip, sl.ys, sl.xs, True)
                    cr_v += _crossings(bil, ip, sl.xs, sl.ys, False)
        odd_h, odd_v = (cr_h % 2 == 1) & keep_h, (cr_v % 2 == 1).T & keep_v
        changes += int(ch_h.sum() + ch_v.sum())
        explained += int((ch_h & odd_h).sum() + (ch_v & odd_v).sum())
        spurious += int((~ch_h & odd_h).sum() + (~ch_v & odd_v).sum())
    return BoundaryAgreement(excluded, changes, explained, changes - explained, spurious)
