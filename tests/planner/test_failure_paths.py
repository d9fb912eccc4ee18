"""Every failure path of every goal kind writes its report (issue 31, items 2 and 3).

For each kind of failure (a goal by x, by waypoints, by theta, by palm; the paper hand, the two-link hand, the
parallel jaw) ``qsplan plan`` with the plots on (and off: each report kind by default, every case in the slow run) exits 2 with one line naming the report, and writes
``failure.json`` (its ``kind`` and a ``planner_status`` that says what ran) and, with the plots, ``failure.png``;
no plan file.  Before: a turning goal that could not be planned crashed while drawing its failure
(``ax.axvline`` of a goal with no x), a goal the route refused wrote no report, a pentagon's turning goal leaked an
internal error about an edge the user never named, and a band that closed after the search had run was reported
as "not run (start or goal invalid)".
"""

from __future__ import annotations

import json

import pytest

from qsplan.planner.cli.main import main
from qsplan.planner.pipeline.run import CERTIFICATE_REFUSED
from qsplan.planner.plan.failure import NOT_RUN_BAND_AT_END, NOT_RUN_GOAL, NOT_RUN_INVALID, SEARCHED_BANDS
from qsplan.planner.plan.pivot import IN_SEARCH
from qsplan.planner.plan.turning import SEARCHED_FORMATIONS
from qsplan.planner.task.task import task_paths

#: ``planner_status`` of a task refused from its geometry (a position beyond the palm).
NOT_RUN_GEOMETRY = "not run (refused from the task's geometry)"

#: The demo's workpiece as the bundled tasks write it, and the README's pentagon (its pivots' fingers meet at once).
DEMO_SHAPE = "workpiece = [[0.0, 0.0], [0.080, 0.0], [0.085, 0.080], [0.008, 0.100]]"
README_PENTAGON = "workpiece = [[0.0, 0.0], [0.08, 0.0], [0.09, 0.06], [0.04, 0.1], [-0.01, 0.06]]"

#: One task per failure kind: ``(bundled task, [(old text, new text)], failure.json kind, planner_status)``.
CASES = {
    "x beyond the palm": ("demo_task", [("x = -0.04", "x = -0.5")], "beyond the palm", NOT_RUN_GEOMETRY),
    "x beyond the palm, parallel jaw": ("parallel_jaw_task", [("x = -0.02", "x = 0.3")], "beyond the palm",
                                        NOT_RUN_GEOMETRY),
    "x with crossing fingers at the start": ("pentagon_task", [("finger_length = 0.11", "finger_length = 0.16")],
                                             "invalid configuration", NOT_RUN_INVALID),
    "x whose bands close, two-link hand": ("two_link_task", [("range = [0.0, 0.2]", "range = [0.0, 0.9]")],
                                           "no route (band closes)", SEARCHED_BANDS),
    "x whose bands close, parallel jaw": ("parallel_jaw_task", [("range = [0.0, 0.2]", "range = [0.0, 0.9]")],
                                          "no route (band closes)", SEARCHED_BANDS),
    "waypoints whose band closes": ("scripted_regrasp_task", [("range = [0.0, 0.2]", "range = [0.0, 0.9]")],
                                    "band closes", NOT_RUN_BAND_AT_END),
    "theta counter-clockwise (its one pivot has no band)": ("reorient_task", [("\ntheta = -0.5", "\ntheta = 0.5")],
                                                             "invalid configuration", IN_SEARCH),
    "theta past the second piece's band": ("reorient_task", [("\ntheta = -0.5", "\ntheta = -0.85")],
                                           "invalid configuration", IN_SEARCH),
    "theta far past it": ("reorient_task", [("\ntheta = -0.5", "\ntheta = -1.2")], "no turn", SEARCHED_FORMATIONS),
    "theta whose slide to the flush instant closes": ("reorient_task", [("torque_resolution = 0.02",
                                                                         "torque_resolution = 0.3")],
                                                      "no route (band closes)", SEARCHED_BANDS),
    "theta on a house": ("pentagon_task", [("waypoints = [0.02, -0.02]", ""),
                                           ("[friction]", "[goal]\ntheta = -0.3\n\n[friction]")],
                         "no turn", SEARCHED_FORMATIONS),
    "theta on a pentagon whose pivots end at once": ("reorient_task", [(DEMO_SHAPE, README_PENTAGON),
                                                                       ("\ntheta = -0.5", "\ntheta = -0.3")],
                                                     "no turn", SEARCHED_FORMATIONS),
    "theta with the two-link hand": ("two_link_task", [("x = -0.03", "theta = -0.3")], "no turn", SEARCHED_FORMATIONS),
    "theta with the parallel jaw": ("parallel_jaw_task", [("x = -0.02", "theta = -0.3")], "no turn",
                                    SEARCHED_FORMATIONS),
    "palm vertex without theta": ("reorient_task", [("\ntheta = -0.5", '\npalm = "vertex:1" #')], "goal not served",
                                  NOT_RUN_GOAL),
    "palm edge of a tall quadrilateral": ("reorient_task", [("\ntheta = -0.5", '\npalm = "edge:1" #')], "no turn",
                                          SEARCHED_FORMATIONS),
    "palm edge no pivot lands": ("reorient_edge_task", [('palm = "edge:1"', 'palm = "edge:3"')], "no turn",
                                 SEARCHED_FORMATIONS),
}


def _task_file(tmp_path, source: str, edits) -> str:
    text = task_paths()[source].read_text()
    for old, new in edits:
        assert old in text, (source, old)
        text = text.replace(old, new)
    path = tmp_path / f"{source}_edited.toml"
    path.write_text(text)
    return str(path)


def _failed_run(tmp_path, capsys, task_file, plots: bool) -> dict:
    """``qsplan plan`` on ``task_file``: asserts the failure's outputs and returns ``failure.json``."""
    out = tmp_path / ("plots" if plots else "no_plots")
    argv = ["plan", task_file, "--out", str(out), "--verify", "0", "--quiet"] + ([] if plots else ["--no-plots"])
    code = main(argv)
    stdout, err = capsys.readouterr()
    assert code == 2 and stdout == "" and err.count("\n") == 1 and "Traceback" not in err, err
    assert err.startswith("qsplan: error: ") and err.rstrip().endswith(f"(report: {out / 'failure.json'})")
    assert not (out / "plan.csv").exists() and not (out / "plan.json").exists()
    assert (out / "failure.png").is_file() == plots
    report = json.loads((out / "failure.json").read_text())
    assert report["message"] in err
    return report


def _runs() -> list:
    """Every case with the plots on (``failure.json`` and ``failure.png``), and with them off the first case of each
    ``failure.json`` kind by default, the others slow: the plots off change only whether ``failure.png`` is drawn,
    after the same planning, so one case of each kind shows that no drawing is made and the report is the same."""
    runs, kinds = [], set()
    for case in sorted(CASES):
        runs.append(pytest.param(case, True, id=f"{case}-plots"))
        kind = CASES[case][2]
        marks = () if kind not in kinds else (pytest.mark.slow,)
        kinds.add(kind)
        runs.append(pytest.param(case, False, id=f"{case}-no-plots", marks=marks))
    return runs


@pytest.mark.parametrize("case, plots", _runs())
def test_every_failure_writes_its_report(case, plots, tmp_path, capsys):
    source, edits, kind, status = CASES[case]
    report = _failed_run(tmp_path, capsys, _task_file(tmp_path, source, edits), plots)
    assert report["kind"] == kind
    assert report["planner_status"] == status


def test_the_failure_kinds_cover_every_goal_kind_and_hand():
    """The table holds a failure of each goal kind, and of each bundled hand."""
    goals = {case.split()[0] for case in CASES}
    assert goals == {"x", "waypoints", "theta", "palm"}
    hands = {h for case in CASES for h in ("two-link", "parallel jaw") if h in case}
    assert hands == {"two-link", "parallel jaw"}


def test_a_turn_no_formation_reaches_names_each_and_draws_the_farthest(tmp_path, capsys):
    """theta = -1.2 rad: the clockwise pivot passes its slip reversal (-45.69 deg) through a hold and ends where the
    right finger meets the workpiece (-55.05 deg); the counter-clockwise one does not serve the goal.  The report
    names both and carries the pose where the farthest ended (drawn by failure.png)."""
    task_file = _task_file(tmp_path, "reorient_task", [("\ntheta = -0.5", "\ntheta = -1.2")])
    report = _failed_run(tmp_path, capsys, task_file, plots=False)
    ended, other = report["formations"]
    assert ended["status"] == "ended" and "right finger overlap" in ended["why"]
    assert -55.2 < ended["theta_rad"] * 180 / 3.141592653589793 < -54.8
    assert other["status"] == "not this goal" and report["pose"] == ended["pose"]


def test_a_failed_step_of_a_route_names_the_step(tmp_path, capsys):
    """A resolution wider than the slide's band: the pivot is judged first (it passes), then its slide fails."""
    task_file = _task_file(tmp_path, "reorient_task", [("torque_resolution = 0.02", "torque_resolution = 0.3")])
    report = _failed_run(tmp_path, capsys, task_file, plots=False)
    assert report["route_step"].startswith("the slide to the flush instant (x = -0.0422")
    assert report["message"].startswith(f"no plan: {report['route_step']}: ")


def test_a_refused_certificate_writes_its_report_and_drawing(tmp_path, capsys, monkeypatch):
    """A plan whose certificate fails is not published: ``certificate.json``, ``failure.json`` and ``failure.png``
    are (the certifier made to refuse it, as a tampered file would be)."""
    from dataclasses import replace

    from qsplan.planner.certify import certify

    real = certify.certify_plan

    def refusing(*args, **kwargs):
        cert = real(*args, **kwargs)
        injected = certify.Violation(3, float("nan"), certify.KINDS[0], "injected by the test")
        return replace(cert, ok=False, violations=(injected,))

    monkeypatch.setattr(certify, "certify_plan", refusing)
    out = tmp_path / "out"
    code = main(["plan", "demo_task", "--out", str(out), "--verify", "0", "--quiet"])
    _, err = capsys.readouterr()
    assert code == 2 and err.count("\n") == 1
    report = json.loads((out / "failure.json").read_text())
    assert report["kind"] == "certification" and report["planner_status"] == CERTIFICATE_REFUSED
    assert (out / "failure.png").is_file() and (out / "certificate.json").is_file()
    assert not (out / "plan.csv").exists()
