"""Validators of scene-document fields: numbers, vectors, tables (the boundary of scene loading).

Shared by the raw form (:mod:`qsplan.mechanics.model.scene_io`) and the geometric form
(:mod:`qsplan.mechanics.model.geometric_scene`); every error names the field, what was
expected and what was received.
"""

from __future__ import annotations

import json
import math
import tomllib
from pathlib import Path

import numpy as np

from qsplan.mechanics.errors import SceneError

__all__ = ["read_document", "number", "vector", "check_keys"]


def read_document(path) -> dict:
    """Read a TOML (``.toml``) or JSON (anything else) file into a dict; errors name the file."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise SceneError(f"{path}: cannot read scene file ({exc.strerror})") from None
    try:
        doc = tomllib.loads(text) if path.suffix.lower() == ".toml" else json.loads(text)
    except (tomllib.TOMLDecodeError, json.JSONDecodeError) as exc:
        kind = "TOML" if path.suffix.lower() == ".toml" else "JSON"
        raise SceneError(f"{path}: invalid {kind}: {exc}") from None
    if not isinstance(doc, dict):
        raise SceneError(f"{path}: expected an object/table at the top level; got {type(doc).__name__}")
    return doc


def number(value, field: str) -> float:
    """``value`` as a finite float; ``field`` names it in the error."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise SceneError(f"{field}: expected a number; got {value!r}")
    if not math.isfinite(value):
        raise SceneError(f"{field}: expected a finite number; got {value!r}")
    return float(value)


def vector(value, field: str, length: int | None) -> np.ndarray:
    """``value`` (a list of ``length`` numbers, any length if None) as a float array, shape (length,)."""
    if not isinstance(value, (list, tuple)):
        raise SceneError(f"{field}: expected a list of {length if length is not None else 'some'} numbers; got {value!r}")
    if length is not None and len(value) != length:
        raise SceneError(f"{field}: expected {length} numbers; got {len(value)}")
    return np.array([number(v, f"{field}[{i}]") for i, v in enumerate(value)], dtype=float)


def check_keys(d, allowed, field):
    """``d`` is a dict whose keys are all in ``allowed``; ``field`` names it in the error."""
    if not isinstance(d, dict):
        raise SceneError(f"{field}: expected an object/table; got {d!r}")
    unknown = sorted(set(d) - allowed)
    if unknown:
        raise SceneError(f"{field}: unknown field(s) {', '.join(map(repr, unknown))}; expected some of {sorted(allowed)}")
