"""``qsplan muspace``: the JSON contract, the map file, and bad input (one line, exit 2)."""

import json
import re
import subprocess
import sys

import numpy as np
import pytest

from qsplan.hands.examples.paper import eq42_scene, rod_scene
from qsplan.mechanics import enumerate_modes, scene_from_dict, solve
from qsplan.mechanics.muspace.slices import mu_slice
from qsplan.planner.cli.main import main

LEGEND = ["3S", "R1S2", "R1S3", "R2S1", "R2S3", "R3S1", "R3S2"]


def run(args, capsys):
    code = main(args)
    out, err = capsys.readouterr()
    return code, out, err


@pytest.fixture
def eq42_file(tmp_path):
    p = tmp_path / "eq42.json"
    p.write_text(json.dumps(eq42_scene(0.5)))
    return p


def test_json_contract_matches_solver_cell_by_cell(eq42_file, capsys):
    code, out, err = run(["muspace", str(eq42_file), "--x", "mu1", "--y", "mu2", "--fix", "mu3=0.3",
                          "--range", "0", "1.5", "--n", "16", "--json"], capsys)  # fmt: skip
    assert code == 0 and err == ""
    doc = json.loads(out)
    xs = np.linspace(0, 1.5, 16)
    assert doc["x"] == xs.tolist() and doc["y"] == xs.tolist()
    assert doc["modes"] == LEGEND
    assert doc["letters"] == [m.letters for m in enumerate_modes(3, 3)]
    assert len(doc["cells"]) == 16 and all(len(row) == 16 for row in doc["cells"])
    scene = scene_from_dict(eq42_scene())
    for j, y in enumerate(xs):
        for i, x in enumerate(xs):
            expected = sorted(solve(scene.with_mu([x, y, 0.3]), residuals=False).feasible_modes)
            assert doc["cells"][j][i] == expected, (x, y)
    seen = {tuple(c) for row in doc["cells"] for c in row}
    assert () in seen and any(len(c) == 3 for c in seen)  # a jam and a triple overlap are explicit


def test_axes_order_and_unnamed_coefficients_keep_scene_values(eq42_file, capsys):
    args = ["muspace", str(eq42_file), "--x", "MU3", "--y", "mu1", "--range", "0.1", "1", "--n", "5", "--json"]
    code, out, _ = run(args, capsys)
    assert code == 0
    doc = json.loads(out)
    scene = scene_from_dict(eq42_scene(0.5))
    for j, y in enumerate(doc["y"]):
        for i, x in enumerate(doc["x"]):
            assert doc["cells"][j][i] == sorted(solve(scene.with_mu([y, 0.5, x]), residuals=False).feasible_modes)
    assert doc["axes"] == ["mu3", "mu1"] and doc["base_mu"] == [0.5, 0.5, 0.5]


def test_equal_range_and_two_contacts(tmp_path, capsys):
    p = tmp_path / "rod.json"
    p.write_text(json.dumps(rod_scene(l1=1.0, l2=0.5)))
    code, out, _ = run(["muspace", str(p), "--x", "mu1", "--y", "mu2", "--range", "0.4", "0.4", "--n", "2", "--json"], capsys)
    doc = json.loads(out)
    assert code == 0 and doc["modes"] == ["R1S2", "R2S1"] and doc["cells"] == [[["SR"]] * 2] * 2  # above l1 mu2 = l2 mu1
    code, out, _ = run(["muspace", str(p), "--x", "mu1", "--y", "mu2", "--range", "0", "0.4", "--n", "3", "--json"], capsys)
    cells = json.loads(out)["cells"]
    assert cells[1][2] == ["RS", "SR"] and cells[0][2] == ["RS"]  # (0.4, 0.2) is on the line, (0.4, 0) below


def test_text_output_and_map_file(eq42_file, tmp_path, capsys):
    png = tmp_path / "maps" / "eq42.png"
    code, out, err = run(["muspace", str(eq42_file), "--x", "mu1", "--y", "mu2", "--range", "0", "1.5", "--n", "30",
                          "--out", str(png)], capsys)  # fmt: skip
    assert code == 0 and err == ""
    assert png.stat().st_size > 10_000 and png.read_bytes()[:4] == b"\x89PNG"
    for name in LEGEND:
        assert re.search(rf"\b{name}\b", out)
    assert "ambiguous" in out and f"wrote {png}" in out


def test_json_and_out_together_keep_stdout_pure(eq42_file, tmp_path, capsys):
    svg = tmp_path / "m.svg"
    code, out, _ = run(["muspace", str(eq42_file), "--x", "mu2", "--y", "mu3", "--range", "0", "1", "--n", "8",
                        "--json", "--out", str(svg)], capsys)  # fmt: skip
    assert code == 0 and json.loads(out)["modes"] == LEGEND and svg.stat().st_size > 0


@pytest.mark.parametrize(
    "args,match",
    [
        (["--x", "nu1", "--y", "mu2"], r"--x: expected a friction coefficient mu1\.\.mu3"),
        (["--x", "mu1", "--y", "mu4"], r"--y: the scene has 3 contacts"),
        (["--x", "mu0", "--y", "mu2"], r"--x: the scene has 3 contacts"),
        (["--x", "mu1", "--y", "mu1"], r"--y: expected a coefficient other than --x"),
        (["--x", "mu1", "--y", "mu2", "--fix", "mu3"], r"--fix: expected muK=V"),
        (["--x", "mu1", "--y", "mu2", "--fix", "mu3=abc"], r"--fix: expected a number"),
        (["--x", "mu1", "--y", "mu2", "--fix", "mu3=-1"], r"--fix: expected a finite nonnegative"),
        (["--x", "mu1", "--y", "mu2", "--fix", "mu3=nan"], r"--fix: expected a finite nonnegative"),
        (["--x", "mu1", "--y", "mu2", "--fix", "mu7=0.1"], r"--fix: the scene has 3 contacts"),
        (["--x", "mu1", "--y", "mu2", "--fix", "mu2=0.1"], r"--fix: mu2 is an axis"),
        (["--x", "mu1", "--y", "mu2", "--fix", "mu3=0.1", "--fix", "mu3=0.2"], r"--fix: mu3 given twice"),
    ],
)
def test_bad_coefficients_one_line_exit_2(eq42_file, capsys, args, match):
    code, out, err = run(["muspace", str(eq42_file), *args, "--range", "0", "1", "--n", "5"], capsys)
    assert code == 2 and out == "" and err.count("\n") == 1 and "Traceback" not in err
    assert re.search(match, err), err


@pytest.mark.parametrize(
    "tail,match",
    [
        (["--range", "0", "1", "--n", "1"], r"--n: expected 2\.\.4096"),
        (["--range", "0", "1", "--n", "100000"], r"--n: expected 2\.\.4096"),
        (["--range", "1", "0", "--n", "5"], r"--range: expected LO <= HI"),
        (["--range", "-0.1", "1", "--n", "5"], r"--range: expected LO >= 0"),
        (["--range", "0", "inf", "--n", "5"], r"--range: expected finite"),
        (["--range", "0", "x", "--n", "5"], r"argument --range: invalid float value"),
        (["--range", "0", "--n", "5"], r"argument --range: expected 2 arguments"),
        (["--range", "0", "1", "--n", "two"], r"argument --n: invalid int value"),
        (["--n", "5"], r"required: --range"),
        (["--range", "0", "1", "--n", "5", "--out", "map.jpeg"], r"--out: expected a file name ending in"),
        (["--range", "0", "1", "--n", "5", "--bogus"], r"unrecognized arguments"),
    ],
)
def test_bad_grid_one_line_exit_2(eq42_file, capsys, tail, match):
    code, out, err = run(["muspace", str(eq42_file), "--x", "mu1", "--y", "mu2", *tail], capsys)
    assert code == 2 and out == "" and err.count("\n") == 1 and "Traceback" not in err
    assert re.search(match, err), err


def test_bad_scene_and_unwritable_out(tmp_path, eq42_file, capsys):
    args = ["muspace", str(tmp_path / "none.json"), "--x", "mu1", "--y", "mu2", "--range", "0", "1", "--n", "3"]
    code, out, err = run(args, capsys)
    assert code == 2 and out == "" and "cannot read scene file" in err and err.count("\n") == 1
    blocker = tmp_path / "file"
    blocker.write_text("")
    code, out, err = run(["muspace", str(eq42_file), "--x", "mu1", "--y", "mu2", "--range", "0", "1", "--n", "3",
                          "--out", str(blocker / "m.png")], capsys)  # fmt: skip
    assert code == 2 and out == "" and err.startswith("qsplan: error: --out: cannot write") and err.count("\n") == 1


def test_console_subprocess(eq42_file):
    ok = subprocess.run([sys.executable, "-m", "qsplan.planner.cli", "muspace", str(eq42_file), "--x", "mu1", "--y", "mu2",
                         "--range", "0", "1.5", "--n", "40", "--json"], capture_output=True, text=True)  # fmt: skip
    assert ok.returncode == 0 and ok.stderr == ""
    assert len(json.loads(ok.stdout)["cells"]) == 40
    bad = subprocess.run([sys.executable, "-m", "qsplan.planner.cli", "muspace", str(eq42_file), "--x", "mu9", "--y", "mu2",
                          "--range", "0", "1", "--n", "4"], capture_output=True, text=True)  # fmt: skip
    assert bad.returncode == 2 and bad.stdout == "" and len(bad.stderr.splitlines()) == 1


def test_plots_return_axes():
    from qsplan.planner.plotting.muspace import plot_contact_scene, plot_mu_map

    scene = scene_from_dict(eq42_scene())
    xs = np.linspace(0, 1.5, 30)
    ax = plot_mu_map(mu_slice(scene, 0, 1, xs, xs))
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert any("boundary of R2S1 (4)" in t for t in labels) and any("[ambiguous]" in t for t in labels)
    assert len(ax.lines) >= 2  # exact boundary curves drawn
    ax = plot_contact_scene(scene)
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "triangle p12 p23 p31" in labels and "line of action of $g_{obj}$" in labels
    assert "feasible" in ax.get_title()
    ax = plot_contact_scene(scene, mode="SRB", mu=[0.5, 0.5, 0.5])
    assert ax.get_title().startswith("R2S1 (SRB)")
