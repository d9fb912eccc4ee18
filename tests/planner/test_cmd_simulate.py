"""``qsplan simulate rod``: the JSON contract, the closed form, stops, plots, and one-line errors (exit 2)."""

import json
import subprocess
import sys

import pytest

from qsplan.hands.examples.rod import rod_closed_form
from qsplan.planner.cli.main import main

BASE = ["simulate", "rod", "--l1", "1.0", "--l2", "0.6", "--speed", "0.1"]
KEYS = ("mode", "t_start", "t_end", "l1_start", "l2_start", "l1_end", "l2_end")


def run(args, capsys):
    code = main(args)
    out, err = capsys.readouterr()
    return code, out, err


def simulate_json(capsys, *extra, mu_s=("0.5", "0.5"), mu_k=("0.4", "0.4"), duration="7.5"):
    args = BASE + ["--mu-static", *mu_s, "--mu-kinetic", *mu_k, "--duration", duration, "--json", *extra]
    code, out, err = run(args, capsys)
    assert code == 0 and err == ""
    return json.loads(out)


def test_json_contract_and_closed_form(capsys):
    doc = simulate_json(capsys)
    assert set(doc) >= {"segments", "stopped"}
    assert doc["stopped"] is None  # 7.5 s < t* = 8 s
    segs = doc["segments"]
    assert all(set(s) >= set(KEYS) for s in segs)
    assert [s["mode"] for s in segs[:4]] == ["SR", "RS", "SR", "RS"]  # contact 1 slides first
    cf = rod_closed_form(1.0, 0.6, (0.5, 0.5), (0.4, 0.4), 0.1, 7.5)
    assert len(segs) == len(cf.segments)
    for s, c in zip(segs, cf.segments):
        assert s["mode"] == c.mode
        for k in KEYS[1:]:
            assert s[k] == pytest.approx(getattr(c, k), abs=1e-6)
    assert segs[0]["t_start"] == 0.0 and segs[-1]["t_end"] == pytest.approx(7.5)
    for a, b in zip(segs, segs[1:]):  # contiguous
        assert a["t_end"] == b["t_start"] and a["l1_end"] == b["l1_start"] and a["l2_end"] == b["l2_start"]
    assert doc["closed_form"]["max_abs_error"] < 1e-9 and doc["closed_form"]["modes_match"]
    assert len(doc["events"]) == len(segs) - 1


def test_zeno_is_reported_not_hung(capsys):
    doc = simulate_json(capsys, mu_s=("0.6", "0.6"), mu_k=("0.45", "0.45"), duration="100")
    assert doc["stopped"].startswith("zeno: mode switches accumulate")
    assert doc["stop"]["kind"] == "zeno" and doc["stop"]["time"] < 8.0
    assert doc["closed_form"]["stopped"] == "zeno" and doc["closed_form"]["t_star"] == pytest.approx(8.0)


def test_equal_coefficients_stop_when_the_distances_equalise(capsys):
    doc = simulate_json(capsys, mu_s=("0.3", "0.3"), mu_k=("0.3", "0.3"), duration="20")
    assert [s["mode"] for s in doc["segments"]] == ["SR"]  # the farther support (1) slides
    last = doc["segments"][-1]
    assert last["l1_end"] == pytest.approx(0.6) and last["l2_end"] == pytest.approx(0.6)
    assert last["t_end"] == pytest.approx(2.0)
    assert doc["stopped"].startswith("no_persistent_mode") and "2S" in doc["stopped"]


def test_ambiguous_start_and_initial_mode(capsys):
    args = BASE[:3] + ["1.0", "--l2", "0.9", "--speed", "0.1", "--mu-static", "0.5", "0.5", "--mu-kinetic", "0.4", "0.4",
                       "--duration", "3", "--json"]  # fmt: skip
    code, out, _ = run(args, capsys)
    doc = json.loads(out)
    assert code == 0 and doc["segments"] == [] and doc["stopped"].startswith("ambiguous")
    assert doc["stop"]["candidates"] == ["RS", "SR"]
    code, out, _ = run(args + ["--initial-mode", "RS"], capsys)
    doc = json.loads(out)
    assert doc["stopped"] is None and doc["segments"][0]["mode"] == "RS"


def test_text_output_and_plot(tmp_path, capsys):
    png = tmp_path / "plots" / "rod.png"
    code, out, err = run(BASE + ["--mu-static", "0.5", "0.5", "--mu-kinetic", "0.4", "0.4", "--duration", "5",
                                 "--out", str(png)], capsys)  # fmt: skip
    assert code == 0 and err == ""
    assert "SR    R2S1" in out and "closed form" in out and f"wrote {png}" in out
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.parametrize(
    "change,match",
    [
        ({"--l1": ["0"]}, "--l1: expected a positive finite length"),
        ({"--l2": ["-0.5"]}, "--l2: expected a positive finite length"),
        ({"--l1": ["nan"]}, "--l1"),
        ({"--mu-static": ["-0.1", "0.5"]}, "--mu-static: expected nonnegative finite coefficients"),
        ({"--mu-kinetic": ["0.4", "-1"]}, "--mu-kinetic: expected nonnegative"),
        ({"--mu-kinetic": ["0.6", "0.4"]}, "--mu-kinetic: contact 1 has kinetic 0.6 above its static 0.5"),
        ({"--speed": ["0"]}, "--speed: expected a positive finite speed"),
        ({"--speed": ["-0.1"]}, "--speed"),
        ({"--duration": ["0"]}, "--duration: expected a positive finite duration"),
        ({"--duration": ["-3"]}, "--duration"),
        ({"--out": ["plot.txt"]}, "--out: expected a file name ending in .png"),
        ({"--max-step": ["0"]}, "--max-step"),
        ({"--min-segment": ["1e-12"]}, "--min-segment: expected at least 1e-09 s"),
        ({"--max-switches": ["-1"]}, "--max-switches"),
    ],
)
def test_bad_arguments_exit_2_with_one_line(change, match, capsys):
    opts = {"--l1": ["1.0"], "--l2": ["0.6"], "--mu-static": ["0.5", "0.5"], "--mu-kinetic": ["0.4", "0.4"],
            "--speed": ["0.1"], "--duration": ["1"], **change}  # fmt: skip
    args = ["simulate", "rod"] + [x for k, v in opts.items() for x in (k, *v)]
    code, out, err = run(args, capsys)
    assert code == 2 and out == ""
    assert err.count("\n") == 1 and match in err


def test_usage_errors_exit_2(capsys):
    code, _, err = run(["simulate", "rod", "--l1", "1"], capsys)  # missing options
    assert code == 2 and err.count("\n") == 1
    code, _, err = run(["simulate", "pendulum"] + BASE[2:], capsys)
    assert code == 2 and "invalid choice" in err


def test_console_entry_point_subprocess():
    proc = subprocess.run(
        [sys.executable, "-m", "qsplan.planner.cli", *BASE, "--mu-static", "0.5", "0.5", "--mu-kinetic", "0.6", "0.4",
         "--duration", "1", "--json"],  # fmt: skip
        capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    assert proc.returncode == 2 and proc.stdout == ""
    assert proc.stderr.strip().startswith("qsplan: error: --mu-kinetic") and proc.stderr.count("\n") == 1
