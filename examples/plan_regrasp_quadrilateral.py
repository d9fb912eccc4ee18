"""Plan the bundled regrasp like the paper's Fig. 9 from its task file, export it, and check it by re-simulation.

A quadrilateral workpiece slides on the palm in mode 4S three times (left, right,
left), the fingers regrasping between segments.  The plan is written to
``out/examples/quadrilateral/`` (torque trajectory CSV/JSON and the operator plots),
then the exported file is re-simulated with the finite-motion simulator at friction
vectors drawn from the task's interval.  Public API only::

    python examples/plan_regrasp_quadrilateral.py [OUT_DIR]
"""

import sys
from pathlib import Path

from qsplan.planner.planning.plan import plan_task
from qsplan.planner.export.plan_files import export_plan, read_plan_csv
from qsplan.planner.plotting.plan import plan_figures
from qsplan.planner.plotting.style import save_figure
from qsplan.planner.planning.replay import friction_samples, replay_plan
from qsplan.planner.planning.task import demo_task_path, load_task


def main(out="out/examples/quadrilateral"):
    task = load_task(demo_task_path())
    plan = plan_task(task, progress=lambda line: print("  " + line))
    segment, t, width = plan.narrowest()
    print(f"{task.name}: {plan.duration:.3g} s of motion, narrowest band {width:.4g} N m at t = {t:.3g} s "
          f"({segment}); planned in {plan.seconds:.3g} s")  # fmt: skip
    out = Path(out)
    export_plan(plan, out, force=True)
    for name, fig in plan_figures(plan).items():
        save_figure(fig, out / f"{name}.png")
    columns = read_plan_csv(out / "plan.csv")
    for mu in friction_samples(task.mu_range, 3, seed=1):
        print("re-simulated at", replay_plan(columns, task.hand, mu).summary())
    print(f"wrote {out}/")


if __name__ == "__main__":
    main(*sys.argv[1:2])
