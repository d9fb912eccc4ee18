"""2-D slices of mu-space (the paper's Figs. 3, 6, 8): cell labels with the modes' exact regions.

:func:`mu_slice` maps a grid of a slice through two contacts' friction coefficients,
the others fixed, together with every mode's exact region (Section 4), whose
boundary curves are zero sets of bilinear polynomials; :func:`boundary_agreement`
checks the two against each other.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qsplan.mechanics.errors import SceneError
from qsplan.mechanics.model.friction import check_friction
from qsplan.mechanics.model.scene import Scene
from qsplan.mechanics.muspace.maps import MAP_BATCH, MuMap, feasibility_map, grid_points, polynomial_pass
from qsplan.mechanics.muspace.regions import bounds_region
from qsplan.mechanics.numerics import DEFAULT_TOLERANCES, Status, Tolerances

__all__ = ["MuSlice", "mu_slice", "BoundaryAgreement", "boundary_agreement"]


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
    try:
        check_friction(v, field)
        ok = not np.any(np.diff(v) < 0)
    except SceneError:
        ok = False  # reported with the axis's whole rule
    if not ok:
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
        Send the chunks to a Dask cluster instead (:func:`qsplan.mechanics.parallel.map_chunks`).

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
    base = scene.mu if base_mu is None else check_friction(base_mu, "base_mu")
    if base.shape != (n_c,):
        raise SceneError(f"base_mu: expected {n_c} finite nonnegative friction coefficients; got {np.asarray(base_mu).tolist()}")
    pts = grid_points(base, x, y, xs, ys)
    if method == "polynomial":
        mumap, regions = polynomial_pass(scene, pts, tol, MAP_BATCH, (base, x, y, xs, ys), workers, scheduler)
    elif method == "solver":
        mumap = feasibility_map(scene, pts, tol, workers=workers, scheduler=scheduler)
        _, regions = polynomial_pass(scene, pts[:1], tol, MAP_BATCH)
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
    act = bounds_region(bil, ip, pts)
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
