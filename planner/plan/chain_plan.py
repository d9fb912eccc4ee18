"""Plans for a described hand (:class:`qsplan.hands.chain_hand.ChainHand`): from a start grasp to a goal grasp.

The start grasp is the task's ``[start]`` (the free joints by name), or the grid points of the free joints
(:func:`qsplan.planner.plan.chain_slide.free_grid`) whose grasps at ``start_x`` are valid; the goal grasps
are those at the goal's ``x`` with a start grasp's free joints held (the fingers following the workpiece)
and the grid points there, touching the goal's features (``[goal] left/right``, when given).  For each pair
of grasps and each joint the control-mode partitioner admits as the effort-controlled one (eq. 32,
:func:`effort_candidates`), the guaranteed bands at both ends are computed (the motion's direction, the straight line's slopes); the pairs
are tried widest first, each planned on the contact manifold by OMPL and judged densely
(:func:`qsplan.planner.plan.chain_slide.plan_slide`).  A goal whose features differ from every start grasp's
needs a regrasp (:func:`qsplan.planner.plan.chain_regrasp.chain_regrasp`): the plan slides keeping the start's
features and regrasps at the goal, or regrasps at the start and slides.  Units SI.
"""

from __future__ import annotations

import time

import numpy as np

from qsplan.mechanics.errors import QsplanError

from qsplan.planner.plan.chain_slide import free_grid, plan_slide
from qsplan.planner.plan.chain_states import check_state, closed_state, judge_states, motion_mode, slip_signs
from qsplan.planner.plan.failure import configuration_report
from qsplan.planner.plan.results import Plan, PlanFailure
from qsplan.planner.task.task import MIN_SEGMENT_LENGTH

__all__ = ["MAX_ATTEMPTS", "STABLE_DX", "effort_candidates", "plan_chain_task", "start_grasps"]

#: Distance (m) either side of a candidate grasp's x at which it must touch the same features: two dense-sweep
#: steps (:data:`qsplan.planner.plan.phases.SWEEP_STEP`), so a slide does not start or end on a contact change.
STABLE_DX = 1e-3

#: Pairs of grasps (and effort-controlled joint) tried, widest first, before the planner gives up: each is an
#: OMPL query and a dense judgement, a second or so.
MAX_ATTEMPTS = 6


def _feature_ok(hand, key, feature) -> bool:
    """Whether a contact key ``(link, kind, internal feature)`` touches ``feature`` (``(kind, K)`` as written, or None)."""
    from qsplan.hands.grasps import internal_edge, internal_vertex

    if feature is None:
        return True
    kind, K = feature
    if kind == "vertex":
        return key[1] == "vertex" and key[2] == internal_vertex(hand, K)
    if kind == "edge":
        return key[1] == "edge" and key[2] == internal_edge(hand, K)
    return False


def _stable(task, x: float, q, keys) -> bool:
    """Whether the fingers, free joints held, touch the same features :data:`STABLE_DX` either side of ``x`` (a grasp
    at the edge of its region, about to change contacts, makes a slide that fails at once)."""
    return all(closed_state(task.hand, x + dx, q)[1] == keys for dx in (-STABLE_DX, STABLE_DX))


def start_grasps(task, x: float, features=(None, None)) -> list:
    """Valid grasps at ``x`` touching ``features``: ``[(q (n_j,), keys)]`` on the free joints' grid, each touching
    the same features :data:`STABLE_DX` either side (:func:`_stable`)."""
    out = []
    for q in free_grid(task):
        qc, keys, why = check_state(task, x, q)
        if why is not None:
            continue
        if all(_feature_ok(task.hand, keys[f], features[f]) for f in range(2)) and _stable(task, x, q, keys):
            out.append((qc, keys))
    return out


def effort_candidates(task, x: float, q, mode: str = "SSSS") -> list:
    """The joints the control-mode partitioner (eq. 32, :func:`qsplan.mechanics.modes.partition.effort_partitions`)
    admits as the one effort-controlled joint of ``mode`` at the grasp ``(x, q)``, best-conditioned first (every
    sliding direction checked); for 4S with four contacts, 3 + |tau_I| = 4 gives one joint (eq. 29)."""
    from qsplan.hands.chain_hand import chain_scene
    from qsplan.mechanics.modes.partition import effort_partitions

    n_j = len(task.joint_limits)
    scene = chain_scene(task.hand, task.pose(x), q, np.arange(n_j) == 0, np.zeros(n_j))
    return [p.effort_joints[0] for p in effort_partitions(scene, mode) if len(p.effort_joints) == 1]


def _held(task, starts, x: float) -> list:
    """The grasps at ``x`` with each start grasp's free joints held (only the closing joints move: the fingers
    follow the workpiece), where valid: ``[(q, keys)]``."""
    out = []
    for q, _ in starts:
        qc, keys, why = check_state(task, x, q)
        if why is None:
            out.append((qc, keys))
    return out


def _ends_width(task, x0, q0, x1, q1, effort, keys):
    """The narrower of the two ends' guaranteed bands (N m) of a straight slide, and its mode; -inf without one."""
    free = task.hand.free_joints()
    direction = float(np.sign(x1 - x0))
    unit = np.zeros(len(q0))
    unit[free] = (q1[free] - q0[free]) / (x1 - x0) * direction
    j = judge_states(task, np.array([x0, x1]), np.stack([q0, q1]), np.stack([unit, unit]), direction, effort, keys)
    if not j.ok.all():
        return -np.inf, None, None
    return float(np.min(j.width)), motion_mode(j.scenes[0], j.qd[0], direction), slip_signs(j.scenes[0], j.qd[0], direction)


def _slide(task, name, x0, starts, x1, goals, t0, options, progress, counters):
    """The widest-first slide from one of ``starts`` to one of ``goals`` with the same contact keys:
    ``(ContactSegmentPlan, None)`` or ``(None, reason)``."""
    from qsplan.planner.plan.phases import SWEEP_STEP

    pairs = [(s, g) for s in starts for g in goals if g[1] == s[1]]
    if not pairs:
        return None, "no goal grasp touches the same features as a start grasp"
    scored = []
    for (q0, keys), (q1, _) in pairs[:: max(1, len(pairs) // 40)]:  # a spread of at most ~40 pairs
        for e in effort_candidates(task, x0, q0):
            w, mode, signs = _ends_width(task, x0, q0, x1, q1, e, keys)
            if w >= task.torque_resolution:
                scored.append((w, e, q0, q1, keys, (mode, signs)))
    scored.sort(key=lambda s: -s[0])
    progress(f"  {name}: {len(scored)} (start, goal, effort joint) choices with bands at both ends")
    last = None
    for w, e, q0, q1, keys, mode in scored[:MAX_ATTEMPTS]:
        progress(f"  {name} with {task.hand.joint_names[e]} effort-controlled, mode {mode[0]}, ends' band {w:.4g}")
        seg, res, judged, c, sec = plan_slide(task, name, x0, q0, x1, q1, e, keys, mode, t0, options, SWEEP_STEP)
        counters[0] += c
        counters[1] += sec
        if seg is not None:
            return seg, None
        last = (res, judged)
    if last is None:
        return None, "no (start, goal, effort joint) choice has a guaranteed band at both ends"
    res, judged = last
    if judged is not None:
        k = int(np.flatnonzero(~judged.ok)[0])
        return None, f"the planned slide fails its dense check at x = {judged.x[k]:.4g} m: {judged.reasons[k]}"
    return None, f"OMPL found no slide on the contact manifold ({res.status})"


def _sequence(task, starts, goals_any, goals, options, progress, counters):
    """The phases: one slide when the goal's features are a start grasp's, else a slide and a regrasp (at the goal
    or at the start, whichever plans); ``(phases, None)`` or ``(None, reason)``."""
    from qsplan.planner.plan.chain_regrasp import chain_regrasp

    x0, x1 = task.start_x, task.goal.x
    seg, why = _slide(task, "slide 1", x0, starts, x1, goals, 0.0, options, progress, counters)
    if seg is not None:
        return (seg,), None
    reasons = [why]
    # slide keeping the start's features, then regrasp at the goal onto the goal's features
    seg, why = _slide(task, "slide 1", x0, starts, x1, goals_any, 0.0, options, progress, counters)
    if seg is not None:
        for q1, _ in goals:
            try:
                rg = chain_regrasp(task, "regrasp 1", x1, seg.q[-1], q1, float(seg.t[-1]), options, progress, counters)
            except PlanFailure as exc:
                reasons.append(f"regrasp at the goal: {exc}")
                continue
            return (seg, rg), None
    else:
        reasons.append(why)
    # regrasp at the start onto the goal's features, then slide
    for q0, keys in start_grasps(task, x0, (task.goal.left, task.goal.right)):
        for qs, _ in starts:
            try:
                rg = chain_regrasp(task, "regrasp 1", x0, qs, q0, 0.0, options, progress, counters)
            except PlanFailure as exc:
                reasons.append(f"regrasp at the start: {exc}")
                break
            seg, why = _slide(task, "slide 2", x0, [(q0, keys)], x1, goals, float(rg.t[-1]), options, progress,
                              counters)  # fmt: skip
            if seg is not None:
                return (rg, seg), None
            reasons.append(why)
            break
        break
    return None, "; ".join(dict.fromkeys(r for r in reasons if r))


def plan_chain_task(task, options=None, progress=None) -> Plan:
    """Plan a task of a described hand (see the module docstring).

    Raises
    ------
    PlanFailure
        No valid start or goal grasp, or no slide (and regrasp) found: the report says which.
    """
    from qsplan.planner.plan.phases import DEFAULT_OPTIONS

    options = options or DEFAULT_OPTIONS
    progress = progress or (lambda line: None)
    if task.goal is None:
        raise QsplanError("goal: a task of a described hand gives [goal] x (and optionally left, right); "
                          "scripted waypoints are planned for the paper's hand only")  # fmt: skip
    if abs(task.goal.x - task.start_x) < MIN_SEGMENT_LENGTH:  # the plan's one slide: a direction and slopes
        raise QsplanError(f"goal.x: a described hand's plan slides the workpiece from motion.start_x to goal.x; "
                          f"expected them at least {MIN_SEGMENT_LENGTH:g} m apart, got {task.start_x:g} and "
                          f"{task.goal.x:g} m")  # fmt: skip
    t_start = time.perf_counter()
    hand, x0, x1 = task.hand, task.start_x, task.goal.x
    if task.start_joints is not None:
        qc, keys, why = check_state(task, x0, task.start_joints)
        if why:
            raise PlanFailure(configuration_report(task, "slide 1", "the start", x0, None, why))
        starts = [(qc, keys)]
    else:
        starts = start_grasps(task, x0)
    if not starts:
        raise PlanFailure(configuration_report(task, "slide 1", "the start", x0, None,
                                               "no valid grasp of the free joints' grid"))  # fmt: skip
    goals = _held(task, starts, x1) + start_grasps(task, x1, (task.goal.left, task.goal.right))
    goals = [g for g in goals if all(_feature_ok(hand, g[1][f], (task.goal.left, task.goal.right)[f]) for f in range(2))]
    if not goals:
        raise PlanFailure(configuration_report(task, "slide 1", "the goal", x1, None,
                                               "no valid grasp of the free joints' grid touches the goal's features"))
    goals_any = goals if task.goal.left is None and task.goal.right is None else _held(task, starts, x1) + start_grasps(task, x1)
    progress(f"  {len(starts)} start grasps at x = {x0:.4g} m, {len(goals)} goal grasps at x = {x1:.4g} m")
    counters = [0, 0.0]
    phases, why = _sequence(task, starts, goals_any, goals, options, progress, counters)
    if phases is None:
        raise PlanFailure(configuration_report(task, "slide 1", "the slide", x0, None, why))
    seq = tuple({"kind": "slide", "effort_joint": p.effort_joint, "mode": p.mode, "x_from_m": float(p.x[0]),
                 "x_to_m": float(p.x[-1]), "narrowest_band_N_m": float(np.min(p.width))} if hasattr(p, "mode")
                else {"kind": "regrasp", "x_m": float(p.x)} for p in phases)  # fmt: skip
    seq += ({"kind": "manifold search", "planner": options.planner, "start_grasps": len(starts),
             "goal_grasps": len(goals), "states_judged": counters[0], "seconds": counters[1]},)
    plan = Plan(task, phases, time.perf_counter() - t_start, counters[0], counters[1], options, seq)
    plan.check()
    return plan
