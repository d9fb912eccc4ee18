"""The exported schedules checked against their JSON schema, and the CSV against the JSON.

``torque_schedule.schema.json`` (shipped beside this module, package data) describes both formats:
``qsplan.torque_schedule`` (``qsplan sweep``'s ``segment1.json``) and ``qsplan.torque_schedule.plan``
(``qsplan plan``'s ``plan.json``).  :func:`validate` is a small validator of the JSON Schema keywords
that file uses (``type``, ``enum``, ``const``, ``required``, ``properties``, ``patternProperties``,
``additionalProperties``, ``items``, ``minItems``, ``maxItems``, ``minimum``, ``pattern``, ``oneOf``,
local ``$ref``), so no dependency is needed; :func:`check_schedule_document` adds what a schema cannot
say (every column present once, all of one length; in a plan, every joint of the recorded hand with its
kind's units and ``effort_joint`` naming one of them), and :func:`check_schedule_files` compares the CSV
beside the JSON with it cell by cell.
"""

from __future__ import annotations

import csv
import json
import math
import re
from pathlib import Path

__all__ = ["INFORMATIONAL", "SCHEMA_FILE", "check_schedule_document", "check_schedule_files", "informational_paths",
           "schedule_schema", "validate"]

#: The schema's file name, beside this module.
SCHEMA_FILE = "torque_schedule.schema.json"

#: How the schema's ``description`` of a key begins when the key states nothing a controller relies on (bookkeeping:
#: names, seeds, wall times, search statistics, labels): ``qsplan verify`` does not check it; every other key of a
#: plan's metadata it checks against the task and the rows (:mod:`qsplan.planner.certify.files`).
INFORMATIONAL = "Informational:"

_TYPES = {
    "object": lambda v: isinstance(v, dict),
    "array": lambda v: isinstance(v, list),
    "string": lambda v: isinstance(v, str),
    "integer": lambda v: isinstance(v, int) and not isinstance(v, bool),
    "number": lambda v: isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v),
    "boolean": lambda v: isinstance(v, bool),
    "null": lambda v: v is None,
}


def schedule_schema() -> dict:
    """The packaged schema (a dict)."""
    from importlib.resources import files

    return json.loads(files("qsplan.planner.export").joinpath(SCHEMA_FILE).read_text(encoding="utf-8"))


def _resolve(ref: str, root: dict) -> dict:
    if not ref.startswith("#/"):
        raise ValueError(f"$ref: only local references are supported; got {ref!r}")
    node = root
    for part in ref[2:].split("/"):
        node = node[part]
    return node


def validate(instance, schema: dict, root: dict | None = None, path: str = "$") -> list:
    """Every violation of ``schema`` by ``instance``, as ``"path: message"`` strings (empty: valid).

    Parameters
    ----------
    instance : JSON value
    schema : dict
        A JSON Schema using the keywords listed in the module docstring.
    root : dict, optional
        The document ``$ref`` resolves against (default ``schema``).
    """
    root = schema if root is None else root
    errors = []
    if "$ref" in schema:
        errors += validate(instance, _resolve(schema["$ref"], root), root, path)
    if "type" in schema:
        kinds = schema["type"] if isinstance(schema["type"], list) else [schema["type"]]
        if not any(_TYPES[k](instance) for k in kinds):
            return errors + [f"{path}: expected {' or '.join(kinds)}; got {type(instance).__name__} {_short(instance)}"]
    if "const" in schema and instance != schema["const"]:
        errors.append(f"{path}: expected {schema['const']!r}; got {_short(instance)}")
    if "enum" in schema and instance not in schema["enum"]:
        errors.append(f"{path}: expected one of {schema['enum']}; got {_short(instance)}")
    if isinstance(instance, str) and "pattern" in schema and not re.search(schema["pattern"], instance):
        errors.append(f"{path}: {instance!r} does not match {schema['pattern']!r}")
    if _TYPES["number"](instance) and "minimum" in schema and instance < schema["minimum"]:
        errors.append(f"{path}: expected at least {schema['minimum']}; got {instance}")
    if isinstance(instance, list):
        if len(instance) < schema.get("minItems", 0):
            errors.append(f"{path}: expected at least {schema['minItems']} items; got {len(instance)}")
        if len(instance) > schema.get("maxItems", math.inf):
            errors.append(f"{path}: expected at most {schema['maxItems']} items; got {len(instance)}")
        if "items" in schema:
            for i, item in enumerate(instance):
                errors += validate(item, schema["items"], root, f"{path}[{i}]")
                if len(errors) > 20:  # one bad column: enough said
                    return errors
    if isinstance(instance, dict):
        errors += [f"{path}: missing {key!r}" for key in schema.get("required", ()) if key not in instance]
        props, patterns = schema.get("properties", {}), schema.get("patternProperties", {})
        for key, value in instance.items():
            matched = False
            if key in props:
                errors += validate(value, props[key], root, f"{path}.{key}")
                matched = True
            for pattern, sub in patterns.items():
                if re.search(pattern, key):
                    errors += validate(value, sub, root, f"{path}.{key}")
                    matched = True
            extra = schema.get("additionalProperties", True)
            if not matched and extra is False:
                errors.append(f"{path}: unexpected key {key!r}")
            elif not matched and isinstance(extra, dict):
                errors += validate(value, extra, root, f"{path}.{key}")
    if "oneOf" in schema:
        found = [validate(instance, sub, root, path) for sub in schema["oneOf"]]
        passing = sum(not f for f in found)
        if passing == 0:  # the closest alternative's errors say most (the format names the alternative)
            errors += min(found, key=len)
        elif passing > 1:
            errors.append(f"{path}: {passing} of the {len(found)} alternatives hold; expected exactly one")
    return errors


def _applying(instance, schema: dict, root: dict) -> list:
    """The schema objects that apply to ``instance``: ``schema``, what its ``$ref`` names, and each ``oneOf``
    alternative it satisfies, recursively."""
    out = [schema]
    if "$ref" in schema:
        out += _applying(instance, _resolve(schema["$ref"], root), root)
    for sub in schema.get("oneOf", ()):
        if not validate(instance, sub, root):
            out += _applying(instance, sub, root)
    return out


def informational_paths(doc, schema: dict | None = None) -> list:
    """The paths (``$.metadata.planner``, ``$.metadata.phases[0].name``, ...) of every value of ``doc`` whose schema
    ``description`` begins with :data:`INFORMATIONAL` (what lies under one is not listed again), in document order."""
    root = schedule_schema() if schema is None else schema
    out = []

    def walk(value, schemas, path):
        if any(str(s.get("description", "")).startswith(INFORMATIONAL) for s in schemas):
            out.append(path)
            return
        if isinstance(value, dict):
            for key, item in value.items():
                subs = []
                for s in schemas:
                    patterns = s.get("patternProperties", {}).items()
                    matched = [sub for pattern, sub in patterns if re.search(pattern, key)]
                    if key in s.get("properties", {}):
                        matched.append(s["properties"][key])
                    extra = s.get("additionalProperties")
                    if not matched and isinstance(extra, dict):
                        matched.append(extra)
                    subs += matched
                walk(item, [a for sub in subs for a in _applying(item, sub, root)], f"{path}.{key}")
        elif isinstance(value, list):
            subs = [s["items"] for s in schemas if isinstance(s.get("items"), dict)]
            for i, item in enumerate(value):
                walk(item, [a for sub in subs for a in _applying(item, sub, root)], f"{path}[{i}]")

    walk(doc, _applying(doc, root, root), "$")
    return out


def _short(v) -> str:
    text = json.dumps(v) if not isinstance(v, str) else repr(v)
    return text if len(text) <= 40 else text[:37] + "..."


def check_schedule_document(doc) -> list:
    """Every problem of an exported JSON document (``plan.json``, ``segment1.json``): the schema, then
    ``columns`` = the keys of ``data`` = the keys of ``units``, in order, and every column of one length."""
    errors = validate(doc, schedule_schema())
    if errors or not isinstance(doc, dict):
        return errors
    cols = doc["columns"]
    if list(doc["data"]) != cols:
        errors.append(f"$.data: columns {list(doc['data'])} differ from $.columns {cols}")
    if list(doc["units"]) != cols:
        errors.append(f"$.units: keys {list(doc['units'])} differ from $.columns {cols}")
    if "descriptions" in doc and list(doc["descriptions"]) != cols:
        errors.append("$.descriptions: keys differ from $.columns")
    lengths = {name: len(values) for name, values in doc["data"].items()}
    if len(set(lengths.values())) > 1:
        errors.append(f"$.data: columns of different lengths {lengths}")
    if doc["format"].endswith(".plan"):
        errors += _plan_joint_problems(doc)
    return errors


def _plan_joint_problems(doc) -> list:
    """A plan file's joints against its hand (``metadata.hand``): every joint's five columns present with its kind's
    units (the paper's hand: ``left`` and ``right``, revolute; a described hand: its description's joints), and
    ``effort_joint`` one of them or ``none``."""
    from qsplan.hands.protocol import JOINT_UNITS

    hand = doc["metadata"]["hand"]
    if "description" in hand:
        joints = [(j.get("name"), j.get("type")) for f in hand["description"]["fingers"] for j in f.get("joints", ())]
    else:
        joints = [("left", "revolute"), ("right", "revolute")]
    errors = []
    for name, kind in joints:
        units = JOINT_UNITS["prismatic" if kind == "prismatic" else "revolute"]
        for column, quantity in ((f"q_{name}", "q"), (f"qd_{name}", "qd"), (f"tau_{name}", "tau"),
                                 (f"tau_{name}_min", "tau"), (f"tau_{name}_max", "tau")):  # fmt: skip
            if column not in doc["data"]:
                errors.append(f"$.data: missing {column!r} (joint {name!r} of the hand)")
            elif doc["units"].get(column) != units[quantity]:
                errors.append(f"$.units.{column}: expected {units[quantity]!r} ({kind} joint); got {doc['units'].get(column)!r}")
    known = {name for name, _ in joints} | {"none"}
    bad = sorted({e for e in doc["data"].get("effort_joint", ()) if e not in known})
    if bad:
        errors.append(f"$.data.effort_joint: {bad[0]!r} is no joint of the hand; expected one of {sorted(known)}")
    return errors


def _same(cell: str, value) -> bool:
    """A CSV cell equals the JSON value: the same string, the same number, or a non-finite number for ``null``."""
    if isinstance(value, str):
        return cell == value
    try:
        x = float(cell)
    except ValueError:
        return False
    if value is None:
        return not math.isfinite(x)
    if isinstance(value, int) and not isinstance(value, bool):
        return cell == str(value)
    return x == value


def check_schedule_files(json_path, csv_path=None) -> list:
    """Every problem of an exported JSON file and of the CSV beside it (same stem, when there is one):
    :func:`check_schedule_document`, then the CSV's header equal to ``columns`` and every cell equal to
    the JSON's value (non-finite numbers where JSON has ``null``)."""
    json_path = Path(json_path)
    try:
        doc = json.loads(json_path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        return [f"{json_path}: not JSON ({exc})"]
    errors = [f"{json_path.name}: {e}" for e in check_schedule_document(doc)]
    csv_path = json_path.with_suffix(".csv") if csv_path is None else Path(csv_path)
    if errors or not csv_path.is_file():
        return errors
    with open(csv_path, newline="", encoding="utf-8") as f:
        rows = list(csv.reader(f))
    if not rows or rows[0] != doc["columns"]:
        return errors + [f"{csv_path.name}: header {rows[0] if rows else []} differs from the JSON's columns"]
    n = len(doc["data"]["t"])
    if len(rows) - 1 != n:
        return errors + [f"{csv_path.name}: {len(rows) - 1} rows; the JSON has {n}"]
    for j, name in enumerate(doc["columns"]):
        values = doc["data"][name]
        bad = [i for i in range(n) if not _same(rows[i + 1][j], values[i])]
        if bad:
            i = bad[0]
            errors.append(f"{csv_path.name}: column {name!r} row {i}: {rows[i + 1][j]!r} against JSON {values[i]!r}"
                          f" ({len(bad)} cells differ)")  # fmt: skip
    return errors
