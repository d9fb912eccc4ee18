"""Every mode's status at many friction vectors of one scene (Sections 3.2, 4): the kinematic stage once.

A mode's kinematic stage (eqs. 23-25, 16) does not depend on mu, so :func:`solve_many` runs it once, in
the solver's batches of modes, and repeats only the equilibrium and Coulomb stage (eqs. 26-28), for every
admissible mode at every friction vector, in bounded batches of rows.  It calls the very stages
:func:`qsplan.mechanics.solve` calls and every matrix is factorised alone, so each status, force and
velocity is the one the solver computes for the scene with that mu, bit for bit, however the rows are
batched.  :func:`solve_many_reference` is that solver once per vector; the tests compare the two.

:func:`solve_many_scenes` does the same for many scenes at once (a plan's rows, each at its own friction vectors
and loads): the kinematic stage of every scene in one call per batch of modes (:class:`StackedPools`: each scene's
rows, stacked; every product the one-scene product, scene by scene), the equilibrium stage of every (scene, mode,
vector) row in batches of rows; each scene's answer is :func:`solve_many`'s, bit for bit.  A vector may carry its
own workpiece load (``loads``: the scene's ``g_obj`` replaced, e.g. plus a disturbance wrench, eq. 2), which the
kinematic stage does not see.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from qsplan.mechanics.errors import SceneError
from qsplan.mechanics.model.friction import check_friction
from qsplan.mechanics.model.scene import Scene
from qsplan.mechanics.modes.contact_mode import codes_to_letters, enumerate_modes, iter_mode_batches
from qsplan.mechanics.modes.equilibrium import equilibrium_columns, equilibrium_solve, equilibrium_stage
from qsplan.mechanics.modes.kinematics import (Kinematics, ScenePool, applicable_rows, kinematic_tests, kinematics_stage,
                                               sliding_directions, velocity_scale)  # fmt: skip
from qsplan.mechanics.numerics import DEFAULT_TOLERANCES, Status, StatusCode, Tolerances
from qsplan.mechanics.solver.batch import DEFAULT_BATCH

__all__ = ["ROW_BATCH", "StackedPools", "VectorStatuses", "check_loads", "check_mu_vectors", "solve_many",
           "solve_many_reference", "solve_many_scenes"]

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


def check_loads(loads, m: int, field: str = "loads") -> np.ndarray | None:
    """``loads`` as a float array of shape ``(m, 3)`` (N, N, N m), finite; None stays None.

    Raises
    ------
    SceneError
        Naming ``field``: not numbers, not finite, or not of shape ``(m, 3)``.
    """
    if loads is None:
        return None
    try:
        g = np.array(loads, dtype=float)
    except (TypeError, ValueError):
        raise SceneError(f"{field}: expected numbers (N, N, N m), shape ({m}, 3); got {loads!r}") from None
    if g.shape != (m, 3) or not np.all(np.isfinite(g)):
        raise SceneError(f"{field}: expected finite numbers of shape ({m}, 3) (one load per friction vector); "
                         f"got shape {g.shape}")  # fmt: skip
    return g


@lru_cache(maxsize=8)
def _mode_batches(n_contacts: int, dof: int) -> tuple:
    """The solver's batches of mode codes (read-only) and every mode's letters, in enumeration order."""
    batches = tuple(iter_mode_batches(n_contacts, dof, DEFAULT_BATCH))
    for codes in batches:
        codes.setflags(write=False)
    return batches, tuple(codes_to_letters(c) for codes in batches for c in codes)


def solve_many(scene: Scene, mu_vectors, tol: Tolerances = DEFAULT_TOLERANCES, *, forces: bool = True,
               batch: int = ROW_BATCH, loads=None) -> VectorStatuses:  # fmt: skip
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
    loads : array-like, shape (m, 3), optional
        The workpiece's load ``g_obj`` (N, N, N m; eq. 2) at each vector, in place of the scene's (e.g. the
        scene's plus a disturbance wrench).

    Returns
    -------
    VectorStatuses
        Equal, bit for bit, to :func:`solve_many_reference`.

    Raises
    ------
    SceneError
        ``mu_vectors`` negative, not finite or not of shape ``(m, n_c)``; ``loads`` not of shape ``(m, 3)``.
    """
    mu = check_mu_vectors(scene, mu_vectors)
    g = check_loads(loads, len(mu))
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
                                                   np.broadcast_to(tau_e, (rows_pt.size, tau_e.size)), tol,
                                                   None if g is None else g[rows_pt])  # fmt: skip
            cols = lo + live[rows_mode]
            codes[rows_pt, cols] = est
            ok = est == StatusCode.FEASIBLE
            boundary[rows_pt, cols] = ok & bnd
            if forces:
                c_n[rows_pt[ok], cols[ok]] = cn[ok]
                qdot[rows_pt[ok], cols[ok]] = kin.qdot[rows_mode[ok]]
        lo += status.size
    return VectorStatuses(letters, kinematic, codes, boundary, c_n, qdot)


def solve_many_reference(scene: Scene, mu_vectors, tol: Tolerances = DEFAULT_TOLERANCES, *,
                         loads=None) -> VectorStatuses:  # fmt: skip
    """The reference of :func:`solve_many`: :func:`qsplan.mechanics.solve` at each friction vector (with its load, a
    scene of that ``g_obj``).

    Same parameters (every force kept) and result.  The kinematic statuses are read from a solve at the
    scene's own ``mu`` (the kinematic stage does not depend on it, nor on the load).
    """
    from dataclasses import replace

    from qsplan.mechanics.solver.all_modes import solve  # the reference alone needs the all-modes solver

    mu = check_mu_vectors(scene, mu_vectors)
    g = check_loads(loads, len(mu))
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
        codes[i], solutions = statuses((scene if g is None else replace(scene, g_obj=g[i])).with_mu(row))
        for sol in solutions:
            j = index[sol.mode.letters]
            boundary[i, j] = sol.on_boundary
            c_n[i, j] = sol.c_n
            qdot[i, j] = sol.qdot
    return VectorStatuses(letters, kinematic, codes, boundary, c_n, qdot)


@dataclass(frozen=True, slots=True, eq=False)
class StackedPools:
    """:class:`qsplan.mechanics.modes.kinematics.ScenePool` of ``S`` scenes of one shape, stacked: the row pool of
    :func:`qsplan.mechanics.modes.kinematics.kinematic_tests` for every mode of a batch at every scene at once.

    Attributes
    ----------
    E, V : ndarray of int
        The effort- and velocity-controlled joints (the same at every scene).
    M : ndarray, shape (S, 2 n_c, 3 + n_e)
    log_row_norm, drive : ndarray, shape (S, 2 n_c)
    Wrows : ndarray, shape (S, 2 n_c, 3)
    Jrows : ndarray, shape (S, 2 n_c, n_j)
    velocity : ndarray, shape (S, 1, n_j)
        Each scene's joint velocities, broadcasting over its modes.
    """

    E: np.ndarray
    V: np.ndarray
    M: np.ndarray
    log_row_norm: np.ndarray
    drive: np.ndarray
    Wrows: np.ndarray
    Jrows: np.ndarray
    velocity: np.ndarray

    @classmethod
    def of(cls, pools) -> "StackedPools":
        """Stacked from each scene's own :class:`ScenePool` (its products computed alone: bit for bit)."""
        p0 = pools[0]
        return cls(p0.E, p0.V, *(np.stack([getattr(p, f) for p in pools]) for f in ("M", "log_row_norm", "drive",
                                                                                       "Wrows", "Jrows")),
                   np.stack([p.velocity for p in pools])[:, None, :])  # fmt: skip


def _shape(scene: Scene) -> tuple:
    """What scenes solved together share: contacts, joints and which of them are effort-controlled."""
    return scene.n_contacts, scene.n_joints, scene.effort_controlled.tobytes()


def solve_many_scenes(scenes, mu_vectors, tol: Tolerances = DEFAULT_TOLERANCES, *, loads=None, forces: bool = True,
                      batch: int = ROW_BATCH) -> list:  # fmt: skip
    """:func:`solve_many` at many scenes at once: every scene's kinematic stage in one call per batch of modes, the
    equilibrium stage of every (scene, admissible mode, vector) row in batches of ``batch`` rows.

    Parameters
    ----------
    scenes : sequence of Scene
        Any mix; scenes of one shape (contacts, joints, control partition) are solved together.
    mu_vectors : sequence of array-like, shape (m_s, n_c of scene s)
        Each scene's friction vectors.
    tol : Tolerances
    loads : sequence of (array-like, shape (m_s, 3), or None), optional
        Each scene's workpiece load per vector (:func:`solve_many`'s ``loads``).
    forces, batch
        As :func:`solve_many`.

    Returns
    -------
    list of VectorStatuses
        One per scene, each equal, bit for bit, to ``solve_many(scene, mu, tol, loads=load)``.

    Raises
    ------
    SceneError
        As :func:`solve_many`, or ``mu_vectors`` (``loads``) not one per scene.
    """
    scenes = tuple(scenes)
    mus = list(mu_vectors)
    loads = [None] * len(scenes) if loads is None else list(loads)
    if len(mus) != len(scenes) or len(loads) != len(scenes):
        raise SceneError(f"mu_vectors, loads: expected one per scene ({len(scenes)}); got {len(mus)} and {len(loads)}")
    mus = [check_mu_vectors(s, mu, f"mu_vectors[{i}]") for i, (s, mu) in enumerate(zip(scenes, mus))]
    loads = [check_loads(g, len(mu), f"loads[{i}]") for i, (mu, g) in enumerate(zip(mus, loads))]
    groups = {}
    for i, s in enumerate(scenes):
        groups.setdefault(_shape(s), []).append(i)
    out = [None] * len(scenes)
    for members in groups.values():
        answers = _solve_stacked([scenes[i] for i in members], [mus[i] for i in members], [loads[i] for i in members],
                                 tol, forces, batch)  # fmt: skip
        for i, answer in zip(members, answers):
            out[i] = answer
    return out


def _solve_stacked(scenes, mus, loads, tol, forces, batch) -> list:
    """:func:`solve_many_scenes` for scenes of one shape."""
    s0 = scenes[0]
    S, n_c = len(scenes), s0.n_contacts
    pools = [ScenePool(s) for s in scenes]
    stack = StackedPools.of(pools)
    E = stack.E
    vtol = np.array([tol.velocity * velocity_scale(s) for s in scenes])[:, None, None]
    counts = np.array([len(mu) for mu in mus])
    first = np.concatenate([[0], np.cumsum(counts)[:-1]])
    n = int(counts.sum())
    mu = np.concatenate(mus) if n else np.zeros((0, n_c))
    scene_of = np.repeat(np.arange(S), counts)  # each vector's scene
    load = np.empty((n, 3))  # each vector's g_obj (eq. 2): its own, or its scene's
    for i, (a, c) in enumerate(zip(first, counts)):
        load[a : a + c] = scenes[i].g_obj if loads[i] is None else loads[i]
    effort = np.stack([np.nan_to_num(s.joint_effort)[E] - s.g_man[E] for s in scenes])  # tau_e - g_man,e (eq. 3)
    batches, letters = _mode_batches(n_c, s0.dof)
    kinematic = np.zeros((S, len(letters)), dtype=np.int8)
    codes = np.zeros((n, len(letters)), dtype=np.int8)
    boundary = np.zeros((n, len(letters)), dtype=bool)
    c_n = np.zeros((n, len(letters), n_c)) if forces else None
    qdot = np.zeros((n, len(letters), 3)) if forces else None
    W = stack.Wrows.reshape(S * 2 * n_c, 3)
    J = stack.Jrows.reshape(S * 2 * n_c, -1)
    lo = 0
    for modes in batches:
        m = len(modes)
        idx, contact, slide = applicable_rows(s0, modes)
        k = idx.shape[1]
        status, qd, _, v_t = kinematic_tests(stack, idx, modes, tol, vtol)  # (S, m): each scene's modes
        kinematic[:, lo : lo + m] = status
        codes[:, lo : lo + m] = status[scene_of]
        ls, lj = np.nonzero(status == StatusCode.FEASIBLE)  # the admissible (scene, mode) pairs
        xi = sliding_directions(modes[lj], v_t[ls, lj], np.ones(ls.size, dtype=bool))
        per_pair = counts[ls]
        rows = int(per_pair.sum())
        pair_start = np.concatenate([[0], np.cumsum(per_pair)[:-1]])
        for at in range(0, rows, max(1, batch)):
            r = np.arange(at, min(at + batch, rows))
            pair = np.searchsorted(pair_start, r, side="right") - 1
            s, j = ls[pair], lj[pair]
            pt = first[s] + (r - pair_start[pair])  # the row's vector
            kin = Kinematics(modes[j], idx[j], contact[j], slide[j], qd[s, j], None, xi[pair])
            # Q_AI (eq. 26) by the solver's own function, each row's constraint rows gathered in its mode's order
            # (its applicable rows, then their contacts' tangential rows): the same numbers, the same operations
            gather = s[:, None] * (2 * n_c) + np.concatenate([idx[j], contact[j] + n_c], axis=1)
            Q = equilibrium_columns(W[gather], J[gather], E, np.arange(k), np.arange(k), slide[j],
                                    np.take_along_axis(mu[pt], contact[j], axis=1),
                                    np.take_along_axis(xi[pair], contact[j], axis=1))  # fmt: skip
            rhs = np.concatenate([-load[pt], effort[s]], axis=1)
            est, cn, _, bnd = equilibrium_solve(Q, rhs, kin, mu[pt], n_c, tol)
            cols = lo + j
            codes[pt, cols] = est
            ok = est == StatusCode.FEASIBLE
            boundary[pt, cols] = ok & bnd
            if forces:
                c_n[pt[ok], cols[ok]] = cn[ok]
                qdot[pt[ok], cols[ok]] = kin.qdot[ok]
        lo += m
    return [VectorStatuses(letters, kinematic[i], codes[a : a + c], boundary[a : a + c],
                           None if c_n is None else c_n[a : a + c], None if qdot is None else qdot[a : a + c])
            for i, (a, c) in enumerate(zip(first, counts))]  # fmt: skip

