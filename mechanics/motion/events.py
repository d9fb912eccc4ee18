"""Locating events along a finite motion held in one contact mode (Section 5.1).

:func:`integrate_mode` integrates with a mode held fixed (RK4, :func:`rk4_step`) and
locates the first event (a condition of
:func:`qsplan.mechanics.motion.conditions.mode_values` reaching its bound, a gap
closing, a limit) by root finding; :func:`persists` is the test a candidate mode
must pass at an event.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from qsplan.mechanics.modes.contact_mode import ContactMode
from qsplan.mechanics.motion.conditions import mode_motion, mode_values
from qsplan.mechanics.numerics import DEFAULT_TOLERANCES, Tolerances
from qsplan.mechanics.model.scene import Scene

__all__ = [
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
        :attr:`qsplan.mechanics.motion.trajectory.Segment.label`); ``after`` is ``""`` when the run stopped there.
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
        from scipy.optimize import brentq  # here: importing scipy.optimize costs ~0.5 s, most runs never need it

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
