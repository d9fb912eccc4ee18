"""The certifier's file checks: both exported files say the same, and ``plan.json`` states the task certified.

A controller may read ``plan.csv`` or ``plan.json`` (:func:`qsplan.planner.export.plan_files.export_plan`), so the
certifier (:mod:`qsplan.planner.certify.certify`) checks every row of one of them and, here, that the other
holds the very same cells (:func:`agreement_checks`: the same columns, every number bit for bit, JSON ``null``
where the CSV has ``-inf`` in a ``_min`` column, ``inf`` in a ``_max`` column and ``nan`` elsewhere), that
``plan.json`` follows its schema (:func:`schema_checks`), and that every fact its ``metadata`` states is the
task's or the rows' (:func:`metadata_checks`: friction, resolution, force margin, disturbance, command rule, time
scaling, limits, the hand, the task's tables and record, the plan's narrowest band; each phase and each step of the
sequence, :mod:`qsplan.planner.certify.claims`), or labelled informational by the schema.  Each check returns
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


def _cell(value) -> str:
    """A cell as a person reads it: a number's Python repr (``2.0``, ``nan``), a word quoted (``'SSSS'``), never a numpy
    scalar's repr (``np.float64(2.0)``)."""
    return repr(str(value)) if isinstance(value, (str, np.str_, bytes)) else repr(float(value))


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
            out.append((i, "files", f"column {name}: {a_name} has {_cell(x[i])}, {b_name} {_cell(y[i])}"
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


def _show(v) -> str:
    """A claimed or true value for a message (plain JSON, long ones cut)."""
    text = json.dumps(v, allow_nan=True)
    return text if len(text) <= 240 else text[:237] + "..."


def _difference(claim, truth, path: str):
    """``(path, claimed, true)`` where ``claim`` (what the metadata states) first differs from ``truth`` (numbers to
    :data:`META_TOL`, ``null`` only with ``null``), or None: every key ``claim`` states must hold ``truth``'s value (a
    key it leaves out states nothing: plans written before a key existed lack it)."""
    if isinstance(claim, dict):
        if not isinstance(truth, dict):
            return path, claim, truth
        for key, value in claim.items():
            if key not in truth:
                return f"{path}.{key}", value, "(nothing the certifier can check)"
            found = _difference(value, truth[key], f"{path}.{key}")
            if found:
                return found
        return None
    if isinstance(claim, list):
        if not isinstance(truth, list) or len(claim) != len(truth):
            return path, claim, truth
        return next((d for i, (a, b) in enumerate(zip(claim, truth)) if (d := _difference(a, b, f"{path}[{i}]"))),
                    None)  # fmt: skip
    numeric = isinstance(claim, (int, float)) and not isinstance(claim, bool)
    if numeric and isinstance(truth, (int, float)) and not isinstance(truth, bool):
        return None if _close(claim, truth) else (path, claim, truth)
    return None if (claim == truth and type(claim) is type(truth)) else (path, claim, truth)


def _differs(found, whose: str = "the task's") -> str:
    """A message for :func:`_difference`'s answer: ``"metadata.x states 1, not the task's 2"``."""
    path, claim, truth = found
    if isinstance(claim, list) and isinstance(truth, list) and len(claim) != len(truth):
        return f"{path} states {len(claim)} entries {_show(claim)}, not {whose} {len(truth)} {_show(truth)}"
    return f"{path} states {_show(claim)}, not {whose} {_show(truth)}"


def metadata_checks(meta, task, cols, evidence=None) -> list:
    """Every fact ``plan.json``'s metadata states, against the task, the rows and ``evidence`` (what the row checks
    found: :class:`qsplan.planner.certify.claims.RowEvidence`; each phase's and step's claims,
    :mod:`qsplan.planner.certify.claims`).  Not checked, the keys the schema labels informational: ``source``,
    ``task``, ``planner``, ``narrowest_band.phase``, ``hand.description_source``, ``task_record.name`` and those of
    :mod:`~qsplan.planner.certify.claims`."""
    from qsplan.hands.interface import hand_metadata
    from qsplan.planner.certify.claims import RowEvidence, phase_claims, sequence_claims
    from qsplan.planner.export.plan_files import (command_metadata, disturbance_metadata, force_margin_metadata,
                                                  friction_metadata, plan_metadata_limits,
                                                  time_scaling_metadata)  # fmt: skip
    from qsplan.planner.task.record import task_record, task_tables

    if not isinstance(meta, dict):
        return [(None, "metadata", "plan.json has no metadata object")]
    evidence = RowEvidence() if evidence is None else evidence
    out = []

    def claim(ok, message, row=None):
        if not ok:
            out.append((row, "metadata", message))

    try:
        lacking = [key for key in ("friction", "torque_resolution_N_m", "force_margin") if key not in meta]
        if lacking:  # stated by every plan
            raise KeyError(lacking[0])
        claim(_close(meta["torque_resolution_N_m"], task.torque_resolution),
              f"torque resolution {meta['torque_resolution_N_m']} is not the task's {task.torque_resolution:g}")
        hand = hand_metadata(task.hand)
        hand.pop("description_source", None)  # where the description was read from: not a fact of the plan
        for key, truth in (("friction", friction_metadata(task)), ("force_margin", force_margin_metadata(task)),
                           ("command", command_metadata(task)), ("time_scaling", time_scaling_metadata(task)),
                           ("limits", plan_metadata_limits(task)), ("hand", hand),
                           ("task_tables", task_tables(task)), ("formation", task.formation.as_dict()),
                           ("task_record", task_record(task))):  # fmt: skip
            if key in meta:
                # not facts of the plan: where a hand description was read from, what the task is called
                ignored = {"hand": "description_source", "task_record": "name"}.get(key)
                claimed = {k: v for k, v in meta[key].items() if k != ignored} \
                    if ignored and isinstance(meta[key], dict) else meta[key]
                found = _difference(claimed, _plain(truth), f"metadata.{key}")
                claim(found is None, found and _differs(found))
        if "disturbance" in meta or task.disturbance is not None:
            found = _difference(meta.get("disturbance"), _plain(disturbance_metadata(task)), "metadata.disturbance")
            claim(found is None, found and _differs(found))
        phases = meta["phases"]
        out += phase_claims(phases, task, cols, evidence)
        if "sequence" in meta:
            out += sequence_claims(meta["sequence"], phases, task, cols, evidence)
        contact = np.flatnonzero(cols["mode"] != "free")
        if contact.size:
            t, w = _narrowest(cols, contact)
            nb = meta["narrowest_band"]
            claim(_close(nb["t_s"], t) and _close(nb["width_N_m"], w),
                  f"narrowest band {nb['width_N_m']} at t = {nb['t_s']} s; the rows' is {w} at t = {t:g} s")
    except (KeyError, TypeError, IndexError, ValueError, ZeroDivisionError) as exc:
        out.append((None, "metadata", f"plan.json's metadata lacks or garbles a field ({type(exc).__name__}: {exc})"))
    return out
