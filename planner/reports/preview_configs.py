"""The start and the goal of a task closed and judged: the grasp, the joint limits, the overlapping bodies (issue 25).

:func:`configuration_check` reads one column of the planner's band tables (:mod:`qsplan.planner.search.tables`):
the grasps that meet the task's start (or goal) at its grid point, the planner's own choice of them
(:func:`qsplan.planner.plan.autoplan.start_nodes`, :func:`~qsplan.planner.plan.autoplan.goal_nodes`); where none
is valid, the candidate closest to one is explained in full: every joint beyond its limit and by how much, every
pair of bodies that overlap and by how much (:meth:`qsplan.hands.protocol.Hand.collisions`), or why the fingers
do not close onto the features.  Units SI (m, rad; m for a prismatic joint).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qsplan.planner.task.goal import feature_text

__all__ = ["ConfigurationCheck", "LimitExcess", "configuration_check", "features_words", "goal_candidates",
           "start_candidates"]

@dataclass(frozen=True, slots=True)
class LimitExcess:
    """A joint beyond its limit.

    Attributes
    ----------
    joint : str
    value, lower, upper : float
        Its position and its range (rad, or m for a prismatic joint).
    unit : str
    """

    joint: str
    value: float
    lower: float
    upper: float
    unit: str

    @property
    def excess(self) -> float:
        """How far beyond the nearer limit (rad or m), positive."""
        return float(self.value - self.upper if self.value > self.upper else self.lower - self.value)

    @property
    def message(self) -> str:
        side, limit = ("upper", self.upper) if self.value > self.upper else ("lower", self.lower)
        return (f"joint {self.joint} at {self.value:.4g} {self.unit} is {self.excess:.3g} {self.unit} beyond its "
                f"{side} limit {limit:g} {self.unit}")  # fmt: skip

    def as_dict(self) -> dict:
        return {"joint": self.joint, "value": self.value, "limits": [self.lower, self.upper], "unit": self.unit,
                "excess": self.excess, "message": self.message}  # fmt: skip


@dataclass(frozen=True, slots=True)
class ConfigurationCheck:
    """The start or the goal of a task, closed.

    Attributes
    ----------
    where : str
        ``"start"`` or ``"goal"``.
    x : float
        Workpiece x (m).
    row : int or None
        The tables' row drawn and explained (None: no grasp of the tables meets it, or beyond the palm).
    label : str or None
        That grasp in words.
    q : tuple of float or None
        Its joints (rad or m; NaN where a finger closes onto nothing).
    valid : int
        How many of the grasps meeting it are valid configurations there (the planner may start or end in any).
    candidates : int
        How many grasps of the tables meet it there.
    contact : str or None
        Why the grasp's contacts do not exist there, in words.
    limits : tuple of LimitExcess
        Every joint beyond its limit.
    collisions : tuple of qsplan.hands.geometry.collision.Collision
        Every pair of bodies overlapping beyond its tolerance (names, area m^2, depth m).
    beyond_palm : str or None
        The task puts the workpiece's resting edge beyond the palm here
        (:func:`qsplan.planner.plan.failure.palm_report`'s message).
    note : str or None
        What the check says of a goal it does not judge (a goal that turns the workpiece: not previewed, or refused
        by the route and why); None: judged.  Such a check is not ok, has no x (``x`` is where the preview stopped)
        and its message is the note.
    refused : bool
        Such a goal is one ``qsplan plan`` refuses (the note says why).
    """

    where: str
    x: float
    row: int | None
    label: str | None
    q: tuple | None
    valid: int
    candidates: int
    contact: str | None = None
    limits: tuple = ()
    collisions: tuple = ()
    beyond_palm: str | None = None
    note: str | None = None
    refused: bool = False

    @property
    def ok(self) -> bool:
        return self.valid > 0 and self.note is None

    @property
    def previewed(self) -> bool:
        """Whether the check judged it (a turning goal's is not)."""
        return self.note is None

    @property
    def problems(self) -> list:
        """What is wrong with the explained grasp, one string each (empty where ok)."""
        if self.ok:
            return []
        out = [self.beyond_palm] if self.beyond_palm else []
        out += [self.contact] if self.contact else []
        out += [c.message for c in self.collisions] + [lim.message for lim in self.limits]
        return out or ["no grasp of the hand meets it here"]

    @property
    def message(self) -> str:
        if self.note is not None:
            return f"{self.where}: {self.note}"
        head = f"{self.where} (x = {self.x:.4g} m)"
        if self.ok:
            more = f"; {self.valid} of {self.candidates} grasps meeting it are valid" if self.valid > 1 else ""
            return f"{head}: ok, grasp {self.label}{more}"
        grasp = f" with grasp {self.label}" if self.label else ""
        return f"{head}: not a valid configuration{grasp}: " + "; ".join(self.problems)

    def as_dict(self) -> dict:
        return {"where": self.where, "x_m": self.x if self.previewed else None, "ok": self.ok,
                "previewed": self.previewed, "refused": self.refused, "grasp": self.label,
                "q": None if self.q is None else [None if not np.isfinite(v) else float(v) for v in self.q],
                "valid_grasps": self.valid, "candidate_grasps": self.candidates, "contact": self.contact,
                "limits": [lim.as_dict() for lim in self.limits],
                "collisions": [{"bodies": list(c.bodies), "area_m2": c.area, "depth_m": c.depth, "message": c.message}
                               for c in self.collisions],
                "beyond_palm": self.beyond_palm, "message": self.message}  # fmt: skip


def features_words(task, where: str) -> str:
    """What the task asks of the start or the goal (``where``), in words: its features, or a hand's free joints."""
    hand = task.hand
    if where == "start" and hand.free_joints:
        if task.start_joints is None:
            return "any grasp of the free joints' grid"
        return "the [start] free joints (" + ", ".join(f"{hand.joint_names[j]} {task.start_joints[j]:.4g}"
                                                       for j in hand.free_joints) + ")"  # fmt: skip
    feats = task.start_features if where == "start" else (task.goal.left, task.goal.right) if task.goal else (None, None)
    parts = []
    for side, f in zip(("left", "right"), feats):
        if f is None:
            continue
        kind, k = f
        if kind == "inner":
            parts.append(f"the {side} finger's inner edge on a vertex")
        else:
            parts.append(f"the {side} finger on vertex {k}" if kind == "vertex" else f"the {side} fingertip on edge {k}")
    return " and ".join(parts) or "any grasp"


def _meeting(tables, task, i, feats) -> list:
    """Rows whose grasp meets ``feats`` at grid index ``i`` (a paper placement's vertex there), else whose grasp
    matches them wherever its contacts are (an invalid configuration may touch nothing)."""
    from qsplan.hands.paper_hand.grasps import grasp_meets

    hand, rows = task.hand, tables.grasps
    there = [g for g in range(len(rows)) if grasp_meets(hand, rows[g].grasp, tables.graph.touched[g, i, :2], feats)]
    return there or [g for g in range(len(rows)) if rows[g].grasp.matches(*feats)]


def start_candidates(tables, task, i) -> list:
    """Rows of the tables that are the task's start at grid index ``i``, valid or not: its ``[start]`` free joints
    (a hand with free joints; any row where none are named), else its start features."""
    from qsplan.planner.plan.autoplan import SAME_FREE

    hand = task.hand
    if hand.free_joints:
        if task.start_joints is None:
            return list(range(len(tables.grasps)))
        free = list(hand.free_joints)
        near = np.abs(tables.q[:, i, free] - np.asarray(task.start_joints)[free]) <= SAME_FREE
        return [int(g) for g in np.flatnonzero(np.all(near, axis=1))]
    return _meeting(tables, task, i, [feature_text(f) for f in task.start_features])


def goal_candidates(tables, task, i) -> list:
    """Rows of the tables meeting the goal's features at grid index ``i``, valid or not (a scripted task: its start's
    grasp, which every segment keeps)."""
    if task.goal is None:
        return start_candidates(tables, task, i)
    return _meeting(tables, task, i, [feature_text(task.goal.left), feature_text(task.goal.right)])


def _limit_excess(task, q) -> tuple:
    lim, units = task.joint_limits, task.hand.joint_units()
    return tuple(LimitExcess(name, float(q[k]), float(lim[k, 0]), float(lim[k, 1]), units[k])
                 for k, name in enumerate(task.hand.joint_names) if not lim[k, 0] <= q[k] <= lim[k, 1])  # fmt: skip


def configuration_check(task, tables, i, where, valid_rows, candidates, label, wanted=None) -> ConfigurationCheck:
    """The start or goal (``where``) at grid index ``i`` of ``tables``.

    Parameters
    ----------
    valid_rows : sequence of int
        The planner's valid rows there (:func:`qsplan.planner.plan.autoplan.start_nodes` ...).
    candidates : sequence of int
        Every row meeting it there, valid or not (:func:`start_candidates`, :func:`goal_candidates`).
    label : callable
        ``label(g, i)``: row ``g`` at ``i`` in words.
    wanted : str, optional
        What the task asks there, in words (:func:`features_words`), for the report of no candidate.
    """
    x = float(tables.x[i])
    if valid_rows:
        g = int(valid_rows[0])
        return ConfigurationCheck(where, x, g, label(g, i), tuple(float(v) for v in tables.q[g, i]), len(valid_rows),
                                  len(candidates))  # fmt: skip
    if not candidates:
        what = f"no grasp the hand offers has {wanted}" if wanted else "no grasp the hand offers meets it"
        return ConfigurationCheck(where, x, None, None, None, 0, 0, what + " anywhere on the palm")
    finite = [g for g in candidates if np.all(np.isfinite(tables.q[g, i]))]  # closed: its overlaps and limits measured
    g = int((finite or candidates)[0])
    q = tables.q[g, i]
    limits = collisions = ()
    contact = None
    if np.all(np.isfinite(q)):
        limits = _limit_excess(task, q)
        collisions = tuple(task.hand.collisions(task.pose(x), q))
    if not limits and not collisions:
        from qsplan.planner.plan.obstacles import blocking_overlap

        contact = tables.reason(task, g, i)
        found = blocking_overlap(task, tables, i, candidates)  # a body in the way: where the fingers cannot close
        if found is not None:
            g, q, hit, opened = found
            collisions, contact = (hit,), tables.reason(task, g, i) if opened else None
    return ConfigurationCheck(where, x, g, label(g, i), tuple(float(v) for v in q), 0, len(candidates), contact,
                              limits, collisions)  # fmt: skip
