"""External solvers that stay off stdout: a C library's writes to file descriptor 1 sent to the null device.

``highspy.Highs()`` prints a banner ("Running HiGHS ...") from C++ straight to the process's file
descriptor 1 (measured with highspy 1.16: once per process, when the first solver object is built),
before ``output_flag`` can be set.  ``contextlib.redirect_stdout`` only swaps ``sys.stdout``, a Python
object, so the banner went into ``qsplan modes --json`` and broke its JSON.  :func:`quiet_highs` builds
*every* solver with descriptor 1 pointing at ``os.devnull`` and switches its output off before handing
it out, so it does not matter when a version prints (first construction, every construction, on
loading); afterwards a solver writes only with ``output_flag`` on, which qsplan never sets.  The C
library's own buffers are flushed before and after (``fflush(NULL)``), so a banner still buffered
there cannot reach the real stdout later, and nothing printed before is lost.
"""

from __future__ import annotations

import contextlib
import ctypes
import os
import sys
import threading

__all__ = ["quiet_fd_stdout", "quiet_highs"]

#: Serialises the redirections: two threads swapping descriptor 1 at once could restore
#: each other's null device instead of the real stdout.
_FD_LOCK = threading.Lock()


def _flush_c_streams() -> None:
    """Flush every C stdio stream (``fflush(NULL)``), so that output buffered in the C library
    before the redirection reaches the real stdout and output buffered during it the null device."""
    try:
        ctypes.CDLL(None).fflush(None)
    except (OSError, TypeError, AttributeError):  # no C runtime reachable this way (Windows): nothing to flush
        pass


@contextlib.contextmanager
def quiet_fd_stdout():
    """Point file descriptor 1 at ``os.devnull`` for the block; restore it on exit, error or not.

    ``sys.stdout`` and the C streams are flushed first, so nothing written before is lost.
    Thread safe among its own users (a lock); another thread's direct writes to descriptor 1
    during the block are dropped, so keep the block short.
    """
    with _FD_LOCK:
        try:
            if sys.stdout is not None:
                sys.stdout.flush()
        except (OSError, ValueError):  # a closed or broken stdout: nothing of ours to keep in order
            pass
        _flush_c_streams()
        try:
            saved = os.dup(1)
        except OSError:  # descriptor 1 closed: hold it with the null device, so that no file opened meanwhile gets it
            null = os.open(os.devnull, os.O_WRONLY)
            if null != 1:
                os.dup2(null, 1)
                os.close(null)
            try:
                yield
            finally:
                _flush_c_streams()
                os.close(1)
            return
        try:
            null = os.open(os.devnull, os.O_WRONLY)
            try:
                os.dup2(null, 1)
            finally:
                os.close(null)
            try:
                yield
            finally:
                _flush_c_streams()
                os.dup2(saved, 1)
        finally:
            os.close(saved)


def quiet_highs(highspy):
    """A new ``highspy.Highs()`` with ``output_flag`` off, built while descriptor 1 is silenced.

    Parameters
    ----------
    highspy : module
        The imported ``highspy`` (the caller decides what to do when it is missing).
    """
    with quiet_fd_stdout():
        h = highspy.Highs()
        h.setOptionValue("output_flag", False)
    return h
