"""A start or goal beyond the palm (issue 21, item 5): refused once, from the task's geometry, before any table or
grid is built, with a ``failure.json`` naming the range of x that is possible; no crash for x on the palm near
its ends; a described hand's task with its goal at its start refused in one line, no warning text."""

import json
import re
import subprocess
import sys
from dataclasses import replace

import numpy as np
import pytest
from shapely.geometry import Polygon

from qsplan.mechanics import QsplanError
from qsplan.planner.cli.main import main
from qsplan.planner.plan.failure import PalmReport, palm_report
from qsplan.planner.plan.results import PlanFailure
from qsplan.planner.search.tables import table_grid
from qsplan.planner.task.goal import palm_x_range
from qsplan.planner.task.task import load_task, make_task, task_paths

#: The bundled tasks' workpiece (all but the jaw's hexagon) and the palm's top of every bundled hand (m).
QUAD = [[0.0, 0.0], [0.080, 0.0], [0.085, 0.080], [0.008, 0.100]]
HEXAGON = [[0.0, 0.0], [0.06, 0.0], [0.08, 0.05], [0.05, 0.09], [0.01, 0.09], [-0.02, 0.05]]
PALM = 0.16


def expected_range(polygon, lo=-PALM, hi=PALM):
    """Where the bottom edge (vertices 0, 1 as written) lies on the palm ``[lo, hi]``, from the centroid (shapely)."""
    c = Polygon(polygon).centroid.x
    return lo - (polygon[0][0] - c), hi - (polygon[1][0] - c)


def palm_polygon(lo, hi) -> str:
    """A 20 mm palm whose top runs from ``lo`` to ``hi`` (m), as a hand file writes it."""
    return f"[[{lo}, -0.02], [{hi}, -0.02], [{hi}, 0.0], [{lo}, 0.0]]"


def bundled_variant(tmp_path, name, field, x):
    """The bundled task ``name`` with ``field`` (``start``, ``goal`` or ``waypoint``: the last) set to ``x``."""
    text = task_paths()[name].read_text()
    pattern = {"start": r"^start_x = .*$", "goal": r"^x = .*$", "waypoint": r"^waypoints = .*$"}[field]
    value = f"[-0.04, {x}]" if field == "waypoint" else str(x)
    text, n = re.subn(pattern, pattern.split(" = ")[0].lstrip("^") + f" = {value}", text, flags=re.M)
    assert n == 1
    path = tmp_path / f"{name}.toml"  # a bundled hand is named, not a path: the copy reads the same hand
    path.write_text(text)
    return path


@pytest.mark.parametrize("name, field, x, side, polygon", [
    ("demo_task", "goal", 0.17, "right", QUAD),
    ("demo_task", "goal", -0.17, "left", QUAD),
    ("demo_task", "start", 0.17, "right", QUAD),
    ("demo_task", "start", -0.125, "left", QUAD),
    ("scripted_regrasp_task", "waypoint", 0.17, "right", QUAD),
    ("scripted_regrasp_task", "start", -0.17, "left", QUAD),
    ("two_link_task", "goal", 0.17, "right", QUAD),
    ("two_link_task", "start", -0.17, "left", QUAD),
    ("parallel_jaw_task", "goal", -0.135, "left", HEXAGON),
    ("parallel_jaw_task", "start", 0.17, "right", HEXAGON),
])  # fmt: skip
def test_beyond_the_palm_is_refused_from_the_geometry(tmp_path, capsys, monkeypatch, name, field, x, side, polygon):
    from qsplan.planner.plan import autoplan, scripted as plan

    def never(*args, **kwargs):
        raise AssertionError("planned a task whose start or goal is beyond the palm")

    # refused by plan_task before any table, grid or grasp is built (by any of its planners)
    monkeypatch.setattr(autoplan, "plan_automatic", never)
    monkeypatch.setattr(plan, "check_configurations", never)
    path = bundled_variant(tmp_path, name, field, x)
    out = tmp_path / "out"
    code = main(["plan", str(path), "--out", str(out), "--no-plots", "--verify", "0", "--quiet"])
    stdout, err = capsys.readouterr()
    lo, hi = expected_range(polygon)
    assert code == 2 and stdout == "" and err.count("\n") == 1 and err.startswith("qsplan: error: no plan: ")
    end = -PALM if side == "left" else PALM
    assert f"x = {x:.4g} m" in err and f"beyond the palm's {side} end at {end:.4g} m" in err
    assert f"rests on the palm for x in [{lo:.4g}, {hi:.4g}] m" in err and "failure.json" in err
    report = json.loads((out / "failure.json").read_text())
    assert report["kind"] == "beyond the palm" and report["message"] in err and report["x_m"] == x
    assert report["field"] == {"start": "motion.start_x", "goal": "goal.x", "waypoint": "motion.waypoints[1]"}[field]
    assert report["x_range_m"] == pytest.approx([lo, hi], abs=1e-12)


def test_palm_range_is_exact_for_an_asymmetric_palm(tmp_path):
    hand_file = (task_paths()["two_link_task"].parent.parent.parent / "hands" / "data" / "two_link_hand.toml")
    text = hand_file.read_text().replace("[[-0.16, -0.02], [0.16, -0.02], [0.16, 0.0], [-0.16, 0.0]]",
                                         palm_polygon(-0.10, 0.13))
    (tmp_path / "asym.toml").write_text(text)
    task = make_task({"file": str(tmp_path / "asym.toml"), "workpiece": QUAD}, 0.0, goal={"x": -0.03})
    lo, hi = palm_x_range(task.hand)
    assert (lo, hi) == pytest.approx(expected_range(QUAD, -0.10, 0.13), abs=1e-12)
    at = lambda x: replace(task, goal=replace(task.goal, x=x))  # noqa: E731
    assert palm_report(at(lo)) is None and palm_report(at(hi)) is None  # the ends are on the palm
    for x, side, end in ((np.nextafter(lo, -1.0), "left", -0.10), (np.nextafter(hi, 1.0), "right", 0.13)):
        r = palm_report(at(x))
        assert isinstance(r, PalmReport) and r.side == side and r.palm_end == pytest.approx(end, abs=1e-12)
        assert r.field == "goal.x" and r.where == "the goal"


def test_table_grid_stays_within_its_limits():
    lo, hi = expected_range(QUAD)
    for start, goal in ((0.0, -0.04), (hi, lo), (lo + 1e-9, lo), (hi - 0.003, hi)):
        grid = table_grid(start, goal, (lo, hi))
        assert grid.min() >= lo and grid.max() <= hi and start in grid and goal in grid
        assert np.all(np.diff(grid) > 0) and np.max(np.diff(grid)) <= 5e-4 * (1 + 1e-9)


@pytest.mark.parametrize("start, goal, match", [
    (0.0, 0.17, "goal_x: 0.17 m is outside"),  # the IndexError of issue 21, item 5
    (-0.17, 0.0, "start_x: -0.17 m is outside"),
])  # fmt: skip
def test_table_grid_refuses_ends_beyond_its_limits(start, goal, match):
    with pytest.raises(QsplanError, match=match):
        table_grid(start, goal, 0.16)


#: A paper hand whose fingers reach the ends of a short palm: x near the ends has grasps, and bands.
SHORT_PALM = {"workpiece": QUAD, "palm_halfwidth": 0.06}


@pytest.mark.slow
@pytest.mark.ompl
@pytest.mark.filterwarnings("error")
@pytest.mark.parametrize("kind", ["waypoints", "goal"])
def test_no_crash_near_the_palms_ends(tmp_path, kind):
    """Start or goal on the palm near its ends (ends included): a certified plan or a named failure, nothing else;
    a hair beyond an end: refused from the geometry."""
    from qsplan.planner.pipeline.run import run_plan

    lo, hi = palm_x_range(make_task(SHORT_PALM, 0.0, waypoints=[0.01]).hand)
    assert (lo, hi) == pytest.approx(expected_range(QUAD, -0.06, 0.06), abs=1e-12)
    outcomes = []
    for x in (lo, lo + 1e-9, lo + 1e-4, hi - 1e-4, hi - 1e-9, hi, np.nextafter(lo, -1.0), np.nextafter(hi, 1.0)):
        for which in ("start", "goal"):
            ends = (x, 0.0) if which == "start" else (0.0, x)
            task = make_task(SHORT_PALM, ends[0], **({"waypoints": [ends[1]]} if kind == "waypoints"
                                                     else {"goal": {"x": ends[1]}}))  # fmt: skip
            try:
                run = run_plan(task, tmp_path / f"{which}{x}", plots=False, verify=0)
                assert lo <= x <= hi and run.certificate.ok
                outcomes.append("plan")
            except PlanFailure as exc:
                beyond = isinstance(exc.report, PalmReport)
                assert beyond == (not lo <= x <= hi) and exc.report_path.is_file()
                outcomes.append("beyond" if beyond else "no plan")
    assert outcomes.count("beyond") == 4 and "plan" in outcomes


@pytest.mark.slow
@pytest.mark.ompl
@pytest.mark.filterwarnings("error")
def test_no_crash_at_the_ends_of_a_chain_hands_palm(tmp_path):
    """A described two-link hand on a short palm: start at the palm's left end, goal at its right end."""
    from qsplan.planner.pipeline.run import run_plan

    hand_file = (task_paths()["two_link_task"].parent.parent.parent / "hands" / "data" / "two_link_hand.toml")
    (tmp_path / "short.toml").write_text(hand_file.read_text().replace("[[-0.16, -0.02], [0.16, -0.02], [0.16, 0.0], "
                                                                       "[-0.16, 0.0]]", palm_polygon(-0.06, 0.06)))
    hand = {"file": str(tmp_path / "short.toml"), "workpiece": QUAD}
    lo, hi = palm_x_range(make_task(hand, 0.0, goal={"x": 0.01}).hand)
    for start, goal in ((lo, 0.0), (0.0, hi)):
        try:
            task = make_task(hand, start, goal={"x": goal})
            run = run_plan(task, tmp_path / f"o{start}{goal}", plots=False, verify=0)
            assert run.certificate.ok
        except PlanFailure as exc:
            assert not isinstance(exc.report, PalmReport) and exc.report_path.is_file()


def test_chain_goal_at_its_start_is_one_line_without_warnings(tmp_path):
    """``goal.x == start_x`` on a described hand: one line on stderr (no RuntimeWarning lines before it), exit 2."""
    path = bundled_variant(tmp_path, "two_link_task", "goal", 0.0)
    argv = ["plan", str(path), "--out", str(tmp_path / "o"), "--no-plots", "--verify", "0", "--quiet"]
    proc = subprocess.run([sys.executable, "-m", "qsplan.planner.cli", *argv], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2 and proc.stdout == ""
    assert proc.stderr.count("\n") == 1 and proc.stderr.startswith("qsplan: error: goal: the start already meets")
    assert "nothing to plan" in proc.stderr and not (tmp_path / "o").exists()


@pytest.mark.filterwarnings("error")
def test_jaw_goal_at_its_start_is_refused_before_planning(tmp_path):
    task = load_task(bundled_variant(tmp_path, "parallel_jaw_task", "goal", 0.0))
    from qsplan.planner.plan.scripted import plan_task

    with pytest.raises(QsplanError, match="goal: the start already meets the goal"):
        plan_task(task)
