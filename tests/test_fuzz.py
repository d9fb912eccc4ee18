"""Fuzzing the inputs (issue 12): mutated scene and task files and hostile command-line options.

Every outcome is a clean result (exit 0 or 1), a task accepted up to planning, or a one-line exit-2
error, each within a time bound; never a traceback or a hang.  The fuzzer is :mod:`tests.fuzzing`
(seeded); ``benchmarks/bench_fuzz.py`` runs it at 10,000 cases.  A few cases run the installed
``qsplan`` in a subprocess, Ctrl-C included.
"""

import json
import signal
import subprocess
import sys
import time

import pytest

from tests.fuzzing import CLEAN, make_cases, run_case

#: Cases per run, and the bound on each (s): small inputs answer in well under a second.
N_CASES = 300
CASE_SECONDS = 10.0


def test_fuzz_every_outcome_is_clean(tmp_path):
    bad = []
    t0 = time.perf_counter()
    for i, case in enumerate(make_cases(seed=2024, n=N_CASES)):
        outcome, seconds, err = run_case(case, tmp_path / f"c{i}", timeout=CASE_SECONDS)
        if outcome not in CLEAN:
            bad.append((i, outcome, case["argv"], err[-300:]))
    assert not bad, bad[:5]
    assert time.perf_counter() - t0 < 60


def test_fuzz_cases_are_seeded():
    a, b = make_cases(seed=5, n=20), make_cases(seed=5, n=20)
    assert [c["argv"] for c in a] == [c["argv"] for c in b] and [c.get("file") for c in a] == [c.get("file") for c in b]


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


def test_ctrl_c_leaves_no_partial_file(tmp_path):
    out = tmp_path / "paper"
    proc = subprocess.Popen([sys.executable, "-m", "qsplan.planner.cli", "paper", "--n", "321", "--out", str(out)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)  # fmt: skip
    time.sleep(4.0)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    if proc.returncode == 0:
        pytest.skip("the run finished before the interrupt")
    assert proc.returncode == 130 and err.splitlines()[-1] == "qsplan: interrupted"
    assert "Traceback" not in err
    left = [p.name for p in out.iterdir()] if out.exists() else []
    assert not [n for n in left if n.endswith(".tmp")], left
