"""Which files in an output directory qsplan wrote itself: a manifest of their SHA-256 digests.

A run records every output it writes in ``DIR/.qsplan-outputs.json`` (name -> SHA-256 and size).
The next run into the same directory may replace an output whose content is still the one
recorded (qsplan wrote it and nobody changed it since); any other existing file of the same
name (not recorded, edited, or replaced by someone) is refused without ``force``, as before.
So ``qsplan demo --out out`` can be run twice, and a hand-edited ``plan.csv`` is never lost.

:func:`publish_outputs` moves a run's staged outputs into the directory (removing the earlier run's,
recording the new ones, renaming them into place) in an order that leaves a consistent directory
wherever it is interrupted.
"""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path

from qsplan.mechanics.errors import QsplanError
from qsplan.planner.export.files import atomic_write, remove_stale

__all__ = ["MANIFEST", "own_outputs", "publish_outputs", "record_outputs"]

#: The manifest's file name inside an output directory.
MANIFEST = ".qsplan-outputs.json"

_FORMAT = "qsplan.outputs"


def _digest(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def _read(out: Path) -> dict:
    """The manifest's entries ``{name: {"sha256", "bytes"}}``; empty when missing or unreadable."""
    p = out / MANIFEST
    if p.is_symlink() or not p.is_file():
        return {}
    try:
        doc = json.loads(p.read_text(encoding="utf-8"))
        files = doc["files"] if doc.get("format") == _FORMAT else {}
        return {str(k): v for k, v in files.items() if isinstance(v, dict) and isinstance(v.get("sha256"), str)}
    except (OSError, UnicodeDecodeError, ValueError, KeyError, TypeError, AttributeError):
        return {}


def own_outputs(out_dir) -> set:
    """Names of the files in ``out_dir`` that qsplan wrote and nobody changed since (content as recorded).

    Only regular files count (never a symbolic link).
    """
    out = Path(out_dir)
    own = set()
    for name, entry in _read(out).items():
        p = out / name
        if Path(name).name != name or p.is_symlink() or not p.is_file():
            continue
        try:
            if p.stat().st_size == entry.get("bytes") and _digest(p) == entry["sha256"]:
                own.add(name)
        except OSError:
            continue
    return own


def record_outputs(out_dir, paths) -> Path:
    """Record ``paths`` (files just written into ``out_dir``) in its manifest; returns the manifest's path.

    Entries of other names are kept while their files are unchanged; entries whose file is gone
    or changed are dropped.
    """
    from qsplan import __version__

    out = Path(out_dir)
    keep = own_outputs(out)
    files = {name: entry for name, entry in _read(out).items() if name in keep}
    for p in map(Path, paths):
        if p.is_file() and not p.is_symlink():
            files[p.name] = {"sha256": _digest(p), "bytes": p.stat().st_size}
    doc = {"format": _FORMAT, "version": 1, "written_by": f"qsplan {__version__}",
           "meaning": "files qsplan wrote into this directory; a later run may replace them while unchanged",
           "files": dict(sorted(files.items()))}  # fmt: skip
    return atomic_write(out / MANIFEST, json.dumps(doc, indent=1) + "\n", force=True)


def publish_outputs(out_dir, stage, names, remove=(), last=()) -> list:
    """Move the files ``names``, written into the staging directory ``stage``, into ``out_dir``; returns their paths.

    The caller holds the directory (:func:`qsplan.planner.export.files.locked_out_dir`) and has checked that every
    existing file of ``names`` may be replaced (an earlier run's own output, or ``force``).  In this order, so
    that a run interrupted anywhere leaves a directory that does not mislead:

    1. the files ``remove`` (the earlier run's outputs, ``names`` among them where they exist) are removed:
       an old file never sits beside a new one (a new certificate beside an old plan);
    2. the manifest records the staged files: whichever of them is in place is known as qsplan's, and a
       rerun replaces it without ``force``;
    3. each file is renamed into place (one atomic rename each, the same file system), those in ``last``
       (the plan files) last: where a plan file is, every other output of its run is.

    Raises
    ------
    QsplanError
        A rename failed (naming the file and the OS reason).
    """
    out, stage = Path(out_dir), Path(stage)
    order = [n for n in names if n not in last] + [n for n in last if n in names]
    remove_stale(out, remove)
    record_outputs(out, [stage / n for n in order])
    for name in order:
        try:
            os.replace(stage / name, out / name)
        except OSError as exc:
            raise QsplanError(f"out_dir: cannot move {name!r} into {str(out)!r}: {exc.strerror or exc}") from None
    return [out / n for n in names]
