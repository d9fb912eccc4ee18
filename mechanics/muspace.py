"""Feasible contact modes over many friction coefficients at once (Section 4).

The kinematic stage of every mode (eqs. 24-25, 16) does not depend on mu, so
it runs once; only the equilibrium and Coulomb stage (26)-(28) is repeated, for
all kinematically admissible modes and all mu points together, in bounded
batches.  The answer at every point is exactly what :func:`mechanics.solve`
gives for the scene with that mu.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .errors import SceneError
from .feasibility import velocity_scale
from .modes import ContactMode, codes_to_letters, iter_mode_batches
from .numerics import DEFAULT_TOLERANCES, Status, Tolerances
from .scene import Scene
from .solver import ScenePool, equilibrium_stage, kinematics_stage

__all__ = ["MuMap", "feasibility_map", "grid_points"]

#: Rows (mode x mu point) per equilibrium batch; bounds memory to a few tens of MB.
MAP_BATCH = 1 << 16


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


def feasibility_map(scene: Scene, mu_points, tol: Tolerances = DEFAULT_TOLERANCES, batch: int = MAP_BATCH) -> MuMap:
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

    Returns
    -------
    MuMap
    """
    mu_points = np.asarray(mu_points, dtype=float)
    n_c = scene.n_contacts
    if mu_points.ndim != 2 or mu_points.shape[1] != n_c:
        raise SceneError(f"mu_points: expected shape (N, {n_c}); got {mu_points.shape}")
    if not np.all(np.isfinite(mu_points)) or np.any(mu_points < 0):
        raise SceneError("mu_points: expected finite nonnegative friction coefficients")
    pool = ScenePool(scene)
    vtol = tol.velocity * velocity_scale(scene)
    modes, kstatus, kins = [], [], []
    for codes in iter_mode_batches(n_c, scene.dof):
        status, live, kin = kinematics_stage(scene, pool, codes, tol, vtol)
        modes.extend(ContactMode(codes_to_letters(c)) for c in codes)
        kstatus.extend(Status.ORDER[s] for s in status)
        kins.append((len(modes) - len(codes) + live, kin))
    N = mu_points.shape[0]
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
