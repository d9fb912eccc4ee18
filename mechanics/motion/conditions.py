"""A contact mode's feasibility conditions as continuous functions along a motion (eqs. 24-28).

:func:`qsplan.mechanics.check_mode` answers yes or no at one instant.  To find *when*
along a finite motion (Section 5.1) a mode stops being feasible, the simulator
(:mod:`qsplan.mechanics.motion.simulator`) needs the conditions as numbers that cross zero:

* the Coulomb slacks ``B_A c_A >= 0`` (eqs. 21, 28): both friction-cone edges
  of every rolling contact and the normal force of every sliding contact;
* the separation speeds ``v_n > 0`` of breaking contacts (eqs. 15, 25);
* the signed sliding speeds ``xi v_t > 0`` of sliding contacts, ``xi`` frozen at
  the start of the segment (eq. 16): a sign change means the contact stops;
* the signed Hadamard ratios of ``P_AI`` and ``Q_AI`` (eqs. 23, 26): the mode
  loses the model's utility (32) where one of them vanishes.

:func:`mode_values` evaluates them all, in that order, without the early exits
of :func:`check_mode`; where it is feasible, the two agree (tests check it).
``P_AI``, ``Q_AI``, their solves and the Coulomb slacks are the one implementation
of eqs. (23)-(28) (:mod:`qsplan.mechanics.modes.kinematics`,
:mod:`qsplan.mechanics.modes.equilibrium`) applied to one mode, with ``xi`` frozen
and without the early exits: the simulator tracks the conditions through zero.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qsplan.mechanics.model.scene import Scene
from qsplan.mechanics.modes.contact_mode import ContactMode
from qsplan.mechanics.modes.contact_mode import letters_to_codes
from qsplan.mechanics.modes.equilibrium import contact_forces, coulomb_slacks, equilibrium_matrix
from qsplan.mechanics.modes.kinematics import (
    Kinematics,
    ScenePool,
    applicable_rows,
    kinematics_matrix,
    solve_kinematics,
    velocity_scale,
)
from qsplan.mechanics.modes.solution import relative_velocity
from qsplan.mechanics.numerics import DEFAULT_TOLERANCES, Tolerances, hadamard_ratio

__all__ = ["ModeValues", "mode_values", "mode_motion"]


@dataclass(frozen=True, slots=True, eq=False)
class ModeValues:
    """Every feasibility condition of one mode at one instant, written as ``value >= 0``.

    Attributes
    ----------
    mode : ContactMode
    qdot : ndarray, shape (3,)
        Velocity of the workpiece point at the world origin (m/s) and angular velocity (rad/s).
    thetadot : ndarray, shape (n_j,)
    v_n, v_t : ndarray, shape (n_c,)
        Relative contact velocities (eq. 5), m/s.
    c_n, c_t : ndarray, shape (n_c,)
        Wrench intensities (N), NaN when ``Q_AI`` is singular.
    xi : ndarray of int, shape (n_c,)
        Sliding directions used for the forces (eq. 16); 0 off sliding contacts.
    det_signs : (float, float)
        Signs of ``det P_AI``, ``det Q_AI`` the utility values refer to.
    values : ndarray, shape (m,)
        The conditions, in the order of the module docstring; the mode is feasible
        when all are nonnegative (within tolerance) and the two ratios exceed
        ``Tolerances.singular``.
    labels : tuple of str, length m
        What each value is, naming the contact and the equation.
    scales : ndarray, shape (m,)
        Natural size of each value (N for slacks, m/s for speeds, 1 for ratios), used
        to make tolerances relative.
    kinds : tuple of str, length m
        ``"coulomb"``, ``"separation"``, ``"sliding"`` or ``"utility"``.
    """

    mode: ContactMode
    qdot: np.ndarray
    thetadot: np.ndarray
    v_n: np.ndarray
    v_t: np.ndarray
    c_n: np.ndarray
    c_t: np.ndarray
    xi: np.ndarray
    det_signs: tuple
    values: np.ndarray
    labels: tuple
    scales: np.ndarray
    kinds: tuple


def _rows(scene: Scene, mode: ContactMode):
    """The scene's row pool, the mode's letter codes (1, n_c) and applicable rows (eq. 14)."""
    pool = ScenePool(scene)
    codes = letters_to_codes(mode.letters)[None, :]
    idx, contact, slide = applicable_rows(scene, codes)
    return pool, codes, idx, contact, slide


def mode_motion(scene: Scene, mode: ContactMode, ratio: bool = True):
    """Motion of ``mode`` by eq. (24): ``(qdot (3,), thetadot (n_j,), h_P)``.

    ``h_P`` is the signed Hadamard ratio of ``P_AI`` (NaN when ``ratio`` is False, which
    saves a determinant on the integrator's hot path).  When ``P_AI`` is exactly singular
    the velocities are NaN.
    """
    pool, _, idx, _, _ = _rows(scene, mode)
    return _motion(scene, pool, idx, ratio)


def _motion(scene: Scene, pool: ScenePool, idx: np.ndarray, ratio: bool):
    P = kinematics_matrix(pool, idx)
    square = P.shape[1] == P.shape[2]
    h = (float(hadamard_ratio(P[0], signed=True)) if square else 0.0) if ratio else np.nan
    try:
        qdot, thetadot, _, _ = solve_kinematics(scene, pool, idx, P)  # eq. (24)
    except np.linalg.LinAlgError:
        return np.full(3, np.nan), np.full(scene.n_joints, np.nan), 0.0
    return qdot[0], thetadot[0], h


def mode_values(
    scene: Scene, mode: ContactMode, xi=None, det_signs=None, tol: Tolerances = DEFAULT_TOLERANCES
) -> ModeValues:
    """Evaluate every feasibility condition of ``mode`` in ``scene`` (eqs. 15, 16, 24-28, 32).

    Parameters
    ----------
    scene : Scene
        Its ``mu`` are the coefficients the mode uses (static while rolling, kinetic while sliding).
    mode : ContactMode
        Must have ``2 n_R + n_S = scene.dof`` (eq. 29).
    xi : array-like of int, shape (n_c,), optional
        Sliding directions to use in the forces (eq. 17); by default ``sgn(v_t)`` at the
        sliding contacts.  The simulator freezes them for a segment so that a sign
        change shows up as a sliding-speed value crossing zero.
    det_signs : (int, int), optional
        Signs of ``det P_AI`` and ``det Q_AI`` at the start of the segment (default: the
        current ones).  The utility values are ``sign * h - Tolerances.singular``, so that
        a matrix passing through singularity makes its value cross zero.
    tol : Tolerances
        Only ``tol.singular`` is used, as the threshold subtracted from the two ratios.

    Returns
    -------
    ModeValues
    """
    n_c = scene.n_contacts
    R, S, B = list(mode.rolling), list(mode.sliding), list(mode.breaking)
    names = scene.contact_names
    pool, codes, idx, contact, slide = _rows(scene, mode)
    qdot, thetadot, hP = _motion(scene, pool, idx, True)
    v_n, v_t = relative_velocity(scene, qdot, thetadot)  # eq. (5)
    if xi is None:
        xi_arr = np.zeros(n_c, dtype=int)
        xi_arr[S] = np.sign(np.nan_to_num(v_t[S])).astype(int)
    else:
        xi_arr = np.asarray(xi, dtype=int).reshape(n_c)

    # Equilibrium (18)-(20), (26) with the frozen directions; Coulomb (21)-(22), (28).
    E = scene.effort_joints
    mu = scene.mu
    kin = Kinematics(codes, idx, contact, slide, qdot[None], thetadot[None], xi_arr[None].astype(float))
    Q = equilibrium_matrix(pool, kin, mu[None])[0]
    hQ = float(hadamard_ratio(Q, signed=True)) if Q.shape[0] == Q.shape[1] else 0.0
    tau_in = np.nan_to_num(scene.joint_effort)
    rhs = np.concatenate([-scene.g_obj, tau_in[E] - scene.g_man[E]])
    c_n = np.full(n_c, np.nan)
    c_t = np.full(n_c, np.nan)
    nR, nS = len(R), len(S)
    cA = None
    if hQ != 0 and np.all(np.isfinite(qdot)):
        try:
            cA = np.linalg.solve(Q, rhs)
        except np.linalg.LinAlgError:
            cA = None
    if cA is not None:
        c_n, c_t = (c[0] for c in contact_forces(kin, cA[None], mu[None], n_c))  # eq. (17) at sliding contacts
        fscale = max(float(np.max(np.abs(cA))), float(np.max(np.abs(rhs))), 1e-300)
    else:
        fscale = max(float(np.max(np.abs(rhs))), 1e-300)
    vscale = velocity_scale(scene)
    sP, sQ = det_signs if det_signs is not None else (1.0 if hP >= 0 else -1.0, 1.0 if hQ >= 0 else -1.0)

    values = np.concatenate([
        *coulomb_slacks(mu[R], c_n[R], c_t[R]), c_n[S],  # B_A c_A >= 0 (28)
        v_n[B],  # eq. (25)
        xi_arr[S] * v_t[S],  # eq. (16)
        [sP * hP - tol.singular, sQ * hQ - tol.singular],
    ])  # fmt: skip
    labels = (
        tuple(f"{names[i]} rolling, +edge of friction cone (28)" for i in R)
        + tuple(f"{names[i]} rolling, -edge of friction cone (28)" for i in R)
        + tuple(f"{names[i]} sliding, normal force >= 0 (28)" for i in S)
        + tuple(f"{names[i]} breaking, separation speed > 0 (25)" for i in B)
        + tuple(f"{names[i]} sliding, speed keeps its sign xi = {xi_arr[i]:+d} (16)" for i in S)
        + ("P_AI nonsingular (23, 32)", "Q_AI nonsingular (26, 32)")
    )
    kinds = ("coulomb",) * (2 * nR + nS) + ("separation",) * len(B) + ("sliding",) * nS + ("utility",) * 2
    scales = np.array([fscale] * (2 * nR + nS) + [vscale] * (len(B) + nS) + [1.0, 1.0])
    return ModeValues(mode, qdot, thetadot, v_n, v_t, c_n, c_t, xi_arr, (sP, sQ), values, labels, scales, kinds)
