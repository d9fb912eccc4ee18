"""Two-finger manipulation plans with guaranteed torque bands, regrasps through OMPL (Section 5.2, Figs. 9-13).

:func:`plan_task` turns a :class:`qsplan.planner.task.task.Task` into a :class:`Plan`:

1. **In-contact segments.**  Segment ``i`` slides the workpiece along the palm from
   the previous waypoint to the next in the formation's mode (4S today); its configuration
   variable is the workpiece's ``x`` alone (the fingers follow by tangency,
   :func:`qsplan.hands.paper_hand.two_finger.finger_angles`), so the only path is the straight line
   and there is nothing to search: no OMPL here.  The line is swept every
   :data:`SWEEP_STEP` and every sample judged once with the validity conditions of
   :func:`check_contact_state`: no two bodies overlapping (every pair of fingers, palm
   and workpiece: :mod:`qsplan.hands.geometry.collision`), the same four contacts as at
   the segment's start and the 4S kinematics possible (eqs. 24-25), joints inside their
   limits, and a guaranteed band (desired mode feasible for the whole friction set, every
   competing mode precluded: :func:`qsplan.planner.torque.pointwise.guaranteed_sweep`) at
   least ``torque_resolution`` wide; the first invalid sample ends the segment with a
   :class:`qsplan.planner.plan.failure.FailureReport`.  The effort-controlled finger is
   derived: among the joint sets the control-mode partitioner admits for 4S (eq. 32), the
   one whose narrowest band along the straight line is widest.
2. **Regrasps.**  Between segments both fingers open by :data:`REGRASP_OPENING` and
   close again on the workpiece, planned by OMPL in joint space (two variables: the search that
   ``--planner`` and ``--time-limit`` choose), collision-free
   (:func:`check_free_state`: the fingers clear the workpiece, the palm and each
   other; the straight lines between OMPL's states checked again every :data:`SWEEP_STEP`
   at the fingertips).  Assumed: the workpiece rests on the palm meanwhile (its centre of
   mass lies over its bottom edge, checked by :func:`qsplan.planner.task.task.make_task`) and
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
:class:`qsplan.planner.plan.failure.FailureReport`: where the band closes, which
competitor closes it, the friction at which it does.  Units SI (m, rad, s, N m).
"""

from __future__ import annotations

import time

import numpy as np

from qsplan.mechanics.errors import QsplanError

from qsplan.planner.plan.failure import configuration_report, failure_report
from qsplan.planner.plan.phases import (DEFAULT_OPTIONS, REGRASP_OPENING, SWEEP_STEP, regrasp_phase, slide_phase,
                                        sweep_contact_segment)
from qsplan.planner.plan.results import ContactSegmentPlan, Plan, PlanFailure, RegraspPlan
from qsplan.planner.plan.release import release_holds
from qsplan.planner.plan.timing import time_scale
from qsplan.planner.task.goal import check_goal_served
from qsplan.planner.search.ompl_bridge import PlannerOptions
from qsplan.planner.states.contact import (
    TOUCH_AREA,
    StateCheck,
    check_contact_state,
    check_free_state,
    configuration_problem,
    contact_samples,
    free_state_problem,
)
from qsplan.planner.task.task import Task

__all__ = [
    "DEFAULT_OPTIONS",
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


# ---------------------------------------------------------------------------------------------- planning


def _segment_name(i, x0, x1):
    return f"segment {i + 1}: slide the workpiece {'left' if x1 < x0 else 'right'} from x = {x0:.4g} to {x1:.4g} m"


def _held(task):
    """A scripted task's free joints along every segment: the ``[start]`` ones held (None for a hand without free
    joints).

    Raises
    ------
    QsplanError
        A hand with free joints and no ``[start]``: scripted waypoints start from the joints the task names.
    """
    from qsplan.planner.plan.phases import FreePath

    hand = task.hand
    if not hand.free_joints:
        return None
    if task.start_joints is None:
        raise QsplanError(f"start: a scripted task (motion.waypoints) of a hand with free joints names them in [start] "
                          f"({', '.join(hand.joint_names[j] for j in hand.free_joints)}); or give a [goal] instead")  # fmt: skip
    free = list(hand.free_joints)
    return FreePath(float(task.start_x), np.asarray(task.start_joints, float)[free], np.zeros(len(hand.joint_names)),
                    tuple(free))  # fmt: skip


def _grasp_q(task, x, path):
    """The scripted grasp's joints at ``x`` (m), shape (n_j,) (the paper hand's tangency; any hand's closing)."""
    return task.hand.closed_configuration(task.formation, None, x, None if path is None else path.at([x])[0])


def _no_grasp_report(task, seg, where, x, path, exc):
    """The report of a grasp that does not close at ``x``: with the fingers fully open, the body that already overlaps
    the workpiece (:func:`qsplan.planner.plan.obstacles.open_overlap`), where one does."""
    from qsplan.planner.plan.failure import ConfigurationReport
    from qsplan.planner.plan.obstacles import open_overlap

    hand = task.hand
    q = np.full(len(hand.joint_names), np.nan)
    if path is not None:
        q[list(hand.free_joints)] = path.at([x])[0]
    q_open, hit = open_overlap(task, None, float(x), q)
    reason = f"no four-contact grasp: {exc}"
    if hit is None:
        return configuration_report(task, seg, where, x, None, reason)
    return ConfigurationReport(seg, where, float(x), tuple(float(v) for v in q_open),
                               f"{reason}; with the fingers fully open: {hit.message}", hit.bodies, hit.area, hit.depth)


def check_configurations(task: Task) -> None:
    """Check the task's fixed configurations before planning (milliseconds): the grasp at the start and at
    every waypoint (joint limits, no two bodies overlapping) and the opened fingers of every regrasp.

    Raises
    ------
    PlanFailure
        With a :class:`qsplan.planner.plan.failure.ConfigurationReport` naming the configuration, the
        colliding bodies and their overlap, or the joint beyond its limit.
    """
    from qsplan.planner.plan.phases import OPENING

    path = _held(task)
    xs = [task.start_x, *task.waypoints.tolist()]
    last = len(xs) - 1
    amount = np.array([OPENING[k] for k in task.hand.joint_kinds])
    for i, x in enumerate(xs):
        seg = _segment_name(max(i - 1, 0), xs[max(i - 1, 0)], xs[max(i - 1, 0) + 1])
        where = "the start" if i == 0 else ("the goal" if i == last else f"the end of segment {i}")
        try:
            q = _grasp_q(task, x, path)
        except QsplanError as exc:
            raise PlanFailure(_no_grasp_report(task, seg, where, x, path, exc)) from None
        if configuration_problem(task, task.pose(x), q):
            raise PlanFailure(configuration_report(task, seg, where, x, q))
        if 0 < i < last:
            q_open = q + amount * task.hand.opening(None, x, q)
            if free_state_problem(task, x, q_open):
                name = f"regrasp {i}: both fingers release and regrasp at x = {x:.4g} m"
                raise PlanFailure(configuration_report(task, name, f"the opened fingers of regrasp {i}", x, q_open))


def _effort_joint(task, x0, x1, progress, path):
    """The effort-controlled joint of a segment: admitted by the partitioner (eq. 32), widest narrowest band."""
    from qsplan.mechanics.modes.contact_mode import ContactMode
    from qsplan.mechanics.modes.partition import effort_partitions

    names = task.hand.joint_names
    d = np.sign(x1 - x0)
    xs = np.linspace(x0, x1, 7)
    try:
        scene = contact_samples(task, [x0], names[-1], 0.0, free=None if path is None else path.at([x0])).scenes[0]
        admitted = {names[p.effort_joints[0]] for p in effort_partitions(scene, ContactMode(task.formation.mode))
                    if len(p.effort_joints) == 1}  # fmt: skip
    except QsplanError:
        admitted = set(names)
    best, best_w = None, -np.inf
    for joint in names:
        if joint not in admitted:
            continue
        w = [check_contact_state(task, x, joint, d, free=None if path is None else path.at([x])[0]) for x in xs]
        worst = min((c.width if np.isfinite(c.width) else -np.inf) for c in w)
        if worst > best_w:
            best, best_w = joint, worst
    return best or names[-1]


def _segment(task, i, x0, x1, t0, options, progress, counters, path):
    from qsplan.planner.torque.sweep import competing_modes

    name = _segment_name(i, x0, x1)
    direction = float(np.sign(x1 - x0))
    effort = _effort_joint(task, x0, x1, progress, path)
    progress(f"{name}: effort-controlled finger {effort}; one configuration variable: checking the straight line "
             f"every {SWEEP_STEP * 1e3:g} mm (no search)")  # fmt: skip
    xs = np.linspace(x0, x1, 9)
    try:
        line = contact_samples(task, xs, effort, direction * task.workpiece_speed,
                               free=None if path is None else path.at(xs))  # fmt: skip
    except QsplanError as exc:
        raise PlanFailure(configuration_report(task, name, "the straight line of the segment", x0, None,
                                               f"no four-contact grasp: {exc}")) from None  # fmt: skip
    comps = competing_modes(line)
    touching = line.touching[0]
    for x_end, where in ((x0, "the start of the segment"), (x1, "its goal")):
        free = None if path is None else path.at([x_end])[0]
        c = check_contact_state(task, x_end, effort, direction, touching, comps, free=free)
        if c.ok:
            continue
        if not c.reason.startswith(("band", "no guaranteed band")):  # refused for its geometry: named here
            try:
                q_end = _grasp_q(task, x_end, path)
            except QsplanError:
                q_end = None
            raise PlanFailure(configuration_report(task, name, where, x_end, q_end, c.reason))
        raise PlanFailure(failure_report(task, name, x0, x1, effort, direction, comps, None, path=path))  # for its band
    return slide_phase(task, name, x0, x1, effort, direction, touching, comps, t0, options, progress, counters,
                       path=path)  # fmt: skip


def _regrasp(task, i, x, q, t0, options, progress, counters):
    name = f"regrasp {i + 1}: both fingers release and regrasp at x = {x:.4g} m"
    return regrasp_phase(task, name, x, q, q, t0, options, progress, counters)


def plan_task(task: Task, options: PlannerOptions | None = None, progress=None, sequence_planner: str = "widest") -> Plan:
    """Plan ``task``: in-contact segments through OMPL with guaranteed bands, and regrasps between them.

    Parameters
    ----------
    task : qsplan.planner.task.task.Task
    options : PlannerOptions, optional
        Default :data:`DEFAULT_OPTIONS`.
    progress : callable, optional
        ``progress(line)`` for progress messages.
    sequence_planner : str
        For a task with a ``goal``: the search of the sequence (:func:`qsplan.planner.plan.autoplan.plan_automatic`).

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
        :class:`qsplan.planner.plan.failure.ConfigurationReport` naming it.
    """
    if options is None:
        options = DEFAULT_OPTIONS
    from qsplan.planner.plan.failure import palm_report

    check_goal_served(task)  # a goal in another formation (theta, another palm feature): refused by name first
    from qsplan.planner.task.goal import reorients

    if reorients(task):  # a route of formations: the slide to a flush instant, holds and pivots
        from qsplan.planner.plan.turning import plan_turn

        return plan_turn(task, options, progress, sequence_planner)
    beyond = palm_report(task)  # from the task's geometry alone, before any table or grid is built
    if beyond is not None:
        raise PlanFailure(beyond)
    if task.goal is not None:  # the planner finds the sequence
        from qsplan.planner.plan.autoplan import plan_automatic

        return plan_automatic(task, options, progress, planner=sequence_planner)
    progress = progress or (lambda line: None)
    t_start = time.perf_counter()
    check_configurations(task)
    path = _held(task)
    counters = [0, 0.0]
    phases, t0 = [], 0.0
    xs = [task.start_x, *task.waypoints.tolist()]
    for i, (x0, x1) in enumerate(zip(xs[:-1], xs[1:])):
        if i:
            prev = phases[-1]
            phases.append(_regrasp(task, i - 1, x0, prev.q[-1], t0, options, progress, counters))
            t0 = float(phases[-1].t[-1])
        seg = _segment(task, i, x0, x1, t0, options, progress, counters, path)
        phases.append(seg)
        t0 = float(seg.t[-1])
    plan = time_scale(Plan(task, tuple(phases), time.perf_counter() - t_start, counters[0], counters[1], options))
    plan = release_holds(plan)  # every release from an unloaded hold (qsplan.planner.plan.release)
    plan.check()
    return plan
