"""What a plan is: in-contact segments, regrasps, the plan and the failure (Section 5.2).

Data only: :func:`qsplan.planner.plan.scripted.plan_task` builds these; the export, plots and
replay read them.  Units SI (m, rad, s, N m).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from qsplan.mechanics.errors import NoAnswerError, QsplanError

from qsplan.planner.search.ompl_bridge import PlannerOptions
from qsplan.planner.task.task import Task

__all__ = ["ContactSegmentPlan", "HoldPhase", "PivotPhase", "Plan", "PlanFailure", "RegraspPhase", "RegraspPlan",
           "ReplacePhase", "SlidePhase"]


class PlanFailure(NoAnswerError):
    """No plan exists: ``report`` (a :class:`qsplan.planner.plan.failure.FailureReport`) says where and why.

    A :class:`qsplan.mechanics.NoAnswerError`, not a ``ValueError``: the task is valid, it has no plan.
    """

    def __init__(self, report, report_path=None):
        super().__init__(report.message)
        self.report = report
        #: Where the report was written as JSON (by :func:`qsplan.planner.pipeline.run.run_plan`), or None.
        self.report_path = report_path


@dataclass(frozen=True, slots=True, eq=False)
class ContactSegmentPlan:
    """An in-contact phase of a plan: the common base of :class:`SlidePhase`, :class:`HoldPhase` and
    :class:`PivotPhase` (``isinstance(ph, ContactSegmentPlan)``: the workpiece held in a contact mode).

    Calling ``ContactSegmentPlan(...)`` itself builds a :class:`SlidePhase` (the kind it built before the phases
    were typed); what differs per kind is each type's fields, class attributes and methods, never a string to test.

    Attributes
    ----------
    name : str
    effort_joint : str
        The torque-controlled finger; the other is velocity-controlled.
    mode : str
    x_path : ndarray, shape (m,)
        The path of the workpiece's x (m): the straight line, start and goal.
    t, x : ndarray, shape (n,)
        Dense samples: time from the plan's start (s) and workpiece x (m).
    q, qd : ndarray, shape (n, 2)
        Joint angles (rad) and velocities (rad/s).
    lower, upper, command, margin : ndarray, shape (n,)
        Guaranteed band, command and its margin (N m) of the effort-controlled joint.
    competitors : tuple of str
        Modes precluded along the segment.
    speed : float
        Workpiece speed (m/s).
    planning : qsplan.planner.search.ompl_bridge.PlanResult
        The dense sweep's outcome (no OMPL query: the path is the straight line).
    speed_scale : ndarray, shape (n,), or None
        The time scaling at each row (:mod:`qsplan.planner.plan.timing`): the fraction of the quasistatic speed
        commanded, 0 at rest (the first and last rows), 1 cruising; None before the time scaling.
    formation : str
        The registered formation (:mod:`qsplan.hands.formations.registry`) naming the phase's contacts.

    Class attributes (per type): ``kind`` (``"slide"``, ``"hold"``, ``"pivot"``: the string ``plan.json`` writes as
    ``phase_kind``, read-only), ``moves`` (False: nothing moves, the rows keep their torque ramp's times),
    ``rest_rows_judged`` (True: the rows at rest already carry the hold proved there; a slide's are judged again by
    the time scaling), ``state_word`` (a row's state in a title, or None: said by the motion), ``title_prefix``
    (before the mode's name in a phase's label).
    """

    name: str
    effort_joint: str
    mode: str
    x_path: np.ndarray
    t: np.ndarray
    x: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    command: np.ndarray
    margin: np.ndarray
    competitors: tuple
    speed: float
    planning: object
    speed_scale: np.ndarray | None = None
    formation: str = "palm_edge"
    in_contact = True  # the workpiece held in a contact mode (a class constant, not a field)
    kind = "slide"
    moves = True
    rest_rows_judged = False
    state_word = None
    title_prefix = ""

    def __new__(cls, *args, **kwargs):
        # the base called directly builds a slide (its one kind before the phases were typed)
        return object.__new__(SlidePhase if cls is ContactSegmentPlan else cls)

    @property
    def width(self) -> np.ndarray:
        return self.upper - self.lower

    @property
    def pose(self) -> np.ndarray | None:
        """The workpiece's pose ``(x, y, theta)`` at each row (m, m, rad), or None: on its palm edge at ``x``."""
        return None

    @property
    def row_modes(self) -> tuple | None:
        """Each row's contact mode, or None: :attr:`mode` at every row."""
        return None

    @property
    def contacts(self) -> tuple | None:
        """Per row, the names of the contacts its mode's letters follow, or None: the formation's."""
        return None

    def poses(self, rest_height: float) -> np.ndarray:
        """The workpiece's pose at every row (m, m, rad), shape (n, 3): :attr:`pose`, or ``(x, rest_height, 0)``."""
        if self.pose is not None:
            return np.asarray(self.pose, dtype=float)
        x = np.broadcast_to(np.asarray(self.x, dtype=float), (self.t.size,))
        return np.column_stack([x, np.full(x.size, float(rest_height)), np.zeros(x.size)])

    def modes(self) -> tuple:
        """Each row's mode letters (:attr:`row_modes`, or :attr:`mode` at every row)."""
        return tuple(self.row_modes) if self.row_modes is not None else (self.mode,) * self.t.size

    def row_contacts(self) -> tuple:
        """Per row, the names of the contacts its mode letters follow: :attr:`contacts`, or the formation's."""
        if self.contacts is not None:
            return tuple(self.contacts)
        from qsplan.hands.formations.registry import formation

        return (tuple(formation(self.formation).contact_names),) * self.t.size


@dataclass(frozen=True, slots=True, eq=False)
class SlidePhase(ContactSegmentPlan):
    """A slide: the workpiece slides on its palm edge (the paper's Fig. 9) in one contact mode, resting at ``x``.

    Its rows at rest (the first and last) are judged again by the time scaling for the chord that leaves or
    reaches them (:mod:`qsplan.planner.plan.timing`); a regrasp after it is preceded by a release hold
    (:mod:`qsplan.planner.plan.release`).
    """

    kind = "slide"


@dataclass(frozen=True, slots=True, eq=False)
class HoldPhase(ContactSegmentPlan):
    """A certified hold: nothing moves while the effort joint's torque ramps (:func:`qsplan.planner.plan.pivot.
    hold_phase`); its rows keep the ramp's times.

    Attributes
    ----------
    pose : ndarray, shape (n, 3), or None
        The workpiece's pose at each row (m, m, rad); None: on its palm edge at ``x``.
    contacts : tuple of tuple of str, or None
        Per row, the names of the contacts its mode's letters follow; None: the formation's.
    """

    pose: np.ndarray | None = None
    contacts: tuple | None = None
    kind = "hold"
    moves = False
    rest_rows_judged = True
    state_word = "holding"
    title_prefix = "hold: "


@dataclass(frozen=True, slots=True, eq=False)
class PivotPhase(ContactSegmentPlan):
    """A pivot (a piece of one): the workpiece turns on a palm vertex (:func:`qsplan.planner.plan.pivot.
    piece_phase`).  The first piece's first row is the transition at the flush instant: its mode has the lifting
    vertex's letter ``B`` (:attr:`transition`), the later rows judged without that contact.

    Attributes
    ----------
    pose : ndarray, shape (n, 3)
        The workpiece's pose at each row (m, m, rad).
    row_modes : tuple of str, or None
        Each row's contact mode, one letter per contact the row is judged with (:attr:`contacts`).
    contacts : tuple of tuple of str, or None
        Per row, the names of the contacts its mode's letters follow; None: the formation's.
    """

    pose: np.ndarray | None = None
    row_modes: tuple | None = None
    contacts: tuple | None = None
    kind = "pivot"
    rest_rows_judged = True
    state_word = "pivoting"
    title_prefix = "pivot: "

    @property
    def transition(self) -> bool:
        """Whether the first row is the transition at the flush instant (a contact breaking: a ``B`` letter)."""
        return "B" in self.modes()[0]


@dataclass(frozen=True, slots=True, eq=False)
class RegraspPhase:
    """A free-space finger motion: release and regrasp at a fixed workpiece x.

    Attributes
    ----------
    name : str
    x : float
        Workpiece x (m) meanwhile.
    t : ndarray, shape (n,)
        Times (s) from the plan's start.
    q, qd : ndarray, shape (n, 2)
        Joint angles (rad) and velocities (rad/s), both joints velocity-controlled.
    planning : tuple of qsplan.planner.search.ompl_bridge.PlanResult
        Opening and closing.
    speed_scale : ndarray, shape (n,), or None
        As :attr:`ContactSegmentPlan.speed_scale`: 0 at every row where the straight-line motion turns.
    """

    name: str
    x: float
    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    planning: tuple
    speed_scale: np.ndarray | None = None
    in_contact = False  # the fingers move in free space (a class constant, not a field)
    kind = "regrasp"

    def poses(self, rest_height: float) -> np.ndarray:
        """The workpiece's pose at every row (m, m, rad), shape (n, 3): resting on its palm edge at ``x``."""
        return np.tile([float(self.x), float(rest_height), 0.0], (self.t.size, 1))

    def free_metadata(self) -> dict:
        """What ``plan.json`` adds to the phase's ``kind`` and ``x_workpiece_m``: nothing for a regrasp on the palm."""
        return {}

    def label(self) -> tuple:
        """``(what, control)`` in words, for plots: ``("regrasp", "fingers velocity")``."""
        return "regrasp", "fingers velocity"

    def title(self) -> str:
        """What the hand does, in a plot's title."""
        return "regrasp, every joint velocity-controlled"

    def does(self, who: str) -> str:
        """The card's cell: ``who`` (the fingers that leave the workpiece, in words) and what they do."""
        return f"regrasp: {who}\nopen and close again"


RegraspPlan = RegraspPhase  # its name before the phases were typed (users' scripts import it)


@dataclass(frozen=True, slots=True, eq=False)
class ReplacePhase(RegraspPhase):
    """One finger lifted and replaced during a turn (:func:`qsplan.planner.plan.replace.replace_phase`): the workpiece
    rests at ``pose`` on the palm and the other finger, every joint of which is held, while ``finger`` opens, moves
    through OMPL and closes on a new feature (its free joints possibly held elsewhere afterwards).  Nothing moves: the
    hold with ``finger`` lifted is proved over the task's whole friction box and disturbance box
    (:func:`qsplan.mechanics.bands.friction_hold.prove_friction_hold`), every row.

    Attributes
    ----------
    pose : ndarray, shape (3,)
        The workpiece's pose meanwhile (m, m, rad).
    finger : str
        The finger that moves (``"left"`` or ``"right"``).
    kept : tuple of str
        The contacts that hold the workpiece meanwhile (canonical names, :func:`qsplan.hands.contacts.found.
        contact_names`).
    hold_margin : float
        The proof's certified margin at rest (N, :attr:`qsplan.mechanics.bands.friction_hold.FrictionHold.
        rest_margin`).
    """

    pose: np.ndarray | None = None
    finger: str = "right"
    kept: tuple = ()
    hold_margin: float = float("nan")
    kind = "replace"

    def poses(self, rest_height: float) -> np.ndarray:
        """The workpiece's pose at every row (m, m, rad), shape (n, 3): held at :attr:`pose`."""
        return np.tile(np.asarray(self.pose, dtype=float), (self.t.size, 1))

    def label(self) -> tuple:
        """``(what, control)`` in words, for plots: ``("right finger replaced", "right finger velocity")``."""
        return f"{self.finger} finger replaced", f"{self.finger} finger velocity"

    def title(self) -> str:
        other = "left" if self.finger == "right" else "right"
        return f"the {self.finger} finger replaced, every joint velocity-controlled (the {other} finger held)"

    def does(self, who: str) -> str:
        other = "left" if self.finger == "right" else "right"
        return f"the {self.finger} finger replaced:\nthe {other} finger and palm hold"

    def free_metadata(self) -> dict:
        """``phase_kind`` ``replace``, the ``finger`` that moves, the workpiece's ``y_workpiece_m`` and
        ``theta_workpiece_rad``, and the ``contacts_kept`` that hold it (the certifier checks each against the rows)."""
        return {"phase_kind": self.kind, "finger": self.finger, "y_workpiece_m": float(self.pose[1]),
                "theta_workpiece_rad": float(self.pose[2]), "contacts_kept": list(self.kept)}


@dataclass(frozen=True, slots=True, eq=False)
class Plan:
    """A task's plan: in-contact segments and regrasps, in order.

    Attributes
    ----------
    task : qsplan.planner.task.task.Task
    phases : tuple of (SlidePhase, HoldPhase, PivotPhase or RegraspPhase)
    seconds : float
        Wall-clock planning time (s), OMPL and sweeps.
    validity_checks : int
        States judged: the in-contact segments' dense-sweep samples (each once) plus OMPL's
        validity-checker calls on the regrasps.
    ompl_seconds : float
        Time judging them (s): the in-contact dense sweeps (scenes, overlaps, guaranteed bands)
        plus the regrasps' OMPL queries; ``checks_per_second`` is their ratio.
    options : PlannerOptions
    sequence : tuple
        The sequence the planner chose (automatic planning, :mod:`qsplan.planner.search`): one typed step per
        phase (:class:`qsplan.planner.plan.steps.SlideStep`, :class:`~qsplan.planner.plan.steps.RegraspStep`),
        then the search's :class:`~qsplan.planner.plan.steps.SearchSummary`; empty for a scripted task.
    timing : tuple of qsplan.planner.plan.timing.PhaseTiming
        Each phase's time scaling (stops and acceleration limits, :mod:`qsplan.planner.plan.timing`); empty before it.
    """

    task: Task
    phases: tuple
    seconds: float
    validity_checks: int
    ompl_seconds: float
    options: PlannerOptions = field(default_factory=PlannerOptions)
    sequence: tuple = ()
    timing: tuple = ()

    @property
    def segments(self) -> tuple:
        return tuple(p for p in self.phases if isinstance(p, ContactSegmentPlan))

    @property
    def duration(self) -> float:
        return float(self.phases[-1].t[-1])

    @property
    def search(self):
        """The route search's :class:`~qsplan.planner.plan.steps.SearchSummary`, None for a scripted plan."""
        from qsplan.planner.plan.steps import search_summary

        return search_summary(self.sequence)

    @property
    def checks_per_second(self) -> float:
        return self.validity_checks / self.ompl_seconds if self.ompl_seconds > 0 else float("nan")

    def sample(self, times):
        """This plan at controller ticks ``times`` (s, strictly increasing, within the plan): per tick each joint's
        control mode (``velocity``, ``torque``, ``hold``) and command, by the rule of :mod:`qsplan.planner.plan.sampling`
        (e.g. ``plan.sample(tick_times(plan.duration, 1000))``); a :class:`~qsplan.planner.plan.sampling.PlanSamples`."""
        from qsplan.planner.plan.sampling import sample_columns
        from qsplan.planner.plan.table import plan_columns

        cols, units = plan_columns(self)
        return sample_columns({k: np.asarray(v) for k, v in cols.items()}, units, times)

    def narrowest(self):
        """``(segment name, t, width)`` of the narrowest guaranteed band of the plan (s, N m; width inf when
        every band is unbounded)."""
        best = None
        for s in self.segments:
            k = int(np.argmin(s.width))
            if best is None or s.width[k] < best[2]:
                best = (s.name, float(s.t[k]), float(s.width[k]))
        return best or (None, np.nan, np.inf)

    def check(self) -> None:
        """Raise :class:`qsplan.mechanics.QsplanError` unless every command lies in its band with a positive margin."""
        for s in self.segments:
            bad = ~((s.command > s.lower) & (s.command < s.upper) & (s.margin > 0))
            if bad.any():
                k = int(np.flatnonzero(bad)[0])
                raise QsplanError(f"plan: {s.name}: command {s.command[k]:.6g} N m outside its band "
                                  f"[{s.lower[k]:.6g}, {s.upper[k]:.6g}] at t = {s.t[k]:.4g} s")  # fmt: skip

