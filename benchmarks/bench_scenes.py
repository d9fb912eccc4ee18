"""The two-finger hand's scene at a configuration: the analytic path (the grasp's known contacts) against the
generic one (polygon contact finding), and the planner's in-contact state check with each.

Run: ``python3 benchmarks/bench_scenes.py [--states N] [--repeat R]``.  Times are the best of ``R`` passes
over ``N`` configurations (the machine is shared: the best pass is the least disturbed one), per state.
``max rel diff`` is the largest difference between the two paths' scenes over every array (Wn, Wt, Jn, Jt,
mu, g_obj, g_man, joint inputs), relative to the array's largest entry; ``analytic`` counts the
configurations the analytic path took (the others fall back to the generic path).
"""

import argparse
import contextlib
import functools
import time

import numpy as np

import qsplan.hands.paper_hand.scene as scenes
from qsplan.hands.paper_hand.segments import first_segment
from qsplan.hands.paper_hand.two_finger import default_hand, finger_angles
from qsplan.hands.paper_hand.analytic import grasp_contacts
from qsplan.planner.states.contact import check_contact_state
from qsplan.planner.task.task import load_task, task_paths

FIELDS = ("Wn", "Wt", "Jn", "Jt", "mu", "g_obj", "g_man", "joint_velocity", "joint_effort")


def best_per_call(fn, args, repeat):
    """Best time (ms) per call of ``fn(*a)`` over ``repeat`` passes through ``args``."""
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        for a in args:
            fn(*a)
        best = min(best, time.perf_counter() - t0)
    return 1e3 * best / len(args)


def max_difference(configs, hand):
    worst = 0.0
    for pose, q in configs:
        a = scenes.hand_scene(hand, pose, q, velocity=0.1)
        g = scenes.hand_scene(hand, pose, q, velocity=0.1, method="generic")
        for f in FIELDS:
            A, G = getattr(a, f), getattr(g, f)
            ok = np.isfinite(G)
            if ok.any():
                worst = max(worst, float(np.max(np.abs(A[ok] - G[ok])) / max(np.abs(G[ok]).max(), 1e-300)))
    return worst


@contextlib.contextmanager
def generic_scenes():
    """Every caller of ``hand_scene`` (the planner's checks among them) on the generic path meanwhile."""
    original = scenes.hand_scene
    scenes.hand_scene = functools.partial(original, method="generic")
    try:
        yield
    finally:
        scenes.hand_scene = original


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--states", type=int, default=100, help="configurations per case")
    ap.add_argument("--repeat", type=int, default=7, help="passes (best taken)")
    args = ap.parse_args(argv)
    cases = {"demo hand, segment 1": (default_hand(), None)}
    for stem, path in task_paths().items():
        cases[f"{stem}, segment 1"] = (load_task(path).hand, load_task(path))
    print(f"{'scene build':<28} {'generic ms':>10} {'analytic ms':>11} {'speed-up':>9} {'max rel diff':>13} "
          f"{'analytic':>9}")  # fmt: skip
    for name, (hand, task) in cases.items():
        if task is None:
            poses = first_segment(hand).pose(np.linspace(0.0, 1.0, args.states))
        else:
            poses = np.array([task.pose(x) for x in np.linspace(task.start_x, task.waypoints[0], args.states)])
        configs = [(p, finger_angles(hand, p)[0]) for p in poses]
        calls = [(hand, p, q, "right", 0.1) for p, q in configs]
        generic = best_per_call(functools.partial(scenes.hand_scene, method="generic"), calls, args.repeat)
        analytic = best_per_call(scenes.hand_scene, calls, args.repeat)
        taken = sum(grasp_contacts(hand, p, q) is not None for p, q in configs)
        print(f"{name:<28} {generic:10.3f} {analytic:11.3f} {generic / analytic:9.1f} "
              f"{max_difference(configs, hand):13.2e} {f'{taken}/{len(configs)}':>9}")  # fmt: skip
    print()
    print(f"{'in-contact state check':<28} {'generic ms':>10} {'analytic ms':>11} {'speed-up':>9}")
    for stem, path in task_paths().items():
        task = load_task(path)
        calls = [(task, x, "right", float(np.sign(task.waypoints[0] - task.start_x)))
                 for x in np.linspace(task.start_x, task.waypoints[0], max(args.states // 4, 5))]  # fmt: skip
        generic = analytic = float("inf")
        for _ in range(args.repeat):  # interleaved, so that both see the same load
            with generic_scenes():
                generic = min(generic, best_per_call(check_contact_state, calls, 1))
            analytic = min(analytic, best_per_call(check_contact_state, calls, 1))
        print(f"{stem + ', segment 1':<28} {generic:10.3f} {analytic:11.3f} {generic / analytic:9.2f}")


if __name__ == "__main__":
    main()
