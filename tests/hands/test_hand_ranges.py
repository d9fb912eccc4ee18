"""Plausible ranges of every number of a hand file (issue 21, item 7): each branch refused in one line, named.

A value outside ``HAND_RANGES`` is a unit slip or a typo, not a hand; the error names the file and the
field path, the range expected and the value received, and says "looks like millimetres" (degrees, ...)
where the value does.
"""

import copy
import re
import tomllib

import numpy as np
import pytest

from qsplan.hands.description import bundled_hands, describe_two_finger_hand, hand_from_table, load_hand
from qsplan.hands.description.model import HAND_RANGES
from qsplan.hands.paper_hand.two_finger import default_hand
from qsplan.mechanics import QsplanError, SceneError
from qsplan.mechanics.model.fields import UNIT_SLIPS, in_range
from qsplan.planner.task.fields import TASK_RANGES


def _table(name="two_link_hand") -> dict:
    return tomllib.loads(bundled_hands()[name].read_text())


def _joint(d, finger, joint):
    return d["fingers"][finger]["joints"][joint]


def _link(d, finger, joint):
    return d["fingers"][finger]["joints"][joint]["link"]


def _rect(x0, x1, y0, y1):
    return [[x0, y0], [x1, y0], [x1, y1], [x0, y1]]


MM = ": looks like millimetres; expected metres$"
DEG = ": looks like degrees; expected radians$"
J00, J01 = r"hand\.fingers\[0\]\.joints\[0\]", r"hand\.fingers\[0\]\.joints\[1\]"

#: (id, edit of the two-link hand's table, the error expected).  One per range branch, and its unit slip.
OUT_OF_RANGE = [
    ("palm 1800 km", lambda d: d["palm"].update(polygon=_rect(-1.8e6, 1.8e6, -0.02, 0.0)),
     r"hand\.palm\.polygon\[0\]: expected -1 to 1 m \(.*HAND_RANGES\['palm_vertex'\]\); got \[-1\.8e\+06, -0\.02\]$"),
    ("palm in mm", lambda d: d["palm"].update(polygon=_rect(-160, 160, -20, 0)),
     r"hand\.palm\.polygon\[0\]: expected -1 to 1 m .*; got \[-160, -20\]" + MM),
    ("palm too narrow", lambda d: d["palm"].update(polygon=_rect(-5e-4, 5e-4, -0.02, 0.0)),
     r"hand\.palm\.polygon \(its width\): expected 0\.002 to 2 m \(.*HAND_RANGES\['palm_width'\]\); got 0\.001$"),
    ("palm too thin", lambda d: d["palm"].update(polygon=_rect(-0.16, 0.16, -1e-4, 0.0)),
     r"hand\.palm\.polygon \(its thickness below y = 0\): expected 0\.001 to 1 m .*palm_thickness.*; got 0\.0001$"),
    ("palm of 65 vertices", lambda d: d["palm"].update(
        polygon=[[0.16 * np.cos(t), -0.02 - 0.01 * np.sin(t)] for t in np.linspace(0, np.pi, 63)] + [[0.0, 0.0]] * 2),
     r"hand\.palm\.polygon \(its number of vertices\): expected 3 to 64 vertices .*polygon_vertices.*; got 65$"),
    ("first joint 5 m along", lambda d: _joint(d, 0, 0).update(origin=[5.0e3, 0.0, 0.0]),
     J00 + r"\.origin\[0\]: expected -1 to 1 m \(.*HAND_RANGES\['joint_offset'\]\); got 5000$"),
    ("first joint in mm", lambda d: _joint(d, 0, 0).update(origin=[-90, 0, 0]), J00 + r"\.origin\[0\]: .*; got -90" + MM),
    ("joint 5 m from its parent", lambda d: _joint(d, 0, 1).update(origin=[0.07, 5.0e3, 0.0]),
     J01 + r"\.origin\[1\]: expected -1 to 1 m .*joint_offset.*; got 5000$"),
    ("joint below the palm", lambda d: _joint(d, 0, 0).update(origin=[-0.09, -0.5, 0.0]),
     J00 + r"\.origin\[1\]: expected -0\.02 to 0\.98 m \(.*HAND_RANGES\['palm_joint_height'\] above the palm's bottom "
     r"y = -0\.02 m\); got -0\.5$"),
    ("joint high above the palm", lambda d: _joint(d, 0, 0).update(origin=[-0.09, 3e3, 0.0]),
     J00 + r"\.origin\[1\]: expected -0\.02 to 0\.98 m .*palm_joint_height.*; got 3000$"),
    ("joint above the palm in mm", lambda d: _joint(d, 0, 0).update(origin=[-0.09, 30.0, 0.0]), J00 + r"\.origin\[1\]: .*; got 30" + MM),
    ("frame angle in degrees", lambda d: _joint(d, 0, 1).update(origin=[0.07, 0.0, 90.0]),
     J01 + r"\.origin\[2\]: expected -6\.28319 to 6\.28319 rad \(.*HAND_RANGES\['origin_angle'\]\); got 90" + DEG),
    ("frame angle 1e5 rad", lambda d: _joint(d, 0, 1).update(origin=[0.07, 0.0, 1e5]), J01 + r"\.origin\[2\]: .*; got 100000$"),
    ("limits 1e5 rad", lambda d: _joint(d, 0, 1).update(limits=[-1e5, 1e5]),
     J01 + r"\.limits: expected -3\.14159 to 3\.14159 rad \(.*HAND_RANGES\['revolute_limit'\]\); got \[-100000, 100000\]$"),
    ("limits [3, 177]", lambda d: _joint(d, 0, 0).update(limits=[3, 177]), J00 + r"\.limits: .*; got \[3, 177\]" + DEG),
    ("limits [-200, 200]", lambda d: _joint(d, 0, 1).update(limits=[-200, 200]), J01 + r"\.limits: .*; got \[-200, 200\]" + DEG),
    ("speed 1e5 rad/s", lambda d: _joint(d, 0, 0).update(speed=1e5),
     J00 + r"\.speed: expected 0\.001 to 10 rad/s \(.*HAND_RANGES\['revolute_speed'\]\); got 100000$"),
    ("speed in deg/s", lambda d: _joint(d, 0, 0).update(speed=30),
     J00 + r"\.speed: .*; got 30: looks like degrees per second; expected radians per second$"),
    ("link 50 m", lambda d: _link(d, 0, 0).update(polygon=_rect(0.0, 5e4, -0.006, 0.006)),
     J00 + r"\.link\.polygon\[1\]: expected -1 to 1 m \(.*HAND_RANGES\['link_vertex'\]\); got \[50000, -0\.006\]$"),
    ("link in mm", lambda d: _link(d, 0, 0).update(polygon=_rect(0, 70, -6, 6)), J00 + r"\.link\.polygon\[0\]: .*; got \[0, -6\]" + MM),
    ("link too small", lambda d: _link(d, 0, 0).update(polygon=_rect(0.0, 5e-4, -1e-4, 1e-4)),
     J00 + r"\.link\.polygon \(the longer side of its bounding box\): expected 0\.001 to 1 m .*link_size.*; got 0\.0005$"),
    ("link too long", lambda d: _link(d, 0, 0).update(polygon=_rect(-0.9, 0.9, -0.006, 0.006)),
     J00 + r"\.link\.polygon \(the longer side .*\): expected 0\.001 to 1 m .*; got 1\.8$"),
    ("link 100 t", lambda d: _link(d, 0, 1).update(mass=1e5),
     J01 + r"\.link\.mass: expected 0 to 100 kg \(.*HAND_RANGES\['link_mass'\]\); got 100000$"),
    ("com 2 m away", lambda d: _link(d, 0, 1).update(com=[2e3, 0.0]),
     J01 + r"\.link\.com: expected -1 to 1 m \(.*HAND_RANGES\['com_offset'\]\); got \[2000, 0\]$"),
    ("com off the link", lambda d: _link(d, 0, 1).update(com=[0.5, 0.0]),
     J01 + r"\.link\.com: expected a point of the polygon's bounding box \[0, 0\.07\] x \[-0\.006, 0\.006\] m "
     r"\(a centre of mass lies in its body\); got \[0\.5, 0\.0\]$"),
    ("gravity 981", lambda d: d.update(gravity=981.0),
     r"hand\.gravity: expected 0 to 100 m/s\^2 \(.*HAND_RANGES\['gravity'\]\); got 981$"),
    ("seven joints", lambda d: d["fingers"][0]["joints"].extend(
        copy.deepcopy(_joint(d, 0, 1)) | {"name": f"extra{k}"} for k in range(5)),
     r"hand\.fingers\[0\]\.joints \(their number\): expected 1 to 6 joints .*joints_per_finger.*; got 7$"),
]  # fmt: skip


@pytest.mark.parametrize("edit,expected", [c[1:] for c in OUT_OF_RANGE], ids=[c[0] for c in OUT_OF_RANGE])
def test_out_of_range_hand_fields_are_named(edit, expected):
    doc = _table()
    edit(doc)
    with pytest.raises(SceneError, match="^" + expected) as info:
        hand_from_table(doc)
    assert "\n" not in str(info.value)


@pytest.mark.parametrize("edit,expected", [
    (lambda j: j.update(limits=[0.0, 100.0]),
     r"hand\.fingers\[1\]\.joints\[0\]\.limits: expected -1 to 1 m \(.*HAND_RANGES\['prismatic_limit'\]\); got \[0, 100\]"
     + MM),
    (lambda j: j.update(limits=[0.0, 5e3]), r"hand\.fingers\[1\]\.joints\[0\]\.limits: expected -1 to 1 m .*; got \[0, 5000\]$"),
    (lambda j: j.update(speed=50.0),
     r"hand\.fingers\[1\]\.joints\[0\]\.speed: expected 0\.0001 to 0\.5 m/s \(.*HAND_RANGES\['prismatic_speed'\]\); got 50: "
     r"looks like millimetres per second; expected metres per second$"),
    (lambda j: j.update(speed=1e4), r"hand\.fingers\[1\]\.joints\[0\]\.speed: expected 0\.0001 to 0\.5 m/s .*; got 10000$"),
])  # fmt: skip
def test_prismatic_ranges_are_in_metres(edit, expected):
    doc = _table("parallel_jaw")
    edit(_joint(doc, 1, 0))
    with pytest.raises(SceneError, match="^" + expected):
        hand_from_table(doc)


def test_a_file_names_itself_the_field_the_range_and_the_slip(tmp_path):
    path = tmp_path / "two_link.toml"
    path.write_text(bundled_hands()["two_link_hand"].read_text().replace("limits = [-2.6, 2.6]", "limits = [-150, 150]", 1))
    with pytest.raises(SceneError, match=re.escape(f"{path}: fingers[0].joints[1].limits: expected -3.14159 to 3.14159 rad "
                                                   "(qsplan.hands.description.model.HAND_RANGES['revolute_limit']); got "
                                                   "[-150, 150]: looks like degrees; expected radians") + "$"):  # fmt: skip
        load_hand(path)


def test_bundled_hands_are_inside_every_range():
    for name in bundled_hands():
        desc = load_hand(name)
        assert np.all(np.abs(desc.palm) <= HAND_RANGES["palm_vertex"][1])
        for joint, (lo, hi), speed in zip(desc.manipulator.joints, desc.joint_limits, desc.joint_speeds):
            assert HAND_RANGES[f"{joint.kind}_limit"][0] <= lo < hi <= HAND_RANGES[f"{joint.kind}_limit"][1]
            assert HAND_RANGES[f"{joint.kind}_speed"][0] <= speed <= HAND_RANGES[f"{joint.kind}_speed"][1]


def test_every_range_has_a_unit_and_agrees_with_the_tasks():
    for lo, hi, unit in HAND_RANGES.values():
        assert lo < hi and unit
    # the same quantity in the paper hand's parameter form: the same numbers
    same = {"revolute_limit": "joint_limit", "revolute_speed": "joint_speed", "prismatic_speed": "workpiece_speed",
            "link_mass": "finger_mass", "gravity": "gravity", "palm_thickness": "size", "link_size": "size",
            "prismatic_limit": "position", "palm_vertex": "position"}  # fmt: skip
    for hand_kind, task_kind in same.items():
        assert HAND_RANGES[hand_kind] == TASK_RANGES[task_kind], hand_kind
    assert HAND_RANGES["palm_width"][:2] == tuple(2 * v for v in TASK_RANGES["size"][:2])  # 2 palm_halfwidth


@pytest.mark.parametrize("overrides", [{"finger_length": 1.0, "finger_width": 0.5, "palm_halfwidth": 1.0, "finger_base": 1.0,
                                        "palm_thickness": 1.0, "finger_mass": 100.0, "gravity": 100.0},
                                       {"finger_length": 2e-3, "finger_width": 1e-3, "palm_halfwidth": 1e-3,
                                        "finger_base": 1e-3, "palm_thickness": 1e-3}])  # fmt: skip
def test_the_paper_forms_extremes_are_valid_hands(overrides):
    """Every hand a task's [hand] parameters allow (TASK_RANGES' edges) is a valid description: no contradiction."""
    desc = describe_two_finger_hand(default_hand(**overrides), [-np.pi, np.pi], [1e-3, 10.0])
    assert desc.n_joints == 2


@pytest.mark.parametrize("value,unit,lo,hi,hint", [
    (160.0, "m", -1.0, 1.0, "looks like millimetres; expected metres"),
    (5e3, "m", -1.0, 1.0, None),  # 5 m even in mm is out
    (-0.5, "m", -0.02, 0.98, None),  # too small for a slip: a sign error, not a unit
    ([3.0, 177.0], "rad", -np.pi, np.pi, "looks like degrees; expected radians"),
    ([0.0, 359.0], "rad", -np.pi, np.pi, "looks like degrees; expected radians"),  # beyond the range even in radians
    ([0.0, 361.0], "rad", -np.pi, np.pi, None),
    (30.0, "rad/s", 1e-3, 10.0, "looks like degrees per second; expected radians per second"),
    (1e3, "kg", 0.0, 100.0, None),  # no slip for masses
])  # fmt: skip
def test_in_range_names_unit_slips(value, unit, lo, hi, hint):
    with pytest.raises(QsplanError, match=r"^f: expected .* \(src\); got [^:]*" + (f": {hint}$" if hint else "$")):
        in_range(value, "f", lo, hi, unit, "src", QsplanError)
    assert in_range(0.5 * (lo + hi), "f", lo, hi, unit, "src") == 0.5 * (lo + hi)
    assert set(UNIT_SLIPS) == {"m", "rad", "m/s", "rad/s"}
