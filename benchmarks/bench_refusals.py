"""How long a refusal, a fault's error and a Ctrl-C take: the wall times the tests used to assert, as a table.

The tests check that each of these comes before the work it guards (the planner, the partition table, a TOML
parser, a connection are never reached), that an error names the timeout it waited, and that a Ctrl-C leaves one
line (``tests/planner/test_plan_collisions.py``, ``test_output_safety.py``, ``tests/test_fuzz.py``,
``tests/mechanics/test_partition.py``, ``test_mode_search.py``, ``test_faults.py``).  Here each is timed on this
machine beside the bound a test once asserted (wall times depend on the machine and its load, so no test does).

In-process cases call ``qsplan``'s ``main`` (imports already paid); ``subprocess`` cases run the command as a user
does (interpreter start and imports included).  Cases that need Dask ``distributed`` are skipped without it.

Usage, from the repository root::

    python3 benchmarks/bench_refusals.py [--repeat 3]
"""

import argparse
import contextlib
import io
import json
import os
import random
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))  # the repository root, for tests.fuzzing's dotted keys

from qsplan.mechanics import planted_scene, solve  # noqa: E402
from qsplan.mechanics import parallel  # noqa: E402
from qsplan.mechanics.model.fields import nesting_depth  # noqa: E402
from qsplan.mechanics.model.scene_io_write import scene_to_dict  # noqa: E402
from qsplan.planner.cli.main import main as qsplan  # noqa: E402
from qsplan.planner.export.files import locked_out_dir  # noqa: E402
from qsplan.planner.task.task import task_paths  # noqa: E402
from tests.fuzzing import dotted_key, seed_scenes, toml_text  # noqa: E402

#: Seconds after which a subprocess counts as hung (a guard for the benchmark itself).
HANG_GUARD = 600

PY = [sys.executable, "-m", "qsplan.planner.cli"]


def quiet(argv) -> int:
    """``qsplan ARGV`` in-process, its output swallowed; the exit status."""
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        return qsplan(argv)


def timed(f, repeat):
    """``(last result, median seconds, worst seconds)`` of ``repeat`` calls of ``f``."""
    times, out = [], None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = f()
        times.append(time.perf_counter() - t0)
    return out, float(np.median(times)), max(times)


def _exit_in_worker(x):
    """Kill the worker process running it (never the benchmark itself)."""
    import multiprocessing

    if multiprocessing.parent_process() is not None:
        os._exit(3)
    return x


def lost_twice() -> str:
    """A local pool whose workers die, and again in a new pool: the error's class."""
    try:
        parallel.map_chunks(_exit_in_worker, [1, 2, 3], workers=2)
    except Exception as exc:  # noqa: BLE001 - the error is the result
        return type(exc).__name__
    return "none"


@contextlib.contextmanager
def silent_server():
    """A TCP server on 127.0.0.1 that accepts connections and never sends a byte; yields its address."""
    import socket
    import threading

    srv = socket.socket()
    srv.bind(("127.0.0.1", 0))
    srv.listen(8)
    held = []

    def accept():
        while True:
            try:
                held.append(srv.accept()[0])
            except OSError:
                return

    threading.Thread(target=accept, daemon=True).start()
    try:
        yield f"tcp://127.0.0.1:{srv.getsockname()[1]}"
    finally:
        srv.close()
        for c in held:
            c.close()


def run(argv, **kwargs) -> int:
    return subprocess.run(argv, capture_output=True, text=True, timeout=HANG_GUARD, **kwargs).returncode


def interrupted(argv, ready: str) -> tuple:
    """``(exit status, seconds from SIGINT to exit)``: ``argv`` started in its own process group, the group sent
    SIGINT (a terminal's Ctrl-C) once a stderr line holds ``ready`` and the pool's workers run."""
    proc = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, process_group=0)
    while ready not in proc.stderr.readline():
        pass
    deadline = time.monotonic() + HANG_GUARD
    while time.monotonic() < deadline:
        with open(f"/proc/{proc.pid}/task/{proc.pid}/children") as f:
            if len(f.read().split()) >= 2:
                break
        time.sleep(0.05)
    t0 = time.perf_counter()
    os.killpg(proc.pid, signal.SIGINT)
    proc.communicate(timeout=HANG_GUARD)
    return proc.returncode, time.perf_counter() - t0


def cases(tmp: Path):
    """``(what, former bound in s or None, callable returning an exit status or a value)``."""
    out = []
    for depth in (20_000, 1_000_000):
        text = dotted_key(depth, random.Random(depth)) + " = 1\n"
        out.append((f"nesting_depth of a {len(text) / 1e6:.2g} MB dotted key (in-process)",
                    0.05 * depth / 20_000 + 0.5, lambda text=text: nesting_depth(text, toml=True)))  # fmt: skip
    key = ".".join(["a"] * 20_000)
    sources = {"modes": toml_text(seed_scenes()["joints_toml"][0]),
               "plan": (ROOT / "planner" / "data" / "two_link_task.toml").read_text(),
               "hands": (ROOT / "hands" / "data" / "two_link_hand.toml").read_text()}  # fmt: skip
    for command, source in sources.items():
        path = tmp / f"dotted_{command}.toml"
        path.write_text(f"{key} = 1\n" + source)
        argv = {"modes": ["modes", str(path), "--workers", "1"], "plan": ["plan", str(path), "--out", str(tmp / "o")],
                "hands": ["hands", str(path)]}[command]  # fmt: skip
        out.append((f"qsplan {command}: a 40 kB dotted key refused (subprocess)", 3.0, lambda a=argv: run(PY + a)))
    crossing = tmp / "pentagon16.toml"
    crossing.write_text(task_paths()["pentagon_task"].read_text().replace("finger_length = 0.11", "finger_length = 0.16"))
    out.append(("qsplan plan: an invalid start refused (in-process)", 5.0,
                lambda: quiet(["plan", str(crossing), "--out", str(tmp / "p"), "--quiet", "--no-plots", "--force"])))
    held = tmp / "held"

    def into_held():
        with locked_out_dir(held):
            return quiet(["demo", "--out", str(held), "--no-plots", "--verify", "0", "--quiet"])

    out.append(("qsplan demo: a held --out refused (in-process)", 5.0, into_held))
    if os.path.isdir("/sys"):
        out.append(("qsplan demo --out /sys refused (in-process)", 5.0,
                    lambda: quiet(["demo", "--out", "/sys", "--no-plots", "--verify", "0", "--quiet"])))
        out.append(("qsplan paper --out /sys refused (in-process)", 5.0, lambda: quiet(["paper", "--n", "3", "--out", "/sys"])))
    scene, _ = planted_scene(np.random.default_rng(5), 16, 3, 5)
    n16 = tmp / "n16.json"
    n16.write_text(json.dumps(scene_to_dict(scene)))
    out.append(("qsplan partition: a 16-contact table refused (in-process)", 5.0, lambda: quiet(["partition", str(n16)])))
    out.append(("a local worker lost twice: ParallelError (in-process)", 30.0, lost_twice))
    scene26, _ = planted_scene(np.random.default_rng([1995, 26, 1]), 26, 1)
    out.append(("solve(search='auto'): n_c = 26, one effort joint (gives up pruning)", 10.0,
                lambda: len(solve(scene26, workers=1).feasible_modes)))  # fmt: skip
    try:
        import distributed  # noqa: F401
    except ImportError:
        return out
    out.append(("--scheduler foo refused (in-process)", 2.0, lambda: quiet(["modes", str(ROOT / "examples/scenes/eq42.json"),
                                                                           "--scheduler", "foo"])))  # fmt: skip

    def never_answers():
        with silent_server() as address:
            return quiet(["modes", str(ROOT / "examples/scenes/eq42.json"), "--scheduler", address])

    out.append((f"--scheduler: a server that never answers (CONNECT_TIMEOUT {parallel.CONNECT_TIMEOUT:g} s, in-process)",
                None, never_answers))  # fmt: skip
    out.append(("--scheduler inproc://x refused (subprocess)", None,
                lambda: run(PY + ["sweep", "--samples", "200", "--no-plots", "--out", str(tmp / "s"),
                                  "--scheduler", "inproc://x"])))  # fmt: skip
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3, help="runs of each case (default 3): the median and the worst")
    args = ap.parse_args(argv)
    print(f"{'case':<72} {'result':>13} {'median s':>9} {'worst s':>8} {'once asserted':>13}")
    with tempfile.TemporaryDirectory() as tmp:
        for what, bound, f in cases(Path(tmp)):
            result, median, worst = timed(f, args.repeat)
            print(f"{what:<72} {result!s:>13} {median:>9.3f} {worst:>8.3f} {'< ' + format(bound, 'g') if bound else '':>13}")
        if os.path.exists(f"/proc/{os.getpid()}/task/{os.getpid()}/children"):
            scene, _ = planted_scene(np.random.default_rng([1995, 16, 13]), 16, 13, 15)
            path = Path(tmp) / "n16_13.json"
            path.write_text(json.dumps(scene_to_dict(scene)))
            argv = PY + ["modes", str(path), "--search", "all", "--workers", "2"]
            runs = [interrupted(argv, "this takes about") for _ in range(args.repeat)]
            seconds = [s for _, s in runs]
            print(f"{'Ctrl-C: qsplan modes, 2 workers running, SIGINT to exit (subprocess)':<72} "
                  f"{'/'.join(sorted({str(c) for c, _ in runs})):>13} {np.median(seconds):>9.3f} {max(seconds):>8.3f} {'':>13}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
