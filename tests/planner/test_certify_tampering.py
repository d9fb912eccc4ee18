"""Tampered plans are never certified (issue 21): every kind of edit an adversary or a slip makes to an exported
plan, in either file or both, on a paper-hand plan with a regrasp, a two-link plan with a regrasp and a jaw plan.

Each tampered copy goes through ``qsplan verify`` (the task named, not read back from the tampered metadata):
exit 1 naming the row (or the plan as a whole) and the reason, or exit 2 for unreadable input; never exit 0.
Edits of both files keep them equal cell by cell, so the row checks themselves must catch them; edits of
``plan.json`` alone must be caught as a disagreement, and again by the rows when ``plan.json`` is the only file.
"""

import contextlib
import csv
import io
import json
import math
import shutil

import pytest

from qsplan.planner import ompl_available, task_paths
from qsplan.planner.cli import main
from qsplan.planner.plan.table import is_word_column

pytestmark = pytest.mark.ompl

#: The plans tampered with: a task file (bundled name) per hand; the paper hand's is written here (two 1 cm slides
#: and a regrasp between them: the smallest plan with both kinds of phase).
SHORT_PAPER_TASK = """
name = "short regrasp"
[hand]
file = "paper_hand"
workpiece = [[0.0, 0.0], [0.080, 0.0], [0.085, 0.080], [0.008, 0.100]]
[motion]
start_x = 0.0
waypoints = [-0.01, 0.0]
[friction]
range = [0.0, 0.2]
[controller]
torque_resolution = 0.02
"""


@pytest.fixture(scope="module")
def plans(tmp_path_factory):
    """``{name: (task path, plan dir)}`` of three genuine, certified plans."""
    if not ompl_available():
        pytest.skip("OMPL bindings not installed")
    root = tmp_path_factory.mktemp("tamper")
    (root / "short.toml").write_text(SHORT_PAPER_TASK)
    tasks = {"paper": root / "short.toml", "two_link": task_paths()["two_link_regrasp_task"],
             "jaw": task_paths()["parallel_jaw_task"]}  # fmt: skip
    out = {}
    for name, task in tasks.items():
        code, text, err = _run(["plan", str(task), "--out", str(root / name), "--no-plots", "--quiet", "--verify", "0"])
        assert code == 0, err
        out[name] = (task, root / name)
    return out


def _run(argv):
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(argv)
    return code, out.getvalue(), err.getvalue()


def _read(plan_dir):
    with open(plan_dir / "plan.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    return rows, json.loads((plan_dir / "plan.json").read_text())


def _json_value(column, text):
    if is_word_column(column):
        return text
    if column == "phase":
        return int(float(text))
    x = float(text)
    return x if math.isfinite(x) else None


def _write(dst, rows, doc, json_edit=None):
    """Both files from ``rows`` (the JSON's data rebuilt from them, as the export writes it), then ``json_edit(doc)``."""
    dst.mkdir()
    names = list(rows[0])
    with open(dst / "plan.csv", "w", newline="") as f:
        w = csv.DictWriter(f, names, lineterminator="\n")
        w.writeheader()
        w.writerows(rows)
    doc = json.loads(json.dumps(doc))
    doc["data"] = {c: [_json_value(c, r[c]) for r in rows] for c in names}
    if json_edit is not None:
        json_edit(doc)
    (dst / "plan.json").write_text(json.dumps(doc, indent=1))
    return dst


def _contact(rows, offset=3):
    return next(i for i, r in enumerate(rows) if r["mode"] != "free") + offset


def _free(rows):
    return [i for i, r in enumerate(rows) if r["mode"] == "free"]


# --- edits of both files: (rows, doc) -> None, in place -----------------------------------------------------------

def drop_first_row(rows, doc):
    del rows[0]


def drop_second_half(rows, doc):
    del rows[len(rows) // 2:]


def relabel_slide_as_free(rows, doc):
    """A stretch of in-contact rows relabelled as a regrasp: the workpiece moves while nothing holds it."""
    k = _contact(rows)
    for r in rows[k : k + 10]:
        for c in r:
            if c.startswith("tau_") or c == "margin":
                r[c] = "nan"
            if c.startswith("qd_") and r[c] == "nan":
                r[c] = "0.0"
        r["mode"], r["effort_joint"] = "free", "none"


def raise_during_regrasp(rows, doc):
    """The workpiece 2 mm above the palm on a regrasp's rows."""
    for i in _free(rows):
        rows[i]["y_workpiece"] = repr(float(rows[i]["y_workpiece"]) + 0.002)


def _effort_cells(rows, k):
    e = rows[k]["effort_joint"]
    return f"tau_{e}", f"tau_{e}_min", f"tau_{e}_max"


def widen_band(rows, doc):
    """An exported band widened to unbounded on both sides."""
    k = _contact(rows)
    _, lo, hi = _effort_cells(rows, k)
    rows[k][lo], rows[k][hi] = "-inf", "inf"


def narrow_band(rows, doc):
    """An exported band narrowed to 2e-6 around its command (under the torque resolution)."""
    k = _contact(rows)
    tau, lo, hi = _effort_cells(rows, k)
    t = float(rows[k][tau])
    rows[k][lo], rows[k][hi], rows[k]["margin"] = repr(t - 1e-6), repr(t + 1e-6), repr(1e-6)


def double_margin(rows, doc):
    k = _contact(rows)
    rows[k]["margin"] = repr(2 * float(rows[k]["margin"]))


def bump_phase(rows, doc):
    k = _contact(rows)
    rows[k]["phase"] = str(int(rows[k]["phase"]) + 1)


def swap_times(rows, doc):
    k = _contact(rows)
    rows[k]["t"], rows[k + 1]["t"] = rows[k + 1]["t"], rows[k]["t"]


def shift_torque_out(rows, doc):
    """A torque command moved past its band's upper edge (kept inside the band's claim)."""
    k = _contact(rows)
    tau, lo, hi = _effort_cells(rows, k)
    top = float(rows[k][hi])
    rows[k][tau] = repr((top + 0.5) if math.isfinite(top) else float(rows[k][lo]) - 0.5)


def misstate_phase_rows(rows, doc):
    doc["metadata"]["phases"][0]["rows"] += 3


def misstate_friction(rows, doc):
    doc["metadata"]["friction"]["range"] = [0.0, 0.5]


def swap_controls(rows, doc):
    """The control cells of one in-contact row swapped: the torque joint labelled velocity and a velocity one torque."""
    k = _contact(rows)
    cells = [c for c in rows[k] if c.startswith("control_")]
    values = [rows[k][c] for c in cells]
    for c, v in zip(cells, values[1:] + values[:1]):
        rows[k][c] = v


def no_stop_at_phase_end(rows, doc):
    """The first phase ends at speed (issue 24): its last row's speed scale and velocity commands as the row before."""
    k = max(i for i, r in enumerate(rows) if r["phase"] == rows[0]["phase"])
    for c in rows[k]:
        if c.startswith("qd_") or c == "speed_scale":
            rows[k][c] = rows[k - 1][c]


def rush_the_plan(rows, doc):
    """Every time quartered: the same commands, four times the accelerations and sixteen times the inertial load."""
    for r in rows:
        r["t"] = repr(0.25 * float(r["t"]))


def drop_speed_scale(rows, doc):
    """The time scaling's column removed: nothing says the phases start and end at rest."""
    for r in rows:
        del r["speed_scale"]


def repeat_row_at_its_time(rows, doc):
    """An in-contact row written twice, at one time (a divide by zero in the time scaling's rule, once)."""
    k = _contact(rows)
    rows.insert(k, dict(rows[k]))


def renumber_every_phase(rows, doc):
    """Every row's phase one higher: the plan starts in phase 1 (a divide by zero in the timing checks, once)."""
    for r in rows:
        r["phase"] = str(int(r["phase"]) + 1)


def change_one_mode_letter(rows, doc):
    """One in-contact row's last letter changed (SSSS -> SSSR): not a mode of the row's scene with its control
    partition (eq. 29), which the band recomputation once raised on (exit 2, naming no row)."""
    k = _contact(rows, 5)
    m = rows[k]["mode"]
    rows[k]["mode"] = m[:-1] + ("R" if m[-1] != "R" else "S")


BOTH = [drop_first_row, drop_second_half, relabel_slide_as_free, raise_during_regrasp, widen_band, narrow_band,
        double_margin, bump_phase, swap_times, shift_torque_out, misstate_phase_rows, misstate_friction,
        swap_controls, no_stop_at_phase_end, rush_the_plan, drop_speed_scale, repeat_row_at_its_time,
        renumber_every_phase, change_one_mode_letter]  # fmt: skip

#: The edits each hand's plan gets: every edit on the paper hand's (certified in ~1 s); on the chain hands' (~3 s
#: each) those whose checks read the hand (its start and goal, its regrasp, its bands), so the suite stays short.
EDITS = {"paper": BOTH,
         "two_link": [drop_first_row, drop_second_half, relabel_slide_as_free, raise_during_regrasp, widen_band,
                      narrow_band, double_margin, renumber_every_phase, change_one_mode_letter],
         "jaw": [drop_first_row, drop_second_half, relabel_slide_as_free, widen_band, narrow_band, swap_controls,
                 no_stop_at_phase_end]}  # fmt: skip
CASES = [(hand, edit) for hand, edits in EDITS.items() for edit in edits]

#: The kinds each edit must be named by (at least one of them).
EXPECTED = {
    "swap_controls": {"control"},
    "no_stop_at_phase_end": {"timing"},
    "rush_the_plan": {"acceleration"},
    "drop_speed_scale": {"timing"},
    "drop_first_row": {"start", "time"},
    "drop_second_half": {"goal"},
    "relabel_slide_as_free": {"rest"},
    "raise_during_regrasp": {"rest"},
    "widen_band": {"band"},
    "narrow_band": {"band"},
    "double_margin": {"margin"},
    "bump_phase": {"phase"},
    "swap_times": {"time"},
    "shift_torque_out": {"torque"},
    "misstate_phase_rows": {"metadata"},
    "misstate_friction": {"metadata"},
    "repeat_row_at_its_time": {"time"},
    "renumber_every_phase": {"phase"},
    "change_one_mode_letter": {"mode"},
}


# --- edits of plan.json alone: doc -> None ---------------------------------------------------------------------

def _json_contact(doc, offset=3):
    return next(i for i, m in enumerate(doc["data"]["mode"]) if m != "free") + offset


def json_torque_outside(doc):
    k = _json_contact(doc)
    e = doc["data"]["effort_joint"][k]
    top, bottom = doc["data"][f"tau_{e}_max"][k], doc["data"][f"tau_{e}_min"][k]
    doc["data"][f"tau_{e}"][k] = top + 0.5 if top is not None else bottom - 0.5  # null: unbounded


def json_joint_moved(doc):
    k = _json_contact(doc)
    name = next(c for c in doc["columns"] if c.startswith("q_"))
    doc["data"][name][k] += 0.3


def json_time_out_of_order(doc):
    k = _json_contact(doc)
    t = doc["data"]["t"]
    t[k], t[k + 1] = t[k + 1], t[k]


JSON_ONLY = {"json_torque_outside": (json_torque_outside, {"torque"}),
             "json_joint_moved": (json_joint_moved, {"speed", "motion", "contact", "overlap"}),
             "json_time_out_of_order": (json_time_out_of_order, {"time"})}  # fmt: skip


def _verify(task, plan_dir):
    code, out, err = _run(["verify", str(plan_dir), "--task", str(task), "--random", "0", "--json"])
    doc = json.loads(out) if out.strip() else None
    return code, doc, err


def _kinds(doc) -> set:
    return {v["kind"] for v in doc["violations"]}


def test_genuine_plans_certify(plans):
    for name, (task, plan_dir) in plans.items():
        code, doc, err = _verify(task, plan_dir)
        assert code == 0 and doc["certified"], (name, doc and doc["violations"][:3], err)
        assert len(doc["files"]) == 2 and [c["kind"] for c in doc["checks"]][:3] == ["input", "files", "metadata"]


@pytest.mark.parametrize("hand, edit", CASES, ids=[f"{h}-{e.__name__}" for h, e in CASES])
def test_tampered_plans_are_refused(plans, tmp_path, hand, edit):
    task, src = plans[hand]
    rows, doc = _read(src)
    assert edit is not raise_during_regrasp or _free(rows), "this plan has no regrasp to tamper with"
    edit(rows, doc)
    code, cert, err = _verify(task, _write(tmp_path / "bad", rows, doc))
    assert code == 1, (code, err)
    kinds = _kinds(cert)
    assert kinds & EXPECTED[edit.__name__], (edit.__name__, kinds, cert["violations"][:4])
    assert all(v["message"] for v in cert["violations"]) and not cert["certified"]
    assert not [v for v in cert["violations"] if "np." in v["message"]], "a numpy repr in a message"
    assert "Warning" not in err and "Traceback" not in err, err


@pytest.mark.parametrize("hand", ["paper", "two_link", "jaw"])
@pytest.mark.parametrize("name", list(JSON_ONLY))
def test_json_disagreeing_with_csv_is_refused(plans, tmp_path, hand, name):
    task, src = plans[hand]
    edit, kinds = JSON_ONLY[name]
    rows, doc = _read(src)
    bad = _write(tmp_path / "bad", rows, doc, json_edit=edit)
    code, cert, err = _verify(task, bad)
    assert code == 1 and "files" in _kinds(cert), (code, err, cert and cert["violations"][:3])
    # plan.json alone: its rows themselves are refused
    (bad / "plan.csv").unlink()
    code, cert, err = _verify(task, bad)
    assert code == 1 and _kinds(cert) & kinds, (code, err, cert and cert["violations"][:3])


@pytest.mark.parametrize("damage, match", [
    (lambda d: (d / "plan.csv").write_text("t,q_left\n" + "1" * 200_000 + ",0\n"), "plan"),
    (lambda d: (d / "plan.json").write_text((d / "plan.json").read_text()[:-200]), "not a plan JSON"),
    (lambda d: (d / "plan.csv").write_text("t,mode\n0,SSSS,extra\n"), "cells"),
])  # fmt: skip
def test_unreadable_plans_exit_2(plans, tmp_path, damage, match):
    task, src = plans["paper"]
    dst = tmp_path / "bad"
    shutil.copytree(src, dst)
    damage(dst)
    code, out, err = _run(["verify", str(dst), "--task", str(task)])
    assert code == 2 and err.startswith("qsplan: error: ") and err.count("\n") == 1 and match in err


#: Edits of a turning plan's letters: the transition row's BSSSS (vertex 0 lifts) written as SSSSS, and a pivot row's
#: SSSS as SSSR: each must be exit 1 naming the row and the mode, not exit 2 naming no row.
TURN_LETTERS = {"transition_as_all_sliding": lambda m: "S" * len(m) if m.startswith("B") else None,
                "pivot_row_rolling": lambda m: m[:-1] + "R" if m == "SSSS" else None}  # fmt: skip


@pytest.mark.slow
@pytest.mark.parametrize("name", list(TURN_LETTERS))
def test_turning_plan_with_a_letter_changed_names_the_row(bundled_plan, tmp_path, name):
    src = bundled_plan("reorient_task")
    rows, doc = _read(src)
    pivot = [i for i, r in enumerate(rows) if TURN_LETTERS[name](r["mode"]) is not None and r["phase"] == "2"]
    k = pivot[0] if name.startswith("transition") else pivot[len(pivot) // 2]
    rows[k]["mode"] = TURN_LETTERS[name](rows[k]["mode"])
    code, cert, err = _verify(task_paths()["reorient_task"], _write(tmp_path / "bad", rows, doc))
    assert code == 1, (code, err)
    assert any(v["row"] == k and v["kind"] == "mode" for v in cert["violations"]), cert["violations"][:4]


def test_verify_without_task_blames_the_plan_record_not_the_option(plans, tmp_path):
    """A tampered ``metadata.task_record`` read because no ``--task`` was given: the plan's record is named."""
    _, src = plans["paper"]
    rows, doc = _read(src)
    doc["metadata"]["task_record"]["hand"]["workpiece_mass"] = -1
    bad = _write(tmp_path / "bad", rows, doc)
    code, out, err = _run(["verify", str(bad)])
    assert code == 2 and err.count("\n") == 1 and "--task:" not in err
    assert err.startswith(f"qsplan: error: {bad}: plan.json's metadata.task_record: ") and "with --task" in err
