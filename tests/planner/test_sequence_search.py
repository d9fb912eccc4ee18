"""The widest-route search on band tables against independent brute force, and its OMPL wrappers."""

from collections import deque

import numpy as np
import pytest

from qsplan.planner.search.widest import SearchGraph, slide_widths, widest_route


def random_graph(seed, G=3, n=14, resolution=0.2):
    rng = np.random.default_rng(seed)
    valid = rng.random((G, n)) > 0.1
    valid[0, 1] = True  # the tests' start
    touched = np.zeros((G, n, 2), int)
    touched[:, n // 2 + rng.integers(0, 3):, 0] = 1  # one contact change per grasp somewhere past the middle
    width = rng.uniform(0.0, 1.0, (G, 2, 2, n))
    width[rng.random((G, 2, 2, n)) < 0.15] = -np.inf
    return SearchGraph(valid, touched, np.where(valid[:, None, None, :], width, -np.inf), resolution)


def edges_at_least(graph, w):
    """Every allowed edge of width >= w, from the tables directly (independent of the search's neighbour code)."""
    G, n = graph.shape
    out = {}
    sw = slide_widths(graph)
    for g in range(G):
        for i in range(n - 1):
            if sw[g, :, 1, i].max() >= w:
                out.setdefault((g, i), []).append(((g, i + 1), 0))
            if sw[g, :, 0, i].max() >= w:
                out.setdefault((g, i + 1), []).append(((g, i), 0))
        for i in range(n):
            for h in range(G):
                if h != g and graph.valid[g, i] and graph.valid[h, i]:
                    out.setdefault((g, i), []).append(((h, i), 1))
    return out


def min_regrasps(graph, w, start, goals):
    """0-1 BFS on regrasps over edges at least ``w`` wide: the fewest regrasps, or None if unreachable."""
    adj = edges_at_least(graph, w)
    dist = {start: 0}
    dq = deque([start])
    while dq:
        u = dq.popleft()
        for v, c in adj.get(u, []):
            if dist[u] + c < dist.get(v, 1 << 30):
                dist[v] = dist[u] + c
                (dq.appendleft if c == 0 else dq.append)(v)
    best = [dist[g] for g in goals if g in dist]
    return min(best) if best else None


@pytest.mark.parametrize("seed", range(40))
def test_widest_route_is_optimal_against_brute_force(seed):
    graph = random_graph(seed)
    G, n = graph.shape
    start = (0, 1)
    goals = [(g, n - 2) for g in range(G)]
    route = widest_route(graph, start, goals)
    # brute force: the largest threshold among the table's widths at which a goal is reachable
    candidates = sorted({float(v) for v in slide_widths(graph).ravel() if v >= graph.resolution} | {np.inf}, reverse=True)
    best = next((w for w in candidates if min_regrasps(graph, w, start, goals) is not None), None)
    if best is None:
        assert route is None
        return
    assert route is not None and route.width == best
    assert route.regrasps == min_regrasps(graph, best, start, goals)
    # the route is a connected chain of allowed steps from the start to a goal, each at least its width
    node = start
    for s in route.steps:
        assert (s.grasp, s.i) == node
        assert s.width >= route.width
        if s.kind == "slide":
            assert s.to_grasp == s.grasp and abs(s.to_i - s.i) == 1
            d = int(s.to_i > s.i)
            assert slide_widths(graph)[s.grasp, s.effort, d, min(s.i, s.to_i)] == s.width
        else:
            assert s.to_i == s.i and graph.valid[s.to_grasp, s.i]
        node = (s.to_grasp, s.to_i)
    assert node in goals


def test_forbidden_regrasps_are_avoided():
    G, n = 2, 6
    valid = np.ones((G, n), bool)
    touched = np.zeros((G, n, 2), int)
    width = np.ones((G, 2, 2, n))
    width[0, :, :, 3] = -np.inf  # grasp 0 blocked at 3: regrasp to grasp 1 needed
    graph = SearchGraph(valid, touched, width, 0.5)
    r = widest_route(graph, (0, 0), [(0, 5)])
    assert r.regrasps >= 1
    used = {(s.grasp, s.to_grasp, s.i) for s in r.steps if s.kind == "regrasp"}
    r2 = widest_route(graph, (0, 0), [(0, 5)], forbidden=used)
    assert r2 is None or not ({(s.grasp, s.to_grasp, s.i) for s in r2.steps if s.kind == "regrasp"} & used)
    blocked = {(g, h, i) for g in range(G) for h in range(G) for i in range(n)}
    assert widest_route(graph, (0, 0), [(0, 5)], forbidden=blocked) is None


def test_ompl_planners_on_the_tables():
    pytest.importorskip("ompl")
    from qsplan.planner.search.ompl_search import search_route

    graph = random_graph(3)
    G, n = graph.shape
    start, goals = (0, 1), [(g, n - 2) for g in range(G)]
    exact = widest_route(graph, start, goals)
    ours = search_route(graph, start, goals, "widest")
    assert ours.route == exact  # the OMPL planner wraps the exact search: the same route
    assert search_route(graph, start, goals, "widest").route == ours.route  # deterministic
    for name in ("BITstar", "RRTstar"):
        res = search_route(graph, start, goals, name, iterations=300)
        if res.route is not None:  # a sampling planner's route is allowed and never wider than the optimum
            assert res.route.width <= exact.width
            node = start
            for s in res.route.steps:
                assert (s.grasp, s.i) == node
                node = (s.to_grasp, s.to_i)
            assert node in goals
