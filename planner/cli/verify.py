"""``qsplan verify``: certify an exported two-finger plan from the task alone (issue 12).

::

    qsplan verify PLAN_DIR [--task TASK.toml] [--json] [--random N] [--seed S] [--force-margin N]

Checks every fact ``PLAN_DIR``'s ``plan.csv`` and ``plan.json`` state (a file path works too: it and the other
file beside it) from the task alone (:func:`qsplan.planner.certify.certify.certify_plan`; its ``CHECKS`` say
what each kind covers): both files hold the same cells and the metadata states the task; the start and the
goal (or the waypoints) reached; no overlap between fingers, palm and workpiece, at every row and along the
free motions; the workpiece resting on the palm while regrasped; joint and speed limits; continuity; the
planned contacts present; every exported band recomputed for the whole friction set, the command and its
margin inside it; with the exported commands, the planned mode the only feasible one at the friction set's
vertices and at N seeded random points.  ``--task`` takes a task file or a bundled task's name; without it the
task recorded in ``plan.json``'s metadata is used (said on the first line): to hold a plan to your own task,
name it.

Exit 0: certified.  Exit 1: not certified, one line per violation (the first
:data:`MAX_LINES`, then a count).  Exit 2: bad input, one line on stderr.
"""

from __future__ import annotations

import json
import sys

from qsplan.planner.certify.scope import SCOPE
from qsplan.planner.cli.options import EXIT_FAILED, EXIT_USAGE, cli_message

__all__ = ["FLAGS", "MAX_LINES", "add_parser", "run"]

#: Library fields of :func:`qsplan.planner.certify.certify.certify_plan` and this command's options.
FLAGS = {"n_random": "--random", "seed": "--seed", "force_margin": "--force-margin", "plan": "PLAN_DIR", "task": "--task"}

#: Violations listed one per line before the rest are counted.
MAX_LINES = 20


def add_parser(subparsers):
    p = subparsers.add_parser("verify", help="certify an exported plan row by row from the task alone",
                              description="Certify an exported plan row by row from the task alone. " + SCOPE)
    p.add_argument("plan", metavar="PLAN_DIR", help="plan directory (plan.csv or plan.json), or one of the files")
    p.add_argument("--task", metavar="TASK", help="task file (.toml) or a bundled task's name (demo_task, ...); "
                                                  "default: the task recorded in plan.json")
    p.add_argument("--json", action="store_true", help="print the certificate as JSON")
    p.add_argument("--random", type=int, default=8, metavar="N",
                   help="seeded random friction vectors per row besides the friction set's vertices (default 8)")  # fmt: skip
    p.add_argument("--seed", type=int, default=0, metavar="S", help="seed of the random friction vectors (default 0)")
    p.add_argument("--force-margin", type=float, default=None, metavar="N",
                   help="minimum normal force (N) of the planned mode at every contact "
                        "(default: the task's min_normal_force)")  # fmt: skip
    return p


def _task(args):
    from qsplan.planner.certify.certify import read_plan, task_from_metadata
    from qsplan.planner.task.task import load_task

    if args.task is not None:
        from qsplan.planner.task.task import task_path

        path = task_path(args.task)
        return load_task(path), f"task {path}"
    from qsplan.mechanics import QsplanError

    cols, meta = read_plan(args.plan)
    if meta is None:
        raise QsplanError(f"{args.plan}: the plan has no plan.json metadata recording its task; name the task file "
                          "with --task")  # fmt: skip
    try:
        task = task_from_metadata(meta, cols)
    except QsplanError as exc:  # the plan's record, not an option, is at fault
        raise QsplanError(f"{args.plan}: plan.json's {exc} with --task") from None
    return task, f"task {task.name!r} as recorded in plan.json (palm thickness not recorded: the default)"


def run(args, out) -> int:
    from qsplan.mechanics import QsplanError

    from qsplan.planner.certify.certify import certify_plan

    try:
        task, source = _task(args)
        margin = task.force_margin.normal if args.force_margin is None else args.force_margin
        cert = certify_plan(args.plan, task, n_random=args.random, seed=args.seed, force_margin=margin)
    except QsplanError as exc:
        sys.stderr.write(f"qsplan: error: {cli_message(str(exc), FLAGS)}\n")
        return EXIT_USAGE
    if args.json:
        json.dump({**cert.to_dict(), "task_source": source}, out, indent=1, allow_nan=False)
        out.write("\n")
    else:
        out.write(f"{cert.source}: {source}\n")
        for v in cert.violations[:MAX_LINES]:
            out.write(f"{v}\n")
        if len(cert.violations) > MAX_LINES:
            out.write(f"... and {len(cert.violations) - MAX_LINES} more violations\n")
        out.write(cert.summary() + "\n")
    return 0 if cert.ok else EXIT_FAILED
