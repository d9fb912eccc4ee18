"""The one-mode reference test of Section 3.1-3.2 (eqs. 13-28), written as the paper does.

:func:`check_mode` builds the selection matrices of eq. (12), the applicable
matrices of eqs. (14), (19), (22), the partitions ``P_AI`` (eq. 23) and
``Q_AI`` (eq. 26) for the scene's control-mode partition, and tests the
kinematics (24), the breaking contacts (25), the sliding directions (16),
equilibrium (26)-(27) and Coulomb friction (28) in that order.  It is the
readable reference the vectorized solver (:mod:`qsplan.mechanics.solver`) is tested
against; it is not fast.  It re-derives eqs. (12)-(28) on purpose, independently of
:mod:`qsplan.mechanics.modes.kinematics` and :mod:`qsplan.mechanics.modes.equilibrium`,
so that the tests compare two implementations (it shares only the velocity scale of
the tolerances).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from qsplan.mechanics.modes.contact_mode import ContactMode, mode_from_letters
from qsplan.mechanics.modes.kinematics import velocity_scale
from qsplan.mechanics.numerics import DEFAULT_TOLERANCES, Status, Tolerances, hadamard_ratio
from qsplan.mechanics.model.scene import Scene
from qsplan.mechanics.modes.solution import ModeSolution, model_residuals

__all__ = ["ModeCheck", "check_mode", "selection_matrix"]


@dataclass(frozen=True, slots=True, eq=False)
class ModeCheck:
    """Outcome of testing one mode: a :class:`~qsplan.mechanics.numerics.Status` and, when
    feasible, the solution."""

    mode: ContactMode
    status: str
    solution: ModeSolution | None = None

    @property
    def feasible(self) -> bool:
        return self.status == Status.FEASIBLE

    @property
    def ill_conditioned(self) -> bool:
        """``P_AI`` or ``Q_AI`` failed the Hadamard-ratio test (``Tolerances.singular``): undecided."""
        return self.status in Status.ILL_CONDITIONED


def selection_matrix(indices, n: int) -> np.ndarray:
    """Rows ``e_i^T`` for ``i`` in ``indices`` (eq. 12), shape (len(indices), n)."""
    E = np.zeros((len(indices), n))
    E[np.arange(len(indices)), list(indices)] = 1.0
    return E


def check_mode(scene: Scene, mode: ContactMode, tol: Tolerances = DEFAULT_TOLERANCES) -> ModeCheck:
    """Test one contact mode under the scene's control-mode partition (eqs. 13-28).

    Parameters
    ----------
    scene : Scene
    mode : ContactMode
        Must have ``2 n_R + n_S = 3 + |tau_I|`` (eq. 29 with the scene's partition).
    tol : Tolerances

    Returns
    -------
    ModeCheck
        ``status`` is the first check that failed, or ``feasible`` with the solution.
    """
    n_c, n_j = scene.n_contacts, scene.n_joints
    mode = mode_from_letters(mode, n_c, scene.dof)
    k = mode.n_constraints
    ER = selection_matrix(mode.rolling, n_c)
    ES = selection_matrix(mode.sliding, n_c)
    EB = selection_matrix(mode.breaking, n_c)
    EI = selection_matrix(scene.effort_joints, n_j)  # E_{P_AI} = E_{Q_AI} (eq. 32)
    EII = selection_matrix(scene.velocity_joints, n_j)
    Wn, Wt, Jn, Jt = scene.Wn, scene.Wt, scene.Jn, scene.Jt

    # Kinematics, eqs. (13), (14), (23), (24).
    WA_T = np.vstack([ER @ Wn.T, ER @ Wt.T, ES @ Wn.T])
    JA = np.vstack([ER @ Jn, ER @ Jt, ES @ Jn])
    PAI = np.hstack([WA_T, -JA @ EI.T])
    PAII = -JA @ EII.T
    if hadamard_ratio(PAI) < tol.singular:
        return ModeCheck(mode, Status.KINEMATICS_SINGULAR)
    zII = scene.joint_velocity[scene.velocity_joints]
    zI = -np.linalg.solve(PAI, PAII @ zII)
    qdot = zI[:3]
    thetadot = EII.T @ zII + EI.T @ zI[3:]

    # Breaking contacts separate, eq. (15)/(25); sliding directions, eq. (16).
    vtol = tol.velocity * velocity_scale(scene)
    v_nB = EB @ (Wn.T @ qdot - Jn @ thetadot)
    if np.any(v_nB < -vtol):
        return ModeCheck(mode, Status.BREAKING_VIOLATED)
    if np.any(v_nB <= vtol):
        return ModeCheck(mode, Status.BREAKING_ZERO_SPEED)
    v_tS = ES @ (Wt.T @ qdot - Jt @ thetadot)
    if np.any(np.abs(v_tS) <= vtol):
        return ModeCheck(mode, Status.ZERO_SLIDING_SPEED)
    XiS = np.diag(np.sign(v_tS))
    US = ES @ np.diag(scene.mu) @ ES.T
    UR = ER @ np.diag(scene.mu) @ ER.T

    # Equilibrium, eqs. (18)-(20), (26)-(27).
    nR, nS = len(mode.rolling), len(mode.sliding)
    WAmu = np.hstack([Wn @ ER.T, Wt @ ER.T, Wn @ ES.T - Wt @ ES.T @ US @ XiS])
    JAmu_T = np.hstack([Jn.T @ ER.T, Jt.T @ ER.T, Jn.T @ ES.T - Jt.T @ ES.T @ US @ XiS])
    QAI = np.vstack([WAmu, EI @ JAmu_T])
    QAII = EII @ JAmu_T
    if hadamard_ratio(QAI) < tol.singular:
        return ModeCheck(mode, Status.EQUILIBRIUM_SINGULAR)
    tau_in = np.nan_to_num(scene.joint_effort)  # NaN marks efforts that are outputs
    rhs = np.concatenate([-scene.g_obj, EI @ (tau_in - scene.g_man)])
    cA = np.linalg.solve(QAI, rhs)
    tauII = QAII @ cA + EII @ scene.g_man  # eq. (27), from eq. (3)

    # Coulomb friction, eqs. (21)-(22), (28).
    BA = np.block(
        [
            [UR, np.eye(nR), np.zeros((nR, nS))],
            [UR, -np.eye(nR), np.zeros((nR, nS))],
            [np.zeros((nS, 2 * nR)), np.eye(nS)],
        ]
    )
    # eq. (9) also states c_n >= 0 at rolling contacts; B_A implies it only when mu > 0
    slack = np.concatenate([BA @ cA, cA[:nR]])
    ftol = tol.force * max(float(np.max(np.abs(cA))), float(np.max(np.abs(rhs))), 1e-300)
    if np.any(slack < -ftol):
        return ModeCheck(mode, Status.COULOMB_VIOLATED)

    c_n = ER.T @ cA[:nR] + ES.T @ cA[2 * nR :]
    c_t = ER.T @ cA[nR : 2 * nR] - ES.T @ (US @ XiS @ cA[2 * nR :])  # eq. (17)
    tau = EI.T @ (EI @ tau_in) + EII.T @ tauII
    xi = ES.T @ np.sign(v_tS)
    sol = ModeSolution(
        mode=mode,
        qdot=qdot,
        thetadot=thetadot,
        c_n=c_n,
        c_t=c_t,
        tau=tau,
        xi=xi.astype(int),
        on_boundary=bool(np.any(slack <= ftol)),
    )
    return ModeCheck(mode, Status.FEASIBLE, replace(sol, residuals=model_residuals(scene, sol)))
