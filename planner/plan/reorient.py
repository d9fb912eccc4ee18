"""Reorienting the workpiece: the palm-edge slide to the flush instant, a certified hold, the pivot (issue 23).

A goal that asks another orientation (``[goal] theta``, or ``palm`` naming what rests on the palm) is planned along
the route the paper's own plan takes (Section 5.2: its first segment ends "when the left finger achieves
edge-to-edge contact with the workpiece (along the longest edge)"), over three formations joined in contact:

1. **slide** (formation ``palm_edge``, 4S): the automatic planner's route from the start to the **flush instant**
   (:func:`qsplan.hands.reorient.flush_instant`), where the left finger lies along the workpiece's left edge.  The
   band tables end :data:`FLUSH_APPROACH` short of it (there the polygons still show four contacts); the slide's
   last row is then moved onto the flush instant itself, judged at rest for the motion that reaches it (the
   contact it makes there is open along that motion, :func:`qsplan.hands.found_contacts.made_contacts`);
2. **hold** (formation ``flush_to_pivot_v1``, five contacts, every letter ``R``: nothing moves): the other finger
   held, the pivot's torque-controlled finger's torque ramps from the slide's last command to the pivot's first at
   :data:`HOLD_TORQUE_RATE`.
   Its band is the torque interval over which the hold is *proved* (:func:`qsplan.mechanics.bands.hold.
   hold_torque_interval`: a frictionless equilibrium with every contact loaded by at least the task's force margin,
   at every vertex of the disturbance box; affine in the torque, so the ramp's ends prove it all);
3. **pivot** (formation ``pivot_v1``, 4S): the workpiece turns clockwise on vertex 1, the left finger flush (two
   contacts), the fingers along the closed-form manifold (:func:`qsplan.hands.reorient.pivot_configurations`), one
   finger torque-controlled and the other driven: the one whose narrowest band is widest (:func:`widest_pivot`;
   the right one, the paper's, on a tie).  Its first row is the transition: five contacts, the transition
   formation's mode (vertex 0 lifts, the rest slide), its band the exact transition band, every competitor
   precluded.  It ends at the goal's angle, at rest.

Every band is :func:`qsplan.mechanics.robust_band`'s (exact, or conservative and labelled; the disturbance box of a
turning workpiece, :func:`qsplan.planner.task.dynamics.turning_box`); every row at rest also gets its hold interval.
A goal this route cannot reach (the hand not of the paper's form, a counter-clockwise turn, an event of the pivot
before the goal: a contact changing, a joint limit, the band below the torque resolution) is refused by name with
the angle where it ends.  Units SI (m, rad, s, N m).
"""

from __future__ import annotations

import time
from dataclasses import replace

import numpy as np

from qsplan.hands.reorient import PIVOT_FORMATION, TRANSITION_FORMATION
from qsplan.mechanics.errors import QsplanError

from qsplan.planner.plan.results import ContactSegmentPlan, Plan, PlanFailure
from qsplan.planner.plan.steps import HoldStep, PivotStep, realised_steps
from qsplan.planner.task.goal import Goal, GoalNotServedError

__all__ = ["FLUSH_APPROACH", "HOLD_MIN_DURATION", "HOLD_ROWS", "HOLD_TORQUE_RATE", "PIVOT", "PIVOT_EFFORT_JOINTS", "PIVOT_STEP",
           "hold_phase", "pivot_phase", "pivot_rows", "pivot_target", "plan_reorientation", "route_slide", "widest_pivot"]

#: How far (m) short of the flush instant the slide's band tables end: five times the contact tolerance (1 um), so
#: the polygons show the four contacts of the palm edge there (the left finger's second contact 5 um open); the
#: slide then reaches the flush instant itself in its last row.
FLUSH_APPROACH = 5e-6

#: The rate (N m/s) at which a hold ramps the torque-controlled finger's torque: the demo's step of ~3.7 N m takes
#: about 1.9 s, slow beside a servo's torque loop (ms) so the finger's compliance follows it without a kick.
HOLD_TORQUE_RATE = 2.0

#: Rows of a hold (the ramp's ends decide its proof; the rows between are for plots and a controller's table).
HOLD_ROWS = 11

#: The shortest hold (s), when its ramp is short or nothing ramps: its rows' times must grow, and a controller
#: switching which joint it drives by torque gets a tenth of a second at rest to settle.
HOLD_MIN_DURATION = 0.1

#: The pivot's rows are at most this far apart in the workpiece's angle (rad): 0.25 deg, 0.4 mm at the farthest
#: vertex of the demo's workpiece, like the slides' 0.5 mm rows.
PIVOT_STEP = np.radians(0.25)

#: The fingers the pivot may torque-control, in order of preference on a tie (the paper's Fig. 9: the right one
#: pushes while the left finger, flush on the workpiece, is driven).
PIVOT_EFFORT_JOINTS = ("right", "left")

#: The workpiece's internal vertex the route pivots on: the bottom edge's right end (:mod:`qsplan.hands.workpiece`).
PIVOT = 1

#: ``planner_status`` of a failure of the hold or the pivot: what the route had planned when it stopped.
AFTER_SLIDE = "ran: the slide to the flush instant planned; the hold and pivot stopped here"


def _refuse(field, why):
    return GoalNotServedError(field, f"{field}: {why}")


def pivot_target(task) -> float:
    """The goal's angle (rad): ``goal.theta``, or for ``palm = "edge:K"`` the angle at which that edge lands on the
    palm while the workpiece pivots on vertex 1 (the bottom edge's right end).

    Raises
    ------
    GoalNotServedError
        A counter-clockwise turn, a palm feature the pivot on vertex 1 cannot put there, or a goal ``x``.
    """
    goal, hand = task.goal, task.hand
    pivot = int(hand.user_vertices[PIVOT])  # as the task writes it
    if goal.x is not None:
        raise _refuse("goal.x", "a goal that turns the workpiece is placed by its orientation: the pivot decides x "
                                "(give theta or palm, without x)")  # fmt: skip
    if goal.theta is not None:
        theta = float(goal.theta)
        if not theta < 0:
            raise _refuse("goal.theta", f"turning the workpiece counter-clockwise (theta = {theta:g} rad) is not "
                                        "planned: the route turns it clockwise onto its bottom-right vertex (vertex "
                                        f"{pivot}); pivoting on its bottom-left vertex has no band")  # fmt: skip
        if goal.palm is not None and goal.palm != ("vertex", pivot):
            raise _refuse("goal.palm", f"{goal.palm[0]} {goal.palm[1]} on the palm at theta = {theta:g} rad: the route "
                                       f"pivots on vertex {pivot}")  # fmt: skip
        return theta
    kind, k = goal.palm
    if kind == "vertex":
        raise _refuse("goal.theta", f"vertex {k} on the palm: give the angle too (theta, rad): the workpiece turns on "
                                    "it through many")  # fmt: skip
    landing = int(hand.user_edges[PIVOT])  # the edge from the pivot vertex on: the one it can land on
    if k != landing:
        raise _refuse("goal.palm", f"edge {k} on the palm: the route pivots on vertex {pivot}, and edge {landing} is "
                                   "the one it can land on")  # fmt: skip
    V = np.asarray(hand.workpiece, dtype=float)
    d = V[PIVOT + 1] - V[PIVOT]
    return float(-np.arctan2(d[1], d[0]))  # the turn that lays edge PIVOT -> PIVOT + 1 flat on the palm


def hold_phase(task, name, pose, q, effort_joint, tau_from, tau_to, t0) -> ContactSegmentPlan:
    """A hold at one configuration: ``effort_joint``'s torque ramps from ``tau_from`` to ``tau_to`` (N m) at
    :data:`HOLD_TORQUE_RATE`, every other joint held; its band the proved hold interval (module docstring).
    ``tau_from`` None: the joint is taken over at rest (the phase before had another effort joint) and starts one
    torque resolution inside the proved interval.

    Raises
    ------
    PlanFailure
        No hold is proved there, or the ramp leaves its interval (the report names the torques).
    """
    from qsplan.mechanics.bands.hold import prove_hold
    from qsplan.planner.plan.failure import configuration_report

    effort = np.array(task.hand.joint_names) == effort_joint
    scene, (lo, hi) = _held_interval(task, pose, q, effort)
    if tau_from is None:  # the effort joint taken over at rest: from a resolution inside the proved interval
        tau_from = float(min(lo + task.torque_resolution, tau_to)) if np.isfinite(lo) else float(tau_to)
    proofs = [prove_hold(scene, torques=[t], disturbance=task.disturbance) for t in (tau_from, tau_to)]
    room = 0.5 * task.torque_resolution  # the certifier's least slack to a band's edge (a controller's rounding)
    inside = bool(lo + room <= min(tau_from, tau_to) and max(tau_from, tau_to) <= hi - room)  # False when empty
    if not (inside and all(p.proved for p in proofs)):
        raise PlanFailure(configuration_report(task, name, "the hold", float(pose[0]), q,
                                               f"no hold is proved from {tau_from:.4g} to {tau_to:.4g} N m (proved "
                                               f"interval [{lo:.4g}, {hi:.4g}] N m)", AFTER_SLIDE, pose))  # fmt: skip
    n = HOLD_ROWS
    s = np.linspace(0.0, 1.0, n)
    command = tau_from + s * (tau_to - tau_from)
    t = t0 + s * max(abs(tau_to - tau_from) / HOLD_TORQUE_RATE, HOLD_MIN_DURATION)
    lower, upper = np.full(n, lo), np.full(n, hi)
    margin = np.minimum(command - lower, upper - command)
    qd = np.where(effort[None, :], np.nan, 0.0) * np.ones((n, 1))
    mode = "R" * len(scene.contact_names)
    return ContactSegmentPlan(name, effort_joint, mode, np.array([pose[0]]), t, np.full(n, pose[0]),
                              np.tile(q, (n, 1)), qd, lower, upper, command, margin, (), 0.0, None,
                              np.zeros(n), "hold", np.tile(pose, (n, 1)), None, TRANSITION_FORMATION,
                              (tuple(scene.contact_names),) * n)  # fmt: skip


def _pivot_thetas(theta_goal: float) -> np.ndarray:
    """The pivot's rows' angles (rad): from 0 to ``theta_goal``, at most :data:`PIVOT_STEP` apart."""
    n = int(np.ceil(abs(theta_goal) / PIVOT_STEP)) + 1
    return np.linspace(0.0, theta_goal, n)


def _held_interval(task, pose, q, effort):
    """``(scene, (lo, hi))``: every contact the polygons show at ``pose``, ``q`` (:func:`qsplan.hands.found_contacts.
    hold_scene`, as certified), the ``effort`` joints (bool) torque-controlled and the others held, and the torques
    at which the hold is proved with every contact loaded by the task's force margin at every vertex of its
    disturbance box (N m; nan when none)."""
    from qsplan.hands.found_contacts import hold_scene
    from qsplan.mechanics.bands.hold import hold_torque_interval

    scene = hold_scene(task.hand, pose, q, effort)
    return scene, hold_torque_interval(scene, task.disturbance, margin=task.force_margin.normal)


def _pivot_failure(task, name, c, i, why) -> PlanFailure:
    """The report of the pivot's row ``i`` (of configurations ``c``): its angle, pose and joints, and ``why``."""
    from qsplan.planner.plan.failure import configuration_report

    q = None if np.any(np.isnan(c.q[i])) else c.q[i]
    where = f"theta = {np.degrees(c.theta[i]):.4g} deg"
    return PlanFailure(configuration_report(task, name, where, float(c.pose[i, 0]), q, why, AFTER_SLIDE, c.pose[i]))


def pivot_rows(task, name, instant, theta_goal):
    """The pivot's configurations from the flush instant to ``theta_goal`` (:func:`qsplan.hands.reorient.
    pivot_configurations`), checked whatever finger is torque-controlled: every row reachable, inside the limits,
    no two bodies overlapping, the formation's contacts (the transition's at the first row; at the last, without a
    contact it makes there: an edge landing), no contact's sliding direction reversing.

    Raises
    ------
    PlanFailure
        Naming the row's angle and the reason.
    """
    from qsplan.hands.formations import formation
    from qsplan.hands.found_contacts import made_contacts, ordered_contacts
    from qsplan.hands.reorient import pivot_configurations
    from qsplan.planner.states.contact import configuration_problem

    hand = task.hand
    c = pivot_configurations(hand, _pivot_thetas(theta_goal), PIVOT, instant.edge, instant.right_vertex)
    n = c.theta.size
    blocked = None  # the first row whose geometry ends the pivot: (row, why)
    for i in range(n):
        if np.any(np.isnan(c.q[i])):
            blocked = (i, "the right finger cannot reach its vertex")
            break
        why = configuration_problem(task, c.pose[i], c.q[i])  # a joint limit, two bodies overlapping
        if why:
            blocked = (i, why)
            break
        found = ordered_contacts(hand, c.pose[i], c.q[i])
        if i == n - 1 and i > 0:  # the goal's row may make a contact (an edge landing): not in the motion
            made = made_contacts(hand, (c.pose[i - 1], c.q[i - 1]), (c.pose[i], c.q[i]), found)
            found = [f for f, m in zip(found, made) if not m]
        want = formation(TRANSITION_FORMATION if i == 0 else PIVOT_FORMATION).n_contacts
        if len(found) != want:
            blocked = (i, f"the polygons show {len(found)} contacts; the formation has {want}")
            break
    valid = n if blocked is None else blocked[0]  # the rows before it keep the formation: their slips are defined
    reversal = _slip_reversal(hand, _first_rows(c, valid)) if valid > 1 else None
    if reversal is not None:  # it comes first along the pivot (found among the rows before the geometry's end)
        i, at, contact = reversal
        raise _pivot_failure(task, name, c, i, f"contact {contact} stops sliding at theta = {np.degrees(at):.4g} deg "
                                               "(its sliding direction reverses: it rolls for an instant, and one 4S "
                                               "phase cannot cross it)")  # fmt: skip
    if blocked is not None:
        raise _pivot_failure(task, name, c, *blocked)
    return c


def pivot_phase(task, name, instant, theta_goal, t0, effort_joint: str = "right", rows=None) -> ContactSegmentPlan:
    """The pivot from the flush instant (theta 0) to ``theta_goal`` (rad, negative), ``effort_joint`` (a finger)
    torque-controlled, the other driven along the manifold; the first row the transition (module docstring).
    ``rows``: :func:`pivot_rows`, when already checked.

    Raises
    ------
    PlanFailure
        As :func:`pivot_rows`; a row without a band at least the torque resolution wide.
    """
    from qsplan.hands.formations import formation
    from qsplan.hands.reorient import pivot_scene, transition_scene
    from qsplan.mechanics.bands.batched_robust import robust_bands
    from qsplan.mechanics.bands.robust import robust_band
    from qsplan.planner.torque.command import plan_command, smooth_command

    hand = task.hand
    c = pivot_rows(task, name, instant, theta_goal) if rows is None else rows
    n = c.theta.size
    speeds, rates = np.asarray(task.joint_speeds, float), np.max(np.abs(c.dq), axis=0)
    com_rate = float(np.max(np.hypot(c.dpose[:, 0], c.dpose[:, 1])))
    limits = [task.workpiece_speed / com_rate] + [float(speeds[j] / rates[j]) for j in np.flatnonzero(rates)]
    rate = -min(limits)  # clockwise, the fastest the speed limits allow (rad/s)
    effort = np.array(hand.joint_names) == effort_joint
    first = transition_scene(hand, instant, effort_joint, rate)
    scenes = [pivot_scene(hand, c, i, effort_joint, rate) for i in range(1, n)]
    kw = dict(shared=task.shared_mu, force_margin=task.force_margin, disturbance=task.disturbance)
    bands = [robust_band(first, formation(TRANSITION_FORMATION).mode, task.mu_range, **kw)]
    bands += robust_bands(scenes, formation(PIVOT_FORMATION).mode, task.mu_range, **kw)
    lower = np.array([b.lower if b.feasible else np.nan for b in bands])
    upper = np.array([b.upper if b.feasible else np.nan for b in bands])
    for k in (0, n - 1):  # at rest: the hold must be proved too, with every contact there (as certified)
        held = _held_interval(task, c.pose[k], c.q[k], effort)[1]
        lower[k], upper[k] = max(lower[k], held[0]), min(upper[k], held[1])
    width = upper - lower
    bad = np.flatnonzero(~(width >= task.torque_resolution))
    if bad.size:
        i = int(bad[0])
        why = bands[i].reason if not bands[i].feasible else f"the band is {width[i]:.3g} N m wide"
        raise _pivot_failure(task, name, c, i, f"no guaranteed band at least the torque resolution "
                                               f"({task.torque_resolution:g} N m) wide: {why}")  # fmt: skip
    command, margin = smooth_command(*plan_command(lower, upper, task.torque_resolution), lower, upper)
    qd = np.where(effort[None, :], np.nan, c.dq * rate)  # the velocity-controlled finger along the manifold
    names = (tuple(first.contact_names),) + (tuple(scenes[0].contact_names),) * (n - 1) if scenes else ()
    modes = (formation(TRANSITION_FORMATION).mode,) + (formation(PIVOT_FORMATION).mode,) * (n - 1)
    comps = tuple(sorted({m for b in bands for m in getattr(b, "competitors", ())}))
    return ContactSegmentPlan(name, effort_joint, formation(PIVOT_FORMATION).mode, c.pose[[0, -1], 0],
                              t0 + np.abs(c.theta) / abs(rate), c.pose[:, 0], c.q, qd, lower, upper, command, margin,
                              comps, com_rate * abs(rate), None, None, "pivot", c.pose, modes, PIVOT_FORMATION,
                              names)  # fmt: skip


def _first_rows(c, m: int):
    """The pivot's configurations ``c`` cut to their first ``m`` rows."""
    cut = {k: getattr(c, k)[:m] for k in ("theta", "pose", "q", "dpose", "dq", "vertices")}
    return replace(c, **cut)


def _slip_reversal(hand, c):
    """``(first row past it, angle (rad), contact name)`` of the first contact whose sliding direction reverses along
    the pivot (:func:`qsplan.hands.pivot_sweep.slip_events`), or None."""
    from qsplan.hands.pivot_sweep import slip_events

    events = slip_events(hand, c)
    if not events:
        return None
    first = max(events, key=lambda e: e.theta)  # the angles decrease along the pivot
    return int(np.flatnonzero(c.theta < first.theta)[0]), first.theta, first.name.removeprefix("slip_")


def route_slide(task) -> tuple:
    """``(flush instant, sub-task, words)``: the route's first step, the slide to the flush instant of the longest left
    side of the workpiece the left finger fits along (:func:`qsplan.hands.reorient.left_sides`), planned as a task
    whose goal is the left finger on that side's upper vertex :data:`FLUSH_APPROACH` short of it.

    Raises
    ------
    GoalNotServedError
        A hand not of the paper's form; no left side, or none the finger fits along (each named with where its ends
        lie).
    """
    from qsplan.hands.reorient import flush_instant, left_sides

    hand = task.hand
    if not hand.reorients:
        raise _refuse("goal.theta", "turning the workpiece is planned for the paper's hand form only (two single-link "
                                    "revolute fingers, Fig. 9)")  # fmt: skip
    field = "goal.theta" if task.goal.theta is not None else "goal.palm"
    sides = left_sides(hand)
    if not sides:
        raise _refuse(field, "the route lays the left finger flush along a left side of the workpiece (an edge whose "
                             "lower end is below its upper end), and this workpiece has none")  # fmt: skip
    misfits = []
    for k in sides:  # the longest left side the finger fits along
        try:
            instant = flush_instant(hand, k)
            break
        except QsplanError as exc:  # the edge beyond the finger's reach: no flush instant on it
            misfits.append(f"edge {int(hand.user_edges[k])}: its ends lie {str(exc).partition(' lies ')[2] or exc}")
    else:
        raise _refuse(field, "the route lays the left finger flush along a left side of the workpiece, and none fits "
                             "along it (" + "; ".join(misfits) + ")")  # fmt: skip
    x_near = instant.x + FLUSH_APPROACH * np.sign(task.start_x - instant.x)
    sub = replace(task, goal=Goal(float(x_near), ("vertex", int(hand.user_vertices[instant.edge])), None))
    step = (f"the slide to the flush instant (x = {instant.x:.6g} m, the left finger along edge "
            f"{int(hand.user_edges[instant.edge])})")  # fmt: skip
    return instant, sub, step


def plan_reorientation(task, options=None, progress=None, planner: str = "widest") -> Plan:
    """Plan a goal that turns the workpiece: slide to the flush instant, hold, pivot (the module docstring).

    Raises
    ------
    GoalNotServedError
        The route cannot serve the goal (named field and why).
    PlanFailure
        A phase of the route has no plan (the report says where and why).
    """
    from qsplan.planner.plan.autoplan import plan_automatic
    from qsplan.planner.plan.timing import time_scale

    progress = progress or (lambda line: None)
    started = time.perf_counter()
    hand = task.hand
    theta_goal = pivot_target(task)
    instant, sub, step = route_slide(task)
    progress(f"reorientation: {step}, hold, pivot on vertex {int(hand.user_vertices[PIVOT])} to theta = "
             f"{theta_goal:.4g} rad")  # fmt: skip
    try:
        slide = plan_automatic(sub, options, progress, planner, timed=False)
    except PlanFailure as exc:  # said as the route's step, drawn with the task it was planned as
        from qsplan.planner.plan.failure import StepReport

        raise PlanFailure(StepReport(step, sub, exc.report)) from None
    phases = list(slide.phases)
    last = phases[-1]
    if not last.in_contact:
        raise PlanFailure(slide_failure(task, last))
    # the last row moves onto the flush instant itself (5 um on): a row at rest, its band judged again for the
    # chord that reaches it by the time scaling (the contact made there left out: qsplan.planner.plan.timing)
    x, q, t = last.x.copy(), last.q.copy(), last.t.copy()
    x[-1], q[-1] = instant.x, instant.q
    t[-1] = t[-2] + abs(x[-1] - x[-2]) / abs(last.speed)
    phases[-1] = replace(last, x=x, q=q, t=t)
    # the slide timed first: the hold starts from its last command as the time scaling chose it
    timed = time_scale(Plan(task, tuple(phases), 0.0, 0, 0.0, slide.options))
    end = timed.phases[-1]
    pivot = widest_pivot(task, f"pivot on vertex {int(hand.user_vertices[PIVOT])} to theta = {theta_goal:.4g} rad",
                         instant, theta_goal, progress)  # fmt: skip
    e = pivot.effort_joint
    start = float(end.command[-1]) if end.effort_joint == e else None  # else handed over at rest
    hold = hold_phase(task, "hold at the flush instant", instant.pose, instant.q, e, start,
                      float(pivot.command[0]), 0.0)  # fmt: skip
    pivot = replace(pivot, t=pivot.t + float(hold.t[-1]))
    turned = time_scale(Plan(task, (hold, pivot), 0.0, 0, 0.0, slide.options))
    shift = float(end.t[-1])
    later = tuple(replace(ph, t=ph.t + shift) for ph in turned.phases)
    steps = tuple(st for st in slide.sequence if st.kind != "search") + (
        HoldStep(float(instant.x), 0.0, e, float(hold.command[0]), float(pivot.command[0]),
                 float(hold.lower[0]), float(hold.upper[0])),
        PivotStep(int(hand.user_vertices[PIVOT]), 0.0, theta_goal, e, float(np.min(pivot.width))),
    ) + tuple(st for st in slide.sequence if st.kind == "search")  # fmt: skip
    plan = Plan(task, timed.phases + later, time.perf_counter() - started, slide.validity_checks + pivot.t.size,
                slide.ompl_seconds, slide.options, realised_steps(steps, timed.phases + later),
                timed.timing + turned.timing)  # fmt: skip
    plan.check()
    progress(f"reorientation planned: {len(plan.phases)} phases, {plan.duration:.4g} s")
    return plan


def widest_pivot(task, name, instant, theta_goal, progress) -> ContactSegmentPlan:
    """The pivot with either finger torque-controlled (:data:`PIVOT_EFFORT_JOINTS`), the one whose narrowest band is
    widest (the first on a tie; the second is not computed when the first's bands are all unbounded above); the
    first one's failure when neither has a plan."""
    rows = pivot_rows(task, name, instant, theta_goal)  # the geometry, whatever finger is torque-controlled
    found, first_failure = [], None
    for e in PIVOT_EFFORT_JOINTS:
        if found and np.isinf(np.min(found[0].width)):
            break  # unbounded everywhere: nothing is wider
        try:
            found.append(pivot_phase(task, name, instant, theta_goal, 0.0, e, rows))
        except PlanFailure as exc:
            first_failure = first_failure or exc
            progress(f"  pivot with the {e} finger torque-controlled: {exc}")
    if not found:
        raise first_failure
    best = max(found, key=lambda p: float(np.min(p.width)))  # max keeps the first of equals
    w = float(np.min(best.width))
    width = f"{w:.4g} N m" if np.isfinite(w) else "unbounded above (every band)"
    progress(f"  pivot: the {best.effort_joint} finger torque-controlled, narrowest band {width}")
    return best


def slide_failure(task, phase):
    """The report when the route to the flush instant does not end in contact (a regrasp last)."""
    from qsplan.planner.plan.failure import configuration_report

    return configuration_report(task, phase.name, "the flush instant", float(phase.x[-1]), phase.q[-1],
                                "the route to the flush instant ends with a regrasp, not in contact",
                                "ran: the sequence search to the flush instant")  # fmt: skip
