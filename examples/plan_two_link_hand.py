"""Planning with the bundled two-link hand (issue 15): a regrasp onto another feature, then a 4S slide.

The hand comes from its file (``qsplan hands two_link_hand`` prints it): each finger has a proximal and a
distal revolute joint.  The left finger starts with its distal link's inner edge on the workpiece's top-left
corner (vertex 3) and must end on the left side with its fingertip (edge 3); the workpiece must slide 3 cm
left.  The planner finds the grasps, the regrasp (OMPL in joint space) and the slide on the contact manifold
(OMPL over the workpiece's x and the proximal joints, each distal joint closing onto the workpiece), with the
torque-controlled joint's guaranteed band for every friction coefficient in [0, 0.2]; then it exports the
torque schedule, certifies it row by row, re-simulates it and draws the plan card.  Public API only::

    python examples/plan_two_link_hand.py [OUT_DIR]
"""

import sys

from qsplan.planner import make_task, run_plan


def main(out="out/examples/two_link_hand"):
    hand = {"file": "two_link_hand",  # a bundled hand's name, or a path to your own hand file
            "workpiece": [[0.0, 0.0], [0.080, 0.0], [0.085, 0.080], [0.008, 0.100]], "workpiece_mass": 0.2}
    task = make_task(hand, start_x=0.0, goal={"x": -0.03, "left": "edge:3"},
                     start={"left_proximal": 1.4, "right_proximal": 1.74},  # the free joints; omit to let the planner pick
                     mu_range=(0.0, 0.2), torque_resolution=0.02, name="two-link hand: regrasp, slide 3 cm left")
    run = run_plan(task, out, verify=3, force=True)  # plan, export, certify, re-simulate, plots
    for phase in run.plan.phases:
        kind = type(phase).__name__
        print(f"{kind}: {getattr(phase, 'mode', 'free')}, torque-controlled {getattr(phase, 'effort_joint', 'none')}, "
              f"until t = {phase.t[-1]:.3g} s")
    print(run.certificate.summary())
    print(f"narrowest band {run.plan.narrowest()[2]:.4g} N m; wrote {out}/ (plan.csv, plan_card.png, ...)")


if __name__ == "__main__":
    main(*sys.argv[1:2])
