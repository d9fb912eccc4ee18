"""Benchmark: every contact mode of a scene, n_c = 3..12, against the paper's Table 1 (Section 4.7).

For each n_c a seeded planted scene with ``3 + |tau_I| = n_c`` (n_c - 3 effort-controlled
joints of n_c - 1) is solved ``--repeat`` times; the table gives the number of modes tested
(asserted equal to eq. (49)), the paper's approximate cpu seconds on an RS6000/320 where it
gives them (Table 1 for n_c = 3..8, "approximately 20 cpu minutes" for n_c = 12), our median
``solve()`` wall-clock time, modes per second, the feasible modes found and whether the planted
mode is among them (asserted).  It then times the whole command ``qsplan modes FILE --json``
(interpreter start, imports, JSON in and out) on the largest scene, and checks the counts of
Table 1's three dof rows against eq. (49).

Usage, from the repository root, with qsplan installed (``pip install .``) or ``PYTHONPATH=.``::

    python3 benchmarks/bench_modes.py [--max-contacts 12] [--repeat 3] [--out benchmarks/results/modes.csv]
"""

import argparse
import csv
import importlib.util
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from qsplan.mechanics import count_modes, planted_scene, solve
from qsplan.mechanics.model.scene_io_write import scene_to_dict

SEED = 1995
ROOT = Path(__file__).resolve().parents[1]

#: Table 1, "approx. cpu seconds" (n_c = 3 + |tau_I|), and the text's 20 cpu minutes for n_c = 12.
PAPER_SECONDS = {3: 0.3, 4: 0.4, 5: 0.75, 6: 2.0, 7: 5.4, 8: 15.0, 12: 1200.0}

#: Table 1, contact modes tested for n_c = 3..8, by dof - n_c.
PAPER_COUNTS = {
    -1: (6, 16, 45, 126, 357, 1016),
    0: (7, 19, 51, 141, 393, 1107),
    +1: (6, 16, 45, 126, 357, 1016),
}


def bench_scene(n_c: int, seed: int = SEED):
    """The seeded planted scene for ``n_c`` contacts and ``dof = n_c``."""
    rng = np.random.default_rng([seed, n_c])
    return planted_scene(rng, n_c, n_effort=n_c - 3, n_joints=n_c - 1)


def time_solve(scene, repeat: int):
    times, result = [], None
    for _ in range(repeat):
        t = time.perf_counter()
        result = solve(scene)
        times.append(time.perf_counter() - t)
    return statistics.median(times), result


def time_command(scene):
    """Wall-clock seconds of ``python -m qsplan.planner.cli modes FILE --json`` and its parsed output, or None."""
    if importlib.util.find_spec("qsplan.planner.cli") is None:  # (it was planner/cli.py, now a package)
        return None
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")]))}
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "scene.json"
        path.write_text(json.dumps(scene_to_dict(scene)))
        t = time.perf_counter()
        proc = subprocess.run(
            [sys.executable, "-m", "qsplan.planner.cli", "modes", str(path), "--json"],
            capture_output=True, text=True, cwd=ROOT, env=env,
        )  # fmt: skip
        elapsed = time.perf_counter() - t
    if proc.returncode != 0:
        print(f"  (qsplan modes exited {proc.returncode}: {proc.stderr.strip()[:200]})")
        return None
    try:
        return elapsed, json.loads(proc.stdout)
    except json.JSONDecodeError:
        print("  (qsplan modes --json did not print JSON)")
        return None


def check_table1_counts() -> bool:
    print("\nTable 1, contact modes tested (eq. 49) vs the paper:")
    print(f"{'3 + |tau_I|':<14}" + "".join(f"{'n_c=' + str(n):>9}" for n in range(3, 9)) + "   agrees")
    ok_all = True
    for off, paper in PAPER_COUNTS.items():
        ours = [count_modes(n, n + off) for n in range(3, 9)]
        ok = tuple(ours) == paper
        ok_all &= ok
        label = "n_c" + (f" {'+' if off > 0 else '-'} {abs(off)}" if off else "")
        print(f"{label:<14}" + "".join(f"{x:>9}" for x in ours) + f"   {'yes' if ok else 'NO, paper: ' + str(paper)}")
    print(f"{'3^n_c':<14}" + "".join(f"{3**n:>9}" for n in range(3, 9)))
    return ok_all


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--max-contacts", type=int, default=12)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--seed", type=int, default=SEED)
    ap.add_argument("--out", default=str(ROOT / "benchmarks" / "results" / "modes.csv"))
    args = ap.parse_args(argv)

    print(f"solve() on seeded planted scenes with 3 + |tau_I| = n_c (seed {args.seed}), median of {args.repeat}")
    head = f"{'n_c':>4} {'modes':>7} {'paper s':>8} {'ours s':>9} {'modes/s':>9} {'speedup':>8} {'feasible':>9}  planted found"
    print(head)
    rows = []
    last = None
    for n_c in range(3, args.max_contacts + 1):
        scene, planted = bench_scene(n_c, args.seed)
        sec, result = time_solve(scene, args.repeat)
        assert result.modes_tested == count_modes(n_c, n_c), (n_c, result.modes_tested)
        found = planted.letters in result.feasible_modes
        paper = PAPER_SECONDS.get(n_c)
        row = dict(
            n_c=n_c, dof=n_c, modes_tested=result.modes_tested, paper_seconds=paper, seconds=sec,
            modes_per_second=result.modes_tested / sec, feasible=len(result.solutions), planted_found=found,
        )  # fmt: skip
        rows.append(row)
        paper_s = f"{paper:8.4g}" if paper else f"{'-':>8}"
        speed = f"{paper / sec:8.0f}" if paper else f"{'-':>8}"
        print(
            f"{n_c:>4} {result.modes_tested:>7} {paper_s} {sec:9.4f} {row['modes_per_second']:9.0f} {speed} "
            f"{row['feasible']:>9}  {found}"
        )
        last = (scene, result)
        assert found, f"planted mode {planted.letters} not found for n_c = {n_c}"

    scene, result = last
    timed = time_command(scene)
    if timed is None:
        print(f"\nwhole command (qsplan modes FILE --json, n_c = {scene.n_contacts}): not available")
    else:
        sec, doc = timed
        same = [f["mode"] for f in doc.get("feasible", [])] == result.feasible_modes
        print(
            f"\nwhole command (qsplan modes FILE --json, n_c = {scene.n_contacts}, {doc.get('modes_tested')} modes): "
            f"{sec:.3f} s wall clock, same feasible modes as solve(): {same}"
        )

    ok = check_table1_counts()
    assert ok, "eq. (49) disagrees with Table 1"

    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    with out.open("w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    print(f"\nwrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
