"""The ``qsplan`` command: one module per subcommand, each parsing its arguments, calling one library
function and printing. :func:`main` is the console script's entry point."""

from qsplan.planner.cli.main import main

__all__ = ["main"]
