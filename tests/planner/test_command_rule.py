"""One command rule for plans and ``qsplan sweep`` (issue 16): one margin kept along the whole segment, at most two
torque resolutions, so the command is continuous and close to the torque the mode needs, shared friction or not."""

import json

import numpy as np
import pytest

from qsplan.mechanics import QsplanError
from qsplan.planner.cli.main import main
from qsplan.planner.torque.command import (
    MAX_MARGIN_RESOLUTIONS,
    choose_command,
    command_rule,
    default_safety_margin,
    segment_command,
)


class Band:
    """A band sweep's edges (what default_safety_margin reads)."""

    def __init__(self, lower, upper):
        self.lower, self.upper = np.asarray(lower, float), np.asarray(upper, float)
        self.feasible = np.isfinite(self.lower) | np.isfinite(self.upper)

    @property
    def width(self):
        return self.upper - self.lower


def test_segment_command_keeps_one_margin():
    lower, upper = np.array([0.05, 0.06, 0.07, 0.08]), np.array([np.inf, 3.0, 1.9, 0.18])
    c, m = segment_command(lower, upper, 0.04)
    assert np.allclose(c, [0.09, 0.10, 0.11, 0.12]) and np.allclose(m, 0.04)
    assert np.array_equal(c, choose_command(lower, upper, 0.04, 0.04)[0])
    c, m = segment_command([0.0], [0.06], 0.04)  # narrower than 2 m: the midpoint
    assert np.allclose(c, 0.03) and np.allclose(m, 0.03)


@pytest.mark.parametrize("lower, upper, resolution, margin", [
    ([0.05, 0.06], [2.0, 1.81], None, 0.875),        # half the narrowest band
    ([0.05, 0.06], [2.0, 1.81], 0.02, 0.04),         # at most two resolutions: the demo's third segment
    ([0.0, 0.0], [0.1, 0.2], 0.02, 0.04),            # two resolutions are less than half the narrowest band
    ([0.0, 0.0], [0.06, 0.2], 0.02, 0.03),           # half the narrowest band is less than two resolutions
    ([0.3, 0.2], [np.inf, np.inf], 0.02, 0.04),      # unbounded everywhere: the largest edge, capped
])  # fmt: skip
def test_default_safety_margin(lower, upper, resolution, margin):
    assert default_safety_margin(Band(lower, upper), resolution) == pytest.approx(margin)


def test_bad_resolution_is_named():
    with pytest.raises(QsplanError, match="torque resolution"):
        default_safety_margin(Band([0.0], [1.0]), -1.0)


def test_command_rule_is_stated():
    rule = command_rule(0.04, 0.04, 0.02)
    assert rule["safety_margin_N_m"] == rule["max_margin_N_m"] == 0.04 and rule["torque_resolution_N_m"] == 0.02
    assert rule["max_margin_resolutions"] == MAX_MARGIN_RESOLUTIONS and "whole segment" in rule["rule"]
    assert "midpoint of a bounded band" in command_rule(0.1)["rule"]


@pytest.mark.parametrize("shared", [False, True])
def test_sweep_command_is_continuous_and_near_the_torque_needed(tmp_path, capsys, shared):
    out = tmp_path / "sweep"
    args = ["sweep", "--samples", "41", "--no-plots", "--out", str(out), "--workers", "1", "--json"]
    code = main(args + (["--shared-mu"] if shared else []))
    doc = json.loads(capsys.readouterr()[0])
    assert code == 0 and doc["torque_resolution"] == 0.02
    data = json.loads((out / "segment1.json").read_text())
    lower = np.array(data["data"]["tau_right_min"], float)
    command = np.array(data["data"]["tau_right"], float)
    margin = np.array(data["data"]["margin"], float)
    m = data["metadata"]["command"]["max_margin_N_m"]
    assert m == data["metadata"]["command"]["safety_margin_N_m"] <= MAX_MARGIN_RESOLUTIONS * 0.02 + 1e-15
    assert np.allclose(command, lower + m) and np.allclose(margin, m)  # no jump where the upper edge leaves
    assert np.max(np.abs(np.diff(command))) < 0.01 and doc["command_max"] < 0.2  # shared-mu used to reach 61 N m
    upper = np.array([np.inf if v is None else v for v in data["data"]["tau_right_max"]])
    assert np.all((command > lower) & (command < upper))
