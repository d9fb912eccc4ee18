"""The certifier's file checks: both exported files say the same, and ``plan.json`` states the task certified.

A controller may read ``plan.csv`` or ``plan.json`` (:func:`qsplan.planner.export.plan_files.export_plan`), so the
certifier (:mod:`qsplan.planner.certify.certify`) checks every row of one of them and, here, that the other
holds the very same cells (:func:`agreement_checks`: the same columns, every number bit for bit, JSON ``null``
where the CSV has ``-inf`` in a ``_min`` column, ``inf`` in a ``_max`` column and ``nan`` elsewhere), that
``plan.json`` follows its schema (:func:`schema_checks`), and that every fact its ``metadata`` states is the
task's or the rows' (:func:`metadata_checks`: friction, resolution, force margin, limits, the hand, each phase's
rows, times, mode, effort joint and narrowest band, the plan's narrowest band).  Each check returns
``(row or None, kind, message)`` triples; ``None``: the plan as a whole.  Units SI.
"""

from __future__ import annotations

import json
import math

import numpy as np

__all__ = ["META_TOL", "agreement_checks", "metadata_checks", "schema_checks"]

#: Tolerance (s, m, N m, relative where a number is larger than 1) between a number the metadata states and the
#: rows': the export writes both from the same float, so only a tampered file differs; 1e-9 forgives the
#: decimal round trip of a hand-edited but equal value.
META_TOL = 1e-9


def _fill(name: str) -> float:
    """What a JSON ``null`` stands for in column ``name``: unbounded below, above, or not applicable."""
    return -math.inf if name.endswith("_min") else (math.inf if name.endswith("_max") else math.nan)


def agreement_checks(a_name, a_cols, b_name, b_cols) -> list:
    """Cells of two plan files that differ (at most one message per column: its first row, and how many differ)."""
    out = []
    if list(a_cols) != list(b_cols):
        only_a = [c for c in a_cols if c not in b_cols]
        only_b = [c for c in b_cols if c not in a_cols]
        what = (f"columns only in {a_name}: {', '.join(only_a)}; " if only_a else "") + \
               (f"columns only in {b_name}: {', '.join(only_b)}" if only_b else "") or "the columns' order differs"  # fmt: skip
        out.append((None, "files", f"{a_name} and {b_name} differ: {what.rstrip('; ')}"))
    for name in (c for c in a_cols if c in b_cols):
        x, y = a_cols[name], b_cols[name]
        if x.size != y.size:
            out.append((None, "files", f"{a_name} has {x.size} rows, {b_name} {y.size}"))
            return out
        if x.dtype.kind in "US" or y.dtype.kind in "US":
            bad = np.flatnonzero(x.astype(str) != y.astype(str))
        else:
            # JSON null in a band column reads as that column's non-finite value; a CSV nan where JSON says unbounded
            # (or inf where JSON has null in another column) differs: equal_nan compares only nan with nan
            bad = np.flatnonzero(~((x == y) | (np.isnan(x) & np.isnan(y))))
        if bad.size:
            i = int(bad[0])
            out.append((i, "files", f"column {name}: {a_name} has {x[i]!r}, {b_name} {y[i]!r}"
                                    + (f" ({bad.size} rows differ)" if bad.size > 1 else "")))  # fmt: skip
    return out


def schema_checks(doc) -> list:
    """``plan.json`` against its schema (:func:`qsplan.planner.export.schema.check_schedule_document`)."""
    from qsplan.planner.export.schema import check_schedule_document

    return [(None, "files", f"plan.json: {e}") for e in check_schedule_document(doc)[:5]]


def _close(a, b) -> bool:
    if a is None or b is None:
        return a is None and b is None
    try:
        a, b = float(a), float(b)
    except (TypeError, ValueError):
        return False
    if not (math.isfinite(a) and math.isfinite(b)):
        return a == b
    return abs(a - b) <= META_TOL * max(1.0, abs(a), abs(b))


def _num(v):
    return float(v) if v is not None and math.isfinite(v) else None


def _narrowest(cols, rows) -> tuple:
    """``(t, width or None)`` of the narrowest band over in-contact ``rows`` (None: all unbounded)."""
    e = cols["effort_joint"]
    widths = np.array([cols[f"tau_{e[i]}_max"][i] - cols[f"tau_{e[i]}_min"][i] for i in rows], dtype=float)
    widths = np.where(np.isnan(widths), np.inf, widths)
    k = int(np.argmin(widths))
    return float(cols["t"][rows[k]]), _num(widths[k])


def _plain(value):
    return json.loads(json.dumps(value, allow_nan=False))


def _stated(claim, truth, path: str) -> str | None:
    """Where ``claim`` (what the metadata states) differs from ``truth`` (the task's), or None: every key it states
    must hold the task's value (a key it leaves out states nothing; plans written before a key existed lack it)."""
    if isinstance(claim, dict):
        if not isinstance(truth, dict):
            return path
        for key, value in claim.items():
            if key not in truth:
                return f"{path}.{key}"
            where = _stated(value, truth[key], f"{path}.{key}")
            if where:
                return where
        return None
    if isinstance(claim, list):
        if not isinstance(truth, list) or len(claim) != len(truth):
            return path
        return next((w for i, (a, b) in enumerate(zip(claim, truth)) if (w := _stated(a, b, f"{path}[{i}]"))), None)
    if isinstance(claim, (int, float)) and not isinstance(claim, bool):
        return None if _close(claim, truth) and not isinstance(truth, (bool, str)) else path
    return None if claim == truth else path


def metadata_checks(meta, task, cols) -> list:
    """Every fact ``plan.json``'s metadata states, against the task and the rows."""
    from qsplan.hands.interface import hand_metadata
    from qsplan.planner.export.plan_files import disturbance_metadata, plan_metadata_limits
    from qsplan.planner.task.record import task_record, task_tables

    if not isinstance(meta, dict):
        return [(None, "metadata", "plan.json has no metadata object")]
    out = []

    def claim(ok, message, row=None):
        if not ok:
            out.append((row, "metadata", message))

    try:
        fr = meta["friction"]
        claim(_close(fr["range"][0], task.mu_range[0]) and _close(fr["range"][1], task.mu_range[1])
              and ("shared" in fr["model"]) == task.shared_mu,
              f"friction {fr['range']} ({fr['model']}) is not the task's {list(task.mu_range)} "
              f"({'shared' if task.shared_mu else 'independent'})")  # fmt: skip
        claim(_close(meta["torque_resolution_N_m"], task.torque_resolution),
              f"torque resolution {meta['torque_resolution_N_m']} is not the task's {task.torque_resolution:g}")
        fm = meta["force_margin"]
        claim(_close(fm["min_normal_force_N"], task.force_margin.normal)
              and _close(fm["min_coulomb_slack_N"], task.force_margin.slack),
              f"force margin {fm['min_normal_force_N']} / {fm['min_coulomb_slack_N']} N is not the task's "
              f"{task.force_margin.normal:g} / {task.force_margin.slack:g} N")  # fmt: skip
        hand = hand_metadata(task.hand)
        hand.pop("description_source", None)  # where the description was read from: not a fact of the plan
        for key, truth in (("limits", plan_metadata_limits(task)), ("hand", hand),
                           ("task_tables", task_tables(task)), ("formation", task.formation.as_dict()),
                           ("task_record", task_record(task))):
            if key in meta:
                # not facts of the plan: where a hand description was read from, what the task is called
                ignored = {"hand": "description_source", "task_record": "name"}.get(key)
                claimed = {k: v for k, v in meta[key].items() if k != ignored} \
                    if ignored and isinstance(meta[key], dict) else meta[key]
                where = _stated(claimed, _plain(truth), f"metadata.{key}")
                claim(where is None, f"{where} is not the task's")
        if "disturbance" in meta or task.disturbance is not None:
            where = _stated(meta.get("disturbance"), _plain(disturbance_metadata(task)), "metadata.disturbance")
            claim(where is None and (meta.get("disturbance") is None) == (task.disturbance is None),
                  f"{where or 'metadata.disturbance'} is not the task's")
        out += _phase_claims(meta["phases"], cols)
        contact = np.flatnonzero(cols["mode"] != "free")
        if contact.size:
            t, w = _narrowest(cols, contact)
            nb = meta["narrowest_band"]
            claim(_close(nb["t_s"], t) and _close(nb["width_N_m"], w),
                  f"narrowest band {nb['width_N_m']} at t = {nb['t_s']} s; the rows' is {w} at t = {t:g} s")
    except (KeyError, TypeError, IndexError, ValueError) as exc:
        out.append((None, "metadata", f"plan.json's metadata lacks or garbles a field ({type(exc).__name__}: {exc})"))
    return out


def _phase_claims(phases, cols) -> list:
    """Each ``metadata.phases`` entry against its rows (index, rows, times, kind, mode, effort joint, narrowest)."""
    out = []
    ph = cols["phase"]
    if not isinstance(phases, list) or len(phases) != int(np.max(ph)) + 1:
        return [(None, "metadata", f"{len(phases) if isinstance(phases, list) else 'no'} phases described; the rows "
                                   f"have {int(np.max(ph)) + 1}")]  # fmt: skip
    for i, d in enumerate(phases):
        rows = np.flatnonzero(ph == i)
        if not rows.size:
            out.append((None, "metadata", f"phase {i} has no rows"))
            continue
        first, mode, effort = int(rows[0]), str(cols["mode"][rows[0]]), str(cols["effort_joint"][rows[0]])
        kind = "regrasp" if mode == "free" else "contact"
        problems = []
        if d.get("index") != i:
            problems.append(f"index {d.get('index')}")
        if d.get("rows") != rows.size:
            problems.append(f"{d.get('rows')} rows (the file has {rows.size})")
        if not (_close(d.get("t_start_s"), cols["t"][rows[0]]) and _close(d.get("t_end_s"), cols["t"][rows[-1]])):
            problems.append(f"times {d.get('t_start_s')} to {d.get('t_end_s')} s (the rows': {cols['t'][rows[0]]:g} to "
                            f"{cols['t'][rows[-1]]:g} s)")  # fmt: skip
        if d.get("kind") != kind:
            problems.append(f"kind {d.get('kind')!r} (the rows': {kind})")
        if kind == "contact":
            if d.get("mode") != mode or d.get("effort_joint") != effort:
                problems.append(f"mode {d.get('mode')} / effort joint {d.get('effort_joint')} (the rows': {mode} / {effort})")
            t, w = _narrowest(cols, rows)
            nb = d.get("narrowest_band") or {}
            if not (_close(nb.get("t_s"), t) and _close(nb.get("width_N_m"), w)):
                problems.append(f"narrowest band {nb.get('width_N_m')} at t = {nb.get('t_s')} s (the rows': {w} at {t:g} s)")
        if problems:
            out.append((first, "metadata", f"metadata.phases[{i}] states " + "; ".join(problems)))
    return out
