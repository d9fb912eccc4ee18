"""Every failure path of every goal kind writes its report (issue 31, items 2 and 3).

For each kind of failure (a goal by x, by waypoints, by theta, by palm; the paper hand, the two-link hand, the
parallel jaw) ``qsplan plan`` with the plots on and off exits 2 with one line naming the report, and writes
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
from qsplan.planner.plan.reorient import AFTER_SLIDE
from qsplan.planner.task.task import task_paths

#: ``planner_status`` of a task refused from its geometry (a position beyond the palm).
NOT_RUN_GEOMETRY = "not run (refused from the task's geometry)"

#: The demo's workpiece as the bundled tasks write it, and the README's pentagon: its left sides do not fit along the
#: left finger at a flush instant (the upper one reaches past the fingertip, the lower one below the joint).
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
    "theta counter-clockwise": ("reorient_task", [("\ntheta = -0.5", "\ntheta = 0.5")], "goal not served",
                                NOT_RUN_GOAL),
    "theta past the slip reversal": ("reorient_task", [("\ntheta = -0.5", "\ntheta = -0.85")],
                                     "invalid configuration", AFTER_SLIDE),
    "theta far past it": ("reorient_task", [("\ntheta = -0.5", "\ntheta = -1.2")], "invalid configuration",
                          AFTER_SLIDE),
    "theta whose slide to the flush instant closes": ("reorient_task", [("range = [0.0, 0.2]", "range = [0.0, 0.9]")],
                                                      "no route (band closes)", SEARCHED_BANDS),
    "theta on a house whose slide step ends in an overlap": ("pentagon_task", [("waypoints = [0.02, -0.02]", ""),
                                                                                ("[friction]", "[goal]\ntheta = -0.3\n\n[friction]")],
                                                             "invalid configuration", NOT_RUN_INVALID),
    "theta on a pentagon with no left side the finger fits": ("reorient_task", [(DEMO_SHAPE, README_PENTAGON),
                                                                                ("\ntheta = -0.5", "\ntheta = -0.3")],
                                                              "goal not served", NOT_RUN_GOAL),
    "theta with the two-link hand": ("two_link_task", [("x = -0.03", "theta = -0.3")], "goal not served", NOT_RUN_GOAL),
    "theta with the parallel jaw": ("parallel_jaw_task", [("x = -0.02", "theta = -0.3")], "goal not served",
                                    NOT_RUN_GOAL),
    "palm vertex without theta": ("reorient_task", [("\ntheta = -0.5", '\npalm = "vertex:1" #')], "goal not served",
                                  NOT_RUN_GOAL),
    "palm edge of a tall quadrilateral": ("reorient_task", [("\ntheta = -0.5", '\npalm = "edge:1" #')],
                                          "invalid configuration", AFTER_SLIDE),
    "palm edge the pivot cannot land": ("reorient_edge_task", [('palm = "edge:1"', 'palm = "edge:3"')],
                                        "goal not served", NOT_RUN_GOAL),
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


@pytest.mark.parametrize("plots", [True, False], ids=["plots", "no-plots"])
@pytest.mark.parametrize("case", sorted(CASES))
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


def test_a_turn_stops_at_its_first_event_with_its_pose(tmp_path, capsys):
    """theta = -1.2 rad: the slip reversal at -45.69 deg comes before the overlap at -55 deg, and is reported there,
    with the workpiece's pose (turned) for the drawing."""
    task_file = _task_file(tmp_path, "reorient_task", [("\ntheta = -0.5", "\ntheta = -1.2")])
    report = _failed_run(tmp_path, capsys, task_file, plots=False)
    assert "contact right stops sliding at theta = -45.69 deg" in report["reason"]
    x, y, theta = report["pose"]
    assert report["x_m"] == x and -46.0 < theta * 180 / 3.141592653589793 < -45.69


def test_a_failed_step_of_a_route_names_the_step(tmp_path, capsys):
    task_file = _task_file(tmp_path, "reorient_task", [("range = [0.0, 0.2]", "range = [0.0, 0.9]")])
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
