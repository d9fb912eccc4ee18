"""Automatic planning (issue 14): the [goal] file contract, plans certified and re-simulated, reports, tables."""

import tomllib

import numpy as np
import pytest

from qsplan.mechanics.errors import QsplanError
from qsplan.planner.task.task import demo_task_path, load_task, make_task, task_paths

pytestmark = pytest.mark.ompl

pytest.importorskip("ompl")

DEMO = tomllib.loads(demo_task_path().read_text())
HAND = DEMO["hand"]


def goal_task(tmp_path, goal, **tables):
    """A task file with the demo's hand and start and the given [goal] table (TOML text written by hand)."""
    lines = ["[hand]", f"file = {HAND['file']!r}".replace("'", '"'), f"workpiece = {HAND['workpiece']}",
             "[motion]", "start_x = 0.0", "[goal]"] + [f"{k} = {v!r}".replace("'", '"') for k, v in goal.items()]
    for name, table in tables.items():
        lines += [f"[{name}]"] + [f"{k} = {v!r}".replace("'", '"') for k, v in table.items()]
    lines += ["[controller]", "torque_resolution = 0.02"]
    path = tmp_path / "task.toml"
    path.write_text("\n".join(lines) + "\n")
    return path


def test_goal_contract_is_read(tmp_path):
    task = load_task(goal_task(tmp_path, {"x": -0.03, "left": "vertex:3", "right": "edge:1"}))
    assert task.goal.x == -0.03 and task.goal.left == ("vertex", 3) and task.goal.right == ("edge", 1)
    assert task.automatic and task.waypoints.size == 0
    demo = load_task(demo_task_path())
    assert demo.automatic and demo.goal.x == DEMO["goal"]["x"]


@pytest.mark.parametrize("goal, match", [
    ({"left": "edge:1"}, r"goal\.x: missing"),
    ({"x": "left"}, r"goal\.x: expected a number"),
    ({"x": 5.0}, r"goal\.x: expected -1 to 1 m"),
    ({"x": 0.01, "left": "edge 1"}, r'goal\.left: expected "edge:K" or "vertex:K"'),
    ({"x": 0.01, "right": "vertex:4"}, r"goal\.right: the workpiece has 4 vertices"),
    ({"x": 0.01, "middle": "edge:1"}, r"goal\.middle: unknown field"),
])  # fmt: skip
def test_bad_goals_name_the_field(tmp_path, goal, match):
    with pytest.raises(QsplanError, match=match):
        load_task(goal_task(tmp_path, goal))


def test_waypoints_and_goal_together_are_refused():
    with pytest.raises(QsplanError, match=r"goal: give either motion\.waypoints .* or \[goal\]"):
        make_task(HAND, 0.0, [0.01], goal={"x": 0.01})
    with pytest.raises(QsplanError, match=r"motion\.waypoints: missing \(or give a \[goal\]"):
        make_task(HAND, 0.0)
    with pytest.raises(QsplanError, match=r"start\.left: expected"):
        make_task(HAND, 0.0, goal={"x": 0.01}, start={"left": "palm"})


@pytest.mark.parametrize("goal_x", [-0.03, 0.03])
def test_demo_start_to_goals_left_and_right_certified(tmp_path, goal_x):
    """The acceptance's tasks: the demo's start, goals left and right; a certified plan whose export re-simulates."""
    from qsplan.planner.pipeline.run import run_plan

    task = load_task(goal_task(tmp_path, {"x": goal_x}))
    run = run_plan(task, tmp_path / "out", verify=2, plots=False)
    assert run.followed and run.certificate.ok
    plan = run.plan
    assert plan.phases[0].x[0] == 0.0 and plan.phases[-1].x[-1] == goal_x
    assert plan.sequence and plan.search is plan.sequence[-1] and plan.search.kind == "search"
    assert min(np.min(s.width) for s in plan.segments) >= task.torque_resolution


def test_planner_is_deterministic(tmp_path):
    from qsplan.planner.pipeline.run import run_plan

    task = load_task(demo_task_path())
    a = run_plan(task, tmp_path / "a", verify=0, plots=False)
    b = run_plan(task, tmp_path / "b", verify=0, plots=False)
    assert (tmp_path / "a" / "plan.csv").read_bytes() == (tmp_path / "b" / "plan.csv").read_bytes()
    assert a.plan.sequence[:-1] == b.plan.sequence[:-1]


@pytest.mark.parametrize("stem", sorted(s for s, p in task_paths().items() if "[goal]" in p.read_text()))
def test_bundled_goal_tasks(tmp_path, bundled_plan, stem):
    """Each bundled automatic task is planned, certified and re-simulated; the infeasible one says why.

    The plan and its exported files are the run's shared ones (``qsplan plan``, :func:`tests.planner.bundled.planned`
    and the ``bundled_plan`` fixture, which ``test_plan.py`` reads too): this test adds the re-simulation of the
    exported file at three friction vectors (as ``qsplan plan --verify 3``), the goal reached and the commands'
    continuity."""
    import json

    from qsplan.planner.pipeline.run import run_plan
    from qsplan.planner.pipeline.worker import replay_exported
    from qsplan.planner.plan.results import PlanFailure
    from tests.planner.bundled import planned

    if stem == "friction_closes_task":
        task = load_task(task_paths()[stem])
        with pytest.raises(PlanFailure) as err:
            run_plan(task, tmp_path / "out", verify=0, plots=False)
        msg = err.value.report.message
        assert "no guaranteed band for the whole friction range [0.0, 0.6]" in msg
        assert "with mu in [0, 0.5" in msg  # the friction from which the band closes, by bisection
        assert (tmp_path / "out" / "failure.json").exists()
        return
    plan, out = planned(stem), bundled_plan(stem)
    task = plan.task
    assert json.loads((out / "certificate.json").read_text())["certified"] is True
    replays = replay_exported(plan, out / "plan.csv", 3, seed=1)
    assert len(replays) == 3 and all(r.followed for r in replays), [r.summary() for r in replays if not r.followed]
    if task.goal.x is not None:
        assert np.ravel(plan.phases[-1].x)[-1] == task.goal.x  # a slide's last sample, or a regrasp's x
    else:  # a turning goal: its angle, or its edge on the palm (the certificate checks both)
        assert plan.phases[-1].kind == "pivot"
    for seg in plan.segments:  # commands continuous (a squeezing finger's band unbounded below leapt to -4.5 N m)
        jump = float(np.max(np.abs(np.diff(seg.command)))) if seg.command.size > 1 else 0.0
        assert jump <= 0.1 * (float(np.max(np.abs(seg.command))) + task.torque_resolution), (stem, jump)


def test_goal_on_a_vertex_the_finger_cannot_touch_is_named(tmp_path):
    from qsplan.planner.plan.results import PlanFailure
    from qsplan.planner.plan.scripted import plan_task

    task = load_task(goal_task(tmp_path, {"x": -0.03, "left": "vertex:0"}))
    with pytest.raises(PlanFailure, match=r"the goal is unreachable on this palm.*left finger's inner edge on vertex 3"):
        plan_task(task)


def test_tables_agree_with_the_per_state_check():
    """The batched tables against check_contact_state (the per-state validity checker), state by state."""
    from qsplan.planner.search.tables import band_tables, table_grid
    from qsplan.planner.states.contact import check_contact_state

    for stem in ("demo_task", "pentagon_roof_task"):
        task = load_task(task_paths()[stem])
        tables = band_tables(task, task.hand.grasp_candidates(task.formation), table_grid(task.start_x, task.goal.x, 0.16, step=0.004,
                                                                           margin=0.02))  # fmt: skip
        G, n = tables.graph.shape
        for g in range(G):
            for i in range(0, n, 3):
                for e, d in ((0, 0), (1, 1)):
                    c = check_contact_state(task, tables.x[i], tables.efforts[e], (-1.0, 1.0)[d],
                                            grasp=tables.grasps[g].grasp)  # fmt: skip
                    if not tables.graph.valid[g, i]:
                        assert not c.ok
                        continue
                    lo, hi = tables.lower[g, e, d, i], tables.upper[g, e, d, i]
                    if np.isnan(lo):
                        assert not c.ok or c.reason
                        continue
                    assert (c.lower, c.upper) == (lo, hi)
                    assert c.ok == (hi - lo >= task.torque_resolution)


def test_cli_sequence_planner_option(tmp_path, capsys):
    """``qsplan plan --sequence-planner``: the search is recorded in plan.json's metadata."""
    import json

    from qsplan.planner.cli.main import main

    out = tmp_path / "out"
    code = main(["plan", str(demo_task_path()), "--out", str(out), "--sequence-planner", "BITstar", "--no-plots",
                 "--verify", "0", "--quiet"])  # fmt: skip
    assert code == 0
    meta = json.loads((out / "plan.json").read_text())["metadata"]
    assert meta["sequence"][-1]["planner"] == "BITstar" and meta["sequence"][0]["kind"] == "slide"
    assert "sequence found by the 'BITstar' search" in capsys.readouterr().out


def test_single_link_fingers_have_one_grasp_at_each_x():
    """Why the paper's hand never needs a regrasp onto another feature: a single-link finger turning about a fixed
    axis meets a convex workpiece on the palm in one configuration only, so at each workpiece x at most one
    candidate grasp is valid (checked on every bundled hand, 1 mm apart over the whole palm)."""
    from qsplan.planner.search.tables import band_tables, table_grid

    seen = set()
    for path in task_paths().values():
        task = load_task(path)
        if not task.hand.accelerated:  # a described hand (multi-link fingers, jaws): other tests
            continue
        key = (task.hand.workpiece.tobytes(), task.hand.paper.finger_length, task.hand.paper.finger_base)
        if key in seen:
            continue
        seen.add(key)
        grasps = task.hand.grasp_candidates(task.formation)
        tables = band_tables(task, grasps, table_grid(-0.15, 0.15, 0.16, step=0.001, margin=0.0))
        assert tables.graph.valid.sum(axis=0).max() <= 1, task.name
    assert len(seen) >= 3  # the quadrilateral (16 cm fingers), the pentagon (11 cm), the trapezoid (8 cm)


@pytest.mark.parametrize("seed", range(3))
def test_random_goal_tasks_plan_or_say_why(seed):
    """Seeded random workpieces, fingers, starts (on a grasp valid there) and goals: a plan, or a PlanFailure /
    QsplanError with a message; never another exception (a scene the polygons cannot give crashed the tables)."""
    from dataclasses import replace

    from qsplan.hands.paper_hand.grasp_geometry import grasp_configurations
    from qsplan.hands.paper_hand.grasps import OnVertex
    from qsplan.planner.plan.results import PlanFailure
    from qsplan.planner.plan.scripted import plan_task

    rng = np.random.default_rng(seed)
    for _ in range(8):
        w, h = rng.uniform(0.04, 0.09), rng.uniform(0.03, 0.1)
        top = sorted(rng.uniform(0.0, w, int(rng.integers(1, 4))))[::-1]
        pts = [[0.0, 0.0], [w, 0.0]] + [[float(x), float(h * rng.uniform(0.6, 1.0))] for x in top]
        x0 = float(rng.uniform(-0.03, 0.03))
        try:
            task = make_task({"workpiece": pts, "finger_length": float(rng.uniform(0.06, 0.17))}, x0,
                             goal={"x": x0 + float(rng.choice([-1, 1]) * rng.uniform(0.002, 0.04))})  # fmt: skip
        except QsplanError:
            continue
        for g in task.hand.grasp_candidates(task.formation):
            if grasp_configurations(task.hand.paper, g, np.array([x0])).ok[0]:
                side = [("inner", None) if isinstance(p, OnVertex) else ("edge", p.edge) for p in (g.left, g.right)]
                task = replace(task, start_features=tuple(side))
                break
        try:
            plan_task(task)
        except (PlanFailure, QsplanError) as exc:
            assert str(exc).strip() and "\n" not in str(exc)
