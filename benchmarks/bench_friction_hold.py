"""Holds proved with friction along the demo's turn, one finger lifted (issue 34, item 1): where a hold is proved
(:func:`qsplan.mechanics.bands.friction_hold.prove_friction_hold`) with every joint held and the right (or left)
finger's contacts removed, for friction boxes with a positive lower bound, with timings.

The turn is the plan of the demo's start with ``[goal] theta`` (default -0.84 rad: slide, hold, pivot, hold, pivot),
sampled every ``--every`` rows.  Per sampled row: the workpiece angle, the contacts left, whether the hold is proved
for each box of :data:`BOXES`, and the least lower bound ``m`` for which the box ``[m, m + WIDTH]`` is proved
(bisection to ``MU_RESOLUTION``; "-" where even ``[MU_CAP, MU_CAP + WIDTH]`` is not), against which the frictionless
proof (:func:`qsplan.mechanics.bands.hold.prove_hold`) proves nothing once a finger is lifted (zero friction in the
set, or the rank).  Times: the mean of one proof, in milliseconds.

Usage, from the repository root::

    python3 benchmarks/bench_friction_hold.py [--theta -0.84] [--every 6] [--lift right]
"""

import argparse
import time
from pathlib import Path

import numpy as np

from qsplan.hands.contacts.found import contact_names, ordered_contacts, row_contact_scene
from qsplan.mechanics.bands.friction_hold import prove_friction_hold
from qsplan.planner.plan.scripted import plan_task
from qsplan.planner.task.task import demo_task_path, load_task

#: The friction boxes of the table (per contact, every contact alike).
BOXES = ((0.1, 0.2), (0.2, 0.4), (0.3, 0.6), (0.5, 1.0))
#: The width of the bisected box [m, m + WIDTH].
WIDTH = 0.1
#: The bisection stops at this resolution of m.
MU_RESOLUTION = 0.005
#: The largest m tried.
MU_CAP = 2.0


def _task(theta: float, tmp: Path):
    path = tmp / "turn.toml"  # the demo's task, its goal x replaced by the angle
    path.write_text(demo_task_path().read_text().replace("\nx = -0.04\n", f"\ntheta = {theta}\n", 1))
    return load_task(path)


def _least(scene) -> float:
    if not prove_friction_hold(scene, (MU_CAP, MU_CAP + WIDTH)).proved:
        return np.nan
    lo, hi = 0.0, MU_CAP
    if prove_friction_hold(scene, (0.0, WIDTH)).proved:
        return 0.0
    while hi - lo > MU_RESOLUTION:
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if prove_friction_hold(scene, (mid, mid + WIDTH)).proved else (mid, hi)
    return hi


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--theta", type=float, default=-0.84, help="the turn's goal angle (rad)")
    p.add_argument("--every", type=int, default=6, help="sample every this many rows of each phase")
    p.add_argument("--lift", choices=("right", "left"), default="right", help="the finger lifted")
    args = p.parse_args(argv)
    import tempfile

    from qsplan.mechanics.bands.hold import prove_hold

    with tempfile.TemporaryDirectory() as tmp:
        task = _task(args.theta, Path(tmp))
    t0 = time.perf_counter()
    plan = plan_task(task)
    print(f"turn to {np.degrees(args.theta):.2f} deg planned in {time.perf_counter() - t0:.2f} s; "
          f"the {args.lift} finger lifted, every joint held")  # fmt: skip
    hand = task.hand
    n_j = len(hand.joint_names)
    held = np.zeros(n_j, dtype=bool)
    header = f"{'theta deg':>10}  {'contacts kept':<34}" + "".join(f"{f'[{a:g},{b:g}]':>11}" for a, b in BOXES)
    print(header + f"{'least m':>9}{'frictionless':>14}{'ms/proof':>10}")
    times = []
    seen = set()
    for ph in plan.phases:
        poses = ph.poses(hand.rest_height)
        for k in list(range(0, len(poses), args.every)) + [len(poses) - 1]:
            pose, q = poses[k], ph.q[k]
            key = (round(float(pose[0]), 6), round(float(pose[2]), 6))
            if key in seen:
                continue
            seen.add(key)
            found = ordered_contacts(hand, pose, q)
            names = contact_names(hand, pose, found)
            drop = np.array([n.split(":")[0] == args.lift for n in names])
            if not drop.any() or drop.all():
                continue
            scene = row_contact_scene(hand, pose, q, held, np.zeros(n_j), found=found, drop=drop)
            cells = []
            for box in BOXES:
                t = time.perf_counter()
                cells.append("proved" if prove_friction_hold(scene, box).proved else "-")
                times.append(time.perf_counter() - t)
            least = _least(scene)
            frictionless = prove_hold(scene).proved
            kept = ", ".join(n for n, d in zip(names, drop) if not d)
            print(f"{np.degrees(pose[2]):10.2f}  {kept:<34}" + "".join(f"{c:>11}" for c in cells)
                  + f"{'-' if np.isnan(least) else f'{least:.3f}':>9}{str(frictionless):>14}"
                  + f"{1e3 * np.mean(times[-len(BOXES):]):10.1f}")  # fmt: skip
    print(f"{len(times)} proofs, {1e3 * np.mean(times):.1f} ms each on average")


if __name__ == "__main__":
    main()
