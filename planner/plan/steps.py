"""The planned sequence as typed values: the steps the route search chose and the search's figures (issue 22).

An automatic plan (:func:`qsplan.planner.plan.autoplan.plan_automatic`) records what its search chose, one
frozen step per phase, and a :class:`SearchSummary`.  ``plan.json`` writes them under ``metadata.sequence``
(:meth:`as_dict`), described by the export schema; the keys are the same for every hand.  Each step's
``as_dict`` gives the unit-suffixed keys (``x_from_m``, ``narrowest_band``'s unit in ``effort_unit``) and, beside
them, the keys earlier plans wrote (``x_from``, ``x``, ``from``, ``to``): extended, never renamed.

Units: SI (m, s; the narrowest band in the effort joint's unit, N m or N).  Room for the next formations'
transitions: a new step type with a ``kind``, ``as_dict`` and ``realised``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

__all__ = ["HoldStep", "PivotStep", "RegraspStep", "ReplaceStep", "SearchSummary", "SlideStep", "realised_steps", "route_steps",
           "search_summary", "step_dicts"]


def _finite(v) -> float | None:
    return float(v) if v is not None and math.isfinite(v) else None


@dataclass(frozen=True, slots=True)
class SlideStep:
    """An in-contact slide of the route.

    Attributes
    ----------
    grasp : str
        The grasp's label (what each finger touches; a hand with free joints: their values).
    x_from, x_to : float
        Workpiece ``x`` at its ends (m).
    effort_joint : str
        The effort-controlled joint.
    narrowest_band : float
        Its narrowest guaranteed band along the slide, in the joint's effort unit (inf: unbounded).
    effort_unit : str
        ``"N m"`` (revolute) or ``"N"`` (prismatic).
    """

    grasp: str
    x_from: float
    x_to: float
    effort_joint: str
    narrowest_band: float
    effort_unit: str = "N m"
    kind = "slide"

    def as_dict(self) -> dict:
        band = _finite(self.narrowest_band)
        return {"kind": self.kind, "grasp": self.grasp, "x_from_m": self.x_from, "x_to_m": self.x_to,
                "effort_joint": self.effort_joint, "narrowest_band": band, "effort_unit": self.effort_unit,
                "x_from": self.x_from, "x_to": self.x_to}  # fmt: skip

    def realised(self, phase) -> SlideStep:
        """This step with its ends and narrowest band as ``phase`` (its slide's rows) realises them."""
        x = np.ravel(phase.x)
        return replace(self, narrowest_band=float(np.min(phase.upper - phase.lower)), x_from=float(x[0]),
                       x_to=float(x[-1]))


@dataclass(frozen=True, slots=True)
class RegraspStep:
    """A regrasp of the route: the workpiece rests on the palm at ``x`` (m) while the fingers move.

    Attributes
    ----------
    x : float
    grasp_from, grasp_to : str
        The labels of the grasps released and taken.
    """

    x: float
    grasp_from: str
    grasp_to: str
    kind = "regrasp"

    def as_dict(self) -> dict:
        return {"kind": self.kind, "x_from_m": self.x, "x_to_m": self.x, "grasp_from": self.grasp_from,
                "grasp_to": self.grasp_to, "x": self.x, "from": self.grasp_from, "to": self.grasp_to}  # fmt: skip

    def realised(self, phase) -> RegraspStep:
        """This step: the rows of a regrasp change none of its figures."""
        return self


@dataclass(frozen=True, slots=True)
class HoldStep:
    """A certified hold of the route (:mod:`qsplan.planner.plan.turning`): nothing moves at workpiece ``x`` (m) and
    angle ``theta`` (rad) while ``effort_joint``'s torque ramps ``torque_from`` -> ``torque_to`` inside the proved
    interval ``[proved_lower, proved_upper]`` (N m; inf: unbounded)."""

    x: float
    theta: float
    effort_joint: str
    torque_from: float
    torque_to: float
    proved_lower: float
    proved_upper: float
    kind = "hold"

    def as_dict(self) -> dict:
        return {"kind": self.kind, "x_from_m": self.x, "x_to_m": self.x, "theta_rad": self.theta,
                "effort_joint": self.effort_joint, "torque_from": self.torque_from, "torque_to": self.torque_to,
                "proved_interval": [_finite(self.proved_lower), _finite(self.proved_upper)]}  # fmt: skip

    def realised(self, phase) -> HoldStep:
        """This step: a hold's figures are its rows' already (the torques ramped, the proved interval)."""
        return self


@dataclass(frozen=True, slots=True)
class ReplaceStep:
    """A finger replaced mid-turn (:mod:`qsplan.planner.plan.replace`): at workpiece ``x`` (m) and angle ``theta``
    (rad) the workpiece rests on the contacts ``kept`` (canonical names), every joint held, while ``finger`` lifts, moves
    and closes on ``feature`` (the new formation's name, :attr:`qsplan.hands.formations.pivots.Pivot.name`); the hold is
    proved over the friction box (``hold_margin``, N: the proof's certified margin at rest)."""

    x: float
    theta: float
    finger: str
    kept: tuple
    formation: str
    hold_margin: float
    kind = "replace"

    def as_dict(self) -> dict:
        return {"kind": self.kind, "x_from_m": self.x, "x_to_m": self.x, "theta_rad": self.theta,
                "finger": self.finger, "contacts_kept": list(self.kept), "formation": self.formation,
                "hold_margin_N": _finite(self.hold_margin)}  # fmt: skip

    def realised(self, phase) -> ReplaceStep:
        """This step: the rows of a replacement change none of its figures."""
        return self


@dataclass(frozen=True, slots=True)
class PivotStep:
    """A pivot of the route: the workpiece turns on its vertex ``vertex`` (as the task writes it) on the palm from
    ``theta_from`` to ``theta_to`` (rad), ``effort_joint`` torque-controlled, its narrowest band ``narrowest_band``
    (N m; inf: unbounded)."""

    vertex: int
    theta_from: float
    theta_to: float
    effort_joint: str
    narrowest_band: float
    kind = "pivot"

    def as_dict(self) -> dict:
        return {"kind": self.kind, "vertex": self.vertex, "theta_from_rad": self.theta_from,
                "theta_to_rad": self.theta_to, "effort_joint": self.effort_joint,
                "narrowest_band": _finite(self.narrowest_band), "effort_unit": "N m"}  # fmt: skip

    def realised(self, phase) -> PivotStep:
        """This step with its narrowest band as ``phase`` (the pivot's rows, time-scaled) realises it."""
        return replace(self, narrowest_band=float(np.min(phase.upper - phase.lower)))


@dataclass(frozen=True, slots=True)
class SearchSummary:
    """What the route search did (:mod:`qsplan.planner.search`).

    Attributes
    ----------
    planner : str
        The search that found the route (``"widest"``: the exact widest route; ``"RRTstar"``, ``"BITstar"``).
    rounds : int
        Searches run (a route the realisation refused is searched again without the refused cell).
    grasps, grid_points : int
        The band tables' rows and positions; ``grid_step_m`` their spacing (m).
    table_states, band_states : int
        Configurations in the tables; guaranteed bands computed.
    table_seconds, search_seconds : float
    search_evaluations : int
    route_width : float
        The route's narrowest band (N m; inf: unbounded).
    grid_step_m : float
    """

    planner: str
    rounds: int
    grasps: int
    grid_points: int
    grid_step_m: float
    table_states: int
    band_states: int
    table_seconds: float
    search_seconds: float
    search_evaluations: int
    route_width: float
    kind = "search"

    def as_dict(self) -> dict:
        return {"kind": self.kind, "planner": self.planner, "rounds": self.rounds, "grasps": self.grasps,
                "grid_points": self.grid_points, "grid_step_m": self.grid_step_m, "table_states": self.table_states,
                "band_states": self.band_states, "table_seconds": self.table_seconds,
                "search_seconds": self.search_seconds, "search_evaluations": self.search_evaluations,
                "route_width": _finite(self.route_width)}  # fmt: skip


def search_summary(sequence) -> SearchSummary | None:
    """The :class:`SearchSummary` of a plan's ``sequence`` (None for a scripted plan)."""
    return next((s for s in sequence if isinstance(s, SearchSummary)), None)


def route_steps(sequence) -> tuple:
    """The steps of a plan's ``sequence`` (one per phase when the plan has them), without the search's summary."""
    return tuple(s for s in sequence if not isinstance(s, SearchSummary))


def realised_steps(sequence, phases) -> tuple:
    """``sequence`` with each step's figures as ``phases`` (one per step, in order: the plan's) realise them
    (:meth:`SlideStep.realised`: a slide's ends and narrowest band; a pivot's narrowest band): the time scaling judges
    a slide's rows at rest again, and a reorientation moves its slide's last row onto the flush instant, so the
    search's figures may differ from the rows the plan exports (and ``plan.json`` states; the certifier checks them
    against the rows)."""
    if len(route_steps(sequence)) != len(phases):
        return tuple(sequence)
    realised = iter(s.realised(ph) for s, ph in zip(route_steps(sequence), phases))
    return tuple(s if isinstance(s, SearchSummary) else next(realised) for s in sequence)


def step_dicts(sequence) -> list:
    """``metadata.sequence``: each step's and the summary's :meth:`as_dict`, in order."""
    return [s.as_dict() for s in sequence]
