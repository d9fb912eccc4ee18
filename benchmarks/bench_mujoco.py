"""Every bundled plan executed in MuJoCo at every vertex of its friction set (issue 24's acceptance, the whole set).

Run: ``python3 benchmarks/bench_mujoco.py [--random N] [TASK ...]`` (needs ``pip install '.[sim]'``).  Each bundled
task that plans (``qsplan.planner.task.task.task_paths``; ``friction_closes_task`` has no plan, on purpose) is
planned and exported, then :func:`qsplan.planner.replay.mujoco_replay.replay_mujoco` runs the exported commands at
1 kHz, no stop added, at the friction set's vertices and ``--random`` random points.  The table: runs, runs that kept
the planned modes, the largest workpiece error (mm) overall and at zero palm friction, contacts lost, wall time.
The acceptance asks every mode kept and the workpiece within 0.1 mm of the plan through every regrasp, including at
zero friction.  The tests run a subset (``tests/planner/test_mujoco_replay.py``).
"""

import argparse
import sys
import tempfile
import time
from pathlib import Path

#: The acceptance's bound on the workpiece's error (m).
POSE_BOUND = 1e-4


def main(argv=None) -> int:
    from qsplan.planner import PlanFailure, load_task, plan_task, task_paths
    from qsplan.planner.export.plan_files import export_plan
    from qsplan.planner.replay.mujoco_replay import replay_mujoco

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("tasks", nargs="*", help="bundled task names (default: all)")
    ap.add_argument("--random", type=int, default=2, help="random friction points per task besides the vertices")
    args = ap.parse_args(argv)
    names = args.tasks or sorted(task_paths())
    print(f"{'task':<30} {'runs':>4} {'kept':>4} {'max err mm':>10} {'at mu_palm=0':>12} {'lost':>5} {'wall s':>7} {'<= 0.1 mm':>9}")
    for name in names:
        task = load_task(task_paths()[name])
        try:
            plan = plan_task(task)
        except PlanFailure:
            print(f"{name:<30} no plan (on purpose: see the task file)")
            continue
        with tempfile.TemporaryDirectory() as tmp:
            export_plan(plan, Path(tmp))
            t0 = time.perf_counter()
            result = replay_mujoco(tmp, task=task, n_random=args.random, seed=0)
            wall = time.perf_counter() - t0
        runs = result.runs
        kept = sum(r.modes_kept for r in runs)
        err = max(r.max_error() for r in runs)
        zero = [r.max_error() for r in runs if r.mu[0] == 0.0 and r.mu[1] == 0.0]
        lost = sum(len(r.contacts_lost) for r in runs)
        ok = kept == len(runs) and err <= POSE_BOUND
        print(f"{name:<30} {len(runs):4d} {kept:4d} {err * 1e3:10.3f} {max(zero) * 1e3 if zero else float('nan'):12.3f} "
              f"{lost:5d} {wall:7.1f} {'yes' if ok else 'no':>9}")  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
