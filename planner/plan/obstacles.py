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

from qsplan.planner.task.goal import feature_text
from qsplan.planner.plan.failure import SEARCHED_BANDS, ConfigurationReport, failure_report
from qsplan.planner.states.contact import mode_name
from qsplan.planner.search.widest import SearchGraph, slide_widths, widest_route

#: ``planner_status`` of a geometry report: the sequence search ran over the band tables with any band accepted, and
#: no sequence of slides and regrasps joins the start and the goal.
SEARCHED_GEOMETRY = "ran: the sequence search over the band tables; no sequence of slides and regrasps joins start and goal"

__all__ = ["open_overlap", "NoRouteReport", "blocking_overlap", "no_route_report", "unreachable_goal_report"]


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

    @property
    def planner_status(self) -> str:
        """What ran: the sequence search over the band tables (:data:`SEARCHED_BANDS` when it found routes, all too
        narrow), or the search that found no route for the geometry."""
        return SEARCHED_BANDS if self.kind == "band closes" else SEARCHED_GEOMETRY

    def as_dict(self) -> dict:
        return {"kind": f"no route ({self.kind})", "summary": self.summary, "details": list(self.details),
                "band": None if self.band is None else self.band.as_dict(), "planner_status": self.planner_status,
                "message": self.message}  # fmt: skip


def _touching(task, tables, g, i) -> str:
    """What row ``g`` touches at grid index ``i``, in the polygon's numbering as written."""
    from qsplan.hands.paper_hand.grasps import touch_words

    grasp = tables.grasps[g].grasp
    return " and ".join(touch_words(task.hand, grasp, k, int(tables.graph.touched[g, i, k])) for k in range(2))


def _joint_words(task, name: str) -> str:
    """A joint in words: the paper's one-joint fingers ``"left finger"``, any other ``"joint left_distal"``."""
    k = task.hand.joint_names.index(name)
    return f"{name} finger" if any(f == (k,) for f in task.hand.finger_joints) else f"joint {name}"


def _asked(task, which) -> str | None:
    """What the task asks of its start or goal (``which``), in words, or None where it asks nothing but a position."""
    if which == "goal":
        feats = [f for f in (task.goal.left, task.goal.right) if f is not None]
        return task.goal.describe() if feats else None
    if task.hand.free_joints:
        if task.start_joints is None:
            return None
        names = task.hand.joint_names
        return "the [start] free joints " + ", ".join(f"{names[j]} = {task.start_joints[j]:.4g}"
                                                      for j in task.hand.free_joints)  # fmt: skip
    return f"start features {list(task.start_features)}"


def _matching(task, tables, which) -> list:
    """The rows whose grasp is the start's or the goal's (``which``), valid or not: a hand with free joints' ``[start]``
    rows (closed from those values), else the rows whose placements match the features asked (the vertex a placement
    touches not compared: an invalid configuration may touch none)."""
    rows = range(len(tables.grasps))
    hand = task.hand
    if which == "start" and hand.free_joints:
        start = task.start_free
        if start is None:
            return list(rows)
        return [g for g in rows if np.array_equal(np.asarray(tables.grasps[g].grasp.free, float), start)]
    feats = task.start_features if which == "start" else (task.goal.left, task.goal.right)
    texts = [feature_text(f) for f in feats]
    return [g for g in rows if tables.grasps[g].grasp.matches(*texts)]


def _open(task, tables, g, i):
    """Row ``g`` at grid index ``i`` with the fingers that close onto nothing fully open (:func:`open_overlap`)."""
    return open_overlap(task, tables.grasps[g].grasp, float(tables.x[i]), tables.q[g, i])


def open_overlap(task, grasp, x: float, q):
    """``q`` (n_j,; NaN at the joints that close onto nothing) with those joints fully open: ``(q, collision)``, the
    collision of a body with the workpiece, None where none overlaps it (a closing joint's NaN set to the end of its
    range its opening sense points to: :meth:`qsplan.hands.protocol.Hand.opening`; a link folded onto another there is
    the open pose's, not the grasp's obstacle); ``(None, None)`` when a free joint is unknown."""
    hand, lim = task.hand, task.joint_limits
    q = np.array(q, dtype=float)
    if np.any(~np.isfinite(q[list(hand.free_joints)])):
        return None, None
    mid = np.where(np.isfinite(q), q, 0.5 * (lim[:, 0] + lim[:, 1]))
    sense = hand.opening(grasp, x, mid)
    q = np.where(np.isfinite(q), q, np.where(sense > 0, lim[:, 1], lim[:, 0]))
    hits = [c for c in hand.collisions(task.pose(x), q) if "workpiece" in c.bodies]
    return q, (hits[0] if hits else None)


def blocking_overlap(task, tables, i, rows):
    """The first overlap among the tables' ``rows`` at grid index ``i``: a closed configuration whose bodies overlap,
    else one whose fingers, fully open where they close onto nothing, already overlap the workpiece.

    Returns
    -------
    (int, ndarray (n_j,), qsplan.hands.geometry.collision.Collision, bool) or None
        The row, its joints (rad or m), the overlap, and whether the fingers were opened.
    """
    from qsplan.planner.search.tables import OVERLAP

    for g in rows:
        if tables.why[g, i] == OVERLAP:
            hit = task.hand.collisions(task.pose(tables.x[i]), tables.q[g, i], first=True)
            if hit:
                return g, tables.q[g, i], hit[0], False
    for g in rows:
        if not tables.graph.valid[g, i] and np.any(~np.isfinite(tables.q[g, i])):
            q, hit = _open(task, tables, g, i)
            if hit is not None:
                return g, q, hit, True
    return None


def _reasons(task, tables, i, rows, most: int = 4) -> list:
    """The distinct reasons the rows ``rows`` are invalid at grid index ``i``, each with how many share it and one
    example, in order of first appearance."""
    seen = {}
    for g in rows:
        if not tables.graph.valid[g, i]:
            seen.setdefault(tables.reason(task, g, i), []).append(g)
    n = len(rows)
    return [f"{tables.grasps[gs[0]].label}: {why}" if n == 1 else
            f"{why} ({len(gs)} of {n} grasps, e.g. {tables.grasps[gs[0]].label})"
            for why, gs in list(seen.items())[:most]]  # fmt: skip


def unreachable_goal_report(task, tables, i, which, grasps_at) -> ConfigurationReport:
    """The start or goal (``which``) at grid index ``i`` has no valid grasp with the asked features: the reasons the
    candidates are invalid there, the grasps valid there instead, and the bodies that overlap (a closed grasp's, or
    a finger's fully open where it closes onto nothing), with their configuration."""
    x = float(tables.x[i])
    asked = _asked(task, which)
    cands = grasps_at(tables, task, i)
    everyone = list(range(len(tables.grasps)))
    lines = _reasons(task, tables, i, cands[:6] if asked else everyone)
    if asked:
        lines += [f"{tables.grasps[g].label} is valid there with {_touching(task, tables, g, i)}"
                  for g in everyone if tables.graph.valid[g, i]][:4]  # fmt: skip
    if not lines:  # nothing meets it, nothing is valid: why each grasp is not
        lines = _reasons(task, tables, i, everyone)
    if asked:
        reason = f"the {which} is unreachable on this palm: no grasp meeting it ({asked}) is a valid configuration"
    else:
        reason = (f"the {which} is unreachable on this palm: none of the {len(everyone)} grasps the planner considered "
                  f"(the {which} names no features: any would do) is a valid configuration at x = {x:.4g} m")  # fmt: skip
    reason += f" ({'; '.join(lines)})" if lines else " (no candidate grasp of this hand has those features anywhere)"
    found = blocking_overlap(task, tables, i, (cands or _matching(task, tables, which)) if asked else everyone)
    if found is None:
        return ConfigurationReport(f"the {which}", f"the {which}", x, None, reason)
    g, q, hit, opened = found
    where = "with the fingers that close onto nothing fully open, " if opened else ""
    reason += f"; {where}grasp {tables.grasps[g].label}: {hit.message}"
    return ConfigurationReport(f"the {which}", f"the {which}", x, tuple(float(v) for v in q), reason, hit.bodies,
                               hit.area, hit.depth)  # fmt: skip


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
        narrow = min((s for s in route.steps if s.is_slide), key=lambda s: s.width)
        row = tables.grasps[narrow.grasp]
        e, d = tables.efforts[narrow.effort], float(np.sign(narrow.to_i - narrow.i))
        x0, x1 = float(tables.x[narrow.i]), float(tables.x[narrow.to_i])
        band = failure_report(task, f"the widest route's narrowest slide (grasp {row.label})", x0, x1, e, d, None,
                              xs=np.array([x0, x1]), grasp=row.grasp, path=row.path, status=SEARCHED_BANDS)  # fmt: skip
        u = task.hand.joint_unit(e, "tau")  # a jaw's force in N
        summary = (f"every route's guaranteed band is narrower than the torque resolution "
                   f"({task.torque_resolution:g} {u}): the widest route's narrowest band is {route.width:.4g} {u} "
                   f"at x = {x0:.4g} m (grasp {row.label}, {_joint_words(task, e)} torque-controlled)")  # fmt: skip
        return NoRouteReport("band closes", summary, (), band)
    geo = [r for r in (widest_route(geometric, (s, i_start), goals, forbidden) for s in starts) if r is not None]
    details = tuple(f"grasp {tables.grasps[s].label} from x = {tables.x[i_start]:.4g} m toward {tables.x[i_goal]:.4g} m: "
                    f"{_blocking(task, tables, s, i_start, i_goal)}" for s in starts)  # fmt: skip
    if geo:
        route = geo[0]
        allowed = slide_widths(anyband)
        step = next(st for st in route.steps if st.is_slide
                    and allowed[st.grasp, :, int(st.to_i > st.i), min(st.i, st.to_i)].max() == -np.inf)  # fmt: skip
        row, d = tables.grasps[step.grasp], float(np.sign(step.to_i - step.i))
        x0, x1 = float(tables.x[step.i]), float(tables.x[step.to_i])
        reports = [failure_report(task, f"the slide from x = {x0:.4g} to {x1:.4g} m (grasp {row.label}, "
                                  f"{_joint_words(task, e)} torque-controlled)", x0, x1, e, d, None,
                                  xs=np.array([x0, x1]), grasp=row.grasp, path=row.path, status=SEARCHED_BANDS)
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
