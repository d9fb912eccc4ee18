"""A feasibility preview of a task: where each grasp is valid and banded along the palm, and whether a route exists.

Finding a task that plans used to be trial and error (issue 25): fingers overlapping, beyond reach, a
contact moving to another feature, a band closing.  :func:`preview_task` answers in seconds, before any
planning:

* the start and the goal closed (:mod:`qsplan.planner.reports.preview_configs`): the grasp, every joint
  beyond its limit and every pair of overlapping bodies, named and measured;
* for each grasp the hand offers (the paper hand's tangency and tip placements, split by the workpiece
  features its fingers touch; a hand with free joints, each row of free-joint values), where along the
  palm it is a valid configuration (its contacts, the joint limits, no overlap) and where the formation's
  mode has a guaranteed band at least the torque resolution wide (every competitor precluded, the whole
  friction set), per direction of the slide;
* the verdict: a route of banded slides (and regrasps) from the start to the goal, found by the planner's
  own search in the window it searches, or what blocks it (:func:`qsplan.planner.plan.obstacles.no_route_report`).

A goal that turns the workpiece (``[goal] theta`` or ``palm``) is previewed as the planner's formation search sees
it (:func:`qsplan.planner.plan.turning.survey`): every pivot formation of the hand and workpiece, where each ends and
why (an event and its angle, a band below the resolution) or its narrowest band (:attr:`Preview.formations`); then
the slide to the flush instant of the one with the widest bands, previewed as above (:attr:`Preview.slide_end`).

All of it is read from the planner's own band tables (:func:`qsplan.planner.search.tables.band_tables` of the rows
:func:`qsplan.planner.plan.autoplan.grasp_rows` gives) on a grid across the whole palm through the start and the
goal exactly, at the planner's step: nothing is computed twice.  Like the tables, a preview proposes: the planner
judges its route again sample by sample.  Units SI (m, rad, N m; N for a prismatic joint's force).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace

import numpy as np

from qsplan.planner.reports.preview_configs import (ConfigurationCheck, configuration_check, features_words,
                                                    goal_candidates, start_candidates)  # fmt: skip
from qsplan.planner.reports.preview_route import route_verdict

__all__ = ["GraspBar", "Preview", "preview_task", "torque_words", "x_ranges"]


@dataclass(frozen=True, slots=True, eq=False)
class GraspBar:
    """One grasp of the preview: a row of the tables with its fingers on one pair of features.

    Attributes
    ----------
    name : str
        ``"G1"``, ``"G2"``, ... (the table's and the figure's).
    label : str
        The features touched in words (and a described hand's free joints).
    short : str
        The same, compact (the figure's).
    row : int
        The tables' row.
    touched : (int, int)
        What each finger touches (the tables' codes, :attr:`qsplan.planner.search.widest.SearchGraph.touched`;
        ``(-1, -1)``: a row valid nowhere).
    valid : ndarray of bool, shape (n,)
        A valid configuration at each grid x (contacts on these features, joints inside their limits, no overlap).
    banded : ndarray of bool, shape (2, n)
        Valid, and a guaranteed band at least the resolution wide for some torque-controlled joint, sliding toward
        -x (row 0) and +x (row 1).
    """

    name: str
    label: str
    short: str
    row: int
    touched: tuple
    valid: np.ndarray
    banded: np.ndarray


@dataclass(frozen=True, slots=True, eq=False)
class Preview:
    """The feasibility preview of a task (:func:`preview_task`).

    Attributes
    ----------
    task, hand : str
        Their names.
    x : ndarray, shape (n,)
        The grid of workpiece x (m) across the palm.
    window : (float, float)
        Where the planner searches (m): the start and the goal and its margin beyond them, on the palm.
    waypoints : tuple of float
        A scripted task's waypoints (m; the last is the goal), or ().
    start, goal : ConfigurationCheck
    grasps : tuple of GraspBar
    resolution : float
        The torque resolution (N m; N for a prismatic joint's force): narrower bands do not count.
    resolution_unit : str
        ``"N m"``, ``"N"`` (every joint prismatic) or ``"N m or N"``.
    mu_range : (float, float)
    shared_mu : bool
    mode : str
        The formation's mode (the paper's name, ``"4S"``).
    efforts : tuple of str
        The joints that may be torque-controlled (eq. 32).
    ok : bool
        Start and goal valid and a banded route between them (never for a turning goal: not previewed).
    route : tuple of str
        The route's phases in words (empty without one).
    verdict : str
    seconds : float
        Wall time of the preview (s).
    slide_end : ConfigurationCheck or None
        A turning goal's: the end of the slide to the flush instant of the formation with the widest pivot bands,
        the route's first step, previewed as a goal (the bars and ``route`` are that slide's); None otherwise.
    formations : tuple of qsplan.planner.plan.turning.FormationOutcome
        A turning goal's: every pivot formation the search sees, where each ends and why, or its narrowest band
        (:func:`qsplan.planner.plan.turning.survey`).
    """

    task: str
    hand: str
    x: np.ndarray
    window: tuple
    waypoints: tuple
    start: ConfigurationCheck
    goal: ConfigurationCheck
    grasps: tuple
    resolution: float
    resolution_unit: str
    mu_range: tuple
    shared_mu: bool
    mode: str
    efforts: tuple
    ok: bool
    route: tuple
    verdict: str
    seconds: float
    slide_end: ConfigurationCheck | None = None
    formations: tuple = ()

    def as_dict(self) -> dict:
        x = self.x
        bars = [{"name": b.name, "grasp": b.label, "valid_x_m": x_ranges(x, b.valid),
                 "banded_x_m": {"sliding_left": x_ranges(x, b.banded[0]), "sliding_right": x_ranges(x, b.banded[1])}}
                for b in self.grasps]  # fmt: skip
        return {"kind": "feasibility preview", "task": self.task, "hand": self.hand,
                "grid": {"x_from_m": float(x[0]), "x_to_m": float(x[-1]), "points": int(x.size),
                         "step_m": float(np.max(np.diff(x))) if x.size > 1 else 0.0},
                "search_window_m": list(self.window), "waypoints_m": list(self.waypoints),
                "start": self.start.as_dict(), "goal": self.goal.as_dict(),
                "banded_means": (f"a guaranteed {self.mode} band at least {self.resolution:g} {self.resolution_unit} "
                                 f"wide, every competitor precluded, friction in {list(self.mu_range)}"
                                 f"{' shared by all contacts' if self.shared_mu else ' at every contact'}"),
                "resolution": self.resolution, "resolution_unit": self.resolution_unit,
                "mu_range": list(self.mu_range), "shared_mu": self.shared_mu,
                "mode": self.mode, "effort_joints": list(self.efforts), "grasps": bars, "ok": self.ok,
                "route": list(self.route), "verdict": self.verdict, "seconds": self.seconds,
                "slide_end": None if self.slide_end is None else self.slide_end.as_dict(),
                "formations": [o.as_dict() for o in self.formations]}  # fmt: skip


def x_ranges(x, mask) -> list:
    """The runs of ``mask`` (n,) along the grid ``x`` (n,) (m), as ``[[x_first, x_last], ...]`` (grid points)."""
    m = np.asarray(mask, dtype=bool)
    if not m.any():
        return []
    edges = np.diff(np.concatenate([[0], m.astype(np.int8), [0]]))
    starts, ends = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1) - 1
    return [[float(x[a]), float(x[b])] for a, b in zip(starts, ends)]


def _words(task, tables, g, pair) -> tuple:
    """Row ``g`` touching ``pair`` (per finger, the tables' codes) in words: ``(label, short)``."""
    from qsplan.hands.paper_hand.grasps import touch_words

    row = tables.grasps[g]
    if min(pair) < 0:
        return f"{row.label} (valid nowhere on the palm)", f"{row.label} (valid nowhere)"
    if task.hand.free_joints:  # a described hand's contacts name themselves; its free joints and their slope follow
        from qsplan.hands.protocol import JOINT_UNITS

        grasp, hand = row.grasp, task.hand
        unit = " or ".join(sorted({JOINT_UNITS[hand.joint_kinds[j]]["q"] for j in hand.free_joints}))
        short = f"L {grasp.left} / R {grasp.right}\nfree joints ({', '.join(f'{v:.3g}' for v in grasp.free)}) {unit}"
        if row.path is not None and np.any(np.asarray(row.path.slope) != 0):
            slope = np.asarray(row.path.slope)[list(row.path.free)]
            short += f", sloping ({', '.join(f'{v:.3g}' for v in slope)}) {unit}/m"
        return row.label, short
    words = [touch_words(task.hand, row.grasp, k, int(pair[k])) for k in range(2)]
    short = [w.replace(f"the {s} finger's ", f"{s[0].upper()} ").replace(f"the {s} fingertip", f"{s[0].upper()} tip")
             for w, s in zip(words, ("left", "right"))]  # fmt: skip
    return " and ".join(words), " / ".join(short)


def _bars(task, tables) -> tuple:
    """The tables' rows split by the features their fingers touch (a paper placement's vertex changes along x)."""
    graph, res = tables.graph, tables.graph.resolution
    banded = np.any(graph.width >= res, axis=1)  # (G, 2, n): some torque-controlled joint
    out = []
    for g in range(len(tables.grasps)):
        touched = graph.touched[g, :, :2]
        ok = np.flatnonzero(graph.valid[g])
        pairs = list(dict.fromkeys(tuple(int(v) for v in touched[i]) for i in ok)) or [(-1, -1)]
        for pair in pairs:
            valid = graph.valid[g] & np.all(touched == pair, axis=1)
            label, short = _words(task, tables, g, pair)
            out.append(GraspBar(f"G{len(out) + 1}", label, short, g, pair, valid, banded[g] & valid[None, :]))
    return tuple(out)


def preview_task(task, progress=None) -> Preview:
    """The feasibility preview of ``task`` (see the module docstring).

    Parameters
    ----------
    task : qsplan.planner.task.task.Task
    progress : callable, optional
        ``progress(line)``.

    Returns
    -------
    Preview
    """
    from qsplan.planner.task.goal import GoalNotServedError, reorients

    t0 = time.perf_counter()
    if not reorients(task):
        return _preview(task, progress, t0)
    from qsplan.planner.plan.turning import flush_free_joints, slide_task, survey

    what = f"a turn ({task.goal.describe()})"
    try:
        surveyed = survey(task, progress)
    except GoalNotServedError as exc:  # refused by name: said, the start previewed alone
        return _preview(task, progress, t0, turn=f"{what}: {_REFUSED}{exc}", refused=True)
    formations = tuple(s.outcome for s in surveyed)
    lines = "; ".join(o.line() for o in formations) or "the hand and workpiece offer no pivot formation"
    reaching = [s for s in surveyed if s.pieces is not None]
    if not reaching:
        out = _preview(task, progress, t0, turn=f"{what}: no formation reaches it ({lines})", refused=True)
        return replace(out, formations=formations, seconds=time.perf_counter() - t0)
    best = max(reaching, key=lambda s: s.outcome.band)  # the first of equals, as the planner keeps
    sub, step = slide_task(task, best.pivot, best.start)
    inner = _preview(sub, progress, t0, goal_name="slide's end", goal_free=flush_free_joints(task.hand, best.start))
    goal = ConfigurationCheck("goal", inner.goal.x, None, None, None, 0, 0,
                              note=f"{what}: the formations searched: {lines}")  # fmt: skip
    how = f" ({best.outcome.why})" if best.later else ""  # a finger replaced mid-turn: said where
    verdict = (f"goal: {what}: {best.outcome.words} reaches it{how}, narrowest pivot band "
               f"{torque_words(best.outcome.band)}; its first step, {step}: {inner.verdict} (the holds are proved "
               "when planned)")  # fmt: skip
    return replace(inner, task=task.name, goal=goal, ok=inner.ok, verdict=verdict, slide_end=inner.goal,
                   formations=formations, seconds=time.perf_counter() - t0)  # fmt: skip


#: How a refusal of a turning goal begins.
_REFUSED = "qsplan plan refuses it: "


def torque_words(width: float) -> str:
    """A band's width for the verdict: ``0.214 N m``, or ``unbounded above``."""
    return f"{width:.4g} N m" if np.isfinite(width) else "unbounded above"


def _preview(task, progress, t0, goal_name="goal", turn=None, refused=False, goal_free=None) -> Preview:
    """:func:`preview_task` of a task whose goal keeps the orientation (its goal named ``goal_name``), or of a turning
    goal not previewed (``turn``: what the goal's check says; ``refused``: the route refuses it), the start previewed
    alone.  ``goal_free``: a turn's slide, its route judged as the planner plans it (``plan_automatic``'s): ending at
    rows holding those free joints, by a slide in the goal grasp."""
    from qsplan.planner.plan.autoplan import FREE_SEARCH_MARGIN, ending_in_place, goal_nodes, grasp_rows, start_nodes
    from qsplan.planner.plan.failure import palm_report
    from qsplan.planner.search.tables import SEARCH_MARGIN, band_tables, table_grid
    from qsplan.planner.states.contact import mode_name
    from qsplan.planner.task.goal import goal_refusal, palm_x_range

    progress = progress or (lambda line: None)
    hand = task.hand
    refusal = turn or goal_refusal(task)  # a goal off the palm edge: the verdict says why
    if task.goal is None:
        goal_x = float(task.waypoints[-1])
    else:  # a goal without x (refused) previewed at the start's x
        goal_x = float(task.start_x if task.goal.x is None else task.goal.x)
    lo, hi = palm_x_range(hand)
    beyond = palm_report(task) if refusal is None else None  # (palm_report refuses such a goal: it has no position)
    if beyond is None and refusal is None:
        x = table_grid(task.start_x, goal_x, (lo, hi), margin=hi - lo)  # the planner's grid, across the whole palm
        margin = FREE_SEARCH_MARGIN if hand.free_joints else SEARCH_MARGIN
        window = (max(min(task.start_x, goal_x) - margin, lo), min(max(task.start_x, goal_x) + margin, hi))
    else:  # a position beyond the palm, or a refused goal: the grid across the palm all the same (through the start
        # and the goal where they are on it), the verdict says why
        x = table_grid(float(np.clip(task.start_x, lo, hi)), float(np.clip(goal_x, lo, hi)), (lo, hi), margin=hi - lo)
        window = (lo, hi)
    rows = grasp_rows(task, float(np.clip(task.start_x, lo, hi)), float(np.clip(goal_x, lo, hi)))
    progress(f"band tables: {len(rows)} grasps x {x.size} workpiece positions ({x[0]:.4g} to {x[-1]:.4g} m)")
    tables = band_tables(task, rows, x)
    bars = _bars(task, tables)
    named = {(b.row, b.touched): b for b in bars}

    def label(g, i):  # row g at grid index i: its bar where it has one, else the features it touches there
        pair = tuple(int(v) for v in tables.graph.touched[g, i, :2])
        bar = named.get((g, pair))
        return f"{bar.name} ({bar.label})" if bar is not None else _words(task, tables, g, pair)[0]

    i_start, i_goal = tables.index(task.start_x), tables.index(goal_x)
    starts = [g for g, _ in start_nodes(tables, task)]
    if refusal is not None:
        goals = []
    elif task.goal is not None:
        goals = goal_nodes(tables, task, goal_free)
    else:  # a scripted task ends in its start's grasp
        goals = [(g, i_goal) for g in starts if tables.graph.valid[g, i_goal]]

    def checks(first, last):  # the start and the goal, the rows ``first`` and ``last`` drawn where valid
        return (configuration_check(task, tables, i_start, "start", first, start_candidates(tables, task, i_start),
                                    label, features_words(task, "start")),
                configuration_check(task, tables, i_goal, goal_name, last, goal_candidates(tables, task, i_goal),
                                    label, features_words(task, "goal")))  # fmt: skip

    start, goal = checks(starts, [g for g, _ in goals])
    if beyond is not None:  # the start or the goal beyond the palm is not valid; a waypoint's the verdict says
        start = _beyond(start, beyond, task.start_x) if beyond.where == "the start" else start
        goal = _beyond(goal, beyond, goal_x) if beyond.where == "the goal" else goal
    if turn is not None:  # a turning goal not previewed: the goal says so, the verdict with the start's check
        goal = ConfigurationCheck("goal", goal_x, None, None, None, 0, 0, note=turn, refused=refused)
        ok, route, verdict, ends = False, (), f"start {'ok' if start.ok else 'not ok'} / goal: {turn}", None
    elif refusal is not None:  # no grasp of the formation meets such a goal: the refusal is its problem and the verdict
        where = "" if task.goal.x is not None else " (the goal gives no x: drawn at the start's)"
        goal = ConfigurationCheck("goal", goal_x, None, None, None, 0, goal.candidates, f"{refusal}{where}")
        ok, route, verdict, ends = False, (), str(refusal), None
    else:
        ok, route, verdict, ends = route_verdict(task, tables, bars, window, start, goal, starts, goals, beyond,
                                                 ending_in_place(tables, goals, goal_free))  # fmt: skip
    if ends is not None:  # draw the route's own first and last grasps
        start, goal = checks([ends[0]] + [g for g in starts if g != ends[0]],
                             [ends[1]] + [g for g, _ in goals if g != ends[1]])  # fmt: skip
    return Preview(task.name, hand.name, x, tuple(float(v) for v in window), tuple(float(v) for v in task.waypoints),
                   start, goal, bars, float(task.torque_resolution), _effort_unit(hand), tuple(task.mu_range),
                   bool(task.shared_mu), mode_name(task.formation.mode), tuple(tables.efforts), ok, route, verdict,
                   time.perf_counter() - t0)  # fmt: skip


def _effort_unit(hand) -> str:
    """The unit of the hand's joint efforts: ``"N m"``, ``"N"`` or both."""
    from qsplan.hands.protocol import JOINT_UNITS

    return " or ".join(sorted({JOINT_UNITS[k]["tau"] for k in hand.joint_kinds}, reverse=True))


def _beyond(check, report, x) -> ConfigurationCheck:
    """``check`` of a position beyond the palm: nothing valid there, the palm report its problem."""
    return ConfigurationCheck(check.where, float(x), None, None, None, 0, check.candidates, None, (), (),
                              report.message.removeprefix("no plan: "))  # fmt: skip
