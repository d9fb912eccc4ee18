"""``qsplan demo``: the main job, end to end: plan the first 4S segment of the paper's Fig. 9.

::

    qsplan demo [--out DIR] [--seed S] [--planner NAME] [--force] [--quiet] [--plots card|all|none | --no-plots]

Plans :func:`qsplan.planner.task.task.demo_task_path` exactly as ``qsplan plan`` does (:data:`DEMO_PLAN`
says what it plans; a test holds the plan to it), and writes the torque trajectory, its certificate, the
re-simulation and the plan card (``--plots all``: every plot and the animation) into DIR (default ``out/demo``).
"""

from __future__ import annotations

from qsplan.planner.cli.options import add_plan_options
from qsplan.planner.cli.plan import FLAGS, plots_asked, run_task

__all__ = ["DEMO_PLAN", "FLAGS", "add_parser", "run"]

#: What the demo plans, in words (its ``--help``, the README): ``tests/planner/test_cmd_plan.py`` checks the plan
#: against it (one in-contact segment, no regrasp).
DEMO_PLAN = ("the first 4S segment of Fig. 9: one slide of the paper hand's workpiece 4 cm to the left, no regrasp, "
             "with the widest guaranteed band for every friction in [0, 0.2]")


def add_parser(subparsers):
    p = subparsers.add_parser("demo", help=f"plan the bundled task end to end: {DEMO_PLAN}")
    add_plan_options(p, "out/demo")
    return p


def run(args, out) -> int:
    from qsplan.planner.pipeline.worker import start_early, stop_early

    start_early(plots_asked(args))  # the drawing process loads matplotlib while this one loads the planner
    try:
        from qsplan.planner.task.task import demo_task_path, load_task

        return run_task(load_task(demo_task_path()), args, out, inputs=(demo_task_path(),))
    finally:
        stop_early()
