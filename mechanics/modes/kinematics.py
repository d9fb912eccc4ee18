"""Kinematics of a contact mode, vectorized over modes or over states (eqs. 13-16, 23-25).

For every mode of a batch: the applicable constraint rows (eq. 14), the partition
``P_AI`` (eq. 23) solved for ``qdot, thetadot_I`` (eq. 24), the contact velocities
(eq. 5), the tests of breaking contacts (eq. 15, with eq. 25) and the sliding
directions ``xi`` (eq. 16).  This is the one implementation of eqs. (23)-(25) that the
batched solver, mu-space maps, effort bands, bands over a batch of states
(:mod:`qsplan.mechanics.bands.batched`) and finite motion call.  Each function takes
its rows from a *row pool*: a :class:`ScenePool` (the rows of one scene, shared by many
modes) or a :class:`qsplan.mechanics.bands.batched.StateBatch` (the same attributes with
a leading state axis, one mode); where a product depends on that layout the function
keeps one numpy call per layout, so both stay bit-identical to their former selves.
The one-mode reference (:func:`qsplan.mechanics.modes.reference.check_mode`) re-derives
them on purpose.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qsplan.mechanics.model.scene import Scene
from qsplan.mechanics.modes.contact_mode import ContactMode, Letter, letters_to_codes, mode_from_letters
from qsplan.mechanics.numerics import DEFAULT_TOLERANCES, Status, StatusCode, Tolerances, hadamard_ratio

__all__ = [
    "velocity_scale",
    "applicable_rows",
    "ScenePool",
    "Kinematics",
    "kinematics_rows",
    "kinematics_matrix",
    "contact_motion",
    "solve_kinematics",
    "kinematic_status",
    "sliding_directions",
    "kinematic_tests",
    "kinematics_stage",
    "check_mode_fits",
    "single_mode_kinematics",
]

_B, _R, _S = int(Letter.B), int(Letter.R), int(Letter.S)


def velocity_scale(scene: Scene) -> float:
    """Largest driving speed ``|J_n, J_t thetadot_V|`` at the contacts (m/s); 1 if all are zero."""
    V = scene.velocity_joints
    drive = scene.J[:, V] @ scene.joint_velocity[V]
    s = float(np.max(np.abs(drive))) if drive.size else 0.0
    return s if s > 0 else 1.0


def applicable_rows(scene: Scene, codes: np.ndarray):
    """Row indices of the applicable constraints of each mode (eq. 14) and their roles.

    Parameters
    ----------
    codes : ndarray of uint8, shape (m, n_c)
        Letter codes (:class:`~qsplan.mechanics.modes.contact_mode.Letter`).

    Returns
    -------
    idx : ndarray of int, shape (m, k)
        Into the stacked rows ``[n-rows; t-rows]`` (length 2 n_c).
    contact : ndarray of int, shape (m, k)
        Contact of each row.
    slide : ndarray of bool, shape (m, k)
        True where the row is the normal row of a sliding contact.
    """
    n_c = scene.n_contacts
    mask = np.concatenate([codes != _B, codes == _R], axis=1)
    k = int(mask[0].sum())
    idx = np.argsort(~mask, axis=1, kind="stable")[:, :k]
    contact = idx % n_c
    slide = (idx < n_c) & (np.take_along_axis(codes, contact, axis=1) == _S)
    return idx, contact, slide


def kinematics_rows(Wrows, Jrows, velocity, E, V):
    """The rows of ``P_AI`` of every constraint (eq. 23), their log norms and the drive of eq. (24).

    One scene (rows shared by all its modes) or a stack of scenes (a leading state axis).

    Parameters
    ----------
    Wrows : ndarray, shape (2 n_c, 3) or (S, 2 n_c, 3)
        ``[W_n^T; W_t^T]``: the wrench of each constraint as a row.
    Jrows : ndarray, shape (2 n_c, n_j) or (S, 2 n_c, n_j)
        ``[J_n; J_t]``.
    velocity : ndarray, shape (n_j,) or (S, n_j)
        Joint velocities (those of effort-controlled joints unused).
    E, V : ndarray of int
        Effort- and velocity-controlled joints.

    Returns
    -------
    M : ndarray, shape (..., 2 n_c, 3 + n_e)
        ``[w^T, -J_I]`` per constraint: ``P_AI`` gathers its rows from it.
    log_row_norm : ndarray, shape (..., 2 n_c)
        ``log ||row||`` (``-inf`` for a zero row), the Hadamard ratio's denominator.
    drive : ndarray, shape (..., 2 n_c)
        ``J_II thetadot_II`` (m/s), the right-hand side of eq. (24).
    """
    M = np.concatenate([Wrows, -Jrows[..., E]], axis=-1)
    with np.errstate(divide="ignore"):
        log_row_norm = np.log(np.linalg.norm(M, axis=-1))
    if Jrows.ndim == 2:  # one scene: a matrix-vector product
        drive = Jrows[:, V] @ velocity[V]
    else:  # one per state
        drive = np.einsum("srj,sj->sr", Jrows[:, :, V], velocity[:, V])
    return M, log_row_norm, drive


class ScenePool:
    """Per-scene arrays every batch of modes gathers rows from (computed once per solve).

    The same attributes as :class:`qsplan.mechanics.bands.batched.StateBatch` (which stacks
    them over states), so the functions of eqs. (23)-(25) serve both.
    """

    def __init__(self, scene: Scene):
        self.E, self.V = scene.effort_joints, scene.velocity_joints
        self.Wrows = np.vstack([scene.Wn.T, scene.Wt.T])  # (2 n_c, 3): w_n, w_t as rows
        self.Jrows = np.vstack([scene.Jn, scene.Jt])  # (2 n_c, n_j)
        self.velocity = scene.joint_velocity
        self.M, self.log_row_norm, self.drive = kinematics_rows(self.Wrows, self.Jrows, self.velocity, self.E, self.V)


@dataclass(frozen=True, slots=True, eq=False)
class Kinematics:
    """Kinematic stage (eqs. 24-25, 16) for modes that passed it; rows are modes.

    Attributes
    ----------
    codes : ndarray of uint8, shape (m, n_c)
    idx : ndarray of int, shape (m, k)
        Applicable rows of each mode in ``[n-rows; t-rows]`` order (eq. 14).
    contact : ndarray of int, shape (m, k)
        Contact of each applicable row.
    slide : ndarray of bool, shape (m, k)
        Row is the normal row of a sliding contact.
    qdot : ndarray, shape (m, 3)
    thetadot : ndarray, shape (m, n_j)
    xi : ndarray, shape (m, n_c)
        Sliding directions (eq. 16), 0 at rolling and breaking contacts.
    """

    codes: np.ndarray
    idx: np.ndarray
    contact: np.ndarray
    slide: np.ndarray
    qdot: np.ndarray
    thetadot: np.ndarray
    xi: np.ndarray

    def take(self, rows) -> "Kinematics":
        """The same stage restricted (or repeated) to ``rows``."""
        return Kinematics(*(getattr(self, f)[rows] for f in self.__slots__))


def kinematics_matrix(pool, idx: np.ndarray) -> np.ndarray:
    """``P_AI = [W_A^T, -J_AI]`` (eq. 23) gathered from the rows ``pool.M`` (:func:`kinematics_rows`).

    Parameters
    ----------
    pool : ScenePool or StateBatch
        Rows of one scene, shape (2 n_c, k), or of a stack of states, shape (S, 2 n_c, k).
    idx : ndarray of int, shape (m, k) or (k,)
        Applicable rows (:func:`applicable_rows`): one set per mode (one scene), or one set
        shared by the states.

    Returns
    -------
    ndarray, shape (m, k, k) or (S, k, k)
    """
    return np.take(pool.M, idx, axis=-2)


def contact_motion(pool, idx: np.ndarray, P: np.ndarray):
    """Eq. (24), ``P_AI z_I = J_AII thetadot_II``, then the contact velocities (eq. 5).

    Parameters
    ----------
    pool : ScenePool or StateBatch
        Modes of one scene or states of a batch, as in :func:`kinematics_matrix`; or the modes of each of a stack of
        scenes (:class:`qsplan.mechanics.solver.many.StackedPools`: rows ``(S, 2 n_c, ...)``, ``velocity`` (S, 1, n_j),
        ``idx`` one set per mode; ``P`` and the results with leading axes (S, m)).
    idx : ndarray of int, shape (m, k) or (k,)
    P : ndarray, shape (R, k, k)
        ``P_AI`` (:func:`kinematics_matrix`), nonsingular (raises ``numpy.linalg.LinAlgError``
        otherwise); ``R`` rows are modes (one scene) or states.

    Returns
    -------
    qdot : ndarray, shape (R, 3)
    thetadot : ndarray, shape (R, n_j)
        Inputs at velocity-controlled joints, eq. (24)'s solution at effort-controlled ones.
    v_n, v_t : ndarray, shape (R, n_c)
        Relative contact velocities (eq. 5), m/s.
    """
    n_c = pool.Wrows.shape[-2] // 2
    z = np.linalg.solve(P, np.take(pool.drive, idx, axis=-1)[..., None])[..., 0]  # eq. (24)
    thetadot = np.empty(z.shape[:-1] + pool.velocity.shape[-1:])
    thetadot[..., pool.V] = pool.velocity[..., pool.V]
    thetadot[..., pool.E] = z[..., 3:]
    qdot = z[..., :3]
    if pool.Wrows.ndim == 2:  # rows shared by the modes: two matrix products
        v = qdot @ pool.Wrows.T - thetadot @ pool.Jrows.T  # eq. (5), (R, 2 n_c)
    elif qdot.ndim == pool.Wrows.ndim:  # modes (m) of each of a stack of scenes (S, m, 3): the one-scene products
        v = qdot @ pool.Wrows.swapaxes(-1, -2) - thetadot @ pool.Jrows.swapaxes(-1, -2)  # per scene, bit for bit
    else:  # rows per state
        v = np.einsum("sj,srj->sr", qdot, pool.Wrows) - np.einsum("sj,srj->sr", thetadot, pool.Jrows)
    return qdot, thetadot, v[..., :n_c], v[..., n_c:]


def solve_kinematics(scene: Scene, pool: ScenePool, idx: np.ndarray, P: np.ndarray):
    """:func:`contact_motion` for modes of ``scene`` (``pool`` is its :class:`ScenePool`)."""
    return contact_motion(pool, idx, P)


def kinematic_status(codes: np.ndarray, v_n, v_t, vtol, singular: np.ndarray) -> np.ndarray:
    """The kinematic verdict of eqs. (15)-(16) from the contact velocities, over any leading axes.

    Parameters
    ----------
    codes : ndarray of uint8, shape (..., n_c)
        Letter codes, broadcasting against ``v_n``.
    v_n, v_t : ndarray, shape (..., n_c)
        Relative contact velocities (eq. 5), m/s.
    vtol : float or ndarray broadcasting against ``v_n``
        Velocity tolerance (m/s).
    singular : ndarray of bool, shape (...)
        ``P_AI`` failed the Hadamard test; these keep ``KINEMATICS_SINGULAR``.

    Returns
    -------
    ndarray of int8, shape (...)
        The first failure in ``Status.ORDER`` (singular; a breaking contact approaching (15) or
        not separating; a sliding contact at zero speed, where eq. (16) is undefined), 0 if none.
    """
    status = np.zeros(singular.shape, dtype=np.int8)
    status[singular] = StatusCode.KINEMATICS_SINGULAR
    alive = ~singular
    brk = codes == _B
    for code, bad in ((StatusCode.BREAKING_VIOLATED, np.any(brk & (v_n < -vtol), axis=-1)),  # eq. (15)
                      (StatusCode.BREAKING_ZERO_SPEED, np.any(brk & (v_n <= vtol), axis=-1)),
                      (StatusCode.ZERO_SLIDING_SPEED, np.any((codes == _S) & (np.abs(v_t) <= vtol), axis=-1))):  # eq. (16)
        hit = alive & bad
        status[hit] = code
        alive &= ~hit
    return status


def sliding_directions(codes: np.ndarray, v_t, passed: np.ndarray) -> np.ndarray:
    """``xi = sgn(v_t)`` at sliding contacts (eq. 16), 0 elsewhere and where ``passed`` (shape (...)) is False."""
    return np.where((codes == _S) & passed[..., None], np.sign(v_t), 0.0)


def kinematic_tests(pool, idx: np.ndarray, codes: np.ndarray, tol: Tolerances, vtol):
    """The kinematic stage (eqs. 23-25, 15-16) on modes of one scene or on states of a batch.

    Parameters
    ----------
    pool : ScenePool or StateBatch
        As in :func:`kinematics_matrix`.
    idx : ndarray of int, shape (m, k) or (k,)
    codes : ndarray of uint8, shape (m, n_c) or (n_c,)
    vtol : float or ndarray, shape (S, 1)
        Velocity tolerance (m/s).

    Returns
    -------
    status : ndarray of int8, shape (R,)
        Codes into ``Status.ORDER``; 0 where the mode passed.
    qdot : ndarray, shape (R, 3)
    thetadot : ndarray, shape (R, n_j)
    v_t : ndarray, shape (R, n_c)
        Tangential contact velocities (eq. 5), m/s: :func:`sliding_directions` gives ``xi``
        (left to the caller, so the solver forms it for the surviving modes only: memory).
    """
    P = kinematics_matrix(pool, idx)
    sing = ~(hadamard_ratio(P, log_row_norms=np.take(pool.log_row_norm, idx, axis=-1).sum(axis=-1)) >= tol.singular)
    P[sing] = np.eye(P.shape[-1])
    qdot, thetadot, v_n, v_t = contact_motion(pool, idx, P)
    return kinematic_status(codes, v_n, v_t, vtol, sing), qdot, thetadot, v_t


def kinematics_stage(scene: Scene, pool: "ScenePool", codes: np.ndarray, tol: Tolerances, vtol: float):
    """Kinematic tests of a batch of modes: P_AI (23-24), breaking (25), sliding directions (16).

    Returns
    -------
    status : ndarray of int8, shape (m,)
        Codes into ``Status.ORDER``; 0 (feasible so far) for modes that passed.
    live : ndarray of int, shape (m',)
        Rows that passed.
    kin : Kinematics
        Their kinematic solution (independent of mu and of the effort inputs).
    """
    idx, contact, slide = applicable_rows(scene, codes)
    status, qdot, thetadot, v_t = kinematic_tests(pool, idx, codes, tol, vtol)
    live = np.flatnonzero(status == StatusCode.FEASIBLE)
    xi = sliding_directions(codes[live], v_t[live], np.ones(live.size, dtype=bool))
    kin = Kinematics(codes[live], idx[live], contact[live], slide[live], qdot[live], thetadot[live], xi)
    return status, live, kin


def check_mode_fits(scene: Scene, mode) -> ContactMode:
    """``mode`` (letters or ContactMode) checked against the scene: one letter per contact
    and ``2 n_R + n_S = 3 + |tau_I|`` (eq. 29 with the scene's partition)."""
    return mode_from_letters(mode, scene.n_contacts, scene.dof)


def single_mode_kinematics(scene: Scene, mode, tol: Tolerances = DEFAULT_TOLERANCES):
    """The mu- and effort-independent kinematic stage (eqs. 24-25, 16) of one mode.

    Returns
    -------
    mode : ContactMode
    status : str
        ``Status.FEASIBLE`` when the mode passed.
    pool : ScenePool
    kin : Kinematics or None
        One row with the sliding directions ``xi``; None when the mode failed.
    """
    mode = check_mode_fits(scene, mode)
    pool = ScenePool(scene)
    codes = letters_to_codes(mode.letters)[None, :]
    status, live, kin = kinematics_stage(scene, pool, codes, tol, tol.velocity * velocity_scale(scene))
    return mode, Status.ORDER[int(status[0])], pool, (kin if live.size else None)
