"""``qsplan count --contacts N --dof D [--json]``: the number of contact modes tested (eq. 49, Table 1).

A binomial sum: this module imports nothing of the solver.
"""

from __future__ import annotations

import json

__all__ = ["add_parser", "run"]


def add_parser(subparsers):
    c = subparsers.add_parser("count", help="number of contact modes tested (eq. 49, Table 1)")
    c.add_argument("--contacts", type=int, required=True, metavar="N", help="number of contacts n_c")
    c.add_argument("--dof", type=int, required=True, metavar="D", help="3 + number of effort-controlled joints")
    c.add_argument("--json", action="store_true")
    return c


def run(args, out) -> int:
    from qsplan.mechanics.errors import ModeError
    from qsplan.mechanics.modes.counting import count_modes

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
