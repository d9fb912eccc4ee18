"""Raw scene form: loading from JSON and TOML, and one test per validation branch."""

import copy
import json

import numpy as np
import pytest

from qsplan.hands.examples.paper import eq42_scene, rod_scene
from qsplan.mechanics import SceneError, load_scene, scene_from_dict, solve

RAW = {
    "g_obj": [0.0, -1.0, 0.0],
    "joints": [
        {"control": "velocity", "velocity": 0.5, "g_man": 0.0},
        {"control": "effort", "effort": 1.2, "g_man": 0.1, "name": "wrist"},
    ],
    "contacts": [
        {"wn": [0, 1, -1], "wt": [-1, 0, 0], "mu": 0.3, "jn": [0.0, 0.1], "jt": [-1.0, 0.2]},
        {"r": [1.0, 0.0], "n": [0.0, 2.0], "mu": 0.3, "jn": [0.0, -0.1], "jt": [1.0, 0.3]},
    ],
}


def test_raw_form_parsed():
    s = scene_from_dict(RAW)
    assert (s.n_contacts, s.n_joints, s.dof) == (2, 2, 4)
    np.testing.assert_array_equal(s.effort_controlled, [False, True])
    np.testing.assert_allclose(s.Wn[:, 1], [0, 1, 1])  # r = (1, 0), n = (0, 1): r x n = 1
    np.testing.assert_allclose(s.Wt[:, 1], [-1, 0, 0])
    np.testing.assert_allclose(s.g_man, [0.0, 0.1])
    assert s.joint_names == ("j0", "wrist") and not s.virtual_joints
    assert s.joint_velocity[0] == 0.5 and np.isnan(s.joint_velocity[1])
    assert s.joint_effort[1] == 1.2 and np.isnan(s.joint_effort[0])


def test_scene_without_joints_uses_contact_velocities():
    s = scene_from_dict(rod_scene(l1=1, l2=1, speed=0.2))
    assert s.virtual_joints and s.n_joints == 1 and s.dof == 3
    np.testing.assert_allclose(s.Jt[:, 0] * s.joint_velocity[0], [-0.2, 0.2])


def test_json_and_toml_files_load_the_same(tmp_path):
    import tomllib  # noqa: F401  (stdlib reader; we write TOML by hand below)

    doc = eq42_scene(0.4)
    (tmp_path / "s.json").write_text(json.dumps(doc))
    lines = ["g_obj = [0.0, -1.0, 0.0]"]
    for c in doc["contacts"]:
        lines += ["[[contacts]]", f"wn = {c['wn']}", f"wt = {c['wt']}", f"mu = {c['mu']}", f"velocity = {c['velocity']}"]
    (tmp_path / "s.toml").write_text("\n".join(lines) + "\n")
    a, b = load_scene(tmp_path / "s.json"), load_scene(tmp_path / "s.toml")
    assert solve(a).feasible_modes == solve(b).feasible_modes
    np.testing.assert_array_equal(a.Wn, b.Wn)


def test_mu_override():
    s = scene_from_dict(RAW, mu=0.7)
    np.testing.assert_array_equal(s.mu, [0.7, 0.7])
    s = scene_from_dict(RAW, mu=[0.1, 0.2])
    np.testing.assert_array_equal(s.mu, [0.1, 0.2])
    doc = copy.deepcopy(RAW)
    del doc["contacts"][0]["mu"]
    assert scene_from_dict(doc, mu=0.5).mu[0] == 0.5  # a missing mu is fine when overridden


def _bad(path, value):
    doc = copy.deepcopy(RAW)
    *head, last = path
    d = doc
    for k in head:
        d = d[k]
    if value is KeyError:
        del d[last]
    else:
        d[last] = value
    return doc


@pytest.mark.parametrize(
    "path,value,match",
    [
        (("g_obj",), KeyError, "g_obj: missing"),
        (("g_obj",), [0, 1], "g_obj: expected 3 numbers"),
        (("g_obj",), [0, float("nan"), 0], r"g_obj\[1\]: expected a finite number"),
        (("g_obj",), [0, "x", 0], r"g_obj\[1\]: expected a number"),
        (("g_obj",), [0, True, 0], r"g_obj\[1\]: expected a number"),
        (("contacts",), [], "contacts: expected a non-empty list"),
        (("contacts", 0, "mu"), -0.1, r"contacts\[0\].mu: expected a nonnegative"),
        (("contacts", 0, "mu"), "high", r"contacts\[0\].mu: expected a number"),
        (("contacts", 0, "mu"), float("nan"), r"contacts\[0\].mu: expected a finite"),
        (("contacts", 0, "mu"), KeyError, r"contacts\[0\].mu: missing"),
        (("contacts", 0, "jn"), [0.0], r"contacts\[0\].jn: expected 2 numbers"),
        (("contacts", 0, "jt"), KeyError, r"contacts\[0\].jt: missing"),
        (("contacts", 0, "wn"), [0, 0, 1], r"contacts\[0\].wn: the force part"),
        (("contacts", 0, "wt"), KeyError, r"contacts\[0\].wt: missing"),
        (("contacts", 1, "n"), [0, 0], r"contacts\[1\].n: zero normal"),
        (("contacts", 1, "r"), KeyError, r"contacts\[1\].r: missing"),
        (("contacts", 0, "velocity"), [0, 1], r"contacts\[0\].velocity: only for scenes without joints"),
        (("contacts", 0, "color"), "red", r"contacts\[0\]: unknown field\(s\) 'color'"),
        (("joints", 0, "control"), "position", r"joints\[0\].control: expected 'velocity' or 'effort'"),
        (("joints", 1, "effort"), KeyError, r"joints\[1\].effort: missing"),
        (("joints", 0, "velocity"), float("inf"), r"joints\[0\].velocity: expected a finite"),
        (("joints",), [], "joints: expected a non-empty list"),
        (("extra",), 1, r"scene: unknown field\(s\) 'extra'"),
    ],
)
def test_validation_names_field_and_problem(path, value, match):
    with pytest.raises(SceneError, match=match):
        scene_from_dict(_bad(path, value))


def test_jacobian_rows_without_joints_rejected():
    doc = rod_scene()
    doc["contacts"][0]["jn"] = [1.0]
    with pytest.raises(SceneError, match=r"contacts\[0\].jn: Jacobian rows given but the scene has no joints"):
        scene_from_dict(doc)


def test_velocity_missing_without_joints():
    doc = rod_scene()
    del doc["contacts"][1]["velocity"]
    with pytest.raises(SceneError, match=r"contacts\[1\].velocity: missing"):
        scene_from_dict(doc)


@pytest.mark.parametrize("mu,match", [([0.1, 0.2, 0.3], "expected 1 or 2 values"), ([-1.0], "nonnegative"), ([np.nan], "finite")])
def test_bad_mu_override(mu, match):
    with pytest.raises(SceneError, match=match):
        scene_from_dict(RAW, mu=mu)


def test_file_errors(tmp_path):
    with pytest.raises(SceneError, match="cannot read scene file"):
        load_scene(tmp_path / "missing.json")
    (tmp_path / "bad.json").write_text("{not json")
    with pytest.raises(SceneError, match="invalid JSON"):
        load_scene(tmp_path / "bad.json")
    (tmp_path / "bad.toml").write_text("g_obj = [")
    with pytest.raises(SceneError, match="invalid TOML"):
        load_scene(tmp_path / "bad.toml")
    (tmp_path / "list.json").write_text("[1, 2]")
    with pytest.raises(SceneError, match="top level"):
        load_scene(tmp_path / "list.json")
