"""Plan the bundled scripted sequence like the paper's Fig. 9 from its task file, export it, and re-simulate it.

A quadrilateral workpiece slides on the palm in mode 4S three times (left, right,
left), the fingers regrasping between segments.  The plan is written to
``out/examples/quadrilateral/`` (torque trajectory CSV/JSON and the operator plots),
then the exported file is re-simulated with the finite-motion simulator at friction
vectors drawn from the task's interval: all of it by one call, :func:`qsplan.planner.run_plan`
(what ``qsplan demo`` runs).  Public API only::

    python examples/plan_regrasp_quadrilateral.py [OUT_DIR]
"""

import sys

from qsplan.planner import load_task, run_plan, task_paths

SEED = 1


def main(out="out/examples/quadrilateral"):
    task = load_task(task_paths()["scripted_regrasp_task"])  # waypoints given: the sequence is scripted
    run = run_plan(task, out, seed=SEED, verify=3, force=True, progress=lambda line: print("  " + line))
    plan = run.plan
    segment, t, width = plan.narrowest()
    print(f"{task.name}: {plan.duration:.3g} s of motion, narrowest band {width:.4g} N m at t = {t:.3g} s "
          f"({segment}); planned in {plan.seconds:.3g} s")  # fmt: skip
    for replay in run.replays:
        print("re-simulated at", replay.summary())
    print(f"wrote {out}/")


if __name__ == "__main__":
    main(*sys.argv[1:2])
