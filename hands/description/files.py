"""Hand files: a palm and two fingers in TOML, bundled or the user's (issue 15).

A hand file (all SI: m, kg, rad; m for a prismatic joint)::

    name = "two-link hand"               # optional, default the file's stem
    gravity = 9.81                       # optional, m/s^2 along -y, >= 0
    [palm]
    polygon = [[-0.16, -0.02], [0.16, -0.02], [0.16, 0.0], [-0.16, 0.0]]   # m; top edge on y = 0
    [[fingers]]                          # exactly two: "left", then "right"
    name = "left"
    [[fingers.joints]]                   # base to tip: each joint rides on the previous joint's link
    name = "left_proximal"               # unique in the hand; "palm" is reserved
    type = "revolute"                    # or "prismatic" (slides along its frame's +x)
    origin = [-0.09, 0.0, 0.0]           # x, y (m), angle (rad) in the previous link's frame (the palm = world)
    limits = [0.05, 3.09]                # rad (m for prismatic), lo < hi
    speed = 0.5                          # rad/s (m/s), > 0
    [fingers.joints.link]
    polygon = [[0.0, -0.006], [0.07, -0.006], [0.07, 0.006], [0.0, 0.006]]   # m, link frame
    mass = 0.0                           # kg, optional, >= 0
    com = [0.035, 0.0]                   # m, optional (default: the polygon's centroid)
    [[fingers.joints]]
    ...                                  # the next joint of the left finger, then [[fingers]] name = "right"

A joint's angle ``q`` turns its link about the joint frame's origin (revolute) or slides it by ``q``
along the frame's +x (prismatic).  The palm's highest vertices must lie on ``y = 0`` and form one
horizontal edge: the workpiece rests there.

* :func:`load_hand` reads a bundled hand by name (:func:`bundled_hands`: ``paper_hand``,
  ``two_link_hand``, ``parallel_jaw``) or a file by path;
* :func:`hand_from_table` validates a parsed table: a hand file's top level, or a task's ``[hand]``
  table (whose workpiece keys the task names in ``extra_keys``);
* :func:`description_table` writes a description back as such a table (a plan's metadata records a hand so).

Errors are :class:`~qsplan.mechanics.errors.SceneError` (a ``ValueError``) in one line naming the
field path: in a file, after the file's name (``my_hand.toml: fingers[1].joints[0].type: expected
'revolute' or 'prismatic'; got 'ball'``); in a task, under ``hand.``.  See ``docs/hand_files.md``.
"""

from __future__ import annotations

import os
import tomllib
from pathlib import Path

import numpy as np

from qsplan.hands.description.model import HandDescription, check_unknown, make_hand_description
from qsplan.mechanics.errors import SceneError
from qsplan.mechanics.model.fields import MAX_DEPTH, read_text

__all__ = ["HAND_KEYS", "bundled_hands", "description_table", "load_hand", "hand_from_table"]

#: The fields of a hand table (a hand file's top level).
HAND_KEYS = ("name", "gravity", "palm", "fingers")

_DATA = Path(__file__).resolve().parent.parent / "data"  # hands/data, installed as qsplan.hands package data


def bundled_hands() -> dict:
    """Every bundled hand file, ``{name: Path}`` (the name is the file's stem)."""
    return {p.stem: p for p in sorted(_DATA.glob("*.toml"))}


def hand_from_table(table, field="hand", extra_keys=frozenset(), base_dir=None, source="inline", *,
                    default_name="hand") -> HandDescription:  # fmt: skip
    """Validate a parsed hand table (see the module docstring) into a :class:`HandDescription`.

    Parameters
    ----------
    table : dict
        The table: ``name``, ``gravity``, ``palm``, ``fingers``.  Instead of these it may hold
        ``file`` (a bundled hand name or a path, see :func:`load_hand`), unless ``"file"`` is in
        ``extra_keys``.
    field : str
        The table's path in errors (``"hand"`` in a task, ``""`` at a file's top level).
    extra_keys : collection of str
        Keys ignored here (a task's workpiece keys); any other unknown key is refused, named.
    base_dir : str or Path, optional
        Folder against which a relative ``file`` is resolved.
    source : str
        Recorded in :attr:`HandDescription.source`.
    default_name : str
        The hand's name when the table gives none.

    Raises
    ------
    SceneError
        Naming the field path, e.g. ``hand.palm: missing (...)``.
    """
    if not isinstance(table, dict):
        raise SceneError(f"{field or 'hand'}: expected a table; got {type(table).__name__}")
    keys = set(table) - set(extra_keys)
    if "file" in keys:
        others = sorted(keys - {"file"}, key=str)
        f = f"{field}.file" if field else "file"
        if others:
            raise SceneError(f"{f}: give either a hand file or the hand's fields, not both; got also {', '.join(others)}")
        try:
            return load_hand(table["file"], base_dir)
        except SceneError as exc:
            raise SceneError(f"{f}: {exc}") from None
    check_unknown({k: table[k] for k in keys}, HAND_KEYS, field)
    prefix = f"{field}." if field else ""
    for key, what in (("palm", "the [palm] table with its polygon"), ("fingers", "two [[fingers]] tables, left then right")):
        if key not in table:
            raise SceneError(f"{prefix}{key}: missing ({what})")
    return make_hand_description(table.get("name", default_name), table["palm"], table["fingers"],
                                 table.get("gravity", 9.81), source, field=field)  # fmt: skip


def load_hand(ref, base_dir=None) -> HandDescription:
    """Read a hand: a bundled one by name, or a TOML file by path.

    Parameters
    ----------
    ref : str or Path
        A name of :func:`bundled_hands` (``"two_link_hand"``), or a path to a ``.toml`` file.
    base_dir : str or Path, optional
        Folder against which a relative path is resolved (a task's folder); default the working folder.

    Returns
    -------
    HandDescription
        ``source`` is ``"bundled:<name>"`` or the file's path.

    Raises
    ------
    SceneError
        In one line starting with the file's name: no such hand, unreadable file, invalid TOML, or a bad
        field (named by its path in the file, e.g. ``fingers[0].joints[1].limits``).
    """
    bundled = bundled_hands()
    if isinstance(ref, str) and ref in bundled:
        path, shown, source = bundled[ref], bundled[ref].name, f"bundled:{ref}"
    else:
        if not isinstance(ref, (str, os.PathLike)) or not str(ref).strip():
            raise SceneError(f"hand: expected a bundled hand ({', '.join(bundled)}) or a path to a .toml file; "
                             f"got {ref!r}")  # fmt: skip
        path = Path(ref)
        if base_dir is not None and not path.is_absolute():
            path = Path(base_dir) / path
        shown = source = str(path)
        if not path.is_file():
            raise SceneError(f"{shown}: no such hand file; expected a path to a .toml file or a bundled hand "
                             f"({', '.join(bundled)})")  # fmt: skip
        if path.suffix.lower() != ".toml":
            raise SceneError(f"{shown}: expected a hand file ending in .toml; got {path.suffix or 'no suffix'}")
    try:
        text = read_text(path, "hand", SceneError)
    except SceneError as exc:
        message = str(exc)
        raise SceneError(message if message.startswith(shown) else f"{shown}: {message}") from None
    try:
        doc = tomllib.loads(text)
    except RecursionError:
        raise SceneError(f"{shown}: invalid TOML: nested too deeply; expected at most {MAX_DEPTH} levels") from None
    except ValueError as exc:  # TOMLDecodeError, and integers of thousands of digits
        raise SceneError(f"{shown}: invalid TOML: {' '.join(str(exc).split())}") from None
    try:
        return hand_from_table(doc, field="", source=source, default_name=path.stem)
    except SceneError as exc:
        raise SceneError(f"{shown}: {exc}") from None


def description_table(desc: HandDescription) -> dict:
    """``desc`` as a plain table in the hand-file format: ``name``, ``gravity``, ``palm``, ``fingers``.

    Numbers are Python floats (JSON and TOML keep them exactly); :func:`hand_from_table` gives the description back.
    """
    man = desc.manipulator
    fingers = []
    for finger in desc.fingers:
        joints = []
        for i in finger.joints:
            j = man.joints[i]
            joints.append({"name": j.name, "type": j.kind, "origin": [float(v) for v in j.origin],
                           "limits": [float(v) for v in desc.joint_limits[i]], "speed": float(desc.joint_speeds[i]),
                           "link": {"polygon": np.asarray(j.link_shape, dtype=float).tolist(),
                                    "mass": float(j.link_mass), "com": [float(v) for v in j.link_com]}})  # fmt: skip
        fingers.append({"name": finger.name, "joints": joints})
    return {"name": desc.name, "gravity": float(man.gravity), "palm": {"polygon": np.asarray(desc.palm).tolist()},
            "fingers": fingers}  # fmt: skip
