"""The MuJoCo side of :func:`qsplan.planner.replay.mujoco_replay.replay_mujoco`: one scene, one run per friction vector.

:class:`MujocoSim` compiles the task's scene once (:func:`qsplan.planner.replay.mujoco_scene.scene_xml`) and
executes a plan's controller samples (:class:`qsplan.planner.export.sample.PlanSamples`) at any friction
vector (:meth:`MujocoSim.run`), returning what the replay judges: the workpiece pose and the joints at every row and
each contact's mean normal force (MuJoCo's contact sensors, summed at every physics step) and mean slip speed
(the relative displacement, along the contact's tangent, of its bodies' points that touched at the start) over the
row's judged interval.  The contacts are the scene's (:func:`qsplan.planner.replay.mujoco_scene.contact_pairs`:
``palm:0``, ``palm:1``, ``left``, ``right``, then ``palm:K`` under the workpiece's other vertices), in that order in
every array (:attr:`MujocoSim.names`).  :meth:`MujocoSim.planned_slip` measures the plan's own slip the same way
between its rows' configurations, and :attr:`MujocoSim.creep_rate` is what MuJoCo's friction model lets a contact that
does not slide creep (:mod:`qsplan.planner.replay.mujoco_replay` compares the two).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qsplan.mechanics.errors import QsplanError

__all__ = ["CONTACT_REACH", "NORMAL_GAP", "SNAPSHOT_REACH", "MujocoSim", "RunTrace", "creep_rates"]

#: How far apart (m) two geoms may be for their closest points to be searched (``mj_geomDistance``'s ``distmax``):
#: a contact farther than 1 cm is broken whatever its slip.
SNAPSHOT_REACH = 0.01

#: Smallest separation (m) whose closest points give a contact's normal when MuJoCo has no active contact on the
#: pair: 0.1 um is 10^10 ulps of a coordinate of 0.1 m, so the direction is exact; a closer pair that is not in
#: contact has no defined normal, and its whole relative displacement counts as slip (the larger reading).
NORMAL_GAP = 1e-7

#: Distance (m) within which MuJoCo's collision reports a contact at a plan's row (``pair margin`` of the geometry
#: model :meth:`MujocoSim.contact_jacobians` uses): the plan's contacts touch within the certifier's micron; 10 um
#: finds every planned contact and no open one of a row.  A foot's pair adds how far the foot may stand above its
#: corner (:func:`qsplan.planner.replay.mujoco_scene.foot_centres`: ``r (1 / sin(a / 2) - 1)``, 41 um at a right
#: angle, when the corner's bisector points at the palm).
CONTACT_REACH = 1e-5


@dataclass(frozen=True, slots=True, eq=False)
class RunTrace:
    """What one run measured at the plan's rows.

    Attributes
    ----------
    pose : ndarray, shape (m, 3)
        The workpiece's ``(x, y, theta)`` (m, m, rad) at each row's tick.
    force : ndarray, shape (m, n_c)
        Mean normal force (N) of each contact (:attr:`MujocoSim.names`) over the row's judged interval (ticks).
    slip : ndarray, shape (m, n_c)
        Their mean slip speed (m/s) over that interval: the displacement along the contact's tangent (the normal part,
        the soft contact's penetration changing, is no slip).
    q : ndarray, shape (m, n_j)
        The joints' positions (rad or m) at each row's tick.
    """

    pose: np.ndarray
    force: np.ndarray
    slip: np.ndarray
    q: np.ndarray


def creep_rates(model, pairs) -> np.ndarray:
    """Fastest creep (m/s) per newton of friction force of each contact that MuJoCo holds without sliding.

    MuJoCo's friction is soft (Computation chapter, "Soft constraint model"; Modeling, "Solver parameters:
    Friction"): a friction row of an elliptic cone has no position term, its reference acceleration is ``-B v``,
    and inside the cone its force is ``f = (a_ref - a) / R``.  A contact whose force stays inside the cone (it does
    not slide in Coulomb's sense) therefore settles, within ``1 / B`` (0.1 ms), to the creep ``v = R f / B``; the
    fastest is at the cone's edge, ``|f| = mu f_n``.  ``R = (1 - d) / d * A_hat / impratio`` with ``A_hat`` the
    compiler's diagonal inertia of the pair (the two bodies' ``body_invweight0``) and ``d >= solimp[0]`` (largest
    at the least impedance), ``B = 2 / (solimp[1] timeconst)``.  A contact of several MJCF pairs (a finger's links)
    takes the largest.

    Parameters
    ----------
    model : mujoco.MjModel
    pairs : sequence of (int, sequence of int)
        Each contact's index and its MJCF pair ids.

    Returns
    -------
    ndarray, shape (n_c,)
        ``v / (mu f_n)``, (m/s)/N, ``n_c`` the largest index plus one.
    """
    out = np.zeros(max((c for c, _ in pairs), default=-1) + 1)
    impratio = max(float(model.opt.impratio), 1e-10)
    for c, ids in pairs:
        for i in ids:
            dmin, dmax = (float(v) for v in model.pair_solimp[i, :2])
            timeconst = float(model.pair_solref[i, 0])
            if timeconst <= 0:
                raise QsplanError("scene: a contact pair's solref is in the direct format; its creep is not derived")
            b1, b2 = (int(model.geom_bodyid[g]) for g in (model.pair_geom1[i], model.pair_geom2[i]))
            a_hat = float(model.body_invweight0[b1, 0] + model.body_invweight0[b2, 0])
            r = (1.0 - dmin) / dmin * a_hat / impratio
            out[c] = max(out[c], r * dmax * timeconst / 2.0)
    return out


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
        scene_pairs = contact_pairs(task.hand)
        self.names = tuple(scene_pairs)  # the contacts judged, the order of every array
        # sensordata -> each contact's summed normal force: the normal entry of every slot of its pairs' sensors
        self.normal_of = np.zeros((m.nsensordata, len(self.names)))
        for c, pair_names in enumerate(scene_pairs.values()):
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
        # the same intervals in rows: the plan's own slip over them (planned_slip)
        k = np.arange(rows_t.size)
        self.judged_rows = np.column_stack([np.where(same_next | ~same_prev, k, k - 1),
                                            np.where(same_next, k + 1, k)])  # fmt: skip
        self.start_pose = np.array([cols[k][0] for k in ("x_workpiece", "y_workpiece", "theta_workpiece")], float)
        self.creep_rate = creep_rates(m, self.pairs)
        self.cols = cols
        # each pair's finger joints (indices into samples.joints; none for the palm's)
        fingers = dict(zip(("left", "right"), task.hand.finger_joint_names))
        self.pair_joints = [[names.index(n) for n in fingers.get(c, ())] for c in self.names]
        self.task, self._geometry = task, None

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

    def _snapshot(self, d=None, contacts: bool = True) -> tuple:
        """Where each contact touches in ``d`` (default the run's data): ``(points (n_c, 3), body pairs (n_c, 2),
        normals (n_c, 3), body positions, orientations)``; a contact's point is the midpoint of its nearest pair's
        closest points (MuJoCo's ``mj_geomDistance``), its normal MuJoCo's contact frame on that pair when
        ``contacts`` and one is active, else the closest points' direction when at least :data:`NORMAL_GAP` apart,
        else zero (undefined)."""
        mj, m = self.mj, self.model
        d = self.data if d is None else d
        n_c = len(self.names)
        points, bodies, normals = np.zeros((n_c, 3)), np.zeros((n_c, 2), dtype=int), np.zeros((n_c, 3))
        fromto = np.zeros(6)
        nearest = {}
        for c, geoms in self.geoms:
            best = np.inf
            for g1, g2 in geoms:
                dist = mj.mj_geomDistance(m, d, g1, g2, SNAPSHOT_REACH, fromto)
                if dist < best:
                    best = dist
                    points[c] = 0.5 * (fromto[:3] + fromto[3:])
                    bodies[c] = m.geom_bodyid[g1], m.geom_bodyid[g2]
                    nearest[c] = (g1, g2)
                    gap = fromto[3:] - fromto[:3]
                    n = float(np.linalg.norm(gap))
                    normals[c] = gap / n if n >= NORMAL_GAP else 0.0
        if contacts:
            for i in range(d.ncon):
                con = d.contact[i]
                for c, pair in nearest.items():
                    if {int(con.geom1), int(con.geom2)} == set(pair):
                        normals[c] = con.frame[:3]
        return points, bodies, normals, d.xpos.copy(), d.xmat.copy().reshape(-1, 3, 3)

    @staticmethod
    def _slide(start, end) -> np.ndarray:
        """Each contact's slip (m) from snapshot ``start`` to ``end``: the material points of its two bodies that
        touched at the start, carried by each body to the end; their separation in the plane along the contact's
        tangent (all of it where the start has no normal), shape (n_c,)."""
        points, bodies, normals, x0, r0 = start
        x1, r1 = end[3], end[4]
        out = np.zeros(len(points))
        for c in range(len(points)):
            carried = []
            for b in bodies[c]:
                local = r0[b].T @ (points[c] - x0[b])
                carried.append(x1[b] + r1[b] @ local)
            gap = carried[0] - carried[1]
            gap[2] = 0.0
            n = normals[c].copy()
            n[2] = 0.0
            norm = float(np.linalg.norm(n))
            if norm > 0:
                gap -= (gap @ n) / norm**2 * n
            out[c] = float(np.linalg.norm(gap))
        return out

    def _distances(self, d, pairs) -> np.ndarray:
        """Signed distance (m) of each contact in ``pairs`` (indices) in ``d``: its nearest MJCF pair's."""
        fromto = np.zeros(6)
        return np.array([min(self.mj.mj_geomDistance(self.model, d, g1, g2, SNAPSHOT_REACH, fromto)
                             for g1, g2 in self.geoms[c][1]) for c in pairs])  # fmt: skip

    def contact_jacobians(self, pairs) -> list:
        """How the contacts ``pairs[k]`` (contact indices) of each row ``k`` open, at the row's planned
        configuration: per contact point MuJoCo's collision finds there (a finger flush on an edge touches at two),
        ``n . (v_2 - v_1)`` at the point (``n`` the contact normal, from geom 1 to geom 2, ``v`` the bodies'
        velocities there, MuJoCo's ``mj_jac``) as ``(J_pose (n, 3), J_q (n, n_j), d (n,))``: its rates per unit of
        the workpiece's pose and of each joint, and its signed distance in the scene (the scene's own geometry: a
        turned foot stands above the palm, :func:`qsplan.planner.replay.mujoco_replay.pose_errors`); ``None`` where a
        row has none."""
        from qsplan.planner.replay.mujoco_scene import FOOT_RADIUS, foot_centres, scene_xml

        mj, cols = self.mj, self.cols
        if self._geometry is None:  # a model of its own: the run's contacts keep their margin of zero
            g = self._geometry = mj.MjModel.from_xml_string(scene_xml(self.task))
            g.pair_margin[:] = CONTACT_REACH
            wp = np.asarray(self.task.hand.workpiece, float)
            stand = np.hypot(*(foot_centres(wp) - wp).T) - FOOT_RADIUS  # the most a foot stands above its corner
            for k, h in enumerate(stand):
                g.pair_margin[g.pair(f"palm:{k}").id] += h
        m = self._geometry
        d = mj.MjData(m)
        names = self.samples.joints
        pose = np.column_stack([np.asarray(cols[k], float) for k in ("x_workpiece", "y_workpiece", "theta_workpiece")])
        q = np.column_stack([np.asarray(cols[f"q_{n}"], float) for n in names])
        dofs = np.r_[m.jnt_dofadr[[m.joint(n).id for n in ("workpiece_x", "workpiece_y", "workpiece_theta")]],
                     m.jnt_dofadr[[m.joint(n).id for n in names]]]  # fmt: skip
        owner = {}
        for c, geoms in self.geoms:
            for g1, g2 in geoms:
                owner[(g1, g2)] = owner[(g2, g1)] = c
        jac1, jac2 = np.zeros((3, m.nv)), np.zeros((3, m.nv))
        out = []
        for k, mine in enumerate(pairs):
            d.qpos[:3] = pose[k]
            d.qpos[self.qadr] = np.nan_to_num(q[k])
            mj.mj_fwdPosition(m, d)
            rows, seen = [], set()
            for i in range(d.ncon):
                con = d.contact[i]
                if owner.get((int(con.geom1), int(con.geom2))) not in mine:
                    continue
                key = (int(con.geom1), int(con.geom2), round(float(con.pos[0]), 9), round(float(con.pos[1]), 9))
                if key in seen:  # the prism's two faces touch at the same point of the plane
                    continue
                seen.add(key)
                n = np.array(con.frame[:3])
                mj.mj_jac(m, d, jac1, None, con.pos, int(m.geom_bodyid[con.geom1]))
                mj.mj_jac(m, d, jac2, None, con.pos, int(m.geom_bodyid[con.geom2]))
                rows.append(np.r_[n @ (jac2 - jac1)[:, dofs], con.dist])
            if not rows:
                out.append(None)
                continue
            rows = np.array(rows)
            out.append((rows[:, :3], rows[:, 3:-1], rows[:, -1]))
        return out

    def planned_slip(self) -> np.ndarray:
        """The plan's own mean slip speed (m/s) of each contact over every row's judged interval, measured as
        :meth:`run` measures MuJoCo's (:meth:`_slide`) between the planned configurations (the rows' poses and every
        joint's ``q`` column) at the interval's end rows.  The plan's contacts touch (within the
        certifier's micron), so the whole displacement is slip.  Shape (m, n_c)."""
        mj, m, cols = self.mj, self.model, self.cols
        d = self.mj.MjData(m)
        names = self.samples.joints
        t = np.asarray(cols["t"], float)
        pose = np.column_stack([np.asarray(cols[k], float) for k in ("x_workpiece", "y_workpiece", "theta_workpiece")])
        q = np.column_stack([np.asarray(cols[f"q_{n}"], float) for n in names])
        shots = {}
        for k in np.unique(self.judged_rows):
            d.qpos[:3] = pose[k]
            d.qpos[self.qadr] = np.nan_to_num(q[k])
            mj.mj_kinematics(m, d)
            shots[int(k)] = self._snapshot(d, contacts=False)
        out = np.zeros((t.size, len(self.names)))
        for r, (a, b) in enumerate(self.judged_rows):
            if b > a and t[b] > t[a]:
                out[r] = self._slide(shots[int(a)], shots[int(b)]) / (t[b] - t[a])
        return out

    def run(self, mu) -> RunTrace:
        """Execute the samples at friction ``mu`` (4,) (palm:0, palm:1, left, right; each contact's:
        :func:`qsplan.planner.replay.mujoco_scene.pair_friction`) from the first row's state."""
        from qsplan.planner.replay.mujoco_scene import MIN_MU, pair_friction

        mj, m, d, s = self.mj, self.model, self.data, self.samples
        mu = pair_friction(mu, self.names)
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
        pose, q = np.zeros((n_rows, 3)), np.zeros((n_rows, len(self.qadr)))
        n_c = len(self.names)
        tick_force = np.zeros((n_ticks - 1, n_c))  # mean normal force over the tick (N), every physics step summed
        acc = np.zeros(m.nsensordata)
        rows_at, shots = {}, {}
        for r, i in enumerate(self.row_tick):
            rows_at.setdefault(int(i), []).append(r)
        ends = set(self.judged.ravel().tolist())
        for i in range(n_ticks):
            for r in rows_at.get(i, ()):
                pose[r] = d.qpos[:3]
                q[r] = d.qpos[self.qadr]
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
        force, slip = np.zeros((n_rows, n_c)), np.zeros((n_rows, n_c))
        for r, (a, b) in enumerate(self.judged):
            force[r] = tick_force[a:b].mean(axis=0)
            slip[r] = self._slide(shots[a], shots[b]) / (s.t[b] - s.t[a])
        return RunTrace(pose, force, slip, q)
