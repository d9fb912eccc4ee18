"""Writing output files safely: the one overwrite check, and the cell formats shared by the exports.

A controller file silently replaced is worse than an error: every writer in qsplan (the
schedule and plan exports, the plan pipeline, the CLI) checks its outputs with
:func:`check_outputs` before writing anything.  Messages name the library's fields
(``out_dir``, ``force``); the CLI translates them into its options.
"""

from __future__ import annotations

import math
from pathlib import Path

from qsplan.mechanics.errors import QsplanError

__all__ = ["OutputExistsError", "check_out_dir", "check_outputs", "csv_cell", "json_value"]


class OutputExistsError(QsplanError):
    """An output file exists and overwriting was not asked for.

    Attributes
    ----------
    path : str
        The first existing file.
    count : int
        How many of the outputs exist.
    """

    def __init__(self, path, count: int, message: str):
        super().__init__(message)
        self.path = str(path)
        self.count = int(count)


def check_out_dir(out_dir) -> Path:
    """``out_dir`` as a Path; raises :class:`QsplanError` when it is an existing file."""
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise QsplanError(f"out_dir: {str(out)!r} is a file; expected a directory")
    return out


def check_outputs(paths, force: bool = False) -> None:
    """Refuse to overwrite: raise :class:`OutputExistsError` if any of ``paths`` exists (unless ``force``).

    Also refuses (always) a path that is an existing directory.  Nothing is written.
    """
    paths = [Path(p) for p in paths]
    for p in paths:
        if p.is_dir():
            raise QsplanError(f"out_dir: {str(p)!r} is a directory; cannot write the file there")
    clash = [p for p in paths if p.exists()]
    if clash and not force:
        message = f"out_dir: {str(clash[0])!r} exists; pass force=True to overwrite it or choose another directory"
        if len(clash) > 1:
            message += f" ({len(clash)} of the {len(paths)} output files exist)"
        raise OutputExistsError(clash[0], len(clash), message)


def csv_cell(v) -> str:
    """A CSV cell: strings as they are, numbers in full precision (``repr``; ``inf``, ``nan``)."""
    if isinstance(v, str):
        return v
    return repr(float(v))


def json_value(v):
    """JSON has no infinity or NaN: non-finite floats become ``None`` (``null``)."""
    if isinstance(v, float) and not math.isfinite(v):
        return None
    return v
