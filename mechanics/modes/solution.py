"""Solutions of the quasistatic model for one contact mode, and their residuals (eqs. 2-11).

A :class:`ModeSolution` carries everything needed to check it against the
full, un-reduced model: workpiece twist, all joint velocities, both force
components of every contact, all joint efforts and the sliding directions.
:func:`model_residuals` evaluates every equation and inequality of the model
(eqs. 2-11) for it, so a test or a doubtful user can verify any answer.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from qsplan.mechanics.modes.contact_mode import ContactMode
from qsplan.mechanics.model.scene import Scene

__all__ = ["ModeSolution", "model_residuals", "relative_velocity"]


@dataclass(frozen=True, slots=True, eq=False)
class ModeSolution:
    """A feasible contact mode with its unique motion and forces (eqs. 24-28).

    Attributes
    ----------
    mode : ContactMode
    qdot : ndarray, shape (3,)
        Velocity of the workpiece point at the world origin (m/s) and angular velocity (rad/s).
    thetadot : ndarray, shape (n_j,)
        All joint velocities: inputs and those computed by eq. (24).
    c_n, c_t : ndarray, shape (n_c,)
        Normal and tangential wrench intensities (N); zero at breaking contacts.
    tau : ndarray, shape (n_j,)
        All joint efforts: inputs and those computed by eq. (27).
    xi : ndarray of int, shape (n_c,)
        Sliding directions ``sgn(v_it)`` (eq. 16) at sliding contacts, 0 elsewhere.
    on_boundary : bool
        True when an inequality of eq. (28) holds only within ``Tolerances.force``:
        the mu point lies on the boundary of the mode's region.
    residuals : dict[str, float]
        Worst violation of each equation of the full model, see :func:`model_residuals`.
    """

    mode: ContactMode
    qdot: np.ndarray
    thetadot: np.ndarray
    c_n: np.ndarray
    c_t: np.ndarray
    tau: np.ndarray
    xi: np.ndarray
    on_boundary: bool = False
    residuals: dict = field(default_factory=dict)

    @property
    def max_residual(self) -> float:
        """Largest entry of :attr:`residuals`."""
        return max(self.residuals.values()) if self.residuals else float("nan")


def relative_velocity(scene: Scene, qdot, thetadot):
    """Relative contact velocities ``v_n, v_t`` (eq. 5), each shape (n_c,)."""
    v_n = scene.Wn.T @ qdot - scene.Jn @ thetadot
    v_t = scene.Wt.T @ qdot - scene.Jt @ thetadot
    return v_n, v_t


def model_residuals(scene: Scene, sol: ModeSolution) -> dict:
    """Worst violation of every equation and inequality of the full model (eqs. 2-11).

    Equalities give ``|lhs - rhs|``, inequalities ``max(0, -slack)``; strict
    inequalities (sign of sliding speed, separation of breaking contacts) give
    ``max(0, -slack)`` too, their strictness being the solver's degeneracy check.

    Returns
    -------
    dict[str, float]
        Keys: ``eq2_workpiece_equilibrium``, ``eq3_manipulator_equilibrium``,
        ``eq4_nonpenetration``, ``eq7_friction_cone``, ``eq9_rolling_velocity``,
        ``eq10_sliding_velocity``, ``eq10_sliding_force``, ``eq10_sliding_direction``,
        ``eq11_breaking_force``, ``inputs`` (commanded velocities and efforts met).
    """
    mode = sol.mode
    R, S, B = list(mode.rolling), list(mode.sliding), list(mode.breaking)
    mu = scene.mu
    v_n, v_t = relative_velocity(scene, sol.qdot, sol.thetadot)
    amax = lambda x: float(np.max(np.abs(x))) if np.size(x) else 0.0  # noqa: E731
    neg = lambda x: float(np.max(np.maximum(0.0, -np.asarray(x)))) if np.size(x) else 0.0  # noqa: E731
    res = {
        "eq2_workpiece_equilibrium": amax(scene.Wn @ sol.c_n + scene.Wt @ sol.c_t + scene.g_obj),
        "eq3_manipulator_equilibrium": amax(scene.Jn.T @ sol.c_n + scene.Jt.T @ sol.c_t - sol.tau + scene.g_man),
        "eq4_nonpenetration": neg(v_n),
        "eq7_friction_cone": max(neg(mu * sol.c_n + sol.c_t), neg(mu * sol.c_n - sol.c_t), neg(sol.c_n)),
        "eq9_rolling_velocity": max(amax(v_n[R]), amax(v_t[R])),
        "eq10_sliding_velocity": amax(v_n[S]),
        "eq10_sliding_force": amax(sol.c_t[S] + mu[S] * sol.xi[S] * sol.c_n[S]),
        "eq10_sliding_direction": neg(sol.xi[S] * v_t[S]) + float(np.any(np.abs(sol.xi[S]) != 1)),
        "eq11_breaking_force": max(amax(sol.c_n[B]), amax(sol.c_t[B]), neg(v_n[B])),
    }
    vj = ~scene.effort_controlled
    ej = scene.effort_controlled
    res["inputs"] = max(
        amax(sol.thetadot[vj] - scene.joint_velocity[vj]),
        amax(sol.tau[ej] - scene.joint_effort[ej]),
    )
    return res
