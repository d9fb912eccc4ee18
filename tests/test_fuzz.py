"""Fuzzing the inputs (issues 12, 21): mutated scene, task and hand files, TOML dotted keys, hostile options.

Every outcome is a clean result (exit 0 or 1), a task accepted up to planning, or a one-line exit-2
error; never a traceback or a hang (a case still running after ``CASE_SECONDS`` is one; how long cases take is
for ``benchmarks/bench_fuzz.py`` and ``bench_refusals.py`` to print, not for a test to assert).  The fuzzer is
:mod:`tests.fuzzing` (seeded); ``benchmarks/bench_fuzz.py`` runs it at 10,000 cases.  A few cases run the installed
``qsplan`` in a subprocess, Ctrl-C included, and deep dotted keys (1,200 levels; 40 kB) through
``modes``, ``plan`` and ``hands``.
"""

import json
import random
import re
import signal
import subprocess
import sys
import tomllib

import pytest

from qsplan.mechanics.model.fields import MAX_DEPTH, nesting_depth
from qsplan.planner.cli.main import main
from tests.fuzzing import CASE_MIX, CLEAN, ROOT, dotted_key, dotted_text, make_cases, run_case, seed_scenes, toml_text

#: Cases per run.
N_CASES = 300

#: Seconds after which a case counts as hung (outcome "timeout"): a guard against a wait forever, far above any
#: case on a loaded machine (the slowest of the 300 takes ~4 s here); not a speed claim (``benchmarks/bench_fuzz.py``
#: prints the slowest case).
CASE_SECONDS = 120.0


def test_fuzz_every_outcome_is_clean(tmp_path):
    bad = []
    for i, case in enumerate(make_cases(seed=2024, n=N_CASES)):
        outcome, seconds, err = run_case(case, tmp_path / f"c{i}", timeout=CASE_SECONDS)
        if outcome not in CLEAN:
            bad.append((i, outcome, case["argv"], err[-300:]))
    assert not bad, bad[:5]


def test_fuzz_cases_are_seeded():
    a, b = make_cases(seed=5, n=20), make_cases(seed=5, n=20)
    assert [c["argv"] for c in a] == [c["argv"] for c in b] and [c.get("file") for c in a] == [c.get("file") for c in b]


def test_fuzz_covers_hand_files_and_dotted_keys():
    cases = make_cases(seed=2024, n=N_CASES)
    kinds = {c["kind"] for c in cases}
    assert kinds == {k for k, _ in CASE_MIX} and {"hand", "dotted"} <= kinds
    hand_commands = {c["argv"][0] for c in cases if c["kind"] == "hand"}
    assert hand_commands == {"hands", "plan"}  # the file alone, and through a task's [hand] file = "hand.toml"
    assert all("hand.toml" in c["extra"] for c in cases if c["kind"] == "hand" and c["argv"][0] == "plan")
    assert {c["argv"][0] for c in cases if c["kind"] == "dotted"} == {"modes", "plan", "hands"}


def _true_depth(value) -> int:
    """Levels of lists and tables below ``value`` (a parsed document's value)."""
    if isinstance(value, dict):
        return 1 + max(map(_true_depth, value.values()), default=0)
    if isinstance(value, list):
        return 1 + max(map(_true_depth, value), default=0)
    return 0


def test_nesting_depth_of_dotted_keys_is_the_parsed_depth():
    """The pre-parse scan equals the depth tomllib builds, for seeded deep dotted keys in every position."""
    rng = random.Random(21)
    base = [(ROOT / "hands" / "data" / "two_link_hand.toml").read_text(), (ROOT / "planner" / "data" / "demo_task.toml").read_text(),
            toml_text(seed_scenes()["joints_toml"][0])]  # fmt: skip
    for k in range(200):
        text = dotted_text(base[k % 3], rng, depth=rng.randint(1, MAX_DEPTH + 2)).replace("name.", "name_.")
        doc = tomllib.loads(text)
        assert nesting_depth(text, toml=True) == max(map(_true_depth, doc.values())), text[:200]


#: Times the scan of a TOML text may read each of its characters: once by the pattern that takes a key path or
#: skips blanks, once by the search for the next character that matters (measured: exactly once for a dotted key).
#: A scan that went back over a key path (tomllib's dotted keys: quadratic) reads it once per key.
SCAN_PASSES = 2


class _Counted:
    """A compiled pattern of :mod:`qsplan.mechanics.model.fields` that adds to ``read[0]`` the characters each call
    reads (from where it starts to where it stops) and counts the calls in ``read[1]``."""

    def __init__(self, pattern, read):
        self.pattern, self.read = pattern, read

    def _count(self, start, stop):
        self.read[0] += max(stop - start, 0)
        self.read[1] += 1

    def match(self, text, pos=0):
        m = self.pattern.match(text, pos)
        self._count(pos, m.end() if m else pos)
        return m

    def search(self, text, pos=0):
        m = self.pattern.search(text, pos)
        self._count(pos, m.end() if m else len(text))
        return m

    def findall(self, text):
        self._count(0, len(text))
        return self.pattern.findall(text)

    def sub(self, repl, text):
        self._count(0, len(text))
        return self.pattern.sub(repl, text)


@pytest.mark.parametrize("where", ["line", "header", "inline"])
def test_nesting_depth_is_linear_in_a_dotted_keys_length(monkeypatch, where):
    """The scan reads each character a bounded number of times (``SCAN_PASSES``), so its work is linear in the
    key's length: counted through every pattern it uses, not timed (``benchmarks/bench_refusals.py`` times it)."""
    from qsplan.mechanics.model import fields

    read = [0, 0]
    for name, value in vars(fields).copy().items():
        if isinstance(value, re.Pattern):
            monkeypatch.setattr(fields, name, _Counted(value, read))
    for depth in (20_000, 1_000_000):  # 40 kB and 2 MB
        key = dotted_key(depth, random.Random(depth))
        text = {"line": f"{key} = 1\n", "header": f"[{key}]\nx = 1\n", "inline": f"zz = {{ {key} = 1 }}\n"}[where]
        read[:] = [0, 0]
        assert nesting_depth(text, toml=True) == depth - 1 + {"line": 0, "header": 1, "inline": 1}[where]
        assert 0 < read[0] <= SCAN_PASSES * len(text) and read[1] <= 16, (read, len(text))


def _qsplan(*args, **kwargs):
    return subprocess.run([sys.executable, "-m", "qsplan.planner.cli", *args], capture_output=True, text=True,
                          timeout=60, **kwargs)  # fmt: skip


@pytest.mark.parametrize(
    "data",
    [json.dumps({"g_obj": [0, -1, 0]}).encode("utf-16"), b'{"g_obj": ' + b"[" * 200_000 + b"]" * 200_000 + b"}",
     b'{"g_obj": [0, -1, 1e308], "contacts": [{"r": [0, 0], "n": [0, 1e308], "mu": 0.3, "velocity": [0, 1]}]}'],
    ids=["utf16", "deep", "huge"],
)  # fmt: skip
def test_subprocess_hostile_scene_one_line(tmp_path, data):
    path = tmp_path / "s.json"
    path.write_bytes(data)
    p = _qsplan("modes", str(path), "--workers", "1")
    assert p.returncode == 2 and p.stderr.count("\n") == 1 and p.stderr.startswith("qsplan: error: ")


@pytest.mark.parametrize("command,depth,where", [
    ("modes", 1200, "line"), ("modes", 20_000, "header"), ("plan", 1200, "inline"), ("plan", 20_000, "line"),
    ("hands", 1200, "array-header"), ("hands", 20_000, "line"),
])  # fmt: skip
def test_subprocess_deep_dotted_key_one_line(tmp_path, monkeypatch, capsys, command, depth, where):
    """Refused in one line before any TOML parser sees the text (before the scan counted dotted keys, tomllib took
    19.5 s and 1.6 GiB on a 40 kB key): in a subprocess as a user runs it, and in-process with the parser made to
    fail the test."""
    key = ".".join(["a"] * depth)  # 1,200 levels: 2.4 kB; 20,000: 40 kB
    extra = {"line": f"{key} = 1\n", "inline": f"zz = {{ {key} = 1 }}\n", "header": f"[{key}]\nx = 1\n",
             "array-header": f"[[{key}]]\nx = 1\n"}[where]  # fmt: skip
    source = {"modes": toml_text(seed_scenes()["joints_toml"][0]),
              "plan": (ROOT / "planner" / "data" / "two_link_task.toml").read_text(),
              "hands": (ROOT / "hands" / "data" / "two_link_hand.toml").read_text()}[command]  # fmt: skip
    path = tmp_path / "input.toml"
    path.write_text(extra + source)
    argv = {"modes": ["modes", str(path), "--workers", "1"], "plan": ["plan", str(path), "--out", str(tmp_path / "out")],
            "hands": ["hands", str(path)]}[command]  # fmt: skip
    p = _qsplan(*argv)
    assert p.returncode == 2 and p.stderr.count("\n") == 1, p.stderr[-500:]
    assert p.stderr.startswith(f"qsplan: error: {path}: ") and f"nests lists/tables {nesting_depth(extra + source, True)} deep" in p.stderr
    assert nesting_depth(extra + source, True) >= depth - 1
    assert p.stdout == "" and not (tmp_path / "out").exists()

    def parsed(*args, **kwargs):
        raise AssertionError("a TOML parser read the text")

    monkeypatch.setattr(tomllib, "loads", parsed)
    monkeypatch.setattr(tomllib, "load", parsed)
    assert main(argv) == 2
    assert capsys.readouterr().err == p.stderr


def test_ctrl_c_leaves_no_partial_file(tmp_path):
    out = tmp_path / "paper"
    proc = subprocess.Popen([sys.executable, "-m", "qsplan.planner.cli", "paper", "--n", "321", "--out", str(out)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)  # fmt: skip
    assert "eq. (37)" in proc.stderr.readline()  # the examples are being computed (321 x 321 grids: seconds)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    if proc.returncode == 0:
        pytest.skip("the run finished before the interrupt")
    assert proc.returncode == 130 and err.splitlines()[-1] == "qsplan: interrupted"
    assert "Traceback" not in err
    left = [p.name for p in out.iterdir()] if out.exists() else []
    assert not [n for n in left if n.endswith(".tmp")], left
