"""An exported plan executed in MuJoCo, at the friction set's vertices and random points (issue 24, item 5).

:func:`replay_mujoco` builds the task's scene (:func:`qsplan.planner.replay.mujoco_scene.scene_xml`), samples the
plan at :data:`CONTROL_RATE` (:func:`qsplan.planner.export.sample.sample_plan`: the controller's commands) and
executes them as a controller would, with no stop added anywhere: over each tick a velocity-controlled or held
joint's servo tracks ``q + qd (t - t_tick)`` with ``qd`` as feed-forward (its drive integrates the velocity
command, so it lands on the next tick's ``q``), a torque-controlled joint's servo is switched off and its motor
applies ``tau``.  Before ``t = 0`` the grasp is loaded for :data:`PRELOAD_TIME` with the first row's commands,
the joints held: the plan's first row is a loaded grasp.

At every row of the plan it reports the workpiece's pose error (the simulated pose against the row's) and each
contact's interaction (palm:0, palm:1, left, right), judged over the interval from the row to the next row of
its phase (a phase's last row: from the previous one): ``B`` (broken) where the contact's mean normal force
over the interval is under :data:`BROKEN_FORCE`, else ``S`` (sliding) where its two bodies' points that touched
at the interval's start have slid apart faster than :data:`SLIP_SPEED` on average, else ``R`` (rolling).
Means matter: MuJoCo's convex contact model lets a sliding contact separate at ``mu`` times its slip speed
(micrometre hops at kHz, which no 1 kHz controller sees), so the force at one instant can be zero while its
mean is the quasistatic one.  In-contact rows compare the letters with the planned mode; a regrasp's rows
(``free``) are judged by the pose only (the workpiece should rest where the plan leaves it).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from qsplan.mechanics.errors import QsplanError

__all__ = ["BROKEN_FORCE", "CONTACTS", "CONTROL_RATE", "PRELOAD_TIME", "SLIP_SPEED", "MujocoReplay", "MujocoRun",
           "load_mujoco", "pair_letters", "planned_pairs", "replay_mujoco"]

#: Control rate (Hz) at which the exported commands are sampled and sent: a common joint-servo rate.
CONTROL_RATE = 1000.0

#: Time (s) the grasp is loaded before the plan's clock starts (joints held, the first row's torque applied):
#: the contacts settle in ~1 ms (:data:`qsplan.planner.replay.mujoco_scene.CONTACT_TIMECONST`); 20 ms is 20 ticks.
PRELOAD_TIME = 0.02

#: Mean slip speed (m/s) between two rows above which a loaded contact is sliding: 16x below the slowest contact
#: slip measured in the bundled slides (1.6 mm/s at 1 cm/s of workpiece speed), 3x above the fastest drift of a
#: resting contact (3e-5 m/s: a workpiece settling on the palm after a release; MuJoCo's steady creep is ~1e-7).
SLIP_SPEED = 1e-4

#: Mean normal force (N) between two rows under which a contact is broken: a fifth of the planner's default force
#: margin (0.05 N, every loaded contact's guaranteed minimum).
BROKEN_FORCE = 0.01

#: The paper's contacts, in the plan's mode-letter order.
CONTACTS = ("palm:0", "palm:1", "left", "right")


def load_mujoco():
    """The ``mujoco`` module.

    Raises
    ------
    QsplanError
        ``engine: MuJoCo is not installed ...`` naming the extra that installs it.
    """
    try:
        import mujoco
    except ImportError:
        raise QsplanError("engine: MuJoCo is not installed; pip install 'qsplan[sim]' (or mujoco)") from None
    return mujoco


@dataclass(frozen=True, slots=True, eq=False)
class MujocoRun:
    """One execution of a plan in MuJoCo at one friction vector.

    Attributes
    ----------
    mu : ndarray, shape (4,)
        Friction of palm:0, palm:1, left, right.
    t : ndarray, shape (m,)
        The plan's row times (s).
    phase : ndarray of int, shape (m,)
    planned, observed : ndarray of str, shape (m,)
        The plan's mode (``free`` on regrasps) and the letters judged in MuJoCo (:data:`CONTACTS` order).
    position_error : ndarray, shape (m,)
        Distance (m) of the workpiece's centre of mass from the row's.
    theta_error : ndarray, shape (m,)
        Its orientation error (rad).
    normal_force, slip_speed : ndarray, shape (m, 4)
        Each contact's mean normal force (N) and mean slip speed (m/s) over the row's judged interval.
    seconds : float
        Wall time of the run.
    """

    mu: np.ndarray
    t: np.ndarray
    phase: np.ndarray
    planned: np.ndarray
    observed: np.ndarray
    position_error: np.ndarray
    theta_error: np.ndarray
    normal_force: np.ndarray
    slip_speed: np.ndarray
    seconds: float

    @property
    def contact_rows(self) -> np.ndarray:
        """Where the plan is in contact (not a regrasp), shape (m,) bool."""
        return self.planned != "free"

    @property
    def mismatches(self) -> np.ndarray:
        """In-contact rows whose judged letters differ from the planned mode, shape (m,) bool.

        Two readings the means cannot make are left to what they can:

        * the first row of a phase leaves rest: its interval's means still count the load a breaking contact had
          (MuJoCo's contacts are compliant: the pivot's vertex 0 unloads over that interval) and a sliding contact's
          slip from rest may average under :data:`SLIP_SPEED`; a pair whose letter differs there is kept when the
          next row of the phase observes the planned letter;
        * a hold (every planned letter ``R``) claims that nothing moves, not how the load is shared: five contacts
          hold the workpiece statically indeterminately (the proof shows an equilibrium with every contact loaded;
          the compliant model may pick one that leaves a contact without force); a pair read ``B`` by its force
          alone is kept while it slips under :data:`SLIP_SPEED`.
        """
        out = self.contact_rows & (self.observed != self.planned)
        m = out.size
        for k in np.flatnonzero(out):
            start = k == 0 or self.phase[k - 1] != self.phase[k]
            nxt = self.observed[k + 1] if k + 1 < m and self.phase[k + 1] == self.phase[k] else None
            hold = set(self.planned[k]) == {"R"}
            out[k] = not all(p == o or (start and nxt is not None and nxt[j] == p)
                             or (hold and o == "B" and self.slip_speed[k, j] < SLIP_SPEED)
                             for j, (p, o) in enumerate(zip(self.planned[k], self.observed[k])))  # fmt: skip
        return out

    @property
    def modes_kept(self) -> bool:
        return not self.mismatches.any()

    @property
    def contacts_lost(self) -> tuple:
        """``(t, contact)`` of every in-contact row where a planned contact is judged broken (and the row's letters
        are not kept: :attr:`mismatches`)."""
        out = []
        for k in np.flatnonzero(self.mismatches):
            out += [(float(self.t[k]), c) for c, p, o in zip(CONTACTS, self.planned[k], self.observed[k])
                    if p != "B" and o == "B"]  # fmt: skip
        return tuple(out)

    def max_error(self, rows=None) -> float:
        """Largest position error (m) over ``rows`` (bool, default all)."""
        e = self.position_error if rows is None else self.position_error[rows]
        return float(np.max(e, initial=0.0))

    def summary(self) -> str:
        """One line: friction, modes, pose error, contacts lost."""
        mu = ", ".join(f"{m:.3g}" for m in self.mu)
        n, bad = int(self.contact_rows.sum()), int(self.mismatches.sum())
        modes = f"modes kept at all {n} in-contact rows" if not bad else f"modes differ at {bad} of {n} in-contact rows"
        if bad:
            k = int(np.flatnonzero(self.mismatches)[0])
            modes += f" (first t = {self.t[k]:.4g} s: {self.observed[k]} for {self.planned[k]})"
        free = ~self.contact_rows
        line = f"mu = ({mu}): {modes}; pose error max {self.max_error() * 1e3:.3g} mm"
        if free.any():
            line += f" (regrasps {self.max_error(free) * 1e3:.3g} mm)"
        lost = self.contacts_lost
        return line + (f"; contacts lost at {len(lost)} rows, first {lost[0][1]} at t = {lost[0][0]:.4g} s" if lost
                       else "; no contact lost")  # fmt: skip

    def as_dict(self) -> dict:
        """Plain JSON (SI units in the keys)."""
        free = ~self.contact_rows
        return {"mu": [float(m) for m in self.mu], "modes_kept": self.modes_kept,
                "in_contact_rows": int(self.contact_rows.sum()), "mode_mismatches": int(self.mismatches.sum()),
                "max_position_error_m": self.max_error(),
                "max_regrasp_position_error_m": self.max_error(free) if free.any() else None,
                "max_theta_error_rad": float(np.max(np.abs(self.theta_error), initial=0.0)),
                "contacts_lost": [{"t_s": t, "contact": c} for t, c in self.contacts_lost],
                "rows": [{"t_s": float(t), "phase": int(p), "planned": str(a), "observed": str(b),
                          "position_error_m": float(e), "normal_force_N": [float(v) for v in f],
                          "slip_speed_m_s": [float(v) for v in v_]}
                         for t, p, a, b, e, f, v_ in zip(self.t, self.phase, self.planned, self.observed,
                                                         self.position_error, self.normal_force, self.slip_speed)],
                "seconds": self.seconds}  # fmt: skip


@dataclass(frozen=True, slots=True, eq=False)
class MujocoReplay:
    """A plan executed in MuJoCo at several friction vectors.

    Attributes
    ----------
    task : str
        The task's name.
    engine : str
        ``"mujoco <version>"``.
    settings : dict
        The replay's constants (rates, steps, thresholds) as recorded.
    runs : tuple of MujocoRun
    """

    task: str
    engine: str
    settings: dict
    runs: tuple = field(default=())

    @property
    def modes_kept(self) -> bool:
        return all(r.modes_kept for r in self.runs)

    def max_error(self) -> float:
        """Largest workpiece position error (m) over every run and row."""
        return max((r.max_error() for r in self.runs), default=0.0)

    def as_dict(self) -> dict:
        return {"task": self.task, "engine": self.engine, "settings": self.settings, "modes_kept": self.modes_kept,
                "max_position_error_m": self.max_error(), "runs": [r.as_dict() for r in self.runs]}  # fmt: skip


def _friction_vectors(task, mu, n_random, seed) -> np.ndarray:
    """Friction vectors (m, 4): ``mu`` as given, or the friction set's vertices and ``n_random`` seeded draws."""
    from qsplan.planner.certify.rows import friction_points

    if mu is None:
        return friction_points(task, n_random, np.random.default_rng(seed))
    m = np.asarray(mu, dtype=float)
    m = m.reshape(1, -1) if m.ndim == 1 else m
    if m.ndim != 2 or m.shape[1] != 4 or np.any(~np.isfinite(m)) or np.any(m < 0):
        raise QsplanError(f"mu: expected friction vectors (palm:0, palm:1, left, right) of nonnegative coefficients, "
                          f"shape (4,) or (m, 4); got shape {np.shape(mu)}")  # fmt: skip
    return m


def pair_letters(mode: str, names) -> str:
    """A row's planned letters over its contacts ``names`` (the canonical order, :mod:`qsplan.hands.found_contacts`)
    on the scene's four pairs (:data:`CONTACTS`): ``palm:K`` on its foot, a finger's contacts on its links; a pair
    no planned contact is on is ``B`` (open: a lifted vertex); a finger flush on an edge (two contacts) slides if
    either does, else rolls."""
    from qsplan.hands.found_contacts import slot_of

    slots = [slot_of(n, CONTACTS) for n in names]
    out = []
    for i in range(len(CONTACTS)):
        mine = [m for m, j in zip(mode, slots) if j == i]
        out.append("B" if not mine else ("S" if "S" in mine else ("R" if "R" in mine else "B")))
    return "".join(out)


def planned_pairs(cols, meta) -> np.ndarray:
    """Each row's planned letters on the four pairs (:func:`pair_letters`): a row whose phase names its contacts
    (``metadata.phases[i].contact_sets``, plans that turn the workpiece) mapped; any other row as written."""
    planned = np.asarray(cols["mode"]).astype(str).copy()
    phases = (meta or {}).get("phases") or []
    phase = np.asarray(cols["phase"]).astype(int)
    for i, d in enumerate(phases):
        rows = np.flatnonzero(phase == i)
        for run in d.get("contact_sets") or []:
            for k in rows[run["rows"][0]:run["rows"][1] + 1]:
                if planned[k] != "free":
                    planned[k] = pair_letters(planned[k], run["contacts"])
    return planned


def replay_mujoco(plan_dir, task=None, mu=None, n_random: int = 2, seed: int = 0) -> MujocoReplay:
    """Execute an exported plan in MuJoCo (the rules: :mod:`qsplan.planner.replay.mujoco_replay`).

    Parameters
    ----------
    plan_dir : str or Path
        A plan directory (``plan.csv`` and ``plan.json``) or one of its files.
    task : qsplan.planner.task.task.Task, optional
        Default: the task the plan's metadata records (:func:`qsplan.planner.certify.inputs.task_from_metadata`).
    mu : array-like, shape (4,) or (m, 4), optional
        Friction vectors to run; default every vertex of the task's friction set and ``n_random`` seeded points.
    n_random : int
        Random friction vectors besides the vertices (when ``mu`` is None).
    seed : int
        Seed of those draws.

    Returns
    -------
    MujocoReplay

    Raises
    ------
    QsplanError
        MuJoCo missing (naming the extra to install), an unreadable plan, a plan without metadata and no ``task``,
        bad ``mu``.
    """
    from qsplan.planner.certify.inputs import read_plan, task_from_metadata
    from qsplan.planner.export.sample import sample_plan, tick_times
    from qsplan.planner.replay.mujoco_run import MujocoSim

    mujoco = load_mujoco()
    cols, meta = read_plan(plan_dir)
    if task is None:
        if meta is None:
            raise QsplanError("task: the plan has no plan.json metadata recording its task; pass the task")
        task = task_from_metadata(meta, cols)
    if isinstance(n_random, bool) or not isinstance(n_random, (int, np.integer)) or n_random < 0:
        raise QsplanError(f"n_random: expected a nonnegative number of random friction vectors; got {n_random!r}")
    vectors = _friction_vectors(task, mu, int(n_random), seed)
    t = np.asarray(cols["t"], float)
    samples = sample_plan(cols, tick_times(float(t.max()), CONTROL_RATE))
    sim = MujocoSim(mujoco, task, samples, cols, PRELOAD_TIME)
    planned = planned_pairs(cols, meta)
    pose = np.column_stack([np.asarray(cols[k], float) for k in ("x_workpiece", "y_workpiece", "theta_workpiece")])
    runs = []
    for m in vectors:
        start = time.perf_counter()
        trace = sim.run(m)
        letters = np.where(trace.force < BROKEN_FORCE, "B", np.where(trace.slip > SLIP_SPEED, "S", "R"))
        observed = np.array(["".join(row) for row in letters])
        d = trace.pose - pose
        runs.append(MujocoRun(np.asarray(m, float), t, np.asarray(cols["phase"]).astype(int), planned, observed,
                              np.hypot(d[:, 0], d[:, 1]), d[:, 2], trace.force, trace.slip,
                              time.perf_counter() - start))  # fmt: skip
    from qsplan.planner.replay.mujoco_scene import CONTACT_TIMECONST, PHYSICS_STEP, SERVO_OMEGA

    settings = {"control_rate_Hz": CONTROL_RATE, "physics_step_s": PHYSICS_STEP, "preload_s": PRELOAD_TIME,
                "servo_omega_rad_s": SERVO_OMEGA, "contact_timeconst_s": CONTACT_TIMECONST,
                "slip_speed_m_s": SLIP_SPEED, "broken_force_N": BROKEN_FORCE, "stops_added": 0}  # fmt: skip
    return MujocoReplay(task.name, f"mujoco {mujoco.__version__}", settings, tuple(runs))
