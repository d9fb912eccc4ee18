"""What a plan file states against what is true: the tolerance and the comparisons the certifier's file and claim
checks share (:mod:`qsplan.planner.certify.files`, :mod:`qsplan.planner.certify.claims`).  Units SI.
"""

from __future__ import annotations

import json
import math

import numpy as np

__all__ = ["META_TOL", "close", "difference", "differs", "finite_or_none", "narrowest", "plain", "show"]

#: Tolerance (s, m, N m, relative where a number is larger than 1) between a number the metadata states and the
#: rows': the export writes both from the same float, so only a tampered file differs; 1e-9 forgives the
#: decimal round trip of a hand-edited but equal value.
META_TOL = 1e-9


def close(a, b) -> bool:
    if a is None or b is None:
        return a is None and b is None
    try:
        a, b = float(a), float(b)
    except (TypeError, ValueError):
        return False
    if not (math.isfinite(a) and math.isfinite(b)):
        return a == b
    return abs(a - b) <= META_TOL * max(1.0, abs(a), abs(b))


def finite_or_none(v):
    return float(v) if v is not None and math.isfinite(v) else None


def narrowest(cols, rows) -> tuple:
    """``(t, width or None)`` of the narrowest band over in-contact ``rows`` (None: all unbounded)."""
    e = cols["effort_joint"]
    widths = np.array([cols[f"tau_{e[i]}_max"][i] - cols[f"tau_{e[i]}_min"][i] for i in rows], dtype=float)
    widths = np.where(np.isnan(widths), np.inf, widths)
    k = int(np.argmin(widths))
    return float(cols["t"][rows[k]]), finite_or_none(widths[k])


def plain(value):
    return json.loads(json.dumps(value, allow_nan=False))


def show(v) -> str:
    """A claimed or true value for a message (plain JSON, long ones cut)."""
    text = json.dumps(v, allow_nan=True)
    return text if len(text) <= 240 else text[:237] + "..."


def difference(claim, truth, path: str):
    """``(path, claimed, true)`` where ``claim`` (what the metadata states) first differs from ``truth`` (numbers to
    :data:`META_TOL`, ``null`` only with ``null``), or None: every key ``claim`` states must hold ``truth``'s value (a
    key it leaves out states nothing: plans written before a key existed lack it)."""
    if isinstance(claim, dict):
        if not isinstance(truth, dict):
            return path, claim, truth
        for key, value in claim.items():
            if key not in truth:
                return f"{path}.{key}", value, "(nothing the certifier can check)"
            found = difference(value, truth[key], f"{path}.{key}")
            if found:
                return found
        return None
    if isinstance(claim, list):
        if not isinstance(truth, list) or len(claim) != len(truth):
            return path, claim, truth
        return next((d for i, (a, b) in enumerate(zip(claim, truth)) if (d := difference(a, b, f"{path}[{i}]"))),
                    None)  # fmt: skip
    numeric = isinstance(claim, (int, float)) and not isinstance(claim, bool)
    if numeric and isinstance(truth, (int, float)) and not isinstance(truth, bool):
        return None if close(claim, truth) else (path, claim, truth)
    return None if (claim == truth and type(claim) is type(truth)) else (path, claim, truth)


def differs(found, whose: str = "the task's") -> str:
    """A message for :func:`difference`'s answer: ``"metadata.x states 1, not the task's 2"``."""
    path, claim, truth = found
    if isinstance(claim, list) and isinstance(truth, list) and len(claim) != len(truth):
        return f"{path} states {len(claim)} entries {show(claim)}, not {whose} {len(truth)} {show(truth)}"
    return f"{path} states {show(claim)}, not {whose} {show(truth)}"
