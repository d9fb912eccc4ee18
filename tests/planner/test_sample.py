"""Controller-rate samples of a plan (issue 24, item 3): the tick rule, re-integration, checks, ``qsplan sample``."""

import csv
import io
import json
from pathlib import Path

import numpy as np
import pytest

from qsplan.mechanics import QsplanError
from qsplan.planner.cli.main import main
from qsplan.planner.export.plan_files import read_plan_csv
from qsplan.planner.export.sample import MAX_TICKS, TIME_SNAP, sample_plan, tick_times, write_samples

REFERENCE = Path(__file__).resolve().parent.parent / "data" / "reference_plans"

#: The acceptance bound (issue 24): the sampled qd re-integrated lands on the exported q to this (rad).
REINTEGRATION_TOL = 1e-6


def _toy():
    """A slide (phase 0: ``a`` velocity-controlled, ``b`` torque), a regrasp (phase 1, both velocity, ``b`` still for
    its first interval), hand-written: every number below follows from these rows."""
    nan = np.nan
    return {
        "t": np.array([0.0, 0.1, 0.2, 0.2, 0.5, 0.8]),
        "q_a": np.array([0.0, 0.01, 0.03, 0.03, 0.33, 0.03]),
        "q_b": np.array([1.0, 1.1, 1.2, 1.2, 1.2, 1.5]),
        "qd_a": np.array([0.1, 0.2, 0.2, 1.0, -1.0, 0.0]),
        "qd_b": np.array([nan, nan, nan, 0.0, 1.0, 0.0]),
        "tau_a": np.full(6, nan),
        "tau_b": np.array([0.5, 0.7, 0.9, nan, nan, nan]),
        "mode": np.array(["SSSS"] * 3 + ["free"] * 3),
        "effort_joint": np.array(["b"] * 3 + ["none"] * 3),
        "phase": np.array([0.0, 0, 0, 1, 1, 1]),
    }


def test_tick_rule_on_hand_written_rows():
    s = sample_plan(_toy(), [0.0, 0.05, 0.1, 0.15, 0.2, 0.35, 0.6, 0.8])
    a, b = 0, 1
    # q linear between rows; qd the rate of q over the tick (0.05 s ticks inside the first interval: 0.1 rad/s)
    assert s.q[:4, a] == pytest.approx([0.0, 0.005, 0.01, 0.02])
    assert s.qd[:2, a] == pytest.approx([0.1, 0.1]) and s.qd[2, a] == pytest.approx(0.2)
    # torque linear between the slide's rows; no position or velocity command under torque control
    assert s.tau[:4, b] == pytest.approx([0.5, 0.6, 0.7, 0.8])
    assert list(s.control[:4, b]) == ["torque"] * 4 and np.isnan(s.q[:4, b]).all() and np.isnan(s.qd[:4, b]).all()
    assert s.q_plan[1, b] == pytest.approx(1.05)
    # the tick at the switch (0.2 s) takes the regrasp: both joints velocity-controlled, no torque
    assert s.phase.tolist() == [0, 0, 0, 0, 1, 1, 1, 1] and s.mode[4] == "free"
    assert list(s.control[4]) == ["velocity", "hold"] and np.isnan(s.tau[4]).all()
    assert s.qd[4, a] == pytest.approx((0.18 - 0.03) / 0.15)  # 0.2 -> 0.35 s at 1 rad/s
    assert s.qd[4, b] == 0.0 and s.q[4, b] == 1.2  # b does not move before 0.5 s: held
    # across a row inside the tick (0.35 -> 0.6 s spans the row at 0.5 s): the mean rate, so q lands on the tick
    assert s.q[6, a] == pytest.approx(0.23)
    assert s.q[5, a] + s.qd[5, a] * 0.25 == pytest.approx(s.q[6, a])
    # the last tick: the rate of the rows' interval it ends
    assert s.qd[7, a] == pytest.approx(-1.0) and s.qd[7, b] == pytest.approx(1.0)


def test_a_tick_within_the_snap_of_a_switch_takes_the_new_phase():
    s = sample_plan(_toy(), [0.2 - 0.5 * TIME_SNAP, 0.2 + 1e-6])
    assert s.phase.tolist() == [1, 1]
    s = sample_plan(_toy(), [0.2 - 2 * TIME_SNAP, 0.2 + 1e-6])
    assert s.phase.tolist() == [0, 1]


def _reintegrate(samples, cols):
    """Largest |q - exported q| (rad) at the rows, each velocity-controlled stretch of a joint re-integrated tick by
    tick (q_{i+1} = q_i + qd_i dt) from its first tick's q, and carried to a row between two ticks at the tick's
    ``qd`` (a drive holding it over the tick)."""
    t = samples.t
    tick = np.clip(np.searchsorted(t, cols["t"] + TIME_SNAP, side="right") - 1, 0, t.size - 1)  # the tick at or before
    ahead = cols["t"] - t[tick]
    assert np.all(ahead >= -TIME_SNAP) and np.all(ahead < np.max(np.diff(t)) + TIME_SNAP)
    worst, checked = 0.0, 0
    for j, name in enumerate(samples.joints):
        commanded = samples.control[:, j] != "torque"
        q = np.full(t.size, np.nan)
        for i in range(t.size):
            if not commanded[i]:
                continue
            start = i == 0 or not commanded[i - 1]
            q[i] = samples.q[i, j] if start else q[i - 1] + samples.qd[i - 1, j] * (t[i] - t[i - 1])
        # rows where the joint is commanded (a row at a switch: the phase the tick takes)
        rows = np.flatnonzero(np.isfinite(q[tick]) & (samples.phase[tick] == cols["phase"].astype(int)))
        at = q[tick[rows]] + np.where(ahead[rows] > TIME_SNAP, np.nan_to_num(samples.qd[tick[rows], j]) * ahead[rows], 0.0)
        worst = max(worst, float(np.max(np.abs(at - cols[f"q_{name}"][rows]), initial=0.0)))
        checked += rows.size
    assert checked > 0
    return worst


@pytest.mark.parametrize("name", ["demo_task", "scripted_regrasp_task"])
def test_reintegrated_velocity_reproduces_the_exported_q(name):
    cols = read_plan_csv(REFERENCE / f"{name}.csv")
    s = sample_plan(REFERENCE / f"{name}.csv", tick_times(cols["t"][-1], 1000.0))
    assert np.all(np.diff(s.t) > 0)
    assert _reintegrate(s, cols) <= REINTEGRATION_TOL


@pytest.fixture(scope="module")
def chain_plans(tmp_path_factory):
    """The bundled chain-hand tasks planned and exported: ``{name: plan directory}``."""
    from qsplan.planner.export.plan_files import export_plan
    from tests.planner.bundled import planned

    out = {}
    for name in ("parallel_jaw_task", "two_link_task"):
        d = tmp_path_factory.mktemp(name)
        export_plan(planned(name), d)
        out[name] = d
    return out


@pytest.mark.slow
@pytest.mark.ompl
@pytest.mark.parametrize("name", ["parallel_jaw_task", "two_link_task"])
def test_reintegration_on_chain_hand_plans(chain_plans, name):
    d = chain_plans[name]
    cols = read_plan_csv(d / "plan.csv")
    s = sample_plan(d, tick_times(cols["t"][-1], 1000.0))
    assert _reintegrate(s, cols) <= REINTEGRATION_TOL
    assert s.kinds == (("prismatic",) * 2 if name == "parallel_jaw_task" else ("revolute",) * 4)  # from plan.json
    j = sample_plan(d / "plan.json", s.t)  # the JSON file reads alike
    assert np.array_equal(j.q, s.q, equal_nan=True) and np.array_equal(j.tau, s.tau, equal_nan=True)


def test_json_plan_reads_like_its_csv(tmp_path):
    cols = read_plan_csv(REFERENCE / "demo_task.csv")
    data = {k: [None if isinstance(v, float) and np.isnan(v) else v for v in cols[k].tolist()] for k in cols}
    (tmp_path / "plan.json").write_text(json.dumps({"data": data, "units": {"q_left": "rad"}}))
    ticks = tick_times(cols["t"][-1], 200.0)
    a, b = sample_plan(tmp_path, ticks), sample_plan(REFERENCE / "demo_task.csv", ticks)
    assert np.array_equal(a.q, b.q, equal_nan=True) and np.array_equal(a.tau, b.tau, equal_nan=True)


def test_csv_has_units_and_empty_cells_where_not_commanded():
    s = sample_plan(_toy(), [0.0, 0.2, 0.5, 0.8])
    f = io.StringIO()
    write_samples(s, f, "toy")
    lines = f.getvalue().splitlines()
    assert lines[0].startswith("# qsplan.samples 1: controller-rate samples of toy")
    assert "q_a rad" in lines[1] and "qd_a rad/s" in lines[1] and "tau_b N m" in lines[1]
    rows = list(csv.DictReader(line for line in lines if not line.startswith("#")))
    assert list(rows[0]) == ["t", "control_a", "q_a", "qd_a", "tau_a", "control_b", "q_b", "qd_b", "tau_b", "phase",
                             "mode"]  # fmt: skip
    assert rows[0]["control_b"] == "torque" and rows[0]["q_b"] == "" and rows[0]["tau_b"] == "0.5"
    assert rows[1]["control_b"] == "hold" and rows[1]["qd_b"] == "0.0" and rows[1]["tau_b"] == ""


@pytest.mark.parametrize("times, match", [
    ([], "finite tick times"),
    ([0.0, np.nan], "finite tick times"),
    ([0.0, 0.1, 0.1], "strictly increasing"),
    ([0.0, 0.2, 0.1], "strictly increasing"),
    ([-0.01, 0.1], "outside the plan"),
    ([0.0, 0.8 + 1e-6], "outside the plan"),
])  # fmt: skip
def test_bad_times_are_refused(times, match):
    with pytest.raises(QsplanError, match=match):
        sample_plan(_toy(), times)


def test_too_many_times_are_refused():
    with pytest.raises(QsplanError, match=f"at most {MAX_TICKS}"):
        sample_plan(_toy(), np.linspace(0.0, 0.8, MAX_TICKS + 1))


@pytest.mark.parametrize("rate, match", [(0.0, "positive number"), (np.inf, "positive number"),
                                          (1e12, "at most")])  # fmt: skip
def test_bad_rates_are_refused(rate, match):
    with pytest.raises(QsplanError, match=match):
        tick_times(1.0, rate)


def _edit(**changes):
    cols = _toy()
    for k, v in changes.items():
        if v is None:
            del cols[k]
        else:
            cols[k] = np.asarray(v)
    return cols


@pytest.mark.parametrize("changes, match", [
    ({"q_a": None, "q_b": None}, "no column 'q_<joint>'"),
    ({"qd_b": None}, "column 'qd_b' missing"),
    ({"phase": None}, "column 'phase' missing"),
    ({"t": [0.0, 0.1, np.nan, 0.2, 0.5, 0.8]}, "column 't'"),
    ({"phase": [0.0, 0, 0, 1.5, 1.5, 1.5]}, "not a phase index"),
    ({"phase": [0.0, 0, 1, 1, 0, 0]}, "not a phase index"),
    ({"t": [0.0, 0.1, 0.1, 0.2, 0.5, 0.8]}, "out of time order"),
    ({"t": [0.0, 0.1, 0.2, 0.3, 0.5, 0.8]}, "not where phase 0 ends"),
    ({"tau_b": [0.5, np.nan, 0.9, np.nan, np.nan, np.nan]}, "neither a torque"),
    ({"qd_a": [0.1, np.nan, 0.2, 1.0, -1.0, 0.0]}, "neither a torque"),
])  # fmt: skip
def test_bad_plans_are_refused(changes, match):
    with pytest.raises(QsplanError, match=match):
        sample_plan(_edit(**changes), [0.0])


def test_a_path_that_is_no_plan_is_refused(tmp_path):
    with pytest.raises(QsplanError, match="no plan directory"):
        sample_plan(tmp_path, [0.0])
    (tmp_path / "plan.json").write_text("{not json")
    with pytest.raises(QsplanError, match="not a readable plan file"):
        sample_plan(tmp_path / "plan.json", [0.0])


def test_cli_writes_the_csv_to_stdout_and_to_a_file(tmp_path, capsys):
    plan = REFERENCE / "demo_task.csv"
    assert main(["sample", str(plan), "--rate", "100"]) == 0
    text = capsys.readouterr().out
    rows = list(csv.DictReader(line for line in text.splitlines() if not line.startswith("#")))
    cols = read_plan_csv(plan)
    assert len(rows) == round(cols["t"][-1] * 100) + 1 and float(rows[-1]["t"]) == cols["t"][-1]
    out = tmp_path / "s.csv"
    assert main(["sample", str(plan), "--rate", "100", "--out", str(out)]) == 0
    assert out.read_text() == text and f"wrote {out}" in capsys.readouterr().out
    assert main(["sample", str(plan), "--rate", "100", "--out", str(out)]) == 2  # never overwritten silently
    assert "--force" in capsys.readouterr().err
    assert main(["sample", str(plan), "--rate", "100", "--out", str(out), "--force"]) == 0


@pytest.mark.parametrize("args, match", [(["--rate", "-5"], "--rate: expected a positive number"),
                                          (["--rate", "x"], "invalid float value")])  # fmt: skip
def test_cli_bad_input_is_one_line(args, match, capsys):
    assert main(["sample", str(REFERENCE / "demo_task.csv"), *args]) == 2
    err = capsys.readouterr().err
    assert match in err and len(err.strip().splitlines()) == 1


def test_plan_sample_is_the_files_samples(tmp_path):
    """``Plan.sample`` (the planned plan) and ``sample_plan`` (its exported files) give the same ticks: one rule."""
    from qsplan.planner.export.plan_files import export_plan
    from qsplan.planner.export.sample import sample_plan, tick_times
    from tests.planner.bundled import planned

    plan = planned("parallel_jaw_task")
    export_plan(plan, tmp_path)
    ticks = tick_times(plan.duration, 200)
    a, b = plan.sample(ticks), sample_plan(tmp_path, ticks)
    assert a.joints == b.joints and a.kinds == b.kinds == ("prismatic", "prismatic")
    np.testing.assert_array_equal(a.control, b.control)
    for name in ("q", "qd", "tau", "q_plan"):
        np.testing.assert_allclose(getattr(a, name), getattr(b, name), rtol=1e-12, atol=1e-15, equal_nan=True)
