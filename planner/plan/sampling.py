"""Controller-rate samples of a plan: each tick's control mode and command, per joint (issue 24, item 3).

A plan's table (:mod:`qsplan.planner.plan.table`, what the plan files hold) has rows: in-contact phases sample
the slide every 0.5 mm of workpiece travel, regrasps hold each velocity until the next row.  A controller runs
at its own rate; :func:`sample_columns` turns the rows into its ticks, by one rule for every phase:

* **phases**: a tick at ``t`` belongs to the last phase that starts at or before ``t``, so a tick at a switch
  takes the new phase; a switch time is the time of the new phase's first row, and a tick within
  :data:`TIME_SNAP` of it counts as at it (the rows' times carry float noise from summed durations).
* **control mode** of a joint, per phase: ``torque`` where the plan gives it a torque (``tau_<joint>``, the
  phase's effort joint), else ``velocity``; ``hold`` is a velocity-controlled joint that does not move over
  the tick (``qd = 0``, ``q`` held).
* **position** ``q``: along the straight line between the rows of the tick's phase, in proportion to the path
  covered (exact at the rows): between rows ``k`` and ``k + 1`` (``dt`` apart, speed scales ``u_k``, ``u_{k+1}``:
  the ``speed_scale`` column, :mod:`qsplan.planner.plan.timing`) the speed scale changes linearly in time, so at
  ``tau`` after row ``k`` the fraction covered is
  ``sigma = (u_k tau + (u_{k+1} - u_k) tau^2 / (2 dt)) / ((u_k + u_{k+1}) dt / 2)`` (constant acceleration; linear
  in time where the speed scale is constant, or where a plan has no ``speed_scale`` column).
* **velocity** ``qd``: the rate of that position over the tick, ``(q(t_{i+1}) - q(t_i)) / (t_{i+1} - t_i)``
  (the last tick: the rate at its instant, 0 at the plan's final rest).  A controller that holds each tick's
  ``qd`` until the next tick lands on ``q`` at every tick, so on every row that falls on a tick.  Every phase
  starts and ends at rest, so ticks near a switch command small velocities, never a step.
* **torque** ``tau``: along the path like ``q`` (``tau_k + (tau_{k+1} - tau_k) sigma``): bands are functions of
  the configuration.  The band guarantee holds at the rows (every 0.5 mm of travel); between them the command is
  the interpolation of guaranteed ones.

``q`` is the command of a velocity or held joint (``nan`` under torque control), ``qd`` of a velocity joint
(0 when held, ``nan`` under torque), ``tau`` of a torque joint (``nan`` otherwise); :attr:`PlanSamples.q_plan`
keeps the plan's position of every joint (a torque-controlled joint's expected one).  Units per joint kind:
rad, rad/s, N m (revolute); m, m/s, N (prismatic).  Times are refused when not strictly increasing or
outside the plan.  :meth:`qsplan.planner.plan.results.Plan.sample` samples a planned plan;
:func:`qsplan.planner.export.sample.sample_plan` a plan file; ``qsplan sample`` writes the CSV.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qsplan.hands.protocol import JOINT_UNITS
from qsplan.mechanics.errors import QsplanError

__all__ = ["CONTROL_MODES", "MAX_TICKS", "TIME_SNAP", "PlanSamples", "path_fraction", "sample_columns", "tick_times"]

#: A joint's control modes at a tick: track ``q`` and ``qd``; apply ``tau``; hold ``q`` (``qd = 0``).
CONTROL_MODES = ("velocity", "torque", "hold")

#: How close (s) a tick may be to a switch or to the plan's ends to count as at it.  Row times are sums of
#: durations (``11.400000000000002``): their float noise is ~1e-15 s; a nanosecond is far below any
#: controller's period (a 1 MHz loop ticks every 1e-6 s).
TIME_SNAP = 1e-9

#: Most ticks sampled at once (~150 bytes a CSV row: 150 MB): a 1000 s plan at 1 kHz.  The bundled plans
#: last 2 to 15 s.
MAX_TICKS = 1_000_000



@dataclass(frozen=True, slots=True, eq=False)
class PlanSamples:
    """A plan sampled at controller ticks (the rule: :mod:`qsplan.planner.plan.sampling`).

    Attributes
    ----------
    t : ndarray, shape (n,)
        Tick times (s), strictly increasing.
    joints : tuple of str, length n_j
    kinds : tuple of str, length n_j
        ``"revolute"`` or ``"prismatic"``; ``"revolute"`` when the plan file does not say (a CSV alone).
    control : ndarray of str, shape (n, n_j)
        One of :data:`CONTROL_MODES` per tick and joint.
    q, qd, tau : ndarray, shape (n, n_j)
        Position (rad or m), velocity (rad/s or m/s) and torque (N m or N) commands; ``nan`` where not commanded.
    q_plan : ndarray, shape (n, n_j)
        Every joint's planned position at the tick (rad or m), the torque-controlled one's included.
    phase : ndarray of int, shape (n,)
        The plan's phase of each tick.
    mode : ndarray of str, shape (n,)
        Its contact mode (``free`` on regrasps).
    """

    t: np.ndarray
    joints: tuple
    kinds: tuple
    control: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    tau: np.ndarray
    q_plan: np.ndarray
    phase: np.ndarray
    mode: np.ndarray

    def units(self) -> dict:
        """``{column: unit}`` of :meth:`columns` (None for words)."""
        out = {"t": "s"}
        for n, k in zip(self.joints, self.kinds):
            u = JOINT_UNITS[k]
            out.update({f"control_{n}": None, f"q_{n}": u["q"], f"qd_{n}": u["qd"], f"tau_{n}": u["tau"]})
        return {**out, "phase": None, "mode": None}

    def columns(self) -> dict:
        """``{column: ndarray}`` in the CSV's order: ``t``, per joint ``control_``, ``q_``, ``qd_``, ``tau_``, then
        ``phase`` and ``mode``."""
        out = {"t": self.t}
        for j, n in enumerate(self.joints):
            out.update({f"control_{n}": self.control[:, j], f"q_{n}": self.q[:, j], f"qd_{n}": self.qd[:, j],
                        f"tau_{n}": self.tau[:, j]})  # fmt: skip
        return {**out, "phase": self.phase, "mode": self.mode}


def _joints(cols, units) -> tuple:
    """``(joint names, kinds)`` from the ``q_<joint>`` columns; kinds from the units (revolute when unknown)."""
    joints = tuple(k[2:] for k in cols if k.startswith("q_"))
    if not joints:
        raise QsplanError("plan: no column 'q_<joint>'; expected the columns of qsplan.planner.plan.table")
    for key in ("t", "phase", "mode", *(f"{c}_{n}" for n in joints for c in ("qd", "tau"))):
        if key not in cols:
            raise QsplanError(f"plan: column {key!r} missing; expected the columns of qsplan.planner.plan.table")
    kinds = tuple("prismatic" if (units or {}).get(f"q_{n}") == "m" else "revolute" for n in joints)
    return joints, kinds


def _phases(cols, joints) -> list:
    """Per phase in time order: ``(index, rows, torque joints (n_j,) bool)``, checked."""
    t = np.asarray(cols["t"], float)
    if t.size == 0 or not np.all(np.isfinite(t)):
        raise QsplanError("plan: column 't' is empty or holds a value that is not a finite time")
    try:
        phase = np.asarray(cols["phase"], float)
    except (TypeError, ValueError):
        phase = np.array([np.nan])
    if phase.shape != t.shape or not (np.all(phase == np.round(phase)) and np.all(np.diff(phase) >= 0)):
        raise QsplanError("plan: column 'phase' holds a value that is not a phase index (0, 1, ...) in time order")
    out = []
    for p in np.unique(phase):
        rows = np.flatnonzero(phase == p)
        if np.any(np.diff(t[rows]) <= 0):
            k = rows[1:][np.diff(t[rows]) <= 0][0]
            raise QsplanError(f"plan: phase {int(p)} has rows out of time order at t = {t[k]!r} s")
        if out and abs(t[rows[0]] - t[out[-1][1][-1]]) > TIME_SNAP:
            raise QsplanError(f"plan: phase {int(p)} starts at t = {t[rows[0]]!r} s, not where phase {out[-1][0]} "
                              f"ends (t = {t[out[-1][1][-1]]!r} s)")  # fmt: skip
        torque = np.zeros(len(joints), dtype=bool)
        for j, n in enumerate(joints):
            tau, qd = np.asarray(cols[f"tau_{n}"], float)[rows], np.asarray(cols[f"qd_{n}"], float)[rows]
            torque[j] = np.all(np.isfinite(tau))
            given = tau if torque[j] else qd
            if not (torque[j] or np.all(np.isnan(tau))) or not np.all(np.isfinite(given)):
                raise QsplanError(f"plan: joint {n!r} in phase {int(p)} has neither a torque (tau_{n}) at every row "
                                  f"nor a velocity (qd_{n}) at every row")  # fmt: skip
        out.append((int(p), rows, torque))
    return out


def path_fraction(tc, tr, u) -> tuple:
    """Where ticks ``tc`` (s, within ``tr[0]``..``tr[-1]``) fall between a phase's rows (times ``tr``, speed scales
    ``u``): ``(interval k, fraction sigma of it covered, d sigma / dt at the tick (1/s))``, each shape (n,), by the
    module's rule (constant acceleration of the speed scale between rows)."""
    if tr.size < 2:
        z = np.zeros(tc.size)
        return np.zeros(tc.size, dtype=int), z, z
    k = np.clip(np.searchsorted(tr, tc, side="right") - 1, 0, tr.size - 2)
    dt = tr[k + 1] - tr[k]
    tau = np.clip(tc - tr[k], 0.0, dt)
    a, b = u[k], u[k + 1]
    total = 0.5 * (a + b) * dt
    ok = total > 0
    safe = np.where(ok, total, 1.0)
    sigma = np.where(ok, (a * tau + 0.5 * (b - a) * tau**2 / dt) / safe, tau / dt)
    rate = np.where(ok, (a + (b - a) * tau / dt) / safe, 1.0 / dt)
    return k, np.clip(sigma, 0.0, 1.0), rate


def tick_times(duration, rate) -> np.ndarray:
    """The ticks ``k / rate`` (s) from 0 to ``duration`` (s), shape (n,); the last tick is ``duration`` itself (a plan
    ends at rest there: its last command is its final position): the tick within :data:`TIME_SNAP` of it, or one
    more tick when it falls between two.

    Raises
    ------
    QsplanError
        ``rate`` not a positive finite number (Hz), or more than :data:`MAX_TICKS` ticks.
    """
    rate = float(rate)
    if not (np.isfinite(rate) and rate > 0):
        raise QsplanError(f"rate: expected a positive number of ticks per second (Hz); got {rate!r}")
    duration = float(duration)
    n = int(np.floor((duration + TIME_SNAP) * rate)) + 1
    if n > MAX_TICKS:
        raise QsplanError(f"rate: {rate:g} Hz gives {n} ticks over {duration:g} s; at most {MAX_TICKS} (a lower rate)")
    t = np.arange(n) / rate
    if duration - t[-1] <= TIME_SNAP:
        t[-1] = duration if n > 1 else t[-1]
    else:
        t = np.append(t, duration)
    return t


def sample_columns(cols, units, times) -> PlanSamples:
    """Each tick's control mode and command per joint (the rule: the module docstring).

    Parameters
    ----------
    cols : dict
        The plan's columns ``{name: array}`` (:func:`qsplan.planner.plan.table.plan_columns`, or a plan file's).
    units : dict or None
        Their units (a joint's kind read from its ``q_<joint>`` unit; None: revolute).
    times : array-like, shape (n,)
        Tick times (s), strictly increasing, within the plan (:data:`TIME_SNAP`); e.g. :func:`tick_times`.

    Returns
    -------
    PlanSamples

    Raises
    ------
    QsplanError
        Naming ``times`` (empty, repeated, out of order, outside the plan) or ``plan`` (a missing column, a
        phase without a command at a row, phases out of order or with a gap).
    """
    joints, kinds = _joints(cols, units)
    phases = _phases(cols, joints)
    t_rows = np.asarray(cols["t"], float)
    ts = np.asarray(times, dtype=float).reshape(-1)
    if ts.size == 0 or not np.all(np.isfinite(ts)):
        got = f"{ts.size} values" if ts.size else "none"
        raise QsplanError(f"times: expected finite tick times (s); got {got}")
    if ts.size > MAX_TICKS:
        raise QsplanError(f"times: {ts.size} ticks; at most {MAX_TICKS}")
    if np.any(np.diff(ts) <= 0):
        k = int(np.flatnonzero(np.diff(ts) <= 0)[0])
        raise QsplanError(f"times: expected strictly increasing ticks; tick {k + 1} (t = {ts[k + 1]!r} s) does not "
                          f"follow tick {k} (t = {ts[k]!r} s)")  # fmt: skip
    t0, t1 = t_rows[phases[0][1][0]], t_rows[phases[-1][1][-1]]
    if ts[0] < t0 - TIME_SNAP or ts[-1] > t1 + TIME_SNAP:
        bad = ts[0] if ts[0] < t0 - TIME_SNAP else ts[-1]
        raise QsplanError(f"times: t = {bad!r} s is outside the plan ({t0!r} to {t1!r} s)")
    starts = np.array([t_rows[rows[0]] for _, rows, _ in phases])
    which = np.clip(np.searchsorted(starts, ts + TIME_SNAP, side="right") - 1, 0, len(phases) - 1)
    n, nj = ts.size, len(joints)
    q_plan, tau = np.full((n, nj), np.nan), np.full((n, nj), np.nan)
    torque = np.zeros((n, nj), dtype=bool)
    phase, mode = np.zeros(n, dtype=int), np.empty(n, dtype=object)
    last_rate = np.zeros(nj)
    scale = np.asarray(cols["speed_scale"], float) if "speed_scale" in cols else np.ones(t_rows.size)
    for i, (p, rows, effort) in enumerate(phases):
        at = np.flatnonzero(which == i)
        tr = t_rows[rows]
        tc = np.clip(ts[at], tr[0], tr[-1])
        phase[at], mode[at], torque[at] = p, str(cols["mode"][rows[0]]), effort
        k, sigma, rate = path_fraction(tc, tr, scale[rows])
        for j, name in enumerate(joints):
            qr = np.asarray(cols[f"q_{name}"], float)[rows]
            q_plan[at, j] = qr[k] + (qr[k + 1] - qr[k]) * sigma if tr.size > 1 else qr[0]
            if effort[j]:
                tr_tau = np.asarray(cols[f"tau_{name}"], float)[rows]
                tau[at, j] = tr_tau[k] + (tr_tau[k + 1] - tr_tau[k]) * sigma if tr.size > 1 else tr_tau[0]
            if i == which[-1] and tr.size > 1:  # the last tick: the rate at its instant
                last_rate[j] = (qr[k[-1] + 1] - qr[k[-1]]) * rate[-1]
    qd = np.empty((n, nj))
    qd[:-1] = np.diff(q_plan, axis=0) / np.diff(ts)[:, None]
    qd[-1] = last_rate
    hold = ~torque & (qd == 0.0)
    control = np.where(torque, "torque", np.where(hold, "hold", "velocity"))
    q_cmd = np.where(torque, np.nan, q_plan)
    qd = np.where(torque, np.nan, qd)
    return PlanSamples(ts, joints, kinds, control, q_cmd, qd, tau, q_plan, phase, mode.astype(str))
