"""The widest-band sequence of slides and regrasps over band tables: exact at the tables' resolution.

The search graph (issue 14, Section 5.2): a node is a grasp ``g`` (which feature each finger
touches) and a grid index ``i`` of the workpiece's ``x``.  Two kinds of edge:

* **slide** ``(g, i) -> (g, i +- 1)`` in mode 4S, with effort-controlled finger ``e``: allowed where
  both ends are valid configurations touching the same features and the guaranteed band of
  ``(g, e, direction)`` (every competitor precluded, :func:`qsplan.mechanics.robust_band`) is at
  least the torque resolution wide at both; its *width* is the narrower of the two;
* **regrasp** ``(g, i) -> (g', i)``: both fingers release and close on other features, the
  workpiece resting on the palm; width unbounded (no band is needed), allowed unless
  ``forbidden`` (a regrasp the motion planner could not realise).

A route's width is its narrowest edge.  :func:`widest_route` finds the route from the start node
to a goal node whose width is largest (a max-min Dijkstra), then, among the routes at least that
wide, the one with the fewest regrasps, then the fewest slide steps (time at the constant
speeds of the plan), then the fewest segments (changes of finger, direction or grasp), then the
smallest **peak squeeze** (:func:`slide_efforts`: the largest, over its slide steps, of the
torque some joint must hold at the friction set's worst point): a lexicographic Dijkstra on the
graph restricted to edges at least that wide (the peak combines by ``max``, which keeps the order
isotone, so the label-setting search stays exact).  The last key decides between routes the others
cannot tell apart, above all those of bands unbounded on one side (width ``inf``): a band
``(-inf, -40] N m`` is as wide as ``(-inf, -0.4]`` and as ``[0.003, inf)``, but the state asks a
squeeze a hundred times larger (a wedge nearing a jam; a compliant hand stores it and kicks the
workpiece when it lets go); then each segment torque-controls, of the joints whose bands are at
least that wide along it, the one whose command can stay nearest 0.  Both stages are exact on the
graph, so the route is optimal at the tables' resolution; the plan built from it is checked again
sample by sample (:func:`qsplan.planner.plan.scripted.sweep_contact_segment`).

Plain Python and numpy, no OMPL: :mod:`qsplan.planner.search.ompl_search` runs this search as an
OMPL planner.  Units SI (m, N m).
"""

from __future__ import annotations

import heapq
from dataclasses import dataclass, replace

import numpy as np

__all__ = ["Route", "RouteStep", "SearchGraph", "least_effort", "slide_efforts", "slide_widths", "widest_route"]


@dataclass(frozen=True, slots=True)
class RouteStep:
    """One edge of a route: a slide step or a regrasp.

    Attributes
    ----------
    kind : {"slide", "regrasp"}
    grasp, i : int
        The node the edge leaves (grasp index, grid index).
    to_grasp, to_i : int
        The node it reaches.
    effort : int
        Slides: the effort-controlled joint (an index into the tables' ``efforts``); regrasps: -1.
    width : float
        The edge's width (N m; ``inf`` for regrasps).
    """

    kind: str
    grasp: int
    i: int
    to_grasp: int
    to_i: int
    effort: int
    width: float

    @property
    def is_slide(self) -> bool:
        """Whether the edge is a slide step (else a regrasp): what the route's readers ask, not the string."""
        return self.kind == "slide"


@dataclass(frozen=True, slots=True)
class Route:
    """A route from the start node to a goal node.

    Attributes
    ----------
    steps : tuple of RouteStep
    width : float
        Its narrowest edge (N m); ``inf`` for a route without slides.
    regrasps : int
    nodes_expanded : int
        Nodes popped by both stages of the search (the work done).
    """

    steps: tuple
    width: float
    regrasps: int
    nodes_expanded: int


@dataclass(frozen=True, slots=True, eq=False)
class SearchGraph:
    """The band tables the search reads.

    Attributes
    ----------
    valid : ndarray of bool, shape (G, n)
        Grasp ``g`` is a valid configuration at grid point ``i`` (contacts found, joint limits, no overlap).
    touched : ndarray of int, shape (G, n, 2)
        The feature each finger touches (a change between neighbours ends a slide).
    width : ndarray, shape (G, E, 2, n)
        Guaranteed band width (N m or N) for grasp, effort joint (the tables' ``efforts``), direction (0: -x, 1: +x);
        ``-inf`` where there is none (or the configuration is invalid).
    resolution : float
        The torque resolution (N m): narrower bands do not count.
    lower, upper : ndarray, shape (G, E, 2, n), optional
        The bands' edges (N m or N; NaN without one), for the peak-squeeze key (:func:`slide_efforts`); without
        them every route's peak squeeze is 0 (the key decides nothing).
    """

    valid: np.ndarray
    touched: np.ndarray
    width: np.ndarray
    resolution: float
    lower: np.ndarray | None = None
    upper: np.ndarray | None = None

    @property
    def shape(self) -> tuple:
        return self.valid.shape


def slide_widths(graph: SearchGraph) -> np.ndarray:
    """Width of each slide edge, shape (G, E, 2, n - 1) [grasp, effort, direction, i -> i + 1 (direction 1) or
    i + 1 -> i (direction 0)]: the narrower end's band, ``-inf`` where the edge is not allowed."""
    w = np.where(graph.width >= graph.resolution, graph.width, -np.inf)
    same = np.all(graph.touched[:, 1:] == graph.touched[:, :-1], axis=-1) & graph.valid[:, 1:] & graph.valid[:, :-1]
    edge = np.minimum(w[..., 1:], w[..., :-1])
    return np.where(same[:, None, None, :], edge, -np.inf)


def least_effort(lower, upper) -> np.ndarray:
    """The least magnitude of an effort inside each band ``[lower, upper]`` (N m or N): 0 where the band holds 0,
    else its edge nearer 0; NaN without a band."""
    lower, upper = np.asarray(lower, dtype=float), np.asarray(upper, dtype=float)
    with np.errstate(invalid="ignore"):
        return np.where(lower > 0, lower, np.where(upper < 0, -upper, np.where(lower <= upper, 0.0, np.nan)))


def slide_efforts(graph: SearchGraph) -> np.ndarray:
    """Peak squeeze of each slide edge, shape (G, E, 2, n - 1) (as :func:`slide_widths`; the same for every effort
    joint): the larger of its two ends' **squeeze**, the largest over the tables' joints of the least magnitude
    inside that joint's guaranteed band there (:func:`least_effort`, N m or N).  A joint's band edge is what it must
    hold at the friction set's worst point for the mode to stay guaranteed; whichever joint the plan torque-controls,
    a stiff servo on another carries that load there (a wedge: forces that grow without bound toward a jam).  0
    without the bands' edges in ``graph``; a joint without a band at a state counts 0 there."""
    G, E, _, n = graph.width.shape
    if graph.lower is None or graph.upper is None:
        return np.zeros((G, E, 2, max(n - 1, 0)))
    least = least_effort(graph.lower, graph.upper)
    state = np.max(np.where(np.isnan(least), 0.0, least), axis=1, keepdims=True)  # (G, 1, 2, n)
    return np.broadcast_to(np.maximum(state[..., 1:], state[..., :-1]), (G, E, 2, n - 1))


def _neighbours(graph, edges, efforts, g, i, forbidden):
    """Edges out of node (g, i): ``(width, to_g, to_i, effort joint, kind, peak squeeze)``."""
    G, n = graph.shape
    out = []
    for e in range(edges.shape[1]):
        if i + 1 < n and edges[g, e, 1, i] > -np.inf:
            out.append((edges[g, e, 1, i], g, i + 1, e, "slide", efforts[g, e, 1, i]))
        if i > 0 and edges[g, e, 0, i - 1] > -np.inf:
            out.append((edges[g, e, 0, i - 1], g, i - 1, e, "slide", efforts[g, e, 0, i - 1]))
    for h in range(G):
        if h != g and graph.valid[h, i] and (g, h, i) not in forbidden:
            out.append((np.inf, h, i, -1, "regrasp", 0.0))
    return out


def widest_route(graph: SearchGraph, start, goals, forbidden=frozenset()) -> Route | None:
    """The widest route from ``start`` to any node of ``goals``, fewest regrasps, steps and segments among them, then
    the smallest peak squeeze (the module docstring).

    Parameters
    ----------
    graph : SearchGraph
    start : (int, int), or a list of them
        ``(grasp, i)``; several: the route may begin at any (one search from all: every start at an unbounded
        width and no cost, a multi-source Dijkstra in both stages).
    goals : iterable of (int, int)
    forbidden : set of (int, int, int)
        Regrasps ``(from grasp, to grasp, i)`` not to use.

    Returns
    -------
    Route or None
        None when no goal is reachable.
    """
    G, n = graph.shape
    goals = {tuple(map(int, g)) for g in goals}
    edges, efforts = slide_widths(graph), slide_efforts(graph)
    many = len(start) > 0 and not np.isscalar(start[0])
    starts = [(int(s[0]), int(s[1])) for s in (start if many else [start])]
    starts = [s for s in starts if graph.valid[s]]
    if not starts or not goals:
        return None
    memo = {}

    def neighbours(g, i):  # each node's edges once (both stages ask again and again)
        if (g, i) not in memo:
            memo[g, i] = _neighbours(graph, edges, efforts, g, i, forbidden)
        return memo[g, i]

    # stage 1: max-min Dijkstra (the largest bottleneck from the start to every node)
    best = np.full((G, n), -np.inf)
    heap = []
    for s in starts:
        best[s] = np.inf
        heap.append((-np.inf, s))
    expanded = 0
    while heap:
        negw, (g, i) = heapq.heappop(heap)
        w = -negw
        if w < best[g, i]:
            continue
        expanded += 1
        for ew, h, j, _, _, _ in neighbours(g, i):
            nw = min(w, ew)
            if nw > best[h, j]:
                best[h, j] = nw
                heapq.heappush(heap, (-nw, (h, j)))
    reached = [best[gl] for gl in goals if best[gl] > -np.inf]
    if not reached:
        return None
    width = max(reached)
    # stage 2: lexicographic Dijkstra (regrasps, steps, segments, peak squeeze) on edges at least `width` wide
    # node = (grasp, i, effort, direction) of the last slide (-1, -1 after a regrasp or at the start)
    cost, parent, heap = {}, {}, []
    for s in starts:
        s0 = (s[0], s[1], -1, -1)
        cost[s0], parent[s0] = (0, 0, 0, 0.0), None
        heap.append(((0, 0, 0, 0.0), s0))
    heapq.heapify(heap)
    done = None
    while heap:
        c, node = heapq.heappop(heap)
        if cost.get(node) != c:
            continue
        expanded += 1
        g, i, e0, d0 = node
        if (g, i) in goals:
            done = node
            break
        for ew, h, j, e, kind, peak in neighbours(g, i):
            if ew < width:
                continue
            if kind == "regrasp":
                nxt, nc = (h, j, -1, -1), (c[0] + 1, c[1], c[2] + 1, c[3])
            else:
                d = int(j > i)
                nxt = (h, j, e, d)
                nc = (c[0], c[1] + 1, c[2] + (0 if (e, d) == (e0, d0) else 1), max(c[3], float(peak)))
            if nc < cost.get(nxt, (np.inf,)):
                cost[nxt] = nc
                parent[nxt] = (node, ew, e, kind)
                heapq.heappush(heap, (nc, nxt))
    if done is None:  # cannot happen: stage 1 reached a goal at this width
        return None
    steps = []
    node = done
    while parent[node] is not None:
        prev, ew, e, kind = parent[node]
        steps.append(RouteStep(kind, prev[0], prev[1], node[0], node[1], e, float(ew)))
        node = prev
    steps.reverse()
    steps = _lightest_efforts(graph, edges, steps, width)
    return Route(tuple(steps), float(width), sum(not s.is_slide for s in steps), expanded)


def _lightest_efforts(graph, edges, steps, width) -> list:
    """``steps`` with each segment's effort joint (a run of slide steps in one grasp, effort joint and direction) the
    one whose command can stay smallest along it (the largest :func:`least_effort` of its steps' ends) among the
    joints whose every step is at least ``width`` wide there: the peak squeeze is the state's, the same for every
    joint, so the search leaves this choice open.  Regrasps, steps and segments stay as they are (two neighbouring
    segments may merge)."""
    if graph.lower is None or graph.upper is None:
        return steps
    least = np.nan_to_num(least_effort(graph.lower, graph.upper), nan=np.inf)
    out, k = list(steps), 0
    while k < len(out):
        s = out[k]
        if not s.is_slide:
            k += 1
            continue
        d = int(s.to_i > s.i)
        end = k
        while (end + 1 < len(out) and out[end + 1].is_slide and out[end + 1].grasp == s.grasp
               and out[end + 1].effort == s.effort and int(out[end + 1].to_i > out[end + 1].i) == d):  # fmt: skip
            end += 1
        run = out[k:end + 1]
        lo = [min(st.i, st.to_i) for st in run]  # each step's edge index (edges run i -> i + 1)
        ends = [i for st in run for i in (st.i, st.to_i)]
        ok = [e for e in range(edges.shape[1]) if all(edges[s.grasp, e, d, i] >= width for i in lo)]
        best = min(ok, key=lambda e: (float(np.max(least[s.grasp, e, d, ends])), e != s.effort), default=s.effort)
        if best != s.effort:
            out[k:end + 1] = [replace(st, effort=best, width=float(edges[s.grasp, best, d, i]))
                              for st, i in zip(run, lo)]  # fmt: skip
        k = end + 1
    return out
