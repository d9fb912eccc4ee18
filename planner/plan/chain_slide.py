"""A slide of a described hand, planned on the contact manifold through OMPL (Section 5.2 for any hand).

The workpiece slides along the palm from ``x0`` to ``x1`` while both fingers keep their contacts
(:mod:`qsplan.planner.plan.chain_states`).  The fingers' free joints have freedom left over: OMPL
(:func:`qsplan.planner.search.ompl_bridge.plan_path`) plans the path of ``(x, free joints)`` from
the start grasp to a goal grasp, every state valid when it closes onto the same features, keeps
the limits, collides with nothing and has a guaranteed band of the effort-controlled joint at
least the torque resolution wide, judged with the motion's direction (the workpiece moving toward
``x1``, the free joints along the straight line from start to goal).

The path OMPL returns is then judged densely with its own rates (:func:`slide_segment`): samples
every :data:`qsplan.planner.plan.phases.SWEEP_STEP` of ``x``, the free joints' rates the path's
slopes, the closing joints' from eq. 6, the whole batch of guaranteed bands; the path must move
the workpiece monotonically.  The command follows the one rule of every plan
(:func:`qsplan.planner.torque.command.choose_command`).  Units SI.
"""

from __future__ import annotations

import time
from dataclasses import replace
from types import SimpleNamespace

import numpy as np

from qsplan.mechanics.errors import NoAnswerError

from qsplan.planner.plan.chain_states import judge_states
from qsplan.planner.plan.results import ContactSegmentPlan

__all__ = ["GRID_BUDGET", "SEARCH_GRID", "free_grid", "plan_slide", "slide_segment"]

#: Values per free joint of the grid on which start and goal grasps are sought (within the joint's limits):
#: 13 values of a 3 rad range are 0.25 rad apart, about 2 cm at the tip of a 7 cm link.
SEARCH_GRID = 13

#: Most grid points (each closes both fingers and checks collisions, about a millisecond): hands with more
#: free joints get fewer values per joint, at least 3 (two-link fingers keep 13 x 13 = 169).
GRID_BUDGET = 200


def free_grid(task, n: int = SEARCH_GRID, budget: int = GRID_BUDGET) -> np.ndarray:
    """Every combination of up to ``n`` values of each free joint inside its limits (ends excluded; fewer per joint
    where ``n ** d`` exceeds ``budget``, never below 3), shape (m, n_j) (the closing joints' entries 0)."""
    free = task.hand.free_joints()
    if len(free):
        n = max(3, min(n, int(np.floor(budget ** (1.0 / len(free)) + 1e-9))))
    lim = task.joint_limits
    axes = [np.linspace(lim[j, 0], lim[j, 1], n + 2)[1:-1] for j in free]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, len(free)) if len(free) else np.zeros((1, 0))
    out = np.zeros((len(grid), len(task.joint_limits)))
    out[:, free] = grid
    return out


def _densify(path, step):
    """Points along the polyline ``path`` (m, d) with ``x`` (column 0) at most ``step`` apart, shape (n, d)."""
    out = [path[:1]]
    for a, b in zip(path[:-1], path[1:]):
        k = max(1, int(np.ceil(abs(b[0] - a[0]) / step)))
        out.append(a + np.linspace(0.0, 1.0, k + 1)[1:, None] * (b - a))
    return np.concatenate(out)


def slide_segment(task, name, path, effort: int, keys, mode, t0: float, step: float):
    """Judge a path of ``(x, free joints)`` (shape (m, 1 + n_free)) densely and make it a :class:`ContactSegmentPlan`;
    ``(None, judged states)`` where a state fails (the caller reports it).  ``mode`` is ``(letters, sliding
    directions)`` (:func:`qsplan.planner.plan.chain_states.slip_signs`), kept by every state."""
    from qsplan.planner.torque.command import choose_command, default_safety_margin

    hand = task.hand
    free = hand.free_joints()
    dense = _densify(np.asarray(path, float), step)
    x = dense[:, 0]
    dx = np.diff(x)
    direction = float(np.sign(x[-1] - x[0]))
    if direction == 0.0 or np.any(direction * dx <= 0.0):
        return None, None
    slopes = np.diff(dense[:, 1:], axis=0) / dx[:, None]  # d(free joint)/dx of each piece
    slope = np.vstack([slopes, slopes[-1:]])  # a sample takes the slope of the piece it starts
    n_j = len(task.joint_limits)
    q_free = np.zeros((len(x), n_j))
    q_free[:, free] = dense[:, 1:]
    # speed: the workpiece's limit, or slower where a joint would exceed its own (closing joints checked after)
    unit = np.zeros_like(q_free)
    unit[:, free] = slope * direction
    judged = judge_states(task, x, q_free, unit, direction, effort, keys, *mode)
    if not judged.ok.all():
        return None, judged
    rate = np.max(np.abs(judged.qd) / task.joint_speeds[None, :])  # joint-speed fraction per m/s of the workpiece
    speed = min(task.workpiece_speed, 1.0 / rate) if rate > 0 else task.workpiece_speed
    qd = judged.qd * speed
    qd[:, effort] = np.nan  # the effort-controlled joint gets no velocity command
    band_lo, band_hi = judged.lower, judged.upper
    try:  # default_safety_margin reads a band's edges and width
        safety = default_safety_margin(SimpleNamespace(lower=band_lo, upper=band_hi, width=band_hi - band_lo,
                                                      feasible=np.isfinite(band_lo) | np.isfinite(band_hi)),
                                       task.torque_resolution)  # fmt: skip
    except NoAnswerError:
        safety = task.torque_resolution
    command, margin = choose_command(band_lo, band_hi, safety, max_margin=safety)
    s = np.concatenate([[0.0], np.cumsum(np.abs(dx))])
    return ContactSegmentPlan(name, hand.joint_names[effort], mode[0], path[:, 0].copy(), t0 + s / speed, x,
                              judged.q.copy(), qd, band_lo.copy(), band_hi.copy(), command, margin, (), speed,
                              None), judged  # fmt: skip


def plan_slide(task, name, x0, q0, x1, q1, effort: int, keys, mode, t0, options, step, progress=print):
    """Plan a slide from the grasp ``(x0, q0)`` to ``(x1, q1)`` (same contact keys) with OMPL on the contact manifold,
    then judge it densely (:func:`slide_segment`).

    Returns
    -------
    (ContactSegmentPlan or None, PlanResult, JudgedStates or None, checks, seconds)
    """
    from qsplan.planner.search.ompl_bridge import plan_path

    hand = task.hand
    free = hand.free_joints()
    direction = float(np.sign(x1 - x0))
    slope = (q1[free] - q0[free]) / (x1 - x0)
    lim = task.joint_limits
    margin = 0.25 * abs(x1 - x0)
    low = np.concatenate([[min(x0, x1) - margin], lim[free, 0]])
    high = np.concatenate([[max(x0, x1) + margin], lim[free, 1]])
    n_j = len(lim)
    counted = [0, 0.0]

    def is_valid(s):
        t = time.perf_counter()
        q = np.zeros(n_j)
        q[free] = s[1:]
        unit = np.zeros(n_j)
        unit[free] = slope * direction
        ok = bool(judge_states(task, s[:1], q[None], unit[None], direction, effort, keys, *mode).ok[0])
        counted[0] += 1
        counted[1] += time.perf_counter() - t
        return ok

    start = np.concatenate([[x0], q0[free]])
    goal = np.concatenate([[x1], q1[free]])
    res = plan_path(low, high, start, goal, is_valid, options)
    if not res.exact:
        return None, res, None, counted[0], counted[1]
    t = time.perf_counter()
    seg, judged = slide_segment(task, name, res.path, effort, keys, mode, t0, step)
    if seg is not None:
        seg = replace(seg, planning=res)
    counted[1] += time.perf_counter() - t
    counted[0] += 0 if judged is None else len(judged.x)
    return seg, res, judged, counted[0], counted[1]
