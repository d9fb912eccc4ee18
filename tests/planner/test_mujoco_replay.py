"""A plan executed in MuJoCo (issue 24, item 5): the scene's MJCF, a replay at a friction vertex, ``qsplan replay``."""

import json
import sys
from pathlib import Path

import numpy as np
import pytest

from qsplan.mechanics import QsplanError
from qsplan.planner.cli.main import main
from qsplan.planner.export.plan_files import read_plan_csv
from qsplan.planner.replay.mujoco_scene import (ARMATURE, FOOT_RADIUS, SERVO_OMEGA, polygon_inertia, scene_xml,
                                                servo_gains, start_of, write_scene)  # fmt: skip
from qsplan.planner.task.task import load_task, task_paths

REFERENCE = Path(__file__).resolve().parent.parent / "data" / "reference_plans"

#: Contact distance (m) MuJoCo may report at a plan's first row, where the fingers touch: the plans' geometry is
#: exact to ~1e-9 m (the closing's root finding); a micrometre is far below any error the replay reports.
TOUCH_TOL = 1e-6


def test_rectangle_inertia_is_the_closed_form():
    c, i = polygon_inertia([[0.0, 0.0], [0.3, 0.0], [0.3, 0.1], [0.0, 0.1]], 2.0)
    assert c == pytest.approx([0.15, 0.05]) and i == pytest.approx(2.0 * (0.3**2 + 0.1**2) / 12)


def test_servo_is_critically_damped_at_its_frequency():
    for kind, inertia in ARMATURE.items():
        kp, kv = servo_gains(kind)
        assert np.sqrt(kp / inertia) == pytest.approx(SERVO_OMEGA)
        assert kv / (2 * np.sqrt(kp * inertia)) == pytest.approx(1)


@pytest.mark.parametrize("name", ["demo_task", "parallel_jaw_task", "two_link_task"])
def test_scene_loads_with_the_task_s_bodies_joints_and_pairs(name):
    mujoco = pytest.importorskip("mujoco")
    task = load_task(task_paths()[name])
    hand = task.hand
    m = mujoco.MjModel.from_xml_string(scene_xml(task, mu=[0.0, 0.05, 0.1, 0.2]))
    n_j = len(hand.joint_names)
    assert m.njnt == 3 + n_j and m.nu == 2 * n_j
    assert m.body("workpiece").mass[0] == pytest.approx(hand.workpiece_mass)
    links = hand.description.manipulator.joints
    for j in links:
        assert m.body(j.name).mass[0] > 0 and m.joint(j.name).type == (3 if j.kind == "revolute" else 2)  # hinge, slide
    assert m.npair == 2 + len(links)
    assert m.pair("palm:1").friction[0] == pytest.approx(0.05)
    assert m.pair(f"right:{links[-1].name}").friction[0] == pytest.approx(0.2)
    assert m.pair("palm:0").friction[0] > 0  # a coefficient of 0 is MuJoCo's smallest
    assert m.opt.gravity[1] == pytest.approx(-hand.gravity)


def test_start_keyframe_touches_where_the_plan_does(tmp_path):
    mujoco = pytest.importorskip("mujoco")
    task = load_task(task_paths()["demo_task"])
    cols = read_plan_csv(REFERENCE / "demo_task.csv")
    path = write_scene(task, tmp_path / "scene.xml", start=start_of(cols))
    m = mujoco.MjModel.from_xml_path(str(path))
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, 0)
    mujoco.mj_forward(m, d)
    fromto = np.zeros(6)
    for g1, g2 in (("link:left", "workpiece"), ("link:right", "workpiece"), ("palm", "foot:0"), ("palm", "foot:1")):
        assert abs(mujoco.mj_geomDistance(m, d, m.geom(g1).id, m.geom(g2).id, 0.01, fromto)) <= TOUCH_TOL
    foot = d.geom_xpos[m.geom("foot:0").id]
    assert foot[1] - FOOT_RADIUS == pytest.approx(0.0, abs=TOUCH_TOL)  # the bottom edge's end on the palm
    with pytest.raises(QsplanError, match="exists"):
        write_scene(task, path)


@pytest.fixture(scope="module")
def short_demo(tmp_path_factory):
    """The demo plan's first 0.5 s (11 rows): a valid plan that replays in about a second per run."""
    cols = read_plan_csv(REFERENCE / "demo_task.csv")
    lines = (REFERENCE / "demo_task.csv").read_text().splitlines()
    assert len(lines) == cols["t"].size + 1
    path = tmp_path_factory.mktemp("short") / "plan.csv"
    path.write_text("\n".join(lines[:12]) + "\n")
    return path


def test_demo_replay_keeps_its_mode_at_friction_vertices(short_demo):
    pytest.importorskip("mujoco")
    from qsplan.planner.replay.mujoco_replay import replay_mujoco

    task = load_task(task_paths()["demo_task"])
    r = replay_mujoco(short_demo, task=task, mu=[[0.0] * 4, [0.2, 0.2, 0.0, 0.0], [0.2] * 4])
    assert len(r.runs) == 3 and r.engine.startswith("mujoco ")
    for run in r.runs:
        assert run.modes_kept, run.summary()
        assert set(run.observed) == {"SSSS"} and not run.contacts_lost
        assert run.max_error() < 1e-5  # the servos' compliance: micrometres
        assert np.all(run.normal_force > 0.05)  # the plan's force margin, kept in the mean


def test_replay_without_a_task_needs_plan_metadata(short_demo):
    pytest.importorskip("mujoco")
    from qsplan.planner.replay.mujoco_replay import replay_mujoco

    with pytest.raises(QsplanError, match="no plan.json metadata"):
        replay_mujoco(short_demo)


@pytest.mark.parametrize("kwargs, match", [
    ({"mu": [0.1, 0.1]}, "friction vectors"),
    ({"mu": [[-0.1, 0, 0, 0]]}, "friction vectors"),
    ({"n_random": -1}, "n_random"),
])  # fmt: skip
def test_bad_replay_arguments_are_refused(short_demo, kwargs, match):
    pytest.importorskip("mujoco")
    from qsplan.planner.replay.mujoco_replay import replay_mujoco

    with pytest.raises(QsplanError, match=match):
        replay_mujoco(short_demo, task=load_task(task_paths()["demo_task"]), **kwargs)


def test_cli_without_mujoco_names_the_extra(short_demo, monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "mujoco", None)  # import mujoco raises ImportError
    assert main(["replay", str(short_demo), "--task", "demo_task"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and err.startswith("qsplan: error: --engine")
    assert "pip install '.[sim]'" in err


def test_cli_refuses_a_bad_run_count(short_demo, capsys):
    assert main(["replay", str(short_demo), "--task", "demo_task", "--runs", "-1"]) == 2
    assert "--runs: expected 0..1000" in capsys.readouterr().err


@pytest.mark.slow
def test_cli_replays_every_vertex(short_demo, capsys):
    pytest.importorskip("mujoco")
    assert main(["replay", str(short_demo), "--task", "demo_task", "--runs", "0", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["ok"] and doc["modes_kept"] and len(doc["runs"]) == 16  # the box [0, 0.2]^4's corners
    corners = np.array(np.meshgrid(*[[0.0, 0.2]] * 4)).reshape(4, -1).T
    assert {tuple(r["mu"]) for r in doc["runs"]} == {tuple(v) for v in corners}
    assert doc["settings"]["stops_added"] == 0
