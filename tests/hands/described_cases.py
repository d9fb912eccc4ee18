"""Hands the described-hand tests share: the bundled hands with their tasks' workpieces, a mixed hand, the paper tasks.

Task files are read as data (``planner/data/*.toml``, TOML), not through the planner: these tests are about hands."""

import tomllib
from importlib.resources import files

from qsplan.hands.description import load_hand, make_hand_description

#: The parallel-jaw task's hexagon (m), as written.
HEXAGON = [[0.0, 0.0], [0.06, 0.0], [0.08, 0.05], [0.05, 0.09], [0.01, 0.09], [-0.02, 0.05]]

#: The paper hand's parameters a task's ``[hand]`` may give
#: (:func:`qsplan.hands.paper_hand.two_finger.make_two_finger_hand`).
PAPER_KEYS = ("workpiece", "workpiece_mass", "finger_base", "finger_length", "finger_width", "finger_mass",
              "palm_halfwidth", "palm_thickness", "gravity", "mu", "palm_edge")  # fmt: skip


def task_tables() -> dict:
    """``{stem: parsed task}`` of every bundled task."""
    data = files("qsplan.planner").joinpath("data")
    return {p.name[:-5]: tomllib.loads(p.read_text()) for p in sorted(data.iterdir(), key=lambda p: p.name)
            if p.name.endswith(".toml")}  # fmt: skip


def mixed_description():
    """A two-link revolute left finger beside the bundled leaning right jaw (as ``tests/planner/test_chain_plan.py``)."""
    rect = [[0.0, -0.006], [0.07, -0.006], [0.07, 0.006], [0.0, 0.006]]
    left = {"name": "left", "joints": [
        {"name": "left_1", "type": "revolute", "origin": [-0.09, 0.0, 0.0], "limits": [0.05, 3.09], "speed": 0.5,
         "link": {"polygon": rect}},
        {"name": "left_2", "type": "revolute", "origin": [0.07, 0.0, 0.0], "limits": [-2.6, 2.6], "speed": 0.5,
         "link": {"polygon": rect}}]}  # fmt: skip
    jaw = load_hand("parallel_jaw")
    k = jaw.joint_names.index("right_jaw")
    joint = jaw.manipulator.joints[k]
    right = {"name": "right", "joints": [{"name": "right_jaw", "type": "prismatic", "origin": joint.origin.tolist(),
                                          "limits": [0.0, 0.1], "speed": 0.05,
                                          "link": {"polygon": [list(p) for p in joint.link_shape]}}]}  # fmt: skip
    palm = [[-0.16, -0.02], [0.16, -0.02], [0.16, 0.0], [-0.16, 0.0]]
    return make_hand_description("mixed", palm, [left, right])


def chain_cases() -> dict:
    """``{name: (description, workpiece (as written), free-joint centre or None)}``: the bundled chain hands holding
    their tasks' workpieces (the two-link hand's free joints about its task's ``[start]``), and the mixed hand."""
    tasks = task_tables()
    two_link = tasks["two_link_task"]
    return {
        "two_link_hand": (load_hand("two_link_hand"), two_link["hand"]["workpiece"],
                          [two_link["start"]["left_proximal"], two_link["start"]["right_proximal"]]),
        "parallel_jaw": (load_hand("parallel_jaw"), tasks["parallel_jaw_task"]["hand"]["workpiece"], None),
        "mixed": (mixed_description(), HEXAGON, [1.4]),
    }  # fmt: skip


def paper_task_hands() -> dict:
    """``{task stem: TwoFingerHand}`` of every bundled task on the paper's hand (a parameter table or the paper hand
    file), as the task gives it."""
    from qsplan.hands.description.two_finger_form import two_finger_parameters
    from qsplan.hands.paper_hand.two_finger import make_two_finger_hand

    out = {}
    for stem, task in task_tables().items():
        table = task["hand"]
        kw = {k: table[k] for k in PAPER_KEYS if k in table}
        if "file" in table:
            params = two_finger_parameters(load_hand(table["file"]))
            if params is None:
                continue
            kw.update(params)
        out[stem] = make_two_finger_hand(**kw)
    return out
