"""Export a whole plan of any two-finger hand: one torque schedule (CSV and JSON) for every phase, in time order.

Format ``qsplan.torque_schedule.plan``, version 1: the columns of :mod:`qsplan.planner.export.schedule`
(the band issue's format) for every joint of the plan's hand, in the hand's joint order (the paper's
hand: ``left``, ``right``; a described hand: its joints, e.g. ``left_proximal``, ``left_distal``, ...),
since the torque-controlled joint may change between segments, then extra columns (extended, never
renamed).  Units per joint kind (:data:`qsplan.hands.protocol.JOINT_UNITS`): a revolute joint's
in rad, rad/s and N m as in the table; a prismatic joint's in m, m/s and N.  One row per sample, in
this order:

=====================  =======  ==============================================================================
column                 unit     meaning
=====================  =======  ==============================================================================
``t``                  s        time from the plan's start
``q_<joint>``          rad      joint angle (``q_left``, ``q_right``)
``qd_<joint>``         rad/s    velocity command while the joint is velocity-controlled; ``nan`` while it is
                                torque-controlled
``tau_<joint>``        N m      torque command while the joint is torque-controlled; ``nan`` while it is
                                velocity-controlled (every regrasp row, and the other finger in contact)
``tau_<joint>_min``    N m      lower edge of its guaranteed band (``-inf``: unbounded below); ``nan`` as above
``tau_<joint>_max``    N m      upper edge of its guaranteed band (``inf``: unbounded above); ``nan`` as above
``mode``               -        contact mode the command guarantees, one letter per contact in the formation's
                                order (``metadata.formation``; all S = 4S); ``free`` on regrasp rows
``margin``             N m      distance from the torque command to the nearer band edge; ``nan`` on regrasps
``x_workpiece``        m        workpiece pose: x of its centre of mass
``y_workpiece``        m        workpiece pose: y of its centre of mass
``theta_workpiece``    rad      workpiece pose: orientation
``phase``              -        index of the phase, an integer (0, 1, 2, ...: in-contact segments and regrasps
                                in time order); ``metadata.phases[phase]`` names and describes it
``effort_joint``       -        the torque-controlled joint (``left``, ``right``; a described hand's joint
                                name); ``none`` on regrasp rows
``control_<joint>``    -        the joint's control at the row: ``torque``, ``velocity`` or ``hold``
``speed_scale``        -        the time scaling: the fraction of the quasistatic speed commanded (0 at rest)
=====================  =======  ==============================================================================

Times are continuous over the plan; a phase's last row and the next phase's first row share a
time (the switch).  CSV numbers are full precision (``repr``), ``phase`` an integer.  JSON:
``{"format", "version", "columns", "units", "descriptions", "data", "metadata", "null"}``, with
non-finite numbers ``null`` (``tau_<joint>_min``: unbounded below, ``tau_<joint>_max``: unbounded
above, elsewhere not applicable); the schema is ``torque_schedule.schema.json`` beside this module
(:func:`qsplan.planner.export.schema.check_schedule_document`).  ``metadata`` records the task, the
friction model, limits, force margin, the command rule and each phase, the hand
(:meth:`qsplan.hands.protocol.Hand.metadata`: a described hand's description and workpiece, enough to
rebuild it) and the planned ``sequence`` when the plan has one.  Files are never overwritten without
``force``.
"""

from __future__ import annotations

import json
import math

import numpy as np

from qsplan.planner.export.files import atomic_write, check_out_dir, check_outputs, csv_cell, json_value
from qsplan.planner.export.schedule import FORMAT, VERSION
from qsplan.planner.plan.table import PLAN_COLUMNS, column_family, is_word_column, plan_columns, plan_joints
from qsplan.planner.task.dynamics import dynamics_metadata
from qsplan.planner.task.record import task_record, task_tables

#: ``metadata.time_scaling.rule``: how the rows are timed (:mod:`qsplan.planner.plan.timing`).
TIME_SCALING_RULE = ("every phase starts and ends at rest (speed_scale 0, every qd 0); a slide is one rest-to-rest "
                     "piece, a regrasp one per straight leg; between two rows the speed scale changes linearly in "
                     "time (constant acceleration) and every joint moves along the straight line between the rows in "
                     "proportion to the path covered; qd at a row is the quasistatic velocity times speed_scale")

__all__ = ["PLAN_COLUMNS", "PLAN_FORMAT", "column_meanings", "command_metadata", "contact_runs", "export_plan",
           "plan_columns", "plan_joints", "disturbance_metadata", "force_margin_metadata", "friction_metadata",
           "plan_metadata", "plan_metadata_limits", "plain_json", "read_plan_csv", "task_tables",
           "time_scaling_metadata"]

PLAN_FORMAT = FORMAT + ".plan"


def column_meanings(names, kinds=None) -> dict:
    """``{column: meaning}`` of a plan file's columns (:data:`PLAN_COLUMNS`; the joints read from the ``q_<joint>``
    columns); ``kinds``: ``{joint: "revolute" or "prismatic"}`` (default revolute), a prismatic joint's meanings
    speak of its position and force."""
    joints = [k[2:] for k in names if k.startswith("q_")]
    out = {}
    for k in names:
        (family, _, meaning), joint = column_family(k, joints)
        if joint is not None and (kinds or {}).get(joint) == "prismatic" and family != "control_<joint>":
            meaning = meaning.replace("joint angle", "joint position").replace("torque", "force")
        out[k] = meaning
    return out


def phase_contacts(ph) -> dict:
    """``contacts``: the names the mode letters of the phase's first row follow, in order; ``contact_sets``: each run
    of rows (first and last row index within the phase) with one contact list and mode (a pivot's first row judges
    the transition with the contact that lifts, the later rows without it)."""
    names = ph.row_contacts()
    return {"contacts": list(names[0]), "contact_sets": contact_runs(names, ph.modes())}


def contact_runs(names, modes) -> list:
    """``contact_sets``: each run of rows with one contact list (``names[k]``: the names row ``k``'s mode letters
    follow) and one mode (``modes[k]``), as ``{"rows": [first, last], "contacts", "mode"}`` (rows counted from 0)."""
    runs = []
    for k, (c, m) in enumerate(zip(names, modes)):
        if runs and runs[-1]["contacts"] == list(c) and runs[-1]["mode"] == m:
            runs[-1]["rows"][1] = k
        else:
            runs.append({"rows": [k, k], "contacts": list(c), "mode": m})
    return runs


def plan_metadata(plan) -> dict:
    """What a controller engineer needs to trust the plan (all SI).

    Reads ``Plan``'s public fields; ``sequence`` (the planned steps and the search's summary,
    :mod:`qsplan.planner.plan.steps`) is written under ``"sequence"`` when the plan has one.
    """
    from qsplan.planner.plan.results import ContactSegmentPlan

    task = plan.task
    name, t, w = plan.narrowest()
    phases = []
    for i, ph in enumerate(plan.phases):
        d = {"index": i, "name": ph.name, "t_start_s": float(ph.t[0]), "t_end_s": float(ph.t[-1]), "rows": int(ph.t.size)}
        if isinstance(ph, ContactSegmentPlan):
            k = int(np.argmin(ph.width))
            d.update(kind="contact", mode=ph.modes()[0], effort_joint=ph.effort_joint, competitors_precluded=list(ph.competitors),
                     workpiece_speed_m_s=ph.speed, ompl_states=int(ph.x_path.size),
                     narrowest_band={"t_s": float(ph.t[k]), "width_N_m": _num(ph.width[k])},
                     command={"margin_N_m": _num(np.min(ph.margin)), "half_narrowest_band_N_m": _num(0.5 * ph.width[k]),
                              "max_N_m": _num(np.max(ph.command)), "lower_edge_max_N_m": _num(np.max(ph.lower))})  # fmt: skip
            # the effort's unit: N m, or N for a prismatic joint (then its numbers under *_N_m are in N)
            d["effort_unit"] = _joint_units(task.hand)[ph.effort_joint]["tau"]
            d.update(phase_kind=ph.kind, formation=ph.formation, **phase_contacts(ph))
        else:
            d.update(kind="regrasp", x_workpiece_m=float(np.ravel(ph.x)[0]), **ph.free_metadata())
        if plan.timing:
            d["time_scaling"] = plan.timing[i].as_dict()
        phases.append(d)
    doc = {
        "source": "qsplan: Trinkle & Zeng (1995), Section 5.2, Figs. 9-13; planned with OMPL",
        "task": task.name,
        "friction": friction_metadata(task),
        "torque_resolution_N_m": task.torque_resolution,
        "force_margin": force_margin_metadata(task),
        "disturbance": disturbance_metadata(task),
        "command": command_metadata(task),
        "limits": plan_metadata_limits(task),
        "time_scaling": time_scaling_metadata(task),
        "task_tables": task_tables(task),
        "task_record": task_record(task),
        "narrowest_band": {"phase": name, "t_s": _num(t), "width_N_m": _num(w)},
        "formation": task.formation.as_dict(),
        "planner": {"name": plan.options.planner, "seed": plan.options.seed, "seconds": plan.seconds,
                    "route_search": plan.search.planner if plan.search is not None else "scripted",
                    "validity_checks": plan.validity_checks, "checks_per_second": _num(plan.checks_per_second)},
        "phases": phases,
        "hand": task.hand.metadata(),
    }  # fmt: skip
    if plan.sequence:
        from qsplan.planner.plan.steps import step_dicts

        doc["sequence"] = plain_json(step_dicts(plan.sequence))
    return doc


def _joint_units(hand) -> dict:
    """``{joint: {"q", "qd", "tau"} -> unit}`` (:data:`qsplan.hands.protocol.JOINT_UNITS`)."""
    from qsplan.hands.protocol import JOINT_UNITS

    return {n: JOINT_UNITS[k] for n, k in zip(hand.joint_names, hand.joint_kinds)}


def friction_metadata(task) -> dict:
    """``metadata.friction``: the task's friction range and model."""
    return {"range": list(task.mu_range), "model": "one coefficient shared by all contacts" if task.shared_mu
            else "each contact's coefficient independently in the range"}  # fmt: skip


def force_margin_metadata(task) -> dict:
    """``metadata.force_margin``: the task's force margin (N) and its meaning."""
    return dict(task.force_margin.to_dict(),
                meaning="inside every band, for every friction in the range, every loaded contact's normal force and "
                        "every rolling contact's friction-cone slacks are at least these (eq. 28 made strict)")  # fmt: skip


def command_metadata(task) -> dict:
    """``metadata.command``: the command rule in words and numbers (:mod:`qsplan.planner.torque.command`)."""
    from qsplan.planner.torque.command import MAX_MARGIN_RESOLUTIONS

    return {"rule": "per in-contact segment one margin m kept from both band edges at every row: lower + m where the "
                    "band is wider than 2 m, the midpoint where it is narrower; m = min(half the segment's narrowest "
                    "band, max_margin_resolutions x torque_resolution_N_m); each phase records its m "
                    "(command.margin_N_m)",
            "max_margin_resolutions": MAX_MARGIN_RESOLUTIONS, "torque_resolution_N_m": task.torque_resolution,
            "velocity_controlled_torque_cells": "nan in CSV, null in JSON"}  # fmt: skip


def time_scaling_metadata(task) -> dict:
    """``metadata.time_scaling``: the task's acceleration limits, the inertial load and the rule the rows are timed by."""
    return dict(dynamics_metadata(task), rule=TIME_SCALING_RULE)


def disturbance_metadata(task) -> dict | None:
    """``metadata.disturbance``: the task's box of external wrenches (N, N, N m) and its meaning; None: none."""
    if task.disturbance is None:
        return None
    return dict(task.disturbance.to_dict(),
                meaning="every band holds its mode, and precludes every competitor, for every external wrench on the "
                        "workpiece in this box (about the world origin, added to its weight) as well as every friction "
                        "in the range")  # fmt: skip


def plan_metadata_limits(task) -> dict:
    """The task's limits as ``metadata.limits`` records them, the same keys for every hand: per joint by name
    (``joints``: range, speed and their units) and the workpiece's speed; a hand of revolute joints only also as the
    paper's hand always recorded them (``joints_rad``; ``joint_speed_rad_s``, the slowest joint's, the one speed of
    the paper hand's planner; ``joint_speeds_rad_s`` per joint)."""
    units = _joint_units(task.hand)
    speeds = np.asarray(task.joint_speeds, dtype=float)
    joints = {n: {"range": [float(v) for v in task.joint_limits[j]], "unit": units[n]["q"], "speed": float(speeds[j]),
                  "speed_unit": units[n]["qd"]} for j, n in enumerate(units)}  # fmt: skip
    out = {"joints": joints, "workpiece_speed_m_s": task.workpiece_speed}
    if all(k == "revolute" for k in task.hand.joint_kinds):
        out = {"joints_rad": task.joint_limits.tolist(), "joint_speed_rad_s": task.joint_speed,
               "joint_speeds_rad_s": [float(v) for v in speeds], **out}
    return out


def plain_json(value):
    """``value`` as plain JSON: numpy scalars and arrays, tuples and sets as numbers and lists; non-finite
    floats ``None``; other objects as their ``str``."""
    if isinstance(value, dict):
        return {str(k): plain_json(v) for k, v in value.items()}
    if isinstance(value, (list, tuple, set, frozenset, np.ndarray)):
        return [plain_json(v) for v in (sorted(value, key=str) if isinstance(value, (set, frozenset)) else value)]
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        return json_value(float(value))
    if value is None or isinstance(value, str):
        return value
    return str(value)


def _num(v):
    return float(v) if v is not None and math.isfinite(v) else None


def export_plan(plan, out_dir, stem: str = "plan", force: bool = False) -> list:
    """Write ``<stem>.csv`` and ``<stem>.json`` into ``out_dir`` (checked before writing); returns the paths."""
    import csv

    out = check_out_dir(out_dir)
    paths = [out / f"{stem}.csv", out / f"{stem}.json"]
    check_outputs(paths, force)
    cols, units = plan_columns(plan)
    names = list(cols)
    kinds = dict(zip(plan.task.hand.joint_names, plan.task.hand.joint_kinds))
    doc = {"format": PLAN_FORMAT, "version": VERSION, "columns": names, "units": units,
           "descriptions": column_meanings(names, kinds),
           "data": {k: [json_value(v) for v in vals] for k, vals in cols.items()}, "metadata": plan_metadata(plan),
           "null": "tau_<joint>_min: unbounded below; tau_<joint>_max: unbounded above; elsewhere: not applicable "
                   "(the joint is velocity-controlled, or a regrasp row)"}  # fmt: skip
    text = json.dumps(doc, indent=1, allow_nan=False) + "\n"  # before writing anything: no half-written files
    def write_csv(f):
        w = csv.writer(f, lineterminator="\n")
        w.writerow(names)
        for row in zip(*(cols[n] for n in names)):
            w.writerow([csv_cell(v) for v in row])

    atomic_write(paths[0], write_csv, force=True)
    atomic_write(paths[1], text, force=True)
    return paths


def read_plan_csv(path) -> dict:
    """Read a plan CSV back: ``{column: ndarray}`` (floats; ``mode`` and ``effort_joint`` as str arrays).

    ``phase`` (an integer since issue 16; ``0.0``, ``1.0``, ... in older files) is read as floats like
    the other numbers, so files of either kind read alike.
    """
    import csv

    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    head, body = rows[0], rows[1:]
    out = {}
    for j, name in enumerate(head):
        vals = [r[j] for r in body]
        out[name] = np.array(vals) if is_word_column(name) else np.array(vals, dtype=float)
    return out
