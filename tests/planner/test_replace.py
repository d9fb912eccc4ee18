"""A finger lifted and replaced during a turn (issue 34, item 2): the hold with a finger lifted, the replacement's
motion, the certifier's checks of it, and what it refuses.

The plan is the bundled ``finger_replaced_task``'s (planned once per test run): the turning hand turns a block whose
sloping top is too short for any one held knuckle, so the formation search lifts the right finger at rest where the
hold with it lifted is proved, moves its knuckle and closes the tip again farther along the top, and turns on to the
landing.  Independent of the planner's choices, the certifier (``qsplan verify``) proves the hold again from the task
and the rows; the edits below must each be refused.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from qsplan.planner import ompl_available, task_paths
from tests.planner.bundled import planned
from tests.planner.test_certify_tampering import _read, _run, _write

pytestmark = pytest.mark.ompl

TASK = "finger_replaced_task"


@pytest.fixture(scope="module")
def replaced(bundled_plan):
    """``(task path, plan dir, plan)``: the bundled turn with the right finger replaced, exported once per run."""
    if not ompl_available():
        pytest.skip("OMPL bindings not installed")
    return task_paths()[TASK], bundled_plan(TASK), planned(TASK)


def _replace_phase(plan):
    return next(i for i, ph in enumerate(plan.phases) if ph.kind == "replace")


def test_the_replacement_moves_one_finger_only_around_a_held_workpiece(replaced):
    from qsplan.hands.contacts.found import contact_names, ordered_contacts
    from qsplan.planner.states.contact import configuration_problem

    _, _, plan = replaced
    i = _replace_phase(plan)
    ph, before, after = plan.phases[i], plan.phases[i - 1], plan.phases[i + 1]
    hand = plan.task.hand
    right = list(hand.finger_joints[1])
    left = list(hand.finger_joints[0])
    assert ph.finger == "right"
    assert np.all(ph.q[:, left] == ph.q[0, left])  # the held finger does not move
    assert np.ptp(ph.q[:, right], axis=0).max() > 0.05  # the replaced one does
    assert abs(ph.q[-1, right[0]] - ph.q[0, right[0]]) > 1e-3  # its knuckle is held anew
    pose = ph.poses(hand.rest_height)
    assert np.all(pose == pose[0]) and np.array_equal(pose[0], before.pose[-1]) and np.array_equal(pose[0], after.pose[0])
    assert np.array_equal(ph.q[0], before.q[-1]) and np.array_equal(ph.q[-1], after.q[0])
    for k in range(ph.t.size):
        assert configuration_problem(plan.task, pose[k], ph.q[k]) is None
        names = contact_names(hand, pose[k], ordered_contacts(hand, pose[k], ph.q[k]))
        touching = any(n.split(":")[0] == "right" for n in names)
        assert touching == (k in (0, ph.t.size - 1))  # off the workpiece between its ends
        assert [n for n in names if not n.startswith("right")] == list(ph.kept)
    assert ph.kept == ("palm:1", "left:base", "left:tip")


def test_the_lifted_hold_needs_friction_it_can_count_on(replaced):
    """Proved over the task's box; refused with zero friction in the box (the frictionless proof's answer: the block
    slides on the palm and along the flush finger for free), by the hold proof and by the frictionless proof alike."""
    from dataclasses import replace as with_

    from qsplan.hands.contacts.found import lifted_scene
    from qsplan.mechanics.bands.hold import prove_hold
    from qsplan.planner.plan.replace import lifted_hold

    _, _, plan = replaced
    ph = plan.phases[_replace_phase(plan)]
    task, pose, q = plan.task, ph.pose, ph.q[0]
    assert lifted_hold(task, pose, q, "right").proved
    zero = lifted_hold(with_(task, mu_range=(0.0, 0.1)), pose, q, "right")
    assert not zero.proved
    assert not prove_hold(lifted_scene(task.hand, pose, q, "right")).proved
    assert not lifted_hold(task, pose, q, "left").proved  # the right finger alone cannot hold it on the vertex


def test_the_plan_with_a_replacement_is_certified(replaced):
    task, plan_dir, plan = replaced
    code, out, err = _run(["verify", str(plan_dir), "--task", str(task)])
    assert code == 0, out + err
    doc = json.loads((plan_dir / "plan.json").read_text())
    i = _replace_phase(plan)
    phase = doc["metadata"]["phases"][i]
    assert phase["kind"] == "regrasp" and phase["phase_kind"] == "replace" and phase["finger"] == "right"
    assert phase["contacts_kept"] == ["palm:1", "left:base", "left:tip"]
    steps = [s for s in doc["metadata"]["sequence"] if s["kind"] != "search"]
    assert steps[i]["kind"] == "replace" and steps[i - 1]["kind"] == "hold"  # unloaded before it lets go
    assert steps[i - 1]["torque_to"] < steps[i - 1]["torque_from"]


def _rows_of(rows, phase):
    return [k for k, r in enumerate(rows) if int(float(r["phase"])) == phase]


def move_held_finger(rows, doc, plan):
    """The held finger's knuckle nudged 1 mrad on an inner row of the replacement."""
    k = _rows_of(rows, _replace_phase(plan))[2]
    rows[k]["q_left_distal"] = repr(float(rows[k]["q_left_distal"]) + 1e-3)


def tip_workpiece(rows, doc, plan):
    """The workpiece turned 1 mrad on every row of the replacement: it must stay as the pivot left it."""
    for k in _rows_of(rows, _replace_phase(plan)):
        rows[k]["theta_workpiece"] = repr(float(rows[k]["theta_workpiece"]) - 1e-3)


def misstate_finger(rows, doc, plan):
    doc["metadata"]["phases"][_replace_phase(plan)]["finger"] = "left"


def misstate_kept(rows, doc, plan):
    doc["metadata"]["phases"][_replace_phase(plan)]["contacts_kept"] = ["palm:1", "left:tip"]


@pytest.mark.parametrize("edit", [move_held_finger, tip_workpiece, misstate_finger, misstate_kept])
def test_an_edited_replacement_is_refused(replaced, tmp_path, edit):
    task, plan_dir, plan = replaced
    rows, doc = _read(plan_dir)
    edit(rows, doc, plan)
    dst = _write(tmp_path / "edited", rows, doc)
    code, out, err = _run(["verify", str(dst), "--task", str(task)])
    assert code == 1, out + err
    assert "NOT certified" in out


def test_a_box_with_zero_friction_refuses_the_replacement(replaced, tmp_path):
    """The same rows judged for friction in [0, 0.1]: the hold with the right finger lifted is not proved at any row of
    the replacement (the other rows' bands are judged anew too, and refused where they reach beyond the wider box's)."""
    task, plan_dir, plan = replaced
    wider = tmp_path / "wider.toml"
    text = task.read_text()
    assert "range = [0.05, 0.1]" in text
    wider.write_text(text.replace("range = [0.05, 0.1]", "range = [0.0, 0.1]"))
    code, out, err = _run(["verify", str(plan_dir), "--task", str(wider), "--json"])
    assert code == 1
    doc = json.loads(out)
    rest = {v["row"] for v in doc["violations"] if v["kind"] == "rest"}
    rows = np.flatnonzero(np.asarray(json.loads((plan_dir / "plan.json").read_text())["data"]["phase"])
                          == _replace_phase(plan))  # fmt: skip
    assert rest == set(rows.tolist())
    assert all("while the right finger moves, and that hold is not proved" in v["message"]
               for v in doc["violations"] if v["kind"] == "rest")


def test_a_turn_past_its_formation_says_why_no_finger_was_replaced(tmp_path):
    """The demo's turn asked to -1.2 rad (its formation ends at -55 deg, the right finger meeting the workpiece) with
    friction in [0, 0.2]: zero friction is in the box, so the hold with the right finger lifted is proved at no angle,
    and the refusal says so beside the formation's own end."""
    from qsplan.planner.plan.results import PlanFailure
    from qsplan.planner.plan.turning import plan_turn
    from qsplan.planner.task.task import load_task

    path = tmp_path / "far.toml"
    path.write_text(task_paths()["reorient_task"].read_text().replace("\ntheta = -0.5 ", "\ntheta = -1.2 ", 1))
    with pytest.raises(PlanFailure) as exc:
        plan_turn(load_task(path))
    message = str(exc.value)
    assert "ended at theta = -55.05 deg" in message
    assert "the right finger is replaced nowhere: the hold with it lifted is proved at no angle of this formation for " \
           "friction in [0, 0.2]" in message
