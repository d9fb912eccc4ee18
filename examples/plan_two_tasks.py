"""Plan two two-finger tasks with different workpieces (the bundled quadrilateral regrasp and a pentagon).

Each task is planned through OMPL (seed 1) with guaranteed torque bands; the torque
trajectory and the operator plots go to ``out/examples/<task>/``.  Public API only.
"""

from pathlib import Path

from planner.plan import plan_task
from planner.plan_export import export_plan
from planner.plan_plots import plan_figures
from planner.plots import save_figure
from planner.task import load_task, task_paths


def main(out="out/examples"):
    for stem, path in task_paths().items():
        task = load_task(path)
        plan = plan_task(task, progress=lambda line: print("  " + line))
        name, t, w = plan.narrowest()
        print(f"{task.name}: {plan.duration:.3g} s of motion, narrowest band {w:.4g} N m, planned in {plan.seconds:.3g} s")
        d = Path(out) / stem
        export_plan(plan, d, force=True)
        for fig_name, fig in plan_figures(plan).items():
            save_figure(fig, d / f"{fig_name}.png")


if __name__ == "__main__":
    main()
