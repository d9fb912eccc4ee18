"""``qsplan sweep``: the JSON summary, files written, refusal to overwrite, one-line errors (exit 2)."""

import json
import subprocess
import sys

import pytest

from qsplan.planner.cli.main import main

FAST = ["sweep", "--samples", "11", "--no-plots"]


def run(args, capsys):
    code = main(args)
    out, err = capsys.readouterr()
    return code, out, err


def test_json_summary_and_files(tmp_path, capsys):
    code, out, err = run(FAST + ["--out", str(tmp_path), "--json"], capsys)
    assert code == 0 and err == ""
    doc = json.loads(out)
    assert doc["mode"] == "SSSS" and doc["effort_joint"] == "right" and doc["velocity_joint"] == "left"
    assert doc["mu_range"] == [0.0, 0.2] and doc["shared_mu"] is False and doc["samples"] == 11
    assert doc["guaranteed"]["exact"] and doc["guaranteed"]["points_without_band"] == 0
    n = doc["guaranteed"]["narrowest"]
    assert n["t"] == 10.0 and n["width"] == pytest.approx(0.25934, rel=1e-4)
    assert doc["competitors"]["BSRS"]["feasible_at_mu_high"][0][1] == 10.0
    assert doc["frictionless_upper_infinite"][0][0] == 0.0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["segment1.csv", "segment1.json"]


def test_refuses_to_overwrite_without_force(tmp_path, capsys):
    assert run(FAST + ["--out", str(tmp_path)], capsys)[0] == 0
    before = (tmp_path / "segment1.csv").read_text()
    code, out, err = run(FAST + ["--out", str(tmp_path), "--shared-mu"], capsys)
    assert code == 2 and out == "" and "exists" in err and "--force" in err and err.count("\n") == 1
    assert (tmp_path / "segment1.csv").read_text() == before
    code, out, _ = run(FAST + ["--out", str(tmp_path), "--shared-mu", "--force"], capsys)
    assert code == 0 and "wrote" in out and (tmp_path / "segment1.csv").read_text() != before


def test_plots_and_text_summary(tmp_path, capsys):
    code, out, err = run(["sweep", "--samples", "9", "--out", str(tmp_path)], capsys)
    assert code == 0 and err == ""
    for name in ("fig10_frictionless", "fig11_mu_high", "fig12_competitors", "fig13_guaranteed", "hand_strip"):
        assert (tmp_path / f"{name}.png").stat().st_size > 1000
    assert "narrowest guaranteed band" in out and "Fig. 12: competitor BSRS" in out


@pytest.mark.parametrize(
    "extra, match",
    [
        (["--mu-range", "0.3", "0.1"], "--mu-range"),
        (["--mu-range", "-0.1", "0.1"], "--mu-range"),
        (["--samples", "1"], "--samples"),
        (["--duration", "0"], "--duration"),
        (["--paper-samples", "0"], "--paper-samples"),
        (["--safety-margin", "-1"], "--safety-margin"),
        (["--max-margin", "nan"], "--max-margin"),
        (["--display-limit", "0"], "--display-limit"),
        (["--segment", "2"], "--segment"),
        (["--effort-joint", "thumb"], "--effort-joint"),
    ],
)
def test_bad_arguments_exit_2_with_one_line(tmp_path, capsys, extra, match):
    code, out, err = run(FAST + ["--out", str(tmp_path)] + extra, capsys)
    assert code == 2 and out == "" and match in err and err.count("\n") == 1


def test_console_entry_point(tmp_path):
    r = subprocess.run([sys.executable, "-m", "qsplan.planner.cli"] + FAST + ["--out", str(tmp_path), "--json", "--samples", "5"],
                       capture_output=True, text=True, check=False)  # fmt: skip
    assert r.returncode == 0, r.stderr
    assert json.loads(r.stdout)["samples"] == 5
