"""Why an automatic task has no plan: the obstacle named (issue 14, item 4).

Three answers, from the band tables (:mod:`qsplan.planner.search.tables`):

* **the start or goal unreachable**: no grasp with the asked features is a valid configuration
  there; the report lists each candidate and what is wrong with it (a joint beyond its limit,
  two bodies overlapping, the finger not reaching the feature);
* **blocked by geometry**: even with any band accepted, no sequence of slides and regrasps joins
  start and goal; the report names, for each start grasp, where its slides end toward the goal
  and why (the joint limit, the overlap, the contact that changes) and that no regrasp reaches a
  grasp that continues;
* **the bands close**: the geometry allows a route but every route has a band narrower than the
  torque resolution; the report takes the widest route ignoring the resolution, its narrowest
  slide, and gives the segment report of :func:`qsplan.planner.plan.failure.failure_report`
  there: the friction from which the band closes and the competitor mode that closes it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qsplan.planner.plan.failure import ConfigurationReport, failure_report
from qsplan.planner.states.contact import mode_name
from qsplan.planner.search.widest import SearchGraph, slide_widths, widest_route

__all__ = ["NoRouteReport", "no_route_report", "unreachable_goal_report"]


@dataclass(frozen=True, slots=True, eq=False)
class NoRouteReport:
    """No route from the start to the goal.

    Attributes
    ----------
    kind : str
        ``"geometry"`` or ``"band closes"``.
    summary : str
        The obstacle in words.
    details : tuple of str
        Supporting lines (per grasp).
    band : FailureReport or None
        For ``"band closes"``: the segment report at the narrowest slide of the widest route.
    """

    kind: str
    summary: str
    details: tuple
    band: object = None

    @property
    def message(self) -> str:
        tail = f" {self.band.message}" if self.band is not None else ""
        return f"no plan: {self.summary}.{tail}"

    def as_dict(self) -> dict:
        return {"kind": f"no route ({self.kind})", "summary": self.summary, "details": list(self.details),
                "band": None if self.band is None else self.band.as_dict(), "message": self.message}  # fmt: skip


def _touching(task, tables, g, i) -> str:
    """What row ``g`` touches at grid index ``i``, in the polygon's numbering as written."""
    from qsplan.hands.grasps import touch_words

    grasp = tables.grasps[g].grasp
    return " and ".join(touch_words(task.hand, grasp, k, int(tables.graph.touched[g, i, k])) for k in range(2))


def _joint_words(task, name: str) -> str:
    """A joint in words: the paper's one-joint fingers ``"left finger"``, any other ``"joint left_distal"``."""
    k = task.hand.joint_names.index(name)
    return f"{name} finger" if any(f == (k,) for f in task.hand.finger_joints) else f"joint {name}"


def unreachable_goal_report(task, tables, i, which, grasps_at) -> ConfigurationReport:
    """The start or goal (``which``) at grid index ``i`` has no valid grasp with the asked features."""
    cands = grasps_at(tables, task, i)
    lines = [f"{tables.grasps[g].label}: {tables.reason(task, g, i)}" for g in cands[:6] if not tables.graph.valid[g, i]]
    lines += [f"{tables.grasps[g].label} is valid there with {_touching(task, tables, g, i)}"
              for g in range(len(tables.grasps)) if tables.graph.valid[g, i]][:4]  # fmt: skip
    if not lines:  # nothing meets it, nothing is valid: why each candidate is not
        lines = [f"{tables.grasps[g].label}: {tables.reason(task, g, i)}" for g in range(len(tables.grasps))][:4]
    feats = task.goal.describe() if which == "goal" else f"start features {list(task.start_features)}"
    reason = (f"the {which} is unreachable on this palm: no grasp meeting it ({feats}) is a valid configuration"
              + (f" ({'; '.join(lines)})" if lines else " (no candidate grasp of this hand has those features anywhere)"))  # fmt: skip
    return ConfigurationReport(f"the {which}", f"the {which}", float(tables.x[i]), None, reason)


def _blocking(task, tables, g, i0, i1) -> str:
    """Where grasp ``g``'s slides from ``i0`` toward ``i1`` end, and why."""
    step = 1 if i1 >= i0 else -1
    touched0 = tables.graph.touched[g, i0]
    for i in range(i0, i1 + step, step):
        if not tables.graph.valid[g, i]:
            return f"at x = {tables.x[i]:.4g} m: {tables.reason(task, g, i)}"
        if np.any(tables.graph.touched[g, i, :2] != touched0[:2]):
            return f"at x = {tables.x[i]:.4g} m a finger's contact moves to another feature"
        if np.any(tables.graph.touched[g, i] != touched0):
            return f"at x = {tables.x[i]:.4g} m a sliding contact's direction reverses (a mode change, eq. 16)"
    return "nothing blocks its geometry"


def no_route_report(task, tables, graph, starts, i_start, goals, forbidden) -> NoRouteReport:
    """What blocks every route from the start grasps ``starts`` at ``i_start`` to ``goals`` (``(g, i)`` nodes)."""
    i_goal = goals[0][1]
    # any band: width >= 0 counts (the resolution dropped); geometry: every valid slide counts
    anyband = SearchGraph(graph.valid, graph.touched, graph.width, 0.0)
    every = np.broadcast_to(np.where(graph.valid[:, None, None, :], 1.0, -np.inf), graph.width.shape)
    geometric = SearchGraph(graph.valid, graph.touched, every, 0.0)
    routes = [r for r in (widest_route(anyband, (s, i_start), goals, forbidden) for s in starts) if r is not None]
    if routes:
        route = max(routes, key=lambda r: r.width)
        narrow = min((s for s in route.steps if s.kind == "slide"), key=lambda s: s.width)
        row = tables.grasps[narrow.grasp]
        e, d = tables.efforts[narrow.effort], float(np.sign(narrow.to_i - narrow.i))
        x0, x1 = float(tables.x[narrow.i]), float(tables.x[narrow.to_i])
        band = failure_report(task, f"the widest route's narrowest slide (grasp {row.label})", x0, x1, e, d, None,
                              xs=np.array([x0, x1]), grasp=row.grasp, path=row.path)  # fmt: skip
        summary = (f"every route's guaranteed band is narrower than the torque resolution "
                   f"({task.torque_resolution:g} N m): the widest route's narrowest band is {route.width:.4g} N m "
                   f"at x = {x0:.4g} m (grasp {row.label}, {_joint_words(task, e)} torque-controlled)")  # fmt: skip
        return NoRouteReport("band closes", summary, (), band)
    geo = [r for r in (widest_route(geometric, (s, i_start), goals, forbidden) for s in starts) if r is not None]
    details = tuple(f"grasp {tables.grasps[s].label} from x = {tables.x[i_start]:.4g} m toward {tables.x[i_goal]:.4g} m: "
                    f"{_blocking(task, tables, s, i_start, i_goal)}" for s in starts)  # fmt: skip
    if geo:
        route = geo[0]
        allowed = slide_widths(anyband)
        step = next(st for st in route.steps if st.kind == "slide"
                    and allowed[st.grasp, :, int(st.to_i > st.i), min(st.i, st.to_i)].max() == -np.inf)  # fmt: skip
        row, d = tables.grasps[step.grasp], float(np.sign(step.to_i - step.i))
        x0, x1 = float(tables.x[step.i]), float(tables.x[step.to_i])
        reports = [failure_report(task, f"the slide from x = {x0:.4g} to {x1:.4g} m (grasp {row.label}, "
                                  f"{_joint_words(task, e)} torque-controlled)", x0, x1, e, d, None,
                                  xs=np.array([x0, x1]), grasp=row.grasp, path=row.path)
                   for e in tables.efforts]  # fmt: skip
        band = max(reports, key=lambda r: -1.0 if r.mu_closes is None else r.mu_closes)
        which = "either finger" if len(tables.efforts) == 2 else "any joint"
        summary = (f"the geometry allows a route, but at x = {x0:.4g} m (grasp {row.label}, sliding "
                   f"{'right' if d > 0 else 'left'}) {mode_name(task.formation.mode)} has no guaranteed band for the "
                   f"whole friction range {list(task.mu_range)} with {which} torque-controlled")  # fmt: skip
        return NoRouteReport("band closes", summary, details + tuple(r.message for r in reports), band)
    regrasps = f"; {len(forbidden)} regrasps OMPL could not realise" if forbidden else ""
    summary = ("no sequence of slides and regrasps joins the start and the goal: " + "; ".join(details)
               + f"; no regrasp reaches a grasp that continues{regrasps}")  # fmt: skip
    return NoRouteReport("geometry", summary, details)
