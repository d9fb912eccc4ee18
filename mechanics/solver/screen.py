"""The reduced screen of the pruned search: modes rejected without the full test (eqs. 13-17, 24, 26, 28).

Within a breaking set ``B`` (the other contacts ``A``), every mode shares two reductions:

* kinematics: ``v_n = 0`` on ``A`` (eq. 13) leaves ``x = [qdot; thetadot_I] = x0 + Z u`` with
  ``u`` of dimension ``p = n_R``; the rolling contacts' ``v_t = 0`` fix ``u`` by a ``p x p``
  solve instead of the ``dof x dof`` one of eq. (24), and a breaking contact with
  ``v_n < -margin`` there penetrates (eq. 15);
* equilibrium: eq. (26) over every force of ``A``, ``E_A c = rhs``, leaves ``c = c0 + N w`` with
  ``w`` of dimension ``n_S``; the sliding contacts' ``c_t = -mu xi c_n`` (eq. 17, ``xi = sgn v_t``
  from the reduced kinematics, eq. 16) fix ``w`` by an ``n_S x n_S`` solve, and a Coulomb slack
  (eq. 28) below ``-(tol.force + FORCE_MARGIN) F`` rejects the mode.

A mode is rejected only when its reduced systems are well conditioned (:data:`REDUCED_SINGULAR`)
and it fails by a margin far above their rounding; every other mode is left to the reference test
(:func:`qsplan.mechanics.solver.batch.solve_batch`), so every reported solution and status of a
tested mode is exactly the reference's.  :func:`screen_set` is the numpy reference; the compiled
kernel (``screen_kernel.c``, built by ``pip install .``) makes the same decisions, visiting the
rolling sets depth first with one elimination step per level, and :func:`screen_sets` uses it when
it is importable (:data:`KERNEL`).
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from qsplan.mechanics.modes.contact_mode import combinations_array
from qsplan.mechanics.modes.equilibrium import equilibrium_columns
from qsplan.mechanics.modes.kinematics import ScenePool, velocity_scale
from qsplan.mechanics.model.scene import Scene
from qsplan.mechanics.numerics import Tolerances, hadamard_ratio

#: The interface of ``screen_kernel.c`` this module calls (its ``ABI``): a stale build is not used.
#: 2: ``relax``, the breaking sets' equilibrium relaxation (:mod:`qsplan.mechanics.solver.breaking_sets`).
KERNEL_ABI = 2

try:  # compiled by `pip install .`; the numpy reference below when it is missing
    from qsplan.mechanics.solver.screen_kernel import ABI as _built_abi, relax as compiled_relax, screen as compiled_screen
except ImportError:  # pragma: no cover - a build without a C compiler (or one older than ``relax``)
    compiled_screen, compiled_relax, _built_abi = None, None, None
if _built_abi != KERNEL_ABI:  # pragma: no cover - an editable install not rebuilt after a change
    compiled_screen = compiled_relax = None

__all__ = [
    "KEEP",
    "KINEMATIC",
    "COULOMB",
    "KERNEL",
    "KERNEL_ABI",
    "REDUCED_SINGULAR",
    "PENETRATION_MARGIN",
    "SLIP_MARGIN",
    "FORCE_MARGIN",
    "ReducedScene",
    "rolling_positions",
    "rolling_vertices",
    "reduced_equilibrium",
    "screen_set",
    "screen_sets",
]

#: Verdicts of :func:`screen_set`: left to the reference test, rejected by eq. (15), rejected by eq. (28).
KEEP, KINEMATIC, COULOMB = 0, 1, 2

#: The compiled kernel is importable (``pip install .`` with a C compiler): :func:`screen_sets` uses it.
KERNEL = compiled_screen is not None

#: A reduced system (``N_A``, ``E_A``, the ``p x p`` rolling rows or the ``n_S x n_S`` sliding rows)
#: with a smaller Hadamard ratio (:func:`qsplan.mechanics.numerics.hadamard_ratio`) is not trusted to
#: reject a mode: 1e-8 keeps its rounding (1e-16 / 1e-8) far below the margins.
REDUCED_SINGULAR = 1e-8

#: Relative to the scene's driving speed: a breaking contact of the reduced solve must penetrate
#: by more than this to reject the mode (1e3 times ``tol.velocity``'s default, and 1e2 above the
#: reduced solve's rounding); the reference then finds ``v_n < -tol.velocity`` there too.
PENETRATION_MARGIN = 1e-6

#: Relative to the driving speed: a sliding contact slipping slower than this in the reduced solve
#: has an uncertain ``xi`` (eq. 16), so its mode is not screened for eq. (28); same reasoning as
#: :data:`PENETRATION_MARGIN`.
SLIP_MARGIN = 1e-6

#: Relative to the mode's largest load or force ``F`` (as in the reference's ``ftol``), added to
#: ``tol.force``: a Coulomb slack must fall below ``-(tol.force + FORCE_MARGIN) F`` to reject the
#: mode, 1e3 times the reference's own tolerance and 1e2 above the reduced solve's rounding.
FORCE_MARGIN = 1e-6


@lru_cache(maxsize=64)
def rolling_positions(n: int, k: int) -> np.ndarray:
    """Every rolling set of ``k`` of the ``n`` contacts outside a breaking set, as positions in
    lexicographic order, shape (C(n, k), k): :func:`~qsplan.mechanics.modes.contact_mode.combinations_array`,
    cached (every breaking set of one size reuses it) and read-only."""
    out = combinations_array(n, k)
    out.setflags(write=False)
    return out


class ReducedScene:
    """The per-scene rows every breaking set's reductions gather from (computed once per chunk).

    Attributes
    ----------
    M : ndarray, shape (2 n_c, dof)
        ``[w^T, -J_I]`` per constraint, normal rows first (``ScenePool.M``, eq. 23).
    drive : ndarray, shape (2 n_c,)
        ``J_II thetadot_II`` (m/s), eq. (24)'s right-hand side.
    E : ndarray, shape (2 n_c, dof)
        Column of eq. (26) of each constraint's force, as a row (no sliding columns folded).
    rhs : ndarray, shape (dof,)
        ``[-g_obj; tau_I - g_I]`` of eq. (26).
    mu : ndarray, shape (n_c,)
    vmargin, slip : float
        :data:`PENETRATION_MARGIN` and :data:`SLIP_MARGIN` times the driving speed (m/s).
    force_rel : float
        ``tol.force + FORCE_MARGIN``.
    """

    def __init__(self, scene: Scene, tol: Tolerances, pool: ScenePool | None = None):
        pool = ScenePool(scene) if pool is None else pool
        n2 = pool.Wrows.shape[0]
        rows = np.arange(n2)
        none = np.zeros(n2, dtype=bool)
        # eq. (26)'s columns of every constraint, unfolded: Q_AI of "all rows applicable" (equilibrium_columns)
        cols = equilibrium_columns(pool.Wrows, pool.Jrows, pool.E, rows, rows % (n2 // 2), none, scene.mu, 0.0 * scene.mu)
        self.M = np.ascontiguousarray(pool.M, dtype=float)
        self.drive = np.ascontiguousarray(pool.drive, dtype=float)
        self.E = np.ascontiguousarray(cols.T, dtype=float)
        tau_e = np.nan_to_num(scene.joint_effort)[pool.E]
        self.rhs = np.concatenate([-scene.g_obj, tau_e - scene.g_man[pool.E]])  # eq. (26), as in equilibrium_stage
        self.mu = np.ascontiguousarray(scene.mu, dtype=float)
        vscale = velocity_scale(scene)
        self.vmargin, self.slip = PENETRATION_MARGIN * vscale, SLIP_MARGIN * vscale
        self.force_rel = tol.force + FORCE_MARGIN
        self.n_contacts, self.dof = scene.n_contacts, scene.dof


def _particular_and_null(X: np.ndarray):
    """``(x, N, ratio)`` for the rows of ``X.T`` (``X`` of shape (m, n), m >= n): the least-norm ``x``
    with ``X.T x = b`` is ``x(b)``; ``N`` spans the null space of ``X.T``; ``ratio`` is the Hadamard
    ratio of ``X.T``'s rows (Householder QR: ``prod |R_ii| / prod ||row||``)."""
    m, n = X.shape
    Q, R = np.linalg.qr(X, mode="complete")
    d = np.abs(np.diag(R[:n]))
    norms = np.linalg.norm(X, axis=0)
    ratio = 0.0 if np.any(d == 0) or np.any(norms == 0) else float(np.exp(np.sum(np.log(d) - np.log(norms))))
    return (lambda b: Q[:, :n] @ np.linalg.solve(R[:n].T, b)), Q[:, n:], ratio


def reduced_equilibrium(rs: ReducedScene, A: np.ndarray):
    """``(c0, N)``: every force of ``A`` with ``E_A c = rhs`` (eq. 26) is ``c0 + N w``; None if ``E_A`` is not trusted.

    Returns
    -------
    c0 : ndarray, shape (2 n_A,)
        ``[c_n(A); c_t(A)]`` (N).
    N : ndarray, shape (2 n_A, 2 n_A - dof)
        Orthonormal.
    """
    n_c = rs.n_contacts
    solve, N, ratio = _particular_and_null(rs.E[np.concatenate([A, A + n_c])])
    if ratio < REDUCED_SINGULAR:
        return None
    return solve(rs.rhs), N


def rolling_vertices(M: np.ndarray, drive: np.ndarray, B: np.ndarray, A: np.ndarray, P: np.ndarray, vmargin: float):
    """The reduced kinematics of every rolling set ``A[P]`` of breaking set ``B`` (eqs. 13, 15, 24).

    Parameters
    ----------
    M, drive : ndarray, shapes (2 n_c, dof) and (2 n_c,)
        The constraint rows and drive of :class:`ReducedScene` (or a ``ScenePool``).
    B, A : ndarray of int
    P : ndarray of int, shape (m, p)
        Rolling sets as positions in ``A``.
    vmargin : float
        m/s: a breaking contact penetrating by more rejects the mode.

    Returns
    -------
    None when ``N_A`` (the normal rows of ``A``) has a Hadamard ratio below :data:`REDUCED_SINGULAR`, else a tuple
    penetrating : ndarray of bool, shape (m,)
        Well conditioned, and some contact of ``B`` has ``v_n < -vmargin`` (eq. 15).
    good : ndarray of bool, shape (m,)
        The rolling rows' Hadamard ratio is at least :data:`REDUCED_SINGULAR`.
    u : ndarray, shape (m, p)
        The vertex (meaningless where not ``good``).
    TZ, tx : ndarray, shapes (n_A, p), (n_A,)
        ``v_t(A) = TZ u - tx`` (eq. 5).
    """
    n_c = M.shape[0] // 2
    solve, Z, ratio = _particular_and_null(M[A].T)
    if ratio < REDUCED_SINGULAR:
        return None
    x0 = solve(drive[A])
    m, p = P.shape
    TZ, tx = M[n_c + A] @ Z, drive[n_c + A] - M[n_c + A] @ x0
    G = TZ[P]  # (m, p, p): the rolling rows
    good = hadamard_ratio(G) >= REDUCED_SINGULAR
    G[~good] = np.eye(p)
    u = np.linalg.solve(G, tx[P][..., None])[..., 0]
    vB = u @ (M[B] @ Z).T + (M[B] @ x0 - drive[B])  # v_n on B (eq. 15)
    return good & np.any(vB < -vmargin, axis=1), good, u, TZ, tx


def screen_set(rs: ReducedScene, B: np.ndarray, A: np.ndarray, P: np.ndarray, coulomb: bool = True) -> np.ndarray:
    """The verdict of every mode with breaking set ``B`` and rolling contacts ``A[P]`` (numpy reference).

    Parameters
    ----------
    rs : ReducedScene
    B, A : ndarray of int
        Breaking contacts and the others.
    P : ndarray of int, shape (m, p)
        Rolling sets as positions in ``A`` (``p = dof - n_A``).
    coulomb : bool
        Screen eq. (28) too (else eq. 15 only).

    Returns
    -------
    ndarray of int8, shape (m,)
        :data:`KEEP`, :data:`KINEMATIC` or :data:`COULOMB`.
    """
    m, p = P.shape
    verdict = np.zeros(m, dtype=np.int8)
    kin = rolling_vertices(rs.M, rs.drive, B, A, P, rs.vmargin) if m else None
    if kin is None:
        return verdict
    pen, good, u, TZ, tx = kin
    verdict[pen] = KINEMATIC
    n_A = A.size
    live = np.flatnonzero(good & ~pen)  # the modes eq. (28) may still reject
    eq = reduced_equilibrium(rs, A) if coulomb and n_A and live.size else None
    if eq is None:
        return verdict
    c0, N = eq
    m, u = live.size, u[live]
    rolling = np.zeros((m, n_A), dtype=bool)
    rolling[np.arange(m)[:, None], P[live]] = True
    S = np.nonzero(~rolling)[1].reshape(m, n_A - p)  # sliding positions, ascending
    vt = np.einsum("msq,mq->ms", TZ[S], u) - tx[S]
    certain = np.all(np.abs(vt) > rs.slip, axis=1)
    mx = rs.mu[A][S] * np.where(vt > 0, 1.0, -1.0)  # mu xi (eqs. 16-17)
    K = N[n_A + S] + mx[..., None] * N[S]  # c_t + mu xi c_n = 0 at every sliding contact
    h = -(c0[n_A + S] + mx * c0[S])
    ok = hadamard_ratio(K) >= REDUCED_SINGULAR
    K[~ok] = np.eye(K.shape[-1])
    w = np.linalg.solve(K, h[..., None])[..., 0]
    c = c0 + w @ N.T
    c_n, c_t = c[:, :n_A], c[:, n_A:]
    F = np.maximum(np.max(np.abs(rs.rhs), initial=0.0),
                   np.maximum(np.abs(c_n).max(axis=1), np.where(rolling, np.abs(c_t), 0.0).max(axis=1)))  # fmt: skip
    mc = rs.mu[A] * c_n
    cone = np.where(rolling, np.minimum(np.minimum(mc + c_t, mc - c_t), c_n), c_n)  # eq. (28), as worst_slack
    verdict[live[certain & ok & (F > 0) & (cone.min(axis=1) < -rs.force_rel * F)]] = COULOMB
    return verdict


def screen_sets(rs: ReducedScene, masks: np.ndarray, coulomb: bool = True, compiled: bool | None = None):
    """The modes of the breaking sets ``masks`` that the screen keeps, and the counts it rejected.

    Parameters
    ----------
    masks : ndarray of uint8, shape (s, n_c)
        One breaking set per row (1 = breaking); sets with no mode (eq. 29) are skipped.
    compiled : bool or None
        Use the compiled kernel (None: when :data:`KERNEL`); False forces the numpy reference.

    Returns
    -------
    codes : ndarray of uint8, shape (m, n_c)
        Letter codes (0 B, 1 R, 2 S) of the kept modes: sets in order, rolling sets lexicographic.
    n_kinematic, n_coulomb : int
        Modes rejected by eq. (15) and by eq. (28).
    n_modes : int
        Modes of the sets.
    """
    n_c, dof = rs.n_contacts, rs.dof
    masks = np.ascontiguousarray(masks, dtype=np.uint8).reshape(-1, n_c)
    if compiled or (compiled is None and KERNEL):
        raw, n_kin, n_coul, total = compiled_screen(rs.M, rs.drive, rs.E, rs.rhs, rs.mu, masks, n_c, dof, rs.vmargin,
                                                    rs.slip, rs.force_rel, REDUCED_SINGULAR, coulomb)  # fmt: skip
        return np.frombuffer(raw, dtype=np.uint8).reshape(-1, n_c), n_kin, n_coul, total
    parts, n_kin, n_coul, total = [], 0, 0, 0
    for mask in masks:
        B, A = np.flatnonzero(mask), np.flatnonzero(mask == 0)
        p = dof - A.size
        if not 0 <= p <= A.size:
            continue
        P = rolling_positions(A.size, p)
        verdict = screen_set(rs, B, A, P, coulomb)
        keep = P[verdict == KEEP]
        codes = np.full((keep.shape[0], n_c), 2, dtype=np.uint8)
        codes[:, B] = 0
        codes[np.arange(keep.shape[0])[:, None], A[keep]] = 1
        parts.append(codes)
        n_kin += int(np.sum(verdict == KINEMATIC))
        n_coul += int(np.sum(verdict == COULOMB))
        total += P.shape[0]
    codes = np.concatenate(parts) if parts else np.zeros((0, n_c), dtype=np.uint8)
    return codes, n_kin, n_coul, total
