"""The ``qsplan`` command.

Subcommands::

    qsplan modes SCENE [--mu M ...] [--json] [--method enumerate|lcp]
                       [--workers N] [--scheduler ADDRESS] [--search auto|prune|all] [--stats]
                                                    every feasible contact mode (lcp: one, fast)
    qsplan count --contacts N --dof D [--json]      number of modes tested (eq. 49)
    qsplan partition SCENE [--mode LETTERS] [--json]  control-mode partitioner (eq. 32)
    qsplan paper [--out DIR]                        reproduce the paper's examples into DIR

Bad input prints one line on stderr naming the field and the problem and
exits with status 2; nothing else is written.
"""

from __future__ import annotations

import argparse
import json
import sys
import time

__all__ = ["main", "build_parser", "add_parallel_options", "parallel_options"]

EXIT_USAGE = 2


class _UsageError(Exception):
    pass


class _Parser(argparse.ArgumentParser):
    """argparse that reports errors in one line (no usage dump) and exits 2."""

    def error(self, message):  # noqa: D102
        raise _UsageError(f"{self.prog}: {message}")


def build_parser() -> argparse.ArgumentParser:
    p = _Parser(prog="qsplan", description="Quasistatic planar contact-mode prediction (Trinkle & Zeng 1995).")
    sub = p.add_subparsers(dest="command", required=True, parser_class=_Parser)

    m = sub.add_parser("modes", help="every feasible contact mode of a scene")
    m.add_argument("scene", help="scene file (.json or .toml; raw or geometric form)")
    m.add_argument("--mu", type=float, nargs="+", metavar="M", help="friction override: one value or one per contact")
    m.add_argument("--json", action="store_true", help="machine-readable output on stdout")
    m.add_argument("--method", choices=("enumerate", "lcp"), default="enumerate",
                   help="enumerate: every feasible mode (default); lcp: one mode by Lemke's method, fast")  # fmt: skip
    add_parallel_options(m)
    m.add_argument("--search", choices=("auto", "prune", "all"), default="auto",
                   help="prune: skip modes whose breaking set admits no equilibrium (same result); all: test "
                        "every mode; auto (default): prune from 20,000 modes on")  # fmt: skip
    m.add_argument("--stats", action="store_true", help="time, modes tested/pruned and peak memory on stderr")

    c = sub.add_parser("count", help="number of contact modes tested (eq. 49, Table 1)")
    c.add_argument("--contacts", type=int, required=True, metavar="N", help="number of contacts n_c")
    c.add_argument("--dof", type=int, required=True, metavar="D", help="3 + number of effort-controlled joints")
    c.add_argument("--json", action="store_true")

    t = sub.add_parser("partition", help="control-mode partitions admitted by each contact mode (eq. 32)")
    t.add_argument("scene")
    t.add_argument("--mode", metavar="LETTERS", help="rank the effort-joint sets of one mode, e.g. RBS")
    t.add_argument("--json", action="store_true")

    r = sub.add_parser("paper", help="reproduce the paper's examples (eqs. 37, 42, rod) into --out")
    r.add_argument("--out", default="out", metavar="DIR", help="output directory (default: out)")
    r.add_argument("--n", type=int, default=161, help="grid points per mu axis (default 161)")

    for name in COMMAND_MODULES:
        _command_module(name).add_parser(sub)
    return p


#: Subcommands that live in their own module ``qsplan.planner.cli.<name>``, each with
#: ``add_parser(subparsers)`` and ``run(args, out) -> int``.
COMMAND_MODULES: tuple = ("muspace", "band", "simulate", "sweep", "plan", "demo")


def _command_module(name):
    import importlib

    return importlib.import_module(f"qsplan.planner.cli.{name}")


def add_parallel_options(p):
    """``--workers N`` and ``--scheduler ADDRESS`` (see :func:`mechanics.parallel.map_chunks`)."""
    p.add_argument("--workers", type=int, metavar="N",
                   help="local processes for independent chunks (default: all cores; 1: in-process)")  # fmt: skip
    p.add_argument("--scheduler", metavar="ADDRESS",
                   help="run the chunks on a Dask cluster, e.g. tcp://host:8786 (needs qsplan[cluster])")  # fmt: skip


def parallel_options(args) -> dict:
    """``{"workers": ..., "scheduler": ...}`` from :func:`add_parallel_options`'s arguments, checked."""
    from qsplan.mechanics import QsplanError

    if args.workers is not None and args.workers < 1:
        raise QsplanError(f"--workers: expected a positive number of processes (1 runs in-process); got {args.workers}")
    return {"workers": args.workers, "scheduler": args.scheduler}


def _fmt(x, width=9):
    return f"{x:{width}.4g}"


def _cmd_modes(args, out):
    from qsplan.mechanics import load_scene, solve

    scene = load_scene(args.scene, mu=args.mu)
    if getattr(args, "method", "enumerate") == "lcp":
        return _cmd_modes_lcp(scene, args, out)
    started = time.perf_counter()
    result = solve(scene, search=args.search, **parallel_options(args))
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


def _cmd_modes_lcp(scene, args, out):
    """``qsplan modes --method lcp``: one mode from the LCP (mechanics.lcp), or why there is none."""
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


def _cmd_count(args, out):
    from qsplan.mechanics import ModeError, count_modes

    if args.contacts < 0:
        raise ModeError(f"--contacts: expected a nonnegative integer; got {args.contacts}")
    if args.dof < 0:
        raise ModeError(f"--dof: expected a nonnegative integer; got {args.dof}")
    n = count_modes(args.contacts, args.dof)
    if args.json:
        json.dump({"contacts": args.contacts, "dof": args.dof, "modes": n, "all_combinations": 3**args.contacts}, out)
        out.write("\n")
    else:
        out.write(f"{n}\n")
    return 0


def _cmd_partition(args, out):
    from qsplan.mechanics import load_scene, mode_from_letters
    from qsplan.mechanics.modes.partition import effort_partitions, partition_table

    scene = load_scene(args.scene)
    if scene.virtual_joints:
        from qsplan.mechanics import SceneError

        raise SceneError(f"{args.scene}: joints: the scene gives contact velocities, not joints; nothing to partition")
    names = scene.joint_names
    if args.mode:
        mode = mode_from_letters(args.mode, scene.n_contacts)
        parts = effort_partitions(scene, mode)
        rows = [
            {"effort_joints": [names[i] for i in p.effort_joints], "rcond_P": p.rcond_P, "rcond_Q": p.rcond_Q}
            for p in parts
        ]
        if args.json:
            json.dump({"mode": mode.letters, "name": mode.name, "partitions": rows}, out)
            out.write("\n")
        else:
            out.write(f"mode {mode.letters} ({mode.name}): {len(rows)} admissible effort-joint sets, best first\n")
            for r in rows:
                out.write(f"  effort {{{', '.join(r['effort_joints'])}}}  rcond P {r['rcond_P']:.3g}  Q {r['rcond_Q']:.3g}\n")
        return 0
    table = partition_table(scene)
    if args.json:
        json.dump({"partitions": [{"effort_joints": [names[i] for i in k], "modes": v} for k, v in table.items()]}, out)
        out.write("\n")
    else:
        for k, v in table.items():
            out.write(f"effort {{{', '.join(names[i] for i in k)}}}: {len(v)} modes: {' '.join(v)}\n")
    return 0


def _cmd_paper(args, out):
    from qsplan.planner.reports.paper import reproduce_paper

    if args.n < 2:
        from qsplan.mechanics import QsplanError

        raise QsplanError(f"--n: expected at least 2 grid points; got {args.n}")
    summary = reproduce_paper(args.out, n=args.n, progress=sys.stderr)
    out.write(summary)
    return 0


_COMMANDS = {"modes": _cmd_modes, "count": _cmd_count, "partition": _cmd_partition, "paper": _cmd_paper}


def main(argv=None) -> int:
    """Entry point of the ``qsplan`` console script; returns the exit status."""
    from qsplan.mechanics import QsplanError

    try:
        args = build_parser().parse_args(argv)
        if args.command in _COMMANDS:
            return _COMMANDS[args.command](args, sys.stdout)
        return _command_module(args.command).run(args, sys.stdout)
    except _UsageError as exc:
        print(str(exc), file=sys.stderr)
        return EXIT_USAGE
    except QsplanError as exc:
        print(f"qsplan: error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except BrokenPipeError:
        return 0


if __name__ == "__main__":
    sys.exit(main())
