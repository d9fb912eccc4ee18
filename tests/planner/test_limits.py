"""Limits come from one place (issue 21, item 3): the hand's own, narrowed by the task's, for planner and certifier."""

import re

import numpy as np
import pytest

from qsplan.hands.description.files import bundled_hands
from qsplan.mechanics import QsplanError
from qsplan.planner import load_task, ompl_available, task_paths
from qsplan.planner.certify.certify import certify_plan
from qsplan.planner.task.limits import PAPER_DEFAULTS, resolve_limits

NAMES, KINDS = ("a", "b", "c"), ("revolute", "revolute", "prismatic")
HAND_RANGES = [[0.0, 3.0], [-1.0, 1.0], [0.0, 0.05]]
HAND_SPEEDS = [0.5, 0.4, 0.02]


def test_task_narrows_the_hand():
    lim = resolve_limits(NAMES, KINDS, HAND_RANGES, HAND_SPEEDS, ranges={"a": [0.5, 2.0]}, joint_speed=0.3,
                         speeds={"c": 0.01})  # fmt: skip
    assert lim.ranges.tolist() == [[0.5, 2.0], [-1.0, 1.0], [0.0, 0.05]]
    assert lim.speeds.tolist() == [0.3, 0.3, 0.01]  # joint_speed: every revolute joint; the prismatic by name
    assert lim.sources == ("task", "task", "task")
    own = resolve_limits(NAMES, KINDS, HAND_RANGES, HAND_SPEEDS)
    assert own.ranges.tolist() == HAND_RANGES and own.speeds.tolist() == HAND_SPEEDS and own.sources == ("hand",) * 3
    assert not own.speeds.flags.writeable and not own.ranges.flags.writeable


def test_paper_parameter_form_has_only_defaults():
    lim = resolve_limits(("left", "right"), ("revolute",) * 2)
    assert lim.ranges.tolist() == [list(PAPER_DEFAULTS["range"])] * 2 and lim.speeds.tolist() == [0.5, 0.5]
    wide = resolve_limits(("left", "right"), ("revolute",) * 2, ranges=[[0.01, 3.13], [0.01, 3.13]], joint_speed=2.0)
    assert wide.ranges.tolist() == [[0.01, 3.13]] * 2 and wide.speeds.tolist() == [2.0, 2.0]


@pytest.mark.parametrize("kw, match", [
    ({"ranges": {"a": [0.0, 3.1]}}, r"limits\.a: \[0, 3\.1\] rad reaches beyond the range \[0, 3\] rad of the hand; a "
                                   r"task may narrow"),
    ({"ranges": {"c": [-0.01, 0.02]}}, r"limits\.c: \[-0\.01, 0\.02\] m reaches beyond"),
    ({"ranges": {"a": [2.0, 1.0]}}, r"limits\.a: expected lo < hi"),
    ({"ranges": {"z": [0.0, 1.0]}}, r"limits\.z: unknown field; expected some of a, (\w+, )*b, c, (\w+, )*joint_speed, (\w+, )*speed"),
    ({"ranges": [[0, 1]]}, r"limits: expected the ranges of the joints a, b, c"),
    ({"joint_speed": 0.45}, r"limits\.joint_speed: 0\.45 rad/s is faster than joint b's speed 0\.4 rad/s in the hand"),
    ({"joint_speed": -1}, r"limits\.joint_speed: expected a positive finite number"),
    ({"speeds": {"c": 0.05}}, r"limits\.speed\.c: 0\.05 m/s is faster than joint c's speed 0\.02 m/s"),
    ({"speeds": {"q": 0.05}}, r"limits\.speed\.q: unknown joint"),
    ({"speeds": 0.3}, r"limits\.speed: expected a table"),
])  # fmt: skip
def test_task_beyond_the_hand_is_refused(kw, match):
    with pytest.raises(QsplanError, match=match):
        resolve_limits(NAMES, KINDS, HAND_RANGES, HAND_SPEEDS, **kw)


def test_joint_speed_needs_a_revolute_joint():
    with pytest.raises(QsplanError, match=r"limits\.joint_speed: the hand has no revolute joint"):
        resolve_limits(("a",), ("prismatic",), [[0, 0.05]], [0.02], joint_speed=0.1)


def _task(tmp_path, limits: str, hand='file = "two_link_hand"', body=""):
    text = (open(task_paths()["two_link_task"]).read().split("[limits]")[0] if not body else body) + limits
    text = text.replace('file = "two_link_hand"', hand)
    path = tmp_path / "t.toml"
    path.write_text(text)
    return load_task(path)


def test_chain_task_speed_is_kept(tmp_path):
    task = _task(tmp_path, "[limits]\njoint_speed = 0.002\nworkpiece_speed = 0.01\n")
    assert task.joint_speeds.tolist() == [0.002] * 4  # no longer validated, then replaced by the hand's
    task = _task(tmp_path, "[limits]\nleft_distal = [-1.0, 1.0]\n[limits.speed]\nright_proximal = 0.1\n")
    assert task.joint_limits[1].tolist() == [-1.0, 1.0] and task.joint_speeds.tolist() == [0.5, 0.5, 0.1, 0.5]


def test_chain_task_faster_than_its_hand_is_refused(tmp_path):
    with pytest.raises(QsplanError, match=r"limits\.joint_speed: 0\.8 rad/s is faster than joint left_proximal's "
                                          r"speed 0\.5 rad/s"):  # fmt: skip
        _task(tmp_path, "[limits]\njoint_speed = 0.8\n")


def test_paper_form_hand_file_speeds_are_kept(tmp_path):
    """A paper-form hand file's per-joint speeds are the task's default, and bound it (they were replaced)."""
    text = bundled_hands()["paper_hand"].read_text()
    slow = re.sub(r"speed = 0\.5", "speed = 0.3", text, count=1)  # the left finger's
    (tmp_path / "slow_hand.toml").write_text(slow)
    demo = open(task_paths()["demo_task"]).read().split("[limits]")[0]
    demo = demo.replace('file = "paper_hand"', 'file = "slow_hand.toml"')
    task = _task(tmp_path, "", body=demo)
    assert task.joint_speeds.tolist() == [0.3, 0.5] and task.joint_speed == 0.3
    with pytest.raises(QsplanError, match=r"limits\.joint_speed: 0\.5 rad/s is faster than joint left's speed 0\.3"):
        _task(tmp_path, "[limits]\njoint_speed = 0.5\n", body=demo)


@pytest.mark.ompl
def test_certifier_holds_a_chain_plan_to_the_task_speed(tmp_path):
    """A plan made under the hand's 0.5 rad/s is refused under a task limit of 0.002 rad/s (it was certified)."""
    if not ompl_available():
        pytest.skip("OMPL bindings not installed")
    from qsplan.planner.pipeline.run import run_plan

    fast = load_task(task_paths()["parallel_jaw_task"])
    run = run_plan(fast, tmp_path / "out", verify=0, plots=False)
    assert run.certificate.ok
    text = open(task_paths()["parallel_jaw_task"]).read().replace("[limits]", "[limits.speed]\nleft_jaw = 1e-5\n[limits]")
    (tmp_path / "slow.toml").write_text(text)
    slow = load_task(tmp_path / "slow.toml")
    assert slow.joint_speeds[0] == 1e-5
    cert = certify_plan(tmp_path / "out", slow, n_random=0)
    speed = [v for v in cert.violations if v.kind == "speed"]
    assert not cert.ok and speed and "limit 1e-05 m/s" in speed[0].message
    assert any(v.kind == "metadata" and "limits" in v.message for v in cert.violations)  # the file states 0.5
    assert np.all(np.isfinite(slow.joint_speeds))
