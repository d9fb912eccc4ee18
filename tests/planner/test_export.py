"""The torque schedule export: CSV columns, JSON units and metadata, infinities, no silent overwrite."""

import csv
import json
import math

import numpy as np
import pytest

from qsplan.hands.paper_hand.segments import first_segment, sample_segment
from qsplan.hands.paper_hand.two_finger import default_hand
from qsplan.mechanics import QsplanError
from qsplan.planner.torque.sweep import segment_bands
from qsplan.planner.export.schedule import (
    FORMAT,
    export_schedule,
    schedule_columns,
    write_csv,
    write_json,
)

COLUMNS = ["t", "q_left", "q_right", "qd_left", "tau_right", "tau_right_min", "tau_right_max", "mode", "margin"]


@pytest.fixture(scope="module")
def bands():
    """One shared coefficient: the guaranteed band is unbounded above early in the segment."""
    return segment_bands(sample_segment(first_segment(default_hand()), 11), shared=True)


def _read_csv(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    return rows[0], rows[1:]


def test_csv_columns_and_values(bands, tmp_path):
    path = write_csv(bands, tmp_path / "s.csv")
    header, rows = _read_csv(path)
    assert header == COLUMNS
    assert len(rows) == len(bands.samples)
    col = {name: [r[i] for r in rows] for i, name in enumerate(header)}
    S, g = bands.samples, bands.guaranteed.band
    assert np.array_equal(np.array(col["t"], float), S.t)  # full precision round trip
    assert np.array_equal(np.array(col["q_left"], float), S.q[:, 0])
    assert np.array_equal(np.array(col["qd_left"], float), S.qd[:, 0])
    assert np.array_equal(np.array(col["tau_right"], float), bands.command)
    assert np.array_equal(np.array(col["tau_right_min"], float), g.lower)
    assert np.array_equal(np.array(col["tau_right_max"], float), g.upper)
    assert "inf" in col["tau_right_max"]  # unbounded, written as inf (never a large number)
    assert set(col["mode"]) == {"SSSS"}
    assert np.array_equal(np.array(col["margin"], float), bands.margin)


def test_json_has_units_metadata_and_null_for_infinity(bands, tmp_path):
    path = write_json(bands, tmp_path / "s.json")
    doc = json.loads(path.read_text())
    assert doc["format"] == FORMAT and doc["version"] == 1
    assert doc["columns"] == COLUMNS and list(doc["data"]) == COLUMNS
    assert doc["units"] == {"t": "s", "q_left": "rad", "q_right": "rad", "qd_left": "rad/s", "tau_right": "N m",
                            "tau_right_min": "N m", "tau_right_max": "N m", "mode": None, "margin": "N m"}  # fmt: skip
    upper = doc["data"]["tau_right_max"]
    assert upper[0] is None and all(u is None or math.isfinite(u) for u in upper)
    meta = doc["metadata"]
    assert meta["mode"]["kind"] == "4S" and meta["joints"] == {"left": "velocity", "right": "effort"}
    assert meta["friction"]["range"] == [0.0, 0.2] and "shared" in meta["friction"]["model"]
    assert meta["band"]["narrowest"]["width_N_m"] == pytest.approx(0.5414, rel=1e-3)
    assert meta["band"]["competitors"] == ["RBSS", "SBRS", "BSRS", "BSSR"]
    assert meta["hand"]["finger_base_m"] == 0.09 and meta["command"]["safety_margin_N_m"] > 0
    assert meta["contacts"] == ["palm:0", "palm:1", "left:2", "right:3"]


def test_columns_follow_the_control_partition():
    S = sample_segment(first_segment(default_hand(), effort_joint="left"), 5)
    cols, _ = schedule_columns(segment_bands(S))
    assert list(cols) == ["t", "q_left", "q_right", "qd_right", "tau_left", "tau_left_min", "tau_left_max", "mode", "margin"]


def test_no_silent_overwrite(bands, tmp_path):
    paths = export_schedule(bands, tmp_path, stem="seg")
    assert [p.name for p in paths] == ["seg.csv", "seg.json"]
    before = paths[0].read_text()
    (tmp_path / "other.json").write_text("{}")
    with pytest.raises(QsplanError, match="exists; pass force=True"):
        export_schedule(bands, tmp_path, stem="seg")
    with pytest.raises(QsplanError, match="exists"):
        write_json(bands, tmp_path / "other.json")
    assert (tmp_path / "other.json").read_text() == "{}"
    export_schedule(bands, tmp_path, stem="seg", force=True)
    assert paths[0].read_text() == before
    with pytest.raises(QsplanError, match="is a file"):
        export_schedule(bands, tmp_path / "seg.csv")
