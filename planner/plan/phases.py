"""The two kinds of phase of a two-finger plan: in-contact 4S slides and regrasps (Section 5.2, Fig. 9).

:func:`slide_phase` judges every sample of a slide (the dense sweep, :func:`sweep_contact_segment`) and chooses
its commands; :func:`regrasp_phase` plans the fingers' release, move and re-closing through OMPL.  Both serve the
scripted sequence (:func:`qsplan.planner.plan.scripted.plan_task`) and the sequence the planner finds
(:mod:`qsplan.planner.plan.autoplan`); a ``grasp`` (:class:`qsplan.hands.grasps.Grasp`) says which features the
fingers touch (default both inner edges, as the scripted tasks).  Units SI (m, rad, s, N m).
"""

from __future__ import annotations

import time

import numpy as np

from qsplan.mechanics.errors import NoAnswerError, QsplanError

from qsplan.planner.plan.failure import configuration_report, failure_report
from qsplan.planner.plan.results import ContactSegmentPlan, PlanFailure, RegraspPlan
from qsplan.planner.search.ompl_bridge import PlannerOptions, plan_path
from qsplan.planner.states.contact import MODE, check_contact_state, check_free_state, configuration_problem, contact_samples, free_state_problem

__all__ = ["DEFAULT_OPTIONS", "REGRASP_OPENING", "SWEEP_STEP", "densify", "densify_rows", "regrasp_phase", "slide_phase", "straight_path",
           "sweep_contact_segment"]

#: Angle (rad) each finger opens by to release the workpiece between segments: about 1.5 cm
#: at the tip of a 0.16 m finger, clear of the workpiece's corners.
REGRASP_OPENING = 0.1

#: Distance (m) between the samples of the dense band sweep of a segment (0.5 mm: 80 per 4 cm).
SWEEP_STEP = 5e-4

#: The regrasps' OMPL queries (in-contact segments need no search): RRTConnect, deterministic, seed 1;
#: edges checked every 2 % of the joint box, then the exported lines every SWEEP_STEP at the fingertips.
#: The iteration budget decides (same inputs, same plan); the time limit per OMPL query (s) is a
#: safety net well above the few seconds a query takes, so a loaded machine does not change the answer.
DEFAULT_OPTIONS = PlannerOptions(validity_resolution=0.02, iterations=2_000, time_limit=120.0)


def densify(path_x, step):
    """``path_x`` (m, shape (k,)) with points added on each piece, at most ``step`` apart."""
    xs = [path_x[:1]]
    for a, b in zip(path_x[:-1], path_x[1:]):
        n = max(1, int(np.ceil(abs(b - a) / step)))
        xs.append(np.linspace(a, b, n + 1)[1:])
    return np.concatenate(xs)


def densify_rows(path, step):
    """``path`` (n, d) with states added on each straight edge, at most ``step`` apart in every coordinate."""
    out = [path[:1]]
    for a, b in zip(path[:-1], path[1:]):
        n = max(1, int(np.ceil(np.max(np.abs(b - a)) / step)))
        out.append(a + np.linspace(0.0, 1.0, n + 1)[1:, None] * (b - a))
    return np.vstack(out)


def straight_path(x0, x1):
    """The segment's path: the straight line ``[x0, x1]`` (shape (2, 1)), its ends exactly ``x0`` and ``x1`` (the goal
    is reached exactly, not ``x0 + (x1 - x0)`` rounded)."""
    return np.array([[x0], [x1]], dtype=float)


def sweep_contact_segment(task, name, x, effort, direction, touching, comps, grasp=None):
    """Judge every sample of an in-contact segment once, with the validity conditions of
    :func:`check_contact_state` (the same contacts, no overlap, joint limits, 4S kinematics, a guaranteed band
    at least ``task.torque_resolution`` wide), the band batched over the samples as the plan needs it anyway.

    Parameters
    ----------
    task : Task
    name : str
        The segment's name (for messages).
    x : ndarray, shape (n,)
        Workpiece x of the samples (m), in the order of motion.
    effort : str
        The effort-controlled finger, ``"left"`` or ``"right"``.
    direction : float
        Sign of the workpiece's velocity.
    touching : ndarray, shape (2,)
        The workpiece vertices the fingertips touch at the segment's start (a change is invalid).
    comps : tuple of str
        The competing modes to preclude (:func:`qsplan.planner.torque.sweep.competing_modes`).
    grasp : qsplan.hands.grasps.Grasp, optional
        The features the fingers touch (default: both inner edges, the scripted tasks).

    Returns
    -------
    k : int or None
        Index of the first invalid sample (the first ``k`` where :func:`check_contact_state` is not ok), or None.
    samples : qsplan.hands.segments.SegmentSamples or None
        When every sample is valid: the samples moving at ``speed``.
    band : qsplan.mechanics.bands.effort.Band or None
        Their guaranteed band (N m), competitors precluded.
    speed : float or None
        Workpiece speed (m/s): the fastest within the workpiece and joint speed limits.
    """
    from qsplan.mechanics.bands.effort import band_kinematics
    from qsplan.mechanics.modes.contact_mode import ContactMode

    from qsplan.planner.torque.pointwise import guaranteed_sweep

    try:
        S = contact_samples(task, x, effort, direction, grasp=grasp)
    except QsplanError:  # no grasp somewhere: the first sample without one
        k = next((k for k, xk in enumerate(x)
                  if not check_contact_state(task, xk, effort, direction, touching, comps, grasp).ok), 0)  # fmt: skip
        return k, None, None, None
    rate = np.max(np.abs(S.qd))
    speed = min(task.workpiece_speed, task.joint_speed / rate) if rate > 0 else task.workpiece_speed
    S = contact_samples(task, x, effort, direction * speed, name, grasp=grasp)
    mode = ContactMode(MODE)
    for k in range(len(x)):
        if (np.any(S.touching[k] != touching) or configuration_problem(task, S.pose[k], S.q[k])
                or not band_kinematics(S.scenes[k], mode).ok):  # fmt: skip
            return k, None, None, None
    band = guaranteed_sweep(S, task.mu_range, task.shared_mu, MODE, comps, force_margin=task.force_margin).band
    bad = ~np.asarray(band.feasible) | (band.upper - band.lower < task.torque_resolution)
    if bad.any():
        return int(np.argmax(bad)), None, None, None
    return None, S, band, float(speed)


def slide_phase(task, name, x0, x1, effort, direction, touching, comps, t0, options, progress, counters,
                grasp=None) -> ContactSegmentPlan:  # fmt: skip
    """The in-contact phase sliding the workpiece from ``x0`` to ``x1`` (m) in 4S: the dense sweep judges every
    sample (:func:`sweep_contact_segment`), then the commands are chosen (the largest margin kept along the
    whole segment, :func:`qsplan.planner.torque.command.choose_command`).

    Raises
    ------
    PlanFailure
        With a :func:`qsplan.planner.plan.failure.failure_report` of the first invalid sample.
    """
    from qsplan.planner.search.ompl_bridge import PlanResult
    from qsplan.planner.torque.command import choose_command, default_safety_margin

    # the configuration is the workpiece's x alone (the fingers follow the grasp's closed form): the only path
    # is the straight line, and its dense sweep is the whole check
    path = straight_path(x0, x1)
    x = densify(path[:, 0], SWEEP_STEP)
    t_check = time.perf_counter()
    k, S, band, speed = sweep_contact_segment(task, name, x, effort, direction, touching, comps, grasp)
    seconds = time.perf_counter() - t_check
    counters[0] += len(x) if k is None else k + 1
    counters[1] += seconds
    if k is not None:
        why = check_contact_state(task, x[k], effort, direction, touching, comps, grasp).reason or "band narrower than the resolution"
        status = f"dense sweep: state {k + 1} of {len(x)} invalid, at x = {x[k]:.4g} m: {why}"
        res = PlanResult(path[:k + 1], False, status, k + 1, seconds, options)
        raise PlanFailure(failure_report(task, name, x0, x1, effort, direction, comps, res, grasp=grasp))
    res = PlanResult(path, True, f"dense sweep: all {len(x)} states valid", len(x), seconds, options)
    progress(f"  {res.status} (overlaps, limits, contacts, 4S kinematics, guaranteed band) in {seconds:.2f} s")
    try:
        safety = default_safety_margin(band, task.torque_resolution)
    except NoAnswerError:  # unbounded everywhere: keep the controller's resolution from the finite edge
        safety = task.torque_resolution
    command, margin = choose_command(band.lower, band.upper, safety, max_margin=safety)
    s = np.concatenate([[0.0], np.cumsum(np.abs(np.diff(x)))])
    v = 1 - (0 if effort == "left" else 1)
    qd = S.qd.copy()
    qd[:, 1 - v] = np.nan  # the effort-controlled joint gets no velocity command
    return ContactSegmentPlan(name, effort, MODE, path[:, 0].copy(), t0 + s / speed, x, S.q.copy(), qd,
                              band.lower.copy(), band.upper.copy(), command, margin, comps, speed, res)  # fmt: skip




def regrasp_phase(task, name, x, q_from, q_to, t0, options, progress, counters, opening_from=(1.0, -1.0),
                  opening_to=(1.0, -1.0)) -> RegraspPlan:  # fmt: skip
    """Both fingers release the workpiece at ``x`` (m) from joints ``q_from`` and close on it at ``q_to`` (rad,
    shape (2,)), through OMPL in joint space: each finger opens by :data:`REGRASP_OPENING` in the direction
    ``opening_from`` (the sign of the joint rate that moves its contact out of the workpiece; the default is the
    inner edges': the left finger counter-clockwise), moves to the opened ``q_to`` and closes; the workpiece
    rests on the palm meanwhile.  Every leg is collision-free (:func:`check_free_state`), and the straight lines
    between OMPL's states are checked again every :data:`SWEEP_STEP` at the fingertips.

    Raises
    ------
    PlanFailure
        With a :class:`qsplan.planner.plan.failure.ConfigurationReport` naming the leg and what blocks it.
    """
    progress(name)
    q, q_to = np.asarray(q_from, float), np.asarray(q_to, float)
    q_open = q + REGRASP_OPENING * np.asarray(opening_from, float)
    q_to_open = q_to + REGRASP_OPENING * np.asarray(opening_to, float)
    lim = task.joint_limits
    results, path = [], [q[None, :]]
    legs = [(q, q_open, "the opening"), (q_open, q_to_open, "the move to the new grasp"), (q_to_open, q_to, "the closing")]
    if np.array_equal(q_open, q_to_open):  # the same grasp again: open and close
        legs = [legs[0], (q_open, q_to, "the closing")]
    for a, b, what in legs:
        res = plan_path(lim[:, 0], lim[:, 1], a, b, lambda s: check_free_state(task, x, s), options)
        counters[0] += res.validity_checks
        counters[1] += res.seconds
        progress(f"  OMPL: {what} of the fingers: {res.status}, {len(res.path)} states, "
                 f"{res.validity_checks} validity checks in {res.seconds:.2f} s")  # fmt: skip
        if not res.exact:
            raise PlanFailure(configuration_report(task, name, f"{what} of the fingers", x, b,
                                                   f"OMPL found no collision-free finger motion ({res.status})",
                                                   res.status))  # fmt: skip
        results.append(res)
        path.append(res.path[1:])
    path = np.vstack(path)
    # OMPL checked its edges at validity_resolution; the fingers move on straight lines between the rows
    # exported, so check those lines again every SWEEP_STEP at the fingertips
    dense = densify_rows(path, SWEEP_STEP / task.hand.finger_length)
    for qk in dense:
        why = free_state_problem(task, x, qk)
        if why:
            raise PlanFailure(configuration_report(task, name, "a state between OMPL's states", x, qk, why,
                                                   results[-1].status))  # fmt: skip
    steps = np.max(np.abs(np.diff(path, axis=0)), axis=1)
    t = t0 + np.concatenate([[0.0], np.cumsum(steps / task.joint_speed)])
    seg_qd = np.diff(path, axis=0) / np.maximum(np.diff(t), 1e-12)[:, None]
    qd = np.vstack([seg_qd, np.zeros((1, 2))])
    return RegraspPlan(name, float(x), t, path, qd, tuple(results))


