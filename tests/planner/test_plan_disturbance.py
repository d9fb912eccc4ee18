"""A task's ``[controller] disturbance`` (issue 24, item 2) in the planner and the certifier.

Every band of the plan holds its mode and precludes every competitor for every friction in the set and every
external wrench in the box: checked here by the all-modes solver at the vertices of friction box x wrench box at
the exported commands, and by the certifier, which refuses a plan made without the disturbance.
"""

from __future__ import annotations

import json
from dataclasses import replace
from itertools import product

import numpy as np
import pytest

from qsplan.mechanics import solve_many
from qsplan.mechanics.bands.disturbance import WrenchBox
from qsplan.planner.task.dynamics import inertial_box
from qsplan.mechanics.errors import QsplanError
from qsplan.planner.certify.certify import certify_plan, read_plan
from qsplan.planner.certify.modes import row_scene
from qsplan.planner.export.plan_files import export_plan
from qsplan.planner.plan.scripted import plan_task
from qsplan.planner.task.record import task_record
from qsplan.planner.task.task import load_task, task_from_record, task_paths

BOX = {"lo": [-0.2, -0.2, -0.005], "hi": [0.2, 0.2, 0.005]}


def _task(tmp_path, box=BOX, stem="demo_task"):
    text = task_paths()[stem].read_text()
    cell = "{ lo = %s, hi = %s }" % (box["lo"], box["hi"])
    path = tmp_path / "task.toml"
    path.write_text(text.replace("[controller]\n", f"[controller]\ndisturbance = {cell}\n"))
    return load_task(path)


@pytest.fixture(scope="module")
def planned(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("disturbed")
    task = _task(tmp)
    plan = plan_task(task)
    export_plan(plan, tmp / "out")
    return task, plan, tmp / "out"


def test_the_task_reads_its_box_and_round_trips(planned):
    task = planned[0]
    assert task.disturbance == WrenchBox(BOX["lo"], BOX["hi"])
    assert task_from_record(json.loads(json.dumps(task_record(task)))).disturbance == task.disturbance


@pytest.mark.parametrize("box, message", [
    ({"lo": [0, 0, 0]}, r"controller\.disturbance\.hi: missing"),
    ({"lo": [0, 0], "hi": [0, 0, 0]}, r"controller\.disturbance\.lo: expected 3 numbers"),
    ({"lo": [0, 0, 0], "hi": [0, 0, 0], "mid": 1}, r"controller\.disturbance\.mid: unknown field"),
    ({"lo": [0, -500, 0], "hi": [0, 0, 0]}, r"controller\.disturbance\.lo\[1\]"),
    ({"lo": [0, 1, 0], "hi": [0, 0, 0]}, r"controller\.disturbance: expected lo <= hi"),
])
def test_a_bad_box_names_its_field(tmp_path, box, message):
    path = tmp_path / "task.toml"
    lines = ", ".join(f"{k} = {v}" for k, v in box.items())
    path.write_text(task_paths()["demo_task"].read_text().replace("[controller]\n", f"[controller]\ndisturbance = {{ {lines} }}\n"))
    with pytest.raises(QsplanError, match=message):
        load_task(path)


def test_zero_box_is_no_box_the_inertial_one_stays(tmp_path):
    """A zero box adds nothing: the bands withstand the time scaling's inertial load, as without a box."""
    task = _task(tmp_path, {"lo": [0.0, 0.0, 0.0], "hi": [0.0, 0.0, 0.0]})
    m, y, a = task.hand.workpiece_mass, task.hand.rest_height, task.dynamics.workpiece_acceleration
    assert task.dynamics.source == "inertia" and task.disturbance == inertial_box(m, y, a)
    assert task.disturbance.hi[0] == m * a and task.disturbance.hi[2] >= y * m * a  # rounded up, never down


def test_the_box_narrows_the_plans_bands(planned):
    task, plan, _ = planned
    calm = plan_task(replace(task, disturbance=None))
    assert plan.narrowest()[2] >= task.torque_resolution
    assert plan.narrowest()[2] < calm.narrowest()[2]


def test_the_commands_keep_the_mode_at_every_friction_and_wrench_vertex(planned):
    """The all-modes solver, independent of the bands, at the exported commands: only 4S is feasible at every vertex
    of friction box x wrench box (the command sits inside the band by its margin)."""
    task, _, out = planned
    cols, _ = read_plan(out)
    lo, hi = task.mu_range
    mus = np.array(list(product((lo, hi), repeat=4)))
    rows = np.flatnonzero(cols["mode"] != "free")
    for k in rows[:: max(1, rows.size // 8)]:
        scene = row_scene(task, cols, k)
        for w in task.disturbance.vertices():
            sv = solve_many(replace(scene, g_obj=scene.g_obj + w), mus)
            feasible = sv.codes == 0
            j = sv.letters.index("SSSS")
            assert feasible[:, j].all(), (k, w)
            assert feasible.sum(axis=1).max() == 1, (k, w)


def test_the_certifier_holds_the_plan_to_the_box(planned, tmp_path):
    task, _, out = planned
    cert = certify_plan(out, task, n_random=2)
    assert cert.ok, cert.summary()
    calm = replace(task, disturbance=None)
    export_plan(plan_task(calm), tmp_path / "calm")
    refused = certify_plan(tmp_path / "calm", task, n_random=2)
    kinds = {v.kind for v in refused.violations}
    assert not refused.ok and {"band", "metadata"} <= kinds
