"""Re-simulate an exported plan of any two-finger hand with the finite-motion simulator (Section 5.1).

A plan promises that, for every friction coefficient in the task's interval, the
commands of its torque file make the workpiece slide in the planned mode (4S) along
each in-contact segment.  :func:`replay_plan` checks the promise the hard way: it
reads the commands back from the exported columns (:func:`qsplan.planner.export.plan_files.read_plan_csv`),
drives the hand with them through :func:`qsplan.mechanics.motion.simulator.simulate` at a friction
vector, and compares the simulated mode sequence and workpiece path with the plan's.

Nothing of the planner's band computation is used: the simulator chooses the mode
at every instant from the full model (every mode checked, eqs. 13-28), locates
mode changes as events and stops when the mode becomes ambiguous or jams.

The simulated system (:class:`ReplaySystem`) has the state
``[x, y, theta, q_0, ..., q_{n_j - 1}, t]`` (m, m, rad, the joints in the hand's order in
rad or m, s): the workpiece pose, the joint positions and the plan's clock, which indexes
the commands.  Every velocity-controlled joint follows its joint-velocity column and the
effort-controlled joint its torque column, both interpolated linearly between rows, along the path at
quasistatic speed (:func:`qsplan.planner.plan.timing.quasistatic_rows`: the model is homogeneous in the velocity
input, so the plan's stops and accelerations, which change no path, are left out; the plan's clock is then the
path parameter);
scenes come from :meth:`qsplan.hands.protocol.Hand.scene`.  Between segments the plan's regrasp
puts both fingers back on the workpiece where it is, so each segment starts from the simulated
end of the previous one (errors carry over): the paper's fingers by tangency with the planned
grasp, any other described hand's by closing each finger's last joint onto the workpiece from the plan's free
joints (:meth:`qsplan.hands.described.hand.DescribedHand.reclose`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from qsplan.mechanics.errors import QsplanError
from qsplan.planner.replay.phases import replay_segments, rows_pose

__all__ = ["ReplaySystem", "SegmentReplay", "Replay", "replay_plan", "replay_segments",
           "friction_samples", "REPLAY_STEP", "REVERSAL_NOTE"]

#: Step of the replay (s).  Mode changes are located by root finding, not by the step; 0.05 s is
#: 0.5 mm of workpiece travel at the default 1 cm/s, the spacing of the plan's rows (its band sweep),
#: so each step spans about one row of the linearly interpolated commands.
REPLAY_STEP = 0.05


#: Scenes a replay keeps (:attr:`ReplaySystem.scenes`), a few kB each: ~40 MB at most.
MAX_CACHED_SCENES = 10_000


def _default_options(max_step=REPLAY_STEP):
    from qsplan.mechanics.motion.simulator import MotionOptions

    # max_switches = 0: the first mode change already leaves the plan, so the run stops there
    # (all four contacts are still touching at that instant; nothing beyond it is modelled).
    return MotionOptions(max_step=max_step, max_switches=0)


def _travel_step(t, x, travel) -> float:
    """A replay step (s) for a segment's rows (times ``t`` s, workpiece ``x`` m): at most ``travel`` (m) of workpiece
    travel (:attr:`qsplan.hands.described.hand.DescribedHand.simulation_travel`), at most :data:`REPLAY_STEP`."""
    dt, dx = np.diff(t), np.abs(np.diff(x))
    speed = float(np.max(dx[dt > 0] / dt[dt > 0], initial=0.0))
    return min(REPLAY_STEP, travel / speed) if speed > 0 else REPLAY_STEP


#: How a pivot's piece that ends at its contact's slip reversal was replayed (:func:`_ends_at_its_reversal`).
REVERSAL_NOTE = ("a pivot's piece ending at a contact's slip reversal (the planner's cut): simulated until that "
                 "contact's sliding speed reached zero, within the cut's bracket of the piece's last row")


def _ends_at_its_reversal(motion, columns, rows) -> bool:
    """Whether a pivot's simulated piece stopped where the plan ends it: a contact's sliding speed reached zero (the
    simulator's ``sliding`` event, the last of its motion) within :data:`qsplan.planner.plan.pivot.REVERSAL_TOL` of the
    piece's last row in the workpiece's angle.  The formation search cuts a pivot on the far side of each slip reversal,
    bisected to that bracket (:func:`qsplan.planner.plan.pivot.pivot_geometry`), and holds there: the instants left
    after the reversal belong to the hold, where the certificate proves that nothing moves."""
    from qsplan.planner.plan.pivot import REVERSAL_TOL

    if not motion.events or motion.events[-1].kind != "sliding" or motion.segments[-1].ended_by != "sliding":
        return False
    theta_end = float(np.asarray(columns["theta_workpiece"], float)[rows[-1]])
    return abs(float(motion.events[-1].state[2]) - theta_end) <= REVERSAL_TOL


def _stop_message(motion, planned) -> str | None:
    s = motion.stopped
    if s is None:
        return None
    if s.kind == "max_switches":
        return f"at t = {s.time:.6g} s the mode changes from {planned} to {s.candidates[0]}"
    return s.message


@dataclass(frozen=True, slots=True, eq=False)
class ReplaySystem:
    """A hand driven by one in-contact segment's commands (a :class:`qsplan.mechanics.motion.system.MotionSystem`).

    Attributes
    ----------
    hand : qsplan.hands.protocol.Hand
    effort_controlled : ndarray of bool, shape (n_j,)
        The torque-controlled joint(s); every other joint is velocity-controlled.
    t : ndarray, shape (n,)
        Command rows' times (s).
    velocity, effort : ndarray, shape (n, n_j)
        Each velocity-controlled joint's speed (rad/s or m/s), each effort-controlled joint's effort (N m or N);
        the other entries are not read.
    friction : qsplan.mechanics.motion.system.Friction
        Of the formation's contacts, in its order.
    formation : qsplan.hands.formations.registry.Formation
        The contacts the replay keeps (their names and order).
    tracked : qsplan.hands.contacts.found.TrackedContacts
        Those contacts as the polygons showed them at the phase's start, followed by their features.
    scenes : dict
        Scenes already built, by the state's bytes (a scene depends on the state alone): the
        integrator asks again for the scene at the end of every step (its event functions, then
        the next step's first stage), and replays of one segment at other friction vectors pass
        through the same states when the mode's motion does not depend on friction (eqs. 23-25).
        Cleared past :data:`MAX_CACHED_SCENES`.
    """

    hand: object
    effort_controlled: np.ndarray
    t: np.ndarray
    velocity: np.ndarray
    effort: np.ndarray
    friction: object
    formation: object
    tracked: object
    scenes: dict = field(default_factory=dict, repr=False)

    @property
    def contact_names(self) -> tuple:
        return self.formation.contact_names

    @property
    def state_names(self) -> tuple:
        joints = tuple(f"q_{n} ({u})" for n, u in zip(self.hand.joint_names, self.hand.joint_units()))
        return ("x (m)", "y (m)", "theta (rad)") + joints + ("t (s)",)

    def commands(self, t) -> tuple:
        """``(velocity (n_j,), effort (n_j,))`` at plan time ``t`` (s), linear between rows, held beyond the ends."""
        velocity = np.array([np.interp(t, self.t, self.velocity[:, j]) for j in range(self.velocity.shape[1])])
        effort = np.array([np.interp(t, self.t, self.effort[:, j]) for j in range(self.effort.shape[1])])
        return velocity, effort

    def scene(self, x, contacts):
        from qsplan.planner.replay.phases import found_scene

        if tuple(contacts) != tuple(range(self.formation.n_contacts)):
            raise QsplanError(f"contacts: the replay keeps all {self.formation.n_contacts} contacts of the formation; "
                              f"got {tuple(contacts)}")  # fmt: skip
        key = np.asarray(x, dtype=float).tobytes()
        scene = self.scenes.get(key)
        if scene is None:
            velocity, effort = self.commands(x[-1])
            scene = found_scene(self.hand, x, self.effort_controlled, velocity, effort, self.tracked)
            if len(self.scenes) >= MAX_CACHED_SCENES:
                self.scenes.clear()
            self.scenes[key] = scene
        return scene

    def rates(self, x, qdot, thetadot) -> np.ndarray:
        from qsplan.mechanics.motion.system import pose_rate

        return np.concatenate([pose_rate(x[:3], qdot), np.asarray(thetadot, float), [1.0]])


@dataclass(frozen=True, slots=True, eq=False)
class SegmentReplay:
    """One in-contact segment re-simulated.

    Attributes
    ----------
    phase : int
        The plan's phase index (the ``phase`` column).
    planned_mode : str
    labels : tuple of str
        Mode labels of the simulated stretches, in order (the planned mode alone when followed).
    stop : str or None
        The simulator's stop message, None when it reached the segment's end.
    x_error : float
        Largest distance (m) between the simulated and the planned workpiece x at the plan's rows.
    x_end : float
        Simulated workpiece x at the end (m).
    motion : qsplan.mechanics.motion.trajectory.Motion or None
        None when the segment could not start in its planned mode.
    """

    phase: int
    planned_mode: str
    labels: tuple
    stop: str | None
    x_error: float
    x_end: float
    motion: object
    note: str | None = None  # how the phase was replayed, when not simply (qsplan.planner.replay.phases)

    @property
    def followed(self) -> bool:
        """The simulated motion stayed in the planned mode for the whole segment."""
        return self.stop is None and self.labels == (self.planned_mode,)


@dataclass(frozen=True, slots=True, eq=False)
class Replay:
    """A plan re-simulated at one friction vector.

    Attributes
    ----------
    mu : ndarray, shape (4,)
        Coefficients of the contacts palm:0, palm:1, left, right.
    segments : tuple of SegmentReplay
        Up to and including the first segment that left the plan.
    """

    mu: np.ndarray
    segments: tuple

    @property
    def followed(self) -> bool:
        return all(s.followed for s in self.segments)

    @property
    def x_error(self) -> float:
        return max((s.x_error for s in self.segments), default=0.0)

    def summary(self) -> str:
        """One line: friction, followed or where it left the plan."""
        mu = ", ".join(f"{m:.3g}" for m in self.mu)
        if self.followed:
            return f"mu = ({mu}): followed {' '.join(s.planned_mode for s in self.segments)}; x error {self.x_error:.2g} m"
        bad = next(s for s in self.segments if not s.followed)
        why = bad.stop or f"modes {' -> '.join(bad.labels)}"
        return f"mu = ({mu}): left the plan in phase {bad.phase} ({bad.planned_mode} planned): {why}"

    def as_dict(self) -> dict:
        """The ``replay.json`` entry (JSON has no NaN: ``null``)."""

        def num(v):
            return float(v) if np.isfinite(v) else None

        return {"mu": [float(m) for m in self.mu], "followed": self.followed, "x_error_m": num(self.x_error),
                "segments": [{"phase": s.phase, "planned_mode": s.planned_mode, "modes": list(s.labels), "stop": s.stop,
                              "x_error_m": num(s.x_error), "x_end_m": num(s.x_end), "note": s.note}
                             for s in self.segments]}  # fmt: skip


def _start_modes(system, x0, mu) -> tuple:
    """Letters of every mode feasible at ``x0`` (the full solver, eqs. 13-28): the planned one alone, or the plan fails."""
    from dataclasses import replace

    from qsplan.mechanics.solver.all_modes import solve

    scene = replace(system.scene(x0, tuple(range(len(system.contact_names)))), mu=np.asarray(mu, float))
    return tuple(solve(scene, residuals=False).feasible_modes)


def friction_samples(mu_range, n, seed=1, shared=False, n_contacts: int = 4) -> list:
    """``n`` friction vectors (``n_contacts``,: a formation's contact count, the default formation's 4) from
    ``mu_range``: all at ``lo``, all at ``hi``, then seeded uniform draws (one value for every contact when
    ``shared``)."""
    lo, hi = mu_range
    rng = np.random.default_rng(seed)
    draws = [np.full(n_contacts, rng.uniform(lo, hi)) if shared else rng.uniform(lo, hi, n_contacts)
             for _ in range(max(n - 2, 0))]  # fmt: skip
    return ([np.full(n_contacts, float(lo)), np.full(n_contacts, float(hi))] + draws)[:n]


def replay_plan(columns, hand, mu, options=None, scenes=None, formation=None) -> Replay:
    """Re-simulate every in-contact segment of an exported plan at the friction vector ``mu``.

    Parameters
    ----------
    columns : dict
        The plan's columns as read by :func:`qsplan.planner.export.plan_files.read_plan_csv`.
    hand : qsplan.hands.protocol.Hand
        The task's hand.
    mu : float or array-like, shape (n_c,)
        Friction of the formation's contacts (static = kinetic).
    options : qsplan.mechanics.motion.simulator.MotionOptions, optional
        Default ``max_step`` :data:`REPLAY_STEP` (a described hand's: at most its ``simulation_travel`` of workpiece
        travel per step) and ``max_switches = 0`` (stop at the first mode change).
    scenes : dict, optional
        A cache of the scenes built, to pass again to the replays of the same ``columns`` and
        ``hand`` at other friction vectors (the scenes do not depend on friction); same results.
    formation : qsplan.hands.formations.registry.Formation or str, optional
        The plan's formation (the task's); default the registry's default.

    Returns
    -------
    Replay
    """
    from qsplan.hands.described.build import as_hand
    from qsplan.hands.formations.registry import DEFAULT_FORMATION, Formation, formation as registered_formation
    from qsplan.mechanics.motion.simulator import simulate
    from qsplan.mechanics.motion.system import make_friction
    from qsplan.planner.plan.timing import quasistatic_rows
    from qsplan.planner.replay.phases import HOLD_NOTE, body_friction, formation_of, phase_rows, transition_modes, turns

    hand = as_hand(hand)
    names = hand.joint_names
    missing = [f"{c}_{n}" for n in names for c in ("q", "qd", "tau") if f"{c}_{n}" not in columns]
    if missing:
        raise QsplanError(f"plan: column {missing[0]!r} missing; expected the columns of every joint of the hand")
    given = options
    options = options or _default_options()
    formation = formation if isinstance(formation, Formation) else registered_formation(formation or DEFAULT_FORMATION)
    n_c = formation.n_contacts
    try:
        mu = np.broadcast_to(np.asarray(mu, float), (n_c,)).copy()
    except ValueError:
        raise QsplanError(f"mu: expected one friction coefficient or {n_c} (one per contact); got {np.shape(mu)}") from None
    if np.any(~np.isfinite(mu)) or np.any(mu < 0):
        raise QsplanError(f"mu: expected {n_c} nonnegative friction coefficients; got {mu.tolist()}")
    scenes = {} if scenes is None else scenes
    out, x_prev = [], None
    for seg in replay_segments(columns):
        rows, e = seg["rows"], seg["effort_joint"]
        if set(seg["mode"]) == {"R"}:  # a hold: nothing moves, the certificate proves it
            out.append(SegmentReplay(seg["phase"], seg["mode"], (seg["mode"],), None, 0.0,
                                     float(columns["x_workpiece"][rows[-1]]), None, HOLD_NOTE))  # fmt: skip
            continue
        turning = turns(columns, rows)
        # the contacts a phase makes or leaves at its ends; every scene from the contacts the polygons show
        rows, first, mode, note = phase_rows(hand, columns, rows)
        seg = dict(seg, mode=mode)
        seg_formation, tracked = formation_of(hand, columns, rows[0], mode)
        seg_mu = body_friction(seg_formation.contact_names, mu)
        if turning:
            x_prev = None  # a turning phase starts where its rows say (the hold before it moves nothing)
        if e not in names:
            raise QsplanError(f"plan: effort_joint {e!r} in phase {seg['phase']} is no joint of the hand {names}")
        tau = np.column_stack([np.asarray(columns[f"tau_{n}"], float)[rows] for n in names])
        effort = np.isfinite(tau).any(axis=0) | (np.array(names) == e)  # effort joints: those with a torque command
        # the model is quasistatic: replay along the path at speed scale 1 (the phase's stops carry no motion)
        u = np.asarray(columns["speed_scale"], float)[rows] if "speed_scale" in columns else np.ones(len(rows))
        q_rows = np.column_stack([np.asarray(columns[f"q_{n}"], float)[rows] for n in names])
        qd_rows = np.column_stack([np.asarray(columns[f"qd_{n}"], float)[rows] for n in names])
        s, velocity = quasistatic_rows(np.asarray(columns["t"], float)[rows], u, q_rows, qd_rows)
        t = float(columns["t"][rows[0]]) + s  # the replay's clock: the plan's start time plus the path parameter
        system = ReplaySystem(hand, effort, t, velocity, tau, make_friction(seg_mu, seg_mu), seg_formation, tracked,
                              scenes.setdefault(seg["phase"], {}))  # fmt: skip
        k = rows[0]
        pose = rows_pose(columns, k)
        if x_prev is not None:
            pose = x_prev[:3]  # the regrasp leaves the workpiece where the simulation put it
        q_planned = np.array([columns[f"q_{n}"][k] for n in names], float)
        q = q_planned if turning else hand.reclose(pose, q_planned, rows_pose(columns, k))
        x0 = np.concatenate([pose, q, [t[0]]])
        if hand.simulation_travel is not None and given is None:
            x_rows = np.asarray(columns["x_workpiece"], float)[rows]
            options = _default_options(_travel_step(t, x_rows, hand.simulation_travel))
        if first is not None:  # the transition row with all its contacts: the planned mode alone
            k0 = seg["rows"][0]
            start = transition_modes(hand, columns, k0, effort, mu)
            if start != (first,):
                why = f"at the transition row the feasible modes are {', '.join(start) or 'none (jam)'}"
                out.append(SegmentReplay(seg["phase"], first, start, why, np.nan, float(pose[0]), None))
                break
        start = _start_modes(system, x0, seg_mu)
        if start != (seg["mode"],):
            why = f"at t = {t[0]:.6g} s the feasible modes are {', '.join(start) or 'none (jam)'}"
            out.append(SegmentReplay(seg["phase"], seg["mode"], start, why, np.nan, float(pose[0]), None))
            break
        try:
            motion = simulate(system, x0, float(t[-1] - t[0]), options)
        except QsplanError as exc:  # the geometry left the four-contact grasp between events
            out.append(SegmentReplay(seg["phase"], seg["mode"], (), f"the simulation failed: {exc}", np.nan,
                                     float(pose[0]), None))  # fmt: skip
            break
        states = motion.states
        planned = np.asarray(columns["x_workpiece"], float)[rows]
        if states.shape[0]:
            reached = t <= states[-1, -1]
            err = float(np.max(np.abs(np.interp(t[reached], states[:, -1], states[:, 0]) - planned[reached])))
            end = states[-1]
        else:  # stopped at the segment's start
            err, end = np.nan, np.concatenate([pose, q, [t[0]]])
        stop = _stop_message(motion, seg["mode"])
        if turning and stop is not None and _ends_at_its_reversal(motion, columns, rows):
            stop, note = None, REVERSAL_NOTE
        out.append(SegmentReplay(seg["phase"], seg["mode"], tuple(motion.labels), stop, err, float(end[0]), motion,
                                 note))  # fmt: skip
        if not out[-1].followed:
            break  # the rest of the plan starts from a state the plan did not foresee
        x_prev = end
    return Replay(mu, tuple(out))
