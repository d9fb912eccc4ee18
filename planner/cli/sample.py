"""``qsplan sample``: an exported plan at a controller's rate (issue 24, item 3).

::

    qsplan sample PLAN_DIR --rate HZ [--out FILE.csv] [--force]

Reads ``PLAN_DIR``'s ``plan.csv`` (or ``plan.json``; a file path works too) and writes one CSV row per tick
``k / HZ`` from 0 to the plan's end: ``t``, per joint ``control_<joint>`` (``velocity``, ``torque`` or
``hold``), ``q_<joint>``, ``qd_<joint>``, ``tau_<joint>`` (empty where not commanded), then ``phase`` and
``mode``; ``#`` lines first give the units and the rule (:mod:`qsplan.planner.export.sample`,
``docs/controller.md``).  To stdout without ``--out``; ``--out`` is never overwritten without ``--force``.
Exit 2 with one line on stderr for bad input.
"""

from __future__ import annotations

__all__ = ["FLAGS", "add_parser", "run"]

#: Library fields of :func:`qsplan.planner.export.sample.sample_plan` and this command's options.
FLAGS = {"rate": "--rate", "plan": "PLAN_DIR", "times": "--rate"}


def add_parser(subparsers):
    p = subparsers.add_parser("sample", help="an exported plan's commands at a controller's rate (CSV)")
    p.add_argument("plan", metavar="PLAN_DIR", help="plan directory (plan.csv or plan.json), or one of the files")
    p.add_argument("--rate", type=float, required=True, metavar="HZ", help="ticks per second, e.g. 1000")
    p.add_argument("--out", metavar="FILE.csv", help="write the CSV there (default: stdout)")
    p.add_argument("--force", action="store_true", help="replace an existing --out file")
    return p


def run(args, out) -> int:
    import numpy as np

    from qsplan.planner.export.sample import plan_table, sample_plan, tick_times, write_samples

    cols, _ = plan_table(args.plan)
    t = np.asarray(cols.get("t", []), dtype=float)
    duration = float(np.max(t)) if t.size and np.all(np.isfinite(t)) else 0.0  # sample_plan names a bad column
    samples = sample_plan(args.plan, tick_times(duration, args.rate))
    source = f"{args.plan} at {args.rate:g} Hz"
    if args.out is None:
        write_samples(samples, out, source)
        return 0
    path = write_samples(samples, args.out, source, force=args.force)
    out.write(f"wrote {path} ({samples.t.size} ticks at {args.rate:g} Hz, t = 0 to {samples.t[-1]:.6g} s)\n")
    return 0
