"""Stops and dynamic time scaling: every phase starts and ends at rest, within acceleration limits (issue 24).

A plan found by the quasistatic planner moves at constant speed: each slide at its quasistatic speed (the
fastest within the speed limits), each regrasp leg at its joints' limits, with steps in velocity at every
switch and at every turn of a regrasp's path.  Played as it is, the workpiece coasts after a release.  The
time scaling keeps every row's configuration, band and command and only retimes the rows:

* a phase's **path parameter** ``s`` is its quasistatic time (s), the rows at ``s_k``; the executed motion
  runs along the same rows at ``ds/dt = ṡ``, the **speed scale**: 0 at rest, at most 1 (the quasistatic speed,
  so every speed limit holds);
* between two rows ``ṡ`` changes linearly in time (constant acceleration): the interval takes
  ``dt = 2 (s_{k+1} - s_k) / (ṡ_k + ṡ_{k+1})``, and every joint moves along the straight line between the
  rows in proportion to ``s`` (the tick rule of :mod:`qsplan.planner.plan.sampling`);
* a **slide** is one rest-to-rest piece: ``ṡ_k = min(peak, sqrt(2 α s_k), sqrt(2 α (S - s_k)))``, a trapezoid
  in ``ṡ^2`` whose chords keep every interval's path acceleration within ``α``; its first and last rows are at
  rest, no row is added (each row carries a band);
* a **regrasp** turns at each of its rows (straight joint-space legs between them): each leg is its own
  rest-to-rest piece, rows added where it stops accelerating and starts braking (or at its middle); its first
  and last legs, which leave and reach the workpiece, within the gentler ``release_acceleration``;
* ``α`` (1/s^2) and the peak are the largest that keep the workpiece's acceleration within the task's
  ``workpiece_acceleration`` (:mod:`qsplan.planner.task.dynamics`: so its inertial wrench stays inside the
  disturbance box every band withstands) and every velocity command's change within its joint's
  acceleration per second.

The exported ``qd`` are the quasistatic ones times the speed scale (0 at rest); the certifier re-derives every
acceleration from the rows (:mod:`qsplan.planner.certify.timing`).  Units SI.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from qsplan.planner.task.dynamics import task_dynamics

__all__ = ["PhaseTiming", "SCALE_ITERATIONS", "path_covered", "piece_scale", "quasistatic_rows", "rest_scene",
           "scale_rate", "time_scale"]

#: Rounds of cutting ``α`` and the peak when a slide's curvature makes a joint's command change faster than the
#: trapezoid alone predicts (each round cuts by the measured excess; the bundled plans need at most one).
SCALE_ITERATIONS = 30

@dataclass(frozen=True, slots=True)
class PhaseTiming:
    """One phase's time scaling.

    Attributes
    ----------
    phase : str
        The phase's name.
    pieces : int
        Rest-to-rest pieces (1 for a slide; a regrasp's legs).
    path_acceleration : float
        The largest change of the speed scale per second between two of its rows (1/s^2: quasistatic seconds per
        second squared): the largest ``α`` of its pieces wherever a row lies on a ramp (a ramp that ends inside its
        first interval changes the rows' speed scale slower).  As the rows realise it: ``plan.json`` states it, the
        certifier checks it against the rows.
    peak_speed_scale : float
        The largest speed scale at its rows (1: the quasistatic speed; a short slide's triangle stays below).
    duration, quasistatic_duration : float
        Its duration (s) with the stops, and at constant quasistatic speed.
    binding : str
        The limit that sets ``α``: ``workpiece_acceleration`` or ``joint_acceleration.<joint>``.
    """

    phase: str
    pieces: int
    path_acceleration: float
    peak_speed_scale: float
    duration: float
    quasistatic_duration: float
    binding: str

    def as_dict(self) -> dict:
        return {"pieces": self.pieces, "path_acceleration_1_s2": self.path_acceleration,
                "peak_speed_scale": self.peak_speed_scale, "duration_s": self.duration,
                "quasistatic_duration_s": self.quasistatic_duration, "binding": self.binding}  # fmt: skip


def piece_scale(s, alpha: float, peak: float = 1.0) -> np.ndarray:
    """The speed scale at path parameters ``s`` (shape (n,), from 0 to ``S = s[-1]``) of a rest-to-rest piece with
    path acceleration ``alpha`` (1/s^2) and top speed scale ``peak``; 0 at both ends."""
    s = np.asarray(s, dtype=float)
    S = s[-1]
    v = np.minimum(np.sqrt(2.0 * alpha * np.maximum(s, 0.0)), np.sqrt(2.0 * alpha * np.maximum(S - s, 0.0)))
    v = np.minimum(v, peak)
    v[0] = v[-1] = 0.0
    return v


def _durations(s, v) -> np.ndarray:
    """Each interval's duration (s) under the rule: ``2 ds / (v_k + v_{k+1})``."""
    return 2.0 * np.diff(s) / (v[:-1] + v[1:])


def _slide(task, ph):
    """``(t from 0, speed scale, qd, alpha, peak, binding)`` of a slide."""
    dyn = task_dynamics(task)
    s = ph.t - ph.t[0]
    rates = np.nan_to_num(ph.qd)  # the quasistatic velocity commands (the effort joint: none)
    moving = np.any(rates != 0, axis=0)
    limits = dyn.joint_accelerations
    names = task.hand.joint_names
    cands = {"workpiece_acceleration": dyn.workpiece_acceleration / abs(ph.speed)}
    if ph.pose is not None:  # a turning workpiece: its angular acceleration too (Dynamics.angular_acceleration)
        turn = np.max(np.abs(np.diff(ph.pose[:, 2])) / np.diff(s), initial=0.0)
        if turn > 0:
            cands["workpiece_acceleration (turning)"] = dyn.angular_acceleration(task.hand) / turn
    for j in np.flatnonzero(moving):
        cands[f"joint_acceleration.{names[j]}"] = limits[j] / np.max(np.abs(rates[:, j]))
    binding = min(cands, key=cands.get)
    alpha, peak = cands[binding], 1.0
    for _ in range(SCALE_ITERATIONS):  # the path's curvature: a command changes between rows at cruise too
        v = piece_scale(s, alpha, peak)
        dt = _durations(s, v)
        qd = rates * v[:, None]
        excess = np.max(np.abs(np.diff(qd, axis=0)) / dt[:, None] / limits[None, :], initial=0.0)
        if excess <= 1.0:
            break
        alpha, peak = alpha / excess, peak / np.sqrt(excess)
        binding = "joint_acceleration (the path's curvature)"
    qd = np.where(np.isnan(ph.qd), np.nan, qd)
    return np.concatenate([[0.0], np.cumsum(dt)]), v, qd, alpha, peak, binding


def _rest_bands(task, ph):
    """``ph``'s band, command and margin with its rows at rest judged for the motion that leaves or reaches them.

    A row at rest has no velocity; the certifier judges it for the straight line to the adjacent row, the motion the
    controller makes there (:func:`qsplan.planner.certify.timing.row_velocity`).  The planner's band at that row is
    for the path's tangent; both motions pass the row, so the band kept is their intersection, and the commands
    are chosen again by the slide's rule (:func:`qsplan.planner.torque.command.plan_command`).  With one
    velocity-controlled joint the two directions agree (same sign): nothing changes.  At the instant of rest itself
    the command must hold the workpiece still (:func:`_rest_holds`).
    """
    from qsplan.mechanics.bands.batched_robust import robust_bands
    from qsplan.mechanics.errors import QsplanError
    from qsplan.planner.torque.command import plan_command

    names = task.hand.joint_names
    effort = np.array(names) == ph.effort_joint
    lower, upper = ph.lower.copy(), ph.upper.copy()
    scenes = []
    for k, (a, b) in ((0, (0, 1)), (ph.t.size - 1, (ph.t.size - 2, ph.t.size - 1))):
        chord = (ph.q[b] - ph.q[a]) / (ph.t[b] - ph.t[a])  # the rows' quasistatic times: a velocity at speed scale 1
        scenes.append((k, rest_scene(task, ph, k, a if k == b else b, effort, np.where(effort, 0.0, chord))))
    bands = robust_bands([sc for _, sc in scenes], ph.mode, task.mu_range, shared=task.shared_mu,
                         force_margin=task.force_margin, disturbance=task.disturbance)  # fmt: skip
    for (k, _), rb in zip(scenes, bands):
        if not rb.feasible:
            raise QsplanError(f"plan: {ph.name}: no guaranteed band at rest at x = {ph.x[k]:.6g} m for the motion "
                              f"leaving or reaching it ({rb.reason})")  # fmt: skip
        lower[k], upper[k] = max(lower[k], rb.lower), min(upper[k], rb.upper)
    if np.array_equal(lower, ph.lower) and np.array_equal(upper, ph.upper):
        out = ph.lower, ph.upper, ph.command, ph.margin
    else:
        out = (lower, upper, *plan_command(lower, upper, task.torque_resolution))
    return _rest_holds(task, ph, *out)


def _rest_holds(task, ph, lower, upper, command, margin):
    """``(lower, upper, command, margin)`` with each row at rest's command proved to hold there, as the certifier
    proves it (:func:`qsplan.planner.certify.timing.hold_checks`: every contact present, the other joints held,
    :func:`qsplan.hands.contacts.found.hold_scene`).  A command the hold is not proved at narrows that row's band to
    the proved interval (:func:`qsplan.mechanics.bands.hold.hold_torque_interval`, with the task's force margin) and
    the commands are chosen again; the rows whose holds are proved keep everything.

    Raises
    ------
    QsplanError
        No hold at least the torque resolution wide at a row at rest.
    """
    from qsplan.hands.contacts.found import hold_scene
    from qsplan.mechanics.bands.hold import hold_torque_interval, prove_hold
    from qsplan.mechanics.errors import QsplanError
    from qsplan.planner.torque.command import plan_command

    effort = np.array(task.hand.joint_names) == ph.effort_joint
    pose = ph.poses(task.hand.rest_height)
    narrowed = False
    for k in (0, ph.t.size - 1):
        scene = hold_scene(task.hand, pose[k], ph.q[k], effort)
        if prove_hold(scene, torques=[command[k]], disturbance=task.disturbance).proved:
            continue
        lo, hi = hold_torque_interval(scene, task.disturbance, margin=task.force_margin.normal)
        lower, upper = lower.copy(), upper.copy()
        lower[k], upper[k] = np.maximum(lower[k], lo), np.minimum(upper[k], hi)  # nan (no hold) stays: refused below
        if not upper[k] - lower[k] >= task.torque_resolution:
            raise QsplanError(f"plan: {ph.name}: at rest at x = {ph.x[k]:.6g} m no hold is proved inside the band "
                              f"(the hold's interval [{lo:.4g}, {hi:.4g}], every contact loaded by the force margin)")
        narrowed = True
    if not narrowed:
        return lower, upper, command, margin
    return (lower, upper, *plan_command(lower, upper, task.torque_resolution))


def rest_scene(task, ph, k, other, effort, velocity):
    """The scene of ``ph``'s row ``k`` at rest for the motion to or from row ``other``: the formation's closed form,
    or where the polygons show another contact set there (a slide's last row at the flush instant), every contact
    found but those the motion makes only at ``k`` (:func:`qsplan.hands.contacts.found.made_contacts`)."""
    from qsplan.hands.contacts.found import made_contacts, ordered_contacts, row_contact_scene
    from qsplan.mechanics.errors import SceneError

    pose = ph.poses(task.hand.rest_height)
    try:
        return task.hand.scene(pose[k], ph.q[k], effort, velocity)
    except SceneError:
        found = ordered_contacts(task.hand, pose[k], ph.q[k])
        drop = made_contacts(task.hand, (pose[other], ph.q[other]), (pose[k], ph.q[k]), found) if other < k else None
        return row_contact_scene(task.hand, pose[k], ph.q[k], effort, velocity, drop=drop, found=found)


def _leg(task, qa, qb, limits, what):
    """A regrasp leg from ``qa`` to ``qb`` at rest at both ends, each joint's acceleration within ``limits``
    (``what`` names them): ``(q rows after qa, speed scales, durations, rate, alpha, peak, binding)``."""
    dq = qb - qa
    S = float(np.max(np.abs(dq) / task.joint_speeds))  # quasistatic duration: the slowest joint at its limit
    rate = dq / S
    names = task.hand.joint_names
    cands = {f"{what}.{names[j]}": limits[j] / abs(rate[j]) for j in np.flatnonzero(rate)}
    binding = min(cands, key=cands.get)
    alpha = cands[binding]
    ramp = 1.0 / (2.0 * alpha)  # s covered from rest to the quasistatic speed
    s = np.array([0.0, ramp, S - ramp, S]) if S > 2.0 * ramp else np.array([0.0, 0.5 * S, S])  # where ramps end
    v = piece_scale(s, alpha)
    peak = float(v.max())
    q = qa[None, :] + (s[1:, None] / S) * dq[None, :]
    q[-1] = qb  # exactly the planned row
    return q, v[1:], _durations(s, v), rate, alpha, peak, binding


def _regrasp(task, ph):
    """``(t from 0, q, speed scale, qd, pieces, alpha, peak, binding)`` of a regrasp."""
    dyn = task_dynamics(task)
    q, v, t, qd = [ph.q[0]], [0.0], [0.0], [np.zeros(ph.q.shape[1])]
    alphas, peaks, bind = [], [], []
    legs = [(qa, qb) for qa, qb in zip(ph.q[:-1], ph.q[1:]) if not np.array_equal(qa, qb)]
    for i, (qa, qb) in enumerate(legs):
        touching = i in (0, len(legs) - 1)  # the legs that leave and reach the workpiece: gently
        limits = dyn.release_accelerations if touching else dyn.joint_accelerations
        what = "release_acceleration" if touching else "joint_acceleration"
        rows, vs, dts, rate, alpha, peak, binding = _leg(task, qa, qb, limits, what)
        q += list(rows)
        v += list(vs)
        t += list(t[-1] + np.cumsum(dts))
        qd += [rate * vk for vk in vs]
        alphas.append(alpha), peaks.append(peak), bind.append(binding)
    k = int(np.argmax(alphas)) if alphas else 0
    return (np.array(t), np.array(q), np.array(v), np.array(qd), len(alphas), max(alphas, default=0.0),
            max(peaks, default=0.0), bind[k] if bind else "none")  # fmt: skip


def time_scale(plan):
    """The plan with every phase starting and ending at rest, within the task's acceleration limits (the rule:
    the module docstring); its :attr:`~qsplan.planner.plan.results.Plan.timing` says each phase's scaling."""
    task = plan.task
    phases, timing, t0 = [], [], 0.0
    for ph in plan.phases:
        T = float(ph.t[-1] - ph.t[0])
        if ph.in_contact and not ph.moves:  # a hold: nothing moves, the rows keep their ramp's times
            t, v = ph.t - ph.t[0], np.zeros(ph.t.size)
            new = replace(ph, t=t0 + t, speed_scale=v)
            pieces, alpha, peak, binding = 0, 0.0, 0.0, "none (a hold: nothing moves)"
        elif ph.in_contact:
            # a slide's rows at rest are judged again for the chord that leaves or reaches them; a pivot's already are
            lower, upper, command, margin = ((ph.lower, ph.upper, ph.command, ph.margin) if ph.rest_rows_judged
                                             else _rest_bands(task, ph))  # fmt: skip
            t, v, qd, alpha, peak, binding = _slide(task, ph)
            new = replace(ph, t=t0 + t, qd=qd, speed_scale=v, lower=lower, upper=upper, command=command, margin=margin)
            pieces = 1
        else:
            t, q, v, qd, pieces, alpha, peak, binding = _regrasp(task, ph)
            new = replace(ph, t=t0 + t, q=q, qd=qd, speed_scale=v)
        phases.append(new)
        # the record states what the rows realise (alpha, peak: the rule's parameters; the path they cover)
        if np.any(v > 0):
            T = path_covered(t, v)
        timing.append(PhaseTiming(ph.name, pieces, scale_rate(t, v), float(np.max(v, initial=0.0)), float(t[-1]), T,
                                  binding))  # fmt: skip
        t0 = float(new.t[-1])
    return replace(plan, phases=tuple(phases), timing=tuple(timing))


def path_covered(t, u) -> float:
    """The path parameter (s, quasistatic seconds) rows at times ``t`` with speed scales ``u`` cover by the rule: ``u``
    linear in time between rows, ``sum (u_k + u_{k+1}) dt / 2``.  A regrasp's legs cover each the slowest joint's
    quasistatic time, whatever times its OMPL path had."""
    t, u = np.asarray(t, dtype=float), np.asarray(u, dtype=float)
    return float(np.sum(0.5 * (u[:-1] + u[1:]) * np.diff(t)))


def scale_rate(t, u) -> float:
    """The largest change of the speed scale ``u`` per second between two rows at times ``t`` (s; 1/s^2): by the rule
    it changes linearly in time between rows (0 for fewer than two rows at distinct times)."""
    dt, du = np.diff(np.asarray(t, dtype=float)), np.diff(np.asarray(u, dtype=float))
    return float(np.max(np.abs(du[dt > 0]) / dt[dt > 0], initial=0.0))


def quasistatic_rows(t, u, q, qd):
    """A phase's rows back at quasistatic speed, the inverse of the time scaling: ``(s, qd_s)``, the path parameter
    at each row (s, from 0; ``ds = dt (u_k + u_{k+1}) / 2``) and the velocity commands at speed scale 1 (``qd / u``;
    at a row at rest, the straight line to the adjacent row per unit of ``s``).  The quasistatic model is
    homogeneous in the velocity input, so a replay along ``s`` follows the same path as one along ``t``.

    Parameters
    ----------
    t, u : ndarray, shape (n,)
        Times (s) and speed scales of the rows (``u`` all 1: the rows are already quasistatic).
    q, qd : ndarray, shape (n, n_j)
        Positions and velocity commands (nan: torque-controlled).
    """
    t, u = np.asarray(t, float), np.asarray(u, float)
    q, qd = np.asarray(q, float), np.asarray(qd, float)
    if t.size < 2:
        return t - t[0], qd.copy()
    s = np.concatenate([[0.0], np.cumsum(np.diff(t) * 0.5 * (u[:-1] + u[1:]))])
    out = np.empty_like(qd)
    moving = u > 0
    out[moving] = qd[moving] / u[moving, None]
    for k in np.flatnonzero(~moving):
        a, b = (k, k + 1) if k + 1 < t.size else (k - 1, k)
        out[k] = (q[b] - q[a]) / (s[b] - s[a]) if s[b] > s[a] else 0.0
    return s, np.where(np.isnan(qd), np.nan, out)
