"""Collision checks of hand configurations (issue 13): the shapely reference, the fast single-state path and
the batched path, in microseconds per state, with the figure before issue 13 beside them.

Two sets of states of the demo task's hand (seed 13): the in-contact grasps of a dense sweep of its
segments (the planner's common case: every pair clear or touching) and free finger configurations
drawn in the joint limits with the workpiece anywhere along the sweep (OMPL's regrasp states, some of
them colliding).  Timed, best of ``--repeat`` (the machine is shared: the best run is the least
disturbed one):

* ``shapely``: :func:`qsplan.hands.geometry.collision.shapely_collisions`, every pair measured with
  shapely (the path before issue 13, the reference);
* ``single``: :func:`qsplan.hands.geometry.collision.find_collisions`, one state per call, shapely only
  for the pairs the fast path does not clear;
* ``batch b``: :func:`qsplan.hands.geometry.collision.find_collisions_batch` on batches of b states.

Each path's verdicts are checked against the reference's; the last column counts the states the fast
path left (partly) to shapely.

Run: ``python3 benchmarks/bench_collision.py [--states N] [--repeat R]`` (default 2000 and 3).
"""

import argparse
import time

import numpy as np

from qsplan.hands.paper_hand.two_finger import finger_angles
from qsplan.planner import load_task
from qsplan.hands.geometry.collision import (COLLIDES, UNDECIDED, collision_decisions, find_collisions,
                                             find_collisions_batch, shapely_collisions)  # fmt: skip
from qsplan.planner.task.task import demo_task_path

#: Before issue 13: ``find_collisions`` measured every pair with shapely, ~1 ms per state (2-core machine,
#: under load; ~0.4-0.6 ms when it is quiet), which capped the planner near 1,000 states/s.
PREVIOUS_US = 1000.0


def states(task, n, rng):
    """``{"in contact": (poses, qs), "free": (poses, qs)}``, n states each (shapes (n, 3), (n, 2))."""
    stops = [task.start_x, *task.waypoints]
    poses = np.array([task.pose(x) for x in np.linspace(min(stops), max(stops), n)])
    grasps = np.array([finger_angles(task.hand, p)[0] for p in poses])
    lo, hi = task.joint_limits[:, 0], task.joint_limits[:, 1]
    free = rng.uniform(lo, hi, size=(n, 2))
    return {"in contact": (poses, grasps), "free": (poses[rng.permutation(n)], free)}


def batched(hand, poses, qs, size):
    """:func:`find_collisions_batch` over batches of ``size`` states, shape (n,)."""
    return np.concatenate([find_collisions_batch(hand, poses[i : i + size], qs[i : i + size])
                           for i in range(0, len(poses), size)])  # fmt: skip


def best_us(fn, n, repeat):
    """Smallest time per state (us) of ``fn()`` over ``repeat`` runs, and its last result."""
    times, out = [], None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return min(times) / n * 1e6, out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--states", type=int, default=2000, help="states per set")
    ap.add_argument("--repeat", type=int, default=3, help="runs of each path (best taken)")
    args = ap.parse_args(argv)
    task = load_task(demo_task_path())
    hand, n = task.hand, args.states
    print(f"{'states':<11} {'path':<11} {'us/state':>9} {'before':>8} {'speed-up':>9} {'colliding':>10} "
          f"{'to shapely':>11}")  # fmt: skip
    for name, (poses, qs) in states(task, n, np.random.default_rng(13)).items():
        decisions = collision_decisions(hand, poses, qs)
        deferred = int(np.sum(np.any(decisions == UNDECIDED, axis=1) & ~np.any(decisions == COLLIDES, axis=1)))
        ref_us, ref = best_us(lambda: [bool(shapely_collisions(hand, p, q, True)) for p, q in zip(poses, qs)], n, 1)
        runs = {"shapely": (ref_us, ref)}
        runs["single"] = best_us(lambda: [bool(find_collisions(hand, p, q, True)) for p, q in zip(poses, qs)], n,
                                 args.repeat)  # fmt: skip
        for b in (1, 100, 1000):
            runs[f"batch {b}"] = best_us(lambda: batched(hand, poses, qs, b), n, args.repeat if b > 1 else 1)
        for path, (us, verdicts) in runs.items():
            assert list(verdicts) == ref, f"{path} disagrees with the reference"
            print(f"{name:<11} {path:<11} {us:9.1f} {PREVIOUS_US:8.0f} {PREVIOUS_US / us:8.0f}x {sum(ref):10d} "
                  f"{deferred if path != 'shapely' else 0:11d}")  # fmt: skip


if __name__ == "__main__":
    main()
