"""scene_to_dict inverts scene_from_dict exactly, with and without joints, through JSON too."""

import json

import numpy as np
import pytest

from qsplan.hands.examples.paper import eq37_scene, eq42_scene
from qsplan.mechanics import SceneError, make_scene, planted_scene, scene_from_dict, solve
from qsplan.mechanics.model.scene_io_write import scene_to_dict

FIELDS = ("Wn", "Wt", "Jn", "Jt", "mu", "g_obj", "g_man", "effort_controlled", "joint_velocity", "joint_effort")


def assert_same_scene(a, b):
    for f in FIELDS:
        x, y = getattr(a, f), getattr(b, f)
        assert x.shape == y.shape and x.dtype == y.dtype, f
        assert np.array_equal(x, y, equal_nan=x.dtype.kind == "f"), f  # bit for bit, NaN where unused
    assert a.joint_names == b.joint_names and a.contact_names == b.contact_names
    assert a.virtual_joints == b.virtual_joints


@pytest.mark.parametrize("seed", range(40))
def test_planted_scenes_round_trip(seed):
    rng = np.random.default_rng(seed)
    n_c = int(rng.integers(2, 9))
    n_e = int(rng.integers(0, min(3, 2 * n_c - 3) + 1))  # 2 n_c >= 3 + n_e: some mode exists (eq. 49)
    scene, _ = planted_scene(rng, n_c, n_e, n_joints=n_e + int(rng.integers(1, 4)))
    doc = scene_to_dict(scene)
    assert_same_scene(scene_from_dict(doc), scene)
    assert_same_scene(scene_from_dict(json.loads(json.dumps(doc))), scene)


@pytest.mark.parametrize("doc", [eq37_scene(), eq42_scene(0.5)], ids=["eq37", "eq42"])
def test_virtual_joint_scenes_round_trip(doc):
    scene = scene_from_dict(doc)
    assert scene.virtual_joints
    out = scene_to_dict(scene)
    assert "joints" not in out and all("velocity" in c and "jn" not in c for c in out["contacts"])
    assert_same_scene(scene_from_dict(json.loads(json.dumps(out))), scene)


def test_virtual_speed_is_folded_into_contact_velocities():
    scene = scene_from_dict(eq37_scene()).with_inputs(joint_velocity=[2.0])
    back = scene_from_dict(scene_to_dict(scene))
    np.testing.assert_array_equal(back.Jn[:, 0], 2.0 * scene.Jn[:, 0])
    assert back.joint_velocity[0] == 1.0
    assert solve(back).feasible_modes == solve(scene).feasible_modes


def test_names_survive():
    rng = np.random.default_rng(3)
    scene, _ = planted_scene(rng, 3, 1)
    doc = scene_to_dict(scene)
    doc["joints"][0]["name"] = "shoulder"
    doc["contacts"][2]["name"] = "palm"
    back = scene_from_dict(scene_to_dict(scene_from_dict(doc)))
    assert back.joint_names[0] == "shoulder" and back.contact_names[2] == "palm"


def _virtual(**kw):
    Wn = [[0, 0, 1], [1, 1, 0], [-1, 1, 0]]
    Wt = [[-1, -1, 0], [0, 0, 1], [0, 0, 1]]
    args = dict(Jn=np.ones((3, 1)), Jt=np.zeros((3, 1)), mu=[0.3] * 3, g_obj=[0, -1, 0], joint_velocity=[1.0])
    args.update(kw)
    return make_scene(Wn, Wt, virtual_joints=True, **args)


@pytest.mark.parametrize(
    "kw",
    [
        dict(Jn=np.ones((3, 2)), Jt=np.zeros((3, 2)), joint_velocity=[1.0, 1.0]),
        dict(effort_controlled=[True], joint_velocity=[np.nan], joint_effort=[1.0]),
        dict(g_man=[0.5]),
    ],
    ids=["two_joints", "effort_joint", "g_man"],
)
def test_unrepresentable_virtual_scenes_rejected(kw):
    with pytest.raises(SceneError, match="virtual_joints: a scene without joints has one velocity-controlled"):
        scene_to_dict(_virtual(**kw))
