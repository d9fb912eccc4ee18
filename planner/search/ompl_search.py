"""The sequence search in OMPL: a grasp-and-x state space, our widest-band planner, OMPL's sampling planners.

The space is OMPL's compound of a discrete component (the grasp: which feature each finger
touches, an index into the candidate grasps) and a real one (the workpiece's ``x`` as a grid
coordinate ``0 .. n - 1`` of the band tables).  A motion between two states is a 4S slide in
the first state's grasp along the grid, followed, when the grasps differ, by a regrasp at the
second state's ``x`` (both fingers release and close on the new features, the workpiece resting
on the palm).  Its width is the narrowest band along the slide (N m; unbounded for a pure
regrasp), read from the tables of :class:`qsplan.planner.search.widest.SearchGraph`.

Planners offered (:data:`SEQUENCE_PLANNERS`):

* ``"widest"``: :class:`WidestBandPlanner`, an ``ob.Planner`` subclass that runs the exact
  widest-route search of :func:`qsplan.planner.search.widest.widest_route` on the tables (the
  graph is the tables; the answer is optimal at their resolution and deterministic);
* ``"RRTstar"``, ``"BITstar"``: OMPL's asymptotically optimal sampling planners with a minimax
  objective (:class:`NarrowestBandObjective`: a path costs ``1 / width`` of its narrowest motion,
  combined by ``max``), a Python motion validator on the tables, an iteration budget (same seed,
  same answer).  Offered for comparison (``benchmarks/bench_autoplan.py``): a sampled ``x``
  rarely coincides for two grasps, so they find regrasps only where a motion ends in one.

Everything OMPL-specific stays inside :func:`search_route`, as the cookbook
(``shared/notes/ompl2_python_cookbook.md``) advises: no OMPL object outlives the call.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from qsplan.planner.search.widest import Route, RouteStep, SearchGraph, slide_widths, widest_route

__all__ = ["SEQUENCE_PLANNERS", "SearchResult", "search_route"]

#: Planners of the sequence search: ours (exact on the tables) first, the default.
SEQUENCE_PLANNERS = ("widest", "RRTstar", "BITstar")


@dataclass(frozen=True, slots=True)
class SearchResult:
    """A route and what finding it cost.

    Attributes
    ----------
    route : Route or None
    planner : str
    seconds : float
        Wall time of the OMPL solve (s).
    evaluations : int
        Table look-ups (validity checks and motion checks) or nodes expanded (``"widest"``).
    status : str
        OMPL's status in words.
    """

    route: Route | None
    planner: str
    seconds: float
    evaluations: int
    status: str


def _motion_steps(graph, edges, g1, i1, g2, i2, forbidden):
    """The route steps of the motion ``(g1, i1) -> (g2, i2)`` (slide in g1, then regrasp), or None if not allowed."""
    steps = []
    d = 1 if i2 > i1 else 0
    for i in (range(i1, i2) if d else range(i1, i2, -1)):
        j = i + 1 if d else i - 1
        k = i if d else j  # the edge's index in `edges`
        e = int(np.argmax(edges[g1, :, d, k]))
        w = float(edges[g1, e, d, k])
        if w == -np.inf:
            return None
        steps.append(RouteStep("slide", g1, i, g1, j, e, w))
    if g1 != g2:
        if not graph.valid[g2, i2] or (g1, g2, i2) in forbidden:
            return None
        steps.append(RouteStep("regrasp", g1, i2, g2, i2, -1, np.inf))
    return steps


def _route_from_states(graph, edges, states, forbidden, evaluations):
    steps = []
    for (g1, i1), (g2, i2) in zip(states[:-1], states[1:]):
        s = _motion_steps(graph, edges, g1, i1, g2, i2, forbidden)
        if s is None:
            return None
        steps.extend(s)
    widths = [s.width for s in steps if s.is_slide]
    return Route(tuple(steps), min(widths, default=np.inf), sum(not s.is_slide for s in steps), evaluations)


def search_route(graph: SearchGraph, start, goals, planner: str = "widest", forbidden=frozenset(), seed: int = 1,
                 iterations: int = 3000) -> SearchResult:  # fmt: skip
    """Find a route from ``start`` to one of ``goals`` (``(grasp, i)`` nodes) with ``planner`` inside OMPL.

    Parameters
    ----------
    graph : SearchGraph
    start : (int, int), or a list of them
        Several: the route may begin at any (the widest search runs once from all of them).
    goals : sequence of (int, int)
    planner : str
        One of :data:`SEQUENCE_PLANNERS`.
    forbidden : set of (int, int, int)
        Regrasps ``(from, to, i)`` not to use.
    seed : int
        OMPL's RNG seed (sampling planners).
    iterations : int
        Iteration budget of the sampling planners.

    Returns
    -------
    SearchResult
    """
    from ompl import base as ob, geometric as og, util as ou

    if planner not in SEQUENCE_PLANNERS:
        from qsplan.mechanics.errors import QsplanError

        raise QsplanError(f"planner: expected one of {', '.join(SEQUENCE_PLANNERS)}; got {planner!r}")
    G, n = graph.shape
    starts = [(int(a), int(b)) for a, b in (start if len(start) and not np.isscalar(start[0]) else [start])]
    goals = [tuple(map(int, g)) for g in goals]
    forbidden = frozenset(forbidden)
    edges = slide_widths(graph)
    counter, found = [0], [None]
    ou.setLogLevel(ou.LOG_NONE)
    ou.RNG.setSeed(int(seed))

    space = ob.CompoundStateSpace()
    space.addSubspace(ob.DiscreteStateSpace(0, max(G - 1, 1)), 1.0)  # OMPL refuses a one-value discrete space
    real = ob.RealVectorStateSpace(1)
    real.setBounds(0.0, float(n - 1))
    space.addSubspace(real, 1.0)
    space.registerDefaultProjection(ob.SubspaceProjectionEvaluator(space, 1))
    si = ob.SpaceInformation(space)

    def node(s):
        return int(s[0].value), int(round(min(max(s[1][0], 0.0), n - 1.0)))

    def valid(s):
        counter[0] += 1
        g, i = node(s)
        return bool(g < G and graph.valid[g, i])

    def motion_width(a, b):
        counter[0] += 1
        if node(a)[0] >= G or node(b)[0] >= G:
            return None
        steps = _motion_steps(graph, edges, *node(a), *node(b), forbidden)
        if steps is None:
            return None
        return min((s.width for s in steps if s.is_slide), default=np.inf)

    class TableMotions(ob.MotionValidator):
        def checkMotion(self, a, b):
            return motion_width(a, b) is not None

    class NarrowestBandObjective(ob.OptimizationObjective):
        """Minimax: a path costs ``1 / width`` of its narrowest motion (``max`` combines)."""

        def stateCost(self, s):
            return ob.Cost(0.0)

        def motionCost(self, a, b):
            w = motion_width(a, b)
            return ob.Cost(np.inf if w is None else (0.0 if w == np.inf else 1.0 / max(w, 1e-300)))

        def combineCosts(self, c1, c2):
            return ob.Cost(max(c1.value(), c2.value()))

        def identityCost(self):
            return ob.Cost(0.0)

    class WidestBandPlanner(ob.Planner):
        """The exact widest-route search on the band tables, as an OMPL planner."""

        def __init__(self, si_):
            super().__init__(si_, "WidestBand")

        def solve(self, ptc):
            # the start and goals come from the closure: a state read back through
            # pdef.getStartState() is freed twice at teardown (segfault, ompl 2.0.1)
            pdef = self.getProblemDefinition()
            route = widest_route(graph, starts if len(starts) > 1 else starts[0], goals, forbidden)
            found[0] = route
            if route is None:
                return ob.PlannerStatus(ob.PlannerStatus.TIMEOUT)
            path = og.PathGeometric(si)
            s0 = (route.steps[0].grasp, route.steps[0].i) if route.steps else starts[0]
            for g, i in [s0] + [(step.to_grasp, step.to_i) for step in route.steps]:
                st = si.allocState()
                st[0].value = int(g)
                st[1][0] = float(i)
                path.append(st)
            pdef.addSolutionPath(path)
            return ob.PlannerStatus(ob.PlannerStatus.EXACT_SOLUTION)

    ss = og.SimpleSetup(si)
    ss.setStateValidityChecker(valid)
    mover = TableMotions(si)
    si.setMotionValidator(mover)
    start_s = si.allocState()
    start_s[0].value, start_s[1][0] = starts[0][0], float(starts[0][1])
    goal = ob.GoalStates(si)
    for g, i in goals:
        st = si.allocState()
        st[0].value, st[1][0] = g, float(i)
        goal.addState(st)
    ss.setStartState(start_s)
    for a, b in starts[1:]:
        more = si.allocState()
        more[0].value, more[1][0] = a, float(b)
        ss.getProblemDefinition().addStartState(more)
    ss.setGoal(goal)
    objective = None
    if planner == "widest":
        p = WidestBandPlanner(si)
    else:
        objective = NarrowestBandObjective(si)
        ss.setOptimizationObjective(objective)
        p = getattr(og, planner)(si)
    ss.setPlanner(p)
    k = [0]

    def done():
        k[0] += 1
        return k[0] > iterations

    t0 = time.perf_counter()
    status = ss.solve(ob.PlannerTerminationCondition(done))
    seconds = time.perf_counter() - t0
    exact = status.getStatus() == ob.PlannerStatus.EXACT_SOLUTION
    text = str(status)
    route = None
    if planner == "widest":
        route = found[0]
        evaluations = route.nodes_expanded if route is not None else 0
    else:
        evaluations = counter[0]
        if exact:
            path = og.PathGeometric(ss.getSolutionPath())
            states = [node(s) for s in path.getStates()]
            del path
            route = _route_from_states(graph, edges, states, forbidden, evaluations)
    return SearchResult(route, planner, seconds, evaluations, text)
