"""A plan as its table: the rows every export writes, one column family per quantity (issue 24: the plan's rows
belong to the plan; :mod:`qsplan.planner.export.plan_files` writes them as CSV and JSON, :meth:`qsplan.planner.plan.
results.Plan.sample` samples them at a controller's rate).

Columns (:data:`PLAN_COLUMNS`): ``t``; per joint ``q_<joint>``, ``qd_<joint>``, ``tau_<joint>`` and its band
``tau_<joint>_min`` / ``_max``; ``mode``, ``margin``, the workpiece pose, ``phase``, ``effort_joint``, per joint ``control_<joint>``, ``speed_scale``.  Units SI, a
joint's by its kind (rad, rad/s, N m; m, m/s, N).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["CONTROLS", "PLAN_COLUMNS", "column_family", "is_word_column", "plan_columns", "plan_joints", "row_control"]


#: Every column family of a plan file: ``(name, unit, meaning)``, ``<joint>`` standing for ``left`` and ``right``.
PLAN_COLUMNS = (
    ("t", "s", "time from the plan's start"),
    ("q_<joint>", "rad", "joint angle"),
    ("qd_<joint>", "rad/s", "velocity command while the joint is velocity-controlled; nan (null) while torque-controlled"),
    ("tau_<joint>", "N m", "torque command while the joint is torque-controlled, inside its guaranteed band; nan "
                           "(null) while velocity-controlled (every regrasp row, and the other finger in contact)"),
    ("tau_<joint>_min", "N m", "lower edge of the guaranteed band (-inf, JSON null: unbounded below); nan (null) "
                               "while velocity-controlled"),
    ("tau_<joint>_max", "N m", "upper edge of the guaranteed band (inf, JSON null: unbounded above); nan (null) "
                               "while velocity-controlled"),
    ("mode", None, "contact mode the command guarantees, one letter R, S or B per contact in the formation's order "
                   "(metadata.formation; all S = 4S); free on regrasp rows"),
    ("margin", "N m", "distance from the torque command to the nearer band edge, in the effort joint's unit (N for a "
                      "prismatic joint); nan (null) on regrasp rows"),
    ("x_workpiece", "m", "workpiece pose: x of its centre of mass"),
    ("y_workpiece", "m", "workpiece pose: y of its centre of mass"),
    ("theta_workpiece", "rad", "workpiece pose: orientation"),
    ("phase", None, "index of the phase, an integer (0, 1, 2, ...: segments and regrasps in time order); "
                    "metadata.phases[phase] names it"),
    ("effort_joint", None, "the torque-controlled finger (left, right); none on regrasp rows"),
    ("control_<joint>", None, "the joint's control at this row: torque (apply tau_<joint>, a force for a prismatic "
                              "joint), velocity (track q_<joint> with qd_<joint>) or hold (velocity-controlled at "
                              "rest: hold q_<joint>)"),
    ("speed_scale", None, "the time scaling at this row: the fraction of the phase's quasistatic speed commanded (0 at "
                          "rest: every phase starts and ends at rest; 1 cruising); between two rows it changes linearly "
                          "in time and every joint moves along the straight line between them in proportion to the "
                          "path (metadata.time_scaling)"),
)  # fmt: skip

#: A joint's control at a row (``control_<joint>``; the same words as :data:`qsplan.planner.plan.sampling.CONTROL_MODES`).
CONTROLS = ("velocity", "torque", "hold")


def is_word_column(name: str) -> bool:
    """Whether column ``name`` holds words (``mode``, ``effort_joint``, ``control_<joint>``), not numbers."""
    return name in ("mode", "effort_joint") or name.startswith("control_")


def row_control(effort: bool, qd: float) -> str:
    """``control_<joint>`` of a row: ``torque`` for its effort joint, else ``hold`` at rest (``qd`` 0), ``velocity``."""
    return "torque" if effort else ("hold" if qd == 0.0 else "velocity")

#: Characters a joint's name may hold to name columns (the schema's column pattern).
_NAME_CHARS = frozenset("abcdefghijklmnopqrstuvwxyz0123456789_")


def plan_joints(hand) -> tuple:
    """The joints a plan of ``hand`` has columns for, in the hand's order (:attr:`qsplan.hands.protocol.Hand.joint_names`).

    Raises
    ------
    QsplanError
        A joint whose name cannot name a column (lowercase letters, digits and underscores; not ``none``), or two
        joints whose columns would share a name.
    """
    from qsplan.mechanics.errors import QsplanError

    names = hand.joint_names
    for n in names:
        if not n or set(n) - _NAME_CHARS or n == "none":
            raise QsplanError(f"hand.joint_names: {n!r} cannot name a plan column; expected lowercase letters, digits "
                              "and underscores (and not 'none')")  # fmt: skip
    columns = [f"{c}_{n}{s}" for n in names for c, s in (("q", ""), ("qd", ""), ("tau", ""), ("tau", "_min"),
                                                         ("tau", "_max"), ("control", ""))]  # fmt: skip
    if len(set(columns)) != len(columns):
        raise QsplanError(f"hand.joint_names: {list(names)} give two columns of one name; rename a joint")
    return names


def column_family(name: str, joints=None) -> tuple:
    """``(the PLAN_COLUMNS entry of column name, its joint or None)``; ``joints``: the plan's joint names (default
    the paper's ``left`` and ``right``)."""
    for joint in sorted(joints or ("left", "right"), key=len, reverse=True):
        for head, tail in (("q", ""), ("qd", ""), ("tau", ""), ("tau", "_min"), ("tau", "_max"), ("control", "")):
            if name == f"{head}_{joint}{tail}":
                return next(c for c in PLAN_COLUMNS if c[0] == f"{head}_<joint>{tail}"), joint
    return next(c for c in PLAN_COLUMNS if c[0] == name), None


def plan_columns(plan) -> tuple:
    """The plan as ordered columns ``{name: list}`` and units ``{name: str or None}`` (:data:`PLAN_COLUMNS`).

    Reads the plan's public fields only (``phases``; a phase not ``in_contact`` (a
    :class:`~qsplan.planner.plan.results.RegraspPlan`) is a free motion of every joint); one group of
    columns per joint of ``plan.task.hand``, in its order, with its kind's units.
    """
    from qsplan.hands.protocol import JOINT_UNITS
    joints = plan_joints(plan.task.hand)
    kinds = dict(zip(joints, plan.task.hand.joint_kinds))
    order = ["t", *(f"q_{n}" for n in joints), *(f"qd_{n}" for n in joints)]
    for n in joints:
        order += [f"tau_{n}", f"tau_{n}_min", f"tau_{n}_max"]
    order += ["mode", "margin", "x_workpiece", "y_workpiece", "theta_workpiece", "phase", "effort_joint"]
    order += [f"control_{n}" for n in joints]  # after every earlier column: extended, never reordered
    order += ["speed_scale"]
    cols = {k: [] for k in order}
    y0 = plan.task.hand.rest_height
    for i, ph in enumerate(plan.phases):
        n = ph.t.size
        nan = [math.nan] * n
        cols["t"] += ph.t.tolist()
        for j, name in enumerate(joints):
            cols[f"q_{name}"] += ph.q[:, j].tolist()
            cols[f"qd_{name}"] += ph.qd[:, j].tolist()
        contact = ph.in_contact
        for name in joints:
            mine = contact and ph.effort_joint == name
            cols[f"tau_{name}"] += ph.command.tolist() if mine else nan
            cols[f"tau_{name}_min"] += ph.lower.tolist() if mine else nan
            cols[f"tau_{name}_max"] += ph.upper.tolist() if mine else nan
        cols["mode"] += list(ph.modes()) if contact else ["free"] * n
        cols["margin"] += ph.margin.tolist() if contact else nan
        pose = ph.poses(y0)
        cols["x_workpiece"] += pose[:, 0].tolist()
        cols["y_workpiece"] += pose[:, 1].tolist()
        cols["theta_workpiece"] += pose[:, 2].tolist()
        cols["phase"] += [i] * n
        cols["effort_joint"] += [ph.effort_joint if contact else "none"] * n
        for j, name in enumerate(joints):
            mine = contact and ph.effort_joint == name
            cols[f"control_{name}"] += [row_control(mine, float(v)) for v in ph.qd[:, j]]
        cols["speed_scale"] += (np.ones(n) if ph.speed_scale is None else ph.speed_scale).tolist()
    units = {}
    for k in order:
        (family, unit, _), joint = column_family(k, joints)
        units[k] = None if unit is None else (unit if joint is None else JOINT_UNITS[kinds[joint]][family.split("_")[0]])
    efforts = {kinds[e] for e in cols["effort_joint"] if e != "none"}
    if len(efforts) == 1:  # the margin is a distance in the effort joint's unit
        units["margin"] = JOINT_UNITS[efforts.pop()]["tau"]
    return cols, units
