"""Finite quasistatic motions: stepping through contact-mode switches (Section 5.1).

The model of Sections 3-4 predicts one instant.  :func:`simulate` integrates it:
the configuration ``x`` of a :class:`~qsplan.mechanics.motion.system.MotionSystem` (workpiece pose, joint
positions, ...) evolves under the velocity inputs while a contact mode holds,
and the mode is re-selected at *events*, located by root finding so that they
do not depend on the integration step:

* the active mode's conditions (:func:`qsplan.mechanics.motion.conditions.mode_values`): Coulomb
  slacks ``B_A c_A`` (eq. 28), separation speeds of breaking contacts (eq. 25),
  sliding speeds (sign of eq. 16), and the utility of ``P_AI``, ``Q_AI`` (eq. 32);
* gaps of potential contacts not in contact (a vertex meeting an edge): contacts appear;
* the system's own limits (e.g. a support reaching the rod's centre of mass): the run stops.

Friction is per contact (:class:`~qsplan.mechanics.motion.system.Friction`): the static coefficient while a
contact rolls (sticks), the kinetic one while it slides, switched at events.

Mode selection rule.  Keep the current mode while it stays feasible.  At an
event (and at the start) the *candidates* are the modes feasible at that instant,
each with its own friction (:func:`qsplan.mechanics.check_mode`); a candidate is kept only
if it *persists*, i.e. stays feasible a short probe along its own motion (a
condition on its bound must not decrease).  This drops the mode whose condition
just ran out, and any mode that would fail at once (Section 5.1: "the mode must
switch ... because if it did not, then in the next instant, the R2S1 mode would
become infeasible").  One persistent candidate: switch to it.  Several: stop
with ``ambiguous`` unless a ``policy`` picks one.  None: stop with ``jam`` (no
mode feasible, the paper's "Jam") or ``no_persistent_mode`` (some are feasible at
the instant but each fails immediately; the motion leaves the model, e.g. the
rod's 2S mode with equal coefficients).  Switches closer than
``MotionOptions.min_segment`` stop the run with ``zeno``.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Callable

import numpy as np

from qsplan.mechanics.errors import QsplanError
from qsplan.mechanics.motion.events import Event, gaps_of, integrate_mode, limit_name, limits_of, persists
from qsplan.mechanics.motion.system import MotionSystem
from qsplan.mechanics.motion.trajectory import Motion, Segment, Stop, mode_label
from qsplan.mechanics.modes.reference import check_mode
from qsplan.mechanics.modes.contact_mode import ContactMode, count_modes, enumerate_modes
from qsplan.mechanics.numerics import DEFAULT_TOLERANCES, Tolerances
from qsplan.mechanics.model.scene import check_finite_array
from qsplan.mechanics.modes.solution import ModeSolution

__all__ = ["MotionOptions", "simulate"]


@dataclass(frozen=True, slots=True)
class MotionOptions:
    """Step, event and stopping parameters of :func:`simulate` (SI units).

    Attributes
    ----------
    max_step : float
        Integration step (s).  Events are found between steps by the sign of their
        condition, so it must resolve the fastest change of sign; switch instants
        themselves are located by root finding and do not depend on it.
    event_xtol : float
        Absolute time tolerance (s) of the root finder (``scipy.optimize.brentq``).
        1e-12 s puts switch instants of motions lasting seconds at rounding level.
    probe_time : float
        Look-ahead (s) of the persistence test of candidate modes at an event.
        Must be shorter than any segment to resolve (below ``min_segment``), far longer
        than the root finder's uncertainty (at least ``100 event_xtol``), and long enough
        that a condition decreasing at a physical rate changes by more than
        ``FLAT_CHANGE`` of its scale: 1e-8 s suits conditions that change by their own
        size over up to 1e4 s.
    bound_band : float
        Relative band: a condition within ``bound_band * scale`` of zero is *on its
        bound*; it must not decrease over the probe, and it may dip this far below
        zero along a segment before an event fires (rounding at a segment's start).
        1e-9 matches ``Tolerances.force``.
    min_segment : float
        A mode that lasts less than this (s) between two switches stops the run as
        ``zeno`` (switches accumulating, e.g. the rod of Fig. 8 as the supports meet).
    max_switches : int
        Hard cap on the number of mode switches (a safety net; reported as ``max_switches``).
    gap_tol : float
        A potential contact whose gap is at most this (m) is in contact.  1e-9 m is
        far above the gap error of a located event and far below any geometry.
    """

    max_step: float = 0.05
    event_xtol: float = 1e-12
    probe_time: float = 1e-8
    bound_band: float = 1e-9
    min_segment: float = 1e-6
    max_switches: int = 10_000
    gap_tol: float = 1e-9

    def __post_init__(self):
        for name in ("max_step", "event_xtol", "probe_time", "bound_band", "min_segment", "gap_tol"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and np.isfinite(v) and v > 0):
                raise QsplanError(f"options.{name}: expected a positive finite number; got {v!r}")
        if not (isinstance(self.max_switches, int) and self.max_switches >= 0):
            raise QsplanError(f"options.max_switches: expected a nonnegative integer; got {self.max_switches!r}")
        if not 100 * self.event_xtol <= self.probe_time < self.min_segment:
            raise QsplanError(
                f"options.probe_time: expected at least 100 event_xtol = {100 * self.event_xtol:g} s (beyond the "
                f"root finder's uncertainty) and below min_segment = {self.min_segment:g} s; got {self.probe_time:g}"
            )


@dataclass(frozen=True, slots=True, eq=False)
class _Candidate:
    mode: ContactMode
    mu: np.ndarray
    solution: ModeSolution
    label: str


Policy = Callable[[float, np.ndarray, tuple], object]


def simulate(
    system,
    x0,
    duration: float,
    options: MotionOptions = MotionOptions(),
    policy: str | Policy | None = None,
    tol: Tolerances = DEFAULT_TOLERANCES,
) -> Motion:
    """Integrate the quasistatic model of ``system`` from ``x0`` for ``duration`` seconds.

    Parameters
    ----------
    system : MotionSystem
    x0 : array-like, shape (n_x,)
        Initial configuration.
    duration : float
        s, positive.
    options : MotionOptions
    policy : None, "first" or callable, optional
        How to resolve an ambiguous choice (several persistent candidates).  None stops
        the run and reports it; ``"first"`` takes the first in enumeration order (eq. 49);
        a callable ``policy(time, state, candidates)`` gets the candidates as a tuple of
        :class:`~qsplan.mechanics.ModeSolution` and returns one of them, its mode letters, or None
        (unresolved: the run stops as ``ambiguous``).
    tol : Tolerances
        Per-instant feasibility tolerances (:func:`qsplan.mechanics.check_mode`).

    Returns
    -------
    Motion

    Raises
    ------
    QsplanError
        Bad ``x0``, ``duration`` or ``policy``, or ``x0`` with a penetrating contact.

    References
    ----------
    Section 5.1 (mode switches with rolling and sliding friction); eqs. (15), (16),
    (24)-(28) for the conditions located as events; eq. (32) for utility.
    """
    if not isinstance(system, MotionSystem):
        raise QsplanError(
            "system: expected a MotionSystem (state_names, contact_names, friction, scene, rates); "
            f"got {type(system).__name__}"
        )
    x = check_finite_array(x0, "x0", (len(system.state_names),))
    try:
        duration = float(duration)
    except (TypeError, ValueError):
        raise QsplanError(f"duration: expected a positive finite time in s; got {duration!r}") from None
    if not (np.isfinite(duration) and duration > 0):
        raise QsplanError(f"duration: expected a positive finite time in s; got {duration!r}")
    if not (policy is None or policy == "first" or callable(policy)):
        raise QsplanError(f"policy: expected None, 'first' or a callable; got {policy!r}")
    n_p = len(system.contact_names)
    gaps = gaps_of(system, x)
    if np.any(gaps < -options.gap_tol):
        i = int(np.argmin(gaps))
        raise QsplanError(f"x0: contact {system.contact_names[i]!r} penetrates by {-gaps[i]:.3g} m")
    t = 0.0
    segments: list[Segment] = []
    events: list[Event] = []
    current: _Candidate | None = None
    current_contacts: tuple = ()
    switches = 0

    def stop(kind, candidates, message):
        return Motion(system, tuple(segments), tuple(events), Stop(kind, float(t), np.array(x), tuple(candidates), message),
                      float(duration))  # fmt: skip

    lim = limits_of(system, x)
    if lim.size and np.any(lim <= 0):
        return stop("limit", (), f"at the start: {limit_name(system, int(np.argmin(lim)))} already reached")
    while True:
        where = "at the start" if current is None else f"at t = {t:.9g} s"
        contacts = tuple(int(i) for i in np.flatnonzero(gaps_of(system, x) <= options.gap_tol))
        if not contacts:
            return stop("jam", (), f"{where}: no contact left; the workpiece is unsupported")
        cands = _candidates(system, x, contacts, tol)
        if not cands:
            dof = system.scene(x, contacts).dof
            if count_modes(len(contacts), dof) == 0:
                return stop("jam", (), f"{where}: {len(contacts)} contact(s) cannot give the {dof} constraints every mode "
                                      "needs (eq. 29): the quasistatic model has no solution (Section 2.2)")  # fmt: skip
            return stop("jam", (), f"{where}: no contact mode is feasible (jam)")
        persistent = [c for c in cands if persists(system, x, contacts, c.mode, c.mu, c.solution.xi, options, tol)]
        if current is not None and contacts == current_contacts:
            keep = [c for c in persistent if c.mode == current.mode]
            persistent = keep or persistent  # the current mode stays feasible: keep it
        if not persistent:
            labels = tuple(c.label for c in cands)
            return stop("no_persistent_mode", labels,
                        f"{where}: the feasible modes {', '.join(labels)} each become infeasible immediately along their "
                        "own motion; the motion continues outside the model's utility conditions (e.g. indeterminate "
                        "sliding)")  # fmt: skip
        chosen = persistent[0] if len(persistent) == 1 else _apply_policy(policy, t, x, persistent)
        if chosen is None:
            labels = tuple(c.label for c in persistent)
            return stop("ambiguous", labels,
                        f"{where}: {len(labels)} modes are feasible and persist ({', '.join(labels)}); "
                        "the model does not say which occurs")  # fmt: skip
        if events:
            events[-1] = replace(events[-1], after=chosen.label)
        if current is not None:
            switches += 1
            if switches > options.max_switches:
                msg = f"{where}: more than max_switches = {options.max_switches} mode switches"
                return stop("max_switches", (chosen.label,), msg)
        current, current_contacts = chosen, contacts

        times, states, ev = integrate_mode(
            system, x, t, duration, chosen.mode, contacts, chosen.mu, chosen.solution.xi, chosen.label, options, tol
        )
        seg = Segment(
            mode=chosen.mode, contacts=contacts, n_potential=n_p, t_start=float(times[0]), t_end=float(times[-1]),
            times=times, states=states, mu=chosen.mu, solution=chosen.solution,
            ended_by="duration" if ev is None else ev.kind,
        )  # fmt: skip
        segments.append(seg)
        t, x = seg.t_end, seg.x_end
        if ev is None:
            return Motion(system, tuple(segments), tuple(events), None, float(duration))
        events.append(ev)
        if ev.kind == "limit":
            return stop("limit", (), f"at t = {t:.9g} s: {ev.labels[0]} reached")
        if seg.duration < options.min_segment and len(segments) > 1:
            return stop("zeno", (), _zeno_message(segments, options))


def _zeno_message(segments, options) -> str:
    ts = np.array([s.t_end for s in segments])
    est = ""
    seq = ts[-5::2] if ts.size >= 5 else ts[-3:]
    if seq.size == 3:
        d1, d2 = seq[1] - seq[0], seq[2] - seq[1]
        if d2 < d1 and d1 > 0:
            est = f"; the switch times converge to about t = {seq[2] + d2 * d2 / (d1 - d2):.9g} s"
    last = segments[-1]
    return (f"mode switches accumulate (Zeno): after {len(segments) - 1} switches, mode {last.label} lasted "
            f"{last.duration:.3g} s < min_segment = {options.min_segment:g} s at t = {last.t_end:.9g} s{est}")  # fmt: skip


def _apply_policy(policy, t, x, persistent):
    if policy is None:
        return None
    if policy == "first":
        return persistent[0]
    picked = policy(float(t), np.array(x), tuple(c.solution for c in persistent))
    if picked is None:
        return None
    for c in persistent:
        if picked is c.solution or (isinstance(picked, str) and picked.upper() in (c.mode.letters, c.label)):
            return c
    raise QsplanError(f"policy: returned {picked!r}, which is not one of the candidates {[c.label for c in persistent]}")


def _candidates(system, x, contacts, tol) -> list[_Candidate]:
    base = system.scene(x, contacts)
    out = []
    for mode in enumerate_modes(len(contacts), base.dof):
        mu = system.friction.for_mode(mode, contacts)
        check = check_mode(replace(base, mu=mu), mode, tol)
        if check.feasible:
            out.append(_Candidate(mode, mu, check.solution, mode_label(mode, contacts, len(system.contact_names))))
    return out
