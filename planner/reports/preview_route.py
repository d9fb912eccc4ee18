"""The preview's verdict: a banded route from the start to the goal in the planner's own search, or what blocks it.

A task with a ``[goal]``: the widest route of :func:`qsplan.planner.search.widest.widest_route` on the band tables,
restricted to the window the planner searches (the start, the goal and
:data:`qsplan.planner.search.tables.SEARCH_MARGIN` beyond them, or
:data:`qsplan.planner.plan.autoplan.FREE_SEARCH_MARGIN` for a hand with free joints), and where there is none, the
obstacle :func:`qsplan.planner.plan.obstacles.no_route_report` names.  A scripted task (``waypoints``): each segment
slides in the start's grasp with one torque-controlled joint, as :func:`qsplan.planner.plan.scripted.plan_task` plans
it; the verdict names the first segment the tables refuse and where.  Units SI (m, N m).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

__all__ = ["route_verdict", "window_graph"]


def window_graph(tables, window):
    """The tables' search graph with every grid point outside ``window`` (m, ``(lo, hi)``) invalid."""
    inside = (tables.x >= window[0]) & (tables.x <= window[1])
    graph = tables.graph
    width = np.where(inside, graph.width, -np.inf)
    return replace(graph, valid=graph.valid & inside[None, :], width=width)


def _bar_at(bars, g, i):
    return next((b for b in bars if b.row == g and b.valid[i]), next(b for b in bars if b.row == g))


def _effort_words(task, name) -> str:
    k = task.hand.joint_names.index(name)
    return f"{name} finger" if any(f == (k,) for f in task.hand.finger_joints) else f"joint {name}"


def _unit(task, name) -> str:
    return task.hand.joint_unit(name, "tau")


def _width(w: float, unit: str) -> str:
    """A band width in words: ``"0.238 N m"``, or ``"unbounded (no upper edge)"`` all along it."""
    return "unbounded (no upper edge)" if np.isinf(w) else f"{w:.3g} {unit}"


def _route_words(task, tables, bars, route) -> tuple:
    """The route's phases in words, one string each."""
    from qsplan.planner.plan.autoplan import route_phases

    x, out = tables.x, []
    for ph in route_phases(route):
        if ph[0] == "regrasp":
            _, g, h, i = ph
            out.append(f"regrasp at x = {x[i]:.4g} m from {_bar_at(bars, g, i).name} to {_bar_at(bars, h, i).name}")
            continue
        _, g, i0, i1, e = ph
        out.append(f"slide {'left' if i1 < i0 else 'right'} from x = {x[i0]:.4g} to {x[i1]:.4g} m along "
                   f"{_bar_at(bars, g, i0).name} ({_effort_words(task, tables.efforts[e])} torque-controlled)")  # fmt: skip
    return tuple(out)


def _narrowest(task, tables, route) -> str:
    slides = [s for s in route.steps if s.is_slide]
    if not slides:
        return ""
    s = min(slides, key=lambda s: s.width)
    return f"; narrowest band {_width(s.width, _unit(task, tables.efforts[s.effort]))}"


def _automatic(task, tables, bars, window, starts, goals, goal_name="goal", forbidden=frozenset()):
    from qsplan.planner.plan.obstacles import no_route_report
    from qsplan.planner.search.widest import widest_route

    i_start = tables.index(task.start_x)
    if any((g, i_start) in set(goals) for g in starts):
        return False, (), f"the start already meets the {goal_name} ({task.goal.describe()}): nothing to plan", None
    graph = window_graph(tables, window)
    route = widest_route(graph, [(g, i_start) for g in starts], goals, forbidden)
    if route is None:
        report = no_route_report(task, tables, graph, starts, i_start, goals, set(forbidden))
        return False, (), f"no banded route from the start to the {goal_name}: {report.summary}", None
    words = _route_words(task, tables, bars, route)
    text = (f"a banded route exists from the start to the {goal_name}: " + ", then ".join(words)
            + _narrowest(task, tables, route))  # fmt: skip
    return True, words, text, (route.steps[0].grasp, route.steps[-1].to_grasp)


def _blocked(task, tables, g, i0, i1) -> str:
    """Why row ``g`` has no banded slide from grid index ``i0`` to ``i1`` with one torque-controlled joint."""
    graph, x = tables.graph, tables.x
    step = 1 if i1 > i0 else -1
    for i in range(i0, i1 + step, step):
        if not graph.valid[g, i]:
            return f"at x = {x[i]:.4g} m: {tables.reason(task, g, i)}"
        if np.any(graph.touched[g, i] != graph.touched[g, i0]):
            return (f"at x = {x[i]:.4g} m a contact changes (a finger moves to another feature, or a sliding contact "
                    "reverses)")
    d = int(i1 > i0)
    lo, hi = min(i0, i1), max(i0, i1)
    w = graph.width[g, :, d, lo:hi + 1]  # (E, m): every joint's band along the segment
    e = int(np.argmax(np.min(w, axis=1)))
    k = lo + int(np.argmin(w[e]))
    return (f"no torque-controlled joint keeps a band {task.torque_resolution:g} wide along it: the widest, "
            f"{_effort_words(task, tables.efforts[e])}'s, narrows to {max(float(w[e].min()), 0.0):.3g} "
            f"{_unit(task, tables.efforts[e])} at x = {x[k]:.4g} m")  # fmt: skip


def _scripted(task, tables, bars, start):
    from qsplan.planner.search.widest import slide_widths

    hand = task.hand
    if hand.free_joints and task.start_joints is None:  # the scripted planner starts from the joints the task names
        names = ", ".join(hand.joint_names[j] for j in hand.free_joints)
        return False, (), (f"a scripted task (motion.waypoints) of a hand with free joints names them in [start] "
                           f"({names}): the planner refuses it as written (or give a [goal] instead)"), None  # fmt: skip
    g = start.row
    edges = slide_widths(tables.graph)
    xs = [task.start_x, *task.waypoints.tolist()]
    words = []
    for k, (a, b) in enumerate(zip(xs[:-1], xs[1:])):
        i0, i1 = tables.index(a), tables.index(b)
        d = int(i1 > i0)
        run = edges[g, :, d, min(i0, i1):max(i0, i1)]  # (E, m) the slide's steps
        ok = np.all(run > -np.inf, axis=1)
        name = f"segment {k + 1} (x = {a:.4g} to {b:.4g} m)"
        if not ok.any():
            why = _blocked(task, tables, g, i0, i1)
            return False, tuple(words), f"{name} has no banded slide along {_bar_at(bars, g, i0).name}: {why}", None
        e = int(np.argmax(np.where(ok, np.min(run, axis=1), -np.inf)))
        words.append(f"slide {'left' if b < a else 'right'} from x = {a:.4g} to {b:.4g} m along "
                     f"{_bar_at(bars, g, i0).name} "
                     f"({_effort_words(task, tables.efforts[e])} torque-controlled; narrowest band "
                     f"{_width(float(run[e].min()), _unit(task, tables.efforts[e]))})")  # fmt: skip
    return True, tuple(words), "every segment slides banded in the start's grasp: " + ", then ".join(words), (g, g)


def _nearest(x, bars, x0, most: int = 3) -> str:
    """The grasps banded nearest ``x0`` (m), nearest first: where a start or goal might go instead."""
    found = []
    for b in bars:
        ok = np.flatnonzero(np.any(b.banded, axis=0))
        if ok.size:
            k = ok[np.argmin(np.abs(x[ok] - x0))]
            found.append((abs(x[k] - x0), f"{b.name} at x = {x[k]:.4g} m"))
    if not found:
        return "no grasp is valid and banded anywhere on the palm"
    return "banded nearest: " + ", ".join(w for _, w in sorted(found)[:most])


def route_verdict(task, tables, bars, window, start, goal, starts, goals, beyond, forbidden=frozenset()) -> tuple:
    """``(ok, route words, verdict, ends)`` of the preview (see the module docstring); ``beyond`` a
    :class:`qsplan.planner.plan.failure.PalmReport` or None; ``ends`` the route's first and last rows, or None.  The
    goal is named as its check names itself (``goal.where``: a turn's slide previews its end, "slide's end").
    ``forbidden``: regrasps ``(from grasp, to grasp, i)`` the route may not use (the planner's:
    :func:`qsplan.planner.plan.autoplan.ending_in_place`)."""
    head = f"start {'ok' if start.ok else 'not ok'} / {goal.where} {'ok' if goal.ok else 'not ok'}"
    if beyond is not None:
        return False, (), f"{head} / {beyond.message.removeprefix('no plan: ')}", None
    if not start.ok or not goal.ok:
        bad = [c for c in (start, goal) if not c.ok]
        text = "; ".join(f"the {c.where}: {'; '.join(c.problems)} ({_nearest(tables.x, bars, c.x)})" for c in bad)
        return False, (), f"{head}: {text}", None
    ok, words, text, ends = _automatic(task, tables, bars, window, starts, goals, goal.where, forbidden) \
        if task.goal is not None else _scripted(task, tables, bars, start)  # fmt: skip
    return ok, words, f"{head} / {text} (a preview on the planner's grid: the planner judges its route again)", ends
