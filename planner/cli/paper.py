"""``qsplan paper [--out DIR] [--n N] [--force]``: reproduce the paper's examples (eqs. 37, 42, the rod) into DIR.

Existing files of the same names in DIR are replaced only with ``--force`` (checked before any work).

Calls :func:`qsplan.planner.reports.paper.reproduce_paper` and prints its summary; progress on stderr.
"""

from __future__ import annotations

import sys

__all__ = ["add_parser", "run"]


def add_parser(subparsers):
    r = subparsers.add_parser("paper", help="reproduce the paper's examples (eqs. 37, 42, rod) into --out")
    r.add_argument("--out", default="out", metavar="DIR", help="output directory (default: out)")
    r.add_argument("--n", type=int, default=161, help="grid points per mu axis (default 161)")
    r.add_argument("--force", action="store_true", help="replace existing outputs in DIR")
    return r


def run(args, out) -> int:
    from qsplan.mechanics import QsplanError

    from qsplan.planner.reports.paper import reproduce_paper

    if args.n < 2:
        raise QsplanError(f"--n: expected at least 2 grid points; got {args.n}")
    out.write(reproduce_paper(args.out, n=args.n, progress=sys.stderr, force=args.force))
    return 0
