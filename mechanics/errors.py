"""The qsplan exception hierarchy.

Every error raised on bad input is a :class:`QsplanError`, which subclasses
``ValueError`` so that generic callers can still catch it.  Messages name the
field, what was expected and what was received.
"""

from __future__ import annotations

__all__ = ["QsplanError", "SceneError", "ModeError"]


class QsplanError(ValueError):
    """Base class of every error qsplan raises on bad input."""


class SceneError(QsplanError):
    """A scene (file or value) is malformed: wrong shape, non-finite, unknown field."""


class ModeError(QsplanError):
    """A contact mode is malformed (wrong length, unknown letter) or does not fit the scene."""
