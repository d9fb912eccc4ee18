"""Export a segment's torque schedule for a robot controller: CSV, and the same as JSON with units and metadata.

One row per sample of the segment, columns in this order:

=====================  =======  ======================================================================
column                 unit     meaning
=====================  =======  ======================================================================
``t``                  s        time from the segment's start
``q_<joint>``          rad      every joint's angle (m for a prismatic joint)
``qd_<joint>``         rad/s    velocity command of each velocity-controlled joint
``tau_<joint>``        N m      torque command of each effort-controlled joint (N: prismatic)
``tau_<joint>_min``    N m      lower edge of its guaranteed band
``tau_<joint>_max``    N m      upper edge of its guaranteed band
``mode``               -        the contact mode the command guarantees (letters, one per contact)
``margin``             N m      distance from the command to the nearest band edge
=====================  =======  ======================================================================

CSV: a header line with the column names, then numbers written in full
precision (``repr``); an unbounded band side is ``-inf`` / ``inf``; a sample
with no guaranteed band has ``nan`` in ``tau_*`` and ``margin``.  JSON: an object
``{"format", "version", "columns", "units", "descriptions", "data", "metadata", "null"}`` with
``data`` holding one list per column (the schema: :mod:`qsplan.planner.export.schema`);
``metadata["command"]`` states the command rule
(:func:`qsplan.planner.torque.command.command_rule`); JSON has no infinity, so non-finite numbers are
``null`` (in ``tau_<joint>_min``: unbounded below; ``tau_<joint>_max``: unbounded
above; elsewhere: no guaranteed band).

Files are never overwritten unless asked (``force=True``): a controller file
silently replaced is worse than an error.
"""

from __future__ import annotations

import csv
import json
from pathlib import Path


from qsplan.planner.export.files import atomic_write, check_out_dir, check_outputs, csv_cell, json_value

__all__ = ["FORMAT", "SCHEDULE_COLUMNS", "VERSION", "export_schedule", "schedule_columns", "schedule_metadata",
           "write_csv", "write_json"]

FORMAT = "qsplan.torque_schedule"
VERSION = 1

#: Every column family of a schedule: ``(name, unit, meaning)``, ``<joint>`` standing for a joint's name.
SCHEDULE_COLUMNS = (
    ("t", "s", "time from the segment's start"),
    ("q_<joint>", "rad", "joint angle"),
    ("qd_<joint>", "rad/s", "velocity command of a velocity-controlled joint"),
    ("tau_<joint>", "N m", "torque command of a torque-controlled joint, inside its guaranteed band; nan (null) "
                           "where the sample has no band"),
    ("tau_<joint>_min", "N m", "lower edge of the guaranteed band (-inf, JSON null: unbounded below)"),
    ("tau_<joint>_max", "N m", "upper edge of the guaranteed band (inf, JSON null: unbounded above)"),
    ("mode", None, "the contact mode the command guarantees, one letter R, S or B per contact (all S = 4S)"),
    ("margin", "N m", "distance from the command to the nearer band edge"),
)  # fmt: skip


def _meaning(name: str) -> str:
    for family, _, meaning in SCHEDULE_COLUMNS:
        head, _, tail = family.partition("<joint>")
        if name == family or (tail is not None and "<joint>" in family and name.startswith(head)
                              and name.endswith(tail) and len(name) > len(head) + len(tail)
                              and "_" not in name[len(head):len(name) - len(tail)]):  # fmt: skip
            return meaning
    return ""


def schedule_columns(bands) -> tuple:
    """The schedule as ordered columns and their units.

    Parameters
    ----------
    bands : qsplan.planner.torque.sweep.SegmentBands

    Returns
    -------
    columns : dict of str to list
        Column name -> values (floats, or str for ``mode``), one per sample.
    units : dict of str to (str or None)
    """
    S = bands.samples
    scene = S.scenes[0]
    names = scene.joint_names
    e = scene.effort_controlled
    band = bands.guaranteed.band
    cols, units = {"t": S.t.tolist()}, {"t": "s"}
    for j, name in enumerate(names):
        cols[f"q_{name}"] = S.q[:, j].tolist()
        units[f"q_{name}"] = "rad"
    for j, name in enumerate(names):
        if not e[j]:
            cols[f"qd_{name}"] = S.qd[:, j].tolist()
            units[f"qd_{name}"] = "rad/s"
    for j, name in enumerate(names):
        if e[j]:
            cols[f"tau_{name}"] = bands.command.tolist()
            cols[f"tau_{name}_min"] = band.lower.tolist()
            cols[f"tau_{name}_max"] = band.upper.tolist()
            for c in ("", "_min", "_max"):
                units[f"tau_{name}{c}"] = "N m"
    cols["mode"] = [band.mode] * len(S)
    units["mode"] = None
    cols["margin"] = bands.margin.tolist()
    units["margin"] = "N m"
    return cols, units


def schedule_metadata(bands, resolution=None) -> dict:
    """What a controller engineer needs to trust the schedule (all SI); ``resolution``: the controller's torque
    resolution (N m) the command's margin was sized with, if any."""
    from qsplan.hands.described.build import as_hand
    from qsplan.mechanics.bands.effort import check_force_margin
    from qsplan.mechanics.modes.contact_mode import ContactMode

    from qsplan.mechanics.bands.preclusion import PRECLUSION_RTOL

    from qsplan.planner.torque.command import command_rule
    from qsplan.planner.torque.pointwise import narrowest

    S = bands.samples
    seg = S.segment
    hand = as_hand(seg.hand)  # the door: a segment's record (the paper hand by its parameters) as a described hand
    g = bands.guaranteed
    band = g.band
    scene = S.scenes[0]
    k, w = narrowest(band)
    no_band = ~band.feasible
    mode = ContactMode(band.mode)
    return {
        "source": "qsplan: Trinkle & Zeng (1995), Section 5.2, Figs. 9-13",
        "segment": {"name": seg.name, "duration_s": seg.duration, "samples": len(S),
                    "pose_start": seg.pose_start.tolist(), "pose_end": seg.pose_end.tolist(),
                    "pose_units": ["m", "m", "rad"]},
        "mode": {"letters": mode.letters, "name": mode.name, "kind": mode.kind},
        "contacts": list(scene.contact_names),
        "joints": {name: ("effort" if scene.effort_controlled[j] else "velocity") for j, name in enumerate(scene.joint_names)},
        "friction": {"range": list(g.mu_range), "model": "one coefficient shared by all contacts" if g.shared
                     else "each contact's coefficient independently in the range"},
        "band": {
            "method": band.method + " + competitor preclusion (branch and bound)",
            "exact_points": int((band.exact & band.feasible).sum()),
            "conservative_points": int((~band.exact & band.feasible).sum()),
            "points_without_band": int(no_band.sum()),
            "split_points": int(g.split.sum()),
            "competitors": list(g.competitors),
            "tolerance_relative": PRECLUSION_RTOL,
            "force_margin": dict(check_force_margin(g.force_margin).to_dict(),
                                 meaning="inside the band, for every friction in the range, every loaded contact's "
                                         "normal force and every rolling contact's friction-cone slacks are at least "
                                         "these (eq. 28 made strict)"),
            "narrowest": None if k is None else {"t_s": float(S.t[k]), "width_N_m": w, "lower_N_m": float(band.lower[k]),
                                                 "upper_N_m": float(band.upper[k])},
        },
        "command": command_rule(bands.safety_margin, bands.max_margin, resolution),
        "hand": hand.metadata(),
    }  # fmt: skip


def write_csv(bands, path, force: bool = False) -> Path:
    """Write the schedule as CSV (see the module docstring); returns the path."""
    path = Path(path)
    check_outputs([path], force)
    cols, _ = schedule_columns(bands)
    names = list(cols)
    def write(f):
        w = csv.writer(f, lineterminator="\n")
        w.writerow(names)
        for row in zip(*(cols[n] for n in names)):
            w.writerow([csv_cell(v) for v in row])

    return atomic_write(path, write, force=True)


def write_json(bands, path, force: bool = False, resolution=None) -> Path:
    """Write the schedule as JSON with units and metadata (see the module docstring); returns the path."""
    path = Path(path)
    check_outputs([path], force)
    cols, units = schedule_columns(bands)
    doc = {
        "format": FORMAT,
        "version": VERSION,
        "columns": list(cols),
        "units": units,
        "descriptions": {k: _meaning(k) for k in cols},
        "data": {k: [json_value(v) for v in vals] for k, vals in cols.items()},
        "metadata": schedule_metadata(bands, resolution),
        "null": "tau_<joint>_min: unbounded below; tau_<joint>_max: unbounded above; elsewhere: no guaranteed band",
    }
    return atomic_write(path, json.dumps(doc, indent=1, allow_nan=False) + "\n", force=True)


def export_schedule(bands, out_dir, stem: str = "segment1", force: bool = False, resolution=None) -> list:
    """Write ``<stem>.csv`` and ``<stem>.json`` into ``out_dir``; refuse to overwrite unless ``force``.

    Both files are checked before either is written, so a refusal leaves nothing half done.
    ``resolution`` (N m), the controller's torque resolution the command was sized with, is recorded.

    Returns
    -------
    list of pathlib.Path
    """
    out = check_out_dir(out_dir)
    paths = [out / f"{stem}.csv", out / f"{stem}.json"]
    check_outputs(paths, force)
    return [write_csv(bands, paths[0], force=True), write_json(bands, paths[1], force=True, resolution=resolution)]
