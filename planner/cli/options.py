"""What every ``qsplan`` subcommand shares: the parser that fails in one line, common options, translation.

* :class:`Parser` raises :class:`UsageError` (one line, exit :data:`EXIT_USAGE`) instead of printing usage;
* :func:`add_parallel_options` / :func:`parallel_options`: ``--workers`` and ``--scheduler``;
* :func:`add_plan_options`: the options of ``qsplan plan`` and ``qsplan demo``;
* :func:`overwrite_message`: the CLI's message when the library's overwrite check
  (:func:`qsplan.planner.export.files.check_outputs`) refuses;
* :func:`cli_message`: library messages name library fields (``out_dir``, ``force=True``); the CLI
  names its options (``--out``, ``--force``);
* :data:`COUNT_RANGES` / :func:`check_counts`: every integer option of every subcommand bounded
  (``--verify 99999999999999999999`` hung the planner), checked once after parsing.
"""

from __future__ import annotations

import argparse

__all__ = [
    "COUNT_RANGES",
    "EXIT_FAILED",
    "EXIT_INTERRUPTED",
    "EXIT_USAGE",
    "FLAGS",
    "Parser",
    "UsageError",
    "add_parallel_options",
    "add_plan_options",
    "check_counts",
    "cli_message",
    "overwrite_message",
    "parallel_options",
]

#: Exit status of bad input, and of valid input without an answer (no plan, no band).
EXIT_USAGE = 2

#: Exit status when the command ran but its result failed a check (a re-simulated plan left its modes).
EXIT_FAILED = 1

#: Exit status after Ctrl-C (128 + SIGINT, the shell's convention).
EXIT_INTERRUPTED = 130

#: Range ``(lo, hi, what)`` of every integer option, by its ``dest``; outside it the value is refused
#: in one line before any work.  The bounds keep every run finite and in memory:
#:
#: * ``verify``: each re-simulation of a plan takes about a second; 1000 is a quarter of an hour;
#: * ``n``: ``muspace``'s 4096^2 grid points stay within a few seconds and ~1 GB; ``paper`` computes
#:   nine slices and three figures, so its grid stops at 1024 (keys ``"<command>.<dest>"`` override);
#: * ``samples``, ``paper_samples``, ``random``: instants or friction vectors, each a solve;
#: * ``seed``: OMPL and numpy take unsigned 32-bit seeds;
#: * ``workers``: local processes; more than 1024 exceeds any machine's cores and process limits;
#: * ``contacts``, ``dof`` (``count``): eq. 49's sum at 1000 contacts already has 478 digits;
#: * ``max_switches``: mode switches of one simulated motion.
COUNT_RANGES = {
    "verify": (0, 1000, "re-simulations of the plan"),
    "n": (2, 4096, "grid points per axis"),
    "paper.n": (2, 1024, "grid points per axis"),
    "samples": (2, 100_000, "instants along the segment"),
    "paper_samples": (1, 10_000, "friction samples"),
    "random": (0, 100_000, "random friction vectors per row"),
    "seed": (0, 2**32 - 1, "a random seed"),
    "workers": (1, 1024, "local processes (1 runs in-process)"),
    "contacts": (0, 1000, "contacts"),
    "dof": (0, 1003, "3 + effort-controlled joints"),
    "max_switches": (0, 1_000_000, "mode switches"),
}

#: Library field names and the options that set them, to translate library messages.
FLAGS = {"out_dir": "--out", "workers": "--workers", "scheduler": "--scheduler"}


class UsageError(Exception):
    """Bad command line: the message is printed as it is, exit :data:`EXIT_USAGE`."""


class Parser(argparse.ArgumentParser):
    """argparse that reports errors in one line (no usage dump) and exits 2."""

    def error(self, message):  # noqa: D102
        raise UsageError(f"{self.prog}: {message}")


def cli_message(message: str, flags: dict | None = None) -> str:
    """A library message with its field names as the command's options (``out_dir:`` -> ``--out:``)."""
    table = {**FLAGS, **(flags or {})}
    field, sep, rest = message.partition(":")
    if sep and field in table:
        message = table[field] + ":" + rest
    return message.replace("pass force=True", "pass --force")


def check_counts(args) -> None:
    """Every integer option in ``args`` inside its :data:`COUNT_RANGES` entry.

    Raises
    ------
    UsageError
        ``"qsplan: error: --verify: expected 0..1000 (re-simulations of the plan); got 99999999999999999999"``.
    """
    command = getattr(args, "command", None)
    for dest in sorted({key.rpartition(".")[2] for key in COUNT_RANGES}):
        lo, hi, what = COUNT_RANGES.get(f"{command}.{dest}", COUNT_RANGES.get(dest, (None, None, None)))
        value = getattr(args, dest, None)
        if lo is None:
            continue
        if isinstance(value, int) and not isinstance(value, bool) and not lo <= value <= hi:
            shown = str(value) if abs(value) < 10**30 else f"an integer of {len(str(abs(value)))} digits"
            expected = f"a nonnegative integer, at most {hi}" if lo == 0 and value < 0 else f"{lo}..{hi}"
            raise UsageError(f"qsplan: error: --{dest.replace('_', '-')}: expected {expected} ({what}); got {shown}")


def add_parallel_options(p):
    """``--workers N`` and ``--scheduler ADDRESS`` (see :func:`qsplan.mechanics.map_chunks`)."""
    p.add_argument("--workers", type=int, metavar="N",
                   help="local processes for independent chunks (default: all cores; 1: in-process)")  # fmt: skip
    p.add_argument("--scheduler", metavar="ADDRESS",
                   help="run the chunks on a Dask cluster, e.g. tcp://host:8786 (needs qsplan[cluster])")  # fmt: skip


def parallel_options(args) -> dict:
    """``{"workers": ..., "scheduler": ...}`` from :func:`add_parallel_options`'s arguments, checked."""
    from qsplan.mechanics.errors import QsplanError

    if args.workers is not None and args.workers < 1:
        raise QsplanError(f"--workers: expected a positive number of processes (1 runs in-process); got {args.workers}")
    return {"workers": args.workers, "scheduler": args.scheduler}


def add_plan_options(p, default_out):
    """The options of ``qsplan plan`` and ``qsplan demo``."""
    from qsplan.planner.search.ompl_bridge import PLANNERS

    p.add_argument("--out", default=default_out, metavar="DIR", help=f"output directory (default {default_out})")
    p.add_argument("--seed", type=int, default=1, metavar="S", help="OMPL's random seed (default 1)")
    p.add_argument("--planner", choices=PLANNERS, default="RRTConnect",
                   help="OMPL planner of the regrasps' finger motions (default RRTConnect)")  # fmt: skip
    p.add_argument("--sequence-planner", choices=("widest", "RRTstar", "BITstar"), default="widest",
                   help="tasks with a [goal]: the search of the sequence of slides and regrasps in OMPL (default widest: "
                        "exact on the band tables; RRTstar, BITstar: OMPL's sampling planners, minimax objective)")  # fmt: skip
    p.add_argument("--time-limit", type=float, default=None, metavar="SECONDS",
                   help="time limit of each OMPL query (default 120; the iteration budget decides first)")
    p.add_argument("--force", action="store_true",
                   help="replace existing outputs in DIR (never an input, never through a symbolic link)")  # fmt: skip
    p.add_argument("--quiet", action="store_true", help="no progress lines on stderr")
    plots = p.add_mutually_exclusive_group()
    plots.add_argument("--plots", choices=("card", "all", "none"), default="card",
                       help="card (default): the plan card; all: also the bands, the mode timeline, the hand snapshots "
                            "and the animation; none: as --no-plots")  # fmt: skip
    plots.add_argument("--no-plots", action="store_true", help="write the torque trajectory only")
    p.add_argument("--verify", type=int, default=3, metavar="N",
                   help="re-simulate the exported plan at N friction vectors from the interval (the two uniform "
                        "extremes, then seeded random ones; 0: skip; default 3)")  # fmt: skip


def overwrite_message(exc) -> str:
    """The CLI's message for a :class:`qsplan.planner.export.files.OutputExistsError`."""
    return f"--out: {exc.path!r} exists ({exc.count} of the output files do); pass --force to overwrite or choose another --out"
