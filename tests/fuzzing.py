"""A seeded mutation fuzzer of qsplan's inputs: scene, task and hand files and command-line options (issues 12, 21).

Hand files (the bundled ``hands/data/*.toml``, mutated as data and as text: numbers scaled by 1e3, 1e-3,
1e5, written in degrees or millimetres, fields deleted or duplicated) run through ``qsplan hands FILE``
and through a task whose ``[hand]`` names the file (``file = "hand.toml"``).  Dotted keys (``a.a.a...``
bare, quoted or spaced, in key/value lines, inline tables and ``[table.headers]``, from 13 to 20,000
levels) are put into valid scene, task and hand files.

Shared by ``tests/test_fuzz.py`` (a few hundred cases) and ``benchmarks/bench_fuzz.py`` (10,000).
Each case is a command line run in-process through :func:`qsplan.planner.cli.main.main` with
stdout and stderr captured and a per-case time bound.  Outcomes:

* ``ok`` (exit 0) and ``failed`` (exit 1: ran, the result failed a check): clean results
  (``-warned`` when a numpy or Python warning reached stderr on the way);
* ``usage`` (exit 2, exactly one line on stderr): a clean refusal;
* ``accepted``: a task and ``plan`` options that passed every check up to planning (planning itself,
  OMPL, is replaced by a stub: the fuzzer checks the boundary, not the planner);
* ``multiline`` (exit 2 with more than one line), ``traceback:<Type>`` (an exception escaped
  ``main``), ``timeout`` (the case ran past its bound), ``exit:<n>``: bugs.
"""

from __future__ import annotations

import contextlib
import io
import json
import math
import random
import re
import signal
import time
import tomllib
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

#: Outcomes that are not bugs (``*-warned``: a clean result, but a numpy/Python warning reached stderr).
CLEAN = {"ok", "failed", "usage", "accepted", "ok-warned", "failed-warned"}

#: Numbers a hostile or careless user types.
HOSTILE_NUMBERS = [0, -1, 1e-300, 1e30, 1e308, -1e308, 1e21, 5e-324, 10**400, -(10**25), 1e-9, 0.5, 2.0, 100.0,
                   float("inf"), float("-inf"), float("nan")]  # fmt: skip
HOSTILE_VALUES = [None, True, "", "abc", "1e3", [], {}, [1.0], [[1.0, 2.0]], {"x": 1}, "\u00e9\u6f22", "\x00"]
HOSTILE_OPTION_TEXT = ["0", "-1", "1", "2", "3", "1e-300", "1e300", "1e308", "-1e308", "inf", "nan", "-inf",
                       "99999999999999999999", "1" * 40, "abc", "", "0x10", "1e-320", "0.5", "-0"]  # fmt: skip


class CaseTimeout(BaseException):
    """Raised by the alarm inside a case that ran past its bound (a BaseException: not swallowed)."""


class ReachedPlanning(BaseException):
    """Raised by the planning stub: every check before planning passed."""


def seed_scenes() -> dict:
    """``{name: (document, suffix)}``: the paper's raw scenes, a raw scene with joints, a geometric one."""
    from qsplan.hands.examples.paper import eq37_scene, eq42_scene, rod_scene

    joints = {
        "g_obj": [0.0, -1.0, 0.0],
        "joints": [{"control": "velocity", "velocity": 0.5}, {"control": "effort", "effort": 0.1}],
        "contacts": [
            {"wn": [0, 1, -1], "wt": [-1, 0, 0], "mu": 0.3, "jn": [0.0, 0.1], "jt": [-1.0, 0.2]},
            {"r": [1.0, 0.0], "n": [0.0, 1.0], "mu": 0.3, "jn": [0.2, 0.0], "jt": [0.5, 1.0]},
            {"r": [0.5, 1.0], "n": [0.0, -1.0], "mu": 0.2, "jn": [0.1, 0.3], "jt": [0.0, 0.4]},
        ],
    }
    geometric = tomllib.loads((ROOT / "examples" / "scenes" / "box_and_finger.toml").read_text())
    return {"eq37": (eq37_scene(), ".json"), "eq42": (eq42_scene(), ".json"), "rod": (rod_scene(), ".json"),
            "joints": (joints, ".json"), "joints_toml": (joints, ".toml"), "box": (geometric, ".toml")}  # fmt: skip


def seed_tasks() -> dict:
    """``{name: document}`` of the bundled task files."""
    return {p.stem: tomllib.loads(p.read_text()) for p in sorted((ROOT / "planner" / "data").glob("*.toml"))}


def seed_hands() -> dict:
    """``{name: text}`` of the bundled hand files, with the task that uses each (its ``[hand] file``)."""
    tasks = seed_tasks()
    out = {}
    for p in sorted((ROOT / "hands" / "data").glob("*.toml")):
        users = [t for t, doc in tasks.items() if doc.get("hand", {}).get("file") == p.stem]
        out[p.stem] = (p.read_text(), tasks[users[0]] if users else None)
    return out


def toml_text(doc: dict) -> str:
    """A TOML document with every table inline (enough for fuzzing; None becomes a string)."""

    def value(v):
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, int):
            return str(v)
        if isinstance(v, float):
            return "nan" if math.isnan(v) else ("inf" if v == math.inf else "-inf" if v == -math.inf else repr(v))
        if isinstance(v, str):
            return json.dumps(v)
        if isinstance(v, (list, tuple)):
            return "[" + ", ".join(value(x) for x in v) + "]"
        if isinstance(v, dict):
            return "{" + ", ".join(f"{json.dumps(str(k))} = {value(x)}" for k, x in v.items()) + "}"
        return json.dumps(str(v))

    return "".join(f"{json.dumps(str(k))} = {value(v)}\n" for k, v in doc.items())


def _paths(doc, prefix=()):
    """Every (path, value) in a nested document, containers included."""
    yield prefix, doc
    if isinstance(doc, dict):
        for k, v in doc.items():
            yield from _paths(v, prefix + (k,))
    elif isinstance(doc, list):
        for i, v in enumerate(doc):
            yield from _paths(v, prefix + (i,))


def _parent(doc, path):
    for k in path[:-1]:
        doc = doc[k]
    return doc


def mutate_document(doc, rng: random.Random, n_mutations: int = 2):
    """A copy of ``doc`` with ``n_mutations`` random edits: hostile leaves, typos, deletions, copies."""
    doc = json.loads(json.dumps(doc))
    for _ in range(n_mutations):
        paths = [p for p, _ in _paths(doc) if p]
        if not paths:
            break
        path = rng.choice(paths)
        parent, key = _parent(doc, path), path[-1]
        op = rng.random()
        if op < 0.45:
            parent[key] = rng.choice(HOSTILE_NUMBERS)
        elif op < 0.6:
            parent[key] = rng.choice(HOSTILE_VALUES)
        elif op < 0.7 and isinstance(parent, dict):
            parent[str(key)[:-1] + "x" if len(str(key)) > 1 else "zz"] = parent.pop(key)  # a typo in a key
        elif op < 0.8:
            if isinstance(parent, dict):
                del parent[key]
            else:
                parent.pop(key)
        elif op < 0.9 and isinstance(parent, list) and len(parent) < 6:
            parent.append(json.loads(json.dumps(parent[key])))  # one more contact, joint, vertex ...
        elif isinstance(parent[key], (int, float)) and not isinstance(parent[key], bool) and abs(parent[key]) < 1e300:
            parent[key] = parent[key] * rng.choice([1e-12, -1, 1.0001, 1e12])
        else:
            parent[key] = rng.choice(HOSTILE_NUMBERS)
    return doc


#: Factors of the unit slips and typos a hand file's numbers get: kilo, milli, 1e5, degrees.
SCALES = [1e3, 1e-3, 1e5, 180.0 / math.pi, -1.0]

_NUMBER = re.compile(r"(?<![\w.])-?\d+(?:\.\d+)?(?:[eE][-+]?\d+)?(?![\w.])")


def scale_numbers(doc, rng: random.Random):
    """A copy of ``doc`` with one number, or every number of one list (a polygon, limits), scaled by a slip."""
    doc = json.loads(json.dumps(doc))
    paths = [p for p, v in _paths(doc) if p and (_is_number(v) or (isinstance(v, list) and v))]
    if not paths:
        return doc
    path = rng.choice(paths)
    parent, key, factor = _parent(doc, path), path[-1], rng.choice(SCALES)

    def scaled(v):
        return [scaled(x) for x in v] if isinstance(v, list) else v * factor if _is_number(v) else v

    parent[key] = scaled(parent[key])
    return doc


def _is_number(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and abs(v) < 1e300


def mutate_text(text: str, rng: random.Random) -> str:
    """A TOML text edited as text: a number scaled, a line deleted or repeated, a header or a dotted key added."""
    lines = text.splitlines()
    op = rng.random()
    if op < 0.4:
        numbers = list(_NUMBER.finditer(text))
        if numbers:
            m = rng.choice(numbers)
            return text[: m.start()] + repr(float(m.group()) * rng.choice(SCALES)) + text[m.end():]
    if op < 0.6 and lines:
        del lines[rng.randrange(len(lines))]
    elif op < 0.8 and lines:
        k = rng.randrange(len(lines))
        lines.insert(k, lines[k])  # a duplicated key, header or table
    else:
        return dotted_text(text, rng)
    return "\n".join(lines) + "\n"


#: How deep the fuzzer's dotted keys go: just past MAX_DEPTH, past Python's recursion limit, 40 kB.
DOTTED_DEPTHS = [13, 50, 1200, 20000]


def dotted_key(depth: int, rng: random.Random) -> str:
    """A key path of ``depth`` keys: bare, quoted (basic or literal) or spaced around the dots."""
    style = rng.choice(["bare", "basic", "literal", "spaced", "mixed"])
    keys = {"bare": ["a"] * depth, "basic": ['"a"'] * depth, "literal": ["'a'"] * depth, "spaced": ["a"] * depth,
            "mixed": [rng.choice(["a", '"b.c"', "'d'", "e-1"]) for _ in range(depth)]}[style]  # fmt: skip
    return (" . " if style == "spaced" else ".").join(keys)


def dotted_text(text: str, rng: random.Random, depth: int | None = None) -> str:
    """``text`` (a valid TOML file) with a deep dotted key put in: a key/value line, an inline table or a header."""
    key = dotted_key(depth or rng.choice(DOTTED_DEPTHS), rng)
    where = rng.choice(["line", "inline", "header", "array-header", "under"])
    extra = {"line": f"{key} = 1\n", "inline": f"zz = {{ {key} = 1 }}\n", "header": f"[{key}]\nx = 1\n",
             "array-header": f"[[{key}]]\nx = 1\n", "under": f"name.{key} = 1\n"}[where]  # fmt: skip
    # before the first table header (a key/value line must not land in a table), or after everything
    head, sep, tail = text.partition("\n[")
    return extra + text if where in ("header", "array-header") or not sep else head + "\n" + extra + sep[1:] + tail


def encode(doc, suffix: str, rng: random.Random) -> bytes:
    """Serialise ``doc`` (JSON or TOML), sometimes damaged at the byte level."""
    text = toml_text(doc) if suffix == ".toml" else json.dumps(doc)
    r = rng.random()
    if r < 0.04:
        return text.encode("utf-16")
    if r < 0.08:
        return b"\xff\xfe\x80" + text.encode()
    if r < 0.12:
        depth = rng.choice([50, 1000, 100000])
        inner = "[" * depth + "]" * depth
        return (f'"g_obj" = {inner}\n' if suffix == ".toml" else f'{{"g_obj": {inner}}}').encode()
    if r < 0.15:
        return text.encode()[: rng.randrange(max(len(text), 1))]
    if r < 0.17:
        return text.encode("utf-8-sig")
    return text.encode()


def scene_case(rng: random.Random, seeds: dict) -> dict:
    name = rng.choice(sorted(seeds))
    doc, suffix = seeds[name]
    data = encode(mutate_document(doc, rng, rng.randint(1, 3)), suffix, rng)
    try:
        n_c = len(json.loads(data.decode()).get("contacts", [])) if suffix == ".json" else 3
    except Exception:  # noqa: BLE001 - damaged on purpose
        n_c = 3
    n_c = max(n_c, 1)
    command = rng.choice(["modes", "modes-json", "partition", "band", "muspace"])
    tail = {"modes": ["modes", "FILE", "--workers", "1"], "modes-json": ["modes", "FILE", "--json", "--workers", "1"],
            "partition": ["partition", "FILE"], "band": ["band", "FILE", "--mode", "S" * n_c],
            "muspace": ["muspace", "FILE", "--x", "mu1", "--y", "mu2", "--range", "0", "1", "--n", "4",
                        "--workers", "1"]}[command]  # fmt: skip
    return {"kind": "scene", "argv": tail, "file": data, "suffix": suffix}


def task_case(rng: random.Random, seeds: dict) -> dict:
    doc = seeds[rng.choice(sorted(seeds))]
    data = encode(mutate_document(doc, rng, rng.randint(1, 3)), ".toml", rng)
    return {"kind": "task", "argv": ["plan", "FILE", "--out", "OUT", "--quiet", "--no-plots"], "file": data,
            "suffix": ".toml"}  # fmt: skip


def hand_case(rng: random.Random, seeds: dict) -> dict:
    """A mutated bundled hand file through ``qsplan hands FILE``, or through a task naming it (``plan``)."""
    name = rng.choice(sorted(seeds))
    text, task = seeds[name]
    r = rng.random()
    if r < 0.35:
        text = toml_text(scale_numbers(tomllib.loads(text), rng))
    elif r < 0.55:
        text = toml_text(mutate_document(tomllib.loads(text), rng, rng.randint(1, 2)))
    else:
        text = mutate_text(text, rng)
    data = text.encode() if rng.random() < 0.9 else encode({}, ".toml", rng)
    if task is None or rng.random() < 0.5:
        return {"kind": "hand", "argv": ["hands", "FILE"], "file": data, "suffix": ".toml"}
    task = json.loads(json.dumps(task))
    task["hand"]["file"] = "hand.toml"  # relative to the task file's folder
    return {"kind": "hand", "argv": ["plan", "FILE", "--out", "OUT", "--quiet", "--no-plots"],
            "file": toml_text(task).encode(), "suffix": ".toml", "extra": {"hand.toml": data}}  # fmt: skip


def dotted_case(rng: random.Random, seeds: dict) -> dict:
    """A valid scene, task or hand file with a deep dotted key, through ``modes``, ``plan`` or ``hands``."""
    which = rng.choice(["scene", "task", "hand"])
    if which == "scene":
        text, argv = toml_text(seeds["scenes"]["joints_toml"][0]), ["modes", "FILE", "--workers", "1"]
    elif which == "task":
        text = (ROOT / "planner" / "data" / rng.choice(["demo_task.toml", "two_link_task.toml"])).read_text()
        argv = ["plan", "FILE", "--out", "OUT", "--quiet", "--no-plots"]
    else:
        text, argv = seeds["hands"][rng.choice(sorted(seeds["hands"]))][0], ["hands", "FILE"]
    return {"kind": "dotted", "argv": argv, "file": dotted_text(text, rng).encode(), "suffix": ".toml"}


def option_case(rng: random.Random, seeds: dict) -> dict:
    """A command line with hostile option values (files are valid)."""
    h = lambda: rng.choice(HOSTILE_OPTION_TEXT)  # noqa: E731
    scene = json.dumps(seeds["eq42"][0]).encode()
    joints = json.dumps(seeds["joints"][0]).encode()
    which = rng.choice(["count", "simulate", "muspace", "modes", "band", "plan", "paper", "verify"])
    if which == "count":
        return {"kind": "option", "argv": ["count", "--contacts", h(), "--dof", h()]}
    if which == "simulate":
        vals = [rng.choice(["1.0", "0.6", "0.3", h()]) for _ in range(8)]
        argv = ["simulate", "rod", "--l1", vals[0], "--l2", vals[1], "--mu-static", vals[2], "0.3",
                "--mu-kinetic", vals[3], "0.2", "--speed", vals[4], "--duration", vals[5]]  # fmt: skip
        if rng.random() < 0.5:
            argv += [rng.choice(["--max-step", "--min-segment", "--max-switches"]), vals[6]]
        return {"kind": "option", "argv": argv}
    if which == "muspace":
        argv = ["muspace", "FILE", "--x", rng.choice(["mu1", "mu3", "mu9", h()]), "--y", "mu2", "--range",
                rng.choice(["0", h()]), rng.choice(["1", h()]), "--n", rng.choice(["3", h()]), "--workers", "1"]
        if rng.random() < 0.3:
            argv += ["--fix", rng.choice(["mu3=0.2", f"mu3={h()}", h()])]
        return {"kind": "option", "argv": argv, "file": scene, "suffix": ".json"}
    if which == "modes":
        argv = ["modes", "FILE", "--mu", h(), "--workers", rng.choice(["1", "1", h()])]
        return {"kind": "option", "argv": argv, "file": scene, "suffix": ".json"}
    if which == "band":
        argv = ["band", "FILE", "--mode", rng.choice(["SSS", "RBS", "SS", "XYZ", h()])]
        if rng.random() < 0.6:
            argv += ["--mu-range", rng.choice(["0", h()]), rng.choice(["0.5", h()])]
        return {"kind": "option", "argv": argv, "file": joints, "suffix": ".json"}
    if which == "plan":
        argv = ["plan", str(ROOT / "planner" / "data" / "demo_task.toml"), "--out", "OUT", "--quiet", "--no-plots",
                rng.choice(["--verify", "--time-limit", "--seed"]), h()]  # fmt: skip
        return {"kind": "option", "argv": argv}
    if which == "paper":
        return {"kind": "option", "argv": ["paper", "--out", "OUT", "--n", rng.choice(["0", "1", "-5", "1" * 30, "abc"])]}
    return {"kind": "option", "argv": ["verify", "OUT", "--random", h(), "--seed", h()]}


#: The share of each kind of case (they add up to 1).
CASE_MIX = (("scene", 0.35), ("task", 0.2), ("hand", 0.2), ("dotted", 0.1), ("option", 0.15))


def make_cases(seed: int, n: int) -> list:
    """``n`` seeded cases, of each kind in the shares of :data:`CASE_MIX`."""
    rng = random.Random(seed)
    seeds = {"scenes": seed_scenes(), "tasks": seed_tasks(), "hands": seed_hands()}
    makers = {"scene": (scene_case, "scenes"), "task": (task_case, "tasks"), "hand": (hand_case, "hands"),
              "dotted": (dotted_case, None), "option": (option_case, "scenes")}  # fmt: skip
    out = []
    for _ in range(n):
        r, kind = rng.random(), CASE_MIX[-1][0]
        for k, share in CASE_MIX:
            if r < share:
                kind = k
                break
            r -= share
        make, key = makers[kind]
        out.append(make(rng, seeds if key is None else seeds[key]))
    return out


def _stub_planning(*args, **kwargs):
    raise ReachedPlanning()


def run_case(case: dict, workdir: Path, timeout: float = 10.0) -> tuple:
    """Run one case in-process; returns ``(outcome, seconds, stderr)``."""
    from qsplan.planner.cli.main import main
    from qsplan.planner.pipeline import run as pipeline

    workdir.mkdir(parents=True, exist_ok=True)
    argv = list(case["argv"])
    if "file" in case:
        path = workdir / f"input{case['suffix']}"
        path.write_bytes(case["file"])
        argv = [str(path) if a == "FILE" else a for a in argv]
    for name, data in case.get("extra", {}).items():  # files the input names (a task's hand file)
        (workdir / name).write_bytes(data)
    argv = [str(workdir / "out") if a == "OUT" else a for a in argv]
    out, err = io.StringIO(), io.StringIO()

    def alarm(signum, frame):
        raise CaseTimeout()

    saved_plan, pipeline.plan_task = pipeline.plan_task, _stub_planning
    old = signal.signal(signal.SIGALRM, alarm)
    signal.setitimer(signal.ITIMER_REAL, timeout)
    t0 = time.perf_counter()
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            code = main(argv)
        outcome = {0: "ok", 1: "failed"}.get(code)
        if outcome and "Warning:" in err.getvalue():
            outcome += "-warned"
        if code == 2:
            outcome = "usage" if err.getvalue().count("\n") == 1 and err.getvalue().endswith("\n") else "multiline"
        outcome = outcome or f"exit:{code}"
    except ReachedPlanning:
        outcome = "accepted"
    except CaseTimeout:
        outcome = "timeout"
    except BaseException as exc:  # noqa: BLE001 - every escape is a finding
        outcome = f"traceback:{type(exc).__name__}"
        err.write(f"{type(exc).__name__}: {exc}\n")
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)
        pipeline.plan_task = saved_plan
    return outcome, time.perf_counter() - t0, err.getvalue()


def run_fuzz(seed: int, n: int, workdir: Path, timeout: float = 10.0, on_case=None) -> Counter:
    """Run ``n`` seeded cases; returns the outcome counts (``on_case(case, outcome, seconds, stderr)`` per case)."""
    counts = Counter()
    for i, case in enumerate(make_cases(seed, n)):
        outcome, seconds, err = run_case(case, workdir / f"case{i}", timeout)
        counts[f"{case['kind']}:{outcome}"] += 1
        if on_case is not None:
            on_case(case, outcome, seconds, err)
    return counts
