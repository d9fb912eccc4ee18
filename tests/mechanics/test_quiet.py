"""The LP solver is built with file descriptor 1 silenced, whatever the highspy version prints there."""

import os
import sys
import types

import pytest

from qsplan.mechanics.quiet import quiet_fd_stdout, quiet_highs


def _fake_highspy(calls):
    """A highspy that prints a banner from "C" (straight to descriptor 1) at every construction."""

    class Highs:
        def __init__(self):
            os.write(1, b"Running FakeHiGHS: Copyright (c)\n")
            calls.append("built")

        def setOptionValue(self, name, value):
            calls.append((name, value))

    return types.SimpleNamespace(Highs=Highs)


def test_quiet_highs_drops_a_banner_at_every_construction(capfd):
    calls = []
    fake = _fake_highspy(calls)
    print("before", end="")  # buffered in sys.stdout: flushed to the real stdout, not dropped
    for _ in range(3):
        quiet_highs(fake)
    print("after")
    assert capfd.readouterr().out == "beforeafter\n"
    assert calls == ["built", ("output_flag", False)] * 3


def test_descriptor_1_is_restored_after_an_error(capfd):
    with pytest.raises(RuntimeError, match="inside"):
        with quiet_fd_stdout():
            os.write(1, b"dropped\n")
            raise RuntimeError("inside")
    os.write(1, b"kept\n")
    sys.stdout.flush()
    assert capfd.readouterr().out == "kept\n"


def test_real_highspy_prints_nothing_on_stdout(capfd):
    highspy = pytest.importorskip("highspy")
    h = quiet_highs(highspy)
    h.addVars(1, [0.0], [1.0])
    h.run()
    assert capfd.readouterr().out == ""


def test_a_closed_descriptor_1_stays_closed_and_takes_no_banner(tmp_path):
    """With descriptor 1 closed, the banner goes to the null device held there, not to a file opened meanwhile."""
    import subprocess

    out = tmp_path / "opened.txt"
    code = (
        "import os, sys, types; from qsplan.mechanics.quiet import quiet_fd_stdout; os.close(1)\n"
        "with quiet_fd_stdout():\n"
        f"    fd = os.open({str(out)!r}, os.O_WRONLY | os.O_CREAT)\n"
        "    os.write(1, b'banner')\n"
        "os.close(fd)\n"
        "try:\n    os.fstat(1)\nexcept OSError:\n    sys.exit(0)\nsys.exit(3)\n"
    )
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0 and r.stderr == "", r.stderr
    assert out.read_text() == ""
