"""The task <-> dict round trip (issue 22): one record, written into plan.json and read by the certifier."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from qsplan.mechanics.errors import QsplanError
from qsplan.planner.task.record import task_record
from qsplan.planner.task.task import load_task, task_from_record, task_paths

#: Re-centring the workpiece on its centroid again moves its vertices by an ulp (sums in another order); every
#: other number of the record comes back exactly.
RECENTRE_ULPS = 1e-15


def _same(a, b, path="record"):
    if isinstance(a, dict):
        assert isinstance(b, dict) and a.keys() == b.keys(), path
        for k in a:
            _same(a[k], b[k], f"{path}.{k}")
    elif isinstance(a, list):
        assert isinstance(b, list) and len(a) == len(b), path
        for i, (x, y) in enumerate(zip(a, b)):
            _same(x, y, f"{path}[{i}]")
    elif isinstance(a, float) and not isinstance(b, bool):
        tol = RECENTRE_ULPS if ".hand.workpiece" in path else 0.0
        assert math.isclose(a, b, rel_tol=0.0, abs_tol=tol), f"{path}: {a} != {b}"
    else:
        assert a == b, f"{path}: {a!r} != {b!r}"


@pytest.mark.parametrize("name", sorted(task_paths()))
def test_every_bundled_task_round_trips(name):
    task = load_task(task_paths()[name])
    record = json.loads(json.dumps(task_record(task)))  # plain JSON, as plan.json stores it
    again = task_from_record(record)
    _same(task_record(again), record)
    assert again.hand.accelerated == task.hand.accelerated and again.hand.paper_form == task.hand.paper_form
    assert again.hand.joint_names == task.hand.joint_names and again.formation == task.formation
    np.testing.assert_array_equal(again.joint_limits, task.joint_limits)
    np.testing.assert_array_equal(again.joint_speeds, task.joint_speeds)
    np.testing.assert_allclose(again.hand.workpiece, task.hand.workpiece, rtol=0, atol=RECENTRE_ULPS)
    assert (again.goal is None) == (task.goal is None) and again.start_features == task.start_features
    assert again.mu_range == task.mu_range and again.shared_mu == task.shared_mu
    assert again.force_margin == task.force_margin and again.torque_resolution == task.torque_resolution


def test_the_rebuilt_task_plans_the_same_plan():
    from qsplan.planner.plan.scripted import plan_task
    from tests.planner.bundled import bundled_task, planned

    task = bundled_task("parallel_jaw_task")
    a, b = planned("parallel_jaw_task"), plan_task(task_from_record(task_record(task)))
    assert [p.name for p in a.phases] == [p.name for p in b.phases]
    assert b.narrowest()[2] == pytest.approx(a.narrowest()[2], rel=1e-12)


def _record(**changes):
    record = json.loads(json.dumps(task_record(load_task(task_paths()["demo_task"]))))
    for path, value in changes.items():
        *head, last = path.split("__")
        node = record
        for key in head:
            node = node[key]
        node[last] = value
    return record


@pytest.mark.parametrize("changes, message", [
    ({"friction__range": [0.3, 0.1]}, r"friction\.range: expected lo <= hi"),
    ({"version": 99}, r"version: expected 1"),
    ({"formation": "no_such"}, r"formation: expected one of (\w+, )*palm_edge"),
    ({"limits__left": [0.0, 9.0]}, r"limits\.left"),
    ({"controller__torque_resolution": -1.0}, r"controller\.torque_resolution"),
    ({"hand__fingers": []}, r"hand\.fingers"),
])
def test_a_bad_record_names_its_field(changes, message):
    with pytest.raises(QsplanError, match=message):
        task_from_record(_record(**changes))


def test_a_record_is_a_table():
    with pytest.raises(QsplanError, match="task: expected a table"):
        task_from_record(["not", "a", "table"])


def test_the_certifier_checks_the_record_but_not_the_tasks_name(tmp_path):
    from dataclasses import replace

    from qsplan.planner.certify.certify import certify_plan
    from qsplan.planner.export.plan_files import export_plan
    from tests.planner.bundled import bundled_task, planned

    task = bundled_task("parallel_jaw_task")
    export_plan(planned("parallel_jaw_task"), tmp_path)
    assert certify_plan(tmp_path, replace(task, name="another name"), n_random=0).ok
    refused = certify_plan(tmp_path, replace(task, mu_range=(0.0, 0.25)), n_random=0)
    assert any(v.kind == "metadata" and "task_record" in v.message for v in refused.violations)
