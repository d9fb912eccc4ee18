"""Export a whole two-finger plan: one torque schedule (CSV and JSON) for every phase, in time order.

The columns are those of :mod:`qsplan.planner.export.schedule` (the band issue's format), for
both joints since the effort-controlled finger changes between segments, then
extra columns (extended, never renamed)::

    t, q_left, q_right, qd_left, qd_right,
    tau_left, tau_left_min, tau_left_max, tau_right, tau_right_min, tau_right_max,
    mode, margin, x_workpiece, y_workpiece, theta_workpiece, phase, effort_joint

* in-contact rows: ``qd_<joint>`` is the velocity command of the velocity-controlled
  joint and ``nan`` for the effort-controlled one; ``tau_<joint>*`` are the command and
  guaranteed band of the effort-controlled joint and ``nan`` for the other; ``mode``
  is the contact mode (``SSSS``); ``effort_joint`` names the torque-controlled finger;
* regrasp rows: both joints velocity-controlled (``qd`` of both), every ``tau`` and
  ``margin`` ``nan``, ``mode`` ``free``, ``effort_joint`` ``none``;
* ``x_workpiece, y_workpiece, theta_workpiece`` (m, m, rad): the workpiece's pose, so
  the scene of any row can be rebuilt from the file alone;
* ``phase``: the index of the phase (0, 1, ...: segment, regrasp, segment, ...).

Times are continuous over the plan; a phase's last row and the next phase's first
row share a time (the switch).  Unbounded band sides are ``inf`` (CSV) / ``null``
(JSON), as in :mod:`qsplan.planner.export.schedule`.  Files are never overwritten without ``force``.
"""

from __future__ import annotations

import json
import math

import numpy as np


from qsplan.planner.export.files import atomic_write, check_out_dir, check_outputs, csv_cell, json_value
from qsplan.planner.export.schedule import FORMAT, VERSION

__all__ = ["PLAN_FORMAT", "plan_columns", "plan_metadata", "export_plan", "read_plan_csv"]

PLAN_FORMAT = FORMAT + ".plan"

_UNITS = {"t": "s", "q": "rad", "qd": "rad/s", "tau": "N m", "margin": "N m", "x_workpiece": "m", "y_workpiece": "m",
          "theta_workpiece": "rad", "mode": None, "phase": None, "effort_joint": None}  # fmt: skip


def plan_columns(plan) -> tuple:
    """The plan as ordered columns ``{name: list}`` and units ``{name: str or None}``."""
    from qsplan.planner.planning.results import ContactSegmentPlan

    names = ("left", "right")
    order = ["t", *(f"q_{n}" for n in names), *(f"qd_{n}" for n in names)]
    for n in names:
        order += [f"tau_{n}", f"tau_{n}_min", f"tau_{n}_max"]
    order += ["mode", "margin", "x_workpiece", "y_workpiece", "theta_workpiece", "phase", "effort_joint"]
    cols = {k: [] for k in order}
    y0 = plan.task.hand.rest_height
    for i, ph in enumerate(plan.phases):
        n = ph.t.size
        nan = [math.nan] * n
        cols["t"] += ph.t.tolist()
        for j, name in enumerate(names):
            cols[f"q_{name}"] += ph.q[:, j].tolist()
            cols[f"qd_{name}"] += ph.qd[:, j].tolist()
        contact = isinstance(ph, ContactSegmentPlan)
        for name in names:
            mine = contact and ph.effort_joint == name
            cols[f"tau_{name}"] += ph.command.tolist() if mine else nan
            cols[f"tau_{name}_min"] += ph.lower.tolist() if mine else nan
            cols[f"tau_{name}_max"] += ph.upper.tolist() if mine else nan
        cols["mode"] += [ph.mode if contact else "free"] * n
        cols["margin"] += ph.margin.tolist() if contact else nan
        cols["x_workpiece"] += ph.x.tolist() if contact else [ph.x] * n
        cols["y_workpiece"] += [y0] * n
        cols["theta_workpiece"] += [0.0] * n
        cols["phase"] += [float(i)] * n
        cols["effort_joint"] += [ph.effort_joint if contact else "none"] * n
    units = {}
    for k in order:
        units[k] = _UNITS.get(k, _UNITS.get(k.split("_")[0]))
    units["phase"] = None
    return cols, units


def plan_metadata(plan) -> dict:
    """What a controller engineer needs to trust the plan (all SI)."""
    from qsplan.planner.planning.results import ContactSegmentPlan

    task = plan.task
    h = task.hand
    name, t, w = plan.narrowest()
    phases = []
    for i, ph in enumerate(plan.phases):
        d = {"index": i, "name": ph.name, "t_start_s": float(ph.t[0]), "t_end_s": float(ph.t[-1]), "rows": int(ph.t.size)}
        if isinstance(ph, ContactSegmentPlan):
            k = int(np.argmin(ph.width))
            d.update(kind="contact", mode=ph.mode, effort_joint=ph.effort_joint, competitors_precluded=list(ph.competitors),
                     workpiece_speed_m_s=ph.speed, ompl_states=int(ph.x_path.size),
                     narrowest_band={"t_s": float(ph.t[k]), "width_N_m": _num(ph.width[k])})  # fmt: skip
        else:
            d.update(kind="regrasp", x_workpiece_m=ph.x)
        phases.append(d)
    return {
        "source": "qsplan: Trinkle & Zeng (1995), Section 5.2, Figs. 9-13; planned with OMPL",
        "task": task.name,
        "friction": {"range": list(task.mu_range), "model": "one coefficient shared by all contacts" if task.shared_mu
                     else "each contact's coefficient independently in the range"},
        "torque_resolution_N_m": task.torque_resolution,
        "force_margin": dict(task.force_margin.to_dict(),
                             meaning="inside every band, for every friction in the range, every loaded contact's "
                                     "normal force and every rolling contact's friction-cone slacks are at least "
                                     "these (eq. 28 made strict)"),
        "limits": {"joints_rad": task.joint_limits.tolist(), "joint_speed_rad_s": task.joint_speed,
                   "workpiece_speed_m_s": task.workpiece_speed},
        "narrowest_band": {"phase": name, "t_s": _num(t), "width_N_m": _num(w)},
        "planner": {"name": plan.options.planner, "seed": plan.options.seed, "seconds": plan.seconds,
                    "validity_checks": plan.validity_checks, "checks_per_second": _num(plan.checks_per_second)},
        "phases": phases,
        "hand": {"workpiece_vertices_m": h.workpiece.tolist(), "workpiece_mass_kg": h.workpiece_mass,
                 "finger_base_m": h.finger_base, "finger_length_m": h.finger_length, "finger_width_m": h.finger_width,
                 "finger_mass_kg": h.finger_mass, "palm_halfwidth_m": h.palm_halfwidth, "gravity_m_s2": h.gravity},
    }  # fmt: skip


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
    doc = {"format": PLAN_FORMAT, "version": VERSION, "columns": names, "units": units,
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
    """Read a plan CSV back: ``{column: ndarray}`` (floats; ``mode`` and ``effort_joint`` as str arrays)."""
    import csv

    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    head, body = rows[0], rows[1:]
    out = {}
    for j, name in enumerate(head):
        vals = [r[j] for r in body]
        out[name] = np.array(vals) if name in ("mode", "effort_joint") else np.array(vals, dtype=float)
    return out
