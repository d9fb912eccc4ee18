"""``qsplan plan``: plan a two-finger task through OMPL with guaranteed torque bands, plots and export.

::

    qsplan plan TASK.toml [--out DIR] [--seed S] [--planner NAME] [--time-limit SECONDS] [--force] [--quiet] [--no-plots] [--verify N]

Reads the task (:mod:`planner.task`), plans it (:func:`planner.plan.plan_task`:
in-contact segments through OMPL with the band validity checker, regrasps in
joint space), and writes into DIR (default ``out/plan``) ``plan.csv`` and
``plan.json`` (the torque trajectory: :mod:`planner.plan_export`), ``replay.json``
(the exported file re-simulated, :mod:`planner.replay`, at ``--verify`` friction
vectors of the interval; exit 1 if any run leaves the planned modes) and, unless
``--no-plots``, ``plan_bands.png``, ``mode_timeline.png`` and ``hand_snapshots.png``.
Existing files are not overwritten without ``--force`` (checked first).  Progress
lines go to stderr unless ``--quiet``; a summary to stdout.

When no plan exists the report (where the band closes, which mode closes it, at
which friction) is written to DIR/failure.json and the command fails with one
line on stderr naming it (exit 2).
"""

from __future__ import annotations

import sys

__all__ = ["add_parser", "run", "run_task"]

_FILES = ("plan.csv", "plan.json", "replay.json")
_PLOTS = ("plan_bands", "mode_timeline", "hand_snapshots")


def _common(p, default_out):
    from qsplan.planner.planning.ompl_bridge import PLANNERS

    p.add_argument("--out", default=default_out, metavar="DIR", help=f"output directory (default {default_out})")
    p.add_argument("--seed", type=int, default=1, metavar="S", help="OMPL's random seed (default 1)")
    p.add_argument("--planner", choices=PLANNERS, default="RRTConnect", help="OMPL planner (default RRTConnect)")
    p.add_argument("--time-limit", type=float, default=None, metavar="SECONDS",
                   help="time limit of each OMPL query (default 120; the iteration budget decides first)")
    p.add_argument("--force", action="store_true", help="overwrite existing files in DIR")
    p.add_argument("--quiet", action="store_true", help="no progress lines on stderr")
    p.add_argument("--no-plots", action="store_true", help="write the torque trajectory only")
    p.add_argument("--verify", type=int, default=3, metavar="N",
                   help="re-simulate the exported plan at N friction vectors from the interval (the two uniform "
                        "extremes, then seeded random ones; 0: skip; default 3)")  # fmt: skip


def add_parser(subparsers):
    p = subparsers.add_parser("plan", help="plan a two-finger task (TOML) through OMPL with guaranteed torque bands")
    p.add_argument("task", help="task file (.toml; see planner.task)")
    _common(p, "out/plan")
    return p


def run_task(task, args, out) -> int:
    """Plan ``task`` and write the outputs as ``args`` ask (shared by ``qsplan demo``)."""
    import json
    from dataclasses import replace
    from pathlib import Path

    from qsplan.mechanics import QsplanError

    from qsplan.planner.planning.plan import DEFAULT_OPTIONS, PlanFailure, plan_task

    if args.verify < 0:
        raise QsplanError(f"--verify: expected a nonnegative number of friction vectors; got {args.verify}")
    outdir = Path(args.out)
    planned = [outdir / f for f in _FILES] + ([] if args.no_plots else [outdir / f"{n}.png" for n in _PLOTS])
    clash = [str(p) for p in planned if p.exists()]
    if clash and not args.force:
        raise QsplanError(f"--out: {clash[0]!r} exists ({len(clash)} of the output files do); "
                          "pass --force to overwrite or choose another --out")  # fmt: skip
    err = sys.stderr

    def progress(line):
        if not args.quiet:
            err.write(f"[qsplan] {line}\n")
            err.flush()

    limit = DEFAULT_OPTIONS.time_limit if args.time_limit is None else args.time_limit
    if not (limit > 0 and limit < float("inf")):
        raise QsplanError(f"--time-limit: expected a positive number of seconds; got {args.time_limit}")
    options = replace(DEFAULT_OPTIONS, seed=args.seed, planner=args.planner, time_limit=limit)
    progress(f"task {task.name!r}: {len(task.waypoints)} in-contact segments, mu in {list(task.mu_range)}, "
             f"torque resolution {task.torque_resolution:g} N m")  # fmt: skip
    try:
        plan = plan_task(task, options, progress)
    except PlanFailure as exc:
        outdir.mkdir(parents=True, exist_ok=True)
        with open(outdir / "failure.json", "w") as f:
            json.dump(exc.report.as_dict(), f, indent=1)
        raise QsplanError(f"{exc} (report: {outdir / 'failure.json'})") from None
    from qsplan.planner.export.plan_files import export_plan

    files = [str(p) for p in export_plan(plan, outdir, force=True)]
    if not args.no_plots:
        progress("drawing the plots")
        from qsplan.planner.plotting.plan import plan_figures
        from qsplan.planner.plotting.style import save_figure

        for name, fig in plan_figures(plan).items():
            path = outdir / f"{name}.png"
            save_figure(fig, path)
            files.append(str(path))
    replays = _verify(plan, outdir / "plan.csv", args, progress)
    if replays:
        with open(outdir / "replay.json", "w") as f:
            json.dump([_replay_dict(r) for r in replays], f, indent=1)
        files.append(str(outdir / "replay.json"))
    name, t, w = plan.narrowest()
    out.write(f"{task.name}: planned {len(plan.segments)} in-contact segments and {len(plan.phases) - len(plan.segments)} "
              f"regrasps, {plan.duration:.4g} s of motion\n")  # fmt: skip
    out.write(f"planning: {plan.seconds:.3g} s, {plan.validity_checks} validity checks "
              f"({plan.checks_per_second:.4g} per second inside OMPL)\n")  # fmt: skip
    out.write(f"narrowest guaranteed band: {w:.6g} N m at t = {t:.4g} s (resolution {task.torque_resolution:g} N m)\n")
    for r in replays:
        out.write(f"re-simulated at {r.summary()}\n")
    for f in files:
        out.write(f"wrote {f}\n")
    if not all(r.followed for r in replays):
        sys.stderr.write("qsplan: error: the exported plan left its planned modes in re-simulation (see replay.json)\n")
        return 1
    return 0


def _verify(plan, csv_path, args, progress) -> list:
    """Re-simulate the exported file (:func:`planner.replay.replay_plan`) at ``args.verify`` friction vectors."""
    from qsplan.planner.export.plan_files import read_plan_csv
    from qsplan.planner.planning.replay import friction_samples, replay_plan

    mus = friction_samples(plan.task.mu_range, args.verify, args.seed, shared=plan.task.shared_mu)
    columns = read_plan_csv(csv_path)
    out = []
    for mu in mus:
        progress(f"re-simulating the exported plan at mu = {[round(float(m), 4) for m in mu]}")
        out.append(replay_plan(columns, plan.task.hand, mu))
    return out


def _replay_dict(r) -> dict:
    import math

    def num(v):  # JSON has no NaN: null
        return float(v) if math.isfinite(v) else None

    return {"mu": [float(m) for m in r.mu], "followed": r.followed, "x_error_m": num(r.x_error),
            "segments": [{"phase": s.phase, "planned_mode": s.planned_mode, "modes": list(s.labels), "stop": s.stop,
                          "x_error_m": num(s.x_error), "x_end_m": num(s.x_end)} for s in r.segments]}  # fmt: skip


def run(args, out) -> int:
    from qsplan.planner.planning.task import load_task

    return run_task(load_task(args.task), args, out)
