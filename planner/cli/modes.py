"""``qsplan modes SCENE``: every feasible contact mode of a scene (Sections 3-4), or one by Lemke's method.

::

    qsplan modes SCENE [--mu M ...] [--json] [--method enumerate|lcp]
                       [--workers N] [--scheduler ADDRESS] [--search auto|prune|all] [--stats]

``--method enumerate`` (default) tests every mode of eq. 49 (:func:`qsplan.mechanics.solve`);
``--method lcp`` finds one by Lemke's method, fast, and says that others may exist.
When the estimated work exceeds :data:`LONG_WORK_SECONDS`, an estimate line and progress
lines go to stderr (stdout, a format others parse, is unchanged).
"""

from __future__ import annotations

import json
import sys
import time

from qsplan.planner.cli.options import add_parallel_options, parallel_options

__all__ = ["FLAGS", "LONG_WORK_SECONDS", "PROGRESS_SECONDS", "add_parser", "run"]

#: Library fields of :func:`qsplan.mechanics.load_scene` and this command's options.
FLAGS = {"mu": "--mu", "search": "--search"}

#: Estimated seconds above which the command says up front how long it expects to take: past
#: ~10 s a silent command looks hung.
LONG_WORK_SECONDS = 10.0

#: Seconds between two progress lines on stderr.
PROGRESS_SECONDS = 10.0


def add_parser(subparsers):
    m = subparsers.add_parser("modes", help="every feasible contact mode of a scene")
    m.add_argument("scene", help="scene file (.json or .toml; raw or geometric form)")
    m.add_argument("--mu", type=float, nargs="+", metavar="M", help="friction override: one value or one per contact")
    m.add_argument("--json", action="store_true", help="machine-readable output on stdout")
    m.add_argument("--method", choices=("enumerate", "lcp"), default="enumerate",
                   help="enumerate: every feasible mode (default); lcp: one mode by Lemke's method, fast")  # fmt: skip
    add_parallel_options(m)
    m.add_argument("--search", choices=("auto", "prune", "all"), default="auto",
                   help="prune: skip modes whose breaking set admits no equilibrium (same result); all: test "
                        "every mode; auto (default): prune when its programmes cost less than testing every mode")  # fmt: skip
    m.add_argument("--stats", action="store_true", help="time, modes tested/pruned and peak memory on stderr")
    return m


def _fmt(x, width=9):
    return f"{x:{width}.4g}"


def run(args, out) -> int:
    from qsplan.mechanics import load_scene, solve

    scene = load_scene(args.scene, mu=args.mu)
    if getattr(args, "method", "enumerate") == "lcp":
        return _run_lcp(scene, args, out)
    options = parallel_options(args)
    started = time.perf_counter()
    result = solve(scene, search=args.search, progress=_announce(scene, args, options, started), **options)
    if args.stats:
        _modes_stats(result, time.perf_counter() - started)
    from qsplan.mechanics.numerics import conditioning_verdict

    verdict = conditioning_verdict(result.counts, result.tolerances)
    if args.json:
        from qsplan.planner.reports.solve_report import solve_result_to_dict

        json.dump({**solve_result_to_dict(result), "ill_conditioned": verdict}, out)
        out.write("\n")
        return 0
    from qsplan.planner.reports.solve_report import format_solve_result

    out.write(format_solve_result(result, source=args.scene))
    if verdict:
        out.write(verdict + "\n")
    return 0


def _announce(scene, args, options, started):
    """For long work: an estimate line on stderr now, and a progress callback printing every
    :data:`PROGRESS_SECONDS`; None for short work.

    The pruned search (``--search auto|prune``) costs at most screening every mode, usually a few
    percent of that (``KEPT_SHARE``): the line is printed when that expected time is long, the
    progress callback installed when the bound is, so that a search that prunes badly still reports.
    """
    from qsplan.mechanics import count_modes
    from qsplan.mechanics.parallel import resolve_workers
    from qsplan.mechanics.solver.all_modes import estimate_seconds
    from qsplan.mechanics.solver.search import KEPT_SHARE, screen_all_seconds

    n_c, dof = scene.n_contacts, scene.dof
    if options["scheduler"] is None:
        workers = resolve_workers(options["workers"])
        where = f"{workers} local process{'es' if workers > 1 else ''}"
    else:
        workers = options["workers"] or 1
        where = f"{workers} cluster worker(s) assumed"
    bound = expected = estimate_seconds(n_c, dof, workers)  # testing every mode
    if args.search != "all":
        bound = min(bound, screen_all_seconds(n_c, dof) / workers)
        expected = KEPT_SHARE * bound
    if bound <= LONG_WORK_SECONDS:
        return None
    if expected > LONG_WORK_SECONDS:
        how = {"all": "every mode tested", "prune": f"breaking sets pruned first; at most about {bound:.0f} s",
               "auto": f"the pruned search's usual share; at most about {bound:.0f} s"}[args.search]  # fmt: skip
        print(f"qsplan modes: {count_modes(n_c, dof):,} modes (eq. 49: n_c = {n_c}, {dof} constraints per mode); "
              f"this takes about {expected:.0f} s on {where} ({how}); progress every {PROGRESS_SECONDS:g} s",
              file=sys.stderr, flush=True)  # fmt: skip
    last = [started]

    def progress(done, total, unit):
        now = time.perf_counter()
        if now - last[0] >= PROGRESS_SECONDS and total:
            last[0] = now
            print(f"qsplan modes: {done:,} of {total:,} {unit} done ({100 * done / total:.0f}%), "
                  f"{now - started:.0f} s", file=sys.stderr, flush=True)  # fmt: skip

    return progress


def _modes_stats(result, seconds):
    """``qsplan modes --stats``: one line on stderr (time, modes tested and pruned, peak memory)."""
    import resource

    pruned = sum(v for k, v in result.counts.items() if k.startswith("pruned"))
    # ru_maxrss is in KiB on Linux; children: the largest worker process
    peak = max(resource.getrusage(who).ru_maxrss for who in (resource.RUSAGE_SELF, resource.RUSAGE_CHILDREN))
    print(
        f"qsplan modes: {seconds:.3f} s solve, {result.modes_tested} modes (eq. 49): {result.modes_tested - pruned} "
        f"tested, {pruned} pruned; {len(result.solutions)} feasible; peak memory {peak / 1024:.0f} MiB",
        file=sys.stderr,
    )


def _run_lcp(scene, args, out):
    """``qsplan modes --method lcp``: one mode from the LCP (qsplan.mechanics.crosscheck.lcp), or why there is none."""
    from qsplan.mechanics import SolveResult
    from qsplan.mechanics.crosscheck.lcp import solve_lcp

    res = solve_lcp(scene)
    if args.json:
        from qsplan.planner.reports.solve_report import solve_result_to_dict

        one = SolveResult(scene=scene, modes_tested=1, solutions=(res.solution,) if res.solved else (), counts={})
        doc = solve_result_to_dict(one)
        doc = {"method": "lcp", "status": res.status, "read_mode": res.letters, "pivots": res.pivots,
               "feasible": doc["feasible"], "units": doc["units"]}  # fmt: skip
        json.dump(doc, out)
        out.write("\n")
        return 0
    out.write(f"scene {args.scene}: {scene.n_contacts} contacts; method lcp (Lemke, one solution): {res.status} "
              f"after {res.pivots} pivots\n")  # fmt: skip
    if res.solved:
        s = res.solution
        out.write(f"mode {s.mode.letters} ({s.mode.name}); verified by check_mode, max residual {s.max_residual:.2g}\n")
        out.write(f"  qdot {' '.join(_fmt(x) for x in s.qdot)}\n  c_n  {' '.join(_fmt(x) for x in s.c_n)}\n"
                  f"  c_t  {' '.join(_fmt(x) for x in s.c_t)}\n")  # fmt: skip
        out.write("other modes may be feasible too: only --method enumerate finds them all\n")
    else:
        read = f" (the LCP solution reads as {res.letters}: {res.check_status})" if res.letters else ""
        out.write(f"no mode found{read}; this does not prove the scene jams: use --method enumerate\n")
    return 0
