"""The ``qsplan`` command: builds the parser from the subcommand modules and dispatches.

Subcommands, one module each in :mod:`qsplan.planner.cli` (``add_parser(subparsers)`` and
``run(args, out) -> int``)::

    qsplan modes SCENE [--mu M ...] [--json] [--method enumerate|lcp]
                       [--workers N] [--scheduler ADDRESS] [--search auto|prune|all] [--stats]
                                                    every feasible contact mode (lcp: one, fast)
    qsplan count --contacts N --dof D [--json]      number of modes tested (eq. 49)
    qsplan partition SCENE [--mode LETTERS] [--json]  control-mode partitioner (eq. 32)
    qsplan paper [--out DIR]                        reproduce the paper's examples into DIR
    qsplan muspace | band | simulate | sweep | plan | demo | verify   (see each module)

Bad input prints one line on stderr naming the field and the problem and
exits with status 2; so does valid input without an answer (no plan, no band).
Library messages name library fields; they are printed with this command's
options instead (:func:`qsplan.planner.cli.options.cli_message`).
"""

from __future__ import annotations

import argparse
import sys

from qsplan.planner.cli import band, count, demo, modes, muspace, paper, partition, plan, simulate, sweep, verify
from qsplan.planner.cli.options import (
    EXIT_USAGE,
    Parser,
    UsageError,
    add_parallel_options,
    cli_message,
    overwrite_message,
    parallel_options,
)

__all__ = ["COMMANDS", "EXIT_USAGE", "main", "build_parser", "add_parallel_options", "parallel_options"]

#: The subcommands, in the order of ``qsplan --help``.
COMMANDS = {"modes": modes, "count": count, "partition": partition, "paper": paper, "muspace": muspace,
            "band": band, "simulate": simulate, "sweep": sweep, "plan": plan, "demo": demo, "verify": verify}  # fmt: skip


def build_parser() -> argparse.ArgumentParser:
    p = Parser(prog="qsplan", description="Quasistatic planar contact-mode prediction (Trinkle & Zeng 1995).")
    sub = p.add_subparsers(dest="command", required=True, parser_class=Parser)
    for module in COMMANDS.values():
        module.add_parser(sub)
    return p


def main(argv=None) -> int:
    """Entry point of the ``qsplan`` console script; returns the exit status."""
    from qsplan.mechanics.errors import NoAnswerError, QsplanError

    from qsplan.planner.export.files import OutputExistsError

    flags = {}
    try:
        args = build_parser().parse_args(argv)
        module = COMMANDS[args.command]
        flags = getattr(module, "FLAGS", {})
        return module.run(args, sys.stdout)
    except UsageError as exc:
        print(str(exc), file=sys.stderr)
        return EXIT_USAGE
    except OutputExistsError as exc:
        print(f"qsplan: error: {overwrite_message(exc)}", file=sys.stderr)
        return EXIT_USAGE
    except QsplanError as exc:
        print(f"qsplan: error: {cli_message(str(exc), flags)}", file=sys.stderr)
        return EXIT_USAGE
    except NoAnswerError as exc:
        path = getattr(exc, "report_path", None)
        print(f"qsplan: error: {exc}" + (f" (report: {path})" if path else ""), file=sys.stderr)
        return EXIT_USAGE
    except BrokenPipeError:
        return 0


if __name__ == "__main__":
    sys.exit(main())
