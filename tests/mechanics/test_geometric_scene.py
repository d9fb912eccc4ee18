"""The geometric scene form: a two-finger scene against hand-computed W, J, g (eqs. 1-5), and validation."""

import copy
import json

import numpy as np
import pytest

from qsplan.mechanics import SceneError, load_scene, scene_from_dict
from qsplan.mechanics.model.geometric_scene import (
    find_scene_contacts,
    geometric_scene_from_dict,
    scene_from_geometric_scene,
    scene_from_geometry,
)
from qsplan.mechanics.model.manipulator import link_poses

# A pointed finger along its link frame's x axis, tip at (1, 0).
TIP = [[0, -0.05], [0.9, -0.05], [1.0, 0], [0.9, 0.05], [0, 0.05]]

# A unit box on a palm, squeezed by two fingers at half height:
#   left:  revolute at (-1.5, 0.5), link along +x, tip at (-0.5, 0.5);
#   slide: prismatic along -x (origin angle pi) at (2.3, 0.5), q = 0.3 -> its link at (2.0, 0.5);
#   right: revolute on the slide link, 0.5 further along -x -> at (1.5, 0.5), tip at (0.5, 0.5).
SPEC = {
    "name": "two fingers",
    "mu": 0.3,
    "workpiece": {"polygon": [[-0.5, 0], [0.5, 0], [0.5, 1], [-0.5, 1]], "com": [0, 0.5], "mass": 1.0},
    "palm": {"polygon": [[-2, -0.2], [2, -0.2], [2, 0], [-2, 0]]},
    "joints": [
        {
            "name": "left", "type": "revolute", "parent": -1, "origin": [-1.5, 0.5, 0],
            "control": "velocity", "velocity": 0.5,
            "link": {"polygon": TIP, "mass": 0.1, "com": [0.5, 0]},
        },
        {
            "name": "slide", "type": "prismatic", "parent": -1, "origin": [2.3, 0.5, np.pi], "q": 0.3,
            "control": "effort", "effort": 1.0,
        },
        {
            "name": "right", "type": "revolute", "parent": "slide", "origin": [0.5, 0, 0],
            "control": "velocity", "velocity": 0.0,
            "link": {"polygon": TIP, "mass": 0.2, "com": [0.5, 0]},
        },
    ],
    "contact_mu": [{"index": 3, "mu": 0.2}],
}  # fmt: skip


def test_two_finger_scene_hand_computed():
    s = scene_from_geometry(SPEC)
    assert s.contact_names == ("palm:0", "palm:1", "left:2", "right:3")
    assert s.joint_names == ("left", "slide", "right")
    # Columns [n; r x n] and [t; r x t] with t = n rotated +90 degrees (eq. 1):
    # palm at (-0.5, 0) and (0.5, 0), n = (0, 1), t = (-1, 0); left tip (-0.5, 0.5), n = (1, 0), t = (0, 1);
    # right tip (0.5, 0.5), n = (-1, 0), t = (0, -1).
    np.testing.assert_allclose(s.Wn, [[0, 0, 1, -1], [1, 1, 0, 0], [-0.5, 0.5, -0.5, 0.5]], atol=1e-12)
    np.testing.assert_allclose(s.Wt, [[-1, -1, 0, 0], [0, 0, 1, -1], [0, 0, -0.5, -0.5]], atol=1e-12)
    # Left tip velocity per unit q_left: z x (tip - joint) = z x (1, 0) = (0, 1) -> j_n = 0, j_t = 1.
    # Slide: axis (-1, 0) -> j_n = n . axis = 1, j_t = 0.  Right: z x (-1, 0) = (0, -1) -> j_n = 0, j_t = 1.
    np.testing.assert_allclose(s.Jn, [[0, 0, 0], [0, 0, 0], [0, 0, 0], [0, 1, 0]], atol=1e-12)
    np.testing.assert_allclose(s.Jt, [[0, 0, 0], [0, 0, 0], [1, 0, 0], [0, 0, 1]], atol=1e-12)
    np.testing.assert_allclose(s.mu, [0.3, 0.3, 0.3, 0.2])
    np.testing.assert_allclose(s.g_obj, [0, -9.81, 0], atol=1e-12)  # com at (0, 0.5): no moment about the origin
    # g_man = dV/dq: left com at 0.5 right of its joint, right com at 0.5 left of its joint.
    np.testing.assert_allclose(s.g_man, [0.1 * 9.81 * 0.5, 0.0, -0.2 * 9.81 * 0.5], atol=1e-12)
    np.testing.assert_array_equal(s.effort_controlled, [False, True, False])
    np.testing.assert_allclose(s.joint_velocity, [0.5, np.nan, 0.0])
    np.testing.assert_allclose(s.joint_effort, [np.nan, 1.0, np.nan])


def test_contact_kinds_and_bodies():
    contacts = find_scene_contacts(geometric_scene_from_dict(SPEC))
    assert [(c.body, c.kind) for c in contacts] == [(-1, "edge-edge"), (-1, "edge-edge"), (0, "edge-vertex"), (2, "edge-vertex")]


def tilted_spec():
    """The scene with the workpiece and fingers turned, so every Jacobian entry is nonzero."""
    spec = copy.deepcopy(SPEC)
    del spec["palm"]
    a = 0.4
    R = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
    spec["workpiece"]["polygon"] = (np.array(spec["workpiece"]["polygon"]) @ R.T).tolist()
    spec["workpiece"]["com"] = (R @ spec["workpiece"]["com"]).tolist()
    for j in (spec["joints"][0], spec["joints"][1]):
        j["origin"] = [*(R @ j["origin"][:2]), j["origin"][2] + a]
    spec["contact_mu"] = []
    return spec


def fd_contact_rows(gs, contact, step=1e-6):
    """Central differences of n . p and t . p for the link point at the contact (eq. 5)."""
    pose = link_poses(gs.manipulator, gs.q)[contact.body]
    c, s = np.cos(pose[2]), np.sin(pose[2])
    local = np.array([[c, s], [-s, c]]) @ (contact.point - pose[:2])
    n = contact.normal
    frame = np.array([n, [-n[1], n[0]]])
    cols = []
    for e in np.eye(len(gs.q)):
        pts = []
        for sign in (1, -1):
            p = link_poses(gs.manipulator, gs.q + sign * step * e)[contact.body]
            c, s = np.cos(p[2]), np.sin(p[2])
            pts.append(p[:2] + np.array([[c, -s], [s, c]]) @ local)
        cols.append(frame @ (pts[0] - pts[1]) / (2 * step))
    return np.column_stack(cols)


@pytest.mark.parametrize("make_spec", [lambda: SPEC, tilted_spec], ids=["upright", "tilted"])
def test_jacobian_rows_match_finite_differences(make_spec):
    gs = geometric_scene_from_dict(make_spec())
    contacts = find_scene_contacts(gs)
    s = scene_from_geometric_scene(gs, contacts)
    assert sum(c.body >= 0 for c in contacts) == 2
    for i, c in enumerate(contacts):
        if c.body < 0:
            assert not s.Jn[i].any() and not s.Jt[i].any()
        else:
            np.testing.assert_allclose([s.Jn[i], s.Jt[i]], fd_contact_rows(gs, c), atol=1e-8)


def test_translating_the_world_moves_only_the_origin():
    # Shifting every world coordinate by d is the old scene seen from the origin -d.
    d = np.array([0.7, -1.3])
    spec = copy.deepcopy(SPEC)
    for key in ("workpiece", "palm"):
        spec[key]["polygon"] = (np.array(spec[key]["polygon"]) + d).tolist()
    spec["workpiece"]["com"] = (np.array(spec["workpiece"]["com"]) + d).tolist()
    for j in spec["joints"]:
        if j["parent"] == -1:
            j["origin"] = [j["origin"][0] + d[0], j["origin"][1] + d[1], j["origin"][2]]
    moved, expected = scene_from_geometry(spec), scene_from_geometry(SPEC).moved_origin(-d)
    for field in ("Wn", "Wt", "Jn", "Jt", "g_obj", "g_man", "mu"):
        np.testing.assert_allclose(getattr(moved, field), getattr(expected, field), atol=1e-12, err_msg=field)


def test_mirror_symmetric_fingers_give_mirrored_columns():
    spec = copy.deepcopy(SPEC)
    spec["joints"] = [
        spec["joints"][0],
        {**spec["joints"][0], "name": "mirror", "origin": [1.5, 0.5, np.pi]},
    ]
    s = scene_from_geometry(spec)
    mirror = np.diag([-1.0, 1.0, -1.0])  # x -> -x flips f_x and the moment; normals mirror, tangents flip
    np.testing.assert_allclose(s.Wn[:, 3], mirror @ s.Wn[:, 2], atol=1e-12)
    np.testing.assert_allclose(s.Wt[:, 3], -(mirror @ s.Wt[:, 2]), atol=1e-12)
    np.testing.assert_allclose(s.g_man, [0.4905, -0.4905], atol=1e-12)


def test_dispatch_from_scene_io_and_toml(tmp_path):
    s = scene_from_dict(SPEC, mu=0.5)
    np.testing.assert_allclose(s.mu, 0.5)
    toml = """
mu = 0.3
[workpiece]
polygon = [[-0.5, 0.0], [0.5, 0.0], [0.5, 1.0], [-0.5, 1.0]]
com = [0.0, 0.5]
mass = 1.0
extra_wrench = [0.0, 0.0, 0.25]
[palm]
polygon = [[-2.0, -0.2], [2.0, -0.2], [2.0, 0.0], [-2.0, 0.0]]
[[joints]]
name = "left"
type = "revolute"
parent = -1
origin = [-1.5, 0.5, 0.0]
control = "effort"
effort = 0.2
link = { polygon = [[0, -0.05], [0.9, -0.05], [1.0, 0], [0.9, 0.05], [0, 0.05]], mass = 0.1, com = [0.5, 0.0] }
[[contact_mu]]
index = 2
mu = 0.1
"""
    path = tmp_path / "scene.toml"
    path.write_text(toml)
    s = load_scene(path)
    assert s.contact_names == ("palm:0", "palm:1", "left:2")
    np.testing.assert_allclose(s.mu, [0.3, 0.3, 0.1])
    np.testing.assert_allclose(s.g_obj, [0, -9.81, 0.25], atol=1e-12)
    (tmp_path / "scene.json").write_text(json.dumps(SPEC))
    np.testing.assert_allclose(load_scene(tmp_path / "scene.json").Wn, scene_from_geometry(SPEC).Wn)


def test_with_q_moves_the_fingers_away():
    gs = geometric_scene_from_dict(SPEC)
    away = gs.with_q([0.5, 0.3, 0.0])  # the left finger turns up and leaves the box
    assert [c.body for c in find_scene_contacts(away)] == [-1, -1, 2]
    with pytest.raises(SceneError, match=r"q: expected shape \(3\)"):
        gs.with_q([0.0])


def edit(path, value):
    """A copy of SPEC with the field at ``path`` (keys and indices) set to ``value`` (``DELETE`` removes it)."""
    spec = copy.deepcopy(SPEC)
    target = spec
    for key in path[:-1]:
        target = target[key]
    if value is DELETE:
        del target[path[-1]]
    else:
        target[path[-1]] = value
    return spec


DELETE = object()


@pytest.mark.parametrize(
    "path, value, match",
    [
        (("joints", 1, "type"), "ball", r"joints\[1\]\.type: expected 'revolute' or 'prismatic'; got 'ball'"),
        (("joints", 1, "type"), DELETE, r"joints\[1\]\.type: missing"),
        (("colour",), "red", r"scene: unknown field\(s\) 'colour'"),
        (("joints", 0, "radius"), 1.0, r"joints\[0\]: unknown field\(s\) 'radius'"),
        (("joints", 0, "link", "colour"), 1.0, r"joints\[0\]\.link: unknown field\(s\) 'colour'"),
        (("workpiece", "colour"), 1.0, r"workpiece: unknown field\(s\) 'colour'"),
        (("palm", "mass"), 1.0, r"palm: unknown field\(s\) 'mass'"),
        (("contact_mu", 0, "name"), "x", r"contact_mu\[0\]: unknown field\(s\) 'name'"),
        (("joints", 2, "parent"), "thumb", r"joints\[2\]\.parent: expected -1 \(the base\) or the name of an earlier joint"),
        (("joints", 0, "parent"), "slide", r"joints\[0\]\.parent: expected -1 \(the base\) or the name of an earlier"),
        (("joints", 0, "parent"), 0, r"joints\[0\]\.parent"),
        (("joints", 1, "name"), "left", r"joints\[1\]\.name: expected a unique name; 'left' is also joints\[0\]\.name"),
        (("joints", 1, "name"), "palm", r"joints\[1\]\.name: 'palm' is reserved"),
        (("joints", 1, "name"), 3, r"joints\[1\]\.name: expected a non-empty string"),
        (("joints", 0, "origin"), [0, 0], r"joints\[0\]\.origin: expected 3 numbers; got 2"),
        (("joints", 0, "origin"), [0, "a", 0], r"joints\[0\]\.origin\[1\]: expected a number"),
        (("joints", 0, "q"), float("nan"), r"joints\[0\]\.q: expected a finite number"),
        (("joints", 0, "control"), "torque", r"joints\[0\]\.control: expected 'velocity' or 'effort'; got 'torque'"),
        (("joints", 1, "effort"), DELETE, r"joints\[1\]\.effort: missing \(a effort-controlled joint"),
        (("joints", 0, "link", "mass"), -0.1, r"joints\[0\]\.link\.mass: expected a nonnegative mass"),
        (("joints", 0, "link", "com"), [1], r"joints\[0\]\.link\.com: expected 2 numbers"),
        (("joints", 0, "link", "polygon"), [[0, 0], [1, 1], [1, 0], [0, 1]], r"joints\[0\]\.link\.polygon: expected a simple"),
        (("joints", 0, "link", "polygon"), [[0, 0], [1, 1]], r"joints\[0\]\.link\.polygon: expected at least 3"),
        (("joints", 0, "link"), 3, r"joints\[0\]\.link: expected an object/table"),
        (("joints",), [], r"joints: expected a non-empty list"),
        (("joints",), DELETE, r"joints: expected a non-empty list"),
        (("workpiece",), DELETE, r"workpiece: missing"),
        (("workpiece", "mass"), DELETE, r"workpiece\.mass: missing"),
        (("workpiece", "mass"), -1, r"workpiece\.mass: expected a nonnegative mass"),
        (("workpiece", "com"), [0, 0, 0], r"workpiece\.com: expected 2 numbers"),
        (("workpiece", "polygon"), [[0, 0], [1, 0]], r"workpiece\.polygon: expected at least 3 vertices"),
        (("workpiece", "polygon"), "square", r"workpiece\.polygon: expected a list of \[x, y\] vertices"),
        (("workpiece", "polygon"), [[0, 0], [1, 0], [1, True]], r"workpiece\.polygon\[2\]\[1\]: expected a number"),
        (("workpiece", "extra_wrench"), [0, 0], r"workpiece\.extra_wrench: expected 3 numbers"),
        (("palm", "polygon"), [[0, 0], [1, 0], [2, 0]], r"palm\.polygon: expected a polygon with positive area"),
        (("gravity",), -9.81, r"gravity: expected a nonnegative magnitude"),
        (("contact_tolerance",), 0.0, r"contact_tolerance: expected a positive distance"),
        (("mu",), -0.1, r"mu: expected a nonnegative friction coefficient"),
        (("mu",), "high", r"mu: expected a number"),
        (("name",), 3, r"name: expected a string"),
        (("contact_mu",), {"index": 0}, r"contact_mu: expected a list"),
        (("contact_mu", 0, "index"), 4, r"contact_mu\[0\]\.index: expected a contact index below 4 \(4 contacts found\); got 4"),
        (("contact_mu", 0, "index"), -1, r"contact_mu\[0\]\.index: expected a nonnegative integer"),
        (("contact_mu", 0, "mu"), -1, r"contact_mu\[0\]\.mu: expected a nonnegative friction coefficient"),
        (("contact_mu", 0, "mu"), DELETE, r"contact_mu\[0\]\.mu: missing"),
        (("contact_mu",), [{"index": 1, "mu": 0.1}, {"index": 1, "mu": 0.2}], r"contact_mu\[1\]\.index: contact 1 already"),
        (("joints", 0, "origin"), [-1.4, 0.5, 0], r"link 0 \('left'\): penetrates the workpiece by 0\.1 m"),
    ],
)
def test_bad_fields_are_named(path, value, match):
    spec = edit(path, value)
    with pytest.raises(SceneError, match=match):
        scene_from_geometry(spec)


def test_no_contacts_found():
    spec = copy.deepcopy(SPEC)
    del spec["palm"]
    spec["contact_mu"] = []
    spec["joints"][0]["q"] = 0.5  # both fingers turn up, away from the box
    spec["joints"][2]["q"] = -0.5
    with pytest.raises(SceneError, match=r"contacts: none found .* contact_tolerance 1e-06 m"):
        scene_from_geometry(spec)


def test_vertex_on_vertex_names_the_link():
    spec = copy.deepcopy(SPEC)
    spec["joints"][0]["origin"] = [-1.5, 1.0, 0]  # the left tip meets the box's top-left corner
    with pytest.raises(SceneError, match=r"contact normal undefined: vertex of link 0 \('left'\)"):
        scene_from_geometry(spec)


def test_document_must_be_a_table():
    with pytest.raises(SceneError, match=r"scene: expected an object/table"):
        scene_from_geometry([1, 2])
