"""Benchmark: the input fuzzer of ``tests/test_fuzz.py`` at 10,000 cases, with a table of outcomes.

Mutated scene files (through ``modes``, ``partition``, ``band``, ``muspace``), mutated task files
(through ``plan`` up to planning; OMPL itself is stubbed), mutated hand files (through ``hands`` and
through a task naming the file), deep TOML dotted keys in scene, task and hand files, and hostile
command-line options, each run in-process through ``qsplan``'s ``main`` with a time bound
(:mod:`tests.fuzzing`; the kinds' shares are its ``CASE_MIX``).  Prints one row per
(kind, outcome) with its count, the slowest case, and every non-clean case (tracebacks, multi-line
exit-2 errors, timeouts), so a regression names its input.  Exit status 1 when any case is not clean.

Usage, from the repository root: ``PYTHONPATH=. python benchmarks/bench_fuzz.py [N] [--seed S] [--timeout T]``
(default N = 10000, seed 2024, 10 s per case).
"""

import argparse
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))  # the repository root, for tests.fuzzing

from tests.fuzzing import CLEAN, make_cases, run_case  # noqa: E402


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("n", nargs="?", type=int, default=10_000, help="cases (default 10000)")
    ap.add_argument("--seed", type=int, default=2024)
    ap.add_argument("--timeout", type=float, default=10.0, help="seconds per case")
    args = ap.parse_args(argv)
    counts, slowest, bad = Counter(), (0.0, None), []
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        for i, case in enumerate(make_cases(args.seed, args.n)):
            outcome, seconds, err = run_case(case, Path(tmp) / f"c{i}", timeout=args.timeout)
            counts[(case["kind"], outcome)] += 1
            if seconds > slowest[0]:
                slowest = (seconds, case["argv"])
            if outcome not in CLEAN:
                bad.append((i, outcome, case["argv"], err.strip().splitlines()[-1:] if err.strip() else []))
            if (i + 1) % 1000 == 0:
                print(f"[bench_fuzz] {i + 1} cases, {time.perf_counter() - t0:.1f} s", file=sys.stderr, flush=True)
    total = time.perf_counter() - t0
    print(f"fuzz: {args.n} cases, seed {args.seed}, {total:.1f} s ({1e3 * total / max(args.n, 1):.1f} ms per case)")
    print(f"{'kind':<8} {'outcome':<28} {'count':>7}")
    for (kind, outcome), n in sorted(counts.items()):
        print(f"{kind:<8} {outcome:<28} {n:>7}")
    print(f"not clean: {len(bad)}; slowest case {slowest[0]:.2f} s: {slowest[1]}")
    for i, outcome, argv, last in bad[:50]:
        print(f"  case {i}: {outcome} {argv} {last}")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
