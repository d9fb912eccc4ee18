"""Holds proved with friction: nothing moves for every friction coefficient in a box (issue 34, item 1).

The frictionless hold proof (:mod:`qsplan.mechanics.bands.hold`) is exact when zero friction lies in the task's
set, but it cannot prove a hold that only friction secures: a workpiece pressed by one finger against the palm, the
other finger lifted.  Here friction is used, for every coefficient in the box ``[mu_lo, mu_hi]`` at each contact.

The setting is :mod:`~qsplan.mechanics.bands.hold`'s: every velocity-controlled joint held, the effort joints at
torques in a ramp ``[tau_a, tau_b]``, an external wrench anywhere in a box.  A first-order motion
``x = (nu, thetadot_e)`` gives each contact its normal and tangential velocities ``v_n = A x``, ``v_t = B x``
(eq. 6; ``A = [Wn^T, -Jn_e]``, ``B = [Wt^T, -Jt_e]``).  A solution of the quasistatic model (eqs. 2-11) that moves
(``x != 0``) has, at each contact, one of four behaviours: it breaks (``B``: ``v_n > 0``, no force), rolls (``R``:
``v_n = v_t = 0``, ``|c_t| <= mu c_n``) or slides either way (``S+`` / ``S-``: ``v_n = 0``, ``+-v_t > 0``,
``c_t = -+mu c_n``); its forces balance the load (eqs. 2-3).  For one assignment of behaviours the conditions are
linear in ``(x, c_n, c_t, w, tau)`` once the coefficient's existence in the box is written as a cone
(``mu_lo c_n <= -+c_t <= mu_hi c_n`` sliding, ``|c_t| <= mu_hi c_n`` rolling: some ``mu_i`` in ``[mu_lo, mu_hi]``
fits), and homogeneous in ``x``, so its strict inequalities (``v_n > 0``, ``+-v_t > 0``) may be written ``>= 1``.
**Nothing moves** iff the rest is a solution (forces inside every friction cone of the box balance every load of
the boxes: else the model has no solution and the workpiece accelerates) and none of the ``4^n_c`` assignments has a
solution (every contact rolling is a motion only where ``[A; B]`` is rank deficient, which is refused).  Each is a
small linear programme (:func:`solve_lp`, HiGHS); :func:`prove_friction_hold` asks each, every constraint
**loosened** by :data:`SLACK` so that the
programme's own tolerances cannot hide a solution: an infeasible verdict is then one with room (conservative;
a motion feasible only within the slack is reported as a witness, never as proved).

Independent coefficients per contact; a shared coefficient is a subset of them, so a proof holds for it too
(conservative there).  The answer carries its witness when not proved: the behaviours, the motion and the forces.
Units SI (N, N m, m/s, rad/s).
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import product

import numpy as np

from qsplan.mechanics.bands.disturbance import check_wrench_box
from qsplan.mechanics.bands.hold import MARGIN_CAP as HOLD_MARGIN_CAP
from qsplan.mechanics.bands.hold import MARGIN_TOL, RANK_TOL, hold_load, hold_matrix
from qsplan.mechanics.errors import QsplanError

__all__ = ["BEHAVIOURS", "SLACK", "FrictionHold", "prove_friction_hold"]

#: Each contact's behaviour in a motion: breaks, rolls, slides with positive or negative tangential velocity.
BEHAVIOURS = ("B", "R", "S+", "S-")

#: How much every constraint of a behaviour's programme is loosened (N for forces, m/s for the normalised motion,
#: whose strict parts are at least 1): ten times HiGHS's feasibility tolerance (1e-7), so an infeasible verdict
#: has room against the solver's rounding, and a millionth of the unit motion or of a newton, far below what any
#: hand's torque resolution resolves.
SLACK = 1e-6


@dataclass(frozen=True, slots=True, eq=False)
class FrictionHold:
    """The answer of :func:`prove_friction_hold`.

    Attributes
    ----------
    proved : bool
        No motion exists for any friction in the box, torque in the ramp and wrench in the box.
    reason : str
        Why not, in words (or ``"proved"``).
    behaviours : tuple of str or None
        A witness's behaviour per contact (:data:`BEHAVIOURS`), None when proved.
    motion : ndarray, shape (3 + n_e,), or None
        The witness's motion ``(nu, thetadot_e)`` (normalised: its strict parts at least 1).
    forces : ndarray, shape (n_c, 2), or None
        Its contact forces ``(c_n, c_t)`` (N).
    mu : ndarray, shape (n_c,), or None
        Coefficients in the box its forces fit (the ratio ``|c_t| / c_n`` where a contact slides).
    programmes : int
        Linear programmes solved.
    rest_margin : float
        The rest's certified margin (N, :func:`_rest_margin`), where it was computed.
    """

    proved: bool
    reason: str
    behaviours: tuple | None = None
    motion: np.ndarray | None = None
    forces: np.ndarray | None = None
    mu: np.ndarray | None = None
    programmes: int = 0
    rest_margin: float = float("nan")


def _programme(scene, A, B, behaviours, mu_lo, mu_hi, tau, box, slack):
    """The programme of one assignment of behaviours: ``(c, A_ub, b_ub, A_eq, b_eq, bounds)`` over
    ``z = (x, c_n, c_t, w, tau)`` (module docstring), every constraint loosened by ``slack``."""
    n_c, nx = A.shape
    e = np.asarray(scene.effort_joints)
    n_e = len(e)
    n = nx + 2 * n_c + 3 + n_e
    ix, icn, ict = slice(0, nx), slice(nx, nx + n_c), slice(nx + n_c, nx + 2 * n_c)
    iw, itau = slice(nx + 2 * n_c, nx + 2 * n_c + 3), slice(nx + 2 * n_c + 3, n)
    ub, bu = [], []

    def le(row, b):  # row . z <= b + slack
        ub.append(row)
        bu.append(b + slack)

    def eq_band(row, b):  # row . z = b within slack
        le(row, b)
        le(-row, -b)

    # equilibrium: Wn c_n + Wt c_t + w = -g_obj; the effort joints: Jn_e^T c_n + Jt_e^T c_t - tau = -g_man_e
    for k in range(3):
        row = np.zeros(n)
        row[icn], row[ict], row[iw.start + k] = scene.Wn[k], scene.Wt[k], 1.0
        eq_band(row, -scene.g_obj[k])
    for j, joint in enumerate(e):
        row = np.zeros(n)
        row[icn], row[ict], row[itau.start + j] = scene.Jn[:, joint], scene.Jt[:, joint], -1.0
        eq_band(row, -scene.g_man[joint])
    for i, b in enumerate(behaviours):
        cn, ct = icn.start + i, ict.start + i
        a, t = np.zeros(n), np.zeros(n)
        a[ix], t[ix] = A[i], B[i]
        if b == "B":  # opens, carries nothing
            le(-a, -1.0)
            for col in (cn, ct):
                row = np.zeros(n)
                row[col] = 1.0
                eq_band(row, 0.0)
            continue
        eq_band(a, 0.0)  # stays closed
        row = np.zeros(n)
        row[cn] = -1.0
        le(row, 0.0)  # c_n >= 0
        if b == "R":
            eq_band(t, 0.0)
            for s in (1.0, -1.0):  # |c_t| <= mu_hi c_n
                row = np.zeros(n)
                row[ct], row[cn] = s, -mu_hi[i]
                le(row, 0.0)
        else:
            s = 1.0 if b == "S+" else -1.0
            le(-s * t, -1.0)  # s v_t >= 1
            row = np.zeros(n)  # -s c_t >= mu_lo c_n: friction opposes the sliding, at least the box's lowest
            row[ct], row[cn] = s, mu_lo[i]
            le(row, 0.0)
            row = np.zeros(n)  # -s c_t <= mu_hi c_n
            row[ct], row[cn] = -s, -mu_hi[i]
            le(row, 0.0)
    bounds = [(None, None)] * (nx + 2 * n_c)
    bounds += [(lo - slack, hi + slack) for lo, hi in zip(box[0], box[1])]
    bounds += [(lo - slack, hi + slack) for lo, hi in zip(tau[0], tau[1])]
    return np.zeros(n), np.array(ub), np.array(bu), bounds, (ix, icn, ict)


def prove_friction_hold(scene, mu_range, torques=None, disturbance=None, slack: float = SLACK) -> FrictionHold:
    """Prove that nothing moves (module docstring).

    Parameters
    ----------
    scene : Scene
        Its velocity-controlled joints held, its effort joints torque-controlled; its ``mu`` is not used.
    mu_range : (float, float) or array-like, shape (2, n_c)
        The friction box: one interval for every contact, or per contact (lower row, upper row).
    torques : array-like, shape (2, n_e) or (n_e,), optional
        The effort joints' torque ramp (its two ends; every torque between is covered); default the scene's
        ``joint_effort``.
    disturbance : WrenchBox or (lo, hi), optional
        External wrenches (N, N, N m, about the world origin); default none.
    slack : float
        How much every constraint is loosened (:data:`SLACK`).

    Returns
    -------
    FrictionHold

    Raises
    ------
    QsplanError
        A friction box or torque ramp of the wrong shape or not finite, or a negative or reversed friction interval.
    """
    from qsplan.mechanics.solver.lp import solve_lp

    e = np.asarray(scene.effort_joints)
    n_c = scene.n_contacts
    if torques is None:
        torques = scene.joint_effort[e]
    tau = np.asarray(torques, dtype=float)
    tau = np.vstack([tau, tau]) if tau.ndim == 1 else tau
    if tau.shape != (2, len(e)) or not np.all(np.isfinite(tau)):
        raise QsplanError(f"torques: expected the ramp's two ends, shape (2, {len(e)}); got "
                          f"{np.asarray(torques).tolist()}")  # fmt: skip
    tau = np.sort(tau, axis=0)
    mu = np.asarray(mu_range, dtype=float)
    mu = np.repeat(mu.reshape(2, 1), n_c, axis=1) if mu.size == 2 else mu.reshape(2, n_c)
    if not (np.all(np.isfinite(mu)) and np.all(mu[0] >= 0) and np.all(mu[0] <= mu[1])):
        raise QsplanError(f"mu_range: expected 0 <= lo <= hi at every contact; got {mu.tolist()}")
    wb = check_wrench_box(disturbance)
    box = (np.zeros(3), np.zeros(3)) if wb is None else (np.array(wb.lo), np.array(wb.hi))
    A = hold_matrix(scene)
    B = np.hstack([scene.Wt.T, -scene.Jt[:, e]])
    rest = _rest_margin(scene, mu[0], tau, np.zeros((1, 3)) if wb is None else wb.vertices())
    if not rest > MARGIN_TOL:
        return FrictionHold(False, f"the rest is not an equilibrium at every load of the box with the lowest friction "
                                   f"(margin {rest:.3g} N): the model has no solution there, and the workpiece "
                                   "would accelerate", programmes=1)  # fmt: skip
    sv = np.linalg.svd(np.vstack([A, B]), compute_uv=False)
    if sv.size < A.shape[1] or sv[-1] <= RANK_TOL * sv[0]:
        return FrictionHold(False, "the contacts let the workpiece move without any of them sliding or opening "
                                   "(the contact constraints are rank deficient)")  # fmt: skip
    count = 0
    for behaviours in product(BEHAVIOURS, repeat=n_c):
        if set(behaviours) == {"R"}:  # no motion at full rank
            continue
        c, A_ub, b_ub, bounds, (ix, icn, ict) = _programme(scene, A, B, behaviours, mu[0], mu[1], tau, box, slack)
        result = solve_lp(c, A_ub, b_ub, bounds=bounds)
        count += 1
        if result.status == 2:  # infeasible: this behaviour cannot happen
            continue
        if result.status != 0:
            return FrictionHold(False, f"behaviours {behaviours} undecided by the solver ({result.message})",
                                behaviours, programmes=count)  # fmt: skip
        z = result.x
        forces = np.column_stack([z[icn], z[ict]])
        ratio = np.divide(np.abs(forces[:, 1]), forces[:, 0], out=np.zeros(n_c), where=forces[:, 0] > 0)
        words = ", ".join(f"{n} {b}" for n, b in zip(scene.contact_names or range(n_c), behaviours))
        return FrictionHold(False, f"a motion may happen: {words}", behaviours, z[ix], forces,
                            np.clip(ratio, mu[0], mu[1]), count)  # fmt: skip
    return FrictionHold(True, "proved", programmes=count + 1, rest_margin=rest)


def _rest_margin(scene, mu_lo, tau, wrenches) -> float:
    """The rest's margin (N): over the vertices of the wrench box and the ramp's ends, the least ``t`` such that
    forces exist balancing the load (eqs. 2-3 at zero motion) with every ``c_n >= t`` and ``mu_lo c_n - |c_t| >= t``
    (inside every friction cone of the box: the lowest coefficient is the narrowest cone; ``c_t = 0`` where it is 0,
    the frictionless proof's equilibrium), the largest such ``t``
    per vertex by a linear programme, checked against its rounding (the equilibrium's residual, mapped to forces by
    the smallest singular value of ``[Wn Wt; Jn_e Jt_e]``).  Where it is positive the rest is a solution for every
    friction, torque and wrench of the boxes (their convex hull: the set of loads with such forces is convex)."""
    from qsplan.mechanics.solver.lp import solve_lp

    e = np.asarray(scene.effort_joints)
    n_c = scene.n_contacts
    M = np.vstack([np.hstack([scene.Wn, scene.Wt]), np.hstack([scene.Jn[:, e].T, scene.Jt[:, e].T])])
    sigma = np.linalg.svd(M, compute_uv=False)
    sigma_min = float(sigma[-1]) if sigma.size >= min(M.shape) and sigma[-1] > RANK_TOL * sigma[0] else 0.0
    # the programme over (c_n, c_t, t), the same at every vertex but for its load: maximise t
    n = 2 * n_c + 1
    c = np.zeros(n)
    c[-1] = -1.0
    ub = []
    for i in range(n_c):
        row = np.zeros(n)
        row[i], row[-1] = -1.0, 1.0  # t <= c_n
        ub.append(row)
        if mu_lo[i] > 0:
            for s in (1.0, -1.0):  # t <= mu_lo c_n - s c_t: inside the narrowest cone, with room
                row = np.zeros(n)
                row[i], row[n_c + i], row[-1] = -mu_lo[i], s, 1.0
                ub.append(row)
    A_ub, A_eq = np.array(ub), np.hstack([M, np.zeros((M.shape[0], 1))])
    # a contact whose lowest coefficient is 0 pushes without friction (c_t = 0 exactly: no cone to be inside)
    bounds = [(None, None)] * n_c + [(None, None) if m > 0 else (0.0, 0.0) for m in mu_lo] + [(None, HOLD_MARGIN_CAP)]
    worst = np.inf
    for w in wrenches:
        for t_e in tau:
            p = hold_load(scene, t_e, w)  # (g_obj + w, tau - g_man,e): the forces balance (-(g_obj + w), tau - g_man,e)
            load = np.concatenate([-p[:3], p[3:]])
            r = solve_lp(c, A_ub, np.zeros(len(ub)), A_eq, load, bounds=bounds)
            if r.status != 0:
                return -np.inf
            residual = float(np.linalg.norm(M @ r.x[:-1] - load))
            certified = float(r.x[-1]) - (residual / sigma_min if sigma_min > 0 else np.inf)
            worst = min(worst, certified)
    return worst
