"""Automatic planning: from a start grasp to a goal grasp, the sequence with the widest guaranteed band.

:func:`plan_automatic` is :func:`qsplan.planner.plan.scripted.plan_task` for tasks with a ``[goal]``:

1. **Tables.**  Every candidate grasp of the hand (:func:`qsplan.hands.grasps.candidate_grasps`:
   each finger's inner edge on a vertex, or its tip on an edge) judged on a grid of the
   workpiece's ``x`` through the start and the goal, where the workpiece rests on the palm
   (:func:`qsplan.planner.search.tables.band_tables`, :func:`qsplan.planner.task.goal.palm_x_range`).
2. **Search.**  The route of 4S slides and regrasps whose narrowest guaranteed band is widest,
   then with the fewest regrasps, steps and segments (:mod:`qsplan.planner.search.widest`), run
   as an OMPL planner (:func:`qsplan.planner.search.ompl_search.search_route`).
3. **Realisation.**  Each slide of the route is judged again sample by sample and gets its
   commands (:func:`qsplan.planner.plan.phases.slide_phase`), each regrasp is planned by OMPL in
   joint space (:func:`qsplan.planner.plan.phases.regrasp_phase`).  A slide the dense sweep
   rejects closes its table cell, a regrasp OMPL cannot realise is forbidden, and the search runs
   again (at most :data:`MAX_ROUNDS` times): the search only proposes.
4. **No route.**  :func:`qsplan.planner.plan.obstacles.no_route_report` names what blocks: the
   goal's grasp invalid at the goal (and why), the geometry (joint limit, overlap, lost contact)
   that separates start and goal, or the narrowest band of the best route with the friction at
   which it closes and the competitor that closes it.

The plan then goes through the same export, certification and re-simulation as a scripted one
(:func:`qsplan.planner.pipeline.run.run_plan`).  Units SI (m, rad, s, N m).
"""

from __future__ import annotations

import time
from dataclasses import replace

import numpy as np

from qsplan.mechanics.errors import QsplanError

from qsplan.planner.plan.results import ContactSegmentPlan, Plan, PlanFailure
from qsplan.planner.search.ompl_search import search_route
from qsplan.planner.search.tables import band_tables, table_grid

__all__ = ["MAX_ROUNDS", "goal_nodes", "plan_automatic", "route_phases", "start_nodes"]

#: Rounds of search and realisation: each failed round closes a table cell or forbids a regrasp, so a
#: handful suffices; the bound keeps a pathological task from looping.
MAX_ROUNDS = 12

_FINGERS = ("left", "right")


def _feature_text(feature):
    """A task's feature as :meth:`qsplan.hands.grasps.Grasp.matches` reads it: None (any), ``"vertex"`` (the start's
    ``"inner"``: the inner edge on whichever vertex), ``"edge:K"``, ``"vertex:K"``."""
    if feature is None:
        return None
    return "vertex" if feature[0] == "inner" else f"{feature[0]}:{feature[1]}"


def _start_grasps(tables, task, i):
    """Indices of the valid grasps that meet the task's start features at grid index ``i``."""
    feats = [_feature_text(f) for f in task.start_features]
    return [g for g in range(len(tables.grasps)) if tables.graph.valid[g, i] and _meets(tables, task, g, i, feats)]


def _meets(tables, task, g, i, feats) -> bool:
    """Whether grasp ``g`` at grid index ``i`` touches the features ``feats`` (left, right: text or None): its
    placements match, and a ``"vertex:K"`` is the vertex touched there."""
    from qsplan.hands.grasps import user_vertex

    if not tables.grasps[g].matches(*feats):
        return False
    for k, f in enumerate(feats):
        if f is not None and f.startswith("vertex:"):
            touched = int(tables.graph.touched[g, i, k])
            if touched < 0 or user_vertex(task.hand, touched) != int(f.split(":")[1]):
                return False
    return True


def _goal_grasps(tables, task, i):
    feats = [_feature_text(task.goal.left), _feature_text(task.goal.right)]
    return [g for g in range(len(tables.grasps)) if _meets(tables, task, g, i, feats)]


def start_nodes(tables, task) -> list:
    """The search's start nodes ``(grasp, i)``: the valid grasps meeting the task's start features at its start."""
    i = tables.index(task.start_x)
    return [(g, i) for g in _start_grasps(tables, task, i)]


def goal_nodes(tables, task) -> list:
    """The search's goal nodes ``(grasp, i)``: the valid grasps meeting the goal's features at the goal x."""
    i = tables.index(task.goal.x)
    return [(g, i) for g in _goal_grasps(tables, task, i) if tables.graph.valid[g, i]]


def route_phases(route) -> list:
    """The route's steps grouped into phases: ``("slide", grasp, i0, i1, effort)`` (a run of steps in one grasp,
    effort finger and direction) and ``("regrasp", from grasp, to grasp, i)``."""
    out = []
    for s in route.steps:
        if s.kind == "regrasp":
            out.append(("regrasp", s.grasp, s.to_grasp, s.i))
            continue
        if out and out[-1][0] == "slide":
            _, g, i0, i1, e = out[-1]
            if g == s.grasp and e == s.effort and i1 == s.i and np.sign(s.to_i - s.i) == np.sign(i1 - i0):
                out[-1] = ("slide", g, i0, s.to_i, e)
                continue
        out.append(("slide", s.grasp, s.i, s.to_i, s.effort))
    return out


def _opening(task, grasp, x):
    """Each finger's opening direction at ``x`` (m): the sign of the joint rate that moves its contact point out
    of the workpiece, ``-sign(j_n)`` with ``j_n = n . (e_z x (p - a))`` (eq. 5), shape (2,)."""
    from qsplan.hands.grasp_geometry import grasp_configurations

    conf = grasp_configurations(task.hand, grasp, np.array([x]))
    pivots = task.hand.pivots
    out = np.empty(2)
    for k in range(2):
        p, n = conf.points[0, 2 + k], conf.normals[0, 2 + k]
        r = p - pivots[k]
        jn = n[0] * (-r[1]) + n[1] * r[0]
        out[k] = -np.sign(jn) if jn != 0 else (1.0 if k == 0 else -1.0)
    return out


def _realise(task, tables, route, options, progress, counters):
    """The route's phases as plan phases; raises ``_Rejected`` naming the table cell or regrasp to drop."""
    from qsplan.planner.plan.phases import regrasp_phase, slide_phase
    from qsplan.planner.states.contact import check_contact_state, contact_samples
    from qsplan.planner.torque.sweep import competing_modes

    x, q_tab = tables.x, tables.q
    phases, seq, t0 = [], [], 0.0
    q_now = None
    n_slide = n_regrasp = 0
    for ph in route_phases(route):
        if ph[0] == "regrasp":
            _, g, h, i = ph
            n_regrasp += 1
            q_from = q_now if q_now is not None else q_tab[g, i]
            name = (f"regrasp {n_regrasp}: release at x = {x[i]:.4g} m and grasp {tables.grasps[h].label} "
                    f"(from {tables.grasps[g].label})")  # fmt: skip
            try:
                r = regrasp_phase(task, name, float(x[i]), q_from, q_tab[h, i], t0, options, progress, counters,
                                  _opening(task, tables.grasps[g], x[i]), _opening(task, tables.grasps[h], x[i]))  # fmt: skip
            except PlanFailure as exc:
                raise _Rejected(("regrasp", g, h, i), exc) from None
            phases.append(r)
            seq.append({"kind": "regrasp", "x": float(x[i]), "from": tables.grasps[g].label, "to": tables.grasps[h].label})
            q_now, t0 = r.q[-1], float(r.t[-1])
            continue
        _, g, i0, i1, e = ph
        n_slide += 1
        grasp, effort, d = tables.grasps[g], _FINGERS[e], float(np.sign(i1 - i0))
        name = (f"segment {n_slide}: slide the workpiece {'left' if d < 0 else 'right'} from x = {x[i0]:.4g} to "
                f"{x[i1]:.4g} m, grasp {grasp.label}")  # fmt: skip
        line = contact_samples(task, np.linspace(x[i0], x[i1], 9), effort, d * task.workpiece_speed, grasp=grasp)
        comps = competing_modes(line)
        touching = line.touching[0]
        try:
            seg = slide_phase(task, name, float(x[i0]), float(x[i1]), effort, d, touching, comps, t0, options,
                              progress, counters, grasp)  # fmt: skip
        except PlanFailure as exc:
            step = 1 if i1 > i0 else -1
            bad = next((i for i in range(i0, i1 + step, step)
                        if not check_contact_state(task, x[i], effort, d, touching, comps, grasp).ok), i1)  # fmt: skip
            raise _Rejected(("cell", g, e, int(d > 0), bad), exc) from None
        phases.append(seg)
        seq.append({"kind": "slide", "grasp": grasp.label, "x_from": float(x[i0]), "x_to": float(x[i1]),
                    "effort_joint": effort, "narrowest_band": float(np.min(seg.width))})  # fmt: skip
        q_now, t0 = seg.q[-1], float(seg.t[-1])
    return phases, seq


class _Rejected(Exception):
    """A proposed phase the realisation refused: ``what`` names the table cell or regrasp to drop."""

    def __init__(self, what, failure):
        super().__init__(str(failure))
        self.what, self.failure = what, failure


def plan_automatic(task, options=None, progress=None, planner: str = "widest", tables=None) -> Plan:
    """Plan an automatic task (one with a ``goal``): see the module docstring.

    Parameters
    ----------
    task : qsplan.planner.task.task.Task
        With ``task.goal``.
    options : qsplan.planner.search.ompl_bridge.PlannerOptions, optional
        The regrasps' OMPL queries (default :data:`qsplan.planner.plan.scripted.DEFAULT_OPTIONS`).
    progress : callable, optional
    planner : str
        The sequence search (:data:`qsplan.planner.search.ompl_search.SEQUENCE_PLANNERS`).
    tables : BandTables, optional
        Precomputed tables (benchmarks reuse them across planners).

    Returns
    -------
    Plan
        With ``sequence``: the phases chosen and the search's figures.

    Raises
    ------
    PlanFailure
        No route, with the report of what blocks it.
    """
    from qsplan.hands.grasp_geometry import candidate_grasps
    from qsplan.planner.plan.obstacles import no_route_report, unreachable_goal_report
    from qsplan.planner.plan.phases import DEFAULT_OPTIONS

    if task.goal is None:
        raise QsplanError("goal: the task has no [goal] (a scripted task: plan it with plan_task)")
    options = options or DEFAULT_OPTIONS
    progress = progress or (lambda line: None)
    t_start = time.perf_counter()
    if tables is None:
        grasps = candidate_grasps(task.hand)
        from qsplan.planner.task.goal import palm_x_range

        grid = table_grid(task.start_x, task.goal.x, palm_x_range(task.hand))  # never the workpiece off the palm
        progress(f"band tables: {len(grasps)} candidate grasps x {len(grid)} workpiece positions "
                 f"({grid[0]:.4g} to {grid[-1]:.4g} m)")  # fmt: skip
        tables = band_tables(task, grasps, grid)
    progress(f"  {tables.states} configurations and {tables.band_states} guaranteed bands in {tables.seconds:.2f} s")
    i_start, i_goal = tables.index(task.start_x), tables.index(task.goal.x)
    starts = [g for g, _ in start_nodes(tables, task)]
    goals = goal_nodes(tables, task)
    if not starts:
        raise PlanFailure(unreachable_goal_report(task, tables, i_start, "start", _start_grasps))
    if not goals:
        raise PlanFailure(unreachable_goal_report(task, tables, i_goal, "goal", _goal_grasps))
    if any(s == g for s in ((st, i_start) for st in starts) for g in goals):
        raise QsplanError(f"goal: the start already meets the goal ({task.goal.describe()}): nothing to plan")
    forbidden, counters, rounds, search_s, evaluations = set(), [0, 0.0], 0, 0.0, 0
    width = tables.graph.width.copy()
    while True:
        rounds += 1
        graph = replace(tables.graph, width=width)
        results = [search_route(graph, (s, i_start), goals, planner, forbidden) for s in starts]
        search_s += sum(r.seconds for r in results)
        evaluations += sum(r.evaluations for r in results)
        found = [r for r in results if r.route is not None]
        if not found:
            raise PlanFailure(no_route_report(task, tables, graph, starts, i_start, goals, forbidden))
        best = max(found, key=lambda r: (r.route.width, -r.route.regrasps, -len(r.route.steps)))
        route = best.route
        progress(f"route ({planner}, round {rounds}): {len(route.steps)} steps, {route.regrasps} regrasps, narrowest "
                 f"band {route.width:.4g} N m, {best.evaluations} evaluations in {best.seconds:.3f} s")  # fmt: skip
        try:
            phases, seq = _realise(task, tables, route, options, progress, counters)
            break
        except _Rejected as rej:
            if rounds >= MAX_ROUNDS:
                raise rej.failure from None
            what = rej.what
            progress(f"  rejected by the final check: {rej}; searching again")
            if what[0] == "regrasp":
                forbidden.add(what[1:])
            else:
                _, g, e, d, i = what
                width[g, e, d, i] = -np.inf
    meta = {"kind": "search", "planner": planner, "rounds": rounds, "grasps": len(tables.grasps), "grid_points": int(len(tables.x)),
            "grid_step_m": float(np.min(np.abs(np.diff(tables.x)))) if len(tables.x) > 1 else 0.0,
            "table_states": int(tables.states), "band_states": int(tables.band_states),
            "table_seconds": float(tables.seconds), "search_seconds": float(search_s),
            "search_evaluations": int(evaluations), "route_width": float(route.width)}  # fmt: skip
    # states judged: every in-contact state check of the tables (a scene and a guaranteed band with competitors
    # precluded, per configuration, torque-controlled finger and direction), then the dense sweeps and OMPL's checks
    plan = Plan(task, tuple(phases), time.perf_counter() - t_start, counters[0] + tables.band_states,
                counters[1] + tables.seconds, options, tuple(seq) + (meta,))  # fmt: skip
    plan.check()
    if not any(isinstance(p, ContactSegmentPlan) for p in plan.phases):
        raise QsplanError("goal: reached by regrasps alone; the plan has no in-contact segment to export")
    return plan
