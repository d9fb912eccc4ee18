"""Modest squeezes and unloaded releases (issue 31: ``two_link_right``, certified, failed 17 of 18 MuJoCo runs).

* The widest-route search's last key, the route's **peak squeeze** (:func:`qsplan.planner.search.widest.slide_efforts`),
  against an independent shortest-path method (Bellman-Ford on the lexicographic costs, no heap, its own neighbour
  code), and each segment's effort joint the lightest the route's width allows;
* :func:`qsplan.planner.plan.release.release_torque`'s closed forms;
* the task itself: the route regrasps before the wedge, the release is preceded by a certified hold of the joint that
  bears the load (read again from the certifier's own scenes), and MuJoCo keeps the workpiece where it was released
  at the two friction vectors where it was kicked 0.14 mm.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from qsplan.planner.plan.release import release_torque
from qsplan.planner.search.widest import SearchGraph, least_effort, slide_efforts, slide_widths, widest_route

#: The task (``benchmarks/mujoco_tasks/two_link_right.toml``: the MuJoCo sweep's file, read, not copied).
TASK = Path(__file__).resolve().parents[2] / "benchmarks" / "mujoco_tasks" / "two_link_right.toml"


def test_release_torque_is_the_least_magnitude_a_resolution_inside():
    assert release_torque(-np.inf, -0.0058, 0.02) == pytest.approx(-0.0258)
    assert release_torque(0.003, np.inf, 0.02) == pytest.approx(0.023)
    assert release_torque(-1.0, 2.0, 0.02) == 0.0
    assert release_torque(-0.01, 2.0, 0.02) == pytest.approx(0.01)  # 0 is not a resolution inside: the edge's
    assert release_torque(0.1, 0.12, 0.02) == pytest.approx(0.11)  # narrower than two resolutions: the midpoint
    assert np.isnan(release_torque(np.nan, np.nan, 0.02))


def _random_graph(seed, G=2, E=2, n=7):
    """Small tables: widths mostly unbounded (ties the other keys must break), bands one-sided of random edges."""
    rng = np.random.default_rng(seed)
    valid = rng.random((G, n)) > 0.1
    valid[0, 0] = True
    touched = np.zeros((G, n, 2), int)
    side = rng.random((G, E, 2, n)) < 0.5
    edge = rng.choice([0.05, 0.2, 0.8, 3.0], size=(G, E, 2, n))
    lower = np.where(side, edge, -np.inf)
    upper = np.where(side, np.inf, -edge)
    narrow = rng.random((G, E, 2, n)) < 0.2  # some two-sided bands, one resolution or more wide
    lower = np.where(narrow, edge, lower)
    upper = np.where(narrow, edge + rng.choice([0.5, 1.0], size=(G, E, 2, n)), upper)
    none = (rng.random((G, E, 2, n)) < 0.1) | ~valid[:, None, None, :]
    lower, upper = np.where(none, np.nan, lower), np.where(none, np.nan, upper)
    width = np.where(np.isnan(lower), -np.inf, upper - lower)
    return SearchGraph(valid, touched, width, 0.1, lower, upper)


def _bellman_ford(graph, start, goals, width):
    """The lexicographic optimum (regrasps, steps, segments, peak squeeze) over routes on edges at least ``width``
    wide, by relaxing every edge until nothing changes (no heap, no label setting)."""
    G, n = graph.shape
    sw, sq = slide_widths(graph), slide_efforts(graph)
    E = sw.shape[1]
    inf = (np.inf,) * 4
    cost = {(start[0], start[1], -1, -1): (0, 0, 0, 0.0)}
    changed = True
    while changed:
        changed = False
        for (g, i, e0, d0), c in list(cost.items()):
            moves = []
            for e in range(E):
                for d, j in ((1, i + 1), (0, i - 1)):
                    if 0 <= j < n and sw[g, e, d, min(i, j)] >= width and sw[g, e, d, min(i, j)] > -np.inf:
                        seg = 0 if (e, d) == (e0, d0) else 1
                        peak = max(c[3], float(sq[g, e, d, min(i, j)]))
                        moves.append(((g, j, e, d), (c[0], c[1] + 1, c[2] + seg, peak)))
            for h in range(G):
                if h != g and graph.valid[h, i]:
                    moves.append(((h, i, -1, -1), (c[0] + 1, c[1], c[2] + 1, c[3])))
            for node, nc in moves:
                if nc < cost.get(node, inf):
                    cost[node], changed = nc, True
    return min((c for (g, i, _, _), c in cost.items() if (g, i) in goals), default=None)


@pytest.mark.parametrize("seed", range(30))
def test_the_peak_squeeze_is_optimal_against_bellman_ford(seed):
    graph = _random_graph(seed)
    G, n = graph.shape
    goals = {(g, n - 1) for g in range(G)}
    route = widest_route(graph, (0, 0), goals)
    if route is None:
        assert _bellman_ford(graph, (0, 0), goals, -np.inf) is None
        return
    best = _bellman_ford(graph, (0, 0), goals, route.width)
    sq = slide_efforts(graph)
    steps = [s for s in route.steps if s.kind == "slide"]
    peak = max((float(sq[s.grasp, s.effort, int(s.to_i > s.i), min(s.i, s.to_i)]) for s in steps), default=0.0)
    segments, last = 0, None
    for s in route.steps:
        key = None if s.kind == "regrasp" else (s.effort, int(s.to_i > s.i))
        segments += key is None or key != last
        last = key
    assert (route.regrasps, len(steps), peak) == (best[0], best[1], best[3])
    assert segments <= best[2]  # the lightest-effort pass may merge two segments, never split one
    for s in steps:  # every step at least the route's width, with the effort joint it states
        assert slide_widths(graph)[s.grasp, s.effort, int(s.to_i > s.i), min(s.i, s.to_i)] >= route.width


def test_the_segment_takes_the_lightest_joint_of_equal_routes():
    """Two joints with unbounded bands along the whole slide (width inf both): the one whose command can stay near
    0 (a lower edge of 0.003 against an upper edge of -40) is the route's."""
    G, E, n = 1, 2, 6
    valid = np.ones((G, n), bool)
    touched = np.zeros((G, n, 2), int)
    lower = np.full((G, E, 2, n), -np.inf)
    upper = np.full((G, E, 2, n), -40.0)
    lower[:, 1], upper[:, 1] = 0.003, np.inf
    width = upper - lower
    graph = SearchGraph(valid, touched, width, 0.02, lower, upper)
    route = widest_route(graph, (0, 0), [(0, n - 1)])
    assert route.width == np.inf and {s.effort for s in route.steps} == {1}
    assert least_effort(lower[0, 1, 1, 0], upper[0, 1, 1, 0]) == pytest.approx(0.003)
    # without the bands' edges every route squeezes 0: the first joint, as before
    bare = widest_route(SearchGraph(valid, touched, width, 0.02), (0, 0), [(0, n - 1)])
    assert {s.effort for s in bare.steps} == {0}


@pytest.fixture(scope="module")
def two_link_right(tmp_path_factory):
    """``(task, run)``: ``two_link_right`` planned, certified and exported (no plots, no re-simulation)."""
    from qsplan.planner.pipeline.run import run_plan
    from qsplan.planner.task.task import load_task

    task = load_task(TASK)
    run = run_plan(task, tmp_path_factory.mktemp("two_link_right") / "out", verify=0, plots="none")
    return task, run


@pytest.mark.slow
@pytest.mark.ompl
def test_the_release_is_unloaded_by_the_joint_that_bears_the_load(two_link_right):
    """The plan: a slide, a release hold, the regrasp, a slide, certified.  The slide's commands stay near 0 (they
    were -0.44 to -40.8 N m) and the hold's joint is the one whose torque is largest at the slide's end over the
    friction set's vertices, read again from the certifier's own row scene (the polygon search) and the solver; it is
    held at the proved interval's least-magnitude torque, a resolution inside."""
    from qsplan.hands.contacts.found import hold_scene
    from qsplan.mechanics import solve
    from qsplan.mechanics.bands.hold import hold_torque_interval
    from qsplan.planner.certify.modes import row_scene
    from qsplan.planner.certify.rows import friction_points, row_pose, row_q
    from qsplan.planner.export.plan_files import read_plan_csv

    task, run = two_link_right
    assert run.certificate.ok, run.certificate.summary()
    kinds = [p.kind if p.in_contact else "regrasp" for p in run.plan.phases]
    assert kinds == ["slide", "hold", "regrasp", "slide"]
    slide, hold = run.plan.phases[0], run.plan.phases[1]
    assert np.max(np.abs(slide.command)) < 0.1 and np.max(np.abs(run.plan.phases[3].command)) < 0.1
    cols = read_plan_csv(run.out_dir / "plan.csv")
    names = list(task.hand.joint_names)
    k = int(np.flatnonzero(cols["phase"] == 0)[-1])
    scene = row_scene(task, cols, k)
    peak = np.zeros(len(names))
    for mu in friction_points(task, 0, np.random.default_rng(0), scene.n_contacts):
        for sol in solve(scene.with_mu(mu), workers=1).solutions:
            peak = np.maximum(peak, np.abs(sol.tau))
    assert hold.effort_joint == names[int(np.argmax(peak))] != slide.effort_joint
    effort = np.array(names) == hold.effort_joint
    held = hold_scene(task.hand, row_pose(cols, k), row_q(cols, k, names), effort)
    lo, hi = hold_torque_interval(held, task.disturbance, margin=task.force_margin.normal)
    assert np.all(hold.command == pytest.approx(release_torque(lo, hi, task.torque_resolution), abs=1e-12))
    assert np.all(np.abs(hold.command) <= min(abs(lo), abs(hi)) + task.torque_resolution + 1e-12)
    steps = [s.kind for s in run.plan.sequence if s.kind != "search"]
    assert steps == ["slide", "hold", "regrasp", "slide"]


@pytest.mark.slow
@pytest.mark.ompl
def test_mujoco_keeps_the_released_workpiece(two_link_right):
    """At the two vertices where the release kicked the workpiece 0.14 mm (palm and left finger at 0.3, the slide
    nearing a wedge), MuJoCo keeps every planned mode and the workpiece within the judge's limits."""
    pytest.importorskip("mujoco")
    from qsplan.planner.replay.mujoco_replay import replay_mujoco

    task, run = two_link_right
    mu = np.array([[0.3, 0.3, 0.3, 0.05], [0.3, 0.3, 0.3, 0.3]])
    rep = replay_mujoco(run.out_dir, task=task, mu=mu)
    assert rep.ok and rep.modes_kept  # ok: within POSE_TOLERANCE in contact, and RELEASE_DRIFT more once released
