"""Every mode's status at many friction vectors of one scene (Sections 3.2, 4): the kinematic stage once.

A mode's kinematic stage (eqs. 23-25, 16) does not depend on mu, so :func:`solve_many` runs it once, in
the solver's batches of modes, and repeats only the equilibrium and Coulomb stage (eqs. 26-28), for every
admissible mode at every friction vector, in bounded batches of rows.  It calls the very stages
:func:`qsplan.mechanics.solve` calls and every matrix is factorised alone, so each status, force and
velocity is the one the solver computes for the scene with that mu, bit for bit, however the rows are
batched.  :func:`solve_many_reference` is that solver once per vector; the tests compare the two.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from qsplan.mechanics.errors import SceneError
from qsplan.mechanics.model.friction import check_friction
from qsplan.mechanics.model.scene import Scene
from qsplan.mechanics.modes.contact_mode import codes_to_letters, enumerate_modes, iter_mode_batches
from qsplan.mechanics.modes.equilibrium import equilibrium_stage
from qsplan.mechanics.modes.kinematics import ScenePool, kinematics_stage, velocity_scale
from qsplan.mechanics.numerics import DEFAULT_TOLERANCES, Status, StatusCode, Tolerances
from qsplan.mechanics.solver.all_modes import solve
from qsplan.mechanics.solver.batch import DEFAULT_BATCH

__all__ = ["ROW_BATCH", "VectorStatuses", "check_mu_vectors", "solve_many", "solve_many_reference"]

#: Rows (admissible mode x friction vector) per equilibrium batch of :func:`solve_many`: bounds the
#: memory of one batch to a few tens of MB (the rows are independent, so the answers do not depend on it).
ROW_BATCH = 1 << 16

#: The statuses the kinematic stage decides (eqs. 15-16, 23-25); the others are the equilibrium stage's.
_KINEMATIC_CODES = (StatusCode.KINEMATICS_SINGULAR, StatusCode.BREAKING_VIOLATED, StatusCode.BREAKING_ZERO_SPEED,
                    StatusCode.ZERO_SLIDING_SPEED)  # fmt: skip


@dataclass(frozen=True, slots=True, eq=False)
class VectorStatuses:
    """Every mode's status at each of ``m`` friction vectors, and the feasible modes' forces and motion.

    Attributes
    ----------
    letters : tuple of str
        The modes, in enumeration order (eq. 49).
    kinematic : ndarray of int8, shape (n_modes,)
        Status codes (into ``Status.ORDER``) of the mu-independent kinematic stage; 0: passed it.
    codes : ndarray of int8, shape (m, n_modes)
        Status codes into ``Status.ORDER`` (0: feasible).
    boundary : ndarray of bool, shape (m, n_modes)
        Feasible only within the force tolerance (on a region's boundary).
    c_n : ndarray, shape (m, n_modes, n_c), or None
        Normal forces (N) of the feasible modes; 0 elsewhere.  None when not asked for.
    qdot : ndarray, shape (m, n_modes, 3), or None
        Workpiece velocity (m/s, m/s, rad/s, of the world origin) of the feasible modes; 0 elsewhere.
        None when not asked for.
    """

    letters: tuple
    kinematic: np.ndarray
    codes: np.ndarray
    boundary: np.ndarray
    c_n: np.ndarray | None
    qdot: np.ndarray | None


def check_mu_vectors(scene: Scene, mu_vectors, field: str = "mu_vectors") -> np.ndarray:
    """``mu_vectors`` as a float array of shape ``(m, n_c)``, nonnegative and finite (eq. 8).

    Raises
    ------
    SceneError
        Naming ``field``: a negative or non-finite coefficient, or the wrong shape.
    """
    mu = check_friction(mu_vectors, field)
    n_c = scene.n_contacts
    if mu.ndim != 2 or mu.shape[1] != n_c:
        raise SceneError(f"{field}: expected shape (N, {n_c}); got {mu.shape}")
    return mu


@lru_cache(maxsize=8)
def _mode_batches(n_contacts: int, dof: int) -> tuple:
    """The solver's batches of mode codes (read-only) and every mode's letters, in enumeration order."""
    batches = tuple(iter_mode_batches(n_contacts, dof, DEFAULT_BATCH))
    for codes in batches:
        codes.setflags(write=False)
    return batches, tuple(codes_to_letters(c) for codes in batches for c in codes)


def solve_many(scene: Scene, mu_vectors, tol: Tolerances = DEFAULT_TOLERANCES, *, forces: bool = True,
               batch: int = ROW_BATCH) -> VectorStatuses:  # fmt: skip
    """Every mode's status at every friction vector: the kinematic stage once, the equilibrium stage batched.

    Parameters
    ----------
    scene : Scene
        Its own ``mu`` is ignored.
    mu_vectors : array-like, shape (m, n_c)
        Nonnegative friction coefficients, one vector per row.
    tol : Tolerances
    forces : bool
        Keep the feasible modes' normal forces and velocities (False: ``c_n`` and ``qdot`` are None, for
        maps of many points).
    batch : int
        Rows (admissible mode x vector) per equilibrium batch.

    Returns
    -------
    VectorStatuses
        Equal, bit for bit, to :func:`solve_many_reference`.

    Raises
    ------
    SceneError
        ``mu_vectors`` negative, not finite or not of shape ``(m, n_c)``.
    """
    mu = check_mu_vectors(scene, mu_vectors)
    n, n_c = mu.shape
    pool = ScenePool(scene)
    vtol = tol.velocity * velocity_scale(scene)
    tau_e = np.nan_to_num(scene.joint_effort)[pool.E]
    batches, letters = _mode_batches(n_c, scene.dof)
    kinematic = np.zeros(len(letters), dtype=np.int8)
    codes = np.zeros((n, len(letters)), dtype=np.int8)
    boundary = np.zeros((n, len(letters)), dtype=bool)
    c_n = np.zeros((n, len(letters), n_c)) if forces else None
    qdot = np.zeros((n, len(letters), 3)) if forces else None
    lo = 0
    for modes in batches:
        status, live, kin = kinematics_stage(scene, pool, modes, tol, vtol)
        kinematic[lo : lo + status.size] = status
        codes[:, lo : lo + status.size] = status
        step = max(1, batch // max(live.size, 1))
        for first in range(0, n if live.size else 0, step):
            pts = np.arange(first, min(first + step, n))
            rows_mode = np.tile(np.arange(live.size), pts.size)
            rows_pt = np.repeat(pts, live.size)
            est, cn, _, _, bnd = equilibrium_stage(scene, pool, kin.take(rows_mode), mu[rows_pt],
                                                   np.broadcast_to(tau_e, (rows_pt.size, tau_e.size)), tol)  # fmt: skip
            cols = lo + live[rows_mode]
            codes[rows_pt, cols] = est
            ok = est == StatusCode.FEASIBLE
            boundary[rows_pt, cols] = ok & bnd
            if forces:
                c_n[rows_pt[ok], cols[ok]] = cn[ok]
                qdot[rows_pt[ok], cols[ok]] = kin.qdot[rows_mode[ok]]
        lo += status.size
    return VectorStatuses(letters, kinematic, codes, boundary, c_n, qdot)


def solve_many_reference(scene: Scene, mu_vectors, tol: Tolerances = DEFAULT_TOLERANCES) -> VectorStatuses:
    """The reference of :func:`solve_many`: :func:`qsplan.mechanics.solve` at each friction vector.

    Same parameters (every force kept) and result.  The kinematic statuses are read from a solve at the
    scene's own ``mu`` (the kinematic stage does not depend on it).
    """
    mu = check_mu_vectors(scene, mu_vectors)
    letters = tuple(m.letters for m in enumerate_modes(scene.n_contacts, scene.dof))
    index = {m: j for j, m in enumerate(letters)}
    m = len(mu)
    codes = np.zeros((m, len(letters)), dtype=np.int8)
    boundary = np.zeros((m, len(letters)), dtype=bool)
    c_n = np.zeros((m, len(letters), scene.n_contacts))
    qdot = np.zeros((m, len(letters), 3))

    def statuses(s):
        res = solve(s, tol, residuals=False, keep_statuses=True, workers=1, search="all")
        return np.array([Status.ORDER.index(st) for st in res.statuses], dtype=np.int8), res.solutions

    own, _ = statuses(scene)
    kinematic = np.where(np.isin(own, _KINEMATIC_CODES), own, StatusCode.FEASIBLE).astype(np.int8)
    for i, row in enumerate(mu):
        codes[i], solutions = statuses(scene.with_mu(row))
        for sol in solutions:
            j = index[sol.mode.letters]
            boundary[i, j] = sol.on_boundary
            c_n[i, j] = sol.c_n
            qdot[i, j] = sol.qdot
    return VectorStatuses(letters, kinematic, codes, boundary, c_n, qdot)
