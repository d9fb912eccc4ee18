"""The result of a finite motion (Section 5.1): segments in one contact mode, events, and why it stopped."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qsplan.mechanics.modes.contact_mode import ContactMode
from qsplan.mechanics.modes.solution import ModeSolution

__all__ = ["STOP_KINDS", "Segment", "Stop", "Motion", "mode_label"]

#: Why a motion stopped before its duration.
STOP_KINDS = ("ambiguous", "jam", "no_persistent_mode", "zeno", "limit", "max_switches")


@dataclass(frozen=True, slots=True, eq=False)
class Segment:
    """A stretch of motion in one contact mode.

    Attributes
    ----------
    mode : ContactMode
        Over the contacts in contact, in the order of ``contacts``.
    contacts : tuple of int
        Indices of the system's potential contacts in contact during the segment.
    n_potential : int
        Number of potential contacts of the system.
    t_start, t_end : float
        s.
    times : ndarray, shape (k,)
        Integration instants, from ``t_start`` to ``t_end``.
    states : ndarray, shape (k, n_x)
    mu : ndarray, shape (n_c,)
        Friction used: static at rolling and breaking contacts, kinetic at sliding ones.
    solution : ModeSolution
        The mode's solution at ``t_start`` (forces, velocities, residuals).
    ended_by : str
        ``"duration"`` or the kind of the :class:`~qsplan.mechanics.motion.events.Event` that ended it.
    """

    mode: ContactMode
    contacts: tuple
    n_potential: int
    t_start: float
    t_end: float
    times: np.ndarray
    states: np.ndarray
    mu: np.ndarray
    solution: ModeSolution
    ended_by: str

    @property
    def duration(self) -> float:
        return self.t_end - self.t_start

    @property
    def x_start(self) -> np.ndarray:
        return self.states[0]

    @property
    def x_end(self) -> np.ndarray:
        return self.states[-1]

    @property
    def label(self) -> str:
        """One letter per *potential* contact: R, S, B, or ``-`` when not in contact."""
        return mode_label(self.mode, self.contacts, self.n_potential)


@dataclass(frozen=True, slots=True, eq=False)
class Stop:
    """Why and where a motion stopped before its duration.

    Attributes
    ----------
    kind : str
        One of :data:`STOP_KINDS`.
    time : float
        s.
    state : ndarray, shape (n_x,)
    candidates : tuple of str
        Mode labels feasible at that instant (for ``ambiguous``: the persistent ones).
    message : str
        One sentence for people, with the numbers.
    """

    kind: str
    time: float
    state: np.ndarray
    candidates: tuple
    message: str


@dataclass(frozen=True, slots=True, eq=False)
class Motion:
    """A simulated finite motion: its segments, events and how it ended.

    Attributes
    ----------
    system : MotionSystem
    segments : tuple of Segment
    events : tuple of Event
        Every instant where a segment ended (switches, contacts appearing, stops).
    stopped : Stop or None
        None when the motion reached its duration.
    duration : float
        Requested duration (s).
    """

    system: object
    segments: tuple
    events: tuple
    stopped: Stop | None
    duration: float

    @property
    def times(self) -> np.ndarray:
        """All integration instants, shape (k,) (segment ends repeat as the next start)."""
        return np.concatenate([s.times for s in self.segments]) if self.segments else np.zeros(0)

    @property
    def states(self) -> np.ndarray:
        """All integrated states, shape (k, n_x)."""
        n_x = len(self.system.state_names)
        return np.concatenate([s.states for s in self.segments]) if self.segments else np.zeros((0, n_x))

    @property
    def switch_times(self) -> np.ndarray:
        """Instants where one segment ended and the next began, shape (len(segments) - 1,)."""
        return np.array([s.t_end for s in self.segments[:-1]])

    @property
    def labels(self) -> list[str]:
        """Mode label of each segment (see :attr:`Segment.label`)."""
        return [s.label for s in self.segments]


def mode_label(mode, contacts, n_potential) -> str:
    """One character per potential contact: the mode's letter at ``contacts``, ``-`` elsewhere."""
    out = ["-"] * n_potential
    for letter, i in zip(mode.letters, contacts):
        out[i] = letter
    return "".join(out)
