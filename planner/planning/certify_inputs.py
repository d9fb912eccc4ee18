"""What the plan certifier reads: an exported plan's columns and metadata, and the task its metadata records.

:func:`read_plan` reads a plan directory, ``plan.csv`` or ``plan.json``
(:func:`qsplan.planner.export.plan_files.export_plan`) and checks that every column of the hand's joints
is there (:func:`plan_columns_required`); :func:`task_from_metadata` rebuilds the task from ``plan.json``'s
metadata: the paper's hand from its parameters, a described chain hand from its description and workpiece
(:func:`qsplan.hands.interface.hand_from_metadata`).  Used by :mod:`qsplan.planner.planning.certify` and
``qsplan verify``.  Units SI.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from qsplan.mechanics import QsplanError

__all__ = ["plan_columns_required", "plan_file", "read_plan", "task_from_metadata"]

#: Columns of a plan file besides the joints' (:func:`plan_columns_required`).
_POSE_COLUMNS = ("mode", "x_workpiece", "y_workpiece", "theta_workpiece", "effort_joint")


def plan_columns_required(joints) -> tuple:
    """The columns a plan file of a hand with joints ``joints`` must hold, in the export's order."""
    out = ["t", *(f"q_{n}" for n in joints), *(f"qd_{n}" for n in joints)]
    for n in joints:
        out += [f"tau_{n}", f"tau_{n}_min", f"tau_{n}_max"]
    return tuple(out) + _POSE_COLUMNS


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


def _read_json(p: Path) -> tuple:
    try:
        doc = json.loads(p.read_text(encoding="utf-8"))
        data = doc["data"]
        n = len(data["t"])
    except (OSError, UnicodeDecodeError, ValueError, KeyError, TypeError, RecursionError) as exc:
        raise QsplanError(f"plan: {str(p)!r} is not a plan JSON file ({type(exc).__name__}: {exc})") from None
    cols = {}
    for name, vals in data.items():
        if name in ("mode", "effort_joint"):
            cols[name] = np.array([str(v) for v in vals])
            continue
        fill = -math.inf if name.endswith("_min") else (math.inf if name.endswith("_max") else math.nan)
        try:
            cols[name] = np.array([fill if v is None else float(v) for v in vals], dtype=float)
        except (TypeError, ValueError):
            raise QsplanError(f"plan: column {name!r} of {str(p)!r} holds a value that is not a number") from None
        if cols[name].size != n:
            raise QsplanError(f"plan: column {name!r} has {cols[name].size} rows; expected {n}")
    return cols, doc.get("metadata") if isinstance(doc, dict) else None


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
    if p.suffix == ".json":
        cols, meta = _read_json(p)
    else:
        from qsplan.planner.export.plan_files import read_plan_csv

        try:
            cols = read_plan_csv(p)
        except (OSError, UnicodeDecodeError, ValueError, IndexError) as exc:
            raise QsplanError(f"plan: {str(p)!r} is not a plan CSV file ({type(exc).__name__}: {exc})") from None
        side = p.with_suffix(".json")
        meta = _read_json(side)[1] if side.is_file() else None
    if joints is None:
        joints = tuple(c[2:] for c in cols if c.startswith("q_")) or ("left", "right")
    missing = [c for c in plan_columns_required(joints) if c not in cols]
    if missing:
        raise QsplanError(f"plan: {str(p)!r} lacks the column(s) {', '.join(missing)}")
    if cols["t"].size == 0:
        raise QsplanError(f"plan: {str(p)!r} has no rows")
    return cols, meta


def task_from_metadata(meta, cols=None):
    """The :class:`~qsplan.planner.planning.task.Task` a plan's ``plan.json`` metadata records.

    The metadata records the hand (the paper's hand by its parameters, but not its palm thickness: the default
    is used; a described hand by its description and workpiece, fully), the friction set, the limits and the
    torque resolution; the start and the waypoints are read from the rows (``cols``) when given.

    Raises
    ------
    QsplanError
        Naming ``task`` when the metadata does not record the task.
    """
    from qsplan.planner.planning.task import make_task

    if isinstance(meta, dict) and isinstance(meta.get("hand"), dict) and "description" in meta["hand"]:
        return _chain_task_from_metadata(meta, cols)
    try:
        h, lim = meta["hand"], meta["limits"]
        hand = {"workpiece": h["workpiece_vertices_m"], "workpiece_mass": h["workpiece_mass_kg"],
                "finger_base": h["finger_base_m"], "finger_length": h["finger_length_m"],
                "finger_width": h["finger_width_m"], "finger_mass": h["finger_mass_kg"],
                "palm_halfwidth": h["palm_halfwidth_m"], "gravity": h["gravity_m_s2"]}  # fmt: skip
        friction = meta["friction"]
        shared = "shared" in friction["model"]
        start, waypoints = (0.0, [1.0]) if cols is None else _rows_motion(cols)
        fm = meta.get("force_margin")  # recorded since force margins exist; older plans: the default
        margin = None if fm is None else (fm["min_normal_force_N"], fm["min_coulomb_slack_N"])
        return make_task(hand, start, waypoints, friction["range"], meta["torque_resolution_N_m"], shared,
                         lim["joints_rad"], lim["joint_speed_rad_s"], lim["workpiece_speed_m_s"],
                         name=meta.get("task", "task"), force_margin=margin)  # fmt: skip
    except (KeyError, TypeError) as exc:
        raise QsplanError(f"task: the plan's metadata does not record the task ({exc}); name the task file") from None


def _rows_motion(cols) -> tuple:
    """``(start x, [x at the end of each in-contact stretch])`` (m) of a plan's rows."""
    x, contact = cols["x_workpiece"], cols["mode"] != "free"
    ends = [i for i in range(x.size) if contact[i] and (i + 1 == x.size or not contact[i + 1])]
    return float(x[0]), [float(x[i]) for i in ends]


def _chain_task_from_metadata(meta, cols):
    """:func:`task_from_metadata` of a described hand's plan (its description and workpiece, :func:`qsplan.hands.
    interface.hand_from_metadata`; the joint limits by joint name; its joint speeds are the description's)."""
    from qsplan.hands.interface import hand_from_metadata, joint_names
    from qsplan.planner.planning.task import make_task

    hand = hand_from_metadata(meta["hand"])
    try:
        lim = meta["limits"]
        joints = lim["joints"]
        limits = [joints[n]["range"] for n in joint_names(hand)]
        friction = meta["friction"]
        start, waypoints = _rows_motion(cols) if cols is not None else (0.0, [1.0])
        fm = meta.get("force_margin")
        margin = None if fm is None else (fm["min_normal_force_N"], fm["min_coulomb_slack_N"])
        return make_task(hand, start, waypoints, friction["range"], meta["torque_resolution_N_m"],
                         "shared" in friction["model"], limits, workpiece_speed=lim["workpiece_speed_m_s"],
                         name=meta.get("task", "task"), force_margin=margin)  # fmt: skip
    except (KeyError, TypeError) as exc:
        raise QsplanError(f"task: the plan's metadata does not record the task ({exc}); name the task file") from None
