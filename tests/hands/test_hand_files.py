"""Hand descriptions and hand files (issue 15): the bundled hands, the paper's form both ways, bad input named."""

import copy
import re
import tomllib

import numpy as np
import pytest

from qsplan.hands.description import (
    HandDescription,
    bundled_hands,
    describe_two_finger_hand,
    hand_from_table,
    joint_frames,
    load_hand,
    make_hand_description,
    two_finger_parameters,
)
from qsplan.hands.paper_hand.two_finger import default_hand, make_two_finger_hand
from qsplan.hands.paper_hand.scene import hand_manipulator
from qsplan.mechanics import SceneError
from qsplan.mechanics.model.manipulator import link_polygons, link_poses

PARAMETERS = ("finger_base", "finger_length", "finger_width", "finger_mass", "palm_halfwidth", "palm_thickness", "gravity")


def _table(name="two_link_hand") -> dict:
    return tomllib.loads(bundled_hands()[name].read_text())


def _same_manipulator(a, b):
    assert a.n_joints == b.n_joints
    for ja, jb in zip(a.joints, b.joints):
        assert (ja.name, ja.kind, ja.parent, ja.link_mass, ja.link_shape) == (jb.name, jb.kind, jb.parent, jb.link_mass, jb.link_shape)
        np.testing.assert_array_equal(ja.origin, jb.origin)
        np.testing.assert_array_equal(ja.link_com, jb.link_com)
    assert a.base_shape == b.base_shape
    assert a.gravity == b.gravity


# --- the bundled hands -------------------------------------------------------------------------------------------


def test_the_bundled_hands_load():
    assert set(bundled_hands()) == {"paper_hand", "two_link_hand", "parallel_jaw", "turning_hand"}
    for name in bundled_hands():
        desc = load_hand(name)
        assert isinstance(desc, HandDescription)
        assert desc.source == f"bundled:{name}"
        assert [f.name for f in desc.fingers] == ["left", "right"]
        assert desc.palm_top == (-0.16, 0.16)
        np.testing.assert_array_equal(desc.palm, [[-0.16, -0.02], [0.16, -0.02], [0.16, 0.0], [-0.16, 0.0]])
        assert desc.manipulator.gravity == 9.81
        assert all(j.link_mass == 0.0 for j in desc.manipulator.joints)
        assert not desc.joint_limits.flags.writeable and not desc.joint_speeds.flags.writeable
        assert not desc.palm.flags.writeable


def test_two_link_hand_structure():
    desc = load_hand("two_link_hand")
    assert desc.joint_names == ("left_proximal", "left_distal", "right_proximal", "right_distal")
    assert desc.joint_kinds == ("revolute",) * 4
    assert [f.joints for f in desc.fingers] == [(0, 1), (2, 3)]
    assert desc.finger_of_joint == ("left", "left", "right", "right")
    assert [j.parent for j in desc.manipulator.joints] == [-1, 0, -1, 2]
    np.testing.assert_array_equal(desc.joint_limits, [[0.05, 3.09], [-2.6, 2.6], [0.05, 3.09], [-2.6, 2.6]])
    np.testing.assert_array_equal(desc.joint_speeds, [0.5] * 4)
    # straight up: the distal joint 70 mm above the proximal one, the tip 140 mm
    poses = link_poses(desc.manipulator, [np.pi / 2, 0.0, np.pi / 2, 0.0])
    np.testing.assert_allclose(poses[:, :2], [[-0.09, 0.0], [-0.09, 0.07], [0.09, 0.0], [0.09, 0.07]], atol=1e-15)
    assert two_finger_parameters(desc) is None


def test_parallel_jaw_structure():
    desc = load_hand("parallel_jaw")
    assert desc.joint_names == ("left_jaw", "right_jaw")
    assert desc.joint_kinds == ("prismatic", "prismatic") and desc.joint_units == ("m", "m")
    np.testing.assert_array_equal(desc.joint_limits, [[0.0, 0.1], [0.0, 0.1]])
    np.testing.assert_array_equal(desc.joint_speeds, [0.05, 0.05])
    lean = np.radians(15.0)
    for q in (0.0, 0.05, 0.1):
        left, right = link_polygons(desc.manipulator, [q, q])
        # vertical plates, mirror images, moved by q along axes leaning 15 degrees down toward the palm
        assert left.bounds == pytest.approx((-0.112 + q * np.cos(lean), 0.03 - q * np.sin(lean),
                                             -0.1 + q * np.cos(lean), 0.12 - q * np.sin(lean)), abs=1e-9)
        assert right.bounds == pytest.approx((0.1 - q * np.cos(lean), 0.03 - q * np.sin(lean),
                                              0.112 - q * np.cos(lean), 0.12 - q * np.sin(lean)), abs=1e-9)
        assert left.area == pytest.approx(0.012 * 0.09, rel=1e-6)
    assert left.bounds[1] > 0.0  # fully closed, the feet stay clear of the palm
    assert two_finger_parameters(desc) is None
    # the prismatic joint frame stays on the palm while the link slides
    np.testing.assert_allclose(joint_frames(desc, [0.04, 0.02])[:, :2], [[-0.1, 0.03], [0.1, 0.03]], atol=1e-15)


def test_paper_file_gives_default_hands_parameters_exactly():
    params = two_finger_parameters(load_hand("paper_hand"))
    hand = default_hand()
    assert params == {name: getattr(hand, name) for name in PARAMETERS}


def test_paper_file_is_hand_manipulator_of_the_default_hand():
    desc = load_hand("paper_hand")
    _same_manipulator(desc.manipulator, hand_manipulator(default_hand()))
    np.testing.assert_array_equal(desc.joint_limits, [[0.05, 3.09], [0.05, 3.09]])


# --- the paper's form both ways ---------------------------------------------------------------------------------


@pytest.mark.parametrize("overrides", [{}, {"finger_mass": 0.05, "finger_length": 0.12, "finger_width": 0.02},
                                       {"finger_base": 0.07, "palm_halfwidth": 0.2, "palm_thickness": 0.01, "gravity": 0.0}])
def test_describe_two_finger_hand_equals_hand_manipulator(overrides):
    hand = default_hand(**overrides)
    desc = describe_two_finger_hand(hand, [[0.05, 3.09], [0.1, 3.0]], 0.5)
    _same_manipulator(desc.manipulator, hand_manipulator(hand))
    assert desc.joint_names == ("left", "right")
    np.testing.assert_array_equal(desc.joint_limits, [[0.05, 3.09], [0.1, 3.0]])
    np.testing.assert_array_equal(desc.joint_speeds, [0.5, 0.5])
    rng = np.random.default_rng(15)
    for q in rng.uniform(0.05, 3.09, size=(5, 2)):
        for a, b in zip(link_polygons(desc.manipulator, q), link_polygons(hand_manipulator(hand), q)):
            assert a.equals_exact(b, 0.0)
    # the round trip: the description's parameters rebuild the same hand
    params = two_finger_parameters(desc)
    assert params == {name: getattr(hand, name) for name in PARAMETERS}
    again = make_two_finger_hand(hand.workpiece, hand.workpiece_mass, mu=hand.mu, **params)
    for name in PARAMETERS:
        assert getattr(again, name) == getattr(hand, name)


def test_bundled_hands_link_polygons_equal_hand_manipulators_at_random_q():
    desc = load_hand("paper_hand")
    man = hand_manipulator(default_hand())
    for q in np.random.default_rng(7).uniform(0.05, 3.09, size=(10, 2)):
        for a, b in zip(link_polygons(desc.manipulator, q), link_polygons(man, q)):
            assert a.equals_exact(b, 0.0)


def test_describe_two_finger_hand_checks_limits_and_speed():
    hand = default_hand()
    desc = describe_two_finger_hand(hand, [0.1, 3.0], [0.4, 0.6])
    np.testing.assert_array_equal(desc.joint_limits, [[0.1, 3.0], [0.1, 3.0]])
    np.testing.assert_array_equal(desc.joint_speeds, [0.4, 0.6])
    with pytest.raises(SceneError, match=r"^joint_limits\[1\]: expected \[lo, hi\] with lo < hi \(rad\); got \[2, 1\]"):
        describe_two_finger_hand(hand, [[0.1, 3.0], [2.0, 1.0]], 0.5)
    with pytest.raises(SceneError, match=r"^joint_speed: expected a positive speed"):
        describe_two_finger_hand(hand, [0.1, 3.0], 0.0)
    with pytest.raises(SceneError, match=r"^joint_limits: expected"):
        describe_two_finger_hand(hand, [0.1, 1.0, 3.0], 0.5)


def _form_variant(edit):
    doc = _table("paper_hand")
    edit(doc)
    return two_finger_parameters(hand_from_table(doc, field=""))


@pytest.mark.parametrize("edit", [
    lambda d: d["fingers"][1]["joints"][0].update(origin=[0.08, 0.0, 0.0]),   # not symmetric
    lambda d: d["fingers"][0]["joints"][0].update(origin=[-0.09, 0.01, 0.0]),  # joint above the palm
    lambda d: d["fingers"][0]["joints"][0].update(type="prismatic", limits=[0.0, 0.1], speed=0.05),
    lambda d: d["fingers"][0]["joints"][0]["link"].update(polygon=[[0.0, -0.006], [0.15, -0.006], [0.15, 0.006], [0.0, 0.006]]),
    lambda d: d["fingers"][0]["joints"][0]["link"].update(polygon=[[0.0, -0.005], [0.16, -0.006], [0.16, 0.006], [0.0, 0.006]]),
    lambda d: d["fingers"][0]["joints"][0]["link"].update(mass=0.1),
    lambda d: d["fingers"][0]["joints"][0]["link"].update(com=[0.07, 0.0]),
    lambda d: d["palm"].update(polygon=[[-0.16, -0.02], [0.15, -0.02], [0.15, 0.0], [-0.16, 0.0]]),
    lambda d: d["palm"].update(polygon=[[-0.16, -0.02], [0.0, -0.03], [0.16, -0.02], [0.16, 0.0], [-0.16, 0.0]]),
    lambda d: d["fingers"][0]["joints"].append(copy.deepcopy(d["fingers"][0]["joints"][0]) | {"name": "tip"}),
])  # fmt: skip
def test_two_finger_parameters_is_none_off_the_papers_form(edit):
    assert _form_variant(edit) is None


def test_two_finger_parameters_takes_a_rectangle_in_any_vertex_order():
    def edit(d):
        for f in d["fingers"]:
            f["joints"][0]["link"]["polygon"] = [[0.16, 0.006], [0.0, 0.006], [0.0, -0.006], [0.16, -0.006]]
        d["palm"]["polygon"] = [[0.16, 0.0], [-0.16, 0.0], [-0.16, -0.02], [0.16, -0.02]]

    assert _form_variant(edit) == {name: getattr(default_hand(), name) for name in PARAMETERS}


# --- the Python API ---------------------------------------------------------------------------------------------


def test_make_hand_description_takes_arrays_and_defaults():
    link = {"polygon": np.array([[0.0, 0.0], [0.1, 0.0], [0.0, 0.03]])}
    fingers = [{"name": n, "joints": [{"name": n, "type": "revolute", "origin": np.array([x, 0.0, 0.0]),
                                       "limits": np.array([0.0, 3.0]), "speed": 1.0, "link": link}]}
               for n, x in (("left", -0.05), ("right", 0.05))]  # fmt: skip
    palm = np.array([[-0.1, -0.01], [0.1, -0.01], [0.1, -1e-13], [-0.1, 0.0]])
    desc = make_hand_description("mine", palm, fingers)
    assert desc.source == "inline" and desc.manipulator.gravity == 9.81
    assert desc.palm[2, 1] == 0.0  # snapped onto y = 0
    np.testing.assert_allclose(desc.manipulator.joints[0].link_com, [0.1 / 3, 0.01])  # the centroid
    assert desc.manipulator.joints[0].link_mass == 0.0


def test_hand_from_table_ignores_extra_keys_and_reads_a_file(tmp_path):
    doc = _table() | {"workpiece": [[0, 0], [1, 0], [0, 1]], "mu": 0.2}
    desc = hand_from_table(doc, extra_keys=frozenset({"workpiece", "workpiece_mass", "palm_edge", "mu", "file"}))
    assert desc.name == "two-link hand" and desc.source == "inline"
    with pytest.raises(SceneError, match=r"^hand\.mu: unknown field"):
        hand_from_table(doc, extra_keys=frozenset({"workpiece"}))
    (tmp_path / "h.toml").write_text(bundled_hands()["parallel_jaw"].read_text())
    desc = hand_from_table({"file": "h.toml", "mu": 0.3}, extra_keys={"mu"}, base_dir=tmp_path)
    assert desc.joint_names == ("left_jaw", "right_jaw") and desc.source == str(tmp_path / "h.toml")
    assert hand_from_table({"file": "paper_hand"}).source == "bundled:paper_hand"
    with pytest.raises(SceneError, match=r"^hand\.file: give either a hand file or the hand's fields"):
        hand_from_table({"file": "paper_hand", "palm": {}})
    with pytest.raises(SceneError, match=r"^hand\.file: .*nope\.toml: no such hand file"):
        hand_from_table({"file": "nope.toml"}, base_dir=tmp_path)


def test_load_hand_resolves_relative_paths_against_base_dir(tmp_path, monkeypatch):
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "my_hand.toml").write_text(bundled_hands()["two_link_hand"].read_text().replace(
        'name = "two-link hand"\n', ""))
    desc = load_hand("my_hand.toml", base_dir=tmp_path / "sub")
    assert desc.name == "my_hand"  # the stem when the file names none
    monkeypatch.chdir(tmp_path)
    assert load_hand("sub/my_hand.toml").source == "sub/my_hand.toml"


# --- bad input, each named by its field path ----------------------------------------------------------------------


def _joint(d, finger, joint):
    return d["fingers"][finger]["joints"][joint]


BAD = [
    ("missing palm", lambda d: d.pop("palm"), r"hand\.palm: missing"),
    ("missing fingers", lambda d: d.pop("fingers"), r"hand\.fingers: missing"),
    ("wrong finger name", lambda d: d["fingers"][0].update(name="thumb"),
     r"hand\.fingers\[0\]\.name: expected 'left' \(fingers are 'left' then 'right'\); got 'thumb'"),
    ("fingers swapped", lambda d: d["fingers"].reverse(), r"hand\.fingers\[0\]\.name: expected 'left'.*got 'right'"),
    ("finger without a name", lambda d: d["fingers"][1].pop("name"), r"hand\.fingers\[1\]\.name: missing"),
    ("three fingers", lambda d: d["fingers"].append(copy.deepcopy(d["fingers"][1])),
     r"hand\.fingers: expected two fingers, 'left' then 'right'; got 3"),
    ("one finger", lambda d: d["fingers"].pop(), r"hand\.fingers: expected two fingers.*got 1"),
    ("finger not a table", lambda d: d["fingers"].__setitem__(0, 1), r"hand\.fingers\[0\]: expected a table"),
    ("no joints", lambda d: d["fingers"][0].update(joints=[]), r"hand\.fingers\[0\]\.joints: expected a non-empty list"),
    ("unknown top key", lambda d: d.update(colour="red"), r"hand\.colour: unknown field; expected some of"),
    ("unknown finger key", lambda d: d["fingers"][1].update(thumb=True), r"hand\.fingers\[1\]\.thumb: unknown field"),
    ("unknown joint key", lambda d: _joint(d, 0, 1).update(limit=[0, 1]), r"hand\.fingers\[0\]\.joints\[1\]\.limit: unknown field"),
    ("parent key refused", lambda d: _joint(d, 0, 1).update(parent=-1), r"hand\.fingers\[0\]\.joints\[1\]\.parent: unknown field"),
    ("unknown link key", lambda d: _joint(d, 1, 1)["link"].update(colour="red"),
     r"hand\.fingers\[1\]\.joints\[1\]\.link\.colour: unknown field"),
    ("unknown palm key", lambda d: d["palm"].update(thickness=0.02), r"hand\.palm\.thickness: unknown field"),
    ("bad type", lambda d: _joint(d, 1, 0).update(type="ball"),
     r"hand\.fingers\[1\]\.joints\[0\]\.type: expected 'revolute' or 'prismatic'; got 'ball'"),
    ("missing type", lambda d: _joint(d, 1, 0).pop("type"), r"hand\.fingers\[1\]\.joints\[0\]\.type: missing"),
    ("lo > hi", lambda d: _joint(d, 0, 1).update(limits=[2, 1]),
     r"hand\.fingers\[0\]\.joints\[1\]\.limits: expected \[lo, hi\] with lo < hi \(rad\); got \[2, 1\]$"),
    ("lo == hi", lambda d: _joint(d, 0, 1).update(limits=[1.0, 1.0]), r"hand\.fingers\[0\]\.joints\[1\]\.limits: expected \[lo, hi\] with lo < hi"),
    ("three limits", lambda d: _joint(d, 0, 0).update(limits=[0, 1, 2]), r"hand\.fingers\[0\]\.joints\[0\]\.limits: expected 2 numbers; got 3"),
    ("infinite limit", lambda d: _joint(d, 0, 0).update(limits=[0, float("inf")]),
     r"hand\.fingers\[0\]\.joints\[0\]\.limits\[1\]: expected a finite number"),
    ("negative speed", lambda d: _joint(d, 1, 1).update(speed=-0.5),
     r"hand\.fingers\[1\]\.joints\[1\]\.speed: expected 0\.001 to 10 rad/s \(.*HAND_RANGES\['revolute_speed'\]\); got -0\.5$"),
    ("zero speed", lambda d: _joint(d, 1, 1).update(speed=0), r"hand\.fingers\[1\]\.joints\[1\]\.speed: expected 0\.001 to 10 rad/s"),
    ("speed not a number", lambda d: _joint(d, 0, 0).update(speed="fast"), r"hand\.fingers\[0\]\.joints\[0\]\.speed: expected a number"),
    ("missing speed", lambda d: _joint(d, 0, 0).pop("speed"), r"hand\.fingers\[0\]\.joints\[0\]\.speed: missing"),
    ("short origin", lambda d: _joint(d, 0, 0).update(origin=[0.0, 0.0]), r"hand\.fingers\[0\]\.joints\[0\]\.origin: expected 3 numbers; got 2"),
    ("nan origin", lambda d: _joint(d, 0, 0).update(origin=[0.0, float("nan"), 0.0]),
     r"hand\.fingers\[0\]\.joints\[0\]\.origin\[1\]: expected a finite number"),
    ("palm top above y = 0", lambda d: d["palm"].update(polygon=[[-0.16, -0.01], [0.16, -0.01], [0.16, 0.01], [-0.16, 0.01]]),
     r"hand\.palm\.polygon: expected the top edge on y = 0 \(the workpiece rests there\); got max y = 0\.01 m"),
    ("palm top below y = 0", lambda d: d["palm"].update(polygon=[[-0.16, -0.03], [0.16, -0.03], [0.16, -0.01], [-0.16, -0.01]]),
     r"hand\.palm\.polygon: expected the top edge on y = 0"),
    ("palm top a vertex", lambda d: d["palm"].update(polygon=[[-0.16, -0.02], [0.16, -0.02], [0.0, 0.0]]),
     r"hand\.palm\.polygon: expected a horizontal top edge on y = 0; only the vertex \[0\.0, 0\.0\] reaches it"),
    ("palm top tilted", lambda d: d["palm"].update(polygon=[[-0.16, -0.02], [0.16, -0.02], [0.16, 0.0], [-0.16, -0.001]]),
     r"hand\.palm\.polygon: expected a horizontal top edge"),
    ("palm top in two pieces", lambda d: d["palm"].update(
        polygon=[[-0.16, -0.02], [0.16, -0.02], [0.16, 0.0], [0.05, 0.0], [0.0, -0.01], [-0.05, 0.0], [-0.16, 0.0]]),
     r"hand\.palm\.polygon: expected one horizontal top edge on y = 0; got 2 separate pieces"),
    ("palm not a polygon", lambda d: d["palm"].update(polygon=[[0, 0], [1, 0]]), r"hand\.palm\.polygon: expected at least 3 vertices"),
    ("palm without polygon", lambda d: d["palm"].pop("polygon"), r"hand\.palm\.polygon: missing"),
    ("link two vertices", lambda d: _joint(d, 0, 0)["link"].update(polygon=[[0, 0], [0.07, 0]]),
     r"hand\.fingers\[0\]\.joints\[0\]\.link\.polygon: expected at least 3 vertices"),
    ("link collinear", lambda d: _joint(d, 0, 0)["link"].update(polygon=[[0, 0], [0.03, 0], [0.07, 0]]),
     r"hand\.fingers\[0\]\.joints\[0\]\.link\.polygon: expected a polygon with positive area"),
    ("link self-crossing", lambda d: _joint(d, 0, 0)["link"].update(polygon=[[0, 0], [0.07, 0.01], [0.07, 0], [0, 0.01]]),
     r"hand\.fingers\[0\]\.joints\[0\]\.link\.polygon: expected a simple polygon"),
    ("link polygon a string", lambda d: _joint(d, 0, 0)["link"].update(polygon="square"),
     r"hand\.fingers\[0\]\.joints\[0\]\.link\.polygon: expected a polygon"),
    ("link vertex of 3 numbers", lambda d: _joint(d, 0, 0)["link"].update(polygon=[[0, 0, 0], [1, 0], [0, 1]]),
     r"hand\.fingers\[0\]\.joints\[0\]\.link\.polygon\[0\]: expected 2 numbers; got 3"),
    ("missing link", lambda d: _joint(d, 1, 1).pop("link"), r"hand\.fingers\[1\]\.joints\[1\]\.link: missing"),
    ("link not a table", lambda d: _joint(d, 1, 1).update(link=[1]), r"hand\.fingers\[1\]\.joints\[1\]\.link: expected a table"),
    ("negative mass", lambda d: _joint(d, 0, 1)["link"].update(mass=-1.0),
     r"hand\.fingers\[0\]\.joints\[1\]\.link\.mass: expected 0 to 100 kg \(.*HAND_RANGES\['link_mass'\]\); got -1$"),
    ("bad com", lambda d: _joint(d, 0, 1)["link"].update(com=[0.0]), r"hand\.fingers\[0\]\.joints\[1\]\.link\.com: expected 2 numbers"),
    ("duplicate joint names", lambda d: _joint(d, 1, 0).update(name="left_proximal"),
     r"hand\.fingers\[1\]\.joints\[0\]\.name: expected a unique name; 'left_proximal' is also hand\.fingers\[0\]\.joints\[0\]\.name"),
    ("joint named palm", lambda d: _joint(d, 0, 1).update(name="palm"), r"hand\.fingers\[0\]\.joints\[1\]\.name: 'palm' is reserved"),
    ("empty joint name", lambda d: _joint(d, 0, 1).update(name=" "), r"hand\.fingers\[0\]\.joints\[1\]\.name: expected a non-empty string"),
    ("negative gravity", lambda d: d.update(gravity=-9.81), r"hand\.gravity: expected 0 to 100 m/s\^2 .*; got -9\.81$"),
    ("name not a string", lambda d: d.update(name=3), r"hand\.name: expected a non-empty string; got 3"),
]  # fmt: skip


@pytest.mark.parametrize("edit,expected", [case[1:] for case in BAD], ids=[case[0] for case in BAD])
def test_bad_tables_name_the_field(edit, expected):
    doc = _table()
    edit(doc)
    with pytest.raises(SceneError, match="^" + expected) as info:
        hand_from_table(doc)
    assert "\n" not in str(info.value)


def test_prismatic_limits_are_in_metres():
    doc = _table("parallel_jaw")
    _joint(doc, 1, 0)["limits"] = [0.0, -0.085]
    with pytest.raises(SceneError, match=r"^hand\.fingers\[1\]\.joints\[0\]\.limits: expected \[lo, hi\] with lo < hi \(m\)"):
        hand_from_table(doc)
    _joint(doc, 1, 0)["limits"], _joint(doc, 0, 0)["speed"] = [-0.085, 0.0], -1
    with pytest.raises(SceneError, match=r"^hand\.fingers\[0\]\.joints\[0\]\.speed: expected 0\.0001 to 0\.5 m/s"):
        hand_from_table(doc)


def test_a_file_names_itself_and_the_field_at_its_top_level(tmp_path):
    text = bundled_hands()["two_link_hand"].read_text()
    path = tmp_path / "my_hand.toml"
    path.write_text(text.replace('type = "revolute"\norigin = [0.09', 'type = "ball"\norigin = [0.09'))
    with pytest.raises(SceneError, match=re.escape(f"{path}: fingers[1].joints[0].type: expected 'revolute' or "
                                                   "'prismatic'; got 'ball'")):  # fmt: skip
        load_hand(path)
    path.write_text(text + "\ncolour = 'red'\n")
    with pytest.raises(SceneError, match=re.escape(f"{path}: fingers[1].joints[1].link.colour: unknown field")):
        load_hand(path)
    path.write_text(text.replace("[palm]", "[hand]"))
    with pytest.raises(SceneError, match=re.escape(f"{path}: hand: unknown field")):
        load_hand(path)
    path.write_text("\n".join(line for line in text.splitlines() if not line.startswith(("[palm]", "polygon = [[-0.16"))))
    with pytest.raises(SceneError, match=re.escape(f"{path}: palm: missing")):
        load_hand(path)


def test_toml_syntax_error_and_missing_files_are_one_line(tmp_path):
    path = tmp_path / "broken.toml"
    path.write_text('name = "broken"\n[palm\npolygon = 1\n')
    with pytest.raises(SceneError, match=re.escape(f"{path}: invalid TOML: ")) as info:
        load_hand(path)
    assert "\n" not in str(info.value)
    with pytest.raises(SceneError, match=re.escape(f"{tmp_path / 'nope.toml'}: no such hand file; expected a path to a "
                                                   ".toml file or a bundled hand (paper_hand, parallel_jaw, "
                                                   "turning_hand, two_link_hand)")):  # fmt: skip
        load_hand("nope.toml", base_dir=tmp_path)
    with pytest.raises(SceneError, match=r"^no_such_hand: no such hand file"):
        load_hand("no_such_hand")
    (tmp_path / "hand.json").write_text("{}")
    with pytest.raises(SceneError, match=r"hand\.json: expected a hand file ending in \.toml; got \.json"):
        load_hand(tmp_path / "hand.json")
    with pytest.raises(SceneError, match=r"^hand: expected a bundled hand"):
        load_hand(3)
    (tmp_path / "utf16.toml").write_bytes("name = 'x'".encode("utf-16"))
    with pytest.raises(SceneError, match=r"utf16\.toml: hand file is UTF-16 encoded"):
        load_hand(tmp_path / "utf16.toml")
