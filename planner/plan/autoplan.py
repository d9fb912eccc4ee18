"""Automatic planning: from a start grasp to a goal grasp, the sequence with the widest guaranteed band.

:func:`plan_automatic` is :func:`qsplan.planner.plan.scripted.plan_task` for tasks with a ``[goal]``:

1. **Tables.**  Every candidate grasp of the hand (:func:`qsplan.hands.paper_hand.grasps.candidate_grasps`:
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

from qsplan.hands.protocol import JOINT_UNITS
from qsplan.mechanics.errors import QsplanError

from qsplan.planner.plan.release import release_holds
from qsplan.planner.plan.results import ContactSegmentPlan, Plan, PlanFailure
from qsplan.planner.plan.steps import RegraspStep, SearchSummary, SlideStep, realised_steps
from qsplan.planner.plan.timing import time_scale
from qsplan.planner.search.ompl_search import search_route
from qsplan.planner.search.tables import band_tables, table_grid
from qsplan.planner.task.goal import feature_text

__all__ = ["FREE_GRID", "FREE_SEARCH_MARGIN", "GOAL_FREE_TOL", "MAX_GOAL_GRASPS", "MAX_ROUNDS", "ending_in_place",
           "grasp_rows", "goal_nodes", "plan_automatic", "route_phases", "start_nodes"]

#: Rounds of search and realisation: each failed round closes a table cell or forbids a regrasp, so a
#: handful suffices; the bound keeps a pathological task from looping.
MAX_ROUNDS = 12

#: Values per free joint of the grid from which a described hand's grasps are sought where the task names no
#: ``[start]`` (and its goal grasps always): 13 values of a 3 rad range are 0.22 rad apart, about 2 cm at the tip of
#: a 7 cm link; two-link fingers then close from 13 x 13 = 169 rows (each closing batched over the whole palm).
FREE_GRID = 13

#: How close (rad or m) a goal row's free joints must come to the values a route must end with
#: (:func:`goal_nodes`' ``goal_free``: a slide that a turn continues from its flush instant, whose free joints the
#: pivot holds): the tables copy those values into a held row, so they agree to round-off; any other row of the grid
#: is at least a grid step (0.2 rad) away.
GOAL_FREE_TOL = 1e-9

#: Most goal grasps a described hand's tables keep (a spread of the valid ones): each adds two rows (held at the goal,
#: sloped from each start grasp) to tables whose every state is judged.
MAX_GOAL_GRASPS = 6

#: How far (m) beyond the start and the goal a described hand's tables reach: its rows are straight lines between
#: start and goal grasps, so detours matter less than to the paper hand's (qsplan.planner.search.tables.SEARCH_MARGIN)
#: and every grid point costs a band per row and effort joint.
FREE_SEARCH_MARGIN = 0.01

#: Two free-joint vectors closer than this (rad or m) in every joint are the same start (a task's [start] as written
#: against a grid row).
SAME_FREE = 1e-9


def _start_grasps(tables, task, i):
    """Indices of the valid rows that meet the task's start at grid index ``i``: its features (a hand without free
    joints) or its ``[start]`` free joints (a hand with them, where given)."""
    free = bool(task.hand.free_joints)  # a hand with free joints starts from them ([start] by name), not features
    feats = [None, None] if free else [feature_text(f) for f in task.start_features]
    out = []
    for g in range(len(tables.grasps)):
        if not (tables.graph.valid[g, i] and _meets(tables, task, g, i, feats)):
            continue
        if task.start_joints is not None and task.hand.free_joints:
            free = list(task.hand.free_joints)
            if np.any(np.abs(tables.q[g, i, free] - task.start_joints[free]) > SAME_FREE):
                continue
        out.append(g)
    return out


def _meets(tables, task, g, i, feats) -> bool:
    """Whether row ``g`` at grid index ``i`` touches the features ``feats`` (left, right: text or None)
    (:func:`qsplan.hands.paper_hand.grasps.grasp_meets`)."""
    from qsplan.hands.paper_hand.grasps import grasp_meets

    return grasp_meets(task.hand, tables.grasps[g].grasp, tables.graph.touched[g, i, :2], feats)


def _goal_grasps(tables, task, i):
    feats = [feature_text(task.goal.left), feature_text(task.goal.right)]
    return [g for g in range(len(tables.grasps)) if _meets(tables, task, g, i, feats)]


def start_nodes(tables, task) -> list:
    """The search's start nodes ``(grasp, i)``: the valid rows meeting the task's start at its start."""
    i = tables.index(task.start_x)
    return [(g, i) for g in _start_grasps(tables, task, i)]


def goal_nodes(tables, task, goal_free=None) -> list:
    """The search's goal nodes ``(grasp, i)``: the valid rows meeting the goal's features at the goal x; with
    ``goal_free`` (the free joints' values, rad or m, in the order of ``task.hand.free_joints``) only the rows holding
    those values there (to :data:`GOAL_FREE_TOL`)."""
    i = tables.index(task.goal.x)
    nodes = [(g, i) for g in _goal_grasps(tables, task, i) if tables.graph.valid[g, i]]
    if goal_free is None:
        return nodes
    free = list(task.hand.free_joints)
    want = np.asarray(goal_free, dtype=float)
    return [(g, j) for g, j in nodes if np.all(np.abs(tables.q[g, j, free] - want) <= GOAL_FREE_TOL)]


def ending_in_place(tables, goals, goal_free) -> set:
    """The regrasps a route ending at ``goals`` must not use: with ``goal_free`` (a turn's slide, continued from its
    flush instant) every regrasp into a goal node's grasp, so the route ends with a slide in that grasp and its last
    row is the flush instant itself; without, none.  ``(from grasp, to grasp, grid index)``, as
    :func:`qsplan.planner.search.widest.widest_route` takes them."""
    if goal_free is None:
        return set()
    return {(h, g, i) for g, i in goals for h in range(len(tables.grasps)) if h != g}


def _free_joints_report(task, tables, i, goal_free):
    """The goal's features are met at grid index ``i``, but by no row holding the free joints at ``goal_free`` (a turn's
    flush instant): a configuration report naming the joints, the values asked and those the valid rows hold."""
    from qsplan.planner.plan.failure import ConfigurationReport

    hand = task.hand
    free = list(hand.free_joints)
    names = [hand.joint_names[j] for j in free]
    units = [JOINT_UNITS[hand.joint_kinds[j]]["q"] for j in free]
    asked = ", ".join(f"{n} = {v:.6g} {u}" for n, v, u in zip(names, goal_free, units))
    held = sorted({tuple(round(float(v), 6) for v in tables.q[g, j, free]) for g, j in goal_nodes(tables, task)})
    rows = "; ".join(", ".join(f"{n} = {v:.6g} {u}" for n, v, u in zip(names, h, units)) for h in held[:4])
    reason = (f"the goal's features are met at x = {float(tables.x[i]):.4g} m only by grasps holding the free joints "
              f"elsewhere ({rows}), none at the values the route must end with ({asked})")  # fmt: skip
    return ConfigurationReport("the goal", "the goal", float(tables.x[i]), None, reason)


def route_phases(route) -> list:
    """The route's steps grouped into phases: ``("slide", grasp, i0, i1, effort)`` (a run of steps in one grasp,
    effort joint and direction) and ``("regrasp", from grasp, to grasp, i)``."""
    out = []
    for s in route.steps:
        if not s.is_slide:
            out.append(("regrasp", s.grasp, s.to_grasp, s.i))
            continue
        if out and out[-1][0] == "slide":
            _, g, i0, i1, e = out[-1]
            if g == s.grasp and e == s.effort and i1 == s.i and np.sign(s.to_i - s.i) == np.sign(i1 - i0):
                out[-1] = ("slide", g, i0, s.to_i, e)
                continue
        out.append(("slide", s.grasp, s.i, s.to_i, s.effort))
    return out


def grasp_rows(task, x0: float, x1: float) -> tuple:
    """The tables' rows for a task from ``x0`` to ``x1`` (m): every grasp candidate of a hand without free joints,
    held; for a hand with free joints, the grasps of the start (its ``[start]``, else a grid of the free joints) and of
    the goal (a grid), each held, and for every start and goal grasp touching the same features the straight line
    between them (the free joints sloping from one to the other as the workpiece slides: the contact manifold's
    simplest path)."""
    from qsplan.planner.plan.phases import FreePath
    from qsplan.planner.search.tables import GraspRow

    hand, formation = task.hand, task.formation
    if not hand.free_joints:
        return tuple(GraspRow(g) for g in hand.grasp_candidates(formation))
    free = list(hand.free_joints)
    lim = task.joint_limits[free]
    axes = [np.linspace(lo, hi, FREE_GRID + 2)[1:-1] for lo, hi in lim]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, len(free))
    starts = task.start_joints[free][None] if task.start_joints is not None else grid
    start = _valid_at(task, hand.grasp_candidates(formation, starts, [x0]), x0)
    goal_feats = (None, None) if task.goal is None else (feature_text(task.goal.left), feature_text(task.goal.right))
    at_goal = _valid_at(task, hand.grasp_candidates(formation, grid, [x1]), x1)
    goals = _spread([g for g in at_goal if g.matches(*goal_feats)])
    keys = {s.keys for s in start}  # grasps at the goal the start's contacts slide to (then a regrasp if need be)
    ends = _spread([g for g in at_goal if g.keys in keys and g not in goals]) + goals
    rows = [GraspRow(g) for g in start] + [GraspRow(g) for g in goals]
    zero = np.zeros(len(hand.joint_names))
    for s in start:
        for g in ends:
            if g.keys == s.keys and x1 != x0:
                slope = zero.copy()
                slope[free] = (np.asarray(g.free) - np.asarray(s.free)) / (x1 - x0)
                rows.append(GraspRow(s, FreePath(float(x0), np.asarray(s.free, float), slope, tuple(free), float(x1))))
    return tuple(rows)


def _spread(grasps) -> list:
    """At most :data:`MAX_GOAL_GRASPS` of ``grasps``, spread over the list (the grid's order)."""
    return list(grasps[:: max(1, int(np.ceil(len(grasps) / MAX_GOAL_GRASPS)))])


def _valid_at(task, grasps, x: float) -> list:
    """The grasps of ``grasps`` that are configurations at ``x`` (their contacts, inside the limits, no overlap)."""
    hand, lim = task.hand, task.joint_limits
    states = [hand.grasp_states(task.formation, g, np.array([x])) for g in grasps]
    ok = [k for k, st in enumerate(states) if st.ok[0] and np.all((st.q[0] >= lim[:, 0]) & (st.q[0] <= lim[:, 1]))]
    if not ok:
        return []
    hit = hand.collide(np.vstack([states[k].poses for k in ok]), np.vstack([states[k].q for k in ok]))
    return [grasps[k] for k, h in zip(ok, hit) if not h]


def _realise(task, tables, route, options, progress, counters):
    """The route's phases as plan phases; raises ``_Rejected`` naming the table cell or regrasp to drop."""
    from qsplan.planner.plan.phases import regrasp_phase, slide_phase
    from qsplan.planner.states.contact import check_contact_state, contact_samples
    from qsplan.planner.torque.sweep import competing_modes

    hand = task.hand
    x, q_tab = tables.x, tables.q
    phases, seq, t0 = [], [], 0.0
    q_now = None
    n_slide = n_regrasp = 0
    for ph in route_phases(route):
        if ph[0] == "regrasp":
            _, g, h, i = ph
            n_regrasp += 1
            q_from = q_now if q_now is not None else q_tab[g, i]
            rg, rh = tables.grasps[g], tables.grasps[h]
            name = f"regrasp {n_regrasp}: release at x = {x[i]:.4g} m and grasp {rh.label} (from {rg.label})"
            try:
                r = regrasp_phase(task, name, float(x[i]), q_from, q_tab[h, i], t0, options, progress, counters,
                                  hand.opening(rg.grasp, x[i], q_from), hand.opening(rh.grasp, x[i], q_tab[h, i]))  # fmt: skip
            except PlanFailure as exc:
                raise _Rejected(("regrasp", g, h, i), exc) from None
            phases.append(r)
            seq.append(RegraspStep(float(x[i]), rg.label, rh.label))
            q_now, t0 = r.q[-1], float(r.t[-1])
            continue
        _, g, i0, i1, e = ph
        n_slide += 1
        row, effort, d = tables.grasps[g], tables.efforts[e], float(np.sign(i1 - i0))
        name = (f"segment {n_slide}: slide the workpiece {'left' if d < 0 else 'right'} from x = {x[i0]:.4g} to "
                f"{x[i1]:.4g} m, grasp {row.label}")  # fmt: skip
        xs = np.linspace(x[i0], x[i1], 9)
        path = row.path
        line = contact_samples(task, xs, effort, d * task.workpiece_speed, grasp=row.grasp,
                               free=None if path is None else path.at(xs),
                               free_rates=None if path is None else path.rates(len(xs), d * task.workpiece_speed))  # fmt: skip
        comps = competing_modes(line)
        touching = line.touching[0]
        try:
            seg = slide_phase(task, name, float(x[i0]), float(x[i1]), effort, d, touching, comps, t0, options,
                              progress, counters, row.grasp, path)  # fmt: skip
        except PlanFailure as exc:
            step = 1 if i1 > i0 else -1

            def bad(i):
                free = None if path is None else path.at([x[i]])[0]
                return not check_contact_state(task, x[i], effort, d, touching, comps, row.grasp, free,
                                               None if path is None else path.slope).ok  # fmt: skip

            worst = next((i for i in range(i0, i1 + step, step) if bad(i)), i1)
            raise _Rejected(("cell", g, e, int(d > 0), worst), exc) from None
        phases.append(seg)
        seq.append(SlideStep(row.label, float(x[i0]), float(x[i1]), effort, float(np.min(seg.width)),
                             JOINT_UNITS[hand.joint_kinds[hand.joint_names.index(effort)]]["tau"]))  # fmt: skip
        q_now, t0 = seg.q[-1], float(seg.t[-1])
    return phases, seq


class _Rejected(Exception):
    """A proposed phase the realisation refused: ``what`` names the table cell or regrasp to drop."""

    def __init__(self, what, failure):
        super().__init__(str(failure))
        self.what, self.failure = what, failure


def plan_automatic(task, options=None, progress=None, planner: str = "widest", tables=None, timed: bool = True,
                   goal_free=None) -> Plan:  # fmt: skip
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
    timed : bool
        Time-scale the plan (:func:`qsplan.planner.plan.timing.time_scale`); False: the quasistatic phases, for a
        route that continues them (:mod:`qsplan.planner.plan.turning`).
    goal_free : array-like, optional
        The free joints' values (rad or m, ``task.hand.free_joints``' order) the route must end with
        (:func:`goal_nodes`), sliding (no regrasp into its last grasp): a turn's slide ends at its formation's flush
        instant, whose free joints the pivot holds, and the turn continues from its last row.

    Returns
    -------
    Plan
        With ``sequence``: the phases chosen and the search's figures.

    Raises
    ------
    PlanFailure
        No route, with the report of what blocks it.
    """
    from qsplan.planner.plan.obstacles import no_route_report, unreachable_goal_report
    from qsplan.planner.plan.phases import DEFAULT_OPTIONS
    from qsplan.planner.search.tables import SEARCH_MARGIN

    if task.goal is None:
        raise QsplanError("goal: the task has no [goal] (a scripted task: plan it with plan_task)")
    options = options or DEFAULT_OPTIONS
    progress = progress or (lambda line: None)
    t_start = time.perf_counter()
    if tables is None:
        from qsplan.planner.task.goal import palm_x_range

        grasps = grasp_rows(task, task.start_x, task.goal.x)
        margin = FREE_SEARCH_MARGIN if task.hand.free_joints else SEARCH_MARGIN
        grid = table_grid(task.start_x, task.goal.x, palm_x_range(task.hand), margin=margin)  # never off the palm
        progress(f"band tables: {len(grasps)} candidate grasps x {len(grid)} workpiece positions "
                 f"({grid[0]:.4g} to {grid[-1]:.4g} m)")  # fmt: skip
        tables = band_tables(task, grasps, grid)
    progress(f"  {tables.states} configurations and {tables.band_states} guaranteed bands in {tables.seconds:.2f} s")
    i_start, i_goal = tables.index(task.start_x), tables.index(task.goal.x)
    starts = [g for g, _ in start_nodes(tables, task)]
    goals = goal_nodes(tables, task, goal_free)
    if not starts:
        raise PlanFailure(unreachable_goal_report(task, tables, i_start, "start", _start_grasps))
    if not goals and goal_free is not None and goal_nodes(tables, task):  # the features are met, the joints not
        raise PlanFailure(_free_joints_report(task, tables, i_goal, goal_free))
    if not goals:
        raise PlanFailure(unreachable_goal_report(task, tables, i_goal, "goal", _goal_grasps))
    if any(s == g for s in ((st, i_start) for st in starts) for g in goals):
        raise QsplanError(f"goal: the start already meets the goal ({task.goal.describe()}): nothing to plan")
    counters, rounds, search_s, evaluations = [0, 0.0], 0, 0.0, 0
    forbidden = ending_in_place(tables, goals, goal_free)  # a turn's slide ends sliding in its goal grasp
    width = tables.graph.width.copy()
    while True:
        rounds += 1
        graph = replace(tables.graph, width=width)
        # the widest search runs once from every start; a sampling planner from each start in turn
        nodes = [[(s, i_start) for s in starts]] if planner == "widest" and len(starts) > 1 else [(s, i_start) for s in starts]
        results = [search_route(graph, node, goals, planner, forbidden) for node in nodes]
        search_s += sum(r.seconds for r in results)
        evaluations += sum(r.evaluations for r in results)
        found = [r for r in results if r.route is not None]
        if not found:
            raise PlanFailure(no_route_report(task, tables, graph, starts, i_start, goals, forbidden))
        best = max(found, key=lambda r: (r.route.width, -r.route.regrasps, -len(r.route.steps)))
        route = best.route
        units = sorted({task.hand.joint_unit(e, "tau") for e in tables.efforts})  # a jaw's force in N
        progress(f"route ({planner}, round {rounds}): {len(route.steps)} steps, {route.regrasps} regrasps, narrowest "
                 f"band {route.width:.4g} {' or '.join(units)}, {best.evaluations} evaluations in "
                 f"{best.seconds:.3f} s")  # fmt: skip
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
    meta = SearchSummary(planner, rounds, len(tables.grasps), int(len(tables.x)),
                         float(np.min(np.abs(np.diff(tables.x)))) if len(tables.x) > 1 else 0.0, int(tables.states),
                         int(tables.band_states), float(tables.seconds), float(search_s), int(evaluations),
                         float(route.width))  # fmt: skip
    # states judged: every in-contact state check of the tables (a scene and a guaranteed band with competitors
    # precluded, per configuration, torque-controlled finger and direction), then the dense sweeps and OMPL's checks
    plan = Plan(task, tuple(phases), time.perf_counter() - t_start, counters[0] + tables.band_states,
                counters[1] + tables.seconds, options, tuple(seq) + (meta,))  # fmt: skip
    if not timed:
        return plan
    plan = time_scale(plan)
    plan = replace(plan, sequence=realised_steps(plan.sequence, plan.phases))  # the steps as the rows are timed
    plan = release_holds(plan)  # every release from an unloaded hold (qsplan.planner.plan.release)
    plan.check()
    if not any(isinstance(p, ContactSegmentPlan) for p in plan.phases):
        raise QsplanError("goal: reached by regrasps alone; the plan has no in-contact segment to export")
    return plan
