"""Holds proved with friction (:mod:`qsplan.mechanics.bands.friction_hold`): nothing moves for every coefficient in a box.

Checked against what does not share its code:

* closed forms of a block (side 0.1 m, 0.2 kg) on a floor pushed sideways by a horizontal effort-controlled pusher:
  it slides once the push exceeds ``mu_lo m g`` (a frictionless pusher), tips once it exceeds ``m g a / h`` (pushed
  high), and, where the pusher's own friction can lift it, may slide from ``mu_lo m g / (1 + mu_lo mu_p)`` although
  resting is still possible (the quasistatic model's non-uniqueness): each 2 % inside and outside its edge, and far
  along the unbounded side (a pusher's friction of 100);
* a witness is a solution of the model (eqs. 2-11): its contact velocities have the behaviours' signs, its forces
  balance the load at a torque in the ramp, inside the cones of coefficients in the box, opposing each slip;
* the frictionless hold proof (:func:`qsplan.mechanics.bands.hold.prove_hold`, a different programme) on the frictionless
  box ``[0, 0]``: the same verdict on its closed-form scenes;
* a rigid-body engine (MuJoCo, the ``sim`` extra): the pushed block at the box's lowest friction, 2 % inside each
  edge, stays put (creeps under 1 mm in a second: its contacts are soft), 2 % outside it slides or tips over;
* a box proved is proved at each of its vertices and at interior points (one coefficient per contact, a point box);
* validation: one ``pytest.raises`` per branch.
"""

from __future__ import annotations

import numpy as np
import pytest

from qsplan.mechanics import QsplanError, make_scene, point_wrench, wrench_matrices
from qsplan.mechanics.bands.friction_hold import BEHAVIOURS, prove_friction_hold
from qsplan.mechanics.bands.hold import prove_hold

G = 9.81  # m/s^2
MASS = 0.2  # kg
A_HALF = 0.05  # m, half the block's width
LOW, HIGH = 0.3, 0.5  # the floor's friction box
#: Inside and outside each closed-form edge by this fraction of the threshold: far above the proof's slack (1e-6 N)
#: and its rest margin's tolerance, so either verdict is decided with room.
EDGE = 0.02
#: A witness's equations hold to this (N, or m/s per unit motion): the programme's slack and rounding.
WITNESS_TOL = 1e-5


def _pushed(height, push):
    """The block on the floor under (-a, 0), (a, 0), its centre of mass at (0, a), pushed along +x at (-a, height)
    by a horizontal prismatic pusher with force ``push`` (N); contacts: floor left, floor right, pusher."""
    a = A_HALF
    r = np.array([(-a, 0.0), (a, 0.0), (-a, height)])
    n = np.array([(0.0, 1.0), (0.0, 1.0), (1.0, 0.0)])
    Wn, Wt = wrench_matrices(r, n)
    Jn = np.array([[0.0], [0.0], [1.0]])  # n . (1, 0): the pusher moves along +x with its joint
    Jt = np.array([[0.0], [0.0], [0.0]])  # t = (0, 1) at the pusher: it moves along x only
    return make_scene(Wn, Wt, Jn, Jt, np.zeros(3), point_wrench((0.0, a), (0.0, -MASS * G)), g_man=np.zeros(1),
                      effort_controlled=np.array([True]), joint_velocity=np.array([np.nan]),
                      joint_effort=np.array([push]))  # fmt: skip


def _box(pusher_mu=(0.0, 0.0)):
    """The friction box: the floor's [LOW, HIGH] at both floor contacts, ``pusher_mu`` at the pusher."""
    return np.array([[LOW, LOW, pusher_mu[0]], [HIGH, HIGH, pusher_mu[1]]])


SLIDE = LOW * MASS * G  # N: the frictionless pusher's push that slides the block at the box's lowest friction


def _check_witness(scene, proof, mu_box, torques):
    """The witness solves the model: behaviours' velocity signs, equilibrium at a torque in the ramp, cones in the box."""
    from qsplan.mechanics.bands.hold import hold_matrix

    e = np.asarray(scene.effort_joints)
    A = hold_matrix(scene)
    B = np.hstack([scene.Wt.T, -scene.Jt[:, e]])
    vn, vt = A @ proof.motion, B @ proof.motion
    cn, ct = proof.forces[:, 0], proof.forces[:, 1]
    lo, hi = mu_box
    for i, b in enumerate(proof.behaviours):
        assert b in BEHAVIOURS
        if b == "B":
            assert vn[i] > 0.5 and abs(cn[i]) < WITNESS_TOL and abs(ct[i]) < WITNESS_TOL
            continue
        assert abs(vn[i]) < WITNESS_TOL and cn[i] > -WITNESS_TOL
        if b == "R":
            assert abs(vt[i]) < WITNESS_TOL and abs(ct[i]) <= hi[i] * cn[i] + WITNESS_TOL
        else:
            s = 1.0 if b == "S+" else -1.0
            assert s * vt[i] > 0.5  # slipping that way
            assert lo[i] * cn[i] - WITNESS_TOL <= -s * ct[i] <= hi[i] * cn[i] + WITNESS_TOL  # friction opposes it
            assert lo[i] - 1e-9 <= proof.mu[i] <= hi[i] + 1e-9
    residual = scene.Wn @ cn + scene.Wt @ ct + scene.g_obj
    np.testing.assert_allclose(residual, 0.0, atol=WITNESS_TOL)
    tau = scene.Jn[:, e].T @ cn + scene.Jt[:, e].T @ ct + scene.g_man[e]  # the torque the witness needs
    assert np.min(torques) - WITNESS_TOL <= tau[0] <= np.max(torques) + WITNESS_TOL


# --- closed forms -----------------------------------------------------------------------------------------------

@pytest.mark.parametrize("side, proved", [(1 - EDGE, True), (1 + EDGE, False)])
def test_block_pushed_low_slides_at_the_lowest_friction(side, proved):
    """Pushed low (tipping needs 0.33 N m / 0.03 m = 3.3 N), a frictionless pusher: held iff push < mu_lo m g."""
    scene = _pushed(0.03, side * SLIDE)
    proof = prove_friction_hold(scene, _box())
    assert proof.proved is proved, proof.reason
    if proved:
        assert proof.rest_margin > 0 and proof.programmes == 4**3  # the rest and 63 motions, every one refused
    else:
        assert "rest is not an equilibrium" in proof.reason


@pytest.mark.parametrize("side, proved", [(1 - EDGE, True), (1 + EDGE, False)])
def test_block_pushed_high_tips_before_it_slides(side, proved):
    """Pushed at 0.25 m, tipping about the right corner (m g a / h = 0.392 N) comes before sliding (0.589 N)."""
    height = 0.25
    tip = MASS * G * A_HALF / height
    assert tip < SLIDE
    proof = prove_friction_hold(_pushed(height, side * tip), _box())
    assert proof.proved is proved, proof.reason


def _lifting_threshold(pusher_hi, height=0.03):
    """The least push at which a slide exists, the pusher stuck to the block lifting it by its friction ``f``:
    ``F >= mu_f (m g - f)`` with ``f <= mu_p F`` (least at the floor's lowest and the pusher's highest coefficient),
    and the lift's moment must leave the left floor contact pressed, ``N_1 = (m g - 2 f - h F / a) / 2 >= 0``
    (moments about the origin): the larger of the two limits.  (With the pusher stuck and the right corner on the
    floor the block can only translate; a slipping pusher lifts nothing, its least friction being 0.)"""
    by_friction = LOW * MASS * G / (1 + LOW * pusher_hi)
    by_moment = (MASS * G / 2) / (1 / LOW - height / (2 * A_HALF))
    return max(by_friction, by_moment)


@pytest.mark.parametrize("pusher_hi", [0.2, 100.0])
@pytest.mark.parametrize("side", [1 - EDGE, 1 + EDGE])
def test_a_pusher_with_friction_can_lift_the_block_into_a_slide(pusher_hi, side):
    """Between :func:`_lifting_threshold` and ``mu_lo m g`` the block may rest and may slide: the rest alone (the
    frictionless proof's question) does not prove a hold; the slide is the witness, a solution of the model.  At a
    pusher's friction of 0.2 the friction limits the lift (0.555 N); at 100 the moment does (0.323 N)."""
    push = side * _lifting_threshold(pusher_hi)
    assert push < SLIDE  # resting is possible at every push here
    scene = _pushed(0.03, push)
    box = _box((0.0, pusher_hi))
    proof = prove_friction_hold(scene, box)
    if side < 1:
        assert proof.proved, proof.reason
        return
    assert not proof.proved and proof.behaviours is not None
    # the floor slides along +x (v_t = t . v with t = (-1, 0): negative), the pusher sticks
    assert proof.behaviours == ("S-", "S-", "R"), proof.behaviours
    _check_witness(scene, proof, box, [push])


def test_a_ramp_is_held_only_where_both_its_ends_are():
    scene = _pushed(0.03, 0.0)
    assert prove_friction_hold(scene, _box(), torques=[[0.1], [(1 - EDGE) * SLIDE]]).proved
    proof = prove_friction_hold(scene, _box(), torques=[[0.1], [(1 + EDGE) * SLIDE]])
    assert not proof.proved and "rest is not an equilibrium" in proof.reason


def test_a_wrench_box_pushing_sideways_adds_to_the_push():
    """A box of sideways forces on the block, up to 0.1 N: the push's limit drops by 0.1 N."""
    from qsplan.mechanics.bands.disturbance import WrenchBox

    box = WrenchBox((-0.1, 0.0, 0.0), (0.1, 0.0, 0.0))
    assert prove_friction_hold(_pushed(0.03, (1 - EDGE) * (SLIDE - 0.1)), _box(), disturbance=box).proved
    assert not prove_friction_hold(_pushed(0.03, (1 + EDGE) * (SLIDE - 0.1)), _box(), disturbance=box).proved


# --- a rigid-body engine ----------------------------------------------------------------------------------------

#: MuJoCo's contacts are soft: a block held by friction creeps; in one second it creeps less than this (m, rad) 2 %
#: inside an edge (measured 0.15 mm), and moves more than MOVED outside it (measured 31 mm and 1.56 rad).
CREEP = (1e-3, 1e-3)
MOVED = (1e-2, 0.1)


def _mujoco_push(height, push, mu, half_height=0.15, seconds=1.0):
    """The pushed block in MuJoCo (x-z plane, gravity along -z): a box ``2a`` wide and ``2 half_height`` tall on a
    plane with friction ``mu`` (elliptic cones), pushed along +x at ``height`` by a frictionless sphere on a slide
    joint with a motor of force ``push`` (N).  Settled 0.3 s unpushed, then pushed for ``seconds``; returns how far the
    block moved along x (m) and turned (rad).  (The tipping threshold m g a / h does not depend on the centre of mass's
    height, so a tall box matches the proof's scene.)"""
    mujoco = pytest.importorskip("mujoco")
    xml = f"""<mujoco><option timestep="0.0005" gravity="0 0 -{G}" cone="elliptic" impratio="20"/>
      <worldbody>
        <geom name="floor" type="plane" size="1 1 0.1" contype="0" conaffinity="0"/>
        <body pos="0 0 {half_height}"><freejoint/>
          <geom name="box" type="box" size="{A_HALF} 0.05 {half_height}" mass="{MASS}" contype="0" conaffinity="0"/>
        </body>
        <body pos="{-A_HALF - 0.005} 0 {height}"><joint name="slide" type="slide" axis="1 0 0"/>
          <geom name="tip" type="sphere" size="0.005" mass="0.01" contype="0" conaffinity="0"/></body>
      </worldbody>
      <contact>
        <pair geom1="box" geom2="floor" condim="3" friction="{mu} {mu} 0.005 0.0001 0.0001" solref="0.002 1"/>
        <pair geom1="box" geom2="tip" condim="1" solref="0.002 1"/>
      </contact>
      <actuator><motor joint="slide" gear="1"/></actuator></mujoco>"""  # fmt: skip
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    for _ in range(int(0.3 / model.opt.timestep)):
        mujoco.mj_step(model, data)
    start = data.qpos[:7].copy()
    data.ctrl[0] = push
    for _ in range(int(seconds / model.opt.timestep)):
        mujoco.mj_step(model, data)
    w = abs(float(np.clip(data.qpos[3] * start[3] + data.qpos[4:7] @ start[4:7], -1.0, 1.0)))
    return float(data.qpos[0] - start[0]), 2 * float(np.arccos(w))


@pytest.mark.parametrize("height, threshold", [(0.03, SLIDE), (0.25, MASS * G * A_HALF / 0.25)], ids=["slide", "tip"])
@pytest.mark.parametrize("side", [1 - EDGE, 1 + EDGE])
def test_a_rigid_body_engine_moves_the_block_where_the_proof_refuses(height, threshold, side):
    proof = prove_friction_hold(_pushed(height, side * threshold), _box())
    moved, turned = _mujoco_push(height, side * threshold, LOW)
    if proof.proved:
        assert abs(moved) < CREEP[0] and turned < CREEP[1], (moved, turned)
    else:
        assert moved > MOVED[0] or turned > MOVED[1], (moved, turned)
    assert proof.proved is (side < 1)


# --- the frictionless proof, a second programme ----------------------------------------------------------------

@pytest.mark.parametrize("walls, weight, pusher", [(True, MASS * G, False), (True, 0.0, False), (True, MASS * G, True)],
                         ids=["between walls", "weightless between walls", "pressed by a pusher"])
def test_frictionless_box_gives_the_frictionless_proofs_verdict(walls, weight, pusher):
    from tests.mechanics.test_hold import _block

    scene = _block(walls=walls, weight=weight, pusher=pusher)
    torques = [0.0] * len(scene.effort_joints)
    expected = prove_hold(scene, torques or None).proved
    assert prove_friction_hold(scene, (0.0, 0.0), torques=torques or None).proved is expected


def test_block_alone_on_a_floor_slides_for_free_without_friction_and_rests_with_it():
    """No joint: the frictionless proof has nothing to hold (it refuses), this one answers: sideways costs nothing at
    zero friction (a witness sliding with no force along it), and any friction keeps it."""
    from tests.mechanics.test_hold import _block

    scene = _block(walls=False, joints=False)
    free = prove_friction_hold(scene, (0.0, 0.0))
    assert not free.proved and set(free.behaviours) <= {"S+", "S-"}
    np.testing.assert_allclose(free.forces[:, 1], 0.0, atol=WITNESS_TOL)
    assert prove_friction_hold(scene, (LOW, HIGH)).proved


# --- the box against its points --------------------------------------------------------------------------------

def test_a_proved_box_is_proved_at_its_vertices_and_inside():
    scene = _pushed(0.03, (1 - EDGE) * _lifting_threshold(0.2))
    box = _box((0.0, 0.2))
    assert prove_friction_hold(scene, box).proved
    rng = np.random.default_rng(3)
    points = [np.where(np.array(c, dtype=bool), box[1], box[0]) for c in np.ndindex(2, 2, 2)]
    points += list(box[0] + rng.random((6, 3)) * (box[1] - box[0]))
    for mu in points:
        assert prove_friction_hold(scene, np.vstack([mu, mu])).proved, mu


def test_a_refused_box_has_a_point_whose_witness_is_a_solution():
    """The witness's coefficients are one point of the box; the point box there is refused too."""
    push = (1 + EDGE) * _lifting_threshold(0.2)
    scene = _pushed(0.03, push)
    proof = prove_friction_hold(scene, _box((0.0, 0.2)))
    assert not proof.proved
    at = np.array(proof.mu)
    at[2] = 0.2  # the sticking pusher needs its friction, up to the box's highest (its ratio is not a slip's)
    point = prove_friction_hold(scene, np.vstack([at, at]))
    assert not point.proved
    _check_witness(scene, point, np.vstack([at, at]), [push])


# --- validation ----------------------------------------------------------------------------------------------------

def test_friction_interval_must_be_ordered_and_nonnegative():
    with pytest.raises(QsplanError, match="mu_range"):
        prove_friction_hold(_pushed(0.03, 0.1), (0.5, 0.3))
    with pytest.raises(QsplanError, match="mu_range"):
        prove_friction_hold(_pushed(0.03, 0.1), (-0.1, 0.3))


def test_torques_need_the_ramps_two_ends():
    with pytest.raises(QsplanError, match="torques"):
        prove_friction_hold(_pushed(0.03, 0.1), _box(), torques=[[0.1, 0.2, 0.3]])
    with pytest.raises(QsplanError, match="torques"):
        prove_friction_hold(_pushed(0.03, 0.1), _box(), torques=[np.nan])
