"""Whole commands as a user runs them (interpreter start, imports, work, outputs), best of N, with issue 33's goals;
with ``--compare REV``, the same commands of the revision REV in the same run, interleaved, and the ratio.

Run, from the repository root with qsplan installed (``pip install -e .``)::

    python3 benchmarks/bench_whole.py [--repeat 3] [--compare REV]

The commands: ``qsplan demo --out DIR`` (a new DIR each run), ``qsplan verify DIR`` (the demo's plan), ``qsplan plan
reorient_task --out DIR`` and ``qsplan modes FILE --json`` on the planted scene of n_c = 20 of
``benchmarks/bench_scale.py``.  The machine is shared and its speed drifts between runs: ``--compare`` runs REV and the
working tree one after the other for every repetition, so both see the same machine; the best of each is compared.
REV's tree is exported with ``git archive`` into a temporary directory laid out as the installed package
(``qsplan/`` with ``mechanics``, ``hands``, ``planner`` inside; the compiled mode screen copied from this tree, or
built with the C compiler when REV's source differs) and run by the same interpreter with that directory first on
``PYTHONPATH``.  Nothing here asserts a time.
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from revisions import revision_env  # noqa: E402 (benchmarks/ on the path first)

#: Issue 33's goals (s, whole command, on this 2-core machine) and its figures before (the issue's table).
GOALS = {"demo": 2.0, "verify": 1.0, "plan reorient_task": 5.0, "modes n_c=20": 0.25}
ISSUE_BEFORE = {"demo": "3.8-6.8", "verify": "2.2", "plan reorient_task": "13.9", "modes n_c=20": "0.29-0.39"}

def planted_scene(path: Path) -> None:
    """``benchmarks/bench_scale.py``'s planted scene with n_c = 20 (|tau_I| = 17) as a scene file."""
    from bench_scale import bench_scene

    from qsplan.mechanics.model.scene_io_write import scene_to_dict

    scene, _ = bench_scene(20, 17)
    path.write_text(json.dumps(scene_to_dict(scene)))


def timed(argv, env, cwd) -> float:
    """Wall seconds of one command (its output discarded; a failure stops the benchmark)."""
    t = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "qsplan.planner.cli", *argv], env=env, cwd=cwd, capture_output=True,
                          text=True, check=False)  # fmt: skip
    elapsed = time.perf_counter() - t
    if proc.returncode != 0:
        raise SystemExit(f"qsplan {' '.join(argv)} exited {proc.returncode}: {proc.stderr.strip()[-400:]}")
    return elapsed


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3, help="runs of each command (best taken)")
    ap.add_argument("--compare", metavar="REV", help="also run revision REV (git), interleaved with this tree")
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="qsplan-bench-") as tmp:
        tmp = Path(tmp)
        scene = tmp / "planted_20.json"
        planted_scene(scene)
        sides = {"after": dict(os.environ)}
        if args.compare:
            sides = {"before": revision_env(args.compare, tmp / "rev"), **sides}
        best = {(cmd, side): float("inf") for cmd in GOALS for side in sides}
        for i in range(args.repeat):
            for side, env in sides.items():
                out = tmp / f"{side}{i}"
                runs = {"demo": ["demo", "--out", str(out / "demo")], "verify": ["verify", str(out / "demo")],
                        "plan reorient_task": ["plan", "reorient_task", "--out", str(out / "reorient")],
                        "modes n_c=20": ["modes", str(scene), "--json"]}  # fmt: skip
                for cmd, command in runs.items():
                    best[cmd, side] = min(best[cmd, side], timed(command, env, tmp))
            print(f"repetition {i + 1} of {args.repeat} done", file=sys.stderr, flush=True)
    rev = f" ({args.compare})" if args.compare else ""
    print(f"whole commands, best of {args.repeat}, {os.cpu_count()} cores, load average now "
          f"{os.getloadavg()[0]:.2f}")  # fmt: skip
    head = f"{'command':<22} {'issue before':>12}"
    head += f" {'before' + rev:>20}" if args.compare else ""
    head += f" {'now s':>7}" + (f" {'ratio':>6}" if args.compare else "") + f" {'goal s':>7}"
    print(head)
    for cmd, goal in GOALS.items():
        now = best[cmd, "after"]
        line = f"{cmd:<22} {ISSUE_BEFORE[cmd]:>12}"
        if args.compare:
            line += f" {best[cmd, 'before']:>20.2f}"
        line += f" {now:>7.2f}"
        if args.compare:
            line += f" {best[cmd, 'before'] / now:>5.2f}x"
        line += f" {goal:>7.2f} {'met' if now <= goal else 'MISSED'}"
        print(line)
    return 0


if __name__ == "__main__":
    sys.exit(main())
