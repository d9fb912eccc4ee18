"""Band tables: every candidate grasp judged along the palm, batched (the search's input, Section 5.2).

For each candidate grasp (which feature each finger touches, :mod:`qsplan.hands.paper_hand.grasps`) and
each workpiece ``x`` of a grid, :func:`band_tables` judges the configuration as the plan's
dense sweep does (:func:`qsplan.planner.states.contact.check_contact_state`): the
four contacts exist (the grasp's closed form), the joints inside their limits, no two bodies
overlapping (:mod:`qsplan.hands.geometry.collision`), and for each effort-controlled finger
and each direction of the slide the guaranteed 4S band with every competitor precluded
(:func:`qsplan.mechanics.bands.batched_robust.robust_band_arrays`, batched over the grid and the
grasps; per-state competitors: a mode kinematically impossible at a state cannot occur there).
The scenes are never built as objects: their arrays come from the grasp's closed form for all
states at once (:meth:`qsplan.hands.protocol.Hand.scene_arrays`), a state's scene
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

__all__ = ["BandTables", "GraspRow", "band_tables", "effort_joints", "table_grid", "GRID_STEP", "OVERLAP",
           "SEARCH_MARGIN"]

#: Grid step (m) of the tables: the plan's dense-sweep step, so that the tables judge the states
#: the plan will judge (:data:`qsplan.planner.plan.scripted.SWEEP_STEP`).
GRID_STEP = 5e-4

#: What :attr:`BandTables.why` holds where two bodies overlap (:meth:`BandTables.reason` says which, and by how much).
OVERLAP = "two bodies overlap"

#: What :attr:`BandTables.why` holds where a line between two grasps does not reach (:class:`qsplan.planner.plan.
#: phases.FreePath` ``x1``).
OFF_LINE = "beyond the ends of this line between two grasps"

#: Relative slack of the grid's end counts: ``(end - start) / h`` computes a hair below its integer when the
#: span is a multiple of the step (floating point), which would drop the last grid point.
_GRID_ROUNDING = 1e-9

#: How far (m) beyond the start and the goal the tables reach: room for the detours a regrasp may
#: need (a slide away from the goal to where another grasp is valid); 6 cm is most of the span between
#: the default hand's fingers (0.18 m) minus a workpiece.
SEARCH_MARGIN = 0.06

#: Tangential speed per unit workpiece speed below which a contact counts as rolling when the tables compare sliding
#: senses: :data:`qsplan.planner.plan.phases.SLIP_RTOL`'s value (the search layer does not import the plan layer).
SLIP_RTOL = 1e-9

#: The scene arrays the tables stack (:class:`qsplan.hands.paper_hand.batch_scenes.SceneArrays`).
_ARRAYS = ("Wn", "Wt", "Jn", "Jt", "g_obj", "g_man")


@dataclass(frozen=True, slots=True, eq=False)
class BandTables:
    """The judged grid.

    Attributes
    ----------
    grasps : tuple of GraspRow
        The rows (a grasp, and a described hand's free joints along x), indexed as the tables' first axis.
    x : ndarray, shape (n,)
        The grid of workpiece x (m).
    graph : SearchGraph
        ``valid (G, n)``, ``touched (G, n, 2 + n_c)`` (what each finger touches, then each contact's sliding sense
        toward +x: a slide keeps both), ``width (G, E, 2, n)`` (N m or N; ``-inf`` without a band).
    q : ndarray, shape (G, n, n_j)
        Joint positions (rad or m; NaN where the row has no configuration).
    lower, upper : ndarray, shape (G, E, 2, n)
        The guaranteed bands (N m or N; NaN without one), per row, effort joint, direction (-x, +x) and x.
    why : ndarray of object, shape (G, n)
        Why a configuration is invalid, in words (None where valid; :data:`OVERLAP` where two bodies overlap,
        :meth:`reason` says which).
    states : int
        Configurations judged (grid points x grasps), and
    band_states : int
        of them, band evaluations (valid configurations x effort fingers x directions).
    seconds : float
        Wall time (s) of building the tables.
    efforts : tuple of str
        The joints of the effort axis (E of them): every joint the control-mode partitioner admits (eq. 32).
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
    efforts: tuple = ("left", "right")

    def index(self, x: float) -> int:
        """The grid index of ``x`` (m): the nearest grid point."""
        return int(np.argmin(np.abs(self.x - x)))

    def reason(self, task, g: int, i: int) -> str | None:
        """Why grasp ``g`` is invalid at grid index ``i``, in words (None where valid): the overlapping bodies
        and their overlap measured here, for reports, not for every configuration of the tables."""
        why = self.why[g, i]
        if why != OVERLAP:
            return why
        hit = task.hand.collisions(task.pose(self.x[i]), self.q[g, i], first=True)
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


@dataclass(frozen=True, slots=True, eq=False)
class GraspRow:
    """One row of the tables: a grasp of the hand (:meth:`qsplan.hands.protocol.Hand.grasp_candidates`) and, for a
    hand with free joints, where they are along x (:class:`qsplan.planner.plan.phases.FreePath`-like: ``x0``,
    ``values``, ``slope``, ``free``, ``at(x)``, ``rates(n, speed)``; None: the grasp's own, held).

    Attributes
    ----------
    grasp : qsplan.hands.paper_hand.grasps.Grasp or qsplan.hands.protocol.ChainGrasp
    path : object or None
    """

    grasp: object
    path: object = None

    @property
    def label(self) -> str:
        if self.path is None or not np.any(np.asarray(self.path.slope) != 0):
            return self.grasp.label
        return f"{self.grasp.label}, free joints sloping {np.round(np.asarray(self.path.slope)[list(self.path.free)], 4).tolist()} per m"

    def matches(self, left=None, right=None) -> bool:
        return self.grasp.matches(left, right)

    def free_at(self, x) -> np.ndarray | None:
        """The free joints (n, n_free) at workpiece ``x`` (n,), or None (the grasp's own)."""
        return None if self.path is None else self.path.at(x)


def _geometry(task, row, x):
    """The states of ``row`` at ``x`` (n,): ``(states, valid (n,), why list)``; overlapping configurations get
    :data:`OVERLAP` (their message is measured only when a report asks: :meth:`BandTables.reason`)."""
    from qsplan.planner.states.contact import limit_problem

    hand = task.hand
    states = hand.grasp_states(task.formation, row.grasp, x, row.free_at(x))
    valid = np.array(states.ok, dtype=bool)
    why = [None] * len(x)
    for k in np.flatnonzero(~valid):
        why[k] = states.why(int(k))
    if row.path is not None:  # a line between two grasps: a configuration of this row only on the line
        off = valid & ~row.path.covers(x)
        for k in np.flatnonzero(off):
            why[k] = OFF_LINE
        valid &= ~off
    lim = task.joint_limits
    inside = np.all((states.q >= lim[:, 0]) & (states.q <= lim[:, 1]), axis=1)
    for k in np.flatnonzero(valid & ~inside):
        why[k] = limit_problem(task, states.q[k])
    valid &= inside
    idx = np.flatnonzero(valid)
    hit = np.zeros(len(x), bool)
    if idx.size:
        hit[idx] = hand.collide(states.poses[idx], states.q[idx])
    for k in np.flatnonzero(hit):
        why[k] = OVERLAP
    return states, valid & ~hit, why


def effort_joints(task, rows, x) -> tuple:
    """The joints the tables make effort-controlled: every joint the control-mode partitioner admits as the one
    effort-controlled joint of the formation's mode (eq. 32; :func:`qsplan.mechanics.modes.partition.effort_partitions`)
    at a valid state of some row, in joint order (the paper's hand: both fingers, as always)."""
    from qsplan.mechanics.modes.partition import effort_partitions

    hand = task.hand
    if not hand.free_joints and len(hand.joint_names) == 2:
        return tuple(hand.joint_names)  # one joint per finger: either may be (the paper's tables always had both)
    n_j = len(hand.joint_names)
    found = set()
    for row in rows:
        states = hand.grasp_states(task.formation, row.grasp, x, row.free_at(x))
        ok = np.flatnonzero(states.ok)
        for k in ok[:: max(1, ok.size // 3)][:3]:  # a few states of the row: admission depends on the grasp only
            arrays = hand.scene_arrays(task.formation, states, [k])
            if not arrays.ok[0]:
                continue
            scene = hand.state_scene(arrays, 0, np.arange(n_j) == 0, np.zeros(n_j))
            found |= {p.effort_joints[0] for p in effort_partitions(scene, task.formation.mode) if len(p.effort_joints) == 1}
        if len(found) == n_j:
            break
    return tuple(hand.joint_names[j] for j in sorted(found))


def band_tables(task, grasps, x, progress=None) -> BandTables:
    """Judge every row of ``grasps`` at every ``x`` (m, shape (n,)) of the grid (see the module docstring).

    Parameters
    ----------
    task : qsplan.planner.task.task.Task
    grasps : sequence of GraspRow
        (or grasps, each then its own row with its free joints held).
    x : ndarray, shape (n,)
    progress : callable, optional

    Returns
    -------
    BandTables
    """
    t0 = time.perf_counter()
    hand = task.hand
    rows = tuple(g if isinstance(g, GraspRow) else GraspRow(g) for g in grasps)
    x = np.asarray(x, dtype=float)
    G, n, n_j = len(rows), len(x), len(hand.joint_names)
    efforts = effort_joints(task, rows, x)
    E = len(efforts)
    n_c = task.formation.n_contacts
    valid = np.zeros((G, n), bool)
    touched = np.full((G, n, 2 + n_c), -1, dtype=int)  # what each finger touches, then each contact's sliding sense
    q = np.full((G, n, n_j), np.nan)
    lower = np.full((G, E, 2, n), np.nan)
    upper = np.full((G, E, 2, n), np.nan)
    why = np.empty((G, n), dtype=object)
    parts = []  # per row with valid configurations: (g, idx, scene arrays, the unit-speed joint rates (m, n_j))
    for g, row in enumerate(rows):
        states, ok, reasons = _geometry(task, row, x)
        valid[g], q[g] = ok, states.q
        touched[g, :, :2] = states.touching()
        why[g] = reasons
        idx = np.flatnonzero(ok)
        if progress:
            progress(f"  grasp {g + 1}/{G} {row.label}: {idx.size} of {n} configurations valid")
        if not idx.size:
            continue
        arrays = hand.scene_arrays(task.formation, states, idx)  # contacts found once per configuration
        for k in np.flatnonzero(~arrays.ok):  # no four-contact scene there: not a configuration of this row
            valid[g, idx[k]] = False
            why[g, idx[k]] = arrays.reasons[k]
        keep = np.flatnonzero(arrays.ok)
        if keep.size:
            rates = _unit_rates(task, row, states, arrays, idx, keep)
            touched[g, idx[keep], 2:] = _slip_senses(task, arrays, keep, rates)
            dirs = (0, 1) if row.path is None else row.path.directions
            parts.append((g, idx[keep], arrays, keep, rates, dirs))
    band_states = 0
    for e, name in enumerate(efforts):  # one batch per effort joint: the states of every row and direction
        if parts:
            b = _effort_bands(task, parts, hand.joint_names.index(name))
            band_states += b.lower.size
            at = 0
            for d in range(2):
                for g, idx, *_, dirs in parts:
                    if d not in dirs:
                        continue
                    part = slice(at, at + idx.size)
                    at += idx.size
                    lower[g, e, d, idx], upper[g, e, d, idx] = b.lower[part], b.upper[part]
    width = np.where(np.isnan(lower) | np.isnan(upper), -np.inf, upper - lower)
    graph = SearchGraph(valid, touched, width, float(task.torque_resolution), lower, upper)
    return BandTables(rows, x, graph, q, lower, upper, why, G * n, band_states, time.perf_counter() - t0, efforts)


def _unit_rates(task, row, states, arrays, idx, keep) -> np.ndarray:
    """Every joint's rate (m, n_j) per m/s of the workpiece at the states ``idx[keep]``: ``dq_dx`` with the free
    joints held (the grasp's closed form or the hand's eq. 6), else eq. 6 with the row's free-joint slopes."""
    from qsplan.hands.formations.motion import closing_rates
    from qsplan.mechanics.errors import QsplanError

    if row.path is None or not np.any(np.asarray(row.path.slope) != 0):
        return states.dq_dx[idx[keep]]
    sub = _take_arrays(arrays, keep)
    try:
        return closing_rates(task.hand, task.formation, sub, 1.0, row.path.rates(keep.size, 1.0))
    except QsplanError:
        return np.full((keep.size, len(task.hand.joint_names)), np.nan)


def _slip_senses(task, arrays, keep, rates) -> np.ndarray:
    """Each contact's sliding sense (m, n_c) moving toward +x at unit speed: the sign of its tangential velocity
    ``W_t^T nu - J_t qdot`` (eq. 6), 0 where below :data:`qsplan.planner.plan.phases.SLIP_RTOL` (rolling).  A slide keeps
    every sense (a reversal passes through rolling: a mode change, eq. 16), so the search graph compares them like the
    contacts: moving toward -x flips every sense alike."""
    nu = np.array([1.0, 0.0, 0.0])
    vt = np.einsum("mik,i->mk", arrays.Wt[keep], nu) - np.einsum("mkj,mj->mk", arrays.Jt[keep], np.nan_to_num(rates))
    return np.where(np.abs(vt) > SLIP_RTOL, np.sign(vt), 0).astype(int)


def _take_arrays(arrays, keep):
    from dataclasses import replace

    return replace(arrays, **{f: getattr(arrays, f)[keep] for f in ("Wn", "Wt", "Jn", "Jt", "g_obj", "g_man")})


def _effort_bands(task, parts, e: int):
    """The guaranteed bands of the formation's mode, competitors precluded, of every configuration of ``parts`` with
    joint ``e`` effort-controlled, moving left (``d = 0``) then right (``d = 1``) where the part is used that way (a
    line between two grasps: toward its end only): one :class:`StateBatch` from the
    arrays, :func:`qsplan.mechanics.bands.batched_robust.robust_band_arrays` (NaN edges where there is no band)."""
    from qsplan.mechanics.bands.batched import LazyScenes, batch_from_arrays
    from qsplan.mechanics.bands.batched_robust import robust_band_arrays

    hand = task.hand
    n_j = len(hand.joint_names)
    effort = np.arange(n_j) == e
    # every (direction, part) pair the part is used in, left (d = 0) then right: the order band_tables reads back
    pairs = [((1.0 if d else -1.0) * task.workpiece_speed, part) for d in range(2) for part in parts if d in part[5]]
    stacked = [np.concatenate([getattr(arrays, f)[keep] for _, (_, _, arrays, keep, _, _) in pairs]) for f in _ARRAYS]
    velocity = np.concatenate([part[4] * xdot for xdot, part in pairs])  # (m, n_j)
    where = [(arrays, int(k)) for _, (_, _, arrays, keep, _, _) in pairs for k in keep]

    def scene(s):  # the scene of state s, as the hand builds it (a per-state search needs it)
        arrays, k = where[s]
        return hand.state_scene(arrays, k, effort, np.where(effort, 0.0, velocity[s]))

    joint_velocity = np.where(effort[None, :], np.nan, velocity)
    batch = batch_from_arrays(LazyScenes(velocity.shape[0], scene), *stacked, joint_velocity)
    return robust_band_arrays(batch, task.formation.mode, task.mu_range, shared=task.shared_mu,
                              force_margin=task.force_margin, disturbance=task.disturbance)  # fmt: skip
