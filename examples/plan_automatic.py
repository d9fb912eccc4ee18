"""Automatic planning: a start grasp, a goal, and the planner finds the slides with the widest guaranteed bands.

The default quadrilateral on the paper's two-finger hand (Fig. 9): from x = 0 the workpiece must reach
x = -0.03 m with the left finger's inner edge still on vertex 3; no waypoints.  The planner builds the band
tables of every grasp, searches them inside OMPL, checks every sample of the chosen slides, exports the
torque trajectory, certifies it row by row, re-simulates it and draws the plan card.  Public API only::

    python examples/plan_automatic.py [OUT_DIR]
"""

import sys

from qsplan.planner import make_task, run_plan


def main(out="out/examples/automatic"):
    hand = {"workpiece": [[0.0, 0.0], [0.080, 0.0], [0.085, 0.080], [0.008, 0.100]], "finger_length": 0.16}
    task = make_task(hand, start_x=0.0, goal={"x": -0.03, "left": "vertex:3"}, mu_range=(0.0, 0.2),
                     torque_resolution=0.02, name="automatic: 3 cm left")  # fmt: skip
    run = run_plan(task, out, verify=3, force=True)  # plan, export, certify, re-simulate, plots
    for step in run.plan.sequence[:-1]:  # the steps the planner chose (qsplan.planner.plan.steps)
        print(step.as_dict())
    print(run.certificate.summary())
    print(f"narrowest band {run.plan.narrowest()[2]:.4g} N m; wrote {out}/ (plan.csv, plan_card.png, ...)")


if __name__ == "__main__":
    main(*sys.argv[1:2])
