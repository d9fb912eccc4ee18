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
    assert m.npair == len(hand.workpiece) + len(links)  # a foot under every workpiece vertex, a pair per link
    assert m.pair("palm:1").friction[0] == pytest.approx(0.05)
    assert m.pair(f"right:{links[-1].name}").friction[0] == pytest.approx(0.2)
    assert m.pair("palm:0").friction[0] > 0  # a coefficient of 0 is MuJoCo's smallest
    assert m.opt.gravity[1] == pytest.approx(-hand.gravity)


def test_every_pentagon_vertex_has_a_foot_in_its_corner_and_a_pair_with_its_friction():
    """Issue 32: a turned workpiece touches the palm with any vertex; each has a foot (a sphere touching both edges
    of its corner: the distance from its centre to each edge's line is its radius) and a pair ``palm:K`` with the
    friction the replays give a palm contact under vertex K (palm:0's, palm:1's, else palm:0's), and a sensor."""
    mujoco = pytest.importorskip("mujoco")
    from shapely.geometry import Point, Polygon

    from qsplan.planner.replay.mujoco_scene import contact_pairs, foot_centres
    from qsplan.planner.replay.phases import body_friction

    task = load_task(task_paths()["pentagon_task"])
    wp = np.asarray(task.hand.workpiece, float)
    assert len(wp) == 5
    mu = [0.05, 0.1, 0.15, 0.2]
    m = mujoco.MjModel.from_xml_string(scene_xml(task, mu=mu))
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    assert list(contact_pairs(task.hand))[:4] == ["palm:0", "palm:1", "left", "right"]  # extended, never renamed
    expected = body_friction([f"palm:{k}" for k in range(5)], mu)
    assert expected.tolist() == [0.05, 0.1, 0.05, 0.05, 0.05]
    for k, centre in enumerate(foot_centres(wp)):
        g = m.geom(f"foot:{k}")
        assert g.size[0] == FOOT_RADIUS and g.pos[:2] == pytest.approx(centre, abs=1e-15)
        for a, b in ((wp[k - 1], wp[k]), (wp[k], wp[(k + 1) % 5])):  # tangent to both edges of its corner
            e = (b - a) / np.hypot(*(b - a))
            assert abs(e[0] * (centre - a)[1] - e[1] * (centre - a)[0]) == pytest.approx(FOOT_RADIUS, rel=1e-9)
        assert Polygon(wp).contains(Point(centre).buffer(0.999 * FOOT_RADIUS))  # inside the corner
        pair = m.pair(f"palm:{k}")
        assert {int(pair.geom1[0]), int(pair.geom2[0])} == {m.geom("palm").id, g.id}
        assert pair.friction[0] == pytest.approx(expected[k])
        assert m.sensor(f"force:palm:{k}").id >= 0
    assert m.npair == 5 + 2


def test_a_foot_stands_on_an_edge_resting_flat_and_never_farther_than_its_bound():
    """The feet of a square turned by any angle: the lowest foot's lowest point is the lowest corner's height, or
    above it by at most ``r (1 / sin(45 deg) - 1)``; exactly at it when an edge rests flat."""
    from qsplan.planner.replay.mujoco_scene import foot_centres

    square = np.array([[0.0, 0.0], [0.05, 0.0], [0.05, 0.05], [0.0, 0.05]])
    for reverse in (False, True):  # either vertex order
        poly = square[::-1] if reverse else square
        feet = foot_centres(poly)
        for theta in np.linspace(-np.pi, np.pi, 73):
            rot = np.array([[np.cos(theta), -np.sin(theta)], [np.sin(theta), np.cos(theta)]])
            gap = (feet @ rot.T)[:, 1].min() - FOOT_RADIUS - (poly @ rot.T)[:, 1].min()
            assert -1e-15 <= gap <= FOOT_RADIUS * (np.sqrt(2) - 1) + 1e-15
            if abs(np.sin(2 * theta)) < 1e-12:
                assert gap == pytest.approx(0.0, abs=1e-15)


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
        assert set(run.observed) == {"SSSSBB"} and not run.contacts_lost  # the upper corners' feet stay open
        assert run.max_error() < 1e-5  # the servos' compliance: micrometres
        assert np.all(run.normal_force[:, :4] > 0.05)  # the plan's force margin, kept in the mean
        assert np.all(run.normal_force[:, 4:] == 0.0)


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


@pytest.mark.slow
def test_reorient_edge_lands_its_edge_on_two_feet(bundled_plan):
    """Issue 32: ``reorient_edge_task`` pivots on vertex 1 until its edge 1 (vertices 1 -> 2) lies on the palm.  At
    the pivot's last row the polygons show the made contact ``palm:2``; in MuJoCo vertex 2 has a foot, and over the
    last rows its pair takes load beside ``palm:1``'s: the landed edge rests on two feet (without a foot under vertex
    2 it would pass through the palm).  The replay keeps its modes at two friction vertices."""
    pytest.importorskip("mujoco")
    from qsplan.hands.contacts.found import contact_names, ordered_contacts
    from qsplan.planner.replay.mujoco_replay import replay_mujoco

    task = load_task(task_paths()["reorient_edge_task"])
    out = bundled_plan("reorient_edge_task")
    cols = read_plan_csv(out / "plan.csv")
    pose = [cols[k][-1] for k in ("x_workpiece", "y_workpiece", "theta_workpiece")]
    q = [cols[f"q_{n}"][-1] for n in task.hand.joint_names]
    names = contact_names(task.hand, pose, ordered_contacts(task.hand, pose, q))
    assert "palm:1" in names and "palm:2" in names  # the landed edge, as the certifier names its contacts
    r = replay_mujoco(out, task=task, mu=[[0.0] * 4, [0.2] * 4])
    for run in r.runs:
        assert run.contacts[:4] == ("palm:0", "palm:1", "left", "right") and "palm:2" in run.contacts
        assert run.ok, run.summary()
        two, one = run.contacts.index("palm:2"), run.contacts.index("palm:1")
        assert np.all(run.normal_force[:-2, two] < 0.01)  # off the palm until the last interval, where it lands
        assert run.normal_force[-1, two] > 0.01 and run.normal_force[-1, one] > 0.01, run.normal_force[-3:]


def _at_the_box_vertices(bundled_plan, name):
    """The bundled task ``name``'s plan replayed in MuJoCo at the 16 vertices of its friction box (four contacts)."""
    pytest.importorskip("mujoco")
    from qsplan.planner.replay.mujoco_replay import replay_mujoco

    task = load_task(task_paths()[name])
    lo, hi = task.mu_range
    corners = np.array(np.meshgrid(*[[lo, hi]] * 4)).reshape(4, -1).T
    runs = replay_mujoco(bundled_plan(name), task=task, mu=corners).runs
    assert len(runs) == 16
    return runs


@pytest.mark.slow
def test_the_full_turn_keeps_its_modes_in_mujoco_at_every_friction_vertex(bundled_plan):
    """Issue 34, item 3: ``full_turn_task`` (the turning hand, a block turned 80.5 deg onto its next edge in one pivot)
    replayed in MuJoCo at the 16 vertices of its friction box [0, 0.03]^4 (about a minute): every run keeps every
    letter MuJoCo resolves and the workpiece within the judge's tolerance of the plan (the plan ends at the landing
    instant itself: MuJoCo's vertex 2 is then micrometres above its foot, so no load on it is asked)."""
    for run in _at_the_box_vertices(bundled_plan, "full_turn_task"):
        assert run.ok, run.summary()


@pytest.mark.slow
def test_the_finger_replaced_mid_turn_keeps_its_modes_in_mujoco_at_every_friction_vertex(bundled_plan):
    """Issue 34, item 2: ``finger_replaced_task`` (the right finger lifted at rest mid-turn, its knuckle moved and its tip
    closed again) replayed in MuJoCo at the 16 vertices of its friction box [0.05, 0.1]^4 (about a minute): every run
    keeps every letter MuJoCo resolves, the take-over of the new grasp's hold included; the block rests within the
    judge's tolerance of where the right finger let it go while the finger moves (the hold with it lifted, proved over
    the box); and it follows the plan within the tolerance up to the last pivot.  Not asserted, measured and said in
    docs/reorientation.md: in the last pivot's final degrees before the landing 8 of the 16 runs stray 25.8-30.4 um from
    the plan (tolerance 25 um), as ``full_turn_task`` does at [0, 0.1]."""
    from qsplan.planner.replay.mujoco_replay import POSE_TOLERANCE, RELEASE_DRIFT

    for run in _at_the_box_vertices(bundled_plan, "finger_replaced_task"):
        assert run.modes_kept, run.summary()
        free = ~run.contact_rows
        assert free.any() and run.max_path_error(free) <= POSE_TOLERANCE + RELEASE_DRIFT, run.summary()
        before_last = run.phase < run.phase.max()
        assert run.max_path_error(before_last) <= POSE_TOLERANCE, run.summary()
