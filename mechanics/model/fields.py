"""Validators of scene-document fields: numbers, vectors, tables (the boundary of scene loading).

Shared by the raw form (:mod:`qsplan.mechanics.model.scene_io`) and the geometric form
(:mod:`qsplan.mechanics.model.geometric_scene`); every error names the field, what was
expected and what was received.
"""

from __future__ import annotations

import json
import math
import re
import reprlib
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
    "short_repr",
    "number",
    "vector",
    "check_keys",
    "in_range",
    "UNIT_SLIPS",
]

#: Largest scene or task file read (bytes).  The bundled files are under 2 kB and a raw scene of
#: 40 contacts is about 10 kB; a bigger file is a mistake (or an attack), not a hand.
MAX_FILE_BYTES = 4 * 1024 * 1024

#: Deepest nesting of lists and tables in a scene, task or hand document (levels below the top).  The
#: deepest legitimate paths are five levels in a scene (joints, joint, link, polygon, vertex) and eight
#: in a task with its hand inline (hand, fingers, finger, joints, joint, link, polygon, vertex).  Parsers
#: recurse per bracket level, Python's repr and copies per level of the parsed document, and tomllib
#: spends memory quadratic in a dotted key's length (a 40 kB ``a.a.a...`` key took 1.6 GiB), so a file
#: nested deeper, by brackets or by keys, is refused before it is parsed.
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
        such), or nested deeper than :data:`MAX_DEPTH` (:func:`nesting_depth`: brackets, and in TOML
        the keys of dotted keys and table headers), all measured before anything parses it.
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
    # a .toml file is read as TOML; any other may be read either way (scenes as JSON, tasks as TOML)
    depth = nesting_depth(text, toml=True)
    if path.suffix.lower() != ".toml":
        depth = max(depth, nesting_depth(text))
    if depth > MAX_DEPTH:
        raise error(f"{path}: {what} file nests lists/tables {depth} deep; expected at most {MAX_DEPTH} (each key of a "
                    "dotted key or [table.header] counts as a level)")  # fmt: skip
    return text


def nesting_depth(text: str, toml: bool = False) -> int:
    """Deepest nesting of lists and tables in a JSON or TOML text, measured without parsing it.

    A linear scan, so that a hostile file is measured without the parsers' recursion (or, for TOML's
    dotted keys, their quadratic memory).  JSON: ``[``/``{`` outside strings.  TOML (strings and
    comments skipped): a value's ``[``/``{`` count one level each, and so do the keys of a path: a
    dotted key ``a.b.c = 1`` nests two tables (``a = {b = {c = 1}}``), a header ``[a.b]`` two, an
    array-of-tables header ``[[a]]`` two (the array and its table), and a header's keys that name an
    array of tables one more each (``[a.b]`` after ``[[a]]``: three).  The count is exact for valid
    TOML; for invalid TOML it is exact up to the first error, where the parser stops.
    """
    return _toml_depth(text) if toml else _json_depth(text)


def _json_depth(text: str) -> int:
    depth = deepest = 0
    i = 0
    while (m := _JSON_SPECIAL.search(text, i)) is not None:
        c, i = m.group(), m.end()
        if c == "\"":
            end = _BASIC_END.match(text, i)
            i = end.end() if end else len(text)
        elif c in "[{":
            depth += 1
            deepest = max(deepest, depth)
        else:
            depth -= 1
    return deepest


#: A TOML key segment: bare, "basic" (with escapes) or 'literal'; and a dotted key path of them.
_SEGMENT = r"""(?:[A-Za-z0-9_-]+|"(?:[^"\\\n]|\\.)*"|'[^'\n]*')"""
_KEY_PATH = re.compile(rf"{_SEGMENT}(?:[ \t]*\.[ \t]*{_SEGMENT})*")
_SEGMENTS = re.compile(_SEGMENT)
_JSON_SPECIAL = re.compile(r'["\[\]{}]')
_BASIC_END = re.compile(r'(?:[^"\\]|\\.)*"', re.S)  # the rest of a "string" (JSON, TOML basic)
_MULTILINE_END = re.compile(r'(?:[^"\\]|\\.|"(?!""))*"""', re.S)  # the rest of a TOML """string"""
_TOML_SPECIAL = re.compile(r"""["'#\[\]{},\n]""")
_BLANK = re.compile(r"(?:[ \t\r\n]|#[^\n]*)*")
_ESCAPE = re.compile(r"\\(u[0-9A-Fa-f]{4}|U[0-9A-Fa-f]{8}|.)")
_ESCAPES = {"b": "\b", "t": "\t", "n": "\n", "f": "\f", "r": "\r", "\"": "\"", "\\": "\\"}


def _key_name(segment: str) -> str:
    """A key segment's name: bare as written, a quoted one without its quotes and escapes."""
    if segment[0] == "'":
        return segment[1:-1]
    if segment[0] != "\"":
        return segment

    def unescape(m):
        code = m.group(1)
        if len(code) == 1:
            return _ESCAPES.get(code, m.group())
        return chr(int(code[1:], 16)) if int(code[1:], 16) <= 0x10FFFF else m.group()

    return _ESCAPE.sub(unescape, segment[1:-1])


def _key_path(text: str, i: int):
    """``(number of keys, the first MAX_DEPTH + 1 key names, end)`` of the key path at ``i`` (0 keys: none there)."""
    m = _KEY_PATH.match(text, i)
    if m is None:
        return 0, (), i
    path = m.group()
    if "\"" in path or "'" in path:
        segments = _SEGMENTS.findall(path)
        count, first = len(segments), segments[: MAX_DEPTH + 1]
    else:  # bare keys only (the hostile a.a.a...): count the dots, split only the head
        count = path.count(".") + 1
        first = path.split(".", MAX_DEPTH + 1)[: MAX_DEPTH + 1]
    return count, tuple(_key_name(k.strip()) for k in first), m.end()


def _skip_string(text: str, i: int) -> int:
    """The index after the TOML string that starts at ``i`` (the end of the text if it never ends)."""
    q = text[i]
    if text.startswith(q * 3, i):
        if q == "'":
            j = text.find("'''", i + 3)
            return len(text) if j < 0 else j + 3
        end = _MULTILINE_END.match(text, i + 3)
    else:
        if q == "'":
            j = text.find("'", i + 1)
            return len(text) if j < 0 else j + 1
        end = _BASIC_END.match(text, i + 1)
    return end.end() if end else len(text)


def _toml_depth(text: str) -> int:
    """:func:`nesting_depth` of a TOML text (see there)."""
    n, i, deepest = len(text), 0, 0
    table = 0  # levels of the current [table] or [[array]] header
    arrays = set()  # the paths named by [[array]] headers (as far as MAX_DEPTH: deeper is refused anyway)
    stack = []  # (bracket, level) of the open [ and { of the current value
    slot = 0  # the level of the container a value being read sits in
    expect_key = True  # at a line's start outside any value, or after { or , in an inline table
    while i < n:
        if expect_key:
            i = _BLANK.match(text, i).end()
            if i >= n:
                break
            expect_key = False
            if not stack and text[i] == "[":  # a table header
                aot = text.startswith("[[", i)
                count, names, i = _key_path(text, _BLANK.match(text, i + 1 + aot).end())
                level = count + sum(names[:k] in arrays for k in range(1, len(names))) + aot
                if aot and count <= MAX_DEPTH:
                    arrays.add(names)
                table = slot = level
                deepest = max(deepest, level)
                while i < n and text[i] in " \t":
                    i += 1
                i += 2 if aot and text.startswith("]]", i) else int(text.startswith("]", i))
                continue
            count, _, i = _key_path(text, i)
            owner = stack[-1][1] if stack else table
            slot = owner + max(count - 1, 0)
            deepest = max(deepest, slot)
            continue
        m = _TOML_SPECIAL.search(text, i)
        if m is None:
            break
        c, i = m.group(), m.start()
        if c in "\"'":
            i = _skip_string(text, i)
            continue
        i += 1
        if c == "#":
            j = text.find("\n", i)
            i = n if j < 0 else j
        elif c == "\n":
            expect_key = not stack
        elif c in "[{":
            slot = (stack[-1][1] if stack and stack[-1][0] == "[" else slot) + 1
            stack.append((c, slot))
            deepest = max(deepest, slot)
            expect_key = c == "{"
        elif c in "]}":
            if stack:
                stack.pop()
        elif stack:  # a comma: the next element of an array, or the next key of an inline table
            expect_key = stack[-1][0] == "{"
    return deepest


def read_document(path, what: str = "scene", error=SceneError) -> dict:
    """Read a TOML (``.toml``) or JSON (anything else) file into a dict; errors name the file.

    The text is checked by :func:`read_text` (size, encoding, depth) before it is parsed.
    """
    path = Path(path)
    text = read_text(path, what, error)
    kind = "TOML" if path.suffix.lower() == ".toml" else "JSON"
    try:
        if kind == "TOML":
            import tomllib  # loaded when needed: ~6 ms that a JSON scene (qsplan modes FILE.json) does without

            doc = tomllib.loads(text)
        else:
            doc = json.loads(text)
    except RecursionError:
        raise error(f"{path}: invalid {kind}: nested too deeply; expected at most {MAX_DEPTH} levels") from None
    except ValueError as exc:  # JSONDecodeError, TOMLDecodeError, and integers of thousands of digits
        raise error(f"{path}: invalid {kind}: {' '.join(str(exc).split())}") from None
    if not isinstance(doc, dict):
        raise error(f"{path}: expected an object/table at the top level; got {type(doc).__name__}")
    return doc


def number(value, field: str, largest: float = MAX_MAGNITUDE) -> float:
    """``value`` as a finite float of magnitude at most ``largest``; ``field`` names it in the error.

    ``largest=math.inf`` leaves the bound to the caller (a range of its own, such as a hand's).
    """
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise SceneError(f"{field}: expected a number; got {short_repr(value)}")
    try:
        x = float(value)
    except OverflowError:
        x = math.inf
    if not math.isfinite(x):
        raise SceneError(f"{field}: expected a finite number; got {short_repr(value)}")
    if abs(x) > largest:
        raise SceneError(f"{field}: expected a magnitude of at most {largest:g} (SI units; see "
                         f"qsplan.mechanics.model.fields.MAX_MAGNITUDE); got {x:g}")  # fmt: skip
    return x


#: How much of a received value an error message quotes: a few elements, three levels, 40 characters
#: (a value from a file may be a table nested to :data:`MAX_DEPTH`, or a list of a million numbers).
_REPR = reprlib.Repr()
_REPR.maxlevel, _REPR.maxlist, _REPR.maxtuple, _REPR.maxdict, _REPR.maxstring, _REPR.maxother = 3, 6, 6, 4, 60, 60
SHORT_REPR_CHARS = 40


def short_repr(value) -> str:
    """A one-line repr of ``value`` for an error message, at most :data:`SHORT_REPR_CHARS` long (bounded depth)."""
    text = _REPR.repr(value)
    return text if len(text) <= SHORT_REPR_CHARS else text[:20] + "..." + text[-10:]


#: Unit slips that :func:`in_range` names: ``{unit: (factor, written in, expected)}``.  A value too large
#: for its range that the factor brings inside was most likely written in the slipped unit (``160`` for
#: a 0.16 m palm); an angle (``rad``) is named so for any magnitude up to a full turn in degrees (360),
#: since ``[3, 177]`` is a range in degrees even where 177 degrees is beyond the joint's range.
UNIT_SLIPS = {
    "m": (1e-3, "millimetres", "metres"),
    "rad": (math.pi / 180.0, "degrees", "radians"),
    "m/s": (1e-3, "millimetres per second", "metres per second"),
    "rad/s": (math.pi / 180.0, "degrees per second", "radians per second"),
}

#: A full turn in degrees: the largest magnitude an angle written in degrees has.
FULL_TURN_DEGREES = 360.0


def in_range(value, field: str, lo: float, hi: float, unit: str, source: str, error=SceneError, slips: bool = True):
    """``value`` (a number, or a list of them) inside ``[lo, hi]`` (``unit``); returned unchanged.

    ``slips=False`` for a quantity derived from others (a polygon's width), which no one wrote in a unit.

    Raises
    ------
    error
        ``<field>: expected <lo> to <hi> <unit> (<source>); got <value>``, followed by ``: looks like
        degrees; expected radians`` (millimetres, ...) where the value looks like a unit slip (:data:`UNIT_SLIPS`).
    """
    v = np.asarray(value, dtype=float)
    if np.all((lo <= v) & (v <= hi)):
        return value
    got = f"{float(v):g}" if v.ndim == 0 else "[" + ", ".join(f"{x:g}" for x in v.ravel()) + "]"
    hint = ""
    if slips and unit in UNIT_SLIPS and np.max(np.abs(v)) > max(abs(lo), abs(hi)):  # too large, not too small
        factor, written, expected = UNIT_SLIPS[unit]
        if unit == "rad":
            slipped = bool(np.all(np.abs(v) <= FULL_TURN_DEGREES))
        else:
            slipped = bool(np.all((lo <= v * factor) & (v * factor <= hi)))
        hint = f": looks like {written}; expected {expected}" if slipped else ""
    raise error(f"{field}: expected {lo:g} to {hi:g} {unit} ({source}); got {got}{hint}")


def vector(value, field: str, length: int | None, largest: float = MAX_MAGNITUDE) -> np.ndarray:
    """``value`` (a list of ``length`` numbers, any length if None) as a float array, shape (length,); see :func:`number`."""
    if not isinstance(value, (list, tuple)):
        raise SceneError(f"{field}: expected a list of {length if length is not None else 'some'} numbers; got {short_repr(value)}")
    if length is not None and len(value) != length:
        raise SceneError(f"{field}: expected {length} numbers; got {len(value)}")
    return np.array([number(v, f"{field}[{i}]", largest) for i, v in enumerate(value)], dtype=float)


def check_keys(d, allowed, field):
    """``d`` is a dict whose keys are all in ``allowed``; ``field`` names it in the error."""
    if not isinstance(d, dict):
        raise SceneError(f"{field}: expected an object/table; got {short_repr(d)}")
    unknown = sorted(set(d) - allowed)
    if unknown:
        raise SceneError(f"{field}: unknown field(s) {', '.join(map(short_repr, unknown))}; expected some of {sorted(allowed)}")
