"""The qsplan exception hierarchy: bad input, and valid input without an answer.

* :class:`QsplanError` (a ``ValueError``): the input is wrong.  Every error raised on bad
  input is one; messages name the field, what was expected and what was received.
  :class:`SceneError` and :class:`ModeError` narrow it down.
* :class:`NoAnswerError` (a ``RuntimeError``, deliberately **not** a ``ValueError``): the input
  is fine but no answer exists (no plan, no guaranteed band, no feasible mode).  Callers that
  catch ``ValueError`` for bad input do not swallow it by accident.
* :class:`ParallelError` (a ``RuntimeError``, neither of the above): the input is fine and an
  answer may exist, but the processes computing it failed (a local worker lost twice, a Dask
  cluster that made no progress).  Nobody may read it as "no answer".

Library messages name library fields (``mu``, ``out_dir``, ``workers``), never command-line
flags: the CLI translates.
"""

from __future__ import annotations

__all__ = ["QsplanError", "SceneError", "ModeError", "NoAnswerError", "ParallelError"]


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


class ParallelError(RuntimeError):
    """The processes running chunks of work failed: a local worker died twice, or a Dask cluster
    made no progress for :data:`qsplan.mechanics.parallel.NO_PROGRESS_TIMEOUT` seconds.

    Neither bad input nor a proof that no answer exists: rerunning (in-process, or on a
    healthy cluster) gives the answer.
    """
