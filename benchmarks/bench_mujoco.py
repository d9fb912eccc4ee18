"""Certified plans executed in MuJoCo at every vertex of their friction set (issue 24's acceptance; issue 31, item 6).

Run: ``python3 benchmarks/bench_mujoco.py [--random N] [--own | --bundled] [--json FILE] [TASK ...]`` (needs
``pip install '.[sim]'``).  The tasks: every bundled task (``qsplan.planner.task.task.task_paths``;
``friction_closes_task`` has no plan, on purpose) and this directory's ``mujoco_tasks/*.toml`` (issue 31's two cases
and tasks of other shapes, friction sets, hands, slides, regrasps and turns); ``TASK`` picks some by name.  Each is
planned and certified as ``qsplan plan`` does (:func:`qsplan.planner.pipeline.run.run_plan`, no plots), then
:func:`qsplan.planner.replay.mujoco_replay.replay_mujoco` runs the exported commands at 1 kHz, no stop added, at the
friction set's vertices and ``--random`` seeded points (seed 0), as ``qsplan replay DIR --engine mujoco`` does.

The table: certified (or why not), ``qsplan replay``'s exit code (0 when every run kept the planned modes where
MuJoCo resolves them and the workpiece within the pose tolerance of the plan at the measured joints), runs,
pair letters not resolvable, the largest workpiece error (mm) against the row, the servos' share of it, what
remains off the plan at the measured joints (in contact), the largest drift from the release over a regrasp,
wall time, and the first failing run.  The acceptance (issue 31): every certified plan's replay exits 0, or each
exception is a documented, measured limit of the engine.  One process, one core: the machine is shared.
"""

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

#: This benchmark's own tasks (TOML task files).
OWN_TASKS = Path(__file__).resolve().parent / "mujoco_tasks"

#: Seed of the random friction vectors besides the vertices.
SEED = 0


def tasks(which: str, names) -> list:
    """``[(name, path)]`` of the bundled tasks and/or this directory's, sorted by name within each."""
    from qsplan.planner.task.task import task_paths

    out = []
    if which in ("all", "bundled"):
        out += sorted(task_paths().items())
    if which in ("all", "own"):
        out += [(p.stem, p) for p in sorted(OWN_TASKS.glob("*.toml"))]
    if names:
        known = dict(out)
        missing = [n for n in names if n not in known]
        if missing:
            raise SystemExit(f"unknown task {missing[0]!r}; known: {', '.join(known)}")
        out = [(n, known[n]) for n in names]
    return out


def run_one(name, path, n_random, keep=None, planned=None) -> dict:
    """Plan, certify and replay one task; a row of the table as a dict (``keep``: a directory to leave the plan and
    its replay, ``mujoco.json``, in, under the task's name; ``planned``: such a directory of an earlier run, whose
    plans are replayed again without planning)."""
    from qsplan.planner import PlanFailure, load_task
    from qsplan.planner.pipeline.run import run_plan
    from qsplan.planner.replay.mujoco_replay import replay_mujoco

    task = load_task(path)
    row = {"task": name}
    with tempfile.TemporaryDirectory() as tmp:
        if keep is not None:
            tmp = Path(keep) / name
        t0 = time.perf_counter()
        why = None
        if planned is None:
            try:
                run_plan(task, tmp, plots=False, verify=0, force=True)
            except PlanFailure as exc:
                why = str(exc).splitlines()[0]
        else:
            tmp = Path(planned) / name
            if (tmp / "failure.json").exists():
                why = json.loads((tmp / "failure.json").read_text())["message"].splitlines()[0]
        if why is not None:
            row.update(certified=False, why="NOT certified" if "certif" in why else "no plan", message=why[:300])
            return row
        row.update(certified=True, plan_s=time.perf_counter() - t0)
        t0 = time.perf_counter()
        result = replay_mujoco(tmp, task=task, n_random=n_random, seed=SEED)
        row["replay_s"] = time.perf_counter() - t0
        if keep is not None:
            (Path(tmp) / "mujoco.json").write_text(json.dumps(result.as_dict(), indent=1))
    runs = result.runs
    free = [r.max_path_error(~r.contact_rows) for r in runs if (~r.contact_rows).any()]
    bad = [r for r in runs if not r.ok]
    row.update(rc=0 if result.ok else 1, runs=len(runs), ok_runs=len(runs) - len(bad),
               unresolved=sum(r.unresolved for r in runs),
               letters=sum(len(r.contacts) * int(r.contact_rows.sum()) for r in runs),
               max_error_mm=result.max_error() * 1e3,
               max_servo_mm=max(float(r.servo_error.max(initial=0.0)) for r in runs) * 1e3,
               max_path_mm=max(r.max_path_error(r.contact_rows) for r in runs) * 1e3,
               max_drift_mm=max(free) * 1e3 if free else None,
               note=bad[0].summary() if bad else "")  # fmt: skip
    return row


def line(row) -> str:
    """One row of the table."""
    if not row["certified"]:
        return f"{row['task']:<30} {row['why']:>13}  ({row['message'][:90]})"
    drift = f"{row['max_drift_mm']:6.3f}" if row["max_drift_mm"] is not None else f"{'-':>6}"
    return (f"{row['task']:<30} {'yes':>13} {row['rc']:>3} {row['ok_runs']:>3}/{row['runs']:<3} "
            f"{row['unresolved']:>5} {row['max_error_mm']:8.3f} {row['max_servo_mm']:8.3f} {row['max_path_mm']:8.4f} "
            f"{drift} {row['replay_s']:7.1f}  {row['note'][:120]}")  # fmt: skip


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("tasks", nargs="*", help="task names (default: all of the chosen set)")
    ap.add_argument("--random", type=int, default=2, help="random friction points per task besides the vertices")
    group = ap.add_mutually_exclusive_group()
    group.add_argument("--own", action="store_const", dest="which", const="own", help="this directory's tasks only")
    group.add_argument("--bundled", action="store_const", dest="which", const="bundled", help="bundled tasks only")
    ap.add_argument("--json", metavar="FILE", help="also write the rows as JSON")
    ap.add_argument("--keep", metavar="DIR", help="leave each plan and its replay (mujoco.json) in DIR/<task>")
    ap.add_argument("--planned", metavar="DIR", help="replay the plans an earlier --keep DIR left, without planning")
    args = ap.parse_args(argv)
    from qsplan.planner.replay.mujoco_replay import POSE_TOLERANCE

    print(f"pose tolerance off the plan at the measured joints: {POSE_TOLERANCE * 1e3:g} mm; seed {SEED}, "
          f"{args.random} random friction vectors per task besides the vertices")  # fmt: skip
    print(f"{'task':<30} {'certified':>13} {'rc':>3} {'ok/runs':>7} {'unres':>5} {'err mm':>8} {'servo mm':>8} "
          f"{'path mm':>8} {'drift':>6} {'wall s':>7}  first failing run")  # fmt: skip
    rows = []
    for name, path in tasks(args.which or "all", args.tasks):
        rows.append(run_one(name, path, args.random, args.keep, args.planned))
        print(line(rows[-1]), flush=True)
    certified = [r for r in rows if r["certified"]]
    passed = [r for r in certified if r["rc"] == 0]
    print(f"{len(certified)} of {len(rows)} tasks certified; {len(passed)} of {len(certified)} replays exit 0")
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
