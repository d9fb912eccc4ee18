"""``qsplan replay``: execute an exported plan in a rigid-body engine (issue 24, item 5).

::

    qsplan replay PLAN_DIR [--engine mujoco] [--runs N] [--seed S] [--task TASK] [--json]

Executes ``PLAN_DIR``'s commands at 1 kHz in MuJoCo (:func:`qsplan.planner.replay.mujoco_replay.replay_mujoco`:
velocity joints on stiff servos, the effort joint given the exported torque, no stop added) at every vertex of
the task's friction set and ``N`` seeded random points (default 2), and prints one line per run: the modes
followed against the plan's, the workpiece's largest position error (mm) and what remains of it off the pose
the plan gives for the joint positions MuJoCo measured (the servos' deflection taken out; over a regrasp: from
where the workpiece was released), and the contacts lost.  MuJoCo is an optional extra: without it the command
fails in one line naming ``pip install '.[sim]'``.  ``--task`` takes a task file or a bundled task's name;
default the task recorded in ``plan.json``.

What the certificate covers and what this adds (:data:`COVERAGE`): ``qsplan verify`` proves, from the task
alone, the plan's rows in the quasistatic rigid-body model: each row's mode the only one for every friction in the
set, every torque command inside its guaranteed band, the holds, the geometry and the timing.  A MuJoCo replay
executes the exported commands in a dynamic engine with compliant contacts, servos of finite stiffness and the
workpiece's inertia, between the rows too, at sampled friction vectors: evidence, not proof.  It compares a
contact's letter only where MuJoCo's soft friction can tell sliding from sticking (the planned slip faster than
twice the slowest slip it resolves there).

Exit 0: every run kept the planned modes where resolvable and the workpiece within
:data:`qsplan.planner.replay.mujoco_replay.POSE_TOLERANCE` of the plan's pose at the measured joints (over a
regrasp, of where it was released, :data:`~qsplan.planner.replay.mujoco_replay.RELEASE_DRIFT` more).  Exit 1:
some run did not (listed).  Exit 2: bad input, or MuJoCo missing (one line on stderr).
"""

from __future__ import annotations

import json

from qsplan.planner.certify.scope import SCOPE
from qsplan.planner.cli.options import EXIT_FAILED

__all__ = ["COVERAGE", "ENGINES", "MUJOCO_ADDS", "FLAGS", "MAX_RUNS", "add_parser", "run"]

#: The engines ``--engine`` offers.
ENGINES = ("mujoco",)

#: Library fields of :func:`qsplan.planner.replay.mujoco_replay.replay_mujoco` and this command's options.
FLAGS = {"n_random": "--runs", "engine": "--engine", "plan": "PLAN_DIR", "task": "--task", "seed": "--seed"}

#: Most random friction vectors per replay: each run simulates the whole plan (1-5 s per simulated second of plan
#: on one core), so 1000 runs of the longest bundled plan (15 s) take about a day.
MAX_RUNS = 1000

#: What a MuJoCo replay adds to the certificate (:data:`qsplan.planner.certify.scope.SCOPE`).
MUJOCO_ADDS = ("A MuJoCo replay adds evidence, not proof: the commands executed at 1 kHz with compliant contacts, "
               "finite-stiffness servos and inertia, between rows too, at the friction set's vertices and sampled "
               "points; it compares a contact's mode where MuJoCo's soft friction resolves the slip, and the pose once "
               "the servos' measured deflection is taken out.")

#: What the certificate covers and what a MuJoCo replay adds: this command's help says it (the plan card and
#: ``qsplan verify --help`` say the first part).
COVERAGE = SCOPE + " " + MUJOCO_ADDS


def add_parser(subparsers):
    p = subparsers.add_parser("replay", help="execute an exported plan in MuJoCo at the friction set's vertices",
                              description="Execute an exported plan's commands in MuJoCo at 1 kHz at every vertex "
                                          "of the task's friction set and N seeded random points. "
                                          + COVERAGE)  # fmt: skip
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
    failed = [r for r in result.runs if not r.ok]
    tolerance = result.settings["pose_tolerance_m"]
    if args.json:
        json.dump({**result.as_dict(), "pose_tolerance_m": tolerance, "ok": not failed}, out, indent=1,
                  allow_nan=False)  # fmt: skip
        out.write("\n")
        return EXIT_FAILED if failed else 0
    out.write(f"{args.plan}: task {result.task!r} in {result.engine}, {len(result.runs)} friction vectors, commands at "
              f"{result.settings['control_rate_Hz']:g} Hz, no stop added\n")  # fmt: skip
    for r in result.runs:
        out.write(f"{r.summary()}\n")
    if failed:
        release = (tolerance + result.settings["release_drift_m"]) * 1e3
        out.write(f"{len(failed)} of {len(result.runs)} runs left the plan (modes where resolvable, or the workpiece "
                  f"beyond {tolerance * 1e3:g} mm of the plan's pose at the measured joints, or a released one beyond "
                  f"{release:g} mm of where it was released)\n")  # fmt: skip
        return EXIT_FAILED
    unresolved = sum(r.unresolved for r in result.runs)
    out.write(f"every run kept the planned modes"
              + (f" ({unresolved} letters too slow for MuJoCo to resolve, not compared)" if unresolved else "")
              + f", the workpiece within {result.max_path_error() * 1e3:.3g} mm of the plan's pose at the measured "
              f"joints or of its release ({result.max_error() * 1e3:.3g} mm of the rows' poses, the servos' "
              f"deflection included)\n")
    return 0
