"""Why a segment has no plan: where the guaranteed band closes, what closes it, at which friction.

:func:`failure_report` samples the straight line between a segment's start and
goal (the only route in its one configuration variable) and judges each
configuration with :func:`qsplan.planner.states.contact.check_contact_state`.  Where the band is
narrower than the torque resolution it names the cause: the desired mode's own
guaranteed band (then the friction values at the box corners where its lower
and upper edges are attained), or a competing mode possible inside it (eq. 28);
and, at the narrowest point, the friction upper bound at which the band shrinks
to the resolution (bisection on the range's upper end).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from itertools import product

import numpy as np

__all__ = ["NOT_RUN_BAND_AT_END", "NOT_RUN_GOAL", "NOT_RUN_INVALID", "SEARCHED_BANDS", "ClosedPoint",
           "ConfigurationReport", "FailureReport", "GoalReport", "PalmReport", "StepReport", "configuration_report",
           "failure_report", "palm_report"]

#: Configurations sampled along the straight line of a failed segment.
REPORT_SAMPLES = 21

#: ``planner_status`` of a report refused before any planning: a start or goal configuration not valid.
NOT_RUN_INVALID = "not run (start or goal invalid)"

#: ``planner_status`` of a segment whose start or goal state already has no band: its sweep is not run.
NOT_RUN_BAND_AT_END = "not run (no guaranteed band at the segment's start or goal)"

#: ``planner_status`` of the sequence search's band report: the search ran over the band tables, and every route it
#: found has a band narrower than the torque resolution, or none.
SEARCHED_BANDS = "ran: the sequence search over the band tables; no route keeps a band at least the resolution wide"

#: ``planner_status`` of a goal the planner does not serve (refused by name before planning).
NOT_RUN_GOAL = "not run (a goal the planner does not serve)"


@dataclass(frozen=True, slots=True)
class ClosedPoint:
    """A configuration where the segment's state is not valid.

    Attributes
    ----------
    x : float
        Workpiece x (m).
    reason : str
    width : float
        Guaranteed band width (N m), competitors precluded; NaN without a band.
    desired_width : float
        Width of the desired mode's guaranteed band before preclusion (N m).
    competitors : tuple of str
        Competing modes possible inside the desired mode's band.
    mu_lower_edge, mu_upper_edge : tuple of float or None
        Per-contact friction (a corner of the box) where the desired band's lower / upper edge is attained.
    """

    x: float
    reason: str
    width: float
    desired_width: float
    competitors: tuple
    mu_lower_edge: tuple | None = None
    mu_upper_edge: tuple | None = None


@dataclass(frozen=True, slots=True, eq=False)
class FailureReport:
    """Why a segment has no plan.

    Attributes
    ----------
    segment : str
    x_start, x_goal : float
        m.
    effort_joint : str
    resolution : float
        N m.
    mu_range : (float, float)
    planner_status : str
        OMPL's status ("not run" when the start or goal was invalid).
    closed : tuple of ClosedPoint
        Every invalid configuration on the straight line, in order.
    narrowest : ClosedPoint or None
        The narrowest one.
    mu_closes : float or None
        At the narrowest point: the upper end of the friction range at which the band is exactly the resolution
        (None if it is narrower even for the range's lower end alone, or the cause is not the band).
    mode_name : str
        The desired mode's name (the paper's: ``"4S"``).
    """

    segment: str
    x_start: float
    x_goal: float
    effort_joint: str
    resolution: float
    mu_range: tuple
    planner_status: str
    closed: tuple
    narrowest: ClosedPoint | None
    mu_closes: float | None
    mode_name: str = "4S"

    @property
    def message(self) -> str:
        n = self.narrowest
        head = f"no plan: {self.segment}"
        if n is None:  # every sample valid on its own: the sweep refused what only the whole slide shows
            return f"{head}: refused ({self.planner_status}) though every configuration is valid on its own"
        xs = [p.x for p in self.closed]
        where = f"x in [{min(xs):.4g}, {max(xs):.4g}] m ({len(xs)} of {REPORT_SAMPLES} configurations)"
        why = n.reason
        if n.competitors:
            why += f"; closed by competing mode {', '.join(n.competitors)}"
        elif np.isfinite(n.desired_width) and n.desired_width < self.resolution:
            why += f"; closed by the {self.mode_name} band itself"
        if n.mu_lower_edge is not None:
            why += f" (edges attained at mu = {list(n.mu_lower_edge)} and {list(n.mu_upper_edge)})"
        if self.mu_closes is not None:
            why += f"; with mu in [{self.mu_range[0]:g}, {self.mu_closes:.4g}] the band there is {self.resolution:g} N m wide, narrower above"
        return f"{head}: band closes at {where}; narrowest at x = {n.x:.4g} m: {why}"

    def as_dict(self) -> dict:
        def point(p):
            return None if p is None else {"x_m": p.x, "reason": p.reason, "width_N_m": _num(p.width),
                                           "desired_width_N_m": _num(p.desired_width), "competitors": list(p.competitors),
                                           "mu_lower_edge": p.mu_lower_edge, "mu_upper_edge": p.mu_upper_edge}  # fmt: skip

        return {"kind": "band closes", "segment": self.segment, "x_start_m": self.x_start, "x_goal_m": self.x_goal,
                "effort_joint": self.effort_joint, "resolution_N_m": self.resolution, "mu_range": list(self.mu_range),
                "planner_status": self.planner_status, "closed": [point(p) for p in self.closed],
                "narrowest": point(self.narrowest), "mu_closes": self.mu_closes, "message": self.message}  # fmt: skip


@dataclass(frozen=True, slots=True, eq=False)
class ConfigurationReport:
    """Why a plan is refused at one configuration: a start, goal or regrasp pose, or a state on a path,
    where a joint is beyond its limit, two bodies overlap, there is no grasp or OMPL found no motion.

    Attributes
    ----------
    phase : str
        The segment or regrasp concerned.
    where : str
        Which configuration, in words ("the start", "the goal", ...).
    x : float
        Workpiece x (m).
    q : tuple of float or None
        Joint angles (rad), None where no grasp exists.
    reason : str
    bodies : tuple of str
        The two overlapping bodies ("left finger", "right finger", "palm", "workpiece"), or ().
    overlap_area, overlap_depth : float or None
        Of that overlap (m^2, m).
    planner_status : str
        What planning had done when it stopped here (:data:`NOT_RUN_INVALID` when the start or goal is refused
        before planning; OMPL's status for a regrasp; what a turning route had planned before this step).
    pose : tuple of float or None
        The workpiece's pose ``(x, y, theta)`` (m, m, rad) where it is not the palm-edge formation's at ``x``
        (a pivot's row); None: resting on its bottom edge at ``x``.
    """

    phase: str
    where: str
    x: float
    q: tuple | None
    reason: str
    bodies: tuple = ()
    overlap_area: float | None = None
    overlap_depth: float | None = None
    planner_status: str = NOT_RUN_INVALID
    pose: tuple | None = None

    @property
    def message(self) -> str:
        at = f"workpiece x = {self.x:.4g} m" + ("" if self.q is None else f", q = {[round(v, 4) for v in self.q]} rad")
        return f"no plan: {self.reason} at {self.where} ({at}; {self.phase})"

    def as_dict(self) -> dict:
        return {"kind": "invalid configuration", "segment": self.phase, "where": self.where, "x_m": self.x,
                "q_rad": None if self.q is None else list(self.q), "reason": self.reason, "bodies": list(self.bodies),
                "overlap_area_m2": self.overlap_area, "overlap_depth_m": self.overlap_depth,
                "planner_status": self.planner_status, "pose": None if self.pose is None else list(self.pose),
                "message": self.message}  # fmt: skip


@dataclass(frozen=True, slots=True, eq=False)
class PalmReport:
    """Why a task has no plan, known from its geometry before any planning: a workpiece x it names puts the
    workpiece's resting edge beyond an end of the palm (no grasp has its two palm contacts there).

    Attributes
    ----------
    where : str
        Which position, in words ("the start", "the goal", "the end of segment 1").
    field : str
        The task field that names it (``motion.start_x``, ``motion.waypoints[k]``, ``goal.x``).
    x : float
        That workpiece x (m).
    x_range : (float, float)
        The workpiece x (m) for which the resting edge lies on the palm
        (:func:`qsplan.planner.task.goal.palm_x_range`).
    edge : (float, float)
        The resting edge's ends (m) at ``x``.
    side : str
        ``"left"`` or ``"right"``: the end of the palm the edge passes,
    palm_end : float
        at this x (m).
    """

    where: str
    field: str
    x: float
    x_range: tuple
    edge: tuple
    side: str
    palm_end: float

    @property
    def message(self) -> str:
        lo, hi = self.x_range
        return (f"no plan: {self.where} x = {self.x:.4g} m ({self.field}) puts the workpiece's resting edge (from x = "
                f"{self.edge[0]:.4g} to {self.edge[1]:.4g} m) beyond the palm's {self.side} end at {self.palm_end:.4g} "
                f"m; the workpiece rests on the palm for x in [{lo:.4g}, {hi:.4g}] m")  # fmt: skip

    def as_dict(self) -> dict:
        return {"kind": "beyond the palm", "where": self.where, "field": self.field, "x_m": self.x,
                "x_range_m": list(self.x_range), "resting_edge_m": list(self.edge), "side": self.side,
                "palm_end_m": self.palm_end, "planner_status": "not run (refused from the task's geometry)",
                "message": self.message}  # fmt: skip


@dataclass(frozen=True, slots=True, eq=False)
class GoalReport:
    """Why a task has no plan, known from its goal before any planning: a valid goal the planner does not serve
    (:class:`qsplan.planner.task.goal.GoalNotServedError`: its field and message, kept word for word).

    Attributes
    ----------
    field : str
        The goal's field (``goal.theta``, ``goal.palm``, ``goal.x``).
    reason : str
        What exists and what is missing (the error's message, which starts with the field).
    """

    field: str
    reason: str

    @classmethod
    def from_error(cls, error) -> "GoalReport":
        """The report of a :class:`qsplan.planner.task.goal.GoalNotServedError`."""
        return cls(error.field, str(error))

    @property
    def message(self) -> str:
        return self.reason

    def as_dict(self) -> dict:
        return {"kind": "goal not served", "field": self.field, "reason": self.reason, "planner_status": NOT_RUN_GOAL,
                "message": self.message}  # fmt: skip


@dataclass(frozen=True, slots=True, eq=False)
class StepReport:
    """A failure inside one step of a route the planner chose (the slide to a turn's flush instant): the step in
    words, the task that step was planned as (its goal the step's end: what a drawing of ``report`` reads), and the
    step's own report.

    Attributes
    ----------
    step : str
    task : qsplan.planner.task.task.Task
    report : FailureReport, ConfigurationReport, PalmReport or NoRouteReport
    """

    step: str
    task: object
    report: object

    @property
    def message(self) -> str:
        return f"no plan: {self.step}: {self.report.message.removeprefix('no plan: ')}"

    def as_dict(self) -> dict:
        return {**self.report.as_dict(), "route_step": self.step, "message": self.message}


def palm_report(task) -> PalmReport | None:
    """The first workpiece x of ``task`` (its start, waypoints, goal) beyond the palm (a :class:`PalmReport`), or None.

    Exact (no tolerance): ``x`` in :func:`qsplan.planner.task.goal.palm_x_range`, ends included, passes.
    """
    from qsplan.planner.task.goal import palm_x_range, task_positions

    lo, hi = palm_x_range(task.hand)
    V = task.hand.workpiece
    for where, field, x in task_positions(task):
        if lo <= x <= hi:
            continue
        edge = (x + float(V[0, 0]), x + float(V[1, 0]))
        side, end = ("left", lo + float(V[0, 0])) if x < lo else ("right", hi + float(V[1, 0]))
        return PalmReport(where, field, x, (lo, hi), edge, side, end)
    return None


def configuration_report(task, phase, where, x, q, reason=None, planner_status=None, pose=None) -> ConfigurationReport:
    """The report of configuration ``q`` (rad, or None) at workpiece ``x`` (m): ``reason`` if given, else what
    :func:`qsplan.planner.states.contact.configuration_problem` finds (with the colliding bodies); ``pose``
    ``(x, y, theta)`` where the workpiece does not rest on its bottom edge (:attr:`ConfigurationReport.pose`)."""
    from qsplan.planner.states.contact import limit_problem

    kw = {} if planner_status is None else {"planner_status": planner_status}
    if pose is not None:
        kw["pose"] = tuple(float(v) for v in pose)
    if q is None:
        return ConfigurationReport(phase, where, float(x), None, reason or "no grasp", **kw)
    q = np.asarray(q, float)
    qt = tuple(float(v) for v in q)
    if reason is None:
        reason = limit_problem(task, q)
    if reason is None:
        hit = task.hand.collisions(task.pose(x) if pose is None else np.asarray(pose, float), q, first=True)
        if hit:
            c = hit[0]
            return ConfigurationReport(phase, where, float(x), qt, c.message, c.bodies, c.area, c.depth, **kw)
        reason = "the configuration is valid"
    return ConfigurationReport(phase, where, float(x), qt, reason, **kw)


def _num(v):
    return float(v) if np.isfinite(v) else None


def _edge_corners(task, x, effort, direction, grasp=None, path=None):
    """Box corners where the desired band's lower and upper edges are attained (vertex theory)."""
    from qsplan.mechanics.bands.effort import effort_bands
    from qsplan.mechanics.modes.contact_mode import ContactMode

    from qsplan.planner.states.contact import contact_samples

    lo, hi = task.mu_range
    speed = direction * task.workpiece_speed
    free = None if path is None else path.at([x])
    rates = None if path is None else path.rates(1, speed)
    scene = contact_samples(task, [x], effort, speed, grasp=grasp, free=free, free_rates=rates).scenes[0]
    n = scene.n_contacts
    rows = np.array([[lo] * n, [hi] * n]) if task.shared_mu else np.array(list(product((lo, hi), repeat=n)))
    low, up, ok = effort_bands(scene, ContactMode(task.formation.mode), rows, force_margin=task.force_margin,
                               disturbance=task.disturbance)
    if not np.any(ok):
        return None, None
    i = int(np.nanargmax(np.where(ok, low, -np.inf)))
    j = int(np.nanargmin(np.where(ok, up, np.inf)))
    return tuple(float(m) for m in rows[i]), tuple(float(m) for m in rows[j])


def _check(task, x, effort, direction, competitors, grasp, path):
    from qsplan.planner.states.contact import check_contact_state

    free = None if path is None else path.at([x])[0]
    return check_contact_state(task, x, effort, direction, None, competitors, grasp, free,
                               None if path is None else path.slope)  # fmt: skip


def failure_report(task, name, x0, x1, effort, direction, competitors, result=None, xs=None,
                   grasp=None, path=None, status=None) -> FailureReport:  # fmt: skip
    """The report for a segment from ``x0`` to ``x1`` (m) with no plan (see the module docstring); ``grasp`` the
    features the fingers touch (default the paper hand's inner edges), ``path`` a described hand's free joints along
    it (:class:`qsplan.planner.plan.phases.FreePath`; default held); ``status`` what planning had done (default the
    sweep's ``result.status``, or :data:`NOT_RUN_BAND_AT_END` without one)."""
    from qsplan.planner.states.contact import mode_name

    xs = np.linspace(x0, x1, REPORT_SAMPLES) if xs is None else np.asarray(xs, float)
    if xs.size > REPORT_SAMPLES:
        xs = xs[np.linspace(0, xs.size - 1, REPORT_SAMPLES).astype(int)]
    checks = [_check(task, x, effort, direction, competitors, grasp, path) for x in xs]
    closed = []
    for c in checks:
        if c.ok:
            continue
        dw = c.desired_upper - c.desired_lower
        closed.append(ClosedPoint(c.x, c.reason, c.width, float(dw) if np.isfinite(dw) or dw == np.inf else np.nan,
                                  c.competitors))  # fmt: skip
    narrowest, mu_closes = None, None
    if closed:
        widths = np.array([p.width if np.isfinite(p.width) else -1.0 for p in closed])
        narrowest = closed[int(np.argmin(widths))]
        if narrowest.reason.startswith(("band", "no guaranteed band")):
            # box corners of the edges mean nothing where the mode is degenerate (Q_AI singular inside the box)
            if "degenerate" not in narrowest.reason:
                lo_e, hi_e = _edge_corners(task, narrowest.x, effort, direction, grasp, path)
                narrowest = replace(narrowest, mu_lower_edge=lo_e, mu_upper_edge=hi_e)
            mu_closes = _mu_closes(task, narrowest.x, effort, direction, competitors, grasp, path)
    if status is None:
        status = NOT_RUN_BAND_AT_END if result is None else result.status
    return FailureReport(name, float(x0), float(x1), effort, task.torque_resolution, task.mu_range, status,
                         tuple(closed), narrowest, mu_closes, mode_name(task.formation.mode))  # fmt: skip


def _mu_closes(task, x, effort, direction, competitors, grasp=None, path=None, iterations=30):
    """The friction upper bound at which the band at ``x`` shrinks to the resolution (bisection), or None."""
    from dataclasses import replace as dc_replace

    lo, hi = task.mu_range

    def ok(m):
        return _check(dc_replace(task, mu_range=(lo, m)), x, effort, direction, competitors, grasp, path).ok

    if not ok(lo) or ok(hi):
        return None
    a, b = lo, hi
    for _ in range(iterations):
        m = 0.5 * (a + b)
        a, b = (m, b) if ok(m) else (a, m)
    return float(a)
