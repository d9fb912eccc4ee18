"""Writing output files safely: the one overwrite check, the one atomic writer, the directory lock, the cell formats.

A controller file silently replaced is worse than an error: every writer in qsplan (the
schedule and plan exports, the plan pipeline, the figures, the paper's outputs, the CLI)

* checks its outputs with :func:`check_outputs` before writing anything: an existing file is
  replaced only with ``force``; a symbolic link is never written through and an input file
  never replaced, ``force`` or not;
* writes every file with :func:`atomic_write`: to a temporary name in the same directory, then
  renamed over the target, so an interrupted run (Ctrl-C, a crash, a full disk) leaves either
  the old file or the new one, never half of one;
* removes with :func:`remove_stale` what an earlier run left that this run did not rewrite,
  so a directory never holds outputs of two runs that look like one result.

A run that writes several files which belong together (the plan pipeline, the paper's outputs)
holds its directory with :func:`locked_out_dir` (an exclusive ``flock`` on ``DIR/.qsplan.lock``,
taken without waiting: a second run into the same directory fails at once, naming the first's
pid; the lock dies with its process, so a killed run's lock file blocks nobody), and the plan
pipeline writes into a private :func:`staging_dir` inside it, published by renames only once
certified (:func:`qsplan.planner.export.manifest.publish_outputs`).  POSIX only (``fcntl``).

Messages name the library's fields (``out_dir``, ``force``); the CLI translates them into its options.
"""

from __future__ import annotations

import math
import os
import shutil
import tempfile
from contextlib import contextmanager
from pathlib import Path

from qsplan.mechanics.errors import QsplanError

__all__ = [
    "LOCK_NAME",
    "OutDirLockedError",
    "OutputExistsError",
    "STAGE_PREFIX",
    "atomic_write",
    "check_out_dir",
    "check_output_path",
    "check_outputs",
    "csv_cell",
    "json_value",
    "locked_out_dir",
    "make_out_dir",
    "remove_stale",
    "staging_dir",
]

#: The lock file of an output directory: held (``flock``, exclusive) by the run writing into it, removed after.
LOCK_NAME = ".qsplan.lock"

#: Name prefix of a run's private staging directory inside its output directory (a random suffix follows).
STAGE_PREFIX = ".qsplan-stage-"

#: Attempts at taking the lock when the lock file is replaced between our open and our ``flock`` (a run that
#: finishes unlinks it): each attempt is an open and a non-blocking ``flock``, microseconds; a bound, not a wait.
LOCK_ATTEMPTS = 100


class OutputExistsError(QsplanError):
    """An output file exists and overwriting was not asked for.

    Attributes
    ----------
    path : str
        The first existing file.
    count : int
        How many of the outputs exist.
    """

    def __init__(self, path, count: int, message: str):
        super().__init__(message)
        self.path = str(path)
        self.count = int(count)


def check_out_dir(out_dir) -> Path:
    """``out_dir`` as a Path; raises :class:`QsplanError` when it is an existing file."""
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise QsplanError(f"out_dir: {str(out)!r} is a file; expected a directory")
    return out


class OutDirLockedError(QsplanError):
    """Another run holds the output directory (:func:`locked_out_dir`).

    Attributes
    ----------
    pid : int or None
        The holder's process id, as it wrote it into the lock file (None if not yet written).
    """

    def __init__(self, pid, message: str):
        super().__init__(message)
        self.pid = pid


def make_out_dir(out_dir, field: str = "out_dir") -> Path:
    """``out_dir`` as a Path, created with its parents; :class:`QsplanError` naming ``field`` and the OS reason
    when it is a file or cannot be created."""
    out = check_out_dir(out_dir)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise QsplanError(f"{field}: cannot create the directory {str(out)!r}: {exc.strerror or exc}") from None
    return out


@contextmanager
def locked_out_dir(out_dir, inputs=(), field: str = "out_dir"):
    """Hold ``out_dir`` for one run: created if missing (and removed again if the run leaves it empty), an
    exclusive lock taken without waiting, released on exit.

    The lock is ``flock`` on ``out_dir/.qsplan.lock`` (:data:`LOCK_NAME`), which holds the holder's pid.  A
    lock dies with its process, so the file a killed run leaves behind does not block; the holder removes the
    file before it releases the lock, and a run that locked a file since removed (its ``stat`` no longer the
    path's) tries again on the new one.  Staging directories that killed runs left
    (:data:`STAGE_PREFIX`) are removed once the lock is held: no run is using them.

    Yields
    ------
    Path
        The directory.

    Raises
    ------
    OutDirLockedError
        Another run holds it (naming its pid).
    QsplanError
        ``out_dir`` cannot be created or written, its lock file is a symbolic link or one of ``inputs``.
    """
    import fcntl

    created = not Path(out_dir).exists()
    out = make_out_dir(out_dir, field)
    path = check_output_path(out / LOCK_NAME, inputs, field)
    fd = None
    for _ in range(LOCK_ATTEMPTS):
        try:
            fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW | os.O_CLOEXEC, 0o666)
        except OSError as exc:
            raise QsplanError(f"{field}: cannot write into {str(out)!r} (its lock file {LOCK_NAME}): "
                              f"{exc.strerror or exc}") from None  # fmt: skip
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            pid = _lock_pid(fd)
            os.close(fd)
            held = f"pid {pid}" if pid is not None else "pid not yet recorded"
            raise OutDirLockedError(pid, f"{field}: {str(out)!r} is being written by another qsplan run ({held}); "
                                         "wait for it or choose another directory") from None  # fmt: skip
        except OSError as exc:  # a file system without locks: refused, never written unlocked
            os.close(fd)
            raise QsplanError(f"{field}: cannot lock {str(out)!r}: {exc.strerror or exc}") from None
        try:
            same = os.path.samestat(os.fstat(fd), os.stat(path, follow_symlinks=False))
        except FileNotFoundError:
            same = False
        if same:
            break
        os.close(fd)  # the holder before us removed it after we opened it: lock the file now at the path
        fd = None
    if fd is None:
        raise QsplanError(f"{field}: could not lock {str(out)!r}: its lock file kept being replaced")
    try:
        os.ftruncate(fd, 0)
        os.write(fd, f"{os.getpid()}\n".encode())
        _remove_stages(out)
        yield out
    finally:
        try:
            os.unlink(path)  # still holding the lock: a run waiting on this file sees it gone and tries again
        except OSError:
            pass
        os.close(fd)
        if created:  # a run that wrote nothing leaves no new directory behind (rmdir removes only an empty one)
            try:
                out.rmdir()
            except OSError:
                pass


def _lock_pid(fd) -> int | None:
    """The pid written in a lock file (None when empty or unreadable)."""
    try:
        text = os.pread(fd, 32, 0).decode("ascii", "replace").strip()
        return int(text) if text.isdigit() else None
    except OSError:
        return None


def _remove_stages(out: Path) -> None:
    """Remove the staging directories of runs that were killed (call only while holding the directory's lock)."""
    for entry in os.scandir(out):
        if entry.name.startswith(STAGE_PREFIX) and entry.is_dir(follow_symlinks=False):
            shutil.rmtree(entry.path, ignore_errors=True)


@contextmanager
def staging_dir(out_dir, field: str = "out_dir"):
    """A private directory inside ``out_dir`` (``.qsplan-stage-<random>``, mode 0700) where a run writes its outputs
    before publishing them by renames (same file system: each rename is atomic); removed on any exit.

    Raises
    ------
    QsplanError
        It cannot be created (naming ``field`` and the OS reason).
    """
    try:
        stage = Path(tempfile.mkdtemp(prefix=STAGE_PREFIX, dir=out_dir))
    except OSError as exc:
        raise QsplanError(f"{field}: cannot write into {str(out_dir)!r}: {exc.strerror or exc}") from None
    try:
        yield stage
    finally:
        shutil.rmtree(stage, ignore_errors=True)


def check_output_path(path, inputs=(), field: str = "out_dir") -> Path:
    """``path`` as a Path, refused (always, whatever ``force``) when it cannot be a safe output.

    Refused: an existing directory, a symbolic link (writing would go through it into its
    target), and any of ``inputs`` (compared as resolved paths, so ``./scene.json`` and
    ``scene.json`` are the same file).

    Raises
    ------
    QsplanError
        Naming ``field`` and the path.
    """
    p = Path(path)
    if p.is_symlink():
        raise QsplanError(f"{field}: {str(p)!r} is a symbolic link; refusing to write through it (remove the link "
                          "or choose another path)")  # fmt: skip
    if p.is_dir():
        raise QsplanError(f"{field}: {str(p)!r} is a directory; cannot write the file there")
    target = p.resolve()
    for source in inputs:
        if source is not None and Path(source).resolve() == target:
            raise QsplanError(f"{field}: {str(p)!r} is an input of this run; refusing to replace it, even with force")
    return p


def check_outputs(paths, force: bool = False, inputs=()) -> None:
    """Refuse to overwrite: raise :class:`OutputExistsError` if any of ``paths`` exists (unless ``force``).

    Also refuses (always) a path that is an existing directory, a symbolic link or one of
    ``inputs`` (:func:`check_output_path`).  Nothing is written.
    """
    paths = [check_output_path(p, inputs) for p in paths]
    clash = [p for p in paths if p.exists()]
    if clash and not force:
        message = f"out_dir: {str(clash[0])!r} exists; pass force=True to overwrite it or choose another directory"
        if len(clash) > 1:
            message += f" ({len(clash)} of the {len(paths)} output files exist)"
        raise OutputExistsError(clash[0], len(clash), message)


def atomic_write(path, content, *, binary: bool = False, force: bool = True, inputs=(), field: str = "out_dir") -> Path:
    """Write a file atomically: to a temporary name in its directory, then renamed over ``path``.

    Parameters
    ----------
    path : str or Path
        The target; its parent folders are created.
    content : str, bytes or callable
        The text (bytes with ``binary``), or ``content(f)`` writing into an open file object
        (text mode with ``newline=""``, or binary with ``binary``).
    force : bool
        Replace an existing file.  The default is True because writers check all their outputs
        with :func:`check_outputs` first; a lone writer passes its caller's ``force``.
    inputs : sequence of paths
        Files this run reads: never replaced (:func:`check_output_path`).
    field : str
        Names the path in errors.

    Returns
    -------
    Path

    Raises
    ------
    QsplanError
        The path is refused (:func:`check_output_path`), exists without ``force``
        (:class:`OutputExistsError`), or cannot be written (naming ``field`` and the OS reason).
        On any error or interruption (KeyboardInterrupt included) the temporary file is removed
        and ``path`` is untouched.
    """
    path = check_output_path(path, inputs, field)
    check_outputs([path], force)
    tmp = None
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
        with open(fd, "wb" if binary else "w", **({} if binary else {"newline": "", "encoding": "utf-8"})) as f:
            if callable(content):
                content(f)
            else:
                f.write(content)
            f.flush()
            os.fsync(f.fileno())
        os.chmod(tmp, 0o666 & ~_umask())  # mkstemp makes 0600; outputs get the usual permissions
        os.replace(tmp, path)
        tmp = None
    except OSError as exc:
        raise QsplanError(f"{field}: cannot write {str(path)!r}: {exc.strerror or exc}") from None
    finally:
        if tmp is not None:
            try:
                os.unlink(tmp)
            except OSError:
                pass
    return path


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def remove_stale(out_dir, names) -> list:
    """Remove the files ``names`` from ``out_dir`` that an earlier run left; returns the removed paths.

    Called by a run that replaces its outputs (``force``) before it writes, and by a run that
    fails, so that a directory never shows an old ``plan.csv`` beside a new ``failure.json``.
    Only regular files and symbolic links (the link, never its target) are removed.
    """
    out = Path(out_dir)
    removed = []
    for name in names:
        p = out / name
        if p.is_symlink() or p.is_file():
            try:
                p.unlink()
            except OSError as exc:
                raise QsplanError(f"out_dir: cannot remove the stale {str(p)!r}: {exc.strerror or exc}") from None
            removed.append(p)
    return removed


def csv_cell(v) -> str:
    """A CSV cell: strings as they are, integers as integers, other numbers in full precision (``repr``;
    ``inf``, ``nan``)."""
    if isinstance(v, str):
        return v
    if isinstance(v, int) and not isinstance(v, bool):
        return str(v)
    return repr(float(v))


def json_value(v):
    """JSON has no infinity or NaN: non-finite floats become ``None`` (``null``)."""
    if isinstance(v, float) and not math.isfinite(v):
        return None
    return v
