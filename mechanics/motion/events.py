"""A contact mode's feasibility conditions as continuous functions along a motion (eqs. 24-28).

:func:`mechanics.check_mode` answers yes or no at one instant.  To find *when*
along a finite motion (Section 5.1) a mode stops being feasible, the simulator
(:mod:`mechanics.motion`) needs the conditions as numbers that cross zero:

* the Coulomb slacks ``B_A c_A >= 0`` (eqs. 21, 28): both friction-cone edges
  of every rolling contact and the normal force of every sliding contact;
* the separation speeds ``v_n > 0`` of breaking contacts (eqs. 15, 25);
* the signed sliding speeds ``xi v_t > 0`` of sliding contacts, ``xi`` frozen at
  the start of the segment (eq. 16): a sign change means the contact stops;
* the signed Hadamard ratios of ``P_AI`` and ``Q_AI`` (eqs. 23, 26): the mode
  loses the model's utility (32) where one of them vanishes.

:func:`mode_values` evaluates them all, in that order, without the early exits
of :func:`check_mode`; where it is feasible, the two agree (tests check it).
:func:`integrate_mode` integrates with a mode held fixed (RK4, :func:`rk4_step`) and
locates the first event (a condition reaching its bound, a gap closing, a limit) by
root finding; :func:`persists` is the test a candidate mode must pass at an event.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from scipy.optimize import brentq

from qsplan.mechanics.modes.reference import velocity_scale
from qsplan.mechanics.modes.contact_mode import ContactMode
from qsplan.mechanics.numerics import DEFAULT_TOLERANCES, Tolerances
from qsplan.mechanics.model.scene import Scene

__all__ = [
    "ModeValues",
    "mode_values",
    "mode_motion",
    "signed_hadamard",
    "rk4_step",
    "Event",
    "persists",
    "integrate_mode",
    "mode_rates",
    "scene_with_mu",
    "gaps_of",
    "limits_of",
    "limit_name",
    "FLAT_CHANGE",
    "REFINE_FRACTION",
]


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


def signed_hadamard(A) -> float:
    """``det A / prod_i ||a_i||`` for a square matrix: the signed Hadamard ratio (0 when singular)."""
    A = np.asarray(A, dtype=float)
    if A.shape[0] == 0:
        return 1.0
    norms = np.linalg.norm(A, axis=1)
    if np.any(norms == 0):
        return 0.0
    sign, logdet = np.linalg.slogdet(A)
    return float(sign * np.exp(logdet - np.log(norms).sum())) if sign != 0 else 0.0


def mode_motion(scene: Scene, mode: ContactMode, ratio: bool = True):
    """Motion of ``mode`` by eq. (24): ``(qdot (3,), thetadot (n_j,), h_P)``.

    ``h_P`` is the signed Hadamard ratio of ``P_AI`` (NaN when ``ratio`` is False, which
    saves a determinant on the integrator's hot path).  When ``P_AI`` is exactly singular
    the velocities are NaN.
    """
    R, S = list(mode.rolling), list(mode.sliding)
    E, V = scene.effort_joints, scene.velocity_joints
    WA_T = np.concatenate([scene.Wn.T[R], scene.Wt.T[R], scene.Wn.T[S]])
    JA = np.concatenate([scene.Jn[R], scene.Jt[R], scene.Jn[S]])
    P = np.hstack([WA_T, -JA[:, E]])
    thetadot = np.empty(scene.n_joints)
    h = (signed_hadamard(P) if P.shape[0] == P.shape[1] else 0.0) if ratio else np.nan
    try:
        zII = scene.joint_velocity[V]
        zI = np.linalg.solve(P, JA[:, V] @ zII)  # eq. (24): P_AI z_I = -P_AII z_II, P_AII = -J_A E_II^T
    except np.linalg.LinAlgError:
        thetadot[:] = np.nan
        return np.full(3, np.nan), thetadot, 0.0
    thetadot[V] = zII
    thetadot[E] = zI[3:]
    return zI[:3], thetadot, h


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
    qdot, thetadot, hP = mode_motion(scene, mode)
    v_n = scene.Wn.T @ qdot - scene.Jn @ thetadot
    v_t = scene.Wt.T @ qdot - scene.Jt @ thetadot
    if xi is None:
        xi_arr = np.zeros(n_c, dtype=int)
        xi_arr[S] = np.sign(np.nan_to_num(v_t[S])).astype(int)
    else:
        xi_arr = np.asarray(xi, dtype=int).reshape(n_c)

    # Equilibrium (18)-(20), (26) with the frozen directions; Coulomb (21)-(22), (28).
    E = scene.effort_joints
    mu = scene.mu
    f = -(mu * xi_arr)[S]  # sliding normal columns pick up -mu xi times the tangential column
    WAmu = np.hstack([scene.Wn[:, R], scene.Wt[:, R], scene.Wn[:, S] + scene.Wt[:, S] * f])
    JAmu_T = np.hstack([scene.Jn.T[:, R], scene.Jt.T[:, R], scene.Jn.T[:, S] + scene.Jt.T[:, S] * f])
    Q = np.vstack([WAmu, JAmu_T[E]])
    hQ = signed_hadamard(Q) if Q.shape[0] == Q.shape[1] else 0.0
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
        c_n[:] = 0.0
        c_t[:] = 0.0
        c_n[R], c_t[R], c_n[S] = cA[:nR], cA[nR : 2 * nR], cA[2 * nR :]
        c_t[S] = f * c_n[S]  # eq. (17)
        fscale = max(float(np.max(np.abs(cA))), float(np.max(np.abs(rhs))), 1e-300)
    else:
        fscale = max(float(np.max(np.abs(rhs))), 1e-300)
    vscale = velocity_scale(scene)
    sP, sQ = det_signs if det_signs is not None else (1.0 if hP >= 0 else -1.0, 1.0 if hQ >= 0 else -1.0)

    values = np.concatenate([
        mu[R] * c_n[R] + c_t[R], mu[R] * c_n[R] - c_t[R], c_n[S],  # B_A c_A >= 0 (28)
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


def rk4_step(f, x, h: float):
    """One classical Runge-Kutta step of ``dx/dt = f(x)`` (autonomous), shape of ``x``.

    Exact for piecewise-constant rates (the rod of Section 5.1), fourth order otherwise.
    """
    k1 = f(x)
    k2 = f(x + 0.5 * h * k1)
    k3 = f(x + 0.5 * h * k2)
    k4 = f(x + h * k3)
    return x + (h / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4)


# --- locating events along a motion held in one mode -------------------------------------

#: A condition that changes by less than this (relative to its scale) over the
#: persistence probe counts as not changing: about 1e4 machine epsilons, above
#: the rounding of a solve with a well-conditioned P_AI or Q_AI.
FLAT_CHANGE = 1e-12

#: Halve a step in which a condition crossed until the bracket of the first crossing is
#: at most ``min_segment`` times this, before root finding: conditions may cross back
#: later in a long step (a step past a limit or a singular configuration), and two
#: events closer than ``min_segment`` are not resolved anyway.
REFINE_FRACTION = 0.5


@dataclass(frozen=True, slots=True, eq=False)
class Event:
    """An instant where a motion changed mode, gained a contact, or stopped.

    Attributes
    ----------
    time : float
        s.
    state : ndarray, shape (n_x,)
    kind : str
        ``"coulomb"``, ``"separation"``, ``"sliding"``, ``"utility"`` (a condition of the
        active mode reached its bound), ``"contact"`` (a contact appeared) or ``"limit"``.
    labels : tuple of str
        The conditions that reached their bound (several when simultaneous).
    before, after : str
        Mode labels (one character per potential contact, see
        :attr:`mechanics.motion.Segment.label`); ``after`` is ``""`` when the run stopped there.
    """

    time: float
    state: np.ndarray
    kind: str
    labels: tuple
    before: str
    after: str = ""


def gaps_of(system, x) -> np.ndarray:
    """``system.gaps(x)`` (m), shape (n_p,); zeros (always in contact) when it has none."""
    n_p = len(system.contact_names)
    g = getattr(system, "gaps", None)
    return np.zeros(n_p) if g is None else np.asarray(g(x), dtype=float).reshape(n_p)


def limits_of(system, x) -> np.ndarray:
    """``system.limits(x)``, shape (n_l,); empty when it has none."""
    f = getattr(system, "limits", None)
    return np.zeros(0) if f is None else np.asarray(f(x), dtype=float).reshape(-1)


def limit_name(system, i: int) -> str:
    names = getattr(system, "limit_names", ())
    return names[i] if i < len(names) else f"limit {i}"


def scene_with_mu(system, x, contacts, mu) -> Scene:
    """``system.scene(x, contacts)`` with the friction ``mu`` (shape (n_c,)) of the mode in force."""
    mu = np.asarray(mu, dtype=float)
    mu.setflags(write=False)
    return replace(system.scene(x, contacts), mu=mu)  # mu comes validated from Friction


def mode_rates(system, contacts, mode: ContactMode, mu):
    """``f(x) = dx/dt`` with ``mode`` held (eq. 24 then ``system.rates``); NaN off the valid range."""

    def f(y):
        if not np.all(np.isfinite(y)):
            return np.full(y.shape, np.nan)
        qdot, thetadot, _ = mode_motion(scene_with_mu(system, y, contacts, mu), mode, ratio=False)
        return np.asarray(system.rates(y, qdot, thetadot), dtype=float)

    return f


def persists(system, x, contacts, mode: ContactMode, mu, xi, options, tol: Tolerances = DEFAULT_TOLERANCES) -> bool:
    """Does ``mode`` (feasible at ``x``) stay feasible a probe along its own motion?

    Every condition of :func:`mode_values` must stay above ``-bound_band * scale`` at
    ``x + probe``, and a condition on its bound at ``x`` (within that band) must not
    decrease by more than ``FLAT_CHANGE * scale``: it would cross at once.  This is the
    selection rule of Section 5.1 ("... in the next instant, the R2S1 mode would
    become infeasible") written for any mode.
    """
    v0 = mode_values(scene_with_mu(system, x, contacts, mu), mode, xi=xi, tol=tol)
    xp = rk4_step(mode_rates(system, contacts, mode, mu), x, options.probe_time)
    if not np.all(np.isfinite(xp)):
        return False
    vp = mode_values(scene_with_mu(system, xp, contacts, mu), mode, xi=xi, det_signs=v0.det_signs, tol=tol)
    band = options.bound_band * v0.scales
    if not np.all(np.isfinite(vp.values)) or np.any(vp.values < -band):
        return False
    on_bound = v0.values <= band
    return not np.any(on_bound & (vp.values < v0.values - FLAT_CHANGE * v0.scales))


def integrate_mode(system, x, t, t_final, mode: ContactMode, contacts, mu, xi, label: str, options,
                   tol: Tolerances = DEFAULT_TOLERANCES):  # fmt: skip
    """Integrate with ``mode`` held from ``(t, x)`` to its first event or ``t_final``.

    Steps are RK4 of at most ``options.max_step``.  After each step every event
    function is checked: the mode's conditions (:func:`mode_values`, ``xi`` frozen),
    the gaps of potential contacts not in ``contacts`` and the system's limits.  In a
    step where one crossed, the first crossing is bracketed by halving and located by
    ``scipy.optimize.brentq`` on ``tau -> g(RK4(x_k, tau))`` to ``options.event_xtol``.
    A condition that starts on its bound (within ``bound_band``) fires only once it
    falls that band below its start.

    Returns
    -------
    times : ndarray, shape (k,)
    states : ndarray, shape (k, n_x)
    event : Event or None
        None when ``t_final`` was reached.
    """
    n_p = len(system.contact_names)
    inactive = np.array([i for i in range(n_p) if i not in contacts], dtype=int)
    v0 = mode_values(scene_with_mu(system, x, contacts, mu), mode, xi=xi, tol=tol)
    signs, m = v0.det_signs, v0.values.size
    n_lim = limits_of(system, x).size
    n_g = m + inactive.size + n_lim

    def G(y):
        if not np.all(np.isfinite(y)):
            return np.full(n_g, np.nan)
        v = mode_values(scene_with_mu(system, y, contacts, mu), mode, xi=xi, det_signs=signs, tol=tol).values
        return np.concatenate([v, gaps_of(system, y)[inactive], limits_of(system, y)])

    g0 = G(x)
    band = options.bound_band * v0.scales
    thr = np.zeros(n_g)
    thr[:m] = np.where(g0[:m] > band, 0.0, np.minimum(g0[:m], 0.0) - band)
    kinds = v0.kinds + ("contact",) * inactive.size + ("limit",) * n_lim
    labels = v0.labels + tuple(f"{system.contact_names[i]} comes into contact (gap = 0)" for i in inactive)
    labels += tuple(limit_name(system, j) for j in range(n_lim))
    f = mode_rates(system, contacts, mode, mu)

    times, states = [t], [x]
    while t < t_final:
        h = min(options.max_step, t_final - t)
        x1 = rk4_step(f, x, h)
        g1 = G(x1)
        crossed = np.flatnonzero(~(g1 >= thr))
        if not crossed.size:
            x, t = x1, (t_final if h >= t_final - t else t + h)
            times.append(t)
            states.append(x)
            continue
        # Narrow [lo, hi] to the first crossing: a condition may cross and come back
        # within a long step once another has crossed (beyond a limit, say).
        lo, hi = 0.0, h
        while hi - lo > REFINE_FRACTION * options.min_segment:
            mid = 0.5 * (lo + hi)
            g_mid = G(rk4_step(f, x, mid))
            c_mid = np.flatnonzero(~(g_mid >= thr))
            if c_mid.size:
                hi, g1, crossed = mid, g_mid, c_mid
            else:
                lo = mid
        roots = {}
        for i in crossed:
            if np.isfinite(g1[i]):
                phi = lambda tau, i=i: G(rk4_step(f, x, tau))[i] - thr[i]  # noqa: E731
                roots[int(i)] = lo if phi(lo) <= 0 else brentq(phi, lo, hi, xtol=options.event_xtol)
        if not roots:  # only non-finite values: the mode's matrices broke down inside the step
            ev = Event(float(t), x.copy(), "utility", ("mode kinematics undefined",), label)
            return np.array(times), np.array(states), ev
        tau = min(roots.values())
        hit = [i for i, r in roots.items() if r <= tau + 2 * options.event_xtol]
        kind = next((kinds[i] for i in hit if kinds[i] == "limit"), kinds[hit[0]])
        x, t = rk4_step(f, x, tau), t + tau
        times.append(t)
        states.append(x)
        return np.array(times), np.array(states), Event(float(t), x.copy(), kind, tuple(labels[i] for i in hit), label)
    return np.array(times), np.array(states), None
