"""An exported plan executed in MuJoCo, at the friction set's vertices and random points (issue 24, item 5).

:func:`replay_mujoco` builds the task's scene (:func:`qsplan.planner.replay.mujoco_scene.scene_xml`), samples the
plan at :data:`CONTROL_RATE` (:func:`qsplan.planner.export.sample.sample_plan`: the controller's commands) and
executes them as a controller would, with no stop added anywhere: over each tick a velocity-controlled or held
joint's servo tracks ``q + qd (t - t_tick)`` with ``qd`` as feed-forward (its drive integrates the velocity
command, so it lands on the next tick's ``q``), a torque-controlled joint's servo is switched off and its motor
applies ``tau``.  Before ``t = 0`` the grasp is loaded for :data:`PRELOAD_TIME` with the first row's commands,
the joints held: the plan's first row is a loaded grasp.

At every row of the plan it reports the workpiece's pose error (the simulated pose against the row's) and each
contact's interaction, judged over the interval from the row to the next row of
its phase (a phase's last row: from the previous one): ``B`` (broken) where the contact's mean normal force
over the interval is under :data:`BROKEN_FORCE`, else ``S`` (sliding) where its two bodies' points that touched
at the interval's start have slid apart, along the contact's tangent, faster than the slip MuJoCo can resolve
there, else ``R`` (rolling).  Means matter: MuJoCo's convex contact model lets a sliding contact separate at ``mu``
times its slip speed (micrometre hops at kHz, which no 1 kHz controller sees), so the force at one instant can be
zero while its mean is the quasistatic one.  The contacts are the scene's pairs
(:func:`qsplan.planner.replay.mujoco_scene.contact_pairs`): the palm edge's four (:data:`CONTACTS`: ``palm:0``,
``palm:1``, ``left``, ``right``, every earlier replay's letters), then ``palm:K``, the foot under each other vertex
``K`` of the workpiece; a row's planned letters are its contacts' mapped onto them by name (:func:`pair_letters`: a
turned workpiece on ``palm:2`` is judged on that foot's pair), a pair no planned contact is on ``B``.

**The slip MuJoCo resolves** (:func:`resolvable_slip`).  MuJoCo's friction is soft: a contact that does not slide
(its friction force inside the cone) still creeps, at ``R f / B`` (:func:`qsplan.planner.replay.mujoco_run.creep_rates`:
the friction row's regulariser ``R`` from ``solimp``, ``impratio`` and the bodies' inertia, its damping ``B`` from
``solref``), at most ``R mu f_n / B`` at the cone's edge; a slip below that needs no saturated friction, so it
does not tell a sliding contact from a stuck one.  The resolvable slip of a contact over an interval is that
creep at its mean normal force and friction, at least :data:`SLIP_RESOLUTION` over the interval.  In-contact rows
compare the letters with the planned mode only where MuJoCo can decide them (:func:`letters_compared`): a planned
``S`` where the plan's own slip (:meth:`qsplan.planner.replay.mujoco_run.MujocoSim.planned_slip`) exceeds
:data:`RESOLVE_FACTOR` times the resolvable slip, an observed ``S`` on a planned ``R`` where MuJoCo's does and
covers more than :data:`POSE_TOLERANCE` over the interval (less is the compliance of servos and contacts taking a
changing load); a break always.  A letter not compared is "not resolvable".

**The pose** (:func:`pose_errors`).  The plan promises the workpiece's pose for the joints at their commands;
the scene's servos track them with the stiffness :data:`qsplan.planner.replay.mujoco_scene.SERVO_OMEGA` gives,
so under load they deflect.  The workpiece is judged against the pose the plan's rigid geometry gives for the
joints MuJoCo measured (its contacts that the velocity-controlled and held joints carry kept closed, to first
order): the servos' share of the error is reported apart, and what remains (the soft contacts' penetration,
separation and vibration) must stay within :data:`POSE_TOLERANCE`.  A regrasp's rows (``free``) are judged
against the pose the workpiece was released at: it should rest there, but for the kick of a compliant release
(:data:`RELEASE_DRIFT`).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from qsplan.mechanics.errors import QsplanError

__all__ = ["BROKEN_FORCE", "CONTACTS", "CONTROL_RATE", "POSE_TOLERANCE", "PRELOAD_TIME", "RELEASE_DRIFT",
           "RESOLVE_FACTOR", "SLIP_RESOLUTION", "MujocoReplay", "MujocoRun", "held_pairs", "letters_compared",
           "load_mujoco", "made_pairs", "pair_letters", "planned_pairs", "pose_errors", "replay_mujoco",
           "resolvable_slip"]

#: Control rate (Hz) at which the exported commands are sampled and sent: a common joint-servo rate.
CONTROL_RATE = 1000.0

#: Time (s) the grasp is loaded before the plan's clock starts (joints held, the first row's torque applied):
#: the contacts settle in ~1 ms (:data:`qsplan.planner.replay.mujoco_scene.CONTACT_TIMECONST`); 20 ms is 20 ticks.
PRELOAD_TIME = 0.02

#: Smallest slip (m) over a row's judged interval the replay reads as a slip: the plan holds its contacts to the
#: certifier's micron (:data:`qsplan.planner.certify.rows.CONTACT_GAP_TOL`), so a slip of less over an interval is
#: inside what the plan promises.  It is also all that separates sliding from sticking at a frictionless contact,
#: whose creep (:func:`resolvable_slip`) vanishes.
SLIP_RESOLUTION = 1e-6

#: A slip decides a letter only when it exceeds the resolvable slip by this factor: where both are resolved,
#: MuJoCo's slip follows the plan's within 4 % at 99.9 % of the 193,746 sliding letters of the 34 plans issue 31's
#: sweep passes (the extremes, 0.45 and 1.33 times, slips of mm/s where the convex contact hops, and 35 um/s read
#: as 46 um/s), so a planned slip twice the resolvable one reads ``S`` and a contact that sticks never reads past it.
RESOLVE_FACTOR = 2.0

#: Largest distance (m) of the workpiece from the pose the plan gives for the joints MuJoCo measured (the servos'
#: deflection taken out, :func:`pose_errors`): the plan's own geometry holds its contacts to 1 um
#: (:data:`SLIP_RESOLUTION`); the rest is MuJoCo's soft contacts, which a rigid plan cannot promise: a sliding
#: contact of the convex model rides apart and vibrates against the stiff servos (1 kHz, micrometres), so the
#: remainder grows with the contact time constant (8.8, 19.7, 40.8 um at 0.2, 0.5, 1 ms on issue 31's hexagon at
#: mu = 0.4) and with friction.  Measured on this scene (docs/controller.md, ``benchmarks/bench_mujoco.py``): at
#: most 14 um in the 34 of issue 31's 36 certified plans that pass (the two others: a wedge of MuJoCo's convex
#: contacts, 94 um, and a plan's 490 N squeeze, 38 um); 25 um leaves room for the friction points a replay draws.
POSE_TOLERANCE = 2.5e-5

#: Largest drift (m) of a released workpiece over a regrasp's rows from where it was released (plus
#: :data:`POSE_TOLERANCE`): a compliant grasp's stored force kicks the workpiece as a finger leaves it, and no palm
#: friction stops it at zero friction.  The plan bounds the kick with its gentle release
#: (``release_acceleration``, 0.05 rad/s^2 by default: docs/controller.md, "Stops and speed", measured 0.04 mm on
#: ``two_link_regrasp_task`` at zero palm friction, 0.28 mm at 0.5 rad/s^2); 29-35 um in issue 31's sweep.
RELEASE_DRIFT = 5e-5

#: Mean normal force (N) between two rows under which a contact is broken: a fifth of the planner's default force
#: margin (0.05 N, every loaded contact's guaranteed minimum).
BROKEN_FORCE = 0.01

#: The palm edge's contacts, in the plan's mode-letter order: the friction vector's four coefficients and a replay's
#: first four pairs (the scene adds ``palm:K`` under the workpiece's other vertices after them).
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
        raise QsplanError("engine: MuJoCo is not installed; pip install '.[sim]' in the qsplan checkout "
                          "(or pip install mujoco)") from None
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
        The plan's mode on the scene's pairs (:func:`planned_pairs`; ``free`` on regrasps) and the letters judged
        in MuJoCo (:attr:`contacts` order).
    position_error : ndarray, shape (m,)
        Distance (m) of the workpiece's centre of mass from the row's.
    theta_error : ndarray, shape (m,)
        Its orientation error (rad).
    normal_force, slip_speed : ndarray, shape (m, n_c)
        Each contact's mean normal force (N) and mean slip speed (m/s) over the row's judged interval.
    seconds : float
        Wall time of the run.
    planned_slip : ndarray, shape (m, n_c)
        The plan's own mean slip speed (m/s) over the same intervals.
    resolvable : ndarray, shape (m, n_c)
        The slowest slip (m/s) MuJoCo resolves there (:func:`resolvable_slip`).
    servo_error : ndarray, shape (m,)
        The share (m) of the position error the servos' measured deflection explains (:func:`pose_errors`).
    path_error : ndarray, shape (m,)
        What remains (m): the workpiece's distance from the plan's pose at the measured joints (a regrasp's rows:
        from where it was released).
    interval : ndarray, shape (m,)
        Duration (s) of each row's judged interval.
    contacts : tuple of str
        The pairs' contacts, the letters' and columns' order (:func:`qsplan.planner.replay.mujoco_scene.contact_pairs`;
        default the palm edge's four, :data:`CONTACTS`).
    holds : ndarray of bool, shape (m,), optional
        The rows that are holds: their written mode every letter ``R`` (:func:`planned_pairs` writes ``B`` on the
        pairs no contact of theirs is on); default the rows whose pair letters are all ``R``.
    made : ndarray of bool, shape (m, n_c), optional
        The pairs whose contact the plan makes where the row's judged interval ends (:func:`made_pairs`): planned
        open, closing over the interval; their letter is not compared where it differs from the plan's.
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
    planned_slip: np.ndarray
    resolvable: np.ndarray
    servo_error: np.ndarray
    path_error: np.ndarray
    interval: np.ndarray
    contacts: tuple = CONTACTS
    holds: np.ndarray | None = None
    made: np.ndarray | None = None

    @property
    def contact_rows(self) -> np.ndarray:
        """Where the plan is in contact (not a regrasp), shape (m,) bool."""
        return self.planned != "free"

    @property
    def compared(self) -> np.ndarray:
        """Which pair letters are compared with the plan's (:func:`letters_compared`), shape (m, n_c) bool; every letter
        of a regrasp's rows is not."""
        out = letters_compared(self.planned, self.observed, self.planned_slip, self.slip_speed, self.resolvable,
                               self.interval)  # fmt: skip
        if self.made is not None:  # a contact made as the interval ends: its letter decides nothing where it differs
            differ = np.zeros_like(out)
            for k, (a, b) in enumerate(zip(self.planned, self.observed)):
                if a != "free":
                    differ[k, :min(len(a), len(b))] = [p != o for p, o in zip(a, b)]
            out &= ~(np.asarray(self.made, bool) & differ)
        return out & self.contact_rows[:, None]

    @property
    def mismatches(self) -> np.ndarray:
        """In-contact rows whose judged letters differ from the planned mode where compared (:attr:`compared`),
        shape (m,) bool.

        Two readings the means cannot make are left to what they can:

        * the first row of a phase leaves rest: its interval's means still count the load a breaking contact had
          (MuJoCo's contacts are compliant: the pivot's vertex 0 unloads over that interval); a pair whose letter
          differs there is kept when the next row of the phase observes the planned letter;
        * a hold (its mode every letter ``R``, :attr:`holds`) claims that nothing moves, not how the load is shared:
          five contacts hold the workpiece statically indeterminately (the proof shows an equilibrium with every
          contact loaded; the compliant model may pick one that leaves a contact without force); a pair read
          ``B`` by its force alone is kept while it slips less than :data:`POSE_TOLERANCE` over the interval
          (the compliance the pose check bounds).
        """
        compared = self.compared
        out = self.contact_rows & np.array([any(c and p != o for p, o, c in zip(a, b, cmp))
                                            for a, b, cmp in zip(self.planned, self.observed, compared)])  # fmt: skip
        m = out.size
        for k in np.flatnonzero(out):
            start = k == 0 or self.phase[k - 1] != self.phase[k]
            nxt = self.observed[k + 1] if k + 1 < m and self.phase[k + 1] == self.phase[k] else None
            hold = bool(self.holds[k]) if self.holds is not None else set(self.planned[k]) == {"R"}
            out[k] = not all(p == o or not compared[k, j] or (start and nxt is not None and nxt[j] == p)
                             or (hold and o == "B" and self.slip_speed[k, j] * self.interval[k] <= POSE_TOLERANCE)
                             for j, (p, o) in enumerate(zip(self.planned[k], self.observed[k])))  # fmt: skip
        return out

    @property
    def modes_kept(self) -> bool:
        return not self.mismatches.any()

    @property
    def unresolved(self) -> int:
        """In-contact pair letters not compared (their slip is not resolvable in MuJoCo)."""
        return int((self.contact_rows[:, None] & ~self.compared).sum())

    @property
    def contacts_lost(self) -> tuple:
        """``(t, contact)`` of every in-contact row where a planned contact is judged broken (and the row's letters
        are not kept: :attr:`mismatches`)."""
        out = []
        for k in np.flatnonzero(self.mismatches):
            out += [(float(self.t[k]), c) for c, p, o in zip(self.contacts, self.planned[k], self.observed[k])
                    if p != "B" and o == "B"]  # fmt: skip
        return tuple(out)

    def max_error(self, rows=None) -> float:
        """Largest position error (m) over ``rows`` (bool, default all)."""
        e = self.position_error if rows is None else self.position_error[rows]
        return float(np.max(e, initial=0.0))

    def max_path_error(self, rows=None) -> float:
        """Largest distance (m) from the plan's pose at the measured joints (:attr:`path_error`) over ``rows``."""
        e = self.path_error if rows is None else self.path_error[rows]
        return float(np.max(e, initial=0.0))

    @property
    def ok(self) -> bool:
        """The planned modes kept where resolvable, the workpiece within :data:`POSE_TOLERANCE` of the plan's pose at
        the measured joints at every in-contact row, and within that and :data:`RELEASE_DRIFT` of where it was
        released over a regrasp."""
        free = ~self.contact_rows
        return (self.modes_kept and self.max_path_error(~free) <= POSE_TOLERANCE
                and self.max_path_error(free) <= POSE_TOLERANCE + RELEASE_DRIFT)  # fmt: skip

    def summary(self) -> str:
        """One line: friction, modes, pose error (and the servos' share), contacts lost."""
        mu = ", ".join(f"{m:.3g}" for m in self.mu)
        n, bad = int(self.contact_rows.sum()), int(self.mismatches.sum())
        modes = f"modes kept at all {n} in-contact rows" if not bad else f"modes differ at {bad} of {n} in-contact rows"
        if bad:
            k = int(np.flatnonzero(self.mismatches)[0])
            modes += f" (first t = {self.t[k]:.4g} s: {self.observed[k]} for {self.planned[k]})"
        if self.unresolved:
            modes += f", {self.unresolved} letters not resolvable"
        free = ~self.contact_rows
        line = (f"mu = ({mu}): {modes}; pose error max {self.max_error() * 1e3:.3g} mm, "
                f"{self.max_path_error() * 1e3:.3g} mm off the plan at the measured joints")  # fmt: skip
        if free.any():
            line += f" (regrasps {self.max_path_error(free) * 1e3:.3g} mm from the release)"
        lost = self.contacts_lost
        return line + (f"; contacts lost at {len(lost)} rows, first {lost[0][1]} at t = {lost[0][0]:.4g} s" if lost
                       else "; no contact lost")  # fmt: skip

    def as_dict(self) -> dict:
        """Plain JSON (SI units in the keys)."""
        free = ~self.contact_rows
        compared = self.compared
        return {"mu": [float(m) for m in self.mu], "contacts": list(self.contacts), "modes_kept": self.modes_kept,
                "ok": self.ok,
                "in_contact_rows": int(self.contact_rows.sum()), "mode_mismatches": int(self.mismatches.sum()),
                "letters_not_resolvable": self.unresolved,
                "max_position_error_m": self.max_error(),
                "max_regrasp_position_error_m": self.max_error(free) if free.any() else None,
                "max_servo_error_m": float(np.max(self.servo_error, initial=0.0)),
                "max_path_error_m": self.max_path_error(),
                "max_theta_error_rad": float(np.max(np.abs(self.theta_error), initial=0.0)),
                "contacts_lost": [{"t_s": t, "contact": c} for t, c in self.contacts_lost],
                "rows": [{"t_s": float(t), "phase": int(p), "planned": str(a), "observed": str(b),
                          "compared": "".join("1" if c else "0" for c in cmp),
                          "position_error_m": float(e), "servo_error_m": float(se), "path_error_m": float(pe),
                          "normal_force_N": [float(v) for v in f], "slip_speed_m_s": [float(v) for v in v_],
                          "planned_slip_m_s": [float(v) for v in ps], "resolvable_slip_m_s": [float(v) for v in rs]}
                         for t, p, a, b, cmp, e, se, pe, f, v_, ps, rs in zip(
                             self.t, self.phase, self.planned, self.observed, compared, self.position_error,
                             self.servo_error, self.path_error, self.normal_force, self.slip_speed,
                             self.planned_slip, self.resolvable)],
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

    @property
    def ok(self) -> bool:
        """Every run :attr:`MujocoRun.ok`."""
        return all(r.ok for r in self.runs)

    def max_error(self) -> float:
        """Largest workpiece position error (m) over every run and row."""
        return max((r.max_error() for r in self.runs), default=0.0)

    def max_path_error(self) -> float:
        """Largest distance (m) from the plan's pose at the measured joints over every run and row."""
        return max((r.max_path_error() for r in self.runs), default=0.0)

    def as_dict(self) -> dict:
        return {"task": self.task, "engine": self.engine, "settings": self.settings, "modes_kept": self.modes_kept,
                "max_position_error_m": self.max_error(), "max_path_error_m": self.max_path_error(),
                "runs": [r.as_dict() for r in self.runs]}  # fmt: skip


def resolvable_slip(creep_rate, mu, normal_force, interval) -> np.ndarray:
    """The slowest slip (m/s) MuJoCo resolves at each contact: the creep of a contact held at its friction cone's edge,
    ``creep_rate mu f_n`` (:func:`qsplan.planner.replay.mujoco_run.creep_rates`), at least :data:`SLIP_RESOLUTION`
    over the row's interval.

    Parameters
    ----------
    creep_rate : array-like, shape (n_c,)
        (m/s)/N.
    mu : array-like, shape (n_c,)
        Each contact's friction.
    normal_force : array-like, shape (m, n_c)
        Mean normal force (N) over each row's interval.
    interval : array-like, shape (m,)
        Each row's judged interval (s).

    Returns
    -------
    ndarray, shape (m, n_c)
    """
    creep = np.asarray(creep_rate, float) * np.asarray(mu, float) * np.asarray(normal_force, float)
    return np.maximum(creep, SLIP_RESOLUTION / np.asarray(interval, float)[:, None])


def letters_compared(planned, observed, planned_slip, slip, resolvable, interval) -> np.ndarray:
    """Which pair letters MuJoCo can decide, shape (m, n_c) bool (``n_c`` the pairs, ``planned_slip``'s columns): a
    break always (the force decides it); a sliding letter of the plan (``S``) where the plan's slip exceeds
    :data:`RESOLVE_FACTOR` times the resolvable slip; MuJoCo's ``S`` on a planned ``R`` where MuJoCo's slip does and
    covers more than :data:`POSE_TOLERANCE` over the row's ``interval`` (s): less is the compliance of servos and
    contacts as the loads change (a hold's ramp moves the workpiece by micrometres), which the pose check bounds;
    equal letters always.  Rows without a mode (``free``) count as equal."""
    m = len(planned)
    out = np.ones((m, np.shape(planned_slip)[1]), dtype=bool)
    for k in range(m):
        if planned[k] == "free":
            continue
        for j, (p, o) in enumerate(zip(planned[k], observed[k])):
            if p == o or "B" in (p, o):
                continue
            if p == "S":
                out[k, j] = planned_slip[k, j] > RESOLVE_FACTOR * resolvable[k, j]
            else:
                out[k, j] = slip[k, j] > RESOLVE_FACTOR * resolvable[k, j] and slip[k, j] * interval[k] > POSE_TOLERANCE
    return out


def held_pairs(planned, cols, pair_joints) -> list:
    """Per row, the paper contacts (indices) that fix the workpiece for the commanded joints: the planned loaded ones
    (letter ``S`` or ``R``) whose finger has no torque-controlled joint at the row (a torque joint goes where the
    contacts push it), the palm's among them; none on a regrasp's rows."""
    joints = [k[len("control_"):] for k in cols if k.startswith("control_")]
    control = np.column_stack([np.asarray(cols[f"control_{n}"]).astype(str) for n in joints])
    out = []
    for k, mode in enumerate(planned):
        if mode == "free":
            out.append([])
            continue
        torque = control[k] == "torque"
        out.append([c for c, letter in enumerate(mode) if letter != "B" and not torque[pair_joints[c]].any()])
    return out


def pose_errors(cols, pose, q, joints, jacobians) -> tuple:
    """The workpiece's error split into the share the scene explains and what remains
    (:mod:`qsplan.planner.replay.mujoco_replay`).

    At every in-contact row the workpiece is moved, to first order, so that the contacts that fix it
    (:func:`held_pairs`; ``jacobians[k] = (J_pose, J_q, d)``, their rates and scene distances at the row) close, with
    the velocity-controlled and held joints where MuJoCo measured them: ``J_pose dpose = -(d + J_q dq)`` in least
    squares (the smallest move where they leave it free).  That pose is where the plan's rigid geometry puts the
    workpiece for the joints MuJoCo reached, in the scene's bodies (``d``: a foot of
    :data:`qsplan.planner.replay.mujoco_scene.FOOT_RADIUS` stands up to ``r (1 / sin(a / 2) - 1)`` above the plan's
    corner of interior angle ``a`` as the workpiece turns, :func:`qsplan.planner.replay.mujoco_scene.foot_centres`).  A
    regrasp's rows (``free``) take that pose of the last row before them (where the workpiece was released; the
    plan's own if none): nothing should move it.

    Parameters
    ----------
    cols : dict
        The plan's columns.
    pose : ndarray, shape (m, 3)
        The simulated workpiece pose at each row.
    q : ndarray, shape (m, n_j)
        The simulated joints at each row.
    joints : sequence of str
        The joints' names (``q`` order).
    jacobians : sequence
        Per row ``(J_pose (n, 3), J_q (n, n_j), d (n,))`` or None
        (:meth:`qsplan.planner.replay.mujoco_run.MujocoSim.contact_jacobians`).

    Returns
    -------
    servo, path : ndarray, shape (m,)
        Distance (m) from the row's planned position to the expected one, and from the expected one to the
        simulated one.
    """
    plan = np.column_stack([np.asarray(cols[k], float) for k in ("x_workpiece", "y_workpiece", "theta_workpiece")])
    Q = np.column_stack([np.asarray(cols[f"q_{n}"], float) for n in joints])
    held = np.column_stack([np.asarray(cols[f"control_{n}"]).astype(str) != "torque" for n in joints])
    free = np.asarray(cols["mode"]).astype(str) == "free"
    expected = plan.copy()
    released = None
    for k in range(plan.shape[0]):
        if free[k]:
            if released is not None:
                expected[k] = released
            continue
        if jacobians[k] is not None:
            jp, jq, gap = jacobians[k]
            dq = np.where(held[k], np.nan_to_num(q[k] - Q[k]), 0.0)
            expected[k] = plan[k] - np.linalg.lstsq(jp, gap + jq @ dq, rcond=None)[0]
        released = expected[k]
    servo = np.hypot(*(expected - plan)[:, :2].T)
    path = np.hypot(*(pose - expected)[:, :2].T)
    return servo, path


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


def pair_letters(mode: str, names, pairs=CONTACTS) -> str:
    """A row's planned letters over its contacts ``names`` (the canonical order, :mod:`qsplan.hands.contacts.found`)
    on the scene's pairs ``pairs`` (:func:`qsplan.planner.replay.mujoco_scene.contact_pairs`' keys; default the palm
    edge's four, :data:`CONTACTS`), by name: ``palm:K`` on the foot under vertex ``K``, a finger's contacts on its
    links; a pair no planned contact is on is ``B`` (open: a lifted vertex); a finger flush on an edge (two
    contacts) slides if either does, else rolls.  A palm corner on a workpiece edge (``palm:edge``) has no pair."""
    from qsplan.hands.contacts.found import slot_of

    slots = [slot_of(n, pairs) for n in names]
    out = []
    for i in range(len(pairs)):
        mine = [m for m, j in zip(mode, slots) if j == i]
        out.append("B" if not mine else ("S" if "S" in mine else ("R" if "R" in mine else "B")))
    return "".join(out)


def planned_pairs(cols, meta, pairs=CONTACTS) -> np.ndarray:
    """Each row's planned letters on the scene's pairs ``pairs`` (:func:`pair_letters`): a row whose phase names its
    contacts (``metadata.phases[i].contact_sets``, plans that turn the workpiece) mapped; any other row as written
    (the palm edge's four letters, :data:`CONTACTS`), ``B`` on the pairs after them (the feet under the other
    vertices, open)."""
    planned = np.asarray(cols["mode"]).astype(str).copy()
    pad = "B" * (len(pairs) - len(CONTACTS))
    planned = np.array([m + pad if m != "free" and len(m) == len(CONTACTS) else m for m in planned], dtype=object)
    phases = (meta or {}).get("phases") or []
    phase = np.asarray(cols["phase"]).astype(int)
    for i, d in enumerate(phases):
        rows = np.flatnonzero(phase == i)
        for run in d.get("contact_sets") or []:
            for k in rows[run["rows"][0]:run["rows"][1] + 1]:
                if planned[k] != "free":
                    planned[k] = pair_letters(str(cols["mode"][k]), run["contacts"], pairs)
    return planned.astype(str)


def made_pairs(hand, cols, meta, pairs, judged_rows) -> np.ndarray:
    """Which pairs' contacts the plan makes where each row's judged interval ends, shape (m, n_c) bool: at a phase's
    last row, the contacts the polygons show (:func:`qsplan.hands.contacts.found.ordered_contacts`, named as the
    certifier names them) on a pair none of the row's planned contacts is on (:func:`planned_pairs`; ``B``).  Such a
    contact is open along the interval and touches at its end (e.g. the edge a pivot lands on the palm); MuJoCo's
    compliant contacts and servos close it micrometres early, so its mean force over the interval decides nothing.
    Rows judged over other intervals, and regrasps, have none."""
    from qsplan.hands.contacts.found import contact_names, ordered_contacts, slot_of

    planned = planned_pairs(cols, meta, pairs)
    phase = np.asarray(cols["phase"]).astype(int)
    m = phase.size
    out = np.zeros((m, len(pairs)), dtype=bool)
    for b in np.flatnonzero(np.r_[phase[1:] != phase[:-1], True]):  # each phase's last row
        if planned[b] == "free":
            continue
        pose = [float(cols[k][b]) for k in ("x_workpiece", "y_workpiece", "theta_workpiece")]
        q = [float(cols[f"q_{n}"][b]) for n in hand.joint_names]
        try:
            found = contact_names(hand, pose, ordered_contacts(hand, pose, q))
        except QsplanError:  # a row the polygon search refuses: nothing is made there
            continue
        for j in {slot_of(n, pairs) for n in found} - {None}:
            if planned[b][j] == "B":
                out[np.asarray(judged_rows)[:, 1] == b, j] = True
    return out


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
    from qsplan.planner.replay.mujoco_scene import pair_friction

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
    planned = planned_pairs(cols, meta, sim.names)
    holds = np.array([set(str(mode)) == {"R"} for mode in cols["mode"]])
    made = made_pairs(task.hand, cols, meta, sim.names, sim.judged_rows)
    planned_slip = sim.planned_slip()
    jacobians = sim.contact_jacobians(held_pairs(planned, cols, sim.pair_joints))
    interval = np.diff(samples.t[sim.judged], axis=1)[:, 0]
    pose = np.column_stack([np.asarray(cols[k], float) for k in ("x_workpiece", "y_workpiece", "theta_workpiece")])
    runs = []
    for m in vectors:
        start = time.perf_counter()
        trace = sim.run(m)
        resolvable = resolvable_slip(sim.creep_rate, pair_friction(m, sim.names), trace.force, interval)
        letters = np.where(trace.force < BROKEN_FORCE, "B", np.where(trace.slip > resolvable, "S", "R"))
        observed = np.array(["".join(row) for row in letters])
        d = trace.pose - pose
        servo, path = pose_errors(cols, trace.pose, trace.q, samples.joints, jacobians)
        runs.append(MujocoRun(np.asarray(m, float), t, np.asarray(cols["phase"]).astype(int), planned, observed,
                              np.hypot(d[:, 0], d[:, 1]), d[:, 2], trace.force, trace.slip,
                              time.perf_counter() - start, planned_slip, resolvable, servo, path,
                              interval, sim.names, holds, made))  # fmt: skip
    from qsplan.planner.replay.mujoco_scene import CONTACT_TIMECONST, PHYSICS_STEP, SERVO_OMEGA

    settings = {"control_rate_Hz": CONTROL_RATE, "physics_step_s": PHYSICS_STEP, "preload_s": PRELOAD_TIME,
                "servo_omega_rad_s": SERVO_OMEGA, "contact_timeconst_s": CONTACT_TIMECONST,
                "slip_speed_m_s": SLIP_RESOLUTION, "slip_resolution_m": SLIP_RESOLUTION,
                "resolve_factor": RESOLVE_FACTOR,
                "creep_m_s_per_N": [float(v) for v in sim.creep_rate], "broken_force_N": BROKEN_FORCE,
                "pose_tolerance_m": POSE_TOLERANCE, "release_drift_m": RELEASE_DRIFT, "stops_added": 0}  # fmt: skip
    return MujocoReplay(task.name, f"mujoco {mujoco.__version__}", settings, tuple(runs))
