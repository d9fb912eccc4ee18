"""``qsplan hands``: list the bundled hands, show one, draw it; a bad file exits 2 in one line."""

import subprocess
import sys

import pytest

from qsplan.hands.description import bundled_hands
from qsplan.planner.cli.main import COMMANDS, main


def run(args, capsys):
    code = main(args)
    out, err = capsys.readouterr()
    return code, out, err


def test_hands_is_registered():
    assert "hands" in COMMANDS


def test_list_names_every_bundled_hand_with_its_joint_kinds(capsys):
    code, out, err = run(["hands"], capsys)
    assert code == 0 and err == ""
    lines = out.splitlines()
    assert len(lines) == 2 + len(bundled_hands())
    rows = {line.split()[0]: line for line in lines[2:]}
    assert set(rows) == set(bundled_hands())
    assert "revolute, revolute  revolute, revolute" in rows["two_link_hand"]
    assert rows["parallel_jaw"].count("prismatic") == 2
    for name, line in rows.items():
        assert line.rstrip().endswith(f"bundled:{name}")


def test_show_prints_joints_with_units(capsys):
    code, out, err = run(["hands", "two_link_hand"], capsys)
    assert code == 0 and err == ""
    assert "hand: two-link hand" in out and "source: bundled:two_link_hand" in out
    assert "paper's two-finger form: no" in out
    for name in ("left_proximal", "left_distal", "right_proximal", "right_distal"):
        assert name in out
    assert "[0.05, 3.09] rad" in out and "[-2.6, 2.6] rad" in out and "0.5 rad/s" in out
    code, out, _ = run(["hands", "parallel_jaw"], capsys)
    assert out.count("[0, 0.1] m") == 2 and "0.05 m/s" in out and "prismatic" in out
    code, out, _ = run(["hands", "paper_hand"], capsys)
    assert "paper's two-finger form: yes" in out and "finger_length = 0.16 m" in out


def test_show_a_file_and_draw_it(tmp_path, capsys, monkeypatch):
    path = tmp_path / "my hand.toml"
    path.write_text(bundled_hands()["parallel_jaw"].read_text())
    monkeypatch.chdir(tmp_path)
    code, out, err = run(["hands", "my hand.toml", "--out", "pics"], capsys)
    assert code == 0 and err == ""
    png = tmp_path / "pics" / "hand_my_hand.png"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert f"wrote {png.relative_to(tmp_path)}" in out
    # an existing picture is replaced only with --force, checked before anything is printed
    code, out, err = run(["hands", "my hand.toml", "--out", "pics"], capsys)
    assert code == 2 and out == "" and "--force" in err and len(err.splitlines()) == 1
    code, out, err = run(["hands", "my hand.toml", "--out", "pics", "--force"], capsys)
    assert code == 0


def test_draw_a_bundled_hand(tmp_path, capsys):
    code, out, _ = run(["hands", "two_link_hand", "--out", str(tmp_path)], capsys)
    assert code == 0 and (tmp_path / "hand_two_link_hand.png").is_file()


@pytest.mark.parametrize("text,expected", [
    ('name = "x"\n[palm\n', "invalid TOML"),
    (None, "no such hand file"),
    ('name = "x"\n[palm]\npolygon = [[0, 0], [1, 0], [0, 1]]\n', "fingers: missing"),
])  # fmt: skip
def test_bad_file_exits_2_with_one_line(tmp_path, capsys, text, expected):
    path = tmp_path / "bad.toml"
    if text is not None:
        path.write_text(text)
    code, out, err = run(["hands", str(path)], capsys)
    assert code == 2 and out == ""
    assert len(err.splitlines()) == 1
    assert err.startswith(f"qsplan: error: {path}: ") and expected in err


def test_out_without_a_hand_is_a_usage_error(tmp_path, capsys):
    code, out, err = run(["hands", "--out", str(tmp_path)], capsys)
    assert code == 2 and out == "" and err.startswith("qsplan: error: --out:")


def test_hands_help_and_list_import_nothing_heavy():
    probe = ("from qsplan.planner.cli.main import main\ntry:\n    main(['hands', '--help'])\nexcept SystemExit:\n    pass\n"
             "import sys\nprint(sorted(m for m in ('numpy', 'shapely', 'matplotlib', 'scipy') if m in sys.modules))")  # fmt: skip
    p = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True)
    assert p.stdout.splitlines()[-1] == "[]"
