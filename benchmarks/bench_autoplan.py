"""Automatic planning (issue 14): the bundled goal tasks with each sequence planner, and the whole pipeline.

For every task of ``planner/data`` with a ``[goal]``, the band tables are built once (their time is
shown) and the route searched by each planner of
:data:`qsplan.planner.search.ompl_search.SEQUENCE_PLANNERS` inside OMPL: ours (``widest``, the exact
widest-route search on the tables, an ``ob.Planner`` subclass) and OMPL's asymptotically optimal
sampling planners with the minimax objective (``RRTstar``, ``BITstar``; iteration budget, seed 1).
The table: time, states evaluated (table look-ups or nodes expanded), the route's narrowest band (N m),
its regrasps; and the same on seeded synthetic tables of six grasps (what a hand with a choice of contacts
gives).  Then each task planned end to end by :func:`qsplan.planner.plan_task` (tables, search, dense
sweeps, OMPL regrasps; wall time), the described hands' (issue 15: the two-link hand, the parallel-jaw
gripper) on their contact manifolds: time, states evaluated (the planner's validity checks and dense
samples), phases and the narrowest guaranteed band.  The goals that turn the workpiece (issue 23: the slide to the
flush instant, a certified hold, the pivot) in a table of their own: time, states, phases, the narrowest band, the
holds and their proof margin, the motion's duration.  ``qsplan demo``'s whole-command time is in ``bench_plan.py``.

Run: ``python3 benchmarks/bench_autoplan.py [--iterations N]``.
"""

import argparse
import time

from qsplan.planner import load_task, plan_task, task_paths
from qsplan.planner.search.ompl_search import SEQUENCE_PLANNERS, search_route
from qsplan.planner.search.tables import band_tables, table_grid


def search_rows(task, iterations):
    """One row per planner: (planner, seconds, evaluations, width, regrasps) on the task's tables."""
    from qsplan.planner.plan.autoplan import goal_nodes, grasp_rows, start_nodes

    t0 = time.perf_counter()
    from qsplan.planner.task.goal import palm_x_range

    tables = band_tables(task, grasp_rows(task, task.start_x, task.goal.x),
                         table_grid(task.start_x, task.goal.x, palm_x_range(task.hand)))
    t_tables = time.perf_counter() - t0
    starts, goals = start_nodes(tables, task), goal_nodes(tables, task)
    rows = []
    for name in SEQUENCE_PLANNERS:
        best = None
        secs = evals = 0
        for s in starts:
            res = search_route(tables.graph, s, goals, name, iterations=iterations)
            secs += res.seconds
            evals += res.evaluations
            if res.route is not None and (best is None or res.route.width > best.width):
                best = res.route
        rows.append((name, secs, evals, None if best is None else best.width, None if best is None else best.regrasps))
    return tables, t_tables, rows


def synthetic_rows(iterations, G=6, n=400, seed=1):
    """The planners on seeded random tables with many grasps (what hands with a choice of contact give): the
    route's width differs between planners only where regrasps and detours matter."""
    import numpy as np

    from qsplan.planner.search.widest import SearchGraph

    rng = np.random.default_rng(seed)
    valid = rng.random((G, n)) > 0.05
    width = np.where(valid[:, None, None, :], rng.uniform(0.0, 1.0, (G, 2, 2, n)), -np.inf)
    graph = SearchGraph(valid, np.zeros((G, n, 2), int), width, 0.1)
    start, goals = (0, 10), [(g, n - 10) for g in range(G)]
    rows = []
    for name in SEQUENCE_PLANNERS:
        res = search_route(graph, start, goals, name, iterations=iterations)
        r = res.route
        rows.append((name, res.seconds, res.evaluations, None if r is None else r.width, None if r is None else r.regrasps))
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--iterations", type=int, default=2000, help="iteration budget of the sampling planners")
    args = ap.parse_args(argv)
    tasks = {stem: load_task(p) for stem, p in task_paths().items()}
    tasks = {k: t for k, t in tasks.items() if t.goal is not None}
    # the band tables: the paper's hand, goals on the palm edge (a turning goal: its own table below)
    paper = {k: t for k, t in tasks.items() if hasattr(t.hand, "finger_length") and t.goal.x is not None}
    print(f"{'task':<22} {'planner':<9} {'search s':>9} {'evaluated':>10} {'narrowest N m':>14} {'regrasps':>9}")
    planned = {}
    for stem, task in paper.items():
        tables, t_tables, rows = search_rows(task, args.iterations)
        print(f"{stem:<22} {'tables':<9} {t_tables:9.3f} {tables.states + tables.band_states:10d} {'':>14} {'':>9}")
        for name, secs, evals, width, regrasps in rows:
            w = "no route" if width is None else f"{width:.4g}"
            print(f"{'':<22} {name:<9} {secs:9.3f} {evals:10d} {w:>14} {'-' if regrasps is None else regrasps:>9}")
        planned[stem] = tables
    label = "synthetic 6 x 400"
    for name, secs, evals, width, regrasps in synthetic_rows(args.iterations):
        w = "no route" if width is None else f"{width:.4g}"
        print(f"{label:<22} {name:<9} {secs:9.3f} {evals:10d} {w:>14} {'-' if regrasps is None else regrasps:>9}")
        label = ""
    turning_rows({k: t for k, t in tasks.items() if t.goal.x is None})
    print()
    print(f"{'task':<30} {'hand':<22} {'plan s':>7} {'states':>7} {'segments':>9} {'regrasps':>9} {'narrowest':>12}")
    for stem, task in tasks.items():
        hand = getattr(getattr(task.hand, "description", None), "name", "paper's hand")
        t0 = time.perf_counter()
        try:
            plan = plan_task(task)
            w = plan.narrowest()[2]
            unit = "N" if all(k == "prismatic" for k in getattr(getattr(task.hand, "description", None),
                                                                  "joint_kinds", ("revolute",))) else "N m"
            print(f"{stem:<30} {hand:<22} {time.perf_counter() - t0:7.2f} {plan.validity_checks:7d} "
                  f"{len(plan.segments):9d} {len(plan.phases) - len(plan.segments):9d} {w:8.4g} {unit}")  # fmt: skip
        except Exception as exc:  # an infeasible task: its report
            print(f"{stem:<30} {hand:<22} {time.perf_counter() - t0:7.2f} no plan: {str(exc)[:80]}")


def hold_margin(task, ph) -> float:
    """The smallest margin (N) of the hold proofs at a hold phase's ramp ends (qsplan.mechanics.bands.hold)."""
    import numpy as np

    from qsplan.hands.found_contacts import row_contact_scene
    from qsplan.mechanics.bands.hold import prove_hold

    pose = ph.poses(task.hand.rest_height)[0]
    effort = np.array(task.hand.joint_names) == ph.effort_joint
    scene = row_contact_scene(task.hand, pose, ph.q[0], effort, np.zeros(effort.size))
    return min(prove_hold(scene, torques=[t], disturbance=task.disturbance).margin for t in ph.command[[0, -1]])


def turning_rows(tasks):
    """The goals that turn the workpiece (issue 23: slide, hold, pivot): time, states, the route's phases, the
    narrowest band, the holds and their smallest proof margin, the motion's duration."""
    print()
    print(f"{'turning task':<22} {'plan s':>7} {'states':>7} {'phases':<20} {'narrowest N m':>14} {'holds':>6} "
          f"{'hold margin N':>14} {'motion s':>9}")  # fmt: skip
    for stem, task in tasks.items():
        t0 = time.perf_counter()
        try:
            plan = plan_task(task)
        except Exception as exc:  # a refused goal: its reason
            print(f"{stem:<22} {time.perf_counter() - t0:7.2f} refused: {str(exc)[:90]}")
            continue
        secs = time.perf_counter() - t0
        holds = [p for p in plan.segments if p.kind == "hold"]
        margin = min((hold_margin(task, h) for h in holds), default=float("nan"))
        kinds = " ".join(p.kind if p.in_contact else "regrasp" for p in plan.phases)
        print(f"{stem:<22} {secs:7.2f} {plan.validity_checks:7d} {kinds:<20} {plan.narrowest()[2]:14.4g} "
              f"{len(holds):6d} {margin:14.4g} {plan.duration:9.2f}")  # fmt: skip


if __name__ == "__main__":
    main()
