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

__all__ = [
    "MAX_DEPTH",
    "MAX_FILE_BYTES",
    "MAX_MAGNITUDE",
    "read_document",
    "read_text",
    "nesting_depth",
    "number",
    "vector",
    "check_keys",
]

#: Largest scene or task file read (bytes).  The bundled files are under 2 kB and a raw scene of
#: 40 contacts is about 10 kB; a bigger file is a mistake (or an attack), not a hand.
MAX_FILE_BYTES = 4 * 1024 * 1024

#: Deepest nesting of lists and tables in a scene or task document.  The deepest legitimate path is
#: six levels (document, joints, joint, link, polygon, vertex); parsers recurse per level, so a
#: file nested thousands deep is refused before it is parsed.
MAX_DEPTH = 12

#: Largest magnitude of any number in a scene document (SI: m, kg, N, N m, rad/s, m/s).  No
#: hand-scale quantity comes near it, and the solver multiplies up to ``2 n_c + 3`` such entries
#: (the determinants of eqs. 26-28) against absolute tolerances near 1e-9: beyond 1e6 an entry
#: leaves no significant digits before it overflows.
MAX_MAGNITUDE = 1e6


def read_text(path, what: str = "scene", error=SceneError) -> str:
    """The text of a UTF-8 file, checked for size, encoding and nesting depth.

    Parameters
    ----------
    path : str or Path
    what : str
        Names the file's role in errors (``"scene"``, ``"task"``).
    error : type
        The :class:`~qsplan.mechanics.errors.QsplanError` subclass raised.

    Raises
    ------
    error
        Unreadable, larger than :data:`MAX_FILE_BYTES`, not UTF-8 (a UTF-16 file is named as
        such), or nested deeper than :data:`MAX_DEPTH`.
    """
    path = Path(path)
    try:
        with open(path, "rb") as f:
            data = f.read(MAX_FILE_BYTES + 1)
    except OSError as exc:
        where = f"{path}: cannot read {what} file" if what == "scene" else f"{what}: cannot read {str(path)!r}"
        raise error(f"{where} ({exc.strerror or exc})") from None
    if len(data) > MAX_FILE_BYTES:
        raise error(f"{path}: {what} file larger than {MAX_FILE_BYTES // (1024 * 1024)} MiB; expected a small text file")
    if data[:2] in (b"\xff\xfe", b"\xfe\xff"):
        raise error(f"{path}: {what} file is UTF-16 encoded; expected UTF-8 text (save it as UTF-8)")
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise error(f"{path}: {what} file is not UTF-8 text (byte {exc.start} is {data[exc.start:exc.start + 1]!r}); "
                    "expected UTF-8") from None  # fmt: skip
    if "\x00" in text:
        raise error(f"{path}: {what} file contains NUL characters; expected UTF-8 text")
    depth = nesting_depth(text, toml=path.suffix.lower() == ".toml")
    if depth > MAX_DEPTH:
        raise error(f"{path}: {what} file nests lists/tables {depth} deep; expected at most {MAX_DEPTH}")
    return text


def nesting_depth(text: str, toml: bool = False) -> int:
    """Deepest nesting of ``[``/``{`` outside strings (and, for TOML, comments) in a JSON or TOML text.

    A linear scan, so that a hostile file is measured without the parsers' recursion.  For TOML a
    table header (``[a]``, ``[[a]]``) counts while it is open, which only overestimates by 2.
    """
    depth = deepest = 0
    i, n = 0, len(text)
    quotes = ("\"", "'") if toml else ("\"",)
    while i < n:
        c = text[i]
        if c in quotes:
            triple = toml and text.startswith(c * 3, i)
            end = c * 3 if triple else c
            i += len(end)
            while i < n and not text.startswith(end, i):
                i += 2 if (c == "\"" and text[i] == "\\") else 1
            i += len(end)
            continue
        if toml and c == "#":
            j = text.find("\n", i)
            i = n if j < 0 else j
            continue
        if c in "[{":
            depth += 1
            deepest = max(deepest, depth)
        elif c in "]}":
            depth -= 1
        i += 1
    return deepest


def read_document(path, what: str = "scene", error=SceneError) -> dict:
    """Read a TOML (``.toml``) or JSON (anything else) file into a dict; errors name the file.

    The text is checked by :func:`read_text` (size, encoding, depth) before it is parsed.
    """
    path = Path(path)
    text = read_text(path, what, error)
    kind = "TOML" if path.suffix.lower() == ".toml" else "JSON"
    try:
        doc = tomllib.loads(text) if kind == "TOML" else json.loads(text)
    except RecursionError:
        raise error(f"{path}: invalid {kind}: nested too deeply; expected at most {MAX_DEPTH} levels") from None
    except ValueError as exc:  # JSONDecodeError, TOMLDecodeError, and integers of thousands of digits
        raise error(f"{path}: invalid {kind}: {' '.join(str(exc).split())}") from None
    if not isinstance(doc, dict):
        raise error(f"{path}: expected an object/table at the top level; got {type(doc).__name__}")
    return doc


def number(value, field: str) -> float:
    """``value`` as a finite float; ``field`` names it in the error."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise SceneError(f"{field}: expected a number; got {_short(value)}")
    try:
        x = float(value)
    except OverflowError:
        x = math.inf
    if not math.isfinite(x):
        raise SceneError(f"{field}: expected a finite number; got {_short(value)}")
    if abs(x) > MAX_MAGNITUDE:
        raise SceneError(f"{field}: expected a magnitude of at most {MAX_MAGNITUDE:g} (SI units; see "
                         f"qsplan.mechanics.model.fields.MAX_MAGNITUDE); got {x:g}")  # fmt: skip
    return x


def _short(value) -> str:
    text = repr(value)
    return text if len(text) <= 40 else text[:20] + "..." + text[-10:]


def vector(value, field: str, length: int | None) -> np.ndarray:
    """``value`` (a list of ``length`` numbers, any length if None) as a float array, shape (length,)."""
    if not isinstance(value, (list, tuple)):
        raise SceneError(f"{field}: expected a list of {length if length is not None else 'some'} numbers; got {_short(value)}")
    if length is not None and len(value) != length:
        raise SceneError(f"{field}: expected {length} numbers; got {len(value)}")
    return np.array([number(v, f"{field}[{i}]") for i, v in enumerate(value)], dtype=float)


def check_keys(d, allowed, field):
    """``d`` is a dict whose keys are all in ``allowed``; ``field`` names it in the error."""
    if not isinstance(d, dict):
        raise SceneError(f"{field}: expected an object/table; got {_short(d)}")
    unknown = sorted(set(d) - allowed)
    if unknown:
        raise SceneError(f"{field}: unknown field(s) {', '.join(map(repr, unknown))}; expected some of {sorted(allowed)}")
