"""Controller-rate samples of an exported plan (issue 24, item 3): the plan files read, sampled by the one rule of
:mod:`qsplan.planner.plan.sampling` (:func:`~qsplan.planner.plan.sampling.sample_columns`), and written as the CSV
of ``qsplan sample`` (:func:`write_samples`: ``#`` comment lines first, the format, units and rule).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from qsplan.mechanics.errors import QsplanError
from qsplan.planner.plan.table import is_word_column
from qsplan.planner.plan.sampling import (CONTROL_MODES, MAX_TICKS, TIME_SNAP, PlanSamples, sample_columns,
                                          tick_times)  # fmt: skip

__all__ = ["CONTROL_MODES", "MAX_TICKS", "SAMPLES_FORMAT", "TIME_SNAP", "PlanSamples", "plan_table", "sample_plan",
           "tick_times", "write_samples"]

#: The CSV's format name (its first comment line) and version.
SAMPLES_FORMAT = "qsplan.samples"
_VERSION = 1

def plan_table(plan) -> tuple:
    """``(columns {name: ndarray}, units {name: str} or None)`` of a plan given as a directory (its ``plan.csv``,
    else ``plan.json``), a ``.csv`` (:func:`~qsplan.planner.export.plan_files.read_plan_csv`; units from the
    ``.json`` beside it) or ``.json`` file, a mapping of columns, or a planned :class:`~qsplan.planner.plan.
    results.Plan` (:func:`~qsplan.planner.export.plan_files.plan_columns`).

    Raises
    ------
    QsplanError
        Naming ``plan``: no such file, or not a plan file.
    """
    from qsplan.planner.export.plan_files import read_plan_csv
    from qsplan.planner.plan.table import plan_columns

    if hasattr(plan, "phases") and hasattr(plan, "task"):
        cols, units = plan_columns(plan)
        return {k: np.asarray(v) for k, v in cols.items()}, units
    if isinstance(plan, dict):
        return {k: np.asarray(v) for k, v in plan.items()}, None
    p = Path(plan)
    if p.is_dir():
        p = p / "plan.csv" if (p / "plan.csv").is_file() else p / "plan.json"
    if not p.is_file() or p.suffix not in (".csv", ".json"):
        raise QsplanError(f"plan: {str(plan)!r} is no plan directory, plan .csv or .json file")
    side = p.with_suffix(".json")
    try:
        doc = _json_doc(side) if p.suffix == ".csv" else json.loads(p.read_text())
        if p.suffix == ".json":
            data = doc["data"]
            cols = {k: np.array(v) if is_word_column(k) else np.array([np.nan if x is None else x for x in v], float)
                    for k, v in data.items()}  # fmt: skip
        else:
            cols = read_plan_csv(p)
    except (OSError, UnicodeDecodeError, ValueError, KeyError, TypeError, IndexError) as exc:
        raise QsplanError(f"plan: {str(p)!r} is not a readable plan file ({type(exc).__name__}: {exc})") from None
    units = doc.get("units") if isinstance(doc, dict) and isinstance(doc.get("units"), dict) else None
    return cols, units


def _json_doc(path):
    """The JSON document at ``path`` beside a CSV (for its units), or None when absent or unreadable."""
    try:
        return json.loads(path.read_text()) if path.is_file() else None
    except (OSError, UnicodeDecodeError, ValueError):
        return None


def sample_plan(plan, times) -> PlanSamples:
    """Each tick's control mode and command per joint (the rule: :mod:`qsplan.planner.plan.sampling`) of ``plan``: a
    plan directory or file, its columns, or a planned plan (:func:`plan_table`); ``times`` (s) strictly increasing,
    within the plan.

    Raises
    ------
    QsplanError
        Naming ``plan`` or ``times`` (:func:`~qsplan.planner.plan.sampling.sample_columns`).
    """
    return sample_columns(*plan_table(plan), times)


def _cell(v) -> str:
    """A CSV cell: words as they are, integers as integers, floats in full precision, ``nan`` empty."""
    if isinstance(v, str):
        return v
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    return "" if np.isnan(v) else repr(float(v))


def write_samples(samples: PlanSamples, target, source: str = "", force: bool = False):
    """Write the samples as CSV to ``target`` (a path, written atomically and never overwritten without ``force``, or
    an open text file such as stdout); returns the path, or None for a file object.

    The CSV starts with ``#`` lines: the format (:data:`SAMPLES_FORMAT`) and ``source``, the units of every
    column, the control modes and the tick rule; then the header line and one row per tick (empty cells: not
    commanded).
    """
    import csv

    from qsplan.planner.export.files import atomic_write, check_outputs

    cols = samples.columns()
    names = list(cols)
    units = samples.units()
    head = [f"# {SAMPLES_FORMAT} {_VERSION}: controller-rate samples" + (f" of {source}" if source else ""),
            "# units: " + "; ".join(f"{k} {u}" for k, u in units.items() if u),
            "# control_<joint>: velocity (track q and qd), torque (apply tau), hold (hold q, qd = 0); empty cells: "
            "not commanded",
            "# rule: q and tau linear between the rows of a phase; qd the rate of q over the tick; a tick at a "
            "switch takes the new phase (qsplan.planner.export.sample)"]  # fmt: skip

    def write(f):
        for line in head:
            f.write(line + "\n")
        w = csv.writer(f, lineterminator="\n")
        w.writerow(names)
        for row in zip(*(cols[k].tolist() for k in names)):
            w.writerow([_cell(v) for v in row])

    if hasattr(target, "write"):
        write(target)
        return None
    path = Path(target)
    check_outputs([path], force)
    return atomic_write(path, write, force=True)
