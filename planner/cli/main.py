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
    qsplan hands [REF] [--out DIR [--force]]        list the bundled hand files, or check and show one
    qsplan check TASK [--out DIR [--force]] [--json]  feasibility preview: valid and banded x ranges per grasp
    qsplan sample PLAN_DIR --rate HZ [--out FILE]   the plan at a controller's rate
    qsplan replay PLAN_DIR [--engine mujoco] ...    the exported commands executed in MuJoCo
    qsplan --version                                the version (qsplan.__version__)

Bad input prints one line on stderr naming the field and the problem and
exits with status 2; so does valid input without an answer (no plan, no band).
Ctrl-C prints ``qsplan: interrupted`` and exits 130; every output is written to a
temporary name and renamed (:func:`qsplan.planner.export.files.atomic_write`), so an
interrupted run leaves no half-written file; ``plan`` and ``demo`` stage their outputs and
publish them only once the plan is certified (:mod:`qsplan.planner.pipeline.run`), so it
leaves no uncertified plan either.  A second run into a directory that ``plan``, ``demo`` or
``paper`` is writing fails at once (exit 2, naming the first run's pid).
Library messages name library fields; they are printed with this command's
options instead (:func:`qsplan.planner.cli.options.cli_message`).
"""

from __future__ import annotations

import argparse
import sys

from qsplan.planner.cli import (band, check, count, demo, hands, modes, muspace, paper, partition, plan, replay,
                                sample, simulate, sweep, verify)  # fmt: skip
from qsplan.planner.cli.options import (
    EXIT_INTERRUPTED,
    EXIT_USAGE,
    Parser,
    UsageError,
    add_parallel_options,
    check_counts,
    cli_message,
    overwrite_message,
    parallel_options,
)

__all__ = ["COMMANDS", "EXIT_USAGE", "main", "build_parser", "add_parallel_options", "parallel_options"]

#: The subcommands, in the order of ``qsplan --help``.
COMMANDS = {"modes": modes, "count": count, "partition": partition, "paper": paper, "muspace": muspace,
            "band": band, "simulate": simulate, "sweep": sweep, "plan": plan, "demo": demo, "verify": verify,
            "hands": hands, "sample": sample, "check": check, "replay": replay}  # fmt: skip


class _VersionShown(Exception):
    """``--version`` was given: its line is the message (printed on stdout, exit 0)."""


class _Version(argparse.Action):
    def __init__(self, option_strings, dest, **kwargs):
        super().__init__(option_strings, dest, nargs=0, default=argparse.SUPPRESS,
                         help="print qsplan's version and exit")  # fmt: skip

    def __call__(self, parser, namespace, values, option_string=None):
        from qsplan import __version__

        raise _VersionShown(f"qsplan {__version__}")


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The ``qsplan`` parser; with ``command`` (a name of :data:`COMMANDS`), that subcommand's alone: what running it
    reads (its help, usage and errors the same), without building the others' (``qsplan modes`` then never imports
    the planner's options)."""
    p = Parser(prog="qsplan", description="Quasistatic planar contact-mode prediction (Trinkle & Zeng 1995).")
    p.add_argument("--version", action=_Version)
    sub = p.add_subparsers(dest="command", required=True, parser_class=Parser)
    for name, module in COMMANDS.items():
        if command is None or name == command:
            module.add_parser(sub)
    return p


def main(argv=None) -> int:
    """Entry point of the ``qsplan`` console script; returns the exit status.

    0: done; 1: ran, but the result failed a check; 2: bad input or no answer (one line on
    stderr); 130: interrupted (Ctrl-C, one line on stderr, no partial file).
    """
    try:
        return _dispatch(argv)
    except KeyboardInterrupt:
        _say("qsplan: interrupted")
        return EXIT_INTERRUPTED


def _say(message: str) -> None:
    """One line on stderr, whatever the message holds (newlines are folded: one error, one line)."""
    print(" | ".join(line.strip() for line in str(message).splitlines() if line.strip()), file=sys.stderr)


def _dispatch(argv) -> int:
    from qsplan.mechanics.errors import NoAnswerError, ParallelError, QsplanError

    flags = {}
    argv = sys.argv[1:] if argv is None else list(argv)
    try:
        args = build_parser(argv[0] if argv and argv[0] in COMMANDS else None).parse_args(argv)
        check_counts(args)
        module = COMMANDS[args.command]
        flags = getattr(module, "FLAGS", {})
        return module.run(args, sys.stdout)
    except _VersionShown as shown:
        print(shown, file=sys.stdout)
        return 0
    except UsageError as exc:
        _say(str(exc))
        return EXIT_USAGE
    except QsplanError as exc:
        from qsplan.planner.export.files import OutputExistsError  # loaded when needed: not by every command

        message = overwrite_message(exc) if isinstance(exc, OutputExistsError) else cli_message(str(exc), flags)
        _say(f"qsplan: error: {message}")
        return EXIT_USAGE
    except ParallelError as exc:  # the processes computing failed: say so in one line, exit 2
        _say(f"qsplan: error: {cli_message(str(exc), flags)}")
        return EXIT_USAGE
    except NoAnswerError as exc:
        path = getattr(exc, "report_path", None)
        _say(f"qsplan: error: {exc}" + (f" (report: {path})" if path else ""))
        return EXIT_USAGE
    except BrokenPipeError:
        return 0


if __name__ == "__main__":
    sys.exit(main())
