"""A second, independent test of the force side of one mode's feasibility, by linear programming.

The solver (:mod:`qsplan.mechanics.solver`, :mod:`qsplan.mechanics.modes.reference`) decides the
force side of a mode by eliminating the sliding tangential forces (eq. 17),
solving the square system ``Q_AI c_A = [-g_obj; tau_I - g_man_I]`` (eq. 26)
and checking ``B_A c_A >= 0`` (eq. 28).  :func:`lp_mode_feasible` asks the
same question of the un-reduced model with a linear program instead: over all
contact forces ``c_n, c_t`` (shape (n_c,) each) and a slack ``s``,

    maximise  s
    subject to  W_n c_n + W_t c_t = -g_obj                        (eq. 2)
                (J_n^T c_n + J_t^T c_t)_i = tau_i - g_man_i,  i effort-controlled   (eq. 3)
                c_in = c_it = 0                       i breaking  (eq. 11)
                c_it = -mu_i xi_i c_in,  c_in >= s    i sliding   (eq. 10, 17)
                mu_i c_in + c_it >= s,  mu_i c_in - c_it >= s,
                (and c_in >= s when mu_i = 0)          i rolling   (eqs. 7-9)
                s <= 1

in units of the load scale ``L`` (the largest entry of ``g_obj`` and
``tau_I - g_man_I``).  The rows of eq. (3) of the velocity-controlled joints
are left out: their efforts are outputs (eq. 27) and impose nothing.  Nothing
here is shared with the solver's linear algebra (no selection matrices, no
``Q_AI``, no Hadamard ratio); it is the cross-check the tests run against it.

When ``Q_AI`` is nonsingular the equalities fix the forces, and the optimal
``s`` is the smallest entry of ``B_A c_A`` divided by ``L``.  When the forces
are statically indeterminate (Section 3.2's relaxed utility condition) the LP
still answers, with the forces of largest margin.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import linprog

from qsplan.mechanics.errors import ModeError, QsplanError
from qsplan.mechanics.modes.contact_mode import ContactMode, mode_from_letters
from qsplan.mechanics.model.scene import Scene

__all__ = ["LPCheck", "lp_mode_feasible", "LP_TOL", "LP_SOLVER_TOL"]

#: Default feasibility tolerance of :func:`lp_mode_feasible`, relative to the load
#: scale ``L``: a mode is feasible when its margin is at least ``-LP_TOL``, so that
#: points on a region's boundary count as feasible, as the paper's non-strict
#: inequalities (7)-(9) say.  1e-9 matches ``Tolerances.force`` of the solver and
#: sits an order above :data:`LP_SOLVER_TOL`, the accuracy HiGHS is asked for.
LP_TOL = 1e-9

#: Primal and dual feasibility tolerances passed to HiGHS (in units of ``L``).
#: Its defaults (1e-7) would limit the forces' agreement with the solver to about
#: 1e-7; 1e-10 is the smallest value HiGHS accepts (it ignores smaller ones with a
#: warning) and stays far above rounding for the small problems of one mode.
LP_SOLVER_TOL = 1e-10


@dataclass(frozen=True, slots=True, eq=False)
class LPCheck:
    """Outcome of :func:`lp_mode_feasible`.

    Attributes
    ----------
    feasible : bool
        Forces exist that satisfy eqs. (2), (3) (effort-controlled rows), (7)-(11)
        within the tolerance: ``margin >= -tol``.
    margin : float
        Optimal slack ``s``: the largest achievable smallest slack of the friction
        inequalities, divided by ``scale`` (dimensionless, at most 1).  ``-inf``
        when the equalities alone have no solution.
    c_n, c_t : ndarray, shape (n_c,), or None
        Forces attaining ``margin`` (N), zero at breaking contacts; None when the
        equalities have no solution.
    message : str
        HiGHS's status message.
    scale : float
        Load scale ``L`` (N or N m): the largest absolute entry of ``g_obj`` and of
        ``tau_I - g_man_I``; 1 when every load is zero.
    """

    feasible: bool
    margin: float
    c_n: np.ndarray | None
    c_t: np.ndarray | None
    message: str
    scale: float = 1.0


def _check_xi(xi, mode: ContactMode) -> np.ndarray:
    try:
        xi = np.asarray(xi, dtype=float)
    except (TypeError, ValueError):
        raise ModeError(f"xi: expected numbers of shape ({mode.n_contacts},); got {xi!r}") from None
    if xi.shape != (mode.n_contacts,):
        raise ModeError(f"xi: expected shape ({mode.n_contacts},) (one per contact); got {xi.shape}")
    bad = [i for i in mode.sliding if xi[i] not in (1.0, -1.0)]
    if bad:
        raise ModeError(
            f"xi[{bad[0]}]: expected +1 or -1 at sliding contact {bad[0]} of mode {mode.letters}; got {xi[bad[0]]}"
        )
    return xi


def lp_mode_feasible(scene: Scene, mode, xi, tol: float = LP_TOL) -> LPCheck:
    """Do contact forces exist for ``mode`` with sliding directions ``xi``?  (LP cross-check.)

    Parameters
    ----------
    scene : Scene
        Its effort-controlled joints' commanded efforts ``tau_I`` enter eq. (3);
        the velocity-controlled joints' rows of eq. (3) are free.
    mode : ContactMode or str
        One letter (R, S, B) per contact.  Any number of applicable constraints is
        accepted; the utility condition (29) is not required.
    xi : array-like, shape (n_c,)
        Sliding directions ``sgn(v_it)`` (eq. 16); +1 or -1 at sliding contacts,
        ignored elsewhere.  Take them from a :class:`~qsplan.mechanics.ModeSolution` or
        from the kinematics (eq. 24): this function decides forces only.
    tol : float
        Feasibility tolerance relative to the load scale (see :data:`LP_TOL`).

    Returns
    -------
    LPCheck

    Raises
    ------
    ModeError
        On a mode of the wrong length, or ``xi`` of the wrong shape or not +-1 at a
        sliding contact.
    QsplanError
        When HiGHS stops without an answer (iteration limit, numerical trouble).

    Notes
    -----
    eqs. (2)-(3), (7)-(11), (17); the reduced form the solver uses is eqs. (26)-(28).
    """
    n_c = scene.n_contacts
    mode = mode_from_letters(mode, n_c)
    xi = _check_xi(xi, mode)
    if not (np.isfinite(tol) and tol >= 0):
        raise QsplanError(f"tol: expected a nonnegative finite number; got {tol!r}")

    mu = scene.mu
    E = np.flatnonzero(scene.effort_controlled)
    tau_rhs = scene.joint_effort[E] - scene.g_man[E]
    loads = np.concatenate([scene.g_obj, tau_rhs])
    L = float(np.max(np.abs(loads)))
    L = L if L > 0 else 1.0

    # x = [c_n (n_c), c_t (n_c), s]
    nv = 2 * n_c + 1
    S_col = 2 * n_c
    eq_rows = [np.concatenate([scene.Wn, scene.Wt, np.zeros((3, 1))], axis=1)]
    eq_rhs = [-scene.g_obj / L]
    if E.size:
        eq_rows.append(np.concatenate([scene.Jn[:, E].T, scene.Jt[:, E].T, np.zeros((E.size, 1))], axis=1))
        eq_rhs.append(tau_rhs / L)
    ub_rows = []
    bounds = [(None, None)] * (2 * n_c) + [(None, 1.0)]
    for i, letter in enumerate(mode.letters):
        if letter == "B":
            bounds[i] = bounds[n_c + i] = (0.0, 0.0)
        elif letter == "S":
            row = np.zeros(nv)
            row[n_c + i], row[i] = 1.0, mu[i] * xi[i]  # c_t + mu xi c_n = 0 (eq. 17)
            eq_rows.append(row[None])
            eq_rhs.append([0.0])
            row = np.zeros(nv)
            row[i], row[S_col] = -1.0, 1.0  # s - c_n <= 0
            ub_rows.append(row)
        else:
            for sign in (1.0, -1.0):
                row = np.zeros(nv)
                row[i], row[n_c + i], row[S_col] = -mu[i], -sign, 1.0  # s - (mu c_n +- c_t) <= 0
                ub_rows.append(row)
            if mu[i] == 0:  # the cone rows no longer imply c_n >= 0 (eq. 9)
                row = np.zeros(nv)
                row[i], row[S_col] = -1.0, 1.0
                ub_rows.append(row)
    cost = np.zeros(nv)
    cost[S_col] = -1.0
    res = linprog(
        cost,
        A_ub=np.array(ub_rows) if ub_rows else None,
        b_ub=np.zeros(len(ub_rows)) if ub_rows else None,
        A_eq=np.vstack(eq_rows),
        b_eq=np.concatenate(eq_rhs),
        bounds=bounds,
        method="highs",
        options={"primal_feasibility_tolerance": LP_SOLVER_TOL, "dual_feasibility_tolerance": LP_SOLVER_TOL},
    )
    if res.status == 2:  # the equalities alone are inconsistent: s is free below, so nothing else can fail
        return LPCheck(False, -np.inf, None, None, res.message, L)
    if res.status != 0:
        raise QsplanError(f"lp_mode_feasible: HiGHS gave no answer for mode {mode.letters} ({res.message})")
    x = res.x
    c_n = x[:n_c] * L
    c_t = x[n_c : 2 * n_c] * L
    margin = float(x[S_col])
    return LPCheck(bool(margin >= -tol), margin, c_n, c_t, res.message, L)
