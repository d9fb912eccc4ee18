"""The plan certifier: a genuine plan certifies; corrupted copies fail naming the row and the reason; ``qsplan verify``."""

import csv
import io
import json
import shutil

import numpy as np
import pytest

from qsplan.hands.paper_hand.two_finger import default_hand
from qsplan.mechanics import QsplanError
from qsplan.planner import export_plan, load_task, make_task, ompl_available, plan_task, task_paths
from qsplan.planner.certify.certify import certify_plan, read_plan, task_from_metadata
from qsplan.planner.cli import verify
from qsplan.planner.cli.options import Parser

@pytest.fixture(scope="module")
def short_plan(tmp_path_factory):
    """The default hand slid 1 cm left, regrasped, slid back: two 4S segments and a regrasp (~45 rows)."""
    if not ompl_available():
        pytest.skip("OMPL bindings not installed")
    task = make_task(default_hand(), 0.0, [-0.01, 0.0], name="short regrasp")
    out = tmp_path_factory.mktemp("short_plan")
    export_plan(plan_task(task), out)
    return task, out


def _corrupt(src, dst, edit):
    """Copy plan.csv from ``src`` into ``dst`` with ``edit(rows: list of dict)`` applied (plan.json dropped)."""
    dst.mkdir()
    with open(src / "plan.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    names = list(rows[0])
    edit(rows)
    with open(dst / "plan.csv", "w", newline="") as f:
        w = csv.DictWriter(f, names, lineterminator="\n")
        w.writeheader()
        w.writerows(rows)
    return dst


def _contact_row(rows, offset=5):
    """Index of an in-contact row inside the first segment."""
    return next(i for i, r in enumerate(rows) if r["mode"] != "free") + offset


@pytest.mark.parametrize("kw, match", [
    ({"n_random": -1}, "n_random"),
    ({"n_random": 1.5}, "n_random"),
    ({"force_margin": -0.1}, "force_margin"),
    ({"force_margin": float("nan")}, "force_margin"),
])  # fmt: skip
def test_bad_parameters_are_named(tmp_path, kw, match):
    with pytest.raises(QsplanError, match=match):
        certify_plan(tmp_path, load_task(task_paths()["demo_task"]), **kw)


@pytest.mark.parametrize("setup, match", [
    (lambda p: p, "neither plan.csv nor plan.json"),
    (lambda p: p / "missing", "no such file"),
    (lambda p: (p / "x.txt").write_text("x") and p / "x.txt", "expected a plan directory"),
    (lambda p: (p / "plan.csv").write_text("t,q_left\n0,1\n") and p, "lacks the column"),
    (lambda p: (p / "plan.json").write_text("{") and p / "plan.json", "not a plan JSON"),
])  # fmt: skip
def test_unreadable_plans_are_named(tmp_path, setup, match):
    with pytest.raises(QsplanError, match=match):
        read_plan(setup(tmp_path))


def test_metadata_without_the_task_names_the_record():
    """The plan's record is at fault, not an option the user gave (``qsplan verify`` without ``--task``)."""
    with pytest.raises(QsplanError, match="^metadata.task_record: missing: .*name the task file"):
        task_from_metadata({"task": "x"})
    with pytest.raises(QsplanError, match="^metadata.task_record: the task the plan records is not a task "):
        task_from_metadata({"task_record": {"version": 1}})


@pytest.mark.ompl
def test_genuine_plan_certifies(short_plan):
    task, out = short_plan
    cert = certify_plan(out, task, n_random=4, seed=3)
    assert cert.ok, "\n".join(map(str, cert.violations[:10]))
    assert cert.violations == () and sum(cert.counts.values()) == 0
    free = [r for r in cert.rows if r.mode == "free"]
    assert free and all(r.friction_points == 0 for r in free)
    assert all(r.friction_points == 16 + 4 for r in cert.rows if r.mode != "free")  # box: 2^4 corners + 4 draws
    assert cert.summary().startswith("certified: ")
    doc = json.loads(json.dumps(cert.to_dict(), allow_nan=False))
    assert doc["certified"] and doc["rows"] == len(cert.rows)
    # the modes set aside are degenerate to machine precision (a breaking finger's joint is free), never 4S
    assert "SSSS" not in doc["excluded_degenerate_modes"]
    # the same verdict from plan.json (nulls read as unbounded band sides)
    assert certify_plan(out / "plan.json", task, n_random=0).ok


@pytest.mark.ompl
def test_torque_outside_its_band_is_named(short_plan, tmp_path):
    task, out = short_plan
    state = {}

    def edit(rows):
        k = state["row"] = _contact_row(rows)
        e = rows[k]["effort_joint"]
        top = float(rows[k][f"tau_{e}_max"])
        edge = top if np.isfinite(top) else float(rows[k][f"tau_{e}_min"])
        rows[k][f"tau_{e}"] = repr(edge + 0.5 if np.isfinite(top) else edge - 0.5)

    bad = certify_plan(_corrupt(out, tmp_path / "bad", edit), task, n_random=0)
    k = state["row"]
    assert not bad.ok and {v.row for v in bad.violations} == {k}
    torque = [v for v in bad.violations if v.kind == "torque"]
    assert len(torque) == 1 and "outside its band" in torque[0].message and "0.5 N m past the edge" in torque[0].message
    assert bad.rows[k].violations and not bad.rows[k - 1].violations


@pytest.mark.ompl
def test_overlapping_fingers_are_named(short_plan, tmp_path):
    task, out = short_plan
    state = {}

    def edit(rows):  # both fingers leaning in at 0.3 rad: 16 cm fingers on joints 18 cm apart cross
        k = state["row"] = _contact_row(rows, 8)
        rows[k]["q_left"], rows[k]["q_right"] = repr(0.3), repr(np.pi - 0.3)

    bad = certify_plan(_corrupt(out, tmp_path / "bad", edit), task, n_random=0)
    k = state["row"]
    assert not bad.ok and {v.row for v in bad.violations} <= {k - 1, k}  # the step into row k too
    overlap = [v for v in bad.violations if v.kind == "overlap" and v.row == k]
    assert any(v.message.startswith("left finger / right finger overlap") for v in overlap)
    assert any(v.kind == "speed" and v.row == k - 1 for v in bad.violations)


@pytest.mark.ompl
def test_joint_beyond_its_limit_is_named(short_plan, tmp_path):
    task, out = short_plan
    state = {}

    def edit(rows):
        k = state["row"] = _contact_row(rows, 10)
        rows[k]["q_right"] = repr(float(task.joint_limits[1, 1]) + 0.01)

    bad = certify_plan(_corrupt(out, tmp_path / "bad", edit), task, n_random=0)
    k = state["row"]
    assert not bad.ok and {v.row for v in bad.violations} <= {k - 1, k}
    limit = [v for v in bad.violations if v.kind == "joint limit"]
    assert len(limit) == 1 and limit[0].row == k
    assert limit[0].message == "right joint at 3.1 rad, outside its limits [0.05, 3.09] rad"


def _verify(argv):
    parser = Parser(prog="qsplan")
    verify.add_parser(parser.add_subparsers(dest="command", required=True, parser_class=Parser))
    out = io.StringIO()
    return verify.run(parser.parse_args(["verify", *argv]), out), out.getvalue()


@pytest.mark.ompl
def test_verify_command(short_plan, tmp_path, capsys):
    task, out = short_plan
    code, text = _verify([str(out), "--random", "0"])  # the task from plan.json's metadata
    assert code == 0 and "as recorded in plan.json" in text and text.splitlines()[-1].startswith("certified: ")

    def edit(rows):
        rows[12]["q_left"] = repr(-0.2)

    bad = _corrupt(out, tmp_path / "bad", edit)
    shutil.copy(out / "plan.json", bad / "plan.json")  # the metadata, beside the corrupted CSV
    code, text = _verify([str(bad), "--random", "0"])
    assert code == 1 and "row 12 (t = " in text and "joint limit: left joint at -0.2 rad" in text
    assert text.splitlines()[-1].startswith("NOT certified: ")
    code, text = _verify([str(bad), "--random", "0", "--json"])
    doc = json.loads(text)
    assert code == 1 and not doc["certified"] and doc["counts"]["joint limit"] == 1
    assert any(v["row"] == 12 and v["kind"] == "joint limit" for v in doc["violations"])

    (bad / "plan.json").unlink()
    code, _ = _verify([str(bad)])
    assert code == 2 and "--task" in capsys.readouterr().err
    code, _ = _verify([str(tmp_path / "nowhere"), "--task", str(task_paths()["demo_task"])])
    err = capsys.readouterr().err
    assert code == 2 and len(err.strip().splitlines()) == 1 and "no such file" in err
    code, _ = _verify([str(out), "--random", "-2"])
    assert code == 2 and "--random" in capsys.readouterr().err


@pytest.mark.slow
@pytest.mark.ompl
def test_pentagon_task_is_certified_or_refused(tmp_path):
    from qsplan.planner import NoAnswerError

    task = load_task(task_paths()["pentagon_task"])
    try:
        plan = plan_task(task)
    except NoAnswerError:
        return  # refused: no plan is presented
    export_plan(plan, tmp_path)
    cert = certify_plan(tmp_path, task, n_random=0)
    assert cert.ok, cert.summary() + "\n" + "\n".join(map(str, cert.violations[:5]))


def _same_certificates(a, b):
    """Two certificates of one plan agree row by row (verdicts, violations, excluded modes); times aside."""
    assert a.rows == b.rows and a.violations == b.violations and a.counts == b.counts and a.ok == b.ok
    assert a.to_dict()["excluded_degenerate_modes"] == b.to_dict()["excluded_degenerate_modes"]


def _flip_velocity(rows):  # the velocity-controlled finger driven backwards: the workpiece moves the other way
    for k in range(_contact_row(rows, 0), _contact_row(rows, 6)):
        v = "right" if rows[k]["effort_joint"] == "left" else "left"
        rows[k][f"qd_{v}"] = repr(-float(rows[k][f"qd_{v}"]))


def _torque_far_outside(rows):  # a torque far beyond its band: another mode wins, or the planned one fails
    for k in range(_contact_row(rows, 0), _contact_row(rows, 4)):
        e = rows[k]["effort_joint"]
        rows[k][f"tau_{e}"] = repr(float(rows[k][f"tau_{e}"]) * 4.0 + 10.0)  # beyond the bands (upper edges ~2 N m)


def _stop_velocity(rows):  # no driving speed: every mode degenerate (zero speeds), all set aside
    for k in range(_contact_row(rows, 0), _contact_row(rows, 3)):
        rows[k][f"qd_{'right' if rows[k]['effort_joint'] == 'left' else 'left'}"] = "0.0"


def _torque_zero(rows):
    for k in range(_contact_row(rows, 2), _contact_row(rows, 5)):
        rows[k][f"tau_{rows[k]['effort_joint']}"] = "0.0"


@pytest.mark.ompl
@pytest.mark.parametrize("edit, kw, kinds", [
    pytest.param(None, {"n_random": 3, "seed": 5}, set(), marks=pytest.mark.slow),
    pytest.param(None, {"n_random": 0, "force_margin": 50.0}, {"force margin"}, marks=pytest.mark.slow),
    pytest.param(_flip_velocity, {"n_random": 2}, {"motion"}, marks=pytest.mark.slow),
    pytest.param(_torque_far_outside, {"n_random": 2}, {"torque", "mode"}, marks=pytest.mark.slow),
    pytest.param(_torque_zero, {"n_random": 1}, {"torque"}, marks=pytest.mark.slow),
    pytest.param(_stop_velocity, {"n_random": 1}, {"mode"}, marks=pytest.mark.slow),
])  # fmt: skip
def test_batched_certificate_is_the_per_vector_one(short_plan, tmp_path, edit, kw, kinds):
    """All friction vectors of a row in one batch give the certificate of one solve per vector (4-15 s each: the
    reference solves once per vector; all slow, while ``test_certify_batched.py`` checks the whole plan's mode checks,
    the only part ``batched`` changes, against the row-by-row reference on genuine plans and every kind of failure by
    default)."""
    task, out = short_plan
    src = out if edit is None else _corrupt(out, tmp_path / "bad", edit)
    fast = certify_plan(src, task, **kw)
    reference = certify_plan(src, task, batched=False, **kw)
    _same_certificates(fast, reference)
    assert kinds <= {v.kind for v in fast.violations}


@pytest.mark.slow
@pytest.mark.ompl
def test_demo_plan_batched_certificate_is_the_per_vector_one(tmp_path):
    from qsplan.planner.task.task import demo_task_path

    task = load_task(demo_task_path())
    export_plan(plan_task(task), tmp_path)
    kw = {"force_margin": task.force_margin.normal}
    fast = certify_plan(tmp_path, task, **kw)
    _same_certificates(fast, certify_plan(tmp_path, task, batched=False, **kw))
    assert fast.ok
