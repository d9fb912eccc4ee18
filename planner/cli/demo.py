"""``qsplan demo``: the main job, end to end: plan the bundled regrasp like the paper's Fig. 9.

::

    qsplan demo [--out DIR] [--seed S] [--planner NAME] [--force] [--quiet] [--no-plots]

Plans :func:`qsplan.planner.task.task.demo_task_path` (three 4S segments of the default hand:
slide left until the left finger nearly meets the longest edge, right, left to
the middle, regrasping between them) exactly as ``qsplan plan`` does, and writes
the torque trajectory and the plots into DIR (default ``out/demo``).
"""

from __future__ import annotations

from qsplan.planner.cli.options import add_plan_options
from qsplan.planner.cli.plan import FLAGS, run_task

__all__ = ["FLAGS", "add_parser", "run"]


def add_parser(subparsers):
    p = subparsers.add_parser("demo", help="plan the bundled two-finger regrasp (like Fig. 9) end to end")
    add_plan_options(p, "out/demo")
    return p


def run(args, out) -> int:
    from qsplan.planner.task.task import demo_task_path, load_task

    return run_task(load_task(demo_task_path()), args, out, inputs=(demo_task_path(),))
