"""The qsplan exception hierarchy: bad input, and valid input without an answer.

* :class:`QsplanError` (a ``ValueError``): the input is wrong.  Every error raised on bad
  input is one; messages name the field, what was expected and what was received.
  :class:`SceneError` and :class:`ModeError` narrow it down.
* :class:`NoAnswerError` (a ``RuntimeError``, deliberately **not** a ``ValueError``): the input
  is fine but no answer exists (no plan, no guaranteed band, no feasible mode).  Callers that
  catch ``ValueError`` for bad input do not swallow it by accident.

Library messages name library fields (``mu``, ``out_dir``, ``workers``), never command-line
flags: the CLI translates.
"""

from __future__ import annotations

__all__ = ["QsplanError", "SceneError", "ModeError", "NoAnswerError"]


class QsplanError(ValueError):
    """Base class of every error qsplan raises on bad input."""


class SceneError(QsplanError):
    """A scene (file or value) is malformed: wrong shape, non-finite, unknown field."""


class ModeError(QsplanError):
    """A contact mode is malformed (wrong length, unknown letter) or does not fit the scene."""


class NoAnswerError(RuntimeError):
    """Valid input without an answer: no plan, no guaranteed band, no feasible mode exists.

    Not a ``ValueError``: nothing is wrong with the input.  Subclasses (e.g.
    :class:`qsplan.planner.PlanFailure`) carry the report of why.
    """
