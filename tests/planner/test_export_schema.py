"""The export as documented (issue 16): every exported file valid against the shipped JSON schema, the CSV equal
to the JSON, ``phase`` an integer, the README's column tables equal to what is written, the command rule stated."""

import copy
import json
import re
import tomllib
from pathlib import Path

import numpy as np
import pytest

from qsplan.hands.paper_hand.segments import first_segment, sample_segment
from qsplan.hands.paper_hand.two_finger import default_hand
from qsplan.planner.export.plan_files import PLAN_COLUMNS, plan_columns, plan_metadata, read_plan_csv
from qsplan.planner.export.schedule import SCHEDULE_COLUMNS
from qsplan.planner.export.schema import (
    SCHEMA_FILE,
    check_schedule_document,
    check_schedule_files,
    schedule_schema,
    validate,
)
from qsplan.planner.replay.replay import replay_segments
from qsplan.planner.reports.segment import sweep_segment

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def sweep_dir(tmp_path_factory):
    """``qsplan sweep --shared-mu``'s export (11 samples, no plots)."""
    out = tmp_path_factory.mktemp("sweep")
    sweep_segment(sample_segment(first_segment(default_hand()), 11), out, shared=True, plots=False, workers=1)
    return out


@pytest.mark.ompl
def test_plan_files_are_valid_and_agree(small_run):
    assert check_schedule_files(small_run.out_dir / "plan.json") == []
    doc = json.loads((small_run.out_dir / "plan.json").read_text())
    assert doc["format"] == "qsplan.torque_schedule.plan" and doc["version"] == 1
    assert list(doc["descriptions"]) == doc["columns"]


def test_sweep_files_are_valid_and_agree(sweep_dir):
    assert check_schedule_files(sweep_dir / "segment1.json") == []


@pytest.mark.ompl
def test_phase_is_an_integer_index(small_run):
    header, *rows = (small_run.out_dir / "plan.csv").read_text().splitlines()
    j = header.split(",").index("phase")
    cells = [r.split(",")[j] for r in rows]
    assert set(cells) == {"0", "1", "2", "3"}  # segment, release hold, regrasp, segment
    doc = json.loads((small_run.out_dir / "plan.json").read_text())
    assert all(type(p) is int for p in doc["data"]["phase"])
    assert [p["index"] for p in doc["metadata"]["phases"]] == [0, 1, 2, 3]
    cols = read_plan_csv(small_run.out_dir / "plan.csv")
    segs = replay_segments(cols)
    assert [s["phase"] for s in segs] == [0, 1, 3]  # the slides and the release hold
    legacy = dict(cols, phase=np.array([f"{p:.1f}" for p in cols["phase"]]))  # files before issue 16
    assert [s["phase"] for s in replay_segments(legacy)] == [0, 1, 3]
    with pytest.raises(ValueError, match="phase"):
        replay_segments(dict(cols, phase=cols["phase"] + 0.5))


@pytest.mark.ompl
def test_velocity_controlled_torque_cells_are_nan_and_null(small_run):
    cols = read_plan_csv(small_run.out_dir / "plan.csv")
    doc = json.loads((small_run.out_dir / "plan.json").read_text())["data"]
    for joint in ("left", "right"):
        torque = cols["effort_joint"] == joint
        for suffix in ("", "_min", "_max"):
            name = f"tau_{joint}{suffix}"
            assert np.all(np.isnan(cols[name][~torque])) and all(doc[name][k] is None for k in np.flatnonzero(~torque))
        assert np.all(np.isfinite(cols[f"tau_{joint}"][torque])) and np.all(np.isnan(cols[f"qd_{joint}"][torque]))
    assert np.all(np.isnan(cols["margin"][cols["mode"] == "free"]))


@pytest.mark.ompl
def test_metadata_states_the_command_rule_and_the_sequence(small_run):
    meta = json.loads((small_run.out_dir / "plan.json").read_text())["metadata"]
    assert "margin" in meta["command"]["rule"] and meta["command"]["max_margin_resolutions"] > 0
    for ph in meta["phases"]:
        if ph["kind"] == "contact":
            assert 0 < ph["command"]["margin_N_m"] <= ph["command"]["half_narrowest_band_N_m"] + 1e-12

    from qsplan.planner.plan.steps import RegraspStep, SearchSummary, SlideStep

    class WithSequence:  # a plan that carries the typed sequence its planner chose
        def __init__(self, plan):
            self.sequence = (SlideStep("L vertex / R vertex", 0.0, -0.02, "right", np.float64(0.2)),
                             RegraspStep(-0.02, "L vertex / R vertex", "L edge:3 / R vertex"),
                             SearchSummary("widest", 1, 2, 41, 0.0025, 82, 300, 0.1, 0.01, 90, float("inf")))
            self._plan = plan

        def __getattr__(self, name):
            return getattr(self._plan, name)

        @property
        def search(self):
            return self.sequence[-1]

    meta = plan_metadata(WithSequence(small_run.plan))
    slide, regrasp, search = meta["sequence"]
    assert slide["x_from_m"] == slide["x_from"] == 0.0 and slide["narrowest_band"] == 0.2
    assert regrasp["x_from_m"] == regrasp["x"] == -0.02 and regrasp["to"] == "L edge:3 / R vertex"
    assert search["route_width"] is None and meta["planner"]["route_search"] == "widest"
    doc = json.loads((small_run.out_dir / "plan.json").read_text())
    doc["metadata"] = json.loads(json.dumps(meta))
    assert check_schedule_document(doc) == []
    doc["metadata"]["sequence"][0]["kind"] = "pivot"  # not a step the schema describes
    assert any("sequence[0]" in e for e in check_schedule_document(doc))


@pytest.mark.ompl
@pytest.mark.parametrize(
    "mutate, match",
    [
        (lambda d: d.update(format="qsplan.other"), "format"),
        (lambda d: d.update(version=2), "version"),
        (lambda d: d["data"].update(phase=[float(p) for p in d["data"]["phase"]]), "phase"),
        (lambda d: d["data"].pop("effort_joint"), "effort_joint"),
        (lambda d: d["data"]["t"].append(1.0), "different lengths"),
        (lambda d: d["units"].update(t="ms"), "units.t"),
        (lambda d: d["data"].update(bogus=[0.0] * len(d["data"]["t"])), "bogus"),
        (lambda d: d["data"]["mode"].__setitem__(0, "XYZ"), "mode"),
        (lambda d: d["metadata"].pop("command"), "command"),
        (lambda d: d["metadata"]["phases"][0].update(kind="hover"), "kind"),
    ],
)
def test_the_schema_refuses_broken_documents(small_run, mutate, match):
    doc = json.loads((small_run.out_dir / "plan.json").read_text())
    bad = copy.deepcopy(doc)
    mutate(bad)
    errors = check_schedule_document(bad)
    assert errors and any(match in e for e in errors), errors


@pytest.mark.ompl
def test_a_csv_that_differs_from_its_json_is_found(small_run, tmp_path):
    for name in ("plan.json", "plan.csv"):
        (tmp_path / name).write_bytes((small_run.out_dir / name).read_bytes())
    lines = (tmp_path / "plan.csv").read_text().splitlines()
    lines[3] = lines[3].replace("SSSS", "SSSB")
    (tmp_path / "plan.csv").write_text("\n".join(lines) + "\n")
    errors = check_schedule_files(tmp_path / "plan.json")
    assert len(errors) == 1 and "'mode' row 2" in errors[0]


@pytest.mark.parametrize("instance, schema, ok", [
    (1, {"type": "integer"}, True), (1.0, {"type": "integer"}, False), (True, {"type": "number"}, False),
    (None, {"type": ["number", "null"]}, True), ("ab", {"pattern": "^a"}, True), ([1], {"minItems": 2}, False),
    ({"a": 1}, {"additionalProperties": False}, False), (3, {"oneOf": [{"minimum": 1}, {"minimum": 2}]}, False),
    (0, {"$ref": "#/$defs/x", "$defs": {"x": {"const": 0}}}, True),
])  # fmt: skip
def test_the_validator_keywords(instance, schema, ok):
    assert (validate(instance, schema) == []) is ok


def test_the_schema_ships_with_the_package():
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["package-data"]
    assert "*.schema.json" in config["qsplan.planner.export"]
    assert (ROOT / "planner" / "export" / SCHEMA_FILE).is_file()
    assert schedule_schema()["properties"]["version"] == {"const": 1}


def _readme_table(heading):
    """``{column: unit}`` of the README's table following ``heading``."""
    text = (ROOT / "README.md").read_text()
    section = text[text.index(heading):]
    table = re.search(r"\| column \| unit \| meaning \|\n\| --- \| --- \| --- \|\n((?:\|.*\|\n)+)", section).group(1)
    rows = [[c.strip() for c in line.strip("|").split("|")] for line in table.splitlines()]
    out = {}
    for name, unit, _ in rows:
        for n in re.findall(r"`([^`]+)`", name):
            out[n] = None if unit == "-" else unit
    return out


@pytest.mark.ompl
def test_readme_plan_table_matches_what_plan_writes(small_run):
    table = _readme_table("#### Plan files")
    written = json.loads((small_run.out_dir / "plan.json").read_text())
    families = {f: u for f, u, _ in PLAN_COLUMNS}
    assert table == families
    for name, unit in written["units"].items():
        family = re.sub(r"_(left|right)", "_<joint>", name, count=1)
        assert family in table and table[family] == unit, name
    assert "qsplan.torque_schedule.plan" in (ROOT / "README.md").read_text()


def test_readme_schedule_table_matches_what_sweep_writes(sweep_dir):
    table = _readme_table("#### Segment files")
    assert table == {f: u for f, u, _ in SCHEDULE_COLUMNS}
    doc = json.loads((sweep_dir / "segment1.json").read_text())
    for name, unit in doc["units"].items():
        family = re.sub(r"_(left|right)", "_<joint>", name, count=1)
        assert table[family] == unit, name


@pytest.mark.ompl
def test_plan_columns_keep_every_name(small_run):
    cols, units = plan_columns(small_run.plan)
    assert list(cols)[:18] == ["t", "q_left", "q_right", "qd_left", "qd_right", "tau_left", "tau_left_min",
                               "tau_left_max", "tau_right", "tau_right_min", "tau_right_max", "mode", "margin",
                               "x_workpiece", "y_workpiece", "theta_workpiece", "phase", "effort_joint"]  # fmt: skip
    assert list(cols)[18:] == ["control_left", "control_right", "speed_scale"]  # extended after every earlier column
    assert cols["speed_scale"][0] == 0.0 and cols["speed_scale"][-1] == 0.0 and max(cols["speed_scale"]) <= 1.0
    assert set(cols["control_left"]) | set(cols["control_right"]) <= {"velocity", "torque", "hold"}
    assert units["phase"] is None and units["tau_right"] == "N m"
