"""The two kinds of phase of a two-finger plan: in-contact slides and regrasps (Section 5.2, Fig. 9), for any hand.

:func:`slide_phase` judges every sample of a slide (the dense sweep, :func:`sweep_contact_segment`) and chooses
its commands; :func:`regrasp_phase` plans the fingers' release, move and re-closing through OMPL.  Both serve the
scripted sequence (:func:`qsplan.planner.plan.scripted.plan_task`) and the sequence the planner finds
(:mod:`qsplan.planner.plan.autoplan`), for every hand (:class:`qsplan.hands.protocol.Hand`): a ``grasp`` says which
features the fingers touch (default the paper hand's inner edges, as its scripted tasks), a :class:`FreePath`
where a described hand's free joints are while the workpiece slides.  The desired mode is the task's
formation's (:attr:`qsplan.planner.task.task.Task.formation`).  Units SI (m, rad, s, N m; m, m/s and N for a
prismatic joint).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from qsplan.mechanics.errors import QsplanError

from qsplan.planner.plan.failure import configuration_report, failure_report
from qsplan.planner.plan.results import PlanFailure, RegraspPhase, SlidePhase
from qsplan.planner.search.ompl_bridge import PlannerOptions, plan_path
from qsplan.planner.states.contact import check_contact_state, configuration_problem, contact_samples, mode_name

__all__ = ["DEFAULT_OPTIONS", "FreePath", "OPENING", "REGRASP_OPENING", "SLIP_RTOL", "SWEEP_STEP", "densify",
           "densify_rows", "free_motion", "regrasp_phase", "slide_phase", "slip_reversal", "straight_path", "sweep_contact_segment"]

#: Angle (rad) each finger opens by to release the workpiece between segments: about 1.5 cm
#: at the tip of a 0.16 m finger, clear of the workpiece's corners.
REGRASP_OPENING = 0.1

#: How far each finger's closing joint opens to let go, by joint kind (rad, m): :data:`REGRASP_OPENING` for a
#: revolute joint (0.1 rad is 7 mm at the tip of a 7 cm link), 5 mm of jaw travel for a prismatic one.  Both far
#: above the contact tolerance and small beside the fingers.
OPENING = {"revolute": REGRASP_OPENING, "prismatic": 0.005}

#: Distance (m) between the samples of the dense band sweep of a segment (0.5 mm: 80 per 4 cm).
SWEEP_STEP = 5e-4

#: Tangential speed, relative to the workpiece's, below which a contact counts as not sliding when sliding
#: directions are compared: a rolling contact's computes as ~1e-16 of the speed; a sliding finger contact of the
#: bundled hands slips at 1e-3 of it or more.
SLIP_RTOL = 1e-9

#: The regrasps' OMPL queries (in-contact segments need no search): RRTConnect, deterministic, seed 1;
#: edges checked every 2 % of the joint box, then the exported lines every SWEEP_STEP at the fingertips.
#: The iteration budget decides (same inputs, same plan); the time limit per OMPL query (s) is a
#: safety net well above the few seconds a query takes, so a loaded machine does not change the answer.
DEFAULT_OPTIONS = PlannerOptions(validity_resolution=0.02, iterations=2_000, time_limit=120.0)


@dataclass(frozen=True, slots=True, eq=False)
class FreePath:
    """A described hand's free joints along a slide: straight in ``x`` (their values at ``x0`` and their slope).

    Attributes
    ----------
    x0 : float
        m.
    values : ndarray, shape (n_free,)
        The free joints at ``x0`` (rad or m), in joint order.
    slope : ndarray, shape (n_j,)
        Every joint's rate per metre of workpiece travel (rad/m or m/m): the free joints' slope, 0 at the closing
        joints (their rates follow from the contacts).
    free : tuple of int
        The free joints' indices.
    x1 : float or None
        Where the line ends (m): a line between two grasps is a configuration of its row only between ``x0`` and
        ``x1``, slid from ``x0`` toward ``x1`` (the band tables judge it there only); None: anywhere, either way.
    """

    x0: float
    values: np.ndarray
    slope: np.ndarray
    free: tuple
    x1: float | None = None

    def covers(self, x) -> np.ndarray:
        """Whether each workpiece ``x`` (n,) lies on the line (between ``x0`` and ``x1``; everywhere without ``x1``)."""
        x = np.asarray(x, dtype=float)
        if self.x1 is None:
            return np.ones(x.shape, dtype=bool)
        return (x >= min(self.x0, self.x1)) & (x <= max(self.x0, self.x1))

    @property
    def directions(self) -> tuple:
        """The slide directions it is used in: ``0`` toward -x, ``1`` toward +x (the band tables' ``d``)."""
        return (0, 1) if self.x1 is None or self.x1 == self.x0 else ((1,) if self.x1 > self.x0 else (0,))

    def at(self, x) -> np.ndarray:
        """The free joints at workpiece ``x`` (n,): shape (n, n_free)."""
        dx = np.asarray(x, dtype=float).reshape(-1, 1) - self.x0
        return np.asarray(self.values, dtype=float)[None, :] + dx * np.asarray(self.slope, dtype=float)[list(self.free)]

    def rates(self, n: int, speed: float) -> np.ndarray:
        """Every joint's rate (n, n_j) at workpiece speed ``speed`` (m/s): the free joints', the closing ones 0."""
        return np.broadcast_to(np.asarray(self.slope, dtype=float) * float(speed), (n, len(self.slope))).copy()


def _pieces(path, step):
    """``(a, b, n)`` of each piece of ``path`` (k,) or (k, d): its ends and the number of steps that keep every
    coordinate at most ``step`` apart (one number, or one per coordinate)."""
    for a, b in zip(path[:-1], path[1:]):
        yield a, b, max(1, int(np.ceil(np.max(np.abs(b - a) / step))))


def densify(path_x, step):
    """``path_x`` (m, shape (k,)) with points added on each piece, at most ``step`` apart."""
    return np.concatenate([path_x[:1]] + [np.linspace(a, b, n + 1)[1:] for a, b, n in _pieces(path_x, step)])


def densify_rows(path, step):
    """``path`` (n, d) with states added on each straight edge, at most ``step`` apart in every coordinate (``step``:
    one number, or one per coordinate, shape (d,))."""
    edges = [a + np.linspace(0.0, 1.0, n + 1)[1:, None] * (b - a) for a, b, n in _pieces(path, step)]
    return np.vstack([path[:1]] + edges)


def straight_path(x0, x1):
    """The segment's path: the straight line ``[x0, x1]`` (shape (2, 1)), its ends exactly ``x0`` and ``x1`` (the goal
    is reached exactly, not ``x0 + (x1 - x0)`` rounded)."""
    return np.array([[x0], [x1]], dtype=float)


def _samples(task, x, effort, speed, name, grasp, path):
    """:func:`contact_samples` of a slide at ``speed`` (m/s, signed) along ``path``."""
    free = None if path is None else path.at(x)
    rates = None if path is None else path.rates(len(x), speed)
    return contact_samples(task, x, effort, speed, name, grasp=grasp, free=free, free_rates=rates)


def _state(task, x, effort, direction, touching, comps, grasp, path):
    """:func:`check_contact_state` at ``x`` of a slide along ``path``."""
    free = None if path is None else path.at([x])[0]
    return check_contact_state(task, x, effort, direction, touching, comps, grasp, free,
                               None if path is None else path.slope)  # fmt: skip


def sweep_contact_segment(task, name, x, effort, direction, touching, comps, grasp=None, path=None):
    """Judge every sample of an in-contact segment once, with the validity conditions of
    :func:`check_contact_state` (the same contacts, no overlap, joint limits, the formation's mode's kinematics, a
    guaranteed band at least ``task.torque_resolution`` wide) and every sliding contact keeping its direction
    (:func:`slip_reversal`), the band batched over the samples as the plan needs it anyway.

    Parameters
    ----------
    task : Task
    name : str
        The segment's name (for messages).
    x : ndarray, shape (n,)
        Workpiece x of the samples (m), in the order of motion.
    effort : str
        The effort-controlled joint's name.
    direction : float
        Sign of the workpiece's velocity.
    touching : ndarray, shape (2,)
        What the fingers touch at the segment's start (:attr:`qsplan.hands.formations.motion.SlideMotion.touching`; a
        change is invalid).
    comps : tuple of str
        The competing modes to preclude (:func:`qsplan.planner.torque.sweep.competing_modes`).
    grasp : optional
        The grasp (:meth:`qsplan.hands.protocol.Hand.grasp_candidates`; default the paper hand's inner edges).
    path : FreePath, optional
        A described hand's free joints along the slide (default: the grasp's, held).

    Returns
    -------
    k : int or None
        Index of the first invalid sample, or None.
    samples : qsplan.hands.paper_hand.segments.SegmentSamples or None
        When every sample is valid: the samples moving at ``speed``; else None.
    band : qsplan.mechanics.bands.effort.Band or None
        Their guaranteed band (N m or N), competitors precluded.
    speed : float or None
        Workpiece speed (m/s): the fastest within the workpiece and every joint's speed limit.
    why : str or None
        Why sample ``k`` is invalid where the one-state check (:func:`check_contact_state`) cannot see it (a sliding
        direction reversing between samples); None otherwise.
    """
    from qsplan.mechanics.bands.effort import band_kinematics
    from qsplan.mechanics.modes.contact_mode import ContactMode

    from qsplan.planner.torque.pointwise import guaranteed_sweep

    try:
        S = _samples(task, x, effort, direction, "segment", grasp, path)
    except QsplanError:  # no grasp somewhere: the first sample without one
        k = next((k for k, xk in enumerate(x) if not _state(task, xk, effort, direction, touching, comps, grasp, path).ok),
                 0)  # fmt: skip
        return k, None, None, None, None
    rate = np.max(np.abs(S.qd) / np.asarray(task.joint_speeds, dtype=float)[None, :])  # per joint, its own limit
    speed = min(task.workpiece_speed, 1.0 / rate) if rate > 0 else task.workpiece_speed
    S = _samples(task, x, effort, direction * speed, name, grasp, path)
    mode = ContactMode(task.formation.mode)
    for k in range(len(x)):
        if (np.any(S.touching[k] != touching) or configuration_problem(task, S.pose[k], S.q[k])
                or not band_kinematics(S.scenes[k], mode).ok):  # fmt: skip
            return k, None, None, None, None
    k = slip_reversal(S, mode.letters, direction * speed)
    if k is not None:
        why = "a sliding contact's direction reverses here (it would roll in between: a mode change, eq. 16)"
        return k, None, None, None, why
    band = guaranteed_sweep(S, task.mu_range, task.shared_mu, mode.letters, comps, force_margin=task.force_margin,
                            disturbance=task.disturbance).band
    bad = ~np.asarray(band.feasible) | (band.upper - band.lower < task.torque_resolution)
    if bad.any():
        return int(np.argmax(bad)), None, None, None, None
    return None, S, band, float(speed), None


def slip_reversal(samples, mode: str, xdot: float):
    """The first sample where a contact the mode slides moves the other way than at the first sample (it stops
    sliding in between: eq. 16, a mode change the letters would not show), or None.  Tangential velocities
    ``W_t^T nu - J_t qdot`` (eq. 6) of the workpiece translating at ``xdot`` (m/s) along x and the joints at the
    samples' rates (the velocity-controlled joints' commands, the effort-controlled joint's rate the contacts give)."""
    sliding = np.array([c == "S" for c in mode])
    nu = np.array([float(xdot), 0.0, 0.0])
    first = None
    for k, scene in enumerate(samples.scenes):
        v = scene.Wt.T @ nu - scene.Jt @ np.asarray(samples.qd[k], dtype=float)
        sign = np.where(np.abs(v) > SLIP_RTOL * abs(float(xdot)), np.sign(v), 0.0)
        if first is None:
            first = sign
        elif np.any(sliding & (sign * first < 0)):
            return k
    return None


def slide_phase(task, name, x0, x1, effort, direction, touching, comps, t0, options, progress, counters,
                grasp=None, path=None) -> SlidePhase:  # fmt: skip
    """The in-contact phase sliding the workpiece from ``x0`` to ``x1`` (m) in the formation's mode: the dense sweep
    judges every sample (:func:`sweep_contact_segment`), then the commands are chosen (the largest margin kept
    along the whole segment, :func:`qsplan.planner.torque.command.plan_command`).  ``path``: a described hand's
    free joints along it (:class:`FreePath`; default held).

    Raises
    ------
    PlanFailure
        With a :func:`qsplan.planner.plan.failure.failure_report` of the first invalid sample.
    """
    from qsplan.planner.search.ompl_bridge import PlanResult
    from qsplan.planner.torque.command import plan_command

    # the configuration is the workpiece's x (the fingers follow the grasp, a described hand's free joints their
    # path): the only path is the straight line, and its dense sweep is the whole check
    line = straight_path(x0, x1)
    x = densify(line[:, 0], min(SWEEP_STEP, 0.5 * abs(x1 - x0)))  # at least 3 rows: the slide starts and ends at rest
    t_check = time.perf_counter()
    k, S, band, speed, why = sweep_contact_segment(task, name, x, effort, direction, touching, comps, grasp, path)
    seconds = time.perf_counter() - t_check
    counters[0] += len(x) if k is None else k + 1
    counters[1] += seconds
    if k is not None:
        why = why or _state(task, x[k], effort, direction, touching, comps, grasp, path).reason
        status = f"dense sweep: state {k + 1} of {len(x)} invalid, at x = {x[k]:.4g} m: {why or 'band narrower than the resolution'}"
        res = PlanResult(line[:k + 1], False, status, k + 1, seconds, options)
        raise PlanFailure(failure_report(task, name, x0, x1, effort, direction, comps, res, grasp=grasp, path=path))
    res = PlanResult(line, True, f"dense sweep: all {len(x)} states valid", len(x), seconds, options)
    mode = task.formation.mode
    progress(f"  {res.status} (overlaps, limits, contacts, {mode_name(mode)} kinematics, guaranteed band) in {seconds:.2f} s")
    command, margin = plan_command(band.lower, band.upper, task.torque_resolution, band.feasible)
    s = np.concatenate([[0.0], np.cumsum(np.abs(np.diff(x)))])
    qd = S.qd.copy()
    qd[:, task.hand.joint_names.index(effort)] = np.nan  # the effort-controlled joint gets no velocity command
    return SlidePhase(name, effort, mode, line[:, 0].copy(), t0 + s / speed, x, S.q.copy(), qd, band.lower.copy(),
                      band.upper.copy(), command, margin, comps, speed, res)  # fmt: skip


def _opened(task, q, opening) -> np.ndarray:
    """``q`` with each joint moved by its opening amount (:data:`OPENING` by kind) in direction ``opening`` (-1, 0, 1)."""
    amount = np.array([OPENING[k] for k in task.hand.joint_kinds])
    return np.asarray(q, float) + amount * np.asarray(opening, float)


def regrasp_phase(task, name, x, q_from, q_to, t0, options, progress, counters, opening_from=None,
                  opening_to=None) -> RegraspPhase:  # fmt: skip
    """Both fingers release the workpiece at ``x`` (m) from joints ``q_from`` and close on it at ``q_to`` (rad or m,
    shape (n_j,)), through OMPL in joint space: each finger's closing joint opens by its :data:`OPENING` in the
    direction ``opening_from`` (per joint -1, 0 or +1, :meth:`qsplan.hands.protocol.Hand.opening`; default the paper
    hand's inner edges': the left finger counter-clockwise), every joint moves to the opened ``q_to`` and the
    fingers close; the workpiece rests on the palm meanwhile.  Every leg is collision-free
    (:func:`free_motion`), and the straight lines between OMPL's states are checked again every
    :data:`SWEEP_STEP` of a link's travel (:attr:`qsplan.hands.protocol.Hand.finger_reach` sets the joint step).

    Raises
    ------
    PlanFailure
        With a :class:`qsplan.planner.plan.failure.ConfigurationReport` naming the leg and what blocks it.
    """
    progress(name)
    q, q_to = np.asarray(q_from, float), np.asarray(q_to, float)
    default = task.hand.opening(None, x, q) if opening_from is None or opening_to is None else None
    q_open = _opened(task, q, default if opening_from is None else opening_from)
    q_to_open = _opened(task, q_to, default if opening_to is None else opening_to)
    t, path, qd, results = free_motion(task, name, task.pose(x), q, q_open, q_to_open, q_to, t0, options, progress,
                                       counters)  # fmt: skip
    return RegraspPhase(name, float(x), t, path, qd, results)


def free_motion(task, name, pose, q, q_open, q_to_open, q_to, t0, options, progress, counters, moving=None,
                who: str = "the fingers") -> tuple:  # fmt: skip
    """The legs of a free finger motion with the workpiece at ``pose``: from ``q`` to the opened ``q_open``, through
    OMPL to ``q_to_open``, and closing at ``q_to`` (rad or m, shape (n_j,)); ``moving`` (bool, shape (n_j,); default
    every joint): the joints OMPL plans, the others held where ``q`` has them.  Every leg is collision-free
    (:func:`configuration_problem`), and the straight lines between OMPL's states are checked again every
    :data:`SWEEP_STEP` of a link's travel.  Returns ``(t, q rows, qd rows, OMPL results)``.

    Raises
    ------
    PlanFailure
        With a :class:`qsplan.planner.plan.failure.ConfigurationReport` naming the leg and what blocks it.
    """
    pose = np.asarray(pose, dtype=float)
    n_j = q.size
    moving = np.ones(n_j, dtype=bool) if moving is None else np.asarray(moving, dtype=bool)
    lim = task.joint_limits
    x = float(pose[0])
    at = None if np.array_equal(pose, task.pose(x)) else pose  # a report names the pose where it is not the rest's

    def full(s):
        out = q.copy()
        out[moving] = s
        return out

    def valid(s):
        return configuration_problem(task, pose, full(s)) is None

    results, path = [], [q[None, :]]
    legs = [(q, q_open, "the opening"), (q_open, q_to_open, "the move to the new grasp"), (q_to_open, q_to, "the closing")]
    if np.array_equal(q_open, q_to_open):  # the same grasp again: open and close
        legs = [legs[0], (q_open, q_to, "the closing")]
    for a, b, what in legs:
        res = plan_path(lim[moving, 0], lim[moving, 1], a[moving], b[moving], valid, options)
        counters[0] += res.validity_checks
        counters[1] += res.seconds
        progress(f"  OMPL: {what} of {who}: {res.status}, {len(res.path)} states, "
                 f"{res.validity_checks} validity checks in {res.seconds:.2f} s")  # fmt: skip
        if not res.exact:
            raise PlanFailure(configuration_report(task, name, f"{what} of {who}", x, b,
                                                   f"OMPL found no collision-free finger motion ({res.status})",
                                                   res.status, at))  # fmt: skip
        results.append(res)
        path.append(np.array([full(s) for s in np.asarray(res.path)[1:]]).reshape(-1, n_j))
    path = np.vstack(path)
    # OMPL checked its edges at validity_resolution; the fingers move on straight lines between the rows
    # exported, so check those lines again every SWEEP_STEP of travel at the fingertips (m for a prismatic joint)
    reach = task.hand.finger_reach
    steps = np.array([SWEEP_STEP / reach if k == "revolute" else SWEEP_STEP for k in task.hand.joint_kinds])
    for qk in densify_rows(path, steps):
        why = configuration_problem(task, pose, qk)
        if why:
            raise PlanFailure(configuration_report(task, name, "a state between OMPL's states", x, qk, why,
                                                   results[-1].status, at))  # fmt: skip
    moves = np.max(np.abs(np.diff(path, axis=0)) / np.asarray(task.joint_speeds, float)[None, :], axis=1)
    t = t0 + np.concatenate([[0.0], np.cumsum(moves)])
    seg_qd = np.diff(path, axis=0) / np.maximum(np.diff(t), 1e-12)[:, None]
    qd = np.vstack([seg_qd, np.zeros((1, path.shape[1]))])
    return t, path, qd, tuple(results)
