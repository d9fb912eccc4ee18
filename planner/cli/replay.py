"""``qsplan replay``: execute an exported plan in a rigid-body engine (issue 24, item 5).

::

    qsplan replay PLAN_DIR [--engine mujoco] [--runs N] [--seed S] [--task TASK] [--json]

Executes ``PLAN_DIR``'s commands at 1 kHz in MuJoCo (:func:`qsplan.planner.replay.mujoco_replay.replay_mujoco`:
velocity joints on stiff servos, the effort joint given the exported torque, no stop added) at every vertex of
the task's friction set and ``N`` seeded random points (default 2), and prints one line per run: the modes
followed against the plan's, the workpiece's largest position error (mm; through the regrasps apart) and the
contacts lost.  MuJoCo is an optional extra: without it the command fails in one line naming
``pip install 'qsplan[sim]'``.  ``--task`` takes a task file or a bundled task's name; default the task
recorded in ``plan.json``.

Exit 0: every run kept the planned modes and the workpiece within :data:`POSE_TOLERANCE` of the plan.  Exit 1:
some run did not (listed).  Exit 2: bad input, or MuJoCo missing (one line on stderr).
"""

from __future__ import annotations

import json

from qsplan.planner.cli.options import EXIT_FAILED

__all__ = ["ENGINES", "FLAGS", "MAX_RUNS", "POSE_TOLERANCE", "add_parser", "run"]

#: The engines ``--engine`` offers.
ENGINES = ("mujoco",)

#: Library fields of :func:`qsplan.planner.replay.mujoco_replay.replay_mujoco` and this command's options.
FLAGS = {"n_random": "--runs", "engine": "--engine", "plan": "PLAN_DIR", "task": "--task", "seed": "--seed"}

#: Most random friction vectors per replay: each run simulates the whole plan (1-5 s per simulated second of plan
#: on one core), so 1000 runs of the longest bundled plan (15 s) take about a day.
MAX_RUNS = 1000

#: Largest workpiece position error (m) a run may show and pass: the issue's 0.1 mm through every regrasp.
POSE_TOLERANCE = 1e-4


def add_parser(subparsers):
    p = subparsers.add_parser("replay", help="execute an exported plan in MuJoCo at the friction set's vertices")
    p.add_argument("plan", metavar="PLAN_DIR", help="plan directory (plan.csv and plan.json), or one of the files")
    p.add_argument("--engine", choices=ENGINES, default="mujoco", help="the rigid-body engine (default mujoco)")
    p.add_argument("--runs", type=int, default=2, metavar="N",
                   help="seeded random friction vectors besides the friction set's vertices (default 2)")  # fmt: skip
    p.add_argument("--seed", type=int, default=0, metavar="S", help="seed of the random friction vectors (default 0)")
    p.add_argument("--task", metavar="TASK", help="task file (.toml) or a bundled task's name; default: the task "
                                                  "recorded in plan.json")  # fmt: skip
    p.add_argument("--json", action="store_true", help="print the runs as JSON (every row's modes and errors)")
    return p


def run(args, out) -> int:
    from qsplan.mechanics.errors import QsplanError
    from qsplan.planner.replay.mujoco_replay import replay_mujoco

    if not 0 <= args.runs <= MAX_RUNS:
        raise QsplanError(f"n_random: expected 0..{MAX_RUNS} random friction vectors; got {args.runs}")
    task = None
    if args.task is not None:
        from qsplan.planner.task.task import load_task, task_path

        task = load_task(task_path(args.task))
    result = replay_mujoco(args.plan, task=task, n_random=args.runs, seed=args.seed)
    failed = [r for r in result.runs if not (r.modes_kept and r.max_error() <= POSE_TOLERANCE)]
    if args.json:
        json.dump({**result.as_dict(), "pose_tolerance_m": POSE_TOLERANCE, "ok": not failed}, out, indent=1,
                  allow_nan=False)  # fmt: skip
        out.write("\n")
        return EXIT_FAILED if failed else 0
    out.write(f"{args.plan}: task {result.task!r} in {result.engine}, {len(result.runs)} friction vectors, commands at "
              f"{result.settings['control_rate_Hz']:g} Hz, no stop added\n")  # fmt: skip
    for r in result.runs:
        out.write(f"{r.summary()}\n")
    if failed:
        out.write(f"{len(failed)} of {len(result.runs)} runs left the plan (modes, or the workpiece beyond "
                  f"{POSE_TOLERANCE * 1e3:g} mm)\n")  # fmt: skip
        return EXIT_FAILED
    out.write(f"every run kept the planned modes, the workpiece within {result.max_error() * 1e3:.3g} mm of the plan\n")
    return 0
