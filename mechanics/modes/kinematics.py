"""Kinematics of a contact mode, vectorized over modes (eqs. 13-16, 23-25).

For every mode of a batch: the applicable constraint rows (eq. 14), the partition
``P_AI`` (eq. 23) solved for ``qdot, thetadot_I`` (eq. 24), the separation speeds of
breaking contacts (eq. 25) and the sliding directions ``xi`` (eq. 16).  This is the
one implementation of eqs. (23)-(25) that the batched solver, mu-space maps, effort
bands and finite motion call; the one-mode reference
(:func:`qsplan.mechanics.modes.reference.check_mode`) re-derives them on purpose.
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
    "kinematics_matrix",
    "solve_kinematics",
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



class ScenePool:
    """Per-scene arrays every batch gathers rows from (computed once per solve)."""

    def __init__(self, scene: Scene):
        self.E, self.V = scene.effort_joints, scene.velocity_joints
        self.Wrows = np.vstack([scene.Wn.T, scene.Wt.T])  # (2 n_c, 3): w_n, w_t as rows
        self.Jrows = np.vstack([scene.Jn, scene.Jt])  # (2 n_c, n_j)
        self.M = np.hstack([self.Wrows, -self.Jrows[:, self.E]])  # rows of P_AI (eq. 23)
        with np.errstate(divide="ignore"):
            self.log_row_norm = np.log(np.linalg.norm(self.M, axis=1))
        self.drive = self.Jrows[:, self.V] @ scene.joint_velocity[self.V]  # right-hand side of eq. (24)


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


def kinematics_matrix(pool: ScenePool, idx: np.ndarray) -> np.ndarray:
    """``P_AI = [W_A^T, -J_AI]`` of every mode (eq. 23), shape (m, k, k) for ``idx`` (m, k) from :func:`applicable_rows`."""
    return pool.M[idx]


def solve_kinematics(scene: Scene, pool: ScenePool, idx: np.ndarray, P: np.ndarray):
    """Eq. (24) for every mode, ``P_AI z_I = J_AII thetadot_II``, then the contact velocities (eq. 5).

    Parameters
    ----------
    idx : ndarray of int, shape (m, k)
        Applicable rows (:func:`applicable_rows`).
    P : ndarray, shape (m, k, k)
        ``P_AI`` (:func:`kinematics_matrix`), nonsingular (raises ``numpy.linalg.LinAlgError`` otherwise).

    Returns
    -------
    qdot : ndarray, shape (m, 3)
    thetadot : ndarray, shape (m, n_j)
        Inputs at velocity-controlled joints, eq. (24)'s solution at effort-controlled ones.
    v_n, v_t : ndarray, shape (m, n_c)
        Relative contact velocities (eq. 5), m/s.
    """
    n_c = scene.n_contacts
    E, V = pool.E, pool.V
    m = idx.shape[0]
    z = np.linalg.solve(P, pool.drive[idx][..., None])[..., 0]  # eq. (24)
    thetadot = np.empty((m, scene.n_joints))
    thetadot[:, V] = scene.joint_velocity[V]
    thetadot[:, E] = z[:, 3:]
    qdot = z[:, :3]
    v = qdot @ pool.Wrows.T - thetadot @ pool.Jrows.T  # eq. (5), (m, 2 n_c)
    return qdot, thetadot, v[:, :n_c], v[:, n_c:]


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
    m = codes.shape[0]
    status = np.zeros(m, dtype=np.int8)

    idx, contact, slide = applicable_rows(scene, codes)
    P = kinematics_matrix(pool, idx)
    sing = ~(hadamard_ratio(P, log_row_norms=pool.log_row_norm[idx].sum(axis=1)) >= tol.singular)
    status[sing] = StatusCode.KINEMATICS_SINGULAR
    P[sing] = np.eye(P.shape[1])
    qdot, thetadot, v_n, v_t = solve_kinematics(scene, pool, idx, P)

    alive = ~sing
    brk = codes == _B
    b_viol = alive & np.any(brk & (v_n < -vtol), axis=1)  # eq. (15)
    status[b_viol] = StatusCode.BREAKING_VIOLATED
    alive &= ~b_viol
    b_zero = alive & np.any(brk & (v_n <= vtol), axis=1)
    status[b_zero] = StatusCode.BREAKING_ZERO_SPEED
    alive &= ~b_zero
    sld = codes == _S
    s_zero = alive & np.any(sld & (np.abs(v_t) <= vtol), axis=1)  # eq. (16) undefined
    status[s_zero] = StatusCode.ZERO_SLIDING_SPEED
    alive &= ~s_zero

    live = np.flatnonzero(alive)
    xi = np.where(sld[live], np.sign(v_t[live]), 0.0)
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
