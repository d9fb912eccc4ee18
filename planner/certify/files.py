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

import math

import numpy as np

from qsplan.planner.certify.stated import META_TOL, close, difference, differs, narrowest, plain

__all__ = ["META_TOL", "agreement_checks", "metadata_checks", "schema_checks"]


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


def metadata_checks(meta, task, cols, evidence=None) -> list:
    """Every fact ``plan.json``'s metadata states, against the task, the rows and ``evidence`` (what the row checks
    found: :class:`qsplan.planner.certify.claims.RowEvidence`; each phase's and step's claims,
    :mod:`qsplan.planner.certify.claims`).  Not checked, the keys the schema labels informational: ``source``,
    ``task``, ``planner``, ``narrowest_band.phase``, ``hand.description_source``, ``task_record.name`` and those of
    :mod:`~qsplan.planner.certify.claims`."""
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
        claim(close(meta["torque_resolution_N_m"], task.torque_resolution),
              f"torque resolution {meta['torque_resolution_N_m']} is not the task's {task.torque_resolution:g}")
        recorded = task.hand.metadata()
        recorded.pop("description_source", None)  # where the description was read from: not a fact of the plan
        for key, truth in (("friction", friction_metadata(task)), ("force_margin", force_margin_metadata(task)),
                           ("command", command_metadata(task)), ("time_scaling", time_scaling_metadata(task)),
                           ("limits", plan_metadata_limits(task)), ("hand", recorded),
                           ("task_tables", task_tables(task)), ("formation", task.formation.as_dict()),
                           ("task_record", task_record(task))):  # fmt: skip
            if key in meta:
                # not facts of the plan: where a hand description was read from, what the task is called
                ignored = {"hand": "description_source", "task_record": "name"}.get(key)
                claimed = {k: v for k, v in meta[key].items() if k != ignored} \
                    if ignored and isinstance(meta[key], dict) else meta[key]
                found = difference(claimed, plain(truth), f"metadata.{key}")
                claim(found is None, found and differs(found))
        if "disturbance" in meta or task.disturbance is not None:
            found = difference(meta.get("disturbance"), plain(disturbance_metadata(task)), "metadata.disturbance")
            claim(found is None, found and differs(found))
        phases = meta["phases"]
        out += phase_claims(phases, task, cols, evidence)
        if "sequence" in meta:
            out += sequence_claims(meta["sequence"], phases, task, cols, evidence)
        contact = np.flatnonzero(cols["mode"] != "free")
        if contact.size:
            t, w = narrowest(cols, contact)
            nb = meta["narrowest_band"]
            claim(close(nb["t_s"], t) and close(nb["width_N_m"], w),
                  f"narrowest band {nb['width_N_m']} at t = {nb['t_s']} s; the rows' is {w} at t = {t:g} s")
    except (KeyError, TypeError, IndexError, ValueError, ZeroDivisionError) as exc:
        out.append((None, "metadata", f"plan.json's metadata lacks or garbles a field ({type(exc).__name__}: {exc})"))
    return out
