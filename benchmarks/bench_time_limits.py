"""Every OMPL planner against its time limit: how long a query with no path runs, and the whole ``qsplan plan``.

The tests check that each planner returns, and that the ones searching in a second thread (PRM) are stopped by
OMPL's own timer (``tests/planner/test_plan_planners.py``); how long they take is measured here, on this machine:

* (a) a query with no path (``plan_path`` on [0, 1] with the obstacle (0.4, 0.6) between start 0.1 and goal 0.9),
  each planner at each time limit: OMPL's status, the seconds ``plan_path`` reports, and the overshoot beyond the
  limit (what a planner does between two looks at the clock: a batch of BIT*'s samples,
  ``BITSTAR_SAMPLES_PER_BATCH``; PRM's last roadmap step).  Deterministic planners stop at their iteration
  budget first when that comes sooner;
* (b) ``qsplan plan`` of a one-segment task with a regrasp (5 mm left, regrasp, back) with each ``--planner`` and
  ``--time-limit 0.5``, in a subprocess (interpreter start and imports included): its exit status, the wall time,
  and the slowest OMPL query it reports.

Usage, from the repository root::

    python3 benchmarks/bench_time_limits.py [--repeat 3] [--limits 0.3 0.5 1.0]
"""

import argparse
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from qsplan.planner.search.ompl_bridge import PLANNERS, PlannerOptions, plan_path

#: A slide of 5 mm, a regrasp, a slide back: two in-contact segments and two OMPL queries (the fingers' opening and
#: closing), on the demo's hand.
TASK = """
name = "one regrasp"
[hand]
workpiece = [[0.0, 0.0], [0.080, 0.0], [0.085, 0.080], [0.008, 0.100]]
[motion]
start_x = 0.0
waypoints = [-0.005, 0.0]
[friction]
range = [0.0, 0.2]
[controller]
torque_resolution = 0.02
"""

#: Seconds after which a run counts as hung (a guard for the benchmark itself).
HANG_GUARD = 600


def blocked_query(planner: str, limit: float):
    """``(status, seconds)`` of a query with no path, limited to ``limit`` s."""
    r = plan_path([0.0], [1.0], [0.1], [0.9], lambda x: not 0.4 < x[0] < 0.6, PlannerOptions(planner, time_limit=limit))
    return r.status, r.seconds


def command(planner: str, limit: float, task: Path, out: Path):
    """``(exit status, wall seconds, slowest OMPL query's seconds or nan)`` of ``qsplan plan``."""
    cmd = [sys.executable, "-m", "qsplan.planner.cli", "plan", str(task), "--planner", planner, "--time-limit",
           str(limit), "--out", str(out), "--no-plots", "--verify", "0", "--force"]  # fmt: skip
    t0 = time.perf_counter()
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=HANG_GUARD)
    wall = time.perf_counter() - t0
    ompl = [float(m.group(1)) for m in re.finditer(r"  OMPL: .* in ([0-9.]+) s", p.stderr)]
    return p.returncode, wall, max(ompl) if ompl else float("nan")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3, help="runs of each case (default 3): the median and the worst")
    ap.add_argument("--limits", type=float, nargs="+", default=[0.3, 0.5, 1.0], help="time limits of (a), s")
    args = ap.parse_args(argv)

    print("(a) a query with no path: OMPL's seconds against the limit (median / worst of "
          f"{args.repeat})")  # fmt: skip
    print(f"{'planner':<11} {'limit s':>7} {'status':<22} {'median s':>9} {'worst s':>8} {'overshoot s':>11}")
    for planner in PLANNERS:
        for limit in args.limits:
            runs = [blocked_query(planner, limit) for _ in range(args.repeat)]
            seconds = [s for _, s in runs]
            statuses = sorted({st for st, _ in runs})
            print(f"{planner:<11} {limit:>7g} {'/'.join(statuses):<22} {np.median(seconds):>9.3f} {max(seconds):>8.3f} "
                  f"{max(seconds) - limit:>+11.3f}")  # fmt: skip

    print(f"\n(b) qsplan plan, one slide, a regrasp, a slide back, --time-limit 0.5 (median / worst of {args.repeat})")
    print(f"{'planner':<11} {'exit':>4} {'median s':>9} {'worst s':>8} {'slowest OMPL query s':>21}")
    with tempfile.TemporaryDirectory() as tmp:
        task = Path(tmp) / "task.toml"
        task.write_text(TASK)
        for planner in PLANNERS:
            runs = [command(planner, 0.5, task, Path(tmp) / "out") for _ in range(args.repeat)]
            codes = sorted({c for c, _, _ in runs})
            walls = [w for _, w, _ in runs]
            ompl = max(q for _, _, q in runs)
            print(f"{planner:<11} {'/'.join(map(str, codes)):>4} {np.median(walls):>9.2f} {max(walls):>8.2f} {ompl:>21.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
