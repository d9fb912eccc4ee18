"""What the plan certifier reads: an exported plan's columns and metadata, and the task its metadata records.

:func:`read_plan` reads a plan directory, ``plan.csv`` or ``plan.json``
(:func:`qsplan.planner.export.plan_files.export_plan`) and checks that every column of the hand's joints
is there (:func:`plan_columns_required`); :func:`task_from_metadata` rebuilds the task from ``plan.json``'s
task record (:mod:`qsplan.planner.task.record`).  Used by :mod:`qsplan.planner.certify.certify` and
``qsplan verify``.  Units SI.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from qsplan.mechanics import QsplanError
from qsplan.planner.plan.table import is_word_column

__all__ = ["MAX_PLAN_BYTES", "MAX_PLAN_ROWS", "plan_columns_required", "plan_file", "plan_sources", "read_plan",
           "read_plan_file", "task_from_metadata"]

#: Largest plan file read (bytes).  A plan row is under 1 kB in either format (a four-joint hand's CSV row is
#: ~400 bytes, its JSON ~600), so :data:`MAX_PLAN_ROWS` rows fit in 16 MiB; a bigger file is not a plan qsplan
#: wrote (a 60 MB file kept ``verify`` busy for half an hour before this bound).
MAX_PLAN_BYTES = 16 * 1024 * 1024

#: Most rows certified.  Certification costs ~20-60 ms per in-contact row (the all-modes solver at every
#: friction vector, the band recomputed), so 20,000 rows take at most ~20 minutes; the planner writes a row
#: per 0.5 mm of workpiece travel, and the bundled plans have 41 to 289 rows.
MAX_PLAN_ROWS = 20_000

#: Columns of a plan file besides the joints' (:func:`plan_columns_required`).
_POSE_COLUMNS = ("mode", "x_workpiece", "y_workpiece", "theta_workpiece", "effort_joint")


def plan_columns_required(joints) -> tuple:
    """The columns a plan file of a hand with joints ``joints`` must hold, in the export's order."""
    out = ["t", *(f"q_{n}" for n in joints), *(f"qd_{n}" for n in joints)]
    for n in joints:
        out += [f"tau_{n}", f"tau_{n}_min", f"tau_{n}_max"]
    return tuple(out) + _POSE_COLUMNS


def plan_sources(path) -> tuple:
    """The plan files to certify: a directory's ``plan.csv`` and ``plan.json`` (those present, CSV first), or the
    file named and the file of the other format beside it (same stem), when there is one.

    Raises
    ------
    QsplanError
        As :func:`plan_file`.
    """
    p = plan_file(path)
    other = p.with_suffix(".json" if p.suffix == ".csv" else ".csv")
    found = [p] + ([other] if other.is_file() else [])
    return tuple(sorted(found, key=lambda q: q.suffix != ".csv"))


def plan_file(path) -> Path:
    """The plan file ``path`` names: itself (a ``.csv`` or ``.json``), or a directory's ``plan.csv`` (else ``plan.json``)."""
    p = Path(path)
    if p.is_dir():
        for name in ("plan.csv", "plan.json"):
            if (p / name).is_file():
                return p / name
        raise QsplanError(f"plan: {str(p)!r} holds neither plan.csv nor plan.json")
    if not p.is_file():
        raise QsplanError(f"plan: no such file or directory: {str(p)!r}")
    if p.suffix not in (".csv", ".json"):
        raise QsplanError(f"plan: expected a plan directory, a .csv or a .json file; got {str(p)!r}")
    return p


def _bytes(p: Path) -> bytes:
    """The file's bytes, at most :data:`MAX_PLAN_BYTES` (else a QsplanError naming the bound)."""
    try:
        with open(p, "rb") as f:
            data = f.read(MAX_PLAN_BYTES + 1)
    except OSError as exc:
        raise QsplanError(f"plan: cannot read {str(p)!r} ({exc.strerror or exc})") from None
    if len(data) > MAX_PLAN_BYTES:
        raise QsplanError(f"plan: {str(p)!r} is larger than {MAX_PLAN_BYTES // 2**20} MiB "
                          f"(qsplan.planner.certify.inputs.MAX_PLAN_BYTES); not a plan qsplan wrote")  # fmt: skip
    return data


def _read_json(p: Path) -> tuple:
    try:
        doc = json.loads(_bytes(p).decode("utf-8"))
        data = doc["data"]
        if not isinstance(data, dict):
            raise TypeError("data is not an object")
        n = len(data["t"])
    except (UnicodeDecodeError, ValueError, KeyError, TypeError, RecursionError) as exc:
        if isinstance(exc, QsplanError):
            raise
        raise QsplanError(f"plan: {str(p)!r} is not a plan JSON file ({type(exc).__name__}: {exc})") from None
    _check_rows(p, n)
    if not isinstance(doc, dict):
        raise QsplanError(f"plan: {str(p)!r} is not a plan JSON file (not an object)")
    cols = {}
    for name, vals in data.items():
        if not isinstance(vals, list):
            raise QsplanError(f"plan: column {name!r} of {str(p)!r} is not a list of values")
        if is_word_column(name):
            cols[name] = np.array([str(v) for v in vals])
            continue
        fill = -math.inf if name.endswith("_min") else (math.inf if name.endswith("_max") else math.nan)
        try:
            cols[name] = np.array([math.nan if v is None else float(v) for v in vals], dtype=float)
        except (TypeError, ValueError):
            raise QsplanError(f"plan: column {name!r} of {str(p)!r} holds a value that is not a number") from None
        if cols[name].size != n:
            raise QsplanError(f"plan: column {name!r} has {cols[name].size} rows; expected {n}")
        if name.startswith("tau_") and not math.isnan(fill):  # a band edge: null is unbounded where it is the band
            null = np.array([v is None for v in vals])
            joint = name[4:-4]
            effort = np.array([str(v) for v in data.get("effort_joint", ())]) if "effort_joint" in data else None
            mine = null if effort is None or effort.size != n else null & (effort == joint)
            cols[name][mine] = fill
    return cols, doc


def _check_rows(p: Path, n: int) -> None:
    if n > MAX_PLAN_ROWS:
        raise QsplanError(f"plan: {str(p)!r} has {n} rows; at most {MAX_PLAN_ROWS} are certified "
                          "(qsplan.planner.certify.inputs.MAX_PLAN_ROWS)")  # fmt: skip


def _read_csv(p: Path) -> dict:
    """``{column: ndarray}`` of a plan CSV (:func:`qsplan.planner.export.plan_files.read_plan_csv`'s columns), size-checked."""
    import csv
    import io

    try:
        rows = list(csv.reader(io.StringIO(_bytes(p).decode("utf-8"), newline="")))
    except (UnicodeDecodeError, csv.Error) as exc:
        raise QsplanError(f"plan: {str(p)!r} is not a plan CSV file ({type(exc).__name__}: {exc})") from None
    if not rows:
        raise QsplanError(f"plan: {str(p)!r} is empty; expected a header and rows")
    head, body = rows[0], rows[1:]
    _check_rows(p, len(body))
    if len(set(head)) != len(head):
        raise QsplanError(f"plan: {str(p)!r} names a column twice in its header")
    short = next((i for i, r in enumerate(body) if len(r) != len(head)), None)
    if short is not None:
        raise QsplanError(f"plan: {str(p)!r} row {short} has {len(body[short])} cells; the header has {len(head)}")
    out = {}
    for j, name in enumerate(head):
        vals = [r[j] for r in body]
        if is_word_column(name):
            out[name] = np.array(vals)
            continue
        try:
            out[name] = np.array(vals, dtype=float)
        except ValueError:
            i = next(i for i, v in enumerate(vals) if not _is_number(v))
            raise QsplanError(f"plan: column {name!r} of {str(p)!r} row {i} holds {vals[i][:40]!r}, not a number") from None
    return out


def _is_number(text) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def read_plan_file(p) -> tuple:
    """``(columns {name: ndarray}, document dict or None)`` of one plan file (``.csv``: no document), within
    :data:`MAX_PLAN_BYTES` and :data:`MAX_PLAN_ROWS`; a JSON document's ``metadata`` is ``doc.get("metadata")``.

    Raises
    ------
    QsplanError
        Unreadable, too large, not a plan file of that format.
    """
    p = Path(p)
    if p.suffix == ".json":
        return _read_json(p)
    return _read_csv(p), None


def read_plan(path, joints=None) -> tuple:
    """Columns ``{name: ndarray}`` and the metadata (dict or None) of a plan directory, ``.csv`` or ``.json``.

    A directory is read from its ``plan.csv`` (else ``plan.json``); the metadata comes from
    ``plan.json`` beside it when there is one.  ``joints``: the names of the hand's joints whose columns must
    be present (:func:`plan_columns_required`); default those of the file's ``q_<joint>`` columns (the paper's
    ``left`` and ``right`` when it has none).

    Raises
    ------
    QsplanError
        Missing or unreadable file, a missing column, columns of different lengths.
    """
    p = plan_file(path)
    cols, doc = read_plan_file(p)
    if p.suffix != ".json":
        side = p.with_suffix(".json")
        doc = _read_json(side)[1] if side.is_file() else None
    meta = doc.get("metadata") if isinstance(doc, dict) else None
    if joints is None:
        joints = tuple(c[2:] for c in cols if c.startswith("q_")) or ("left", "right")
    missing = [c for c in plan_columns_required(joints) if c not in cols]
    if missing:
        raise QsplanError(f"plan: {str(p)!r} lacks the column(s) {', '.join(missing)}")
    if cols["t"].size == 0:
        raise QsplanError(f"plan: {str(p)!r} has no rows")
    return cols, meta


def task_from_metadata(meta, cols=None):
    """The :class:`~qsplan.planner.task.task.Task` a plan's ``plan.json`` metadata records: its task record
    (``metadata.task_record``, :mod:`qsplan.planner.task.record`), read as a task file is read (the one round trip).
    ``cols`` (the rows) is not needed: the record names the start, the goal or the waypoints.

    Raises
    ------
    QsplanError
        Naming ``metadata.task_record`` when the metadata holds no task record (a plan written before qsplan recorded
        its task) or a record that is not a task: then name the task file.
    """
    from qsplan.planner.task.task import task_from_record

    if not (isinstance(meta, dict) and "task_record" in meta):
        raise QsplanError("metadata.task_record: missing: the plan's metadata does not record its task (a plan "
                          "written before qsplan recorded its task); name the task file")  # fmt: skip
    try:
        return task_from_record(meta["task_record"])
    except QsplanError as exc:
        raise QsplanError(f"metadata.task_record: the task the plan records is not a task ({exc}); name the task "
                          "file") from None
