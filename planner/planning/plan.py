"""Two-finger manipulation plans through OMPL with guaranteed torque bands (Section 5.2, Figs. 9-13).

:func:`plan_task` turns a :class:`planner.task.Task` into a :class:`Plan`:

1. **In-contact segments.**  Segment ``i`` slides the workpiece along the palm from
   the previous waypoint to the next in mode 4S (``"SSSS"``); its configuration
   variable is the workpiece's ``x`` (the fingers follow by tangency,
   :func:`hands.two_finger.finger_angles`).  OMPL (:func:`planner.ompl_bridge.plan_path`)
   plans over ``x`` with the validity checker of :func:`check_contact_state`: no
   penetration (shapely), the same four contacts as at the segment's start and the
   4S kinematics possible (eqs. 24-25), joints inside their limits, and a
   guaranteed band (desired mode feasible for the whole friction set, every
   competing mode precluded: :func:`planner.bands_sweep.guaranteed_sweep`) at least
   ``torque_resolution`` wide.  Edges are checked every ``validity_resolution`` of
   the range.  With an optimizing planner, ``state_cost = 1 / margin`` prefers wide
   bands.  The effort-controlled finger is derived: among the joint sets the
   control-mode partitioner admits for 4S (eq. 32), the one whose narrowest band
   along the straight line is widest.
2. **Regrasps.**  Between segments both fingers open by :data:`REGRASP_OPENING` and
   close again on the workpiece, planned by OMPL in joint space, collision-free
   (:func:`check_free_state`: the fingers clear the workpiece, the palm and each
   other).  Assumed: the workpiece rests on the palm meanwhile (its centre of
   mass lies over its bottom edge, checked by :func:`planner.task.make_task`) and
   a quasistatic release leaves it where it is.
3. **From path to plan.**  Each segment's path is swept every :data:`SWEEP_STEP`,
   time-parameterized at the largest constant speed within the workpiece and joint
   speed limits, and each command is chosen in the guaranteed band with the largest
   margin that can be kept along the whole segment: half its narrowest band, from
   both edges (:func:`planner.command.choose_command` with ``max_margin`` = that
   half-width).  So the command is the midpoint where the band is narrowest and
   ``lower + margin`` elsewhere: continuous, and close to the torque the mode needs
   (the pointwise midpoint runs to many times that torque where the upper edge
   blows up, and jumps where it becomes infinite).  A command outside its band is
   never emitted (:func:`Plan.check` raises).

When a segment has no path, :class:`PlanFailure` carries a
:class:`planner.plan_report.FailureReport`: where the band closes, which
competitor closes it, the friction at which it does.  Units SI (m, rad, s, N m).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from qsplan.mechanics.errors import QsplanError

from qsplan.planner.planning.ompl_bridge import PlannerOptions, plan_path
from qsplan.planner.planning.task import Task

__all__ = [
    "DEFAULT_OPTIONS",
    "REGRASP_OPENING",
    "SWEEP_STEP",
    "ContactSegmentPlan",
    "Plan",
    "PlanFailure",
    "RegraspPlan",
    "check_contact_state",
    "check_free_state",
    "contact_samples",
    "plan_task",
]

#: Angle (rad) each finger opens by to release the workpiece between segments: about 1.5 cm
#: at the tip of a 0.16 m finger, clear of the workpiece's corners.
REGRASP_OPENING = 0.1

#: Distance (m) between the samples of the dense band sweep of a segment (0.5 mm: 80 per 4 cm).
SWEEP_STEP = 5e-4

#: Intersection area (m^2) below which two polygons only touch (the fingers touch the workpiece by tangency).
TOUCH_AREA = 1e-10

MODE = "SSSS"

#: RRTConnect, deterministic, seed 1; edges checked every 2 % of the range (0.8 mm over a 4 cm
#: segment, below the 0.5 mm dense sweep that follows only by a factor 1.6: the sweep is the guarantee).
#: The iteration budget decides (same inputs, same plan); the time limit per OMPL query (s) is a
#: safety net well above the few seconds a query takes, so a loaded machine does not change the answer.
DEFAULT_OPTIONS = PlannerOptions(validity_resolution=0.02, iterations=2_000, time_limit=120.0)


class PlanFailure(QsplanError):
    """No plan: ``report`` (a :class:`planner.plan_report.FailureReport`) says where and why."""

    def __init__(self, report):
        super().__init__(report.message)
        self.report = report


@dataclass(frozen=True, slots=True)
class StateCheck:
    """One configuration of an in-contact segment, judged.

    Attributes
    ----------
    x : float
        Workpiece x (m).
    ok : bool
    reason : str or None
        Why not, in words.
    lower, upper : float
        Guaranteed band (N m), NaN without one.
    desired_lower, desired_upper : float
        The desired mode's guaranteed band before precluding competitors (N m).
    competitors : tuple of str
        Competing modes possible inside the desired mode's band (they cut it).
    """

    x: float
    ok: bool
    reason: str | None
    lower: float = np.nan
    upper: float = np.nan
    desired_lower: float = np.nan
    desired_upper: float = np.nan
    competitors: tuple = ()

    @property
    def width(self) -> float:
        return float(self.upper - self.lower) if np.isfinite(self.lower) or np.isfinite(self.upper) else np.nan


@dataclass(frozen=True, slots=True, eq=False)
class ContactSegmentPlan:
    """An in-contact segment of a plan.

    Attributes
    ----------
    name : str
    effort_joint : str
        The torque-controlled finger; the other is velocity-controlled.
    mode : str
    x_path : ndarray, shape (m,)
        OMPL's path of the workpiece's x (m).
    t, x : ndarray, shape (n,)
        Dense samples: time from the plan's start (s) and workpiece x (m).
    q, qd : ndarray, shape (n, 2)
        Joint angles (rad) and velocities (rad/s).
    lower, upper, command, margin : ndarray, shape (n,)
        Guaranteed band, command and its margin (N m) of the effort-controlled joint.
    competitors : tuple of str
        Modes precluded along the segment.
    speed : float
        Workpiece speed (m/s).
    planning : planner.ompl_bridge.PlanResult
    """

    name: str
    effort_joint: str
    mode: str
    x_path: np.ndarray
    t: np.ndarray
    x: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    command: np.ndarray
    margin: np.ndarray
    competitors: tuple
    speed: float
    planning: object

    @property
    def width(self) -> np.ndarray:
        return self.upper - self.lower


@dataclass(frozen=True, slots=True, eq=False)
class RegraspPlan:
    """A free-space finger motion: release and regrasp at a fixed workpiece x.

    Attributes
    ----------
    name : str
    x : float
        Workpiece x (m) meanwhile.
    t : ndarray, shape (n,)
        Times (s) from the plan's start.
    q, qd : ndarray, shape (n, 2)
        Joint angles (rad) and velocities (rad/s), both joints velocity-controlled.
    planning : tuple of planner.ompl_bridge.PlanResult
        Opening and closing.
    """

    name: str
    x: float
    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    planning: tuple


@dataclass(frozen=True, slots=True, eq=False)
class Plan:
    """A task's plan: in-contact segments and regrasps, in order.

    Attributes
    ----------
    task : planner.task.Task
    phases : tuple of (ContactSegmentPlan or RegraspPlan)
    seconds : float
        Wall-clock planning time (s), OMPL and sweeps.
    validity_checks : int
        Validity-checker calls by OMPL.
    ompl_seconds : float
        Time inside OMPL (s).
    """

    task: Task
    phases: tuple
    seconds: float
    validity_checks: int
    ompl_seconds: float
    options: PlannerOptions = field(default_factory=PlannerOptions)

    @property
    def segments(self) -> tuple:
        return tuple(p for p in self.phases if isinstance(p, ContactSegmentPlan))

    @property
    def duration(self) -> float:
        return float(self.phases[-1].t[-1])

    @property
    def checks_per_second(self) -> float:
        return self.validity_checks / self.ompl_seconds if self.ompl_seconds > 0 else float("nan")

    def narrowest(self):
        """``(segment name, t, width)`` of the narrowest guaranteed band of the plan (s, N m; width inf when
        every band is unbounded)."""
        best = None
        for s in self.segments:
            k = int(np.argmin(s.width))
            if best is None or s.width[k] < best[2]:
                best = (s.name, float(s.t[k]), float(s.width[k]))
        return best or (None, np.nan, np.inf)

    def check(self) -> None:
        """Raise :class:`mechanics.QsplanError` unless every command lies in its band with a positive margin."""
        for s in self.segments:
            bad = ~((s.command > s.lower) & (s.command < s.upper) & (s.margin > 0))
            if bad.any():
                k = int(np.flatnonzero(bad)[0])
                raise QsplanError(f"plan: {s.name}: command {s.command[k]:.6g} N m outside its band "
                                  f"[{s.lower[k]:.6g}, {s.upper[k]:.6g}] at t = {s.t[k]:.4g} s")  # fmt: skip


# ---------------------------------------------------------------------------------------------- configurations


def _scene(task, x, effort_joint, velocity):
    from qsplan.hands.two_finger import finger_angles, hand_scene

    pose = task.pose(x)
    q, touching = finger_angles(task.hand, pose)
    return pose, q, touching, hand_scene(task.hand, pose, q, effort_joint, velocity=velocity, effort=0.0)


def contact_samples(task, xs, effort_joint, speed, name="segment"):
    """The configurations at workpiece ``xs`` (m, shape (n,)) moving at ``speed`` (m/s, signed) as
    :class:`hands.segments.SegmentSamples` (times 0, 1, ...: bands do not depend on them).

    Raises
    ------
    mechanics.SceneError
        Where a configuration has no four-contact grasp.
    """
    from qsplan.hands.segments import ManipulationSegment, SegmentSamples
    from qsplan.hands.two_finger import JOINT_NAMES, finger_angle_rates

    v = 1 - JOINT_NAMES.index(effort_joint)
    poses, qs, qds, touch, scenes = [], [], [], [], []
    for x in np.atleast_1d(np.asarray(xs, float)):
        pose = task.pose(x)
        qd = finger_angle_rates(task.hand, pose, (speed, 0.0, 0.0))
        _, q, t, scene = _scene(task, x, effort_joint, qd[v])
        poses.append(pose), qs.append(q), qds.append(qd), touch.append(t), scenes.append(scene)
    n = len(poses)
    poses = np.array(poses)
    seg = ManipulationSegment(task.hand, name, poses[0], poses[-1], float(max(n - 1, 1)), MODE, effort_joint)
    return SegmentSamples(seg, np.arange(n, dtype=float), np.linspace(0.0, 1.0, n), poses, np.array(qs),
                          np.array(qds), np.array(touch), tuple(scenes))  # fmt: skip


def _penetrates(task, pose, q) -> str | None:
    from shapely.geometry import Polygon

    from qsplan.hands.two_finger import hand_polygons

    polys = {k: Polygon(v) for k, v in hand_polygons(task.hand, pose, q).items()}
    for side in ("left", "right"):
        if polys[side].intersection(polys["workpiece"]).area > TOUCH_AREA:
            return f"the {side} finger penetrates the workpiece"
    if polys["workpiece"].intersection(polys["palm"]).area > TOUCH_AREA:
        return "the workpiece penetrates the palm"
    return None


def check_contact_state(task: Task, x: float, effort_joint: str, direction: float, touching=None,
                        competitors=None) -> StateCheck:  # fmt: skip
    """Judge workpiece ``x`` (m) of an in-contact segment moving in ``direction`` (sign of xdot).

    Valid when the four contacts are found (the same finger vertices as ``touching``),
    nothing penetrates, the joints are inside their limits, the 4S kinematics hold and
    the guaranteed band, competitors precluded, is at least ``task.torque_resolution`` wide.
    """
    from qsplan.mechanics.bands.effort import band_kinematics
    from qsplan.mechanics.modes.contact_mode import ContactMode

    from qsplan.planner.torque.sweep import guaranteed_sweep

    try:
        S = contact_samples(task, [x], effort_joint, float(np.sign(direction)) * task.workpiece_speed)
    except QsplanError as exc:
        return StateCheck(float(x), False, f"no four-contact grasp: {exc}")
    q = S.q[0]
    if touching is not None and np.any(S.touching[0] != touching):
        return StateCheck(float(x), False, "a finger moves to another workpiece vertex (a contact change)")
    lim = task.joint_limits
    if np.any(q < lim[:, 0]) or np.any(q > lim[:, 1]):
        return StateCheck(float(x), False, f"joint limits: q = {np.round(q, 4).tolist()} rad")
    why = _penetrates(task, S.pose[0], q)
    if why:
        return StateCheck(float(x), False, why)
    if not band_kinematics(S.scenes[0], ContactMode(MODE)).ok:
        return StateCheck(float(x), False, "the 4S kinematics fail (eqs. 24-25)")
    g = guaranteed_sweep(S, task.mu_range, task.shared_mu, MODE, competitors)
    b, d = g.band, g.desired
    cut = tuple(c for c, (lo, hi) in g.competitors.items() if np.isfinite(lo[0]))
    lo, hi = float(b.lower[0]), float(b.upper[0])
    common = dict(desired_lower=float(d.lower[0]), desired_upper=float(d.upper[0]), competitors=cut)
    if not b.feasible[0]:
        return StateCheck(float(x), False, "no guaranteed band: " + (b.reasons[0] or "4S not guaranteed"), **common)
    if hi - lo < task.torque_resolution:
        return StateCheck(float(x), False, f"band {hi - lo:.4g} N m narrower than the resolution", lo, hi, **common)
    return StateCheck(float(x), True, None, lo, hi, **common)


def _finger_poly(task, k, q):
    from shapely.geometry import Polygon

    h = task.hand
    w = 0.5 * h.finger_width
    c, s = np.cos(q), np.sin(q)
    R = np.array([[c, -s], [s, c]])
    # from two half-widths out: the finger's root turns inside the palm's joint housing
    pts = np.array([(2 * w, -w), (h.finger_length, -w), (h.finger_length, w), (2 * w, w)]) @ R.T + h.pivots[k]
    return Polygon(pts)


def check_free_state(task: Task, x: float, q) -> bool:
    """A free-space finger configuration ``q`` (rad, shape (2,)) with the workpiece at ``x`` (m):
    inside the joint limits, and the fingers (beyond their roots) clear of the workpiece, the palm and each other."""
    from shapely.geometry import Polygon, box

    from qsplan.hands.two_finger import workpiece_world

    q = np.asarray(q, float)
    lim = task.joint_limits
    if np.any(q < lim[:, 0]) or np.any(q > lim[:, 1]):
        return False
    h = task.hand
    wp = Polygon(workpiece_world(h, task.pose(x)))
    palm = box(-h.palm_halfwidth, -h.palm_thickness, h.palm_halfwidth, 0.0)
    fingers = [_finger_poly(task, k, q[k]) for k in range(2)]
    for f in fingers:
        if f.intersection(wp).area > TOUCH_AREA or f.intersection(palm).area > TOUCH_AREA:
            return False
    return fingers[0].intersection(fingers[1]).area <= TOUCH_AREA


# ---------------------------------------------------------------------------------------------- planning


def _effort_joint(task, x0, x1, progress):
    """The effort-controlled finger of a segment: admitted by the partitioner (eq. 32), widest narrowest band."""
    from qsplan.hands.two_finger import JOINT_NAMES
    from qsplan.mechanics.modes.contact_mode import ContactMode
    from qsplan.mechanics.modes.partition import effort_partitions

    d = np.sign(x1 - x0)
    xs = np.linspace(x0, x1, 7)
    try:
        scene = _scene(task, x0, "right", 0.0)[3]
        admitted = {JOINT_NAMES[p.effort_joints[0]] for p in effort_partitions(scene, ContactMode(MODE))
                    if len(p.effort_joints) == 1}  # fmt: skip
    except QsplanError:
        admitted = set(JOINT_NAMES)
    best, best_w = None, -np.inf
    for joint in JOINT_NAMES:
        if joint not in admitted:
            continue
        w = [check_contact_state(task, x, joint, d) for x in xs]
        worst = min((c.width if np.isfinite(c.width) else -np.inf) for c in w)
        if worst > best_w:
            best, best_w = joint, worst
    return best or "right"


def _densify(path_x, step):
    xs = [path_x[:1]]
    for a, b in zip(path_x[:-1], path_x[1:]):
        n = max(1, int(np.ceil(abs(b - a) / step)))
        xs.append(np.linspace(a, b, n + 1)[1:])
    return np.concatenate(xs)


def _segment(task, i, x0, x1, t0, options, progress, counters):
    from qsplan.planner.torque.sweep import competing_modes, guaranteed_sweep
    from qsplan.planner.torque.command import choose_command, default_safety_margin
    from qsplan.planner.planning.failure import failure_report

    name = f"segment {i + 1}: slide the workpiece {'left' if x1 < x0 else 'right'} from x = {x0:.4g} to {x1:.4g} m"
    direction = float(np.sign(x1 - x0))
    effort = _effort_joint(task, x0, x1, progress)
    progress(f"{name}: effort-controlled finger {effort}; planning with OMPL {options.planner}")
    line = contact_samples(task, np.linspace(x0, x1, 9), effort, direction * task.workpiece_speed)
    comps = competing_modes(line)
    touching = line.touching[0]

    memo = {}  # OMPL's simplifier re-checks the same interpolated states along an edge many times

    def judge(x):
        c = memo.get(x)
        if c is None:
            c = memo[x] = check_contact_state(task, x, effort, direction, touching, comps)
        return c

    def valid(s):
        return judge(float(s[0])).ok

    def cost(s):
        c = judge(float(s[0]))
        m = 0.5 * c.width if np.isfinite(c.width) else 1.0
        return 1.0 / max(m, 1e-9)

    pad = max(0.05 * abs(x1 - x0), 1e-3)
    low, high = [min(x0, x1) - pad], [max(x0, x1) + pad]
    optimizing = options.planner in ("RRTstar", "BITstar")
    try:
        res = plan_path(low, high, [x0], [x1], valid, options, state_cost=cost if optimizing else None)
    except QsplanError:
        res = None
    if res is not None:
        counters[0] += res.validity_checks
        counters[1] += res.seconds
    if res is None or not res.exact:
        raise PlanFailure(failure_report(task, name, x0, x1, effort, direction, comps, res))
    progress(f"  OMPL: {res.status}, {len(res.path)} states, {res.validity_checks} validity checks in {res.seconds:.2f} s")
    x = _densify(res.path[:, 0], SWEEP_STEP)
    # the fastest constant speed within the workpiece and joint speed limits
    S = contact_samples(task, x, effort, direction)
    rate = np.max(np.abs(S.qd))
    speed = min(task.workpiece_speed, task.joint_speed / rate) if rate > 0 else task.workpiece_speed
    S = contact_samples(task, x, effort, direction * speed, name)
    progress(f"  sweeping {len(x)} configurations for the guaranteed band")
    band = guaranteed_sweep(S, task.mu_range, task.shared_mu, MODE, comps).band
    if not band.feasible.all() or np.nanmin(band.width) < task.torque_resolution:
        raise PlanFailure(failure_report(task, name, x0, x1, effort, direction, comps, res, xs=x))
    try:
        safety = default_safety_margin(band)
    except QsplanError:  # unbounded everywhere: keep the controller's resolution from the finite edge
        safety = task.torque_resolution
    command, margin = choose_command(band.lower, band.upper, safety, max_margin=safety)
    s = np.concatenate([[0.0], np.cumsum(np.abs(np.diff(x)))])
    v = 1 - (0 if effort == "left" else 1)
    qd = S.qd.copy()
    qd[:, 1 - v] = np.nan  # the effort-controlled joint gets no velocity command
    return ContactSegmentPlan(name, effort, MODE, res.path[:, 0].copy(), t0 + s / speed, x, S.q.copy(), qd,
                              band.lower.copy(), band.upper.copy(), command, margin, comps, float(speed), res)  # fmt: skip


def _regrasp(task, i, x, q, t0, options, progress, counters):
    name = f"regrasp {i + 1}: both fingers release and regrasp at x = {x:.4g} m"
    progress(name)
    q = np.asarray(q, float)
    q_open = q + np.array([REGRASP_OPENING, -REGRASP_OPENING])  # the left finger opens counter-clockwise
    lim = task.joint_limits
    results, path = [], [q[None, :]]
    for a, b in ((q, q_open), (q_open, q)):
        res = plan_path(lim[:, 0], lim[:, 1], a, b, lambda s: check_free_state(task, x, s), options)
        counters[0] += res.validity_checks
        counters[1] += res.seconds
        if not res.exact:
            raise QsplanError(f"plan: {name}: OMPL found no collision-free finger motion ({res.status})")
        results.append(res)
        path.append(res.path[1:])
    path = np.vstack(path)
    steps = np.max(np.abs(np.diff(path, axis=0)), axis=1)
    t = t0 + np.concatenate([[0.0], np.cumsum(steps / task.joint_speed)])
    seg_qd = np.diff(path, axis=0) / np.maximum(np.diff(t), 1e-12)[:, None]
    qd = np.vstack([seg_qd, np.zeros((1, 2))])
    return RegraspPlan(name, float(x), t, path, qd, tuple(results))


def plan_task(task: Task, options: PlannerOptions | None = None, progress=None) -> Plan:
    """Plan ``task``: in-contact segments through OMPL with guaranteed bands, and regrasps between them.

    Parameters
    ----------
    task : planner.task.Task
    options : PlannerOptions, optional
        Default :data:`DEFAULT_OPTIONS`.
    progress : callable, optional
        ``progress(line)`` for progress messages.

    Returns
    -------
    Plan
        Checked: every command inside its band.

    Raises
    ------
    PlanFailure
        When a segment has no plan, with the report of where and why.
    """
    if options is None:
        options = DEFAULT_OPTIONS
    progress = progress or (lambda line: None)
    t_start = time.perf_counter()
    counters = [0, 0.0]
    phases, t0 = [], 0.0
    xs = [task.start_x, *task.waypoints.tolist()]
    for i, (x0, x1) in enumerate(zip(xs[:-1], xs[1:])):
        if i:
            prev = phases[-1]
            phases.append(_regrasp(task, i - 1, x0, prev.q[-1], t0, options, progress, counters))
            t0 = float(phases[-1].t[-1])
        seg = _segment(task, i, x0, x1, t0, options, progress, counters)
        phases.append(seg)
        t0 = float(seg.t[-1])
    plan = Plan(task, tuple(phases), time.perf_counter() - t_start, counters[0], counters[1], options)
    plan.check()
    return plan
