"""The MuJoCo judge (issue 31, item 6): the slip MuJoCo resolves, the letters it compares, the pose off the plan's path.

The resolvable slip is checked against MuJoCo itself (its own regulariser and damping, and a block that creeps on
a palm under a steady push); the comparison rule at its edges; the pose split through contacts of known gain; and,
slow, issue 31's two certified plans that the former judge rejected, planned and replayed as a user would.
"""

import json

import numpy as np
import pytest

from qsplan.planner.replay.mujoco_replay import (POSE_TOLERANCE, RESOLVE_FACTOR, SLIP_RESOLUTION, MujocoRun,
                                                 letters_compared, pose_errors, resolvable_slip)  # fmt: skip
from qsplan.planner.replay.mujoco_run import creep_rates
from qsplan.planner.replay.mujoco_scene import CONTACT_SOLIMP, CONTACT_TIMECONST, FOOT_RADIUS, PHYSICS_STEP

#: A block on a palm, one contact pair with the replay scene's contact parameters (``%`` fills the friction).
BLOCK = f"""<mujoco>
  <option timestep="{PHYSICS_STEP!r}" gravity="0 -9.81 0" integrator="implicitfast" cone="elliptic"/>
  <worldbody>
    <geom name="palm" type="box" pos="0 -0.01 0" size="0.2 0.01 0.01" contype="0" conaffinity="0"/>
    <body name="block">
      <joint name="x" type="slide" axis="1 0 0"/>
      <joint name="y" type="slide" axis="0 1 0"/>
      <inertial pos="0 0.02 0" mass="0.2" diaginertia="1e-4 1e-4 1e-4"/>
      <geom name="foot" type="sphere" size="{FOOT_RADIUS!r}" pos="0 {FOOT_RADIUS!r} 0" contype="0" conaffinity="0"/>
    </body>
  </worldbody>
  <contact>
    <pair name="foot" geom1="palm" geom2="foot" condim="3" friction="%(mu)r %(mu)r 0 0 0"
          solref="{CONTACT_TIMECONST!r} 1" solimp="{' '.join(repr(v) for v in CONTACT_SOLIMP)}"/>
  </contact>
</mujoco>"""

#: Relative agreement asked between the derived creep and MuJoCo's: the derivation takes the impedance at zero
#: penetration (``solimp[0]``) where MuJoCo's grows with the micrometres the block sinks (0.99 -> 0.99 + 1e-5).
CREEP_RTOL = 0.02


def _block(mu):
    mujoco = pytest.importorskip("mujoco")
    m = mujoco.MjModel.from_xml_string(BLOCK % {"mu": mu})
    return mujoco, m, mujoco.MjData(m)


def _push(mujoco, m, d, force, seconds=0.05):
    """Settle the block, push it along +x with ``force`` (N); its mean speed (m/s) over the last half."""
    mujoco.mj_step(m, d, nstep=200)
    d.qfrc_applied[0] = force
    n = int(round(seconds / m.opt.timestep))
    mujoco.mj_step(m, d, nstep=n // 2)
    x0 = float(d.qpos[0])
    mujoco.mj_step(m, d, nstep=n - n // 2)
    return (float(d.qpos[0]) - x0) / ((n - n // 2) * m.opt.timestep)


def test_creep_rate_is_mujoco_s_regulariser_over_its_damping():
    mujoco, m, d = _block(0.3)
    mujoco.mj_step(m, d, nstep=200)
    assert d.ncon == 1
    a = d.contact[0].efc_address
    measured = d.efc_R[a + 1] / d.efc_KBIP[a + 1, 1]  # the friction row's R / B, as MuJoCo computed them
    assert creep_rates(m, [(0, [0])])[0] == pytest.approx(measured, rel=CREEP_RTOL)


@pytest.mark.parametrize("share", [0.25, 0.5, 0.9])
def test_a_block_pushed_inside_its_cone_creeps_at_the_derived_speed(share):
    mu, weight = 0.3, 0.2 * 9.81
    mujoco, m, d = _block(mu)
    v = _push(mujoco, m, d, share * mu * weight)
    assert v == pytest.approx(creep_rates(m, [(0, [0])])[0] * share * mu * weight, rel=CREEP_RTOL)
    assert v < resolvable_slip(creep_rates(m, [(0, [0])]), [mu, 0, 0, 0], [[weight, 0, 0, 0]], [10.0])[0, 0]


def test_a_block_pushed_past_its_cone_slides_beyond_the_resolvable_slip():
    mu, weight = 0.3, 0.2 * 9.81
    mujoco, m, d = _block(mu)
    v = _push(mujoco, m, d, 1.05 * mu * weight)  # 0.05 mu m g left over: 0.15 m/s^2, 3.7 mm/s after 25 ms
    resolvable = resolvable_slip(creep_rates(m, [(0, [0])]), [mu, 0, 0, 0], [[weight, 0, 0, 0]], [0.025])[0, 0]
    assert v > RESOLVE_FACTOR * resolvable


def test_resolvable_slip_is_the_creep_at_the_cone_s_edge_never_under_the_plan_s_micron():
    rate = np.array([2e-6, 2e-6, 1.2e-5, 1.2e-5])
    v = resolvable_slip(rate, [0.4, 0.0, 0.4, 0.1], [[10.0, 10.0, 1.0, 0.01]], [0.5])
    floor = SLIP_RESOLUTION / 0.5
    assert v[0] == pytest.approx([8e-6, floor, 4.8e-6, floor])


def test_the_slip_resolution_is_the_certifier_s_contact_tolerance():
    from qsplan.planner.certify.rows import CONTACT_GAP_TOL

    assert SLIP_RESOLUTION == CONTACT_GAP_TOL


def _row(planned, observed, planned_slip, slip, resolvable=1e-5, interval=100.0):
    return letters_compared(np.array([planned]), np.array([observed]), np.array([planned_slip], float),
                            np.array([slip], float), np.full((1, 4), resolvable), np.array([interval]))[0]  # fmt: skip


@pytest.mark.parametrize("scale, compared", [(0.99, False), (1.01, True)])
def test_a_planned_slip_is_compared_only_beyond_the_resolvable_factor(scale, compared):
    v = scale * RESOLVE_FACTOR * 1e-5
    got = _row("SSSS", "SSRS", [1e-2, 1e-2, v, 1e-2], [1e-2, 1e-2, 0.0, 1e-2])
    assert got.tolist() == [True, True, compared, True]


@pytest.mark.parametrize("scale, compared", [(0.99, False), (1.01, True)])
def test_an_observed_slip_on_a_planned_roll_is_compared_only_beyond_the_factor(scale, compared):
    got = _row("RRRR", "RSRR", [0.0] * 4, [0.0, scale * RESOLVE_FACTOR * 1e-5, 0.0, 0.0])
    assert got.tolist() == [True, compared, True, True]


@pytest.mark.parametrize("scale, compared", [(0.99, False), (1.01, True)])
def test_an_observed_slip_on_a_planned_roll_is_compared_only_beyond_the_pose_tolerance(scale, compared):
    v = 10 * RESOLVE_FACTOR * 1e-5  # resolvable by far; over 0.05 s the contact covers scale * POSE_TOLERANCE
    got = _row("RRRR", "RSRR", [0.0] * 4, [0.0, v, 0.0, 0.0], interval=scale * POSE_TOLERANCE / v)
    assert got.tolist() == [True, compared, True, True]


def test_a_break_is_always_compared():
    assert _row("SSSS", "SSBS", [0.0] * 4, [0.0] * 4).all()
    assert _row("SBSS", "SSSS", [0.0] * 4, [0.0] * 4).all()


def _run(planned, observed, planned_slip, slip, resolvable=1e-5, phase=None):
    m = len(planned)
    z = np.zeros(m)
    return MujocoRun(np.zeros(4), np.arange(m, dtype=float), np.zeros(m, int) if phase is None else np.asarray(phase),
                     np.array(planned), np.array(observed), z, z, np.ones((m, 4)), np.asarray(slip, float), 0.0,
                     np.asarray(planned_slip, float), np.full((m, 4), resolvable), z, z, np.full(m, 100.0))  # fmt: skip


@pytest.mark.parametrize("scale, kept", [(0.99, True), (1.01, False)])
def test_a_slow_planned_slip_read_as_a_roll_is_kept_only_where_not_resolvable(scale, kept):
    fast, v = 1e-2, scale * RESOLVE_FACTOR * 1e-5
    run = _run(["SSSS"] * 3, ["SSSS", "SSRS", "SSRS"], [[fast] * 4, [fast, fast, v, fast], [fast, fast, v, fast]],
               [[fast] * 4, [fast, fast, 0.0, fast], [fast, fast, 0.0, fast]])  # fmt: skip
    assert run.modes_kept is kept
    assert run.unresolved == (2 if kept else 0)
    assert run.ok is kept  # the pose is exact here


def _columns():
    """Five rows of a slide (the right joint velocity-controlled, the left torque-controlled), then a regrasp."""
    q = np.array([1.0, 1.01, 1.02, 1.03, 1.04, 1.04, 1.04])
    return {"x_workpiece": np.r_[2 * (q[:5] - 1.0), [0.08, 0.08]], "y_workpiece": np.full(7, 0.05),
            "theta_workpiece": np.zeros(7), "q_left": np.full(7, 1.3), "q_right": q,
            "control_left": np.array(["torque"] * 5 + ["velocity"] * 2), "control_right": np.array(["velocity"] * 7),
            "phase": np.array([0] * 5 + [1] * 2), "mode": np.array(["SSSS"] * 5 + ["free"] * 2)}  # fmt: skip


#: The contacts that fix the workpiece in :func:`_columns`: the palm's two (its y and theta) and the right finger's,
#: whose distance opens as x - 2 q_right grows (the left finger's joint is torque-controlled: not among them).
JACOBIAN = (np.array([[0.0, 1.0, -0.04], [0.0, 1.0, 0.04], [1.0, 0.0, 0.0]]),
            np.array([[0.0, 0.0], [0.0, 0.0], [0.0, -2.0]]), np.zeros(3))  # fmt: skip


def test_the_contacts_the_velocity_joints_carry_are_chosen():
    from qsplan.planner.replay.mujoco_replay import held_pairs

    cols = _columns()
    pairs = held_pairs(["SSSS", "SSSS", "BSSS", "SSSS", "SSSS", "free", "free"], cols, [[], [], [0], [1]])
    assert pairs == [[0, 1, 3], [0, 1, 3], [1, 3], [0, 1, 3], [0, 1, 3], [], []]


def test_the_servo_s_deflection_is_taken_out_through_the_contacts():
    cols = _columns()
    lag = np.array([-0.002, -0.001, -0.001, -0.001, -0.0005, 0.0, 0.0])  # rad, the right servo behind its command
    q = np.column_stack([np.full(7, 1.31), cols["q_right"] + lag])  # the torque joint's 10 mrad: no share
    pose = np.column_stack([cols["x_workpiece"] + 2 * lag, cols["y_workpiece"], cols["theta_workpiece"]])
    pose[3, 0] += 3e-6  # 3 um the servo does not explain
    pose[5:, 0] = pose[4, 0] + np.array([0.0, 5e-6])  # released where the last row left it, then 5 um of drift
    servo, path = pose_errors(cols, pose, q, ("left", "right"), [JACOBIAN] * 5 + [None] * 2)
    assert servo[:5] == pytest.approx(2 * np.abs(lag[:5]), abs=1e-12)
    assert path[:5] == pytest.approx([0.0, 0.0, 0.0, 3e-6, 0.0], abs=1e-12)
    assert path[5:] == pytest.approx([0.0, 5e-6], abs=1e-12)


def test_a_contact_the_scene_sinks_is_closed():
    cols = _columns()
    q = np.column_stack([np.full(7, 1.3), cols["q_right"]])
    sunk = (JACOBIAN[0], JACOBIAN[1], np.array([-1e-5, -1e-5, 0.0]))  # both feet 10 um into the palm, as planned
    pose = np.column_stack([cols["x_workpiece"], cols["y_workpiece"] + 1e-5, cols["theta_workpiece"]])
    servo, path = pose_errors(cols, pose, q, ("left", "right"), [sunk] * 5 + [None] * 2)
    assert servo == pytest.approx(np.full(7, 1e-5)) and path == pytest.approx(np.zeros(7), abs=1e-12)


def test_a_direction_no_held_contact_fixes_takes_no_share():
    cols = _columns()
    q = np.column_stack([np.full(7, 1.3), cols["q_right"] - 0.001])
    pose = np.column_stack([cols["x_workpiece"] + 1e-6, cols["y_workpiece"], cols["theta_workpiece"]])
    palm_only = (JACOBIAN[0][:2], JACOBIAN[1][:2], JACOBIAN[2][:2])  # x is free: the least move leaves it
    servo, path = pose_errors(cols, pose, q, ("left", "right"), [palm_only] * 5 + [None] * 2)
    assert servo == pytest.approx(np.zeros(7)) and path == pytest.approx(np.full(7, 1e-6))


def test_contact_rates_are_the_derivatives_of_mujoco_s_distances():
    """The closure's rates (MuJoCo's collision and ``mj_jac``) against central differences of ``mj_geomDistance``."""
    mujoco = pytest.importorskip("mujoco")
    from pathlib import Path

    from qsplan.planner.export.plan_files import read_plan_csv
    from qsplan.planner.export.sample import sample_plan, tick_times
    from qsplan.planner.replay.mujoco_run import MujocoSim
    from qsplan.planner.task.task import load_task, task_paths

    cols = read_plan_csv(Path(__file__).resolve().parent.parent / "data" / "reference_plans" / "demo_task.csv")
    task = load_task(task_paths()["demo_task"])
    sim = MujocoSim(mujoco, task, sample_plan(cols, tick_times(float(cols["t"][-1]), 1000.0)), cols, 0.0)
    k = 5
    jp, jq, gap = sim.contact_jacobians([[] if r != k else [0, 1, 3] for r in range(cols["t"].size)])[k]
    assert jp.shape == (3, 3) and np.all(np.abs(gap) < 1e-6)  # one point per contact, touching as planned
    m, d = sim.model, mujoco.MjData(sim.model)
    x0 = np.zeros(m.nq)
    x0[:3] = [cols[c][k] for c in ("x_workpiece", "y_workpiece", "theta_workpiece")]
    x0[sim.qadr] = [cols[f"q_{n}"][k] for n in task.hand.joint_names]
    h, fd = 1e-6, []
    for i in np.r_[0, 1, 2, sim.qadr]:
        rate = 0.0
        for sign in (1.0, -1.0):
            d.qpos[:] = x0
            d.qpos[i] += sign * h
            mujoco.mj_kinematics(m, d)
            rate = rate + sign * sim._distances(d, [0, 1, 3]) / (2 * h)
        fd.append(rate)
    assert np.hstack([jp, jq]) == pytest.approx(np.array(fd).T, abs=1e-6)


#: Issue 31's two certified plans that the former judge rejected (18 of 18 and 16 of 16 runs).
ISSUE_TASKS = {
    "hexagon": """name = "issue 31: hexagon, friction [0.1, 0.4]"
[hand]
file = "paper_hand"
workpiece = [[0.0, 0.0], [0.06, 0.0], [0.09, 0.045], [0.06, 0.09], [0.0, 0.09], [-0.03, 0.045]]
workpiece_mass = 0.3
[motion]
start_x = -0.01
[goal]
x = -0.029
[friction]
range = [0.1, 0.4]
[controller]
torque_resolution = 0.02
""",
    "pentagon": """name = "issue 31: the README's pentagon, friction [0, 0.4]"
[hand]
file = "paper_hand"
workpiece = [[0.0, 0.0], [0.08, 0.0], [0.09, 0.06], [0.04, 0.1], [-0.01, 0.06]]
workpiece_mass = 0.2
[motion]
start_x = 0.0
[goal]
x = -0.03
[friction]
range = [0.0, 0.4]
[controller]
torque_resolution = 0.02
""",
}


def _plan_and_replay(tmp_path, name, capsys):
    from qsplan.planner.cli.main import main

    task = tmp_path / f"{name}.toml"
    task.write_text(ISSUE_TASKS[name])
    out = tmp_path / name
    assert main(["plan", str(task), "--out", str(out), "--no-plots"]) == 0
    capsys.readouterr()
    rc = main(["replay", str(out), "--engine", "mujoco", "--runs", "0", "--json"])
    return rc, json.loads(capsys.readouterr().out), out


@pytest.mark.slow
def test_issue_hexagon_slides_where_its_slip_slows_and_mujoco_says_so(tmp_path, capsys):
    pytest.importorskip("mujoco")
    rc, doc, out = _plan_and_replay(tmp_path, "hexagon", capsys)
    assert rc == 0 and doc["ok"] and len(doc["runs"]) == 16
    for run in doc["runs"]:
        last = run["rows"][-2]  # the deceleration's last interval: the left contact's planned slip at its slowest
        assert run["contacts"] == ["palm:0", "palm:1", "left", "right"] + [f"palm:{k}" for k in range(2, 6)]
        assert last["planned"] == "SSSS" + "B" * 4 and last["compared"] == "1" * 8  # resolvable: MuJoCo compares it ...
        v, resolvable = last["planned_slip_m_s"][2], last["resolvable_slip_m_s"][2]
        assert v < 1e-4 < RESOLVE_FACTOR * 1e-4  # ... below the former fixed 0.1 mm/s that read it "R"
        assert v > 10 * resolvable and last["slip_speed_m_s"][2] > RESOLVE_FACTOR * resolvable
        assert last["observed"] == "SSSS" + "B" * 4  # the hexagon's upper feet stay off the palm
    # the plan is right there: the rigid-body replay (every mode checked) keeps 4S to the end at every vertex
    from qsplan.planner.certify.inputs import read_plan, task_from_metadata
    from qsplan.planner.replay.replay import replay_plan

    cols, meta = read_plan(out)
    task = task_from_metadata(meta, cols)
    scenes = {}
    assert all(replay_plan(cols, task.hand, run["mu"], scenes=scenes).followed for run in doc["runs"])


@pytest.mark.slow
def test_issue_pentagon_s_error_is_the_servos_deflection(tmp_path, capsys):
    """Its plan squeezed 57 N per finger at the start (the held right servo deflected: 0.12-0.19 mm against the former
    judge's round 0.1 mm).  Since the route's last key (the peak squeeze, ``qsplan.planner.search.widest``) the slide
    torque-controls the finger whose command stays near zero: no squeeze, and the error that is left is still the
    servos' deflection, the soft contacts' share a tenth of it."""
    pytest.importorskip("mujoco")
    rc, doc, _ = _plan_and_replay(tmp_path, "pentagon", capsys)
    assert rc == 0 and doc["ok"] and len(doc["runs"]) == 16
    force = max(max(r["normal_force_N"]) for run in doc["runs"] for r in run["rows"] if r.get("normal_force_N"))
    assert force < 20.0  # was 57 N per finger at mu = 0
    assert max(run["max_servo_error_m"] for run in doc["runs"]) >= 0.9 * doc["max_position_error_m"]
    assert doc["max_path_error_m"] <= min(doc["pose_tolerance_m"], 0.2 * doc["max_position_error_m"])
