"""Adding a hand or a formation touches one place (issue 22).

* A hand: one description file (``tests/data/hands/asymmetric_hand.toml``, a left finger of two joints and a
  right finger of one, which no bundled hand has); a task names it and the whole pipeline plans, exports and
  certifies it.
* A formation: one entry of :data:`qsplan.hands.formations.registry.FORMATIONS` (here the palm-edge formation with its
  contacts in the reverse order, added for the test only); a task names it, and the scenes, band tables, plan,
  export and certificate follow its order, with the same physics as the default's.
"""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from qsplan.hands.formations.registry import FORMATIONS, Formation
from qsplan.planner.certify.certify import certify_plan
from qsplan.planner.export.plan_files import export_plan
from qsplan.planner.plan.scripted import plan_task
from qsplan.planner.task.task import load_task, task_paths

HANDS = Path(__file__).resolve().parent.parent / "data" / "hands"

TASK = """
name = "extension point"
{formation}

[hand]
file = "{hand}"
workpiece = [[0.0, 0.0], [0.080, 0.0], [0.085, 0.080], [0.008, 0.100]]
workpiece_mass = 0.2

[motion]
start_x = 0.0

[start]
{start}

[goal]
x = -0.02

[friction]
range = [0.0, 0.2]

[controller]
torque_resolution = 0.02
"""


def _task(tmp_path, hand, start, formation=""):
    path = tmp_path / "task.toml"
    path.write_text(TASK.format(hand=hand, start=start, formation=formation))
    return load_task(path)


def _certified(plan, task, out):
    export_plan(plan, out)
    cert = certify_plan(out, task)
    assert cert.ok, cert.summary()
    return json.loads((out / "plan.json").read_text())["metadata"]


def test_a_hand_is_one_file(tmp_path):
    (tmp_path / "hands").mkdir()
    (tmp_path / "hands" / "asymmetric_hand.toml").write_text((HANDS / "asymmetric_hand.toml").read_text())
    task = _task(tmp_path, "hands/asymmetric_hand.toml", "left_proximal = 1.4")
    assert task.hand.joint_names == ("left_proximal", "left_distal", "right")
    assert task.hand.free_joints == (0,) and not task.hand.accelerated
    plan = plan_task(task)
    assert plan.phases[-1].x[-1] == pytest.approx(-0.02, abs=1e-12)
    meta = _certified(plan, task, tmp_path / "out")
    assert meta["hand"]["description"]["name"] == "asymmetric hand"
    assert set(meta["limits"]["joints"]) == {"left_proximal", "left_distal", "right"}


REVERSED = "palm_edge_reversed"


@pytest.fixture
def reversed_formation(monkeypatch):
    """The test-only registry entry: the default formation's contacts in the reverse order."""
    base = FORMATIONS["palm_edge"]
    entry = Formation(REVERSED, tuple(reversed(base.contacts)), base.mode[::-1], base.closing,
                      "test only: the palm-edge formation, contacts in the reverse order")  # fmt: skip
    monkeypatch.setitem(FORMATIONS, REVERSED, entry)
    return entry


def test_the_scenes_follow_the_formations_order(reversed_formation):
    task = load_task(task_paths()["two_link_task"])
    hand, default = task.hand, task.formation
    held = task.start_joints[list(hand.free_joints)]
    row = hand.grasp_candidates(default, held[None], [task.start_x])[0]
    x = np.array([0.0, -0.01])
    free = np.repeat(held[None], x.size, axis=0)
    a = hand.scene_arrays(default, hand.grasp_states(default, row, x, free))
    b = hand.scene_arrays(reversed_formation, hand.grasp_states(reversed_formation, row, x, free))
    np.testing.assert_allclose(b.Wn, a.Wn[..., ::-1], atol=1e-15)
    np.testing.assert_allclose(b.Jt, a.Jt[..., ::-1, :], atol=1e-15)


@pytest.mark.parametrize("stem", ["demo_task", "two_link_task"])
def test_a_formation_is_one_registry_entry(tmp_path, reversed_formation, stem):
    task = load_task(task_paths()[stem])
    other = replace(task, formation=reversed_formation)
    a, b = plan_task(task), plan_task(other)
    ends = lambda plan: [(type(p).__name__, float(p.x[0]), float(p.x[-1])) for p in plan.phases]  # noqa: E731
    assert ends(b) == ends(a)
    assert b.narrowest()[2] == pytest.approx(a.narrowest()[2], rel=1e-9)
    meta = _certified(b, other, tmp_path / "out")
    assert meta["formation"]["name"] == REVERSED
    assert [c["name"] for c in meta["formation"]["contacts"]] == ["right", "left", "palm:1", "palm:0"]
    assert meta["task_record"]["formation"] == REVERSED
    # certified from the plan alone: the task (and its formation) rebuilt from the record
    cert = certify_plan(tmp_path / "out", load_task_from(meta))
    assert cert.ok, cert.summary()


def test_a_task_file_names_its_formation(tmp_path, reversed_formation):
    task = _task(tmp_path, "two_link_hand", "left_proximal = 1.4\nright_proximal = 1.74",
                 formation=f'formation = "{REVERSED}"')  # fmt: skip
    assert task.formation is reversed_formation
    with pytest.raises(Exception, match="formation: expected one of"):
        _task(tmp_path, "two_link_hand", "left_proximal = 1.4\nright_proximal = 1.74", formation='formation = "nope"')


def load_task_from(meta):
    from qsplan.planner.certify.certify import task_from_metadata

    return task_from_metadata(meta)
