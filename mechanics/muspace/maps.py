"""Feasible contact modes over many friction coefficients at once (Section 4).

The kinematic stage of every mode (eqs. 24-25, 16) does not depend on mu, so
it runs once; only the equilibrium and Coulomb stage (26)-(28) is repeated, for
all kinematically admissible modes and all mu points together, in bounded
batches.  The answer at every point is exactly what :func:`qsplan.mechanics.solve`
gives for the scene with that mu.

Two paths give that answer: :func:`feasibility_map` is the solver's
:func:`~qsplan.mechanics.solver.many.solve_many` (an LU solve per mode and point),
:func:`polynomial_map` evaluates each mode's multilinear form of ``c_A`` (Sections
4.4-4.6) and is much faster.  2-D slices with the modes' exact regions are in
:mod:`qsplan.mechanics.muspace.slices`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qsplan.mechanics.modes.contact_mode import ContactMode, codes_to_letters, count_modes, iter_mode_batches
from qsplan.mechanics.numerics import DEFAULT_TOLERANCES, Status, StatusCode, Tolerances
from qsplan.mechanics.model.scene import Scene
from qsplan.mechanics.muspace.multilinear import monomials, restrict_coef
from qsplan.mechanics.parallel import chunk_count, map_chunks, split_range
from qsplan.mechanics.muspace.regions import empty_region, polynomials_from_kinematics, region_from_polynomials
from qsplan.mechanics.modes.equilibrium import coulomb_slacks
from qsplan.mechanics.modes.kinematics import ScenePool, kinematics_stage, velocity_scale
from qsplan.mechanics.solver.many import check_mu_vectors, solve_many

__all__ = [
    "MuMap",
    "feasibility_map",
    "grid_points",
    "polynomial_map",
    "polynomial_pass",
    "MAP_BATCH",
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
        small map stays in-process.  See :func:`qsplan.mechanics.parallel.map_chunks`.
    scheduler : str or dask.distributed.Client, optional
        Send the chunks to a Dask cluster instead.

    Returns
    -------
    MuMap
        The same (bit for bit) however it was split: every row is computed alone.
    """
    mu_points = check_mu_vectors(scene, mu_points, "mu_points")
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
    sv = solve_many(scene, mu_points, tol, forces=False, batch=batch)
    return MuMap(tuple(ContactMode(m) for m in sv.letters), tuple(Status.ORDER[c] for c in sv.kinematic), mu_points,
                 sv.codes == StatusCode.FEASIBLE, sv.codes == StatusCode.EQUILIBRIUM_SINGULAR, sv.boundary)  # fmt: skip


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

    The decisions are the solver's (:func:`~qsplan.mechanics.modes.equilibrium.equilibrium_stage`): the
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
            plus, minus = coulomb_slacks(mu[:, i], cA[a], cA[t])
            worst = np.minimum(worst, np.minimum(np.minimum(plus, minus), cA[a]))  # and c_n >= 0 (eq. 9)
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
                eqp = polynomials_from_kinematics(scene, pool, kin, r)
                out[int(col)] = _polynomial_status(eqp, mu_points, tau_e, tol, batch) + (region_from_polynomials(eqp, tau_e),)
    return out


def _polynomial_chunk(job):
    """Some modes' columns of a slice's polynomial map, in the process that runs it."""
    scene, grid, tol, batch, columns = job
    return _polynomial_columns(scene, grid_points(*grid), tol, batch, _kinematics_all(scene, tol), columns)


def polynomial_pass(scene: Scene, mu_points: np.ndarray, tol: Tolerances, batch: int, grid=None, workers=1,
                     scheduler=None):  # fmt: skip
    """The polynomial map and every mode's region; with ``grid`` (the arguments of
    :func:`grid_points`) the modes may be split into chunks, each evaluated whole.

    Returns
    -------
    mumap : MuMap
    regions : tuple of MuRegion
        One per mode of ``mumap.modes`` (empty where the kinematic stage fails).
    """
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
    :mod:`qsplan.mechanics.muspace.multilinear`); coefficients that do not vary over the points are
    folded in first, so a 2-D slice costs a few multiply-adds per point and mode.
    The singularity test and the Coulomb tolerances are the solver's, so the map
    equals :func:`feasibility_map` (and :func:`qsplan.mechanics.solve`) except, through
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
    return polynomial_pass(scene, check_mu_vectors(scene, mu_points, "mu_points"), tol, batch)[0]
