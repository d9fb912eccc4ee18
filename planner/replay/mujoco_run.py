"""The MuJoCo side of :func:`qsplan.planner.replay.mujoco_replay.replay_mujoco`: one scene, one run per friction vector.

:class:`MujocoSim` compiles the task's scene once (:func:`qsplan.planner.replay.mujoco_scene.scene_xml`) and
executes a plan's controller samples (:class:`qsplan.planner.export.sample.PlanSamples`) at any friction
vector (:meth:`MujocoSim.run`), returning what the replay judges: the workpiece pose at every row and each
paper contact's mean normal force (MuJoCo's contact sensors, summed at every physics step) and mean slip speed
(the relative displacement of its bodies' points that touched at the start) over the row's judged interval.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qsplan.mechanics.errors import QsplanError

__all__ = ["SNAPSHOT_REACH", "MujocoSim", "RunTrace"]

#: How far apart (m) two geoms may be for their closest points to be searched (``mj_geomDistance``'s ``distmax``):
#: a contact farther than 1 cm is broken whatever its slip.
SNAPSHOT_REACH = 0.01


@dataclass(frozen=True, slots=True, eq=False)
class RunTrace:
    """What one run measured at the plan's rows.

    Attributes
    ----------
    pose : ndarray, shape (m, 3)
        The workpiece's ``(x, y, theta)`` (m, m, rad) at each row's tick.
    force : ndarray, shape (m, 4)
        Mean normal force (N) of palm:0, palm:1, left, right over the row's judged interval (ticks).
    slip : ndarray, shape (m, 4)
        Their mean slip speed (m/s) in the plane over that interval.
    """

    pose: np.ndarray
    force: np.ndarray
    slip: np.ndarray


class MujocoSim:
    """A task's scene compiled in MuJoCo and a plan's samples to execute (mutable: it holds MuJoCo's model and data).

    Parameters
    ----------
    mujoco : module
    task : qsplan.planner.task.task.Task
    samples : qsplan.planner.export.sample.PlanSamples
        The plan at the control rate; every row of ``cols`` must lie on a tick (within half a tick).
    cols : dict
        The plan's columns (:func:`qsplan.planner.export.plan_files.read_plan_csv`).
    preload : float
        Seconds the grasp is loaded before ``t = 0``, joints held at the first tick.
    """

    def __init__(self, mujoco, task, samples, cols, preload: float):
        from qsplan.planner.replay.mujoco_scene import PHYSICS_STEP, SENSOR_SLOTS, contact_pairs, scene_xml

        self.mj, self.samples = mujoco, samples
        if tuple(samples.joints) != tuple(task.hand.joint_names):
            raise QsplanError(f"plan: joints {list(samples.joints)} are not the task's hand's "
                              f"{list(task.hand.joint_names)}")  # fmt: skip
        m = self.model = mujoco.MjModel.from_xml_string(scene_xml(task))
        self.data = mujoco.MjData(m)
        names = samples.joints
        self.qadr = np.array([m.joint(n).qposadr[0] for n in names])
        self.servo = np.array([m.actuator(f"servo:{n}").id for n in names])
        self.act = m.actuator_actadr[self.servo]
        self.motor = np.array([m.actuator(f"motor:{n}").id for n in names])
        self.gain = m.actuator_gainprm[self.servo, 0].copy()
        self.bias = m.actuator_biasprm[self.servo, 1:3].copy()
        self.lead = -self.bias[:, 1] / self.gain  # kv / kp (s): the servo's velocity feed-forward as a position lead
        self.pairs = []  # (contact index, pair ids)
        self.geoms = []  # (contact index, [(geom1, geom2) of each of its pairs])
        # sensordata -> each paper contact's summed normal force: the normal entry of every slot of its pairs' sensors
        self.normal_of = np.zeros((m.nsensordata, 4))
        for c, pair_names in enumerate(contact_pairs(task.hand).values()):
            ids = [m.pair(p).id for p in pair_names]
            self.pairs.append((c, ids))
            self.geoms.append((c, [(int(m.pair_geom1[i]), int(m.pair_geom2[i])) for i in ids]))
            for i, p in zip(ids, pair_names):
                adr = int(m.sensor_adr[m.sensor(f"force:{p}").id])
                self.normal_of[adr + 1 + 4 * np.arange(SENSOR_SLOTS), c] = 1.0
        t = samples.t
        dt = np.diff(t)
        self.substeps = np.maximum(np.rint(dt / PHYSICS_STEP).astype(int), 1)
        self.step = PHYSICS_STEP
        self.n_preload = int(round(preload / PHYSICS_STEP))
        rows_t = np.asarray(cols["t"], float)
        if t.size < 2:
            raise QsplanError("plan: it lasts no longer than one control tick; nothing to execute")
        k = np.clip(np.searchsorted(t, rows_t), 1, t.size - 1)
        self.row_tick = np.where(np.abs(t[k - 1] - rows_t) <= np.abs(t[k] - rows_t), k - 1, k)  # the nearest tick
        half = 0.5 * float(np.max(dt))  # the control period (a last tick at the plan's end may be closer)
        if np.any(np.abs(t[self.row_tick] - rows_t) > half):
            raise QsplanError("plan: a row lies outside the sampled ticks")
        # the ticks judged for each row: to the next row of its phase, a phase's last row's from the previous one
        phase = np.asarray(cols["phase"], float)
        same_next = np.r_[phase[1:] == phase[:-1], False]
        same_prev = np.r_[False, phase[1:] == phase[:-1]]
        nxt, prv = np.r_[self.row_tick[1:], 0], np.r_[0, self.row_tick[:-1]]
        lo = np.where(same_next, self.row_tick, np.where(same_prev, prv, self.row_tick))
        hi = np.where(same_next, nxt, np.where(same_prev, self.row_tick, self.row_tick + 1))
        last = t.size - 1
        self.judged = np.column_stack([np.clip(lo, 0, last - 1), np.clip(np.maximum(hi, lo + 1), 1, last)])
        self.start_pose = np.array([cols[k][0] for k in ("x_workpiece", "y_workpiece", "theta_workpiece")], float)

    def _command(self, i: int, hold: bool = False) -> None:
        """Send tick ``i``'s commands: the servo of a velocity or held joint restarts its reference ramp at ``q`` (plus
        the velocity feed-forward's lead) and integrates ``qd`` over the tick; a torque joint's servo is off and its
        motor applies ``tau``.  ``hold``: every velocity zero (the preload)."""
        s, d, m = self.samples, self.data, self.model
        torque = s.control[i] == "torque"
        qd = np.where(torque | hold, 0.0, np.nan_to_num(s.qd[i]))
        taken = ~torque & self.was_torque  # torque -> position: latch the measured position (bumpless transfer)
        self.offset = np.where(torque, 0.0, np.where(taken, d.qpos[self.qadr] - np.nan_to_num(s.q[i]), self.offset))
        self.was_torque = torque
        m.actuator_gainprm[self.servo, 0] = np.where(torque, 0.0, self.gain)
        m.actuator_biasprm[self.servo, 1:3] = np.where(torque[:, None], 0.0, self.bias)
        d.act[self.act] = np.where(torque, 0.0, np.nan_to_num(s.q[i]) + self.offset + qd * self.lead)
        d.ctrl[self.servo] = qd
        d.ctrl[self.motor] = np.where(torque, np.nan_to_num(s.tau[i]), 0.0)

    def _snapshot(self) -> tuple:
        """Where each paper contact touches now: ``(points (4, 3), body pairs (4, 2), body positions, orientations)``;
        a contact's point is the midpoint of its nearest pair's closest points (MuJoCo's ``mj_geomDistance``)."""
        mj, m, d = self.mj, self.model, self.data
        points, bodies = np.zeros((4, 3)), np.zeros((4, 2), dtype=int)
        fromto = np.zeros(6)
        for c, geoms in self.geoms:
            best = np.inf
            for g1, g2 in geoms:
                dist = mj.mj_geomDistance(m, d, g1, g2, SNAPSHOT_REACH, fromto)
                if dist < best:
                    best = dist
                    points[c] = 0.5 * (fromto[:3] + fromto[3:])
                    bodies[c] = m.geom_bodyid[g1], m.geom_bodyid[g2]
        return points, bodies, d.xpos.copy(), d.xmat.copy().reshape(-1, 3, 3)

    @staticmethod
    def _slide(start, end) -> np.ndarray:
        """Each contact's relative displacement (m) in the plane from snapshot ``start`` to ``end``: the material
        points of its two bodies that touched at the start, carried by each body to the end, shape (4,)."""
        points, bodies, x0, r0 = start
        _, _, x1, r1 = end
        out = np.zeros(4)
        for c in range(4):
            carried = []
            for b in bodies[c]:
                local = r0[b].T @ (points[c] - x0[b])
                carried.append(x1[b] + r1[b] @ local)
            out[c] = float(np.hypot(*(carried[0] - carried[1])[:2]))
        return out

    def run(self, mu) -> RunTrace:
        """Execute the samples at friction ``mu`` (4,) (palm:0, palm:1, left, right) from the first row's state."""
        from qsplan.planner.replay.mujoco_scene import MIN_MU

        mj, m, d, s = self.mj, self.model, self.data, self.samples
        mu = np.asarray(mu, dtype=float)
        for c, ids in self.pairs:
            m.pair_friction[ids, :2] = max(float(mu[c]), MIN_MU)
        mj.mj_resetData(m, d)
        d.qpos[:3] = self.start_pose
        d.qpos[self.qadr] = s.q_plan[0]
        mj.mj_forward(m, d)
        self.offset = np.zeros(len(self.qadr))
        self.was_torque = np.zeros(len(self.qadr), dtype=bool)
        self._command(0, hold=True)
        if self.n_preload:
            mj.mj_step(m, d, nstep=self.n_preload)
        n_rows, n_ticks = self.row_tick.size, s.t.size
        pose = np.zeros((n_rows, 3))
        tick_force = np.zeros((n_ticks - 1, 4))  # mean normal force over the tick (N), every physics step summed
        acc = np.zeros(m.nsensordata)
        rows_at, shots = {}, {}
        for r, i in enumerate(self.row_tick):
            rows_at.setdefault(int(i), []).append(r)
        ends = set(self.judged.ravel().tolist())
        for i in range(n_ticks):
            for r in rows_at.get(i, ()):
                pose[r] = d.qpos[:3]
            if i in ends:
                shots[i] = self._snapshot()
            if i == n_ticks - 1:
                break
            self._command(i)
            n = int(self.substeps[i])
            acc[:] = 0.0
            for _ in range(n):
                mj.mj_step(m, d)
                acc += d.sensordata
            tick_force[i] = acc @ self.normal_of / n
        force, slip = np.zeros((n_rows, 4)), np.zeros((n_rows, 4))
        for r, (a, b) in enumerate(self.judged):
            force[r] = tick_force[a:b].mean(axis=0)
            slip[r] = self._slide(shots[a], shots[b]) / (s.t[b] - s.t[a])
        return RunTrace(pose, force, slip)
