"""A task's ``[hand]``: the paper hand's parameters, a hand file (bundled or a path), or a description inline
(qsplan.planner.task.fields); bad hands are refused in one line naming the field."""

import re
import numpy as np
import pytest

from qsplan.hands.description import bundled_hands
from qsplan.hands.paper_hand.two_finger import TwoFingerHand
from qsplan.mechanics.errors import QsplanError
from qsplan.planner.cli.main import main
from qsplan.planner.task.task import load_task, make_task

WORKPIECE = "workpiece = [[0.0, 0.0], [0.080, 0.0], [0.085, 0.080], [0.008, 0.100]]\n"
REST = "[motion]\nstart_x = 0.0\n[goal]\nx = -0.02\n[controller]\ntorque_resolution = 0.02\n"


def _task(tmp_path, hand_lines, rest=REST, name="t.toml"):
    path = tmp_path / name
    path.write_text("[hand]\n" + hand_lines + rest)
    return path


def test_bundled_and_relative_hand_files(tmp_path):
    two = load_task(_task(tmp_path, 'file = "two_link_hand"\n' + WORKPIECE))
    assert two.hand.paper is None and two.hand.description.source == "bundled:two_link_hand"
    np.testing.assert_array_equal(two.joint_limits, two.hand.description.joint_limits)
    np.testing.assert_array_equal(two.joint_speeds, [0.5] * 4)
    (tmp_path / "hands").mkdir()
    (tmp_path / "hands" / "mine.toml").write_text(bundled_hands()["two_link_hand"].read_text())
    mine = load_task(_task(tmp_path, 'file = "hands/mine.toml"\n' + WORKPIECE))  # relative to the task file
    assert mine.hand.description.source == str(tmp_path / "hands" / "mine.toml")
    paper = load_task(_task(tmp_path, 'file = "paper_hand"\n' + WORKPIECE))
    assert paper.hand.accelerated and isinstance(paper.hand.paper, TwoFingerHand) and paper.hand.finger_length == 0.16
    assert paper.joint_speed == 0.5 and paper.joint_limits.tolist() == [[0.05, 3.09], [0.05, 3.09]]


def test_inline_description_and_start_joints(tmp_path):
    text = bundled_hands()["two_link_hand"].read_text().replace("[palm]", "[hand.palm]")
    text = text.replace("[[fingers]]", "[[hand.fingers]]").replace("[[fingers.joints]]", "[[hand.fingers.joints]]")
    text = text.replace("[fingers.joints.link]", "[hand.fingers.joints.link]")
    head, _, body = text.partition("[hand.palm]")
    head = "\n".join(line for line in head.splitlines() if not line.startswith(("name", "gravity")))
    path = tmp_path / "inline.toml"
    path.write_text(head + "\n[hand]\n" + WORKPIECE + "[hand.palm]" + body + REST
                    + "[start]\nleft_proximal = 1.4\nright_proximal = 1.74\n")
    task = load_task(path)
    assert task.hand.joint_names == ("left_proximal", "left_distal", "right_proximal", "right_distal")
    assert task.start_joints.tolist() == [1.4, 0.0, 1.74, 0.0]


@pytest.mark.parametrize("hand, rest, match", [
    ('file = "no_such_hand"\n' + WORKPIECE, REST, r"^hand\.file: .*no_such_hand: no such hand file; expected a path to a \.toml file or a bundled hand"),
    ('file = "two_link_hand"\npalm = 1\n' + WORKPIECE, REST, r"^hand\.file: give either a hand file or the hand's fields"),
    ('file = "two_link_hand"\n', REST, r"^hand\.workpiece: expected the workpiece polygon"),
    ('file = "two_link_hand"\nworkpiece_mass = -1\n' + WORKPIECE, REST, r"^hand\.workpiece_mass: expected a positive"),
    ('file = "two_link_hand"\n' + WORKPIECE, REST + "[start]\nleft_distal = 0.3\n",
     r"^start\.left_distal: unknown field; expected the free joints left_proximal, right_proximal"),
    ('file = "two_link_hand"\n' + WORKPIECE, REST + "[start]\nleft_proximal = 1.4\n", r"^start\.right_proximal: missing"),
])  # fmt: skip
def test_bad_hands_are_named(tmp_path, hand, rest, match):
    with pytest.raises(QsplanError, match=match):
        load_task(_task(tmp_path, hand, rest))


def test_a_bad_hand_file_is_named_with_its_field(tmp_path):
    bad = bundled_hands()["two_link_hand"].read_text().replace("limits = [-2.6, 2.6]", "limits = [2.6, -2.6]", 1)
    (tmp_path / "bad_hand.toml").write_text(bad)
    with pytest.raises(QsplanError, match=r"^hand\.file: .*bad_hand\.toml: fingers\[0\]\.joints\[1\]\.limits: "):
        load_task(_task(tmp_path, 'file = "bad_hand.toml"\n' + WORKPIECE))


def test_the_cli_refuses_a_bad_hand_in_one_line(tmp_path, capsys):
    path = _task(tmp_path, 'file = "no_such_hand"\n' + WORKPIECE)
    code = main(["plan", str(path), "--out", str(tmp_path / "out")])
    out, err = capsys.readouterr()
    assert code == 2 and len(err.strip().splitlines()) == 1 and "no_such_hand" in err and "Traceback" not in err
    assert not (tmp_path / "out" / "plan.csv").exists()


def test_limits_must_match_the_hands_joints():
    with pytest.raises(QsplanError, match=r"^limits: expected the ranges of the joints left_proximal, left_distal"):
        make_task({"file": "two_link_hand", "workpiece": [[0, 0], [0.08, 0], [0.085, 0.08], [0.008, 0.1]]}, 0.0,
                  goal={"x": -0.02}, joint_limits=((0.05, 3.09), (0.05, 3.09)))


def test_plan_takes_a_bundled_tasks_name(tmp_path, capsys):
    code = main(["plan", "parallel_jaw_task", "--out", str(tmp_path / "out"), "--quiet", "--no-plots", "--verify", "1"])
    out, err = capsys.readouterr()
    assert code == 0 and "parallel-jaw gripper: slide a hexagon left 2 cm" in out
    assert re.search(r"narrowest guaranteed band: 2\.\d+ N at", out)  # a jaw's force, in N
    assert (tmp_path / "out" / "plan.csv").exists()
