"""Planning time and validity checks per second of the two-finger planner (seed 1, deterministic).

Run: ``python3 benchmarks/bench_plan.py`` (the bundled tasks; about a minute).
"""

import time

from qsplan.planner import load_task, plan_task, task_paths


def main():
    print(f"{'task':<16} {'plan s':>8} {'OMPL s':>8} {'checks':>8} {'checks/s':>9} {'narrowest N m':>14}")
    for stem, path in task_paths().items():
        task = load_task(path)
        t0 = time.perf_counter()
        plan = plan_task(task)
        wall = time.perf_counter() - t0
        print(f"{stem:<16} {wall:8.2f} {plan.ompl_seconds:8.2f} {plan.validity_checks:8d} "
              f"{plan.checks_per_second:9.1f} {plan.narrowest()[2]:14.4g}")  # fmt: skip


if __name__ == "__main__":
    main()
