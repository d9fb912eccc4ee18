"""``qsplan plan``: plan a two-finger task through OMPL with guaranteed torque bands, plots and export.

::

    qsplan plan TASK.toml|BUNDLED_TASK [--out DIR] [--seed S] [--planner NAME] [--sequence-planner NAME] [--time-limit SECONDS]
                          [--force] [--quiet] [--plots card|all|none | --no-plots] [--verify N]

Reads the task (:mod:`qsplan.planner.task.task`; a bundled task by its name, e.g. ``two_link_task``)
and runs the pipeline
(:func:`qsplan.planner.pipeline.run.run_plan`): plans it (a task with a ``[goal]``
automatically: band tables of every grasp and the widest route through them, searched in OMPL,
:mod:`qsplan.planner.search`; a task with ``waypoints`` as scripted; in-contact segments
judged by their dense sweeps, regrasps planned in joint space by OMPL), and writes
into DIR (default ``out/plan``) ``plan.csv`` and ``plan.json`` (the torque
trajectory), ``replay.json`` (the exported file re-simulated at ``--verify``
friction vectors of the interval; exit 1 if any run leaves the planned modes) and
``plan_card.png`` (drawn in a second process while the plan is certified; with ``--plots all`` also
``plan_bands.png``, ``mode_timeline.png``, ``hand_snapshots.png`` and the animation; none with
``--no-plots``; a plot that could not be drawn is said on stderr, the certified plan published without
it).  Existing files are not overwritten without ``--force``
(checked first; the task file never, even with it).  The files appear in DIR only once the plan
is certified (written into a staging directory inside DIR, then renamed into place); a second run
into a DIR that a run is writing fails at once (exit 2).  Progress lines go to stderr unless
``--quiet``; a summary to stdout.

When no plan exists the report (where the band closes, which mode closes it, at
which friction) is written to DIR/failure.json and the command fails with one
line on stderr naming it (exit 2).
"""

from __future__ import annotations

import sys

from qsplan.planner.cli.options import EXIT_FAILED, add_plan_options

__all__ = ["FLAGS", "add_parser", "plots_asked", "run", "run_task"]

#: Library fields of :func:`qsplan.planner.pipeline.run.run_plan` and this command's options.
FLAGS = {"verify": "--verify", "time_limit": "--time-limit", "plots": "--plots"}


def add_parser(subparsers):
    p = subparsers.add_parser("plan", help="plan a two-finger task (TOML) through OMPL with guaranteed torque bands")
    p.add_argument("task", help="task file (.toml; see qsplan.planner.task.task), or a bundled task's name "
                                "(demo_task, two_link_task, ...: qsplan.planner.task_paths())")
    add_plan_options(p, "out/plan")
    return p


def plots_asked(args) -> str:
    """The plots ``args`` ask for: ``--plots``, or ``"none"`` with ``--no-plots``."""
    return "none" if args.no_plots else args.plots


def run_task(task, args, out, inputs=()) -> int:
    """Run the pipeline on ``task`` as ``args`` ask and print the summary (shared by ``qsplan demo``); ``inputs``: the
    files read (the task file), never replaced."""
    from qsplan.planner.pipeline.run import run_plan
    from qsplan.planner.plotting.style import torque_text

    err = sys.stderr

    def progress(line):
        if not args.quiet:
            err.write(f"[qsplan] {line}\n")
            err.flush()

    result = run_plan(task, args.out, seed=args.seed, planner=args.planner, time_limit=args.time_limit,
                      verify=args.verify, force=args.force, plots=plots_asked(args),
                      progress=progress, sequence_planner=args.sequence_planner, inputs=inputs)  # fmt: skip
    plan = result.plan
    name, t, w = plan.narrowest()
    replaced = [ph.finger for ph in plan.phases if ph.kind == "replace"]
    mid_turn = f" ({len(replaced)} of them a finger replaced mid-turn: {', '.join(replaced)})" if replaced else ""
    out.write(f"{task.name}: planned {len(plan.segments)} in-contact segments and {len(plan.phases) - len(plan.segments)} "
              f"regrasps{mid_turn}, {plan.duration:.4g} s of motion\n")  # fmt: skip
    out.write(f"planning: {plan.seconds:.3g} s, {plan.validity_checks} states judged "
              f"({plan.checks_per_second:.4g} per second: band tables, dense sweeps and the regrasps' OMPL checks)\n")  # fmt: skip
    search = plan.search
    if search is not None:
        out.write(f"sequence found by the {search.planner!r} search on band tables of {search.grasps} grasps x "
                  f"{search.grid_points} positions ({search.table_states} configurations, {search.band_states} "
                  f"guaranteed bands in {search.table_seconds:.3g} s; search {search.search_seconds:.3g} s)\n")  # fmt: skip
    seg = next((s for s in plan.segments if s.name == name), None)
    unit = "N m" if seg is None else task.hand.joint_unit(seg.effort_joint, "tau")
    width = torque_text(w, unit, side="upper").replace("unbounded above", "unbounded")
    out.write(f"narrowest guaranteed band: {width} at t = {t:.4g} s (resolution {task.torque_resolution:g} {unit})\n")
    out.write(f"{result.certificate.summary()}\n")
    for r in result.replays:
        out.write(f"re-simulated at {r.summary()}\n")
    for f in result.files:
        out.write(f"wrote {f}\n")
    for name, why in result.undrawn:  # said even with --quiet: a file asked for is missing
        sys.stderr.write(f"qsplan: warning: {name} not drawn ({why}); the certified plan is published without it\n")
    if not result.followed:
        sys.stderr.write("qsplan: error: the exported plan left its planned modes in re-simulation (see replay.json)\n")
        return EXIT_FAILED
    return 0


def run(args, out) -> int:
    from pathlib import Path

    from qsplan.planner.pipeline.worker import start_early, stop_early

    start_early(plots_asked(args))  # the drawing process loads matplotlib while this one loads the planner
    try:
        from qsplan.planner.task.task import load_task, task_paths

        bundled = task_paths()
        path = bundled[args.task] if args.task in bundled and not Path(args.task).exists() else args.task
        return run_task(load_task(path), args, out, inputs=(path,))
    finally:
        stop_early()
