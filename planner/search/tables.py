"""Band tables: every candidate grasp judged along the palm, batched (the search's input, Section 5.2).

For each candidate grasp (which feature each finger touches, :mod:`qsplan.hands.grasps`) and
each workpiece ``x`` of a grid, :func:`band_tables` judges the configuration as the plan's
dense sweep does (:func:`qsplan.planner.states.contact.check_contact_state`): the
four contacts exist (the grasp's closed form), the joints inside their limits, no two bodies
overlapping (:mod:`qsplan.hands.collision`), and for each effort-controlled finger
and each direction of the slide the guaranteed 4S band with every competitor precluded
(:func:`qsplan.mechanics.bands.batched_robust.robust_band_arrays`, batched over the grid and the
grasps; per-state competitors: a mode kinematically impossible at a state cannot occur there).
The scenes are never built as objects: their arrays come from the grasp's closed form for all
states at once (:func:`qsplan.planner.states.grasped.grasp_scene_arrays`), a state's scene
only where a per-state search needs it.  The tables are
the search graph of :mod:`qsplan.planner.search.widest`; the plan built from the route is
judged again sample by sample, so the tables only propose.  Units SI (m, rad, N m).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from qsplan.mechanics.errors import QsplanError
from qsplan.planner.search.widest import SearchGraph

__all__ = ["BandTables", "band_tables", "table_grid", "GRID_STEP", "OVERLAP", "SEARCH_MARGIN"]

#: Grid step (m) of the tables: the plan's dense-sweep step, so that the tables judge the states
#: the plan will judge (:data:`qsplan.planner.plan.scripted.SWEEP_STEP`).
GRID_STEP = 5e-4

#: What :attr:`BandTables.why` holds where two bodies overlap (:meth:`BandTables.reason` says which, and by how much).
OVERLAP = "two bodies overlap"

#: Relative slack of the grid's end counts: ``(end - start) / h`` computes a hair below its integer when the
#: span is a multiple of the step (floating point), which would drop the last grid point.
_GRID_ROUNDING = 1e-9

#: How far (m) beyond the start and the goal the tables reach: room for the detours a regrasp may
#: need (a slide away from the goal to where another grasp is valid); 6 cm is most of the span between
#: the default hand's fingers (0.18 m) minus a workpiece.
SEARCH_MARGIN = 0.06

#: The scene arrays the tables stack (:class:`qsplan.hands.batch_scenes.SceneArrays`).
_ARRAYS = ("Wn", "Wt", "Jn", "Jt", "g_obj", "g_man")


@dataclass(frozen=True, slots=True, eq=False)
class BandTables:
    """The judged grid.

    Attributes
    ----------
    grasps : tuple
        The candidate grasps (:class:`qsplan.hands.grasps.Grasp`), indexed as the tables' first axis.
    x : ndarray, shape (n,)
        The grid of workpiece x (m).
    graph : SearchGraph
        ``valid (G, n)``, ``touched (G, n, 2)``, ``width (G, 2, 2, n)`` (N m; ``-inf`` without a band).
    q : ndarray, shape (G, n, 2)
        Joint angles (rad; NaN where the grasp has no configuration).
    lower, upper : ndarray, shape (G, 2, 2, n)
        The guaranteed bands (N m; NaN without one).
    why : ndarray of object, shape (G, n)
        Why a configuration is invalid, in words (None where valid; :data:`OVERLAP` where two bodies overlap,
        :meth:`reason` says which).
    states : int
        Configurations judged (grid points x grasps), and
    band_states : int
        of them, band evaluations (valid configurations x effort fingers x directions).
    seconds : float
        Wall time (s) of building the tables.
    """

    grasps: tuple
    x: np.ndarray
    graph: SearchGraph
    q: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    why: np.ndarray
    states: int
    band_states: int
    seconds: float

    def index(self, x: float) -> int:
        """The grid index of ``x`` (m): the nearest grid point."""
        return int(np.argmin(np.abs(self.x - x)))

    def reason(self, task, g: int, i: int) -> str | None:
        """Why grasp ``g`` is invalid at grid index ``i``, in words (None where valid): the overlapping bodies
        and their overlap measured here, for reports, not for every configuration of the tables."""
        why = self.why[g, i]
        if why != OVERLAP:
            return why
        from qsplan.hands.collision import find_collisions

        hit = find_collisions(task.hand, task.pose(self.x[i]), self.q[g, i], first=True)
        return hit[0].message if hit else "two bodies overlap"


def table_grid(start_x: float, goal_x: float, limit, step: float = GRID_STEP, margin: float = SEARCH_MARGIN):
    """The grid (m), shape (n,): through ``start_x`` and ``goal_x`` exactly, spacing at most ``step``, reaching
    ``margin`` beyond both and no further than ``limit``: ``(lo, hi)`` (the workpiece x on the palm,
    :func:`qsplan.planner.task.goal.palm_x_range`), or a number for ``|x| <= limit``.

    Raises
    ------
    QsplanError
        ``start_x`` or ``goal_x`` outside the limits (a task beyond the palm is refused before its tables:
        :func:`qsplan.planner.plan.failure.palm_report`).
    """
    lo_lim, hi_lim = (-float(limit), float(limit)) if np.ndim(limit) == 0 else (float(limit[0]), float(limit[1]))
    for name, x in (("start_x", start_x), ("goal_x", goal_x)):
        if not lo_lim <= x <= hi_lim:
            raise QsplanError(f"{name}: {x:g} m is outside the grid's limits [{lo_lim:g}, {hi_lim:g}] m")
    span = goal_x - start_x
    k = int(np.ceil(abs(span) / step))
    h = abs(span) / k if k else step
    lo = max(min(start_x, goal_x) - margin, lo_lim)
    hi = min(max(start_x, goal_x) + margin, hi_lim)
    below = int(np.floor((min(start_x, goal_x) - lo) / h + _GRID_ROUNDING))
    above = int(np.floor((hi - max(start_x, goal_x)) / h + _GRID_ROUNDING))
    base = min(start_x, goal_x)
    grid = base + h * np.arange(-below, k + above + 1)
    # the start and the goal exactly (no rounding of base + h * k)
    grid[below] = base
    grid[below + k] = max(start_x, goal_x)
    return np.clip(grid, lo_lim, hi_lim)  # an end point a rounding beyond a limit (_GRID_ROUNDING) is put on it


def _no_contact(grasp, finger: int) -> str:
    """Why ``finger`` (0 left, 1 right) has no contact of ``grasp``'s placement, in words."""
    from qsplan.hands.grasps import TipOnEdge

    side = ("left", "right")[finger]
    placement = (grasp.left, grasp.right)[finger]
    if isinstance(placement, TipOnEdge):
        return (f"the {side} fingertip cannot rest on edge {placement.edge} (out of reach, at an end of the edge, "
                "or the finger would cross the workpiece)")  # fmt: skip
    return (f"the {side} finger's inner edge cannot rest on a workpiece vertex (the vertex of tangency lies beyond "
            "the finger's length, or the finger would cross the workpiece)")  # fmt: skip


def _geometry(task, grasp, x):
    """Configurations of ``grasp`` at ``x`` (n,): ``(conf, valid (n,), why list)``; overlapping configurations get
    :data:`OVERLAP` (their message is measured only when a report asks: :meth:`BandTables.reason`)."""
    from qsplan.hands.grasp_geometry import grasp_configurations
    from qsplan.hands.collision import find_collisions_batch
    from qsplan.planner.states.contact import limit_problem

    conf = grasp_configurations(task.hand, grasp, x)
    valid = np.array(conf.ok, dtype=bool)
    why = [None] * len(x)
    for k in np.flatnonzero(~valid):
        why[k] = _no_contact(grasp, int(np.argmin(conf.finger_ok[k])))
    lim = task.joint_limits
    inside = np.all((conf.q >= lim[:, 0]) & (conf.q <= lim[:, 1]), axis=1)
    for k in np.flatnonzero(valid & ~inside):
        why[k] = limit_problem(task, conf.q[k])
    valid &= inside
    idx = np.flatnonzero(valid)
    hit = np.zeros(len(x), bool)
    if idx.size:
        hit[idx] = find_collisions_batch(task.hand, conf.poses(task.hand.rest_height)[idx], conf.q[idx])
    for k in np.flatnonzero(hit):
        why[k] = OVERLAP
    return conf, valid & ~hit, why


def band_tables(task, grasps, x, progress=None) -> BandTables:
    """Judge every grasp of ``grasps`` at every ``x`` (m, shape (n,)) of the grid (see the module docstring).

    Parameters
    ----------
    task : qsplan.planner.task.task.Task
    grasps : sequence of qsplan.hands.grasps.Grasp
    x : ndarray, shape (n,)
    progress : callable, optional

    Returns
    -------
    BandTables
    """
    from qsplan.planner.states.grasped import grasp_scene_arrays

    t0 = time.perf_counter()
    x = np.asarray(x, dtype=float)
    G, n = len(grasps), len(x)
    valid = np.zeros((G, n), bool)
    touched = np.full((G, n, 2), -1, dtype=int)
    q = np.full((G, n, 2), np.nan)
    lower = np.full((G, 2, 2, n), np.nan)
    upper = np.full((G, 2, 2, n), np.nan)
    why = np.empty((G, n), dtype=object)
    parts = []  # per grasp with valid configurations: (g, idx, scene arrays, generic scenes, dq_dx)
    for g, grasp in enumerate(grasps):
        conf, ok, reasons = _geometry(task, grasp, x)
        valid[g], touched[g], q[g] = ok, conf.touched, conf.q
        why[g] = reasons
        idx = np.flatnonzero(ok)
        if progress:
            progress(f"  grasp {g + 1}/{G} {grasp.label}: {idx.size} of {n} configurations valid")
        if not idx.size:
            continue
        failed = {}
        arrays, generic = grasp_scene_arrays(task.hand, conf, idx, failed)  # contacts found once per configuration
        for k, why_not in failed.items():  # no four-contact scene there: not a configuration of this grasp
            valid[g, idx[k]] = False
            why[g, idx[k]] = why_not
        keep = np.array([k not in failed for k in range(len(idx))], dtype=bool)
        if keep.any():
            rows = np.flatnonzero(keep)
            renumber = {int(k): j for j, k in enumerate(rows)}
            parts.append((g, idx[keep], [getattr(arrays, f)[keep] for f in _ARRAYS],
                          {renumber[k]: s for k, s in generic.items() if k in renumber}, conf.dq_dx[idx[keep]]))  # fmt: skip
    band_states = 0
    for e in range(2):  # one batch per effort finger: the states of every grasp and direction
        if parts:
            b = _effort_bands(task, parts, e)
            band_states += b.lower.size
            at = 0
            for d in range(2):
                for g, idx, *_ in parts:
                    part = slice(at, at + idx.size)
                    at += idx.size
                    lower[g, e, d, idx], upper[g, e, d, idx] = b.lower[part], b.upper[part]
    width = np.where(np.isnan(lower) | np.isnan(upper), -np.inf, upper - lower)
    graph = SearchGraph(valid, touched, width, float(task.torque_resolution))
    return BandTables(tuple(grasps), x, graph, q, lower, upper, why, G * n, band_states, time.perf_counter() - t0)


def _effort_bands(task, parts, e: int):
    """The guaranteed 4S bands, competitors precluded, of every configuration of ``parts`` with finger ``e``
    effort-controlled, moving left (``d = 0``) then right (``d = 1``): one :class:`StateBatch` from the arrays,
    :func:`qsplan.mechanics.bands.batched_robust.robust_band_arrays` (NaN edges where there is no band)."""
    from qsplan.hands.two_finger_analytic import scene_from_arrays
    from qsplan.mechanics.bands.batched import LazyScenes, batch_from_arrays
    from qsplan.mechanics.bands.batched_robust import robust_band_arrays

    from qsplan.planner.states.contact import MODE
    from qsplan.planner.states.grasped import controlled

    effort = np.arange(2) == e
    speeds = [(1.0 if d else -1.0) * task.workpiece_speed for d in range(2)]
    stacked = [np.concatenate([arrays[i] for _ in speeds for _, _, arrays, _, _ in parts]) for i in range(len(_ARRAYS))]
    velocity = np.concatenate([dq_dx[:, 1 - e] * xdot for xdot in speeds for *_, dq_dx in parts])
    where = [(generic, k) for _ in speeds for _, idx, _, generic, _ in parts for k in range(idx.size)]

    def scene(s):  # the scene of state s, as grasp_scenes and controlled build it (a per-state search needs it)
        generic, k = where[s]
        if k in generic:
            return controlled(generic[k], e, velocity[s])
        return scene_from_arrays(task.hand, *(a[s].copy() for a in stacked), effort, velocity[s], 0.0)

    joint_velocity = np.where(effort, np.nan, velocity[:, None])
    batch = batch_from_arrays(LazyScenes(velocity.size, scene), *stacked, joint_velocity)
    return robust_band_arrays(batch, MODE, task.mu_range, shared=task.shared_mu, force_margin=task.force_margin)
