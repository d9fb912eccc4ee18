"""Which files in an output directory qsplan wrote itself: a manifest of their SHA-256 digests.

A run records every output it writes in ``DIR/.qsplan-outputs.json`` (name -> SHA-256 and size).
The next run into the same directory may replace an output whose content is still the one
recorded (qsplan wrote it and nobody changed it since); any other existing file of the same
name (not recorded, edited, or replaced by someone) is refused without ``force``, as before.
So ``qsplan demo --out out`` can be run twice, and a hand-edited ``plan.csv`` is never lost.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

from qsplan.planner.export.files import atomic_write

__all__ = ["MANIFEST", "own_outputs", "record_outputs"]

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
