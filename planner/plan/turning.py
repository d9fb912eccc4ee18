"""Turning the workpiece: a search over the formations the hand and the workpiece offer (issue 32).

A goal that asks another orientation (``[goal] theta``, or ``palm`` naming another feature) is served by a route of
formations joined in contact, generated for the task's hand and workpiece, never a fixed list:

1. a **slide** on the palm edge (formation ``palm_edge``, 4S, regrasps allowed: :func:`qsplan.planner.plan.autoplan.
   plan_automatic`) to a pivot's **flush instant**, where one finger lies flush along a side of the workpiece;
2. a certified **hold** there (nothing moves; the torque-controlled finger's torque ramps to the pivot's);
3. the **pivot** (:class:`qsplan.hands.formations.pivots.Pivot`: on the bottom edge's far end, turning away from the
   flush finger), cut into pieces where a contact's sliding direction reverses, each joined to the next by a certified
   hold (:mod:`qsplan.planner.plan.pivot`), to the goal's angle.

Every pivot formation of the hand (:func:`qsplan.hands.formations.pivots.pivot_formations`: each finger flush on each
side it fits, the other finger on each feature it closes on) whose turn can reach the goal is searched, the cheap part
first (the pivot's geometry, then its bands, then the slide); of the routes found, the one whose narrowest band is
widest is planned (then the fewest phases).  A goal none reaches is refused with a :class:`TurnReport`: every formation
searched and where each ended (its event and angle, or the band, or the slide that failed).  Units SI.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace

import numpy as np

from qsplan.planner.plan.results import Plan, PlanFailure
from qsplan.planner.task.goal import Goal, GoalNotServedError

__all__ = ["FLUSH_APPROACH", "FormationOutcome", "Leg", "REPLACE_ANGLES", "REPLACE_EVERY", "SCREEN_STEP",
           "SEARCHED_FORMATIONS", "Surveyed", "TurnReport", "flush_free_joints", "goal_angle", "pivot_pieces", "plan_turn",
           "slide_task", "survey"]

#: How far (m) short of the flush instant the slide's band tables end: five times the contact tolerance (1 um), so
#: the polygons show the four contacts of the palm edge there; the slide then reaches the flush instant itself in
#: its last row.
FLUSH_APPROACH = 5e-6

#: Rows of a pivot (0.25 deg apart) between the angles where its other finger may be replaced (one degree): the hold
#: with the finger lifted is proved only in windows of a few degrees (docs/reorientation.md), finer gains nothing.
REPLACE_EVERY = 4

#: Rows' spacing (rad) of the coarse sweep that screens a new grasp's formation before its own (2 deg: eight times
#: cheaper; an event it finds is one, and what it misses between its rows the fine sweep finds).
SCREEN_STEP = np.radians(2.0)

#: Angles with a proved lifted hold tried for a replacement, widest margin first: each costs the new grasps' geometry.
REPLACE_ANGLES = 6

#: ``planner_status`` of a turning goal no formation reaches.
SEARCHED_FORMATIONS = "ran: the formation search; no route of formations reaches the goal"


def _refuse(field, why):
    return GoalNotServedError(field, f"{field}: {why}")


def goal_angle(task, pivot) -> tuple:
    """``(theta, None)``: the angle (rad) at which ``pivot`` meets the task's goal (its ``theta``; or for ``palm =
    "edge:K"`` the angle at which that edge lands on the palm turning about the pivot vertex), or ``(None, why)``:
    the pivot cannot serve it (the other direction, another vertex or edge)."""
    goal, hand = task.goal, task.hand
    V = np.asarray(hand.workpiece, dtype=float)
    k = len(V)
    vertex = int(hand.user_vertices[pivot.vertex])
    turn = "clockwise" if pivot.direction < 0 else "counter-clockwise"
    if goal.theta is not None:
        theta = float(goal.theta)
        if np.sign(theta) != pivot.direction:
            return None, f"it turns the workpiece {turn}"
        if goal.palm is not None and goal.palm != ("vertex", vertex):
            return None, f"it pivots on vertex {vertex}"
        return theta, None
    kind, index = goal.palm
    if kind == "vertex":
        return None, "a vertex on the palm needs the angle too (theta)"
    # the edge that lands: from the pivot vertex on (clockwise), or to it (counter-clockwise)
    a, b = (pivot.vertex, (pivot.vertex + 1) % k) if pivot.direction < 0 else ((pivot.vertex - 1) % k, pivot.vertex)
    landing = int(hand.user_edges[a])
    if index != landing:
        return None, f"turning {turn} on vertex {vertex} lands edge {landing}"
    d = V[b] - V[a]
    return float(-np.arctan2(d[1], d[0])), None


def slide_task(task, pivot, start):
    """``(sub-task, words)``: the slide to ``pivot``'s flush instant ``start`` (``(x, y, 0, q)``), planned as a task
    whose goal is the flush finger on its side's upper vertex :data:`FLUSH_APPROACH` short of it."""
    hand = task.hand
    k = len(hand.workpiece)
    upper = pivot.edge if pivot.flush == "left" else (pivot.edge + 1) % k  # the side's upper end
    feature = ("vertex", int(hand.user_vertices[upper]))
    x = float(start[0])
    x_near = x + FLUSH_APPROACH * np.sign(task.start_x - x)
    goal = Goal(x_near, feature, None) if pivot.flush == "left" else Goal(x_near, None, feature)
    words = (f"the slide to the flush instant (x = {x:.6g} m, the {pivot.flush} finger along edge "
             f"{int(hand.user_edges[pivot.edge])})")  # fmt: skip
    return replace(task, goal=goal), words


def flush_free_joints(hand, start):
    """The free joints' values (rad or m, ``hand.free_joints``' order) at a pivot's flush instant ``start`` (``(x, y,
    0, q)``), or None for a hand without free joints: the slide to it must end holding them (the pivot holds them), not
    in another grasp of the goal's features whose last row would then jump to the flush instant."""
    free = list(hand.free_joints)
    return np.asarray(start, dtype=float)[3:][free] if free else None


@dataclass(frozen=True, slots=True)
class FormationOutcome:
    """What the search found of one pivot formation.

    Attributes
    ----------
    formation : str
        Its name (:attr:`qsplan.hands.formations.pivots.Pivot.name`).
    words : str
        It in words.
    status : str
        ``"planned"``, ``"ended"`` (its geometry ends before the goal), ``"no band"`` (a piece has no band at least
        the resolution wide), ``"no slide"`` (the slide to its flush instant failed), ``"hold"`` (a hold is not
        proved) or ``"not this goal"``.
    theta : float or None
        Where it ended, or the goal's angle when planned (rad).
    why : str
        The event, the band's reason, or the failure, in words.
    band : float or None
        The narrowest band of its route (N m) when planned.
    pose, q : tuple or None
        The configuration where it ended (for the drawing).
    """

    formation: str
    words: str
    status: str
    theta: float | None
    why: str
    band: float | None = None
    pose: tuple | None = None
    q: tuple | None = None

    def as_dict(self) -> dict:
        return {"formation": self.formation, "words": self.words, "status": self.status, "theta_rad": self.theta,
                "why": self.why, "narrowest_band": self.band,
                "pose": None if self.pose is None else list(self.pose), "q": None if self.q is None else list(self.q)}

    def line(self) -> str:
        at = "" if self.theta is None else f" at theta = {np.degrees(self.theta):.4g} deg"
        return f"{self.words}: {self.status}{at}: {self.why}"


@dataclass(frozen=True, slots=True, eq=False)
class TurnReport:
    """No route of formations reaches a turning goal: every formation searched and where each ended.

    Attributes
    ----------
    goal : str
        The goal in words.
    outcomes : tuple of FormationOutcome
    goal_theta : float or None
        The goal's angle (rad) for a formation that could reach it (drawn by ``failure.png``).
    """

    goal: str
    outcomes: tuple
    goal_theta: float | None = None

    @property
    def farthest(self) -> FormationOutcome | None:
        """The outcome that turned the workpiece farthest before ending (drawn by ``failure.png``)."""
        drawn = [o for o in self.outcomes if o.pose is not None]
        return max(drawn, key=lambda o: abs(o.pose[2]), default=None)

    @property
    def x(self) -> float:
        far = self.farthest
        return float(far.pose[0]) if far is not None else float("nan")

    @property
    def pose(self):
        far = self.farthest
        return None if far is None else far.pose

    @property
    def q(self):
        far = self.farthest
        return None if far is None else far.q

    @property
    def message(self) -> str:
        if not self.outcomes:
            return f"no plan: {self.goal}: the hand and workpiece offer no pivot formation (no side a finger lies " \
                   "flush along at a flush instant the other finger closes on)"
        return f"no plan: {self.goal}: no route of formations reaches it; " + "; ".join(o.line() for o in self.outcomes)

    def as_dict(self) -> dict:
        return {"kind": "no turn", "goal": self.goal, "formations": [o.as_dict() for o in self.outcomes],
                "planner_status": SEARCHED_FORMATIONS, "pose": None if self.pose is None else list(self.pose),
                "message": self.message}  # fmt: skip


def _outcome(pivot, hand, status, theta, why, pose=None, q=None, band=None) -> FormationOutcome:
    return FormationOutcome(pivot.name, pivot.words(hand), status, None if theta is None else float(theta), why,
                            band, None if pose is None else tuple(float(v) for v in pose),
                            None if q is None else tuple(float(v) for v in q))  # fmt: skip


def pivot_pieces(task, pivot, start, theta_goal, geometry, progress):
    """The pivot's pieces (planned phases, times from 0), from its flush instant ``start`` (or a configuration on it
    mid-turn) to ``theta_goal`` (rad), cut at those of ``geometry.cuts`` before it (:func:`qsplan.planner.plan.pivot.
    pivot_geometry`); raises PlanFailure naming the first row without a band."""
    from qsplan.hands.formations.pivots import pivot_path
    from qsplan.planner.plan.pivot import pivot_thetas, widest_piece

    hand = task.hand
    c = np.asarray(start, dtype=float)
    flush = float(c[2]) == 0.0  # from the flush instant (the transition its first row), or mid-turn
    ends = [float(c[2]), *(cut for cut in geometry.cuts if abs(cut - c[2]) < abs(theta_goal - c[2])), theta_goal]
    pieces = []
    for j, (a, b) in enumerate(zip(ends[:-1], ends[1:])):
        path = pivot_path(hand, pivot, c, pivot_thetas(a, b))
        vertex = int(hand.user_vertices[pivot.vertex])
        name = (f"pivot on vertex {vertex} from theta = {a:.4g} to {b:.4g} rad" if len(ends) > 2 or not flush
                else f"pivot on vertex {vertex} to theta = {b:.4g} rad")
        pieces.append(widest_piece(task, name, pivot, path, np.arange(path.theta.size), flush and j == 0, progress))
        c = np.concatenate([path.pose[-1], path.q[-1]])
    return pieces


@dataclass(frozen=True, slots=True, eq=False)
class Leg:
    """One formation's part of a route: ``pivot`` from configuration ``start`` (its flush instant for the first leg;
    for a later one where ``finger`` was replaced, :mod:`qsplan.planner.plan.replace`) through ``pieces`` (planned
    phases, times from 0)."""

    pivot: object
    start: np.ndarray
    pieces: tuple
    finger: str | None = None


def _route(task, legs, options, progress, planner, started):
    """The whole route: the slide to the first leg's flush instant, a hold, each piece with a hold before the next; a
    later leg's finger replaced before its first hold; timed."""
    from qsplan.planner.plan.autoplan import plan_automatic
    from qsplan.planner.plan.failure import StepReport, configuration_report
    from qsplan.planner.plan.phases import DEFAULT_OPTIONS
    from qsplan.planner.plan.pivot import hold_phase, shifted
    from qsplan.planner.plan.release import release_hold
    from qsplan.planner.plan.replace import replace_phase
    from qsplan.planner.plan.steps import (
        HoldStep,
        PivotStep,
        ReplaceStep,
        SearchSummary,
        realised_steps,
        route_steps,
    )
    from qsplan.planner.plan.timing import time_scale

    hand = task.hand
    pivot, start = legs[0].pivot, legs[0].start
    sub, step = slide_task(task, pivot, start)
    try:
        slide = plan_automatic(sub, options, progress, planner, timed=False, goal_free=flush_free_joints(hand, start))
    except PlanFailure as exc:  # said as the route's step, drawn with the task it was planned as
        raise PlanFailure(StepReport(step, sub, exc.report)) from None
    phases = list(slide.phases)
    last = phases[-1]
    if not last.in_contact:
        x_last = float(np.ravel(last.x)[-1])  # a regrasp's x is one number
        raise PlanFailure(configuration_report(task, last.name, "the flush instant", x_last, last.q[-1],
                                               "the route to the flush instant ends with a regrasp, not in contact",
                                               "ran: the sequence search to the flush instant"))  # fmt: skip
    # the last row moves onto the flush instant itself (5 um on): a row at rest, its band judged again for the
    # chord that reaches it by the time scaling (the contact made there left out: qsplan.planner.plan.timing)
    x, q, t = last.x.copy(), last.q.copy(), last.t.copy()
    x[-1], q[-1] = float(start[0]), np.asarray(start[3:], dtype=float)
    t[-1] = t[-2] + abs(x[-1] - x[-2]) / abs(last.speed)
    phases[-1] = replace(last, x=x, q=q, t=t)
    timed = time_scale(Plan(task, tuple(phases), 0.0, 0, 0.0, slide.options))  # the slide first: its last command
    end = timed.phases[-1]
    turned, steps, t0 = [], [], 0.0
    prev_effort, prev_tau = end.effort_joint, float(end.command[-1])
    counters = [slide.validity_checks, slide.ompl_seconds]
    for leg in legs:
        vertex = int(hand.user_vertices[leg.pivot.vertex])
        if leg.finger is not None:  # the finger replaced: from the last row at rest to the leg's start
            before = turned[-1]
            pose = before.pose[-1]
            # unloaded first, as before a regrasp (qsplan.planner.plan.release): the effort joint ramps at rest to the
            # least torque at which the hold is still proved, so that a compliant grasp stores little when it lets go
            found = release_hold(task, f"release hold at theta = {pose[2]:.4g} rad", pose, before.q[-1],
                                 before.effort_joint, prev_tau, t0, before.formation)  # fmt: skip
            if found is not None and found[1].torque_to != found[1].torque_from:  # already there: no ramp to hold
                turned.append(found[0])
                steps.append(found[1])
                t0 = float(found[0].t[-1])
            moved = replace_phase(task, f"the {leg.finger} finger replaced at theta = {pose[2]:.4g} rad", pose,
                                  before.q[-1], leg.start[3:], leg.finger, t0, options or DEFAULT_OPTIONS, progress,
                                  counters)  # fmt: skip
            turned.append(moved)
            steps.append(ReplaceStep(float(pose[0]), float(pose[2]), leg.finger, moved.kept, leg.pivot.name,
                                     moved.hold_margin))  # fmt: skip
            t0, prev_effort = float(moved.t[-1]), None  # the new grasp's torque is taken over at rest
        for j, piece in enumerate(leg.pieces):
            e = piece.effort_joint
            pose, q0 = piece.pose[0], piece.q[0]
            where = ("the flush instant" if not turned else
                     f"theta = {pose[2]:.4g} rad" + (" (a contact's sliding reverses)" if j else " (the new grasp)"))
            hold = hold_phase(task, f"hold at {where}", pose, q0, e, prev_tau if prev_effort == e else None,
                              float(piece.command[0]), t0, leg.pivot.name)  # fmt: skip
            moved = shifted(piece, float(hold.t[-1]))
            turned += [hold, moved]
            steps += [HoldStep(float(pose[0]), float(pose[2]), e, float(hold.command[0]), float(piece.command[0]),
                               float(hold.lower[0]), float(hold.upper[0])),
                      PivotStep(vertex, float(piece.pose[0, 2]), float(piece.pose[-1, 2]), e,
                                float(np.min(piece.width)))]  # fmt: skip
            t0, prev_effort, prev_tau = float(moved.t[-1]), e, float(piece.command[-1])
    rest = time_scale(Plan(task, tuple(turned), 0.0, 0, 0.0, slide.options))
    later = tuple(shifted(ph, float(end.t[-1])) for ph in rest.phases)
    sequence = route_steps(slide.sequence) + tuple(steps) + \
        tuple(st for st in slide.sequence if isinstance(st, SearchSummary))  # fmt: skip
    n_rows = sum(p.t.size for leg in legs for p in leg.pieces)
    plan = Plan(task, timed.phases + later, time.perf_counter() - started, counters[0] + n_rows, counters[1],
                slide.options, realised_steps(sequence, timed.phases + later), timed.timing + rest.timing)  # fmt: skip
    plan.check()
    return plan


def _check_goal(task) -> None:
    """Refuse by name what no formation serves: a turning goal that also gives ``x``, a palm vertex without theta."""
    goal = task.goal
    if goal.x is not None:
        raise _refuse("goal.x", "a goal that turns the workpiece is placed by its orientation: the pivot decides x "
                                "(give theta or palm, without x)")  # fmt: skip
    if goal.theta is None and goal.palm[0] == "vertex":
        raise _refuse("goal.theta", f"vertex {goal.palm[1]} on the palm: give the angle too (theta, rad): the "
                                    "workpiece turns on it through many")  # fmt: skip


@dataclass(frozen=True, slots=True, eq=False)
class Surveyed:
    """One pivot formation as the search saw it (:func:`survey`): the formation, its flush instant ``start``
    (``(x, y, 0, q)``), the goal's angle for it (rad, or None), what became of it, and its pieces (planned phases,
    times from 0) where it reaches the goal with a band in every piece (or where its other finger is replaced, the
    route going on in :attr:`later`), else None."""

    pivot: object
    start: np.ndarray
    theta_goal: float | None
    outcome: FormationOutcome
    pieces: tuple | None
    failure: object = None
    later: tuple = ()

    @property
    def legs(self) -> tuple:
        """The route's formations (:class:`Leg`): this one to the goal, or to where its other finger is replaced
        (:attr:`later`: the legs after each replacement)."""
        return (Leg(self.pivot, self.start, tuple(self.pieces)), *self.later)


def survey(task, progress=None) -> tuple:
    """Every pivot formation of the task's hand and workpiece, judged toward its goal without the slides that reach
    them: the goal's angle for it, its geometry (where it ends), then its pieces' bands (:class:`Surveyed`, in the
    order :func:`qsplan.hands.formations.pivots.pivot_formations` gives)."""
    from qsplan.hands.formations.pivots import pivot_formations
    from qsplan.planner.plan.pivot import pivot_geometry

    progress = progress or (lambda line: None)
    _check_goal(task)
    hand = task.hand
    formations = pivot_formations(hand, task.start_free)  # a chain hand's free joints held as the task starts them
    progress(f"formation search: {len(formations)} pivot formations of this hand and workpiece")
    out = []
    for pivot, start in formations:
        theta_goal, why = goal_angle(task, pivot)
        if theta_goal is None:
            out.append(Surveyed(pivot, start, None, _outcome(pivot, hand, "not this goal", None, why), None))
            continue
        geometry = pivot_geometry(task, pivot, start, theta_goal)
        if geometry.end is not None:
            e = geometry.end
            i = max(e.row - 1, 0)
            o = _outcome(pivot, hand, "ended", e.theta, e.words, geometry.path.pose[i], geometry.path.q[i])
            found, why = _with_replacement(task, pivot, start, theta_goal, geometry, e.row, o, progress)
            out.append(found or Surveyed(pivot, start, theta_goal, replace(o, why=f"{o.why}; {why}"), None))
            progress(f"  {o.line()}")
            continue
        try:
            pieces = tuple(pivot_pieces(task, pivot, start, theta_goal, geometry, progress))
        except PlanFailure as exc:
            r = exc.report
            o = _outcome(pivot, hand, "no band", r.pose[2], r.reason, r.pose, r.q)
            row = int(np.argmin(np.abs(geometry.path.theta - r.pose[2])))
            found, why = _with_replacement(task, pivot, start, theta_goal, geometry, row, o, progress)
            out.append(found or Surveyed(pivot, start, theta_goal, replace(o, why=f"{o.why}; {why}"), None, exc))
            progress(f"  {o.line()}")
            continue
        band = min(float(np.min(p.width)) for p in pieces)
        o = _outcome(pivot, hand, "reaches the goal", theta_goal, f"{len(pieces)} piece(s), holds between them",
                     band=band)  # fmt: skip
        out.append(Surveyed(pivot, start, theta_goal, o, pieces))
        progress(f"  {o.line()}; narrowest band {_band_words(band)}")
    return tuple(out)


def _with_replacement(task, pivot, start, theta_goal, geometry, stop: int, ended, progress) -> tuple:
    """``(Surveyed or None, why not)``: ``pivot``'s route with its other finger replaced (:mod:`qsplan.planner.plan.
    replace`) at one of its rows before ``stop`` (where it ends or loses its band).  Of the rows every
    :data:`REPLACE_EVERY` where the hold with the finger lifted is proved, the one with the widest margin (the proof's
    certified rest margin: the least normal force and cone slack) first, at most :data:`REPLACE_ANGLES` of them: the
    first where a new grasp's formation reaches the goal with a band in every piece, and this formation's pieces reach
    that row with bands.  ``ended``: this formation's own outcome, said in the new one's."""
    from qsplan.planner.plan.pivot import PivotGeometry, pivot_geometry
    from qsplan.planner.plan.replace import lifted_hold, reclosed, reclosings

    hand, path, finger = task.hand, geometry.path, pivot.other_finger
    proved = []
    for i in range(stop - 1, 0, -REPLACE_EVERY):
        proof = lifted_hold(task, path.pose[i], path.q[i], finger)
        if proof.proved:
            proved.append((-proof.rest_margin, -i, i))
    for _, _, i in sorted(proved)[:REPLACE_ANGLES]:  # the widest margin first (a compliant hand rocks least there)
        pose, q = path.pose[i], path.q[i]
        theta_k = float(path.theta[i])
        progress(f"  the {finger} finger lifted at theta = {np.degrees(theta_k):.2f} deg: the hold is proved")
        pieces1 = None
        for other, c in reclosings(task, pivot, pose, q):
            if pivot_geometry(task, other, c, theta_goal, SCREEN_STEP).end is not None:  # screened coarsely first
                continue
            try:
                if pieces1 is None:  # this formation's pieces to theta_k: their last row is where the finger lifts
                    cuts = tuple(x for x in geometry.cuts if abs(x) < abs(theta_k))
                    pieces1 = pivot_pieces(task, pivot, start, theta_k, PivotGeometry(path, None, cuts), progress)
                c = reclosed(task, other, pieces1[-1].pose[-1], pieces1[-1].q[-1], c)
                later = None if c is None else pivot_geometry(task, other, c, theta_goal)
                if later is None or later.end is not None:
                    continue
                pieces2 = pivot_pieces(task, other, c, theta_goal, later, progress)
            except PlanFailure:
                if pieces1 is None:
                    break  # no band to theta_k: another angle
                continue
            band = min(float(np.min(p.width)) for p in (*pieces1, *pieces2))
            o = _outcome(pivot, hand, "reaches the goal", theta_goal,
                         f"{len(pieces1)} piece(s) to {np.degrees(theta_k):.2f} deg ({ended.why}), the {finger} "
                         f"finger replaced there, then {other.words(hand)}: {len(pieces2)} piece(s)",
                         band=band)  # fmt: skip
            return Surveyed(pivot, start, theta_goal, o, tuple(pieces1), None,
                            (Leg(other, c, tuple(pieces2), finger),)), ""  # fmt: skip
    lo, hi = task.mu_range
    if not proved:
        return None, (f"the {finger} finger is replaced nowhere: the hold with it lifted is proved at no angle of this "
                      f"formation for friction in [{lo:g}, {hi:g}]")
    return None, (f"the {finger} finger is replaced nowhere: the hold with it lifted is proved at {len(proved)} "
                  f"angle(s), and no new grasp there reaches the goal with a band")


def _band_words(width: float) -> str:
    return f"{width:.4g} N m" if np.isfinite(width) else "unbounded above"


def plan_turn(task, options=None, progress=None, planner: str = "widest") -> Plan:
    """Plan a goal that turns the workpiece (the module docstring).

    Raises
    ------
    GoalNotServedError
        A goal that also gives ``x`` (the pivot decides it), or a vertex on the palm without its angle.
    PlanFailure
        No formation reaches the goal: a :class:`TurnReport` (or, where one formation could serve it and failed, that
        formation's own report).
    """
    progress = progress or (lambda line: None)
    started = time.perf_counter()
    hand = task.hand
    surveyed = survey(task, progress)
    outcomes, plans, failures = [], [], [s.failure for s in surveyed if s.failure is not None]
    for s in surveyed:
        if s.pieces is None:
            outcomes.append(s.outcome)
            continue
        try:
            plan = _route(task, s.legs, options, progress, planner, started)
        except PlanFailure as exc:
            r = exc.report
            status = "hold" if str(getattr(r, "where", "")).startswith("the hold") else "no slide"
            pose = getattr(r, "pose", None)
            outcomes.append(_outcome(s.pivot, hand, status, None if pose is None else pose[2], r.message, pose,
                                     getattr(r, "q", None)))  # fmt: skip
            failures.append(exc)
            continue
        band = min(float(np.min(p.width)) for p in plan.segments)
        outcomes.append(replace(s.outcome, status="planned", band=band))
        plans.append((band, -len(plan.phases), -len(plans), plan))
    if plans:
        plan = max(plans, key=lambda p: p[:3])[3]
        progress(f"turn planned: {len(plan.phases)} phases, {plan.duration:.4g} s")
        return plan
    reachable = [o for o in outcomes if o.status != "not this goal"]
    if len(reachable) == 1 and len(failures) == 1:  # one formation could serve it: its own report says it best
        raise failures[0]
    raise PlanFailure(TurnReport(task.goal.describe(), tuple(outcomes), _goal_theta(surveyed)))


def _goal_theta(surveyed):
    """The goal's angle (rad) where a surveyed formation could reach it (the first such), else None."""
    return next((s.theta_goal for s in surveyed if s.theta_goal is not None), None)
