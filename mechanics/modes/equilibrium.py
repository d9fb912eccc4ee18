"""Equilibrium and Coulomb friction of a contact mode, vectorized over modes (eqs. 17-22, 26-28).

The equilibrium partition ``Q_AI`` (eq. 26) with the sliding columns folded in
(eqs. 18-20), its solve for the applicable contact forces and the effort-controlled
joints' efforts (eqs. 26-27), the friction force of a sliding contact (eq. 17) and
the Coulomb slacks (eq. 28).  The one implementation of eqs. (17) and (26)-(28) that
the batched solver, mu-space maps, effort bands and finite motion call; the one-mode
reference (:func:`qsplan.mechanics.modes.reference.check_mode`) and the exact rational
test (:mod:`qsplan.mechanics.crosscheck.exact`) re-derive them on purpose.
"""

from __future__ import annotations

import numpy as np

from qsplan.mechanics.model.scene import Scene
from qsplan.mechanics.modes.contact_mode import Letter
from qsplan.mechanics.modes.kinematics import Kinematics, ScenePool
from qsplan.mechanics.numerics import StatusCode, Tolerances, hadamard_ratio

__all__ = [
    "sliding_friction",
    "coulomb_slacks",
    "worst_slack",
    "equilibrium_columns",
    "equilibrium_matrix",
    "contact_forces",
    "equilibrium_solve",
    "equilibrium_stage",
]


def sliding_friction(mu, xi, c_n):
    """Friction force of sliding contacts, ``c_t = -mu xi c_n`` (eq. 17); arrays broadcast."""
    return -mu * xi * c_n


def coulomb_slacks(mu, c_n, c_t):
    """The two friction-cone slacks of rolling contacts, ``mu c_n + c_t`` and ``mu c_n - c_t`` (eq. 28).

    Parameters
    ----------
    mu, c_n, c_t : array-like, broadcasting shapes
        Friction coefficients and forces (N) of rolling contacts.

    Returns
    -------
    plus, minus : ndarray
        Both >= 0 inside the friction cone (eq. 21); linear in ``(c_n, c_t)``.
    """
    mc = mu * c_n
    return mc + c_t, mc - c_t


def worst_slack(codes, mu, c_n, c_t):
    """The smallest Coulomb slack of each mode (eq. 28), ``inf`` with no rolling or sliding contact.

    Rolling contacts contribute both cone slacks (:func:`coulomb_slacks`) and ``c_n``
    (eq. 9 states ``c_n >= 0``; the cone rows imply it only when ``mu > 0``); sliding
    contacts contribute ``c_n``.

    Parameters
    ----------
    codes : ndarray of uint8, shape (m, n_c)
        Letter codes (:class:`~qsplan.mechanics.modes.contact_mode.Letter`).
    mu, c_n, c_t : ndarray, shape (m, n_c)

    Returns
    -------
    ndarray, shape (m,)
        N; negative when eq. (28) fails.
    """
    plus, minus = coulomb_slacks(mu, c_n, c_t)
    cone = np.minimum(np.minimum(plus, minus), c_n)
    slack = np.where(codes == Letter.R, cone, np.where(codes == Letter.S, c_n, np.inf))
    return slack.min(axis=1)


def equilibrium_columns(Wrows, Jrows, E, idx, contact, slide, mu, xi) -> np.ndarray:
    """``Q_AI = [W_Amu; J_AmuI^T]`` of eq. (26) from the constraint rows, over leading axes.

    Column ``j`` belongs to the applicable constraint ``idx[..., j]``; sliding normal columns
    pick up ``-mu xi`` times the tangential column (eqs. 18-20).  Two layouts, as in
    :func:`qsplan.mechanics.modes.kinematics.kinematics_matrix`: modes of one scene (rows
    shared, ``idx`` one per mode) or states of a batch (rows per state, ``idx`` shared).

    Parameters
    ----------
    Wrows : ndarray, shape (2 n_c, 3) or (..., 2 n_c, 3)
        ``[W_n^T; W_t^T]``; with a leading state axis, add the axes of ``mu`` (e.g. ``(S, 1, 2 n_c, 3)``).
    Jrows : ndarray, shape (2 n_c, n_j) or (..., 2 n_c, n_j)
    E : ndarray of int
        Effort-controlled joints.
    idx, contact : ndarray of int, shape (m, k) or (k,)
        Applicable rows and their contacts (:func:`qsplan.mechanics.modes.kinematics.applicable_rows`).
    slide : ndarray of bool, shape (m, k) or (k,)
        The row is the normal row of a sliding contact.
    mu, xi : ndarray, broadcasting to shape (..., n_c)
        Friction coefficients and sliding directions (eq. 16).

    Returns
    -------
    ndarray, shape (..., k, k)
    """
    n_c = Wrows.shape[-2] // 2
    mu_xi = mu * xi
    at = np.broadcast_to(contact, mu_xi.shape[:-1] + contact.shape[-1:])
    f = np.where(slide, -np.take_along_axis(mu_xi, at, axis=-1), 0.0)[..., None]
    partner = contact + n_c
    JE = Jrows[..., E]
    WAmu = np.take(Wrows, idx, axis=-2) + f * np.take(Wrows, partner, axis=-2)  # (..., k, 3): columns of W_Amu
    JAmu = np.take(JE, idx, axis=-2) + f * np.take(JE, partner, axis=-2)  # columns of J_AmuI^T
    return np.concatenate([WAmu, JAmu], axis=-1).swapaxes(-1, -2)


def equilibrium_matrix(pool: "ScenePool", kin: Kinematics, mu: np.ndarray) -> np.ndarray:
    """``Q_AI`` of eq. (26) for every row of ``kin`` (:func:`equilibrium_columns`), shape (m, k, k).

    Parameters
    ----------
    mu : ndarray, shape (m, n_c)
    """
    return equilibrium_columns(pool.Wrows, pool.Jrows, pool.E, kin.idx, kin.contact, kin.slide, mu, kin.xi)


def contact_forces(kin: Kinematics, cA: np.ndarray, mu: np.ndarray, n_c: int):
    """The wrench intensities of every contact from the applicable ones ``c_A`` (eqs. 14, 17).

    Parameters
    ----------
    kin : Kinematics
        ``codes``, ``idx``, ``contact`` and ``xi`` of the modes, shape (m, ...).
    cA : ndarray, shape (m, k)
        Solution of eq. (26), in the column order of :func:`equilibrium_matrix`.
    mu : ndarray, shape (m, n_c)

    Returns
    -------
    c_n, c_t : ndarray, shape (m, n_c)
        N; 0 at breaking contacts, ``c_t = -mu xi c_n`` at sliding ones (eq. 17).
    """
    m = cA.shape[0]
    idx, contact = kin.idx, kin.contact
    rows = np.broadcast_to(np.arange(m)[:, None], idx.shape)
    c_n = np.zeros((m, n_c))
    c_t = np.zeros((m, n_c))
    is_n = idx < n_c
    c_n[rows[is_n], contact[is_n]] = cA[is_n]
    c_t[rows[~is_n], contact[~is_n]] = cA[~is_n]
    c_t = np.where(kin.codes == Letter.S, sliding_friction(mu, kin.xi, c_n), c_t)  # eq. (17)
    return c_n, c_t


def equilibrium_solve(Q: np.ndarray, rhs: np.ndarray, kin: Kinematics, mu: np.ndarray, n_c: int, tol: Tolerances):
    """Eqs. (26) and (28) given ``Q_AI`` and the right-hand side of every row (the part every layout shares).

    Parameters
    ----------
    Q : ndarray, shape (m, k, k)
        ``Q_AI`` (:func:`equilibrium_columns`); overwritten with the identity where singular.
    rhs : ndarray, shape (m, k)
        ``(-g_obj, tau_e - g_man,e)`` of each row (eqs. 2-3).
    kin : Kinematics
        The rows' modes (``codes``, ``idx``, ``contact``, ``xi``).
    mu : ndarray, shape (m, n_c)

    Returns
    -------
    status : ndarray of int8, shape (m,)
    c_n, c_t : ndarray, shape (m, n_c)
    boundary : ndarray of bool, shape (m,)
        An inequality of (28) holds only within the force tolerance.
    """
    status = np.zeros(Q.shape[0], dtype=np.int8)
    q_sing = hadamard_ratio(Q) < tol.singular
    status[q_sing] = StatusCode.EQUILIBRIUM_SINGULAR
    Q[q_sing] = np.eye(Q.shape[1])
    cA = np.linalg.solve(Q, rhs[..., None])[..., 0]

    c_n, c_t = contact_forces(kin, cA, mu, n_c)

    ftol = tol.force * np.maximum(np.max(np.abs(cA), axis=1), np.max(np.abs(rhs), axis=1))
    worst = worst_slack(kin.codes, mu, c_n, c_t)  # eq. (28), and c_n >= 0 at rolling contacts (eq. 9)
    coul = ~q_sing & (worst < -ftol)
    status[coul] = StatusCode.COULOMB_VIOLATED
    return status, c_n, c_t, worst <= ftol


def equilibrium_stage(scene: Scene, pool: "ScenePool", kin: Kinematics, mu: np.ndarray, tau_e: np.ndarray, tol: Tolerances,
                      g_obj: np.ndarray | None = None):  # fmt: skip
    """Equilibrium (26)-(27) and Coulomb (28) for kinematically admissible modes.

    Parameters
    ----------
    mu : ndarray, shape (m, n_c)
        Friction coefficients per row (rows may repeat a mode with other mu).
    tau_e : ndarray, shape (m, n_e)
        Efforts of the effort-controlled joints per row.
    g_obj : ndarray, shape (m, 3), optional
        The workpiece's load per row (N, N, N m; eq. 2), in place of the scene's.

    Returns
    -------
    status : ndarray of int8, shape (m,)
    c_n, c_t : ndarray, shape (m, n_c)
    tau : ndarray, shape (m, n_j)
    boundary : ndarray of bool, shape (m,)
        An inequality of (28) holds only within the force tolerance.
    """
    E, V = pool.E, pool.V
    m = kin.codes.shape[0]
    Q = equilibrium_matrix(pool, kin, mu)
    load = np.broadcast_to(-scene.g_obj, (m, 3)) if g_obj is None else -g_obj
    rhs = np.concatenate([load, tau_e - scene.g_man[E]], axis=1)
    status, c_n, c_t, boundary = equilibrium_solve(Q, rhs, kin, mu, scene.n_contacts, tol)

    tau = np.empty((m, scene.n_joints))
    tau[:, E] = tau_e
    tau[:, V] = (c_n @ scene.Jn + c_t @ scene.Jt)[:, V] + scene.g_man[V]  # eq. (27), from eq. (3)
    return status, c_n, c_t, tau, boundary
