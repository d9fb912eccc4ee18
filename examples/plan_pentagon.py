"""Plan a pentagonal workpiece built in Python (no task file), and read a planning failure.

The task is the Python equivalent of ``planner/data/pentagon_task.toml``: a house-shaped
pentagon slid right, regrasped, and slid back left past its start, with friction
uncertain in [0, 0.2] at every contact and a controller that resolves 0.01 N m.
Then the same task with friction anywhere in [0, 0.6]: no torque band is guaranteed
for that much uncertainty, and the failure report says where, why and from which
friction value on.  Public API only::

    python examples/plan_pentagon.py [OUT_DIR]
"""

import sys
from dataclasses import replace

from qsplan.hands import make_two_finger_hand
from qsplan.planner import PlanFailure, make_task, plan_task, run_plan

SEED = 1


def pentagon_task(mu_range=(0.0, 0.2)):
    hand = make_two_finger_hand(
        workpiece=[[0.0, 0.0], [0.070, 0.0], [0.070, 0.060], [0.035, 0.090], [0.0, 0.060]],  # m, counter-clockwise
        workpiece_mass=0.15, finger_base=0.09, finger_length=0.11, finger_width=0.012,
    )  # fmt: skip
    return make_task(hand, start_x=0.0, waypoints=[0.02, -0.02], mu_range=mu_range, torque_resolution=0.01,
                     joint_speed=0.5, workpiece_speed=0.01, name="pentagon: right then left")  # fmt: skip


def main(out="out/examples/pentagon"):
    task = pentagon_task()
    plan = run_plan(task, out, seed=SEED, verify=0, force=True, progress=lambda line: print("  " + line)).plan
    for seg in plan.segments:
        print(f"{seg.name}: {seg.effort_joint} finger torque-controlled, band {seg.width.min():.4g} N m at its "
              f"narrowest, command margin >= {seg.margin.min():.4g} N m")  # fmt: skip
    print(f"wrote {out}/")

    wide = replace(task, mu_range=(0.0, 0.6))
    try:
        plan_task(wide)
    except PlanFailure as failure:  # no plan exists (a NoAnswerError, not a ValueError)
        report = failure.report
        print("with mu in [0, 0.6]:", report.message)
        print("  as data:", {k: report.as_dict()[k] for k in ("segment", "mu_closes") if k in report.as_dict()})
    else:
        print("with mu in [0, 0.6]: planned as well")


if __name__ == "__main__":
    main(*sys.argv[1:2])
