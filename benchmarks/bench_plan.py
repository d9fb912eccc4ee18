"""Planning time and in-contact state checks per second of the two-finger planner (seed 1, deterministic),
and the demo's whole-command wall time, with the figures before issue 13 beside them.

Run: ``python3 benchmarks/bench_plan.py [--repeat N]`` (the bundled tasks, then ``qsplan demo`` N times,
default 3, best taken: the machine is shared, so the best run is the least disturbed one).

``checks`` counts the states judged (the in-contact dense sweeps' samples, each once, and OMPL's
validity checks on the regrasps); ``checks/s`` divides them by the time spent judging them.
"""

import argparse
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from qsplan.planner import load_task, plan_task, task_paths

#: Figures before issue 13 (2-core machine, under load): OMPL's validity checker on in-contact segments
#: at ~140-160 checks/s; ``qsplan demo`` 45-55 s wall.
PREVIOUS = {"checks_per_second": "140-160", "demo_wall_s": "45-55"}


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


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3, help="runs of qsplan demo (best taken)")
    args = ap.parse_args(argv)
    print(f"{'task':<16} {'plan s':>8} {'check s':>8} {'checks':>8} {'checks/s':>9} {'before':>9} {'narrowest N m':>14}")
    for stem, path in task_paths().items():
        task = load_task(path)
        t0 = time.perf_counter()
        plan = plan_task(task)
        wall = time.perf_counter() - t0
        print(f"{stem:<16} {wall:8.2f} {plan.ompl_seconds:8.2f} {plan.validity_checks:8d} "
              f"{plan.checks_per_second:9.1f} {PREVIOUS['checks_per_second']:>9} {plan.narrowest()[2]:14.4g}")  # fmt: skip
    print()
    print(f"{'measure':<34} {'now':>8} {'before':>8}")
    print(f"{f'qsplan demo wall, best of {args.repeat} (s)':<34} {demo_wall(args.repeat):8.2f} {PREVIOUS['demo_wall_s']:>8}")


if __name__ == "__main__":
    main()
