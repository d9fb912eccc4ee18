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
holds and their proof margin, the motion's duration.  Last, how far each bundled turning task's hand and workpiece
turn (:data:`REACH`): every formation at each friction set, where its geometry ends and where its bands hold to
(``docs/reorientation.md``'s table).  ``qsplan demo``'s whole-command time is in ``bench_plan.py``.

Run: ``python3 benchmarks/bench_autoplan.py [--iterations N] [--turning]`` (``--turning``: only the turning tables).
"""

import argparse
import time

from qsplan.planner import HoldPhase, load_task, plan_task, task_paths
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
    ap.add_argument("--turning", action="store_true", help="only the turning tasks and the fidelity table")
    args = ap.parse_args(argv)
    tasks = {stem: load_task(p) for stem, p in task_paths().items()}
    tasks = {k: t for k, t in tasks.items() if t.goal is not None}
    if args.turning:
        return turning_rows(tasks)
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

    from qsplan.hands.contacts.found import row_contact_scene
    from qsplan.mechanics.bands.hold import prove_hold

    pose = ph.poses(task.hand.rest_height)[0]
    effort = np.array(task.hand.joint_names) == ph.effort_joint
    scene = row_contact_scene(task.hand, pose, ph.q[0], effort, np.zeros(effort.size))
    return min(prove_hold(scene, torques=[t], disturbance=task.disturbance).margin for t in ph.command[[0, -1]])


def turning_tasks(tasks) -> dict:
    """The bundled turning tasks and the variants issue 32 asks of the formation search: the demo turned past its
    slip reversal (theta = -0.84 rad: two pivots through a hold), the demo mirrored (theta = +0.5 rad: counter-
    clockwise), the two-link hand and the parallel jaw asked to turn."""
    from dataclasses import replace

    from qsplan.planner.task.goal import Goal

    out = {k: t for k, t in tasks.items() if t.goal.x is None}
    demo = tasks["reorient_task"]
    out["reorient -0.84 rad"] = replace(demo, goal=Goal(None, None, None, theta=-0.84))
    out["mirrored +0.5 rad"] = _mirrored()
    for stem in ("two_link_task", "parallel_jaw_task"):
        t = load_task(task_paths()[stem])
        out[f"{stem.split('_task')[0]} -0.3 rad"] = replace(t, goal=Goal(None, None, None, theta=-0.3))
    return out


def _mirrored():
    """``reorient_task`` with its workpiece reflected x -> -x (vertices kept counter-clockwise), its turn reversed."""
    import tempfile
    from pathlib import Path

    text = task_paths()["reorient_task"].read_text()
    text = text.replace("workpiece = [[0.0, 0.0], [0.080, 0.0], [0.085, 0.080], [0.008, 0.100]]",
                        "workpiece = [[-0.080, 0.0], [0.0, 0.0], [-0.008, 0.100], [-0.085, 0.080]]")
    text = text.replace("\ntheta = -0.5", "\ntheta = 0.5")
    path = Path(tempfile.mkdtemp()) / "mirrored.toml"
    path.write_text(text)
    return load_task(path)


def turning_rows(tasks):
    """The goals that turn the workpiece (issue 32: the formation search): time, states, formations searched, the
    route's phases, the narrowest band, the holds and their smallest proof margin, the motion's duration."""
    from qsplan.planner.plan.results import PlanFailure
    from qsplan.planner.plan.turning import survey

    print()
    print(f"{'turning task':<22} {'plan s':>7} {'states':>7} {'forms':>5} {'phases':<34} {'narrowest N m':>14} "
          f"{'holds':>6} {'hold margin N':>14} {'motion s':>9}")  # fmt: skip
    for stem, task in turning_tasks(tasks).items():
        forms = len(survey(task))
        t0 = time.perf_counter()
        try:
            plan = plan_task(task)
        except PlanFailure as exc:  # a refused goal: its reason
            print(f"{stem:<22} {time.perf_counter() - t0:7.2f} {'':>7} {forms:5d} refused: {str(exc)[:110]}")
            continue
        secs = time.perf_counter() - t0
        holds = [p for p in plan.segments if isinstance(p, HoldPhase)]
        margin = min((hold_margin(task, h) for h in holds), default=float("nan"))
        kinds = " ".join(p.kind for p in plan.phases)
        print(f"{stem:<22} {secs:7.2f} {plan.validity_checks:7d} {forms:5d} {kinds:<34} {plan.narrowest()[2]:14.4g} "
              f"{len(holds):6d} {margin:14.4g} {plan.duration:9.2f}")  # fmt: skip
    fidelity(tasks["reorient_task"])


#: How far each bundled turning hand and workpiece turns (issue 34's table): the task, and the friction sets its
#: formations are judged at.
REACH = {"reorient_task": ((0.0, 0.0), (0.0, 0.2)), "reorient_edge_task": ((0.0, 0.0), (0.0, 0.2)),
         "full_turn_task": ((0.0, 0.0), (0.0, 0.03), (0.0, 0.05), (0.0, 0.1), (0.0, 0.2), (0.1, 0.2)),
         "finger_replaced_task": ((0.05, 0.1),)}  # fmt: skip


def fidelity(demo):
    """Issue 32 item 4 and issue 34: from each :data:`REACH` task's start (``reorient_task``: the demo's), at each of its
    friction sets, the furthest turn the search reaches: every formation, where its geometry ends, and where its bands
    first fall below the resolution before that."""
    from dataclasses import replace

    import numpy as np

    from qsplan.planner.plan.pivot import pivot_geometry
    from qsplan.planner.plan.results import PlanFailure
    from qsplan.planner.plan.turning import pivot_pieces
    from qsplan.hands.formations.pivots import pivot_formations
    from qsplan.planner.task.goal import Goal

    print()
    print(f"{'task':<15} {'friction':<11} {'formation':<32} {'geometry ends (deg)':>20} {'bands hold to (deg)':>20}  "
          "what blocks")  # fmt: skip
    for stem, frictions in REACH.items():
        base = demo if stem == "reorient_task" else load_task(task_paths()[stem])
        hand = base.hand
        formations = pivot_formations(hand, base.start_free)  # held as the task starts them (the search's rule)
        for mu in frictions:
            for pivot, start in formations:
                far = pivot.direction * 1.6  # beyond any event: where the geometry ends
                task = replace(base, mu_range=mu, goal=Goal(None, None, None, theta=far))
                geo = pivot_geometry(task, pivot, start, far)
                end = geo.end.theta if geo.end is not None else far
                last = float(geo.path.theta[max((geo.end.row if geo.end else geo.path.theta.size) - 1, 1)])
                try:
                    pieces = pivot_pieces(task, pivot, start, last, pivot_geometry(task, pivot, start, last), None)
                    reach, why = last, geo.end.words if geo.end else "-"
                    n = len(pieces)
                except PlanFailure as exc:
                    reach, why, n = float(exc.report.pose[2]), exc.report.reason, 0
                print(f"{stem.removesuffix('_task'):<15} {str(list(mu)):<11} {pivot.name:<32} {np.degrees(end):20.2f} "
                      f"{np.degrees(reach):20.2f}  {why[:90]}{'' if not n else f' ({n} pieces)'}")  # fmt: skip


if __name__ == "__main__":
    main()
