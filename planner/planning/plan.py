"""Two-finger manipulation plans with guaranteed torque bands, regrasps through OMPL (Section 5.2, Figs. 9-13).

:func:`plan_task` turns a :class:`qsplan.planner.planning.task.Task` into a :class:`Plan`:

1. **In-contact segments.**  Segment ``i`` slides the workpiece along the palm from
   the previous waypoint to the next in mode 4S (``"SSSS"``); its configuration
   variable is the workpiece's ``x`` alone (the fingers follow by tangency,
   :func:`qsplan.hands.two_finger.finger_angles`), so the only path is the straight line
   and there is nothing to search: no OMPL here.  The line is swept every
   :data:`SWEEP_STEP` and every sample judged once with the validity conditions of
   :func:`check_contact_state`: no two bodies overlapping (every pair of fingers, palm
   and workpiece: :mod:`qsplan.planner.planning.collision`), the same four contacts as at
   the segment's start and the 4S kinematics possible (eqs. 24-25), joints inside their
   limits, and a guaranteed band (desired mode feasible for the whole friction set, every
   competing mode precluded: :func:`qsplan.planner.torque.pointwise.guaranteed_sweep`) at
   least ``torque_resolution`` wide; the first invalid sample ends the segment with a
   :class:`qsplan.planner.planning.failure.FailureReport`.  The effort-controlled finger is
   derived: among the joint sets the control-mode partitioner admits for 4S (eq. 32), the
   one whose narrowest band along the straight line is widest.
2. **Regrasps.**  Between segments both fingers open by :data:`REGRASP_OPENING` and
   close again on the workpiece, planned by OMPL in joint space (two variables: the search that
   ``--planner`` and ``--time-limit`` choose), collision-free
   (:func:`check_free_state`: the fingers clear the workpiece, the palm and each
   other; the straight lines between OMPL's states checked again every :data:`SWEEP_STEP`
   at the fingertips).  Assumed: the workpiece rests on the palm meanwhile (its centre of
   mass lies over its bottom edge, checked by :func:`qsplan.planner.planning.task.make_task`) and
   a quasistatic release leaves it where it is.
3. **From path to plan.**  Each segment's dense sweep is
   time-parameterized at the largest constant speed within the workpiece and joint
   speed limits, and each command is chosen in the guaranteed band with the largest
   margin that can be kept along the whole segment: half its narrowest band, from
   both edges (:func:`qsplan.planner.torque.command.choose_command` with ``max_margin`` = that
   half-width).  So the command is the midpoint where the band is narrowest and
   ``lower + margin`` elsewhere: continuous, and close to the torque the mode needs
   (the pointwise midpoint runs to many times that torque where the upper edge
   blows up, and jumps where it becomes infinite).  A command outside its band is
   never emitted (:func:`Plan.check` raises).

Before any of this the fixed configurations are checked (:func:`check_configurations`: the
grasps at the start and every waypoint, the opened fingers of every regrasp), so an invalid
start or goal is refused at once with a report naming the colliding bodies or the joint.
When a segment has no path, :class:`PlanFailure` carries a
:class:`qsplan.planner.planning.failure.FailureReport`: where the band closes, which
competitor closes it, the friction at which it does.  Units SI (m, rad, s, N m).
"""

from __future__ import annotations

import time

import numpy as np

from qsplan.mechanics.errors import NoAnswerError, QsplanError

from qsplan.planner.planning.contact_state import (
    MODE,
    TOUCH_AREA,
    check_contact_state,
    check_free_state,
    configuration_problem,
    contact_samples,
    free_state_problem,
    hand_scene_at,
)
from qsplan.planner.planning.failure import configuration_report, failure_report
from qsplan.planner.planning.ompl_bridge import PlannerOptions, plan_path
from qsplan.planner.planning.results import ContactSegmentPlan, Plan, PlanFailure, RegraspPlan, StateCheck
from qsplan.planner.planning.task import Task

__all__ = [
    "DEFAULT_OPTIONS",
    "MODE",
    "REGRASP_OPENING",
    "SWEEP_STEP",
    "TOUCH_AREA",
    "ContactSegmentPlan",
    "Plan",
    "PlanFailure",
    "RegraspPlan",
    "StateCheck",
    "check_configurations",
    "check_contact_state",
    "check_free_state",
    "contact_samples",
    "plan_task",
    "sweep_contact_segment",
]


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


# ---------------------------------------------------------------------------------------------- planning


def _segment_name(i, x0, x1):
    return f"segment {i + 1}: slide the workpiece {'left' if x1 < x0 else 'right'} from x = {x0:.4g} to {x1:.4g} m"


def check_configurations(task: Task) -> None:
    """Check the task's fixed configurations before planning (milliseconds): the grasp at the start and at
    every waypoint (joint limits, no two bodies overlapping) and the opened fingers of every regrasp.

    Raises
    ------
    PlanFailure
        With a :class:`qsplan.planner.planning.failure.ConfigurationReport` naming the configuration, the
        colliding bodies and their overlap, or the joint beyond its limit.
    """
    from qsplan.hands.two_finger import finger_angles

    xs = [task.start_x, *task.waypoints.tolist()]
    last = len(xs) - 1
    for i, x in enumerate(xs):
        seg = _segment_name(max(i - 1, 0), xs[max(i - 1, 0)], xs[max(i - 1, 0) + 1])
        where = "the start" if i == 0 else ("the goal" if i == last else f"the end of segment {i}")
        try:
            q = finger_angles(task.hand, task.pose(x))[0]
        except QsplanError as exc:
            report = configuration_report(task, seg, where, x, None, f"no four-contact grasp: {exc}")
            raise PlanFailure(report) from None
        if configuration_problem(task, task.pose(x), q):
            raise PlanFailure(configuration_report(task, seg, where, x, q))
        if 0 < i < last:
            q_open = q + np.array([REGRASP_OPENING, -REGRASP_OPENING])
            if free_state_problem(task, x, q_open):
                name = f"regrasp {i}: both fingers release and regrasp at x = {x:.4g} m"
                raise PlanFailure(configuration_report(task, name, f"the opened fingers of regrasp {i}", x, q_open))


def _effort_joint(task, x0, x1, progress):
    """The effort-controlled finger of a segment: admitted by the partitioner (eq. 32), widest narrowest band."""
    from qsplan.hands.two_finger import JOINT_NAMES
    from qsplan.mechanics.modes.contact_mode import ContactMode
    from qsplan.mechanics.modes.partition import effort_partitions

    d = np.sign(x1 - x0)
    xs = np.linspace(x0, x1, 7)
    try:
        scene = hand_scene_at(task, x0, "right", 0.0)[3]
        admitted = {JOINT_NAMES[p.effort_joints[0]] for p in effort_partitions(scene, ContactMode(MODE))
                    if len(p.effort_joints) == 1}  # fmt: skip
    except QsplanError:
        admitted = set(JOINT_NAMES)
    best, best_w = None, -np.inf
    for joint in JOINT_NAMES:
        if joint not in admitted:
            continue
        w = [check_contact_state(task, x, joint, d) for x in xs]
        worst = min((c.width if np.isfinite(c.width) else -np.inf) for c in w)
        if worst > best_w:
            best, best_w = joint, worst
    return best or "right"


def _densify(path_x, step):
    xs = [path_x[:1]]
    for a, b in zip(path_x[:-1], path_x[1:]):
        n = max(1, int(np.ceil(abs(b - a) / step)))
        xs.append(np.linspace(a, b, n + 1)[1:])
    return np.concatenate(xs)


def _densify_rows(path, step):
    """``path`` (n, d) with states added on each straight edge, at most ``step`` apart in every coordinate."""
    out = [path[:1]]
    for a, b in zip(path[:-1], path[1:]):
        n = max(1, int(np.ceil(np.max(np.abs(b - a)) / step)))
        out.append(a + np.linspace(0.0, 1.0, n + 1)[1:, None] * (b - a))
    return np.vstack(out)


def _straight_path(x0, x1):
    """The segment's path: the straight line ``[x0, x1]`` (shape (2, 1)), computed as OMPL's straight line was."""
    start, goal = np.array([x0], float), np.array([x1], float)
    return start + np.linspace(0.0, 1.0, 2)[:, None] * (goal - start)


def sweep_contact_segment(task, name, x, effort, direction, touching, comps):
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
        S = contact_samples(task, x, effort, direction)
    except QsplanError:  # no grasp somewhere: the first sample without one
        k = next((k for k, xk in enumerate(x) if not check_contact_state(task, xk, effort, direction, touching, comps).ok), 0)
        return k, None, None, None
    rate = np.max(np.abs(S.qd))
    speed = min(task.workpiece_speed, task.joint_speed / rate) if rate > 0 else task.workpiece_speed
    S = contact_samples(task, x, effort, direction * speed, name)
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


def _segment(task, i, x0, x1, t0, options, progress, counters):
    from qsplan.hands.two_finger import finger_angles
    from qsplan.planner.planning.ompl_bridge import PlanResult
    from qsplan.planner.torque.sweep import competing_modes
    from qsplan.planner.torque.command import choose_command, default_safety_margin

    name = _segment_name(i, x0, x1)
    direction = float(np.sign(x1 - x0))
    effort = _effort_joint(task, x0, x1, progress)
    progress(f"{name}: effort-controlled finger {effort}; one configuration variable: checking the straight line "
             f"every {SWEEP_STEP * 1e3:g} mm (no search)")  # fmt: skip
    try:
        line = contact_samples(task, np.linspace(x0, x1, 9), effort, direction * task.workpiece_speed)
    except QsplanError as exc:
        raise PlanFailure(configuration_report(task, name, "the straight line of the segment", x0, None,
                                               f"no four-contact grasp: {exc}")) from None  # fmt: skip
    comps = competing_modes(line)
    touching = line.touching[0]
    for x_end, where in ((x0, "the start of the segment"), (x1, "its goal")):
        c = check_contact_state(task, x_end, effort, direction, touching, comps)
        if c.ok:
            continue
        if not c.reason.startswith(("band", "no guaranteed band")):  # refused for its geometry: named here
            try:
                q_end = finger_angles(task.hand, task.pose(x_end))[0]
            except QsplanError:
                q_end = None
            raise PlanFailure(configuration_report(task, name, where, x_end, q_end, c.reason))
        raise PlanFailure(failure_report(task, name, x0, x1, effort, direction, comps, None))  # for its band
    # the configuration is the workpiece's x alone (the fingers follow by tangency): the only path is the
    # straight line, and its dense sweep is the whole check (where OMPL used to return this line after ~100
    # checks at 0.8 mm, followed by this sweep)
    path = _straight_path(x0, x1)
    x = _densify(path[:, 0], SWEEP_STEP)
    t_check = time.perf_counter()
    k, S, band, speed = sweep_contact_segment(task, name, x, effort, direction, touching, comps)
    seconds = time.perf_counter() - t_check
    counters[0] += len(x) if k is None else k + 1
    counters[1] += seconds
    if k is not None:
        why = check_contact_state(task, x[k], effort, direction, touching, comps).reason or "band narrower than the resolution"
        status = f"dense sweep: state {k + 1} of {len(x)} invalid, at x = {x[k]:.4g} m: {why}"
        res = PlanResult(path[:k + 1], False, status, k + 1, seconds, options)
        raise PlanFailure(failure_report(task, name, x0, x1, effort, direction, comps, res))
    res = PlanResult(path, True, f"dense sweep: all {len(x)} states valid", len(x), seconds, options)
    progress(f"  {res.status} (overlaps, limits, contacts, 4S kinematics, guaranteed band) in {seconds:.2f} s")
    try:
        safety = default_safety_margin(band)
    except NoAnswerError:  # unbounded everywhere: keep the controller's resolution from the finite edge
        safety = task.torque_resolution
    command, margin = choose_command(band.lower, band.upper, safety, max_margin=safety)
    s = np.concatenate([[0.0], np.cumsum(np.abs(np.diff(x)))])
    v = 1 - (0 if effort == "left" else 1)
    qd = S.qd.copy()
    qd[:, 1 - v] = np.nan  # the effort-controlled joint gets no velocity command
    return ContactSegmentPlan(name, effort, MODE, path[:, 0].copy(), t0 + s / speed, x, S.q.copy(), qd,
                              band.lower.copy(), band.upper.copy(), command, margin, comps, speed, res)  # fmt: skip


def _regrasp(task, i, x, q, t0, options, progress, counters):
    name = f"regrasp {i + 1}: both fingers release and regrasp at x = {x:.4g} m"
    progress(name)
    q = np.asarray(q, float)
    q_open = q + np.array([REGRASP_OPENING, -REGRASP_OPENING])  # the left finger opens counter-clockwise
    lim = task.joint_limits
    results, path = [], [q[None, :]]
    for a, b, what in ((q, q_open, "the opening"), (q_open, q, "the closing")):
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
    dense = _densify_rows(path, SWEEP_STEP / task.hand.finger_length)
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


def plan_task(task: Task, options: PlannerOptions | None = None, progress=None) -> Plan:
    """Plan ``task``: in-contact segments through OMPL with guaranteed bands, and regrasps between them.

    Parameters
    ----------
    task : qsplan.planner.planning.task.Task
    options : PlannerOptions, optional
        Default :data:`DEFAULT_OPTIONS`.
    progress : callable, optional
        ``progress(line)`` for progress messages.

    Returns
    -------
    Plan
        Checked: every command inside its band.

    Raises
    ------
    PlanFailure
        When a segment has no plan, with the report of where and why (a :class:`qsplan.mechanics.NoAnswerError`);
        when a start, goal or regrasp configuration is not valid (checked first, before OMPL runs: two bodies
        overlap, a joint beyond its limit), or no collision-free regrasp is found, with a
        :class:`qsplan.planner.planning.failure.ConfigurationReport` naming it.
    """
    if options is None:
        options = DEFAULT_OPTIONS
    progress = progress or (lambda line: None)
    t_start = time.perf_counter()
    check_configurations(task)
    counters = [0, 0.0]
    phases, t0 = [], 0.0
    xs = [task.start_x, *task.waypoints.tolist()]
    for i, (x0, x1) in enumerate(zip(xs[:-1], xs[1:])):
        if i:
            prev = phases[-1]
            phases.append(_regrasp(task, i - 1, x0, prev.q[-1], t0, options, progress, counters))
            t0 = float(phases[-1].t[-1])
        seg = _segment(task, i, x0, x1, t0, options, progress, counters)
        phases.append(seg)
        t0 = float(seg.t[-1])
    plan = Plan(task, tuple(phases), time.perf_counter() - t_start, counters[0], counters[1], options)
    plan.check()
    return plan
