"""A task as a plain document and back: the one round trip that metadata and the certifier share (issue 22).

:func:`task_record` writes a :class:`~qsplan.planner.task.task.Task` as a task file's tables (the TOML form of
:mod:`qsplan.planner.task.task`, as a dict of plain numbers, strings and lists), and
:func:`qsplan.planner.task.task.task_from_record` reads it back: the same validation a task file gets, so a
record a user edited is checked as a file is.  ``plan.json`` stores the record under ``metadata.task_record``;
``qsplan verify`` without ``--task`` rebuilds the task from it, and with ``--task`` the certifier checks the
record against the named task, field by field.

The hand is written inline, as its description (:meth:`qsplan.hands.protocol.Hand.description_table`: palm,
fingers with their joints, links, limits and speeds) with the workpiece in the user's vertex numbering (re-centred
on its centre of mass, turned so that its palm edge is level; ``palm_edge`` names that edge), so that every
feature a ``[start]`` or ``[goal]`` names keeps its number.  The limits are the resolved ones (the hand's,
narrowed by the task's), per joint by name.  Units SI (m, kg, rad, s, N, N m).
"""

from __future__ import annotations

import numpy as np

__all__ = ["RECORD_VERSION", "hand_record", "task_record", "task_tables"]

#: The record's version (``metadata.task_record.version``): raised when a field changes meaning.
RECORD_VERSION = 1


def hand_record(hand) -> dict:
    """``[hand]`` of a task record: the description's table and the workpiece keys (see the module docstring)."""
    table = hand.description_table()
    user = np.asarray(hand.workpiece)[list(hand.vertex_of_user)]
    table.update(workpiece=user.tolist(), workpiece_mass=float(hand.workpiece_mass), mu=float(hand.mu),
                 palm_edge=int(hand.user_edges[0]))  # fmt: skip
    return table


def task_tables(task) -> dict:
    """Where the task starts and ends, as its file's ``[motion]``, ``[start]`` and ``[goal]`` tables say it (features
    ``"edge:K"``/``"vertex:K"``/``"inner"`` in the polygon's numbering as written; the goal's ``x``, ``theta`` and
    ``palm`` where it gives them; a hand with free joints: its ``[start]`` by joint name)."""

    def feature(f):
        return "inner" if f is None or f[0] == "inner" else f"{f[0]}:{f[1]}"

    out = {"motion": {"start_x": float(task.start_x)}}
    if task.goal is None:
        out["motion"]["waypoints"] = [float(v) for v in task.waypoints]
    else:
        goal = task.goal  # only the keys the goal gives: a goal without x stays one
        out["goal"] = {key: float(v) for key, v in (("x", goal.x), ("theta", goal.theta)) if v is not None}
        out["goal"].update({key: feature(f) for key, f in (("left", goal.left), ("right", goal.right),
                                                           ("palm", goal.palm)) if f})  # fmt: skip
    if task.hand.free_joints:  # a hand with free joints starts from them (by name); the others from features
        if task.start_joints is not None:
            out["start"] = {task.hand.joint_names[j]: float(task.start_joints[j]) for j in task.hand.free_joints}
    else:
        out["start"] = {side: feature(f) for side, f in zip(("left", "right"), task.start_features)}
    return out


def task_record(task) -> dict:
    """The task as a task file's tables (see the module docstring); :func:`qsplan.planner.task.task.task_from_record`
    reads it back to an equal task."""
    from qsplan.planner.task.dynamics import task_dynamics

    hand = task.hand
    limits = {n: [float(v) for v in task.joint_limits[j]] for j, n in enumerate(hand.joint_names)}
    limits["speed"] = {n: float(task.joint_speeds[j]) for j, n in enumerate(hand.joint_names)}
    limits["workpiece_speed"] = float(task.workpiece_speed)
    dyn = task_dynamics(task)
    limits["workpiece_acceleration"] = float(dyn.workpiece_acceleration)
    limits["acceleration"] = {n: float(dyn.joint_accelerations[j]) for j, n in enumerate(hand.joint_names)}
    if "revolute" in hand.joint_kinds:
        limits["release_acceleration"] = float(dyn.release_accelerations[list(hand.joint_kinds).index("revolute")])
    doc = {"version": RECORD_VERSION, "name": task.name, "formation": task.formation.name, "hand": hand_record(hand),
           **task_tables(task),
           "friction": {"range": [float(v) for v in task.mu_range], "shared": bool(task.shared_mu)},
           "controller": {"torque_resolution": float(task.torque_resolution),
                          "min_normal_force": float(task.force_margin.normal),
                          "min_coulomb_slack": float(task.force_margin.slack)},
           "limits": limits}  # fmt: skip
    if task.disturbance is not None and dyn.source == "task":  # the default box follows from the limits
        doc["controller"]["disturbance"] = {"lo": list(task.disturbance.lo), "hi": list(task.disturbance.hi)}
    return doc
