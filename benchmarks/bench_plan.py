"""Planning time and in-contact state checks per second of the two-finger planner (seed 1, deterministic),
and the demo's whole-command wall time, with the figures before issue 13 beside them.

Run: ``python3 benchmarks/bench_plan.py [--repeat N]`` (the bundled tasks, then ``qsplan demo`` N times,
default 3, best taken: the machine is shared, so the best run is the least disturbed one).

``checks`` counts the states judged (the automatic planner's band-table checks, the in-contact dense
sweeps' samples, each once, and OMPL's validity checks on the regrasps); ``checks/s`` divides them by the
time spent judging them.  The in-contact state checks per second of the issue's target are measured on
their own: the demo hand's band tables over x in [-0.06, 0.06] m (best of ``--repeat``).
"""

import argparse
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from qsplan.planner import PlanFailure, load_task, plan_task, task_paths

#: Figures before issue 13 (2-core machine, under load): OMPL's validity checker on in-contact segments
#: at ~140-160 checks/s; ``qsplan demo`` 45-55 s wall.
PREVIOUS = {"checks_per_second": "140-160", "demo_wall_s": "45-55"}

#: Planning time (s, best of 3, ``plan_task``: search and realisation, no certificate or plots) of each bundled task
#: before issue 22's one pipeline (commit 0ca5728: three planners), measured on this 2-core machine on 2026-11-27
#: while other jobs ran; issue 22's target is 1 s for every bundled task.
BEFORE_22 = {"demo_task": 0.27, "friction_closes_task": 0.61, "parallel_jaw_task": 2.16, "pentagon_goal_task": 0.27,
             "pentagon_roof_task": 0.19, "pentagon_task": 0.64, "quadrilateral_goal_right_task": 2.60,
             "scripted_regrasp_task": 1.21, "trapezoid_tips_task": 0.12, "two_link_regrasp_task": 5.89,
             "two_link_task": 5.32}  # fmt: skip


def demo_wall(repeat):
    """Best wall time (s) of ``qsplan demo`` (plots and re-simulation included) over ``repeat`` runs."""
    best = float("inf")
    for _ in range(repeat):
        with tempfile.TemporaryDirectory() as tmp:
            cmd = [sys.executable, "-m", "qsplan.planner.cli", "demo", "--out", str(Path(tmp) / "out"), "--quiet"]
            t0 = time.perf_counter()
            subprocess.run(cmd, check=True, capture_output=True)
            best = min(best, time.perf_counter() - t0)
    return best


def table_rate(repeat):
    """In-contact state checks per second (best of ``repeat``): the demo's band tables, every check a scene and a
    guaranteed band with every competitor precluded (one torque-controlled finger, one direction), batched."""
    from qsplan.hands.paper_hand.grasp_geometry import candidate_grasps
    from qsplan.planner.search.tables import band_tables, table_grid

    task = load_task(task_paths()["demo_task"])
    grasps, grid = candidate_grasps(task.hand), table_grid(-0.06, 0.06, 0.16, margin=0.0)
    best, n = 0.0, 0
    for _ in range(repeat):
        t0 = time.perf_counter()
        tables = band_tables(task, grasps, grid)
        best, n = max(best, tables.band_states / (time.perf_counter() - t0)), tables.band_states
    return best, n


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3, help="runs of each plan and of qsplan demo (best taken)")
    args = ap.parse_args(argv)
    print(f"{'task':<30} {'plan s':>7} {'before':>7} {'target':>7} {'checks':>8} {'checks/s':>9} {'narrowest N m':>14}")
    for stem, path in task_paths().items():
        task = load_task(path)
        best, plan = float("inf"), None
        for _ in range(args.repeat):
            t0 = time.perf_counter()
            try:
                plan = plan_task(task)
            except PlanFailure:
                plan = None
            best = min(best, time.perf_counter() - t0)
        before = f"{BEFORE_22[stem]:.2f}" if stem in BEFORE_22 else "-"
        if plan is None:
            print(f"{stem:<30} {best:7.2f} {before:>7} {'1':>7}  no plan (on purpose: see the task file)")
            continue
        print(f"{stem:<30} {best:7.2f} {before:>7} {'1':>7} {plan.validity_checks:8d} "
              f"{plan.checks_per_second:9.1f} {plan.narrowest()[2]:14.4g}")  # fmt: skip
    print()
    rate, n = table_rate(args.repeat)
    print(f"{'measure':<44} {'now':>8} {'before':>8} {'target':>8}")
    print(f"{f'in-contact state checks/s, demo hand ({n} states)':<44} {rate:8.0f} {PREVIOUS['checks_per_second']:>8} {'10000':>8}")
    print(f"{f'qsplan demo wall, best of {args.repeat} (s)':<44} {demo_wall(args.repeat):8.2f} {PREVIOUS['demo_wall_s']:>8} {'5':>8}")


if __name__ == "__main__":
    main()
