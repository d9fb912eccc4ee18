"""In-contact state checks per second of every bundled hand through the hand protocol (issue 22).

Run: ``python3 benchmarks/bench_hands.py [--step 5e-4] [--repeat 3]``.  For each bundled hand (the paper hand
twice: its closed forms, and the generic path with them switched off) holding the workpiece of its bundled
task, every candidate grasp (:meth:`qsplan.hands.described.hand.DescribedHand.grasp_candidates`; the two-link hand
from a 3 x 3 grid of its proximal joints about the task's ``[start]``) is judged at every workpiece x of a grid
(``--step``) over ``|x| <= 0.06`` m (``qsplan demo``'s tables), as the planner's band tables judge it:

* *geometry*: ``grasp_states`` (the closing, contacts, joint rates), ``scene_arrays`` (the scenes' matrices,
  eqs. 1-5, contacts checked against the polygon search), the joint limits and ``collide`` (every body pair),
  batched over the states of a grasp;
* *bands*: with each finger's closing joint effort-controlled in turn and the workpiece sliding either way, the
  guaranteed 4S band of the effort-controlled joint over the friction box [0, 0.2]^4, every competitor
  precluded, force margin (0.05, 0.05) (:func:`qsplan.mechanics.bands.batched_robust.robust_band_arrays`).

``states/s`` counts configurations judged by the geometry per second; ``checks/s`` counts in-contact state
checks (a configuration with one effort joint and one direction: a scene and a guaranteed band) per second of
the whole (geometry + bands), as ``benchmarks/bench_plan.py`` counts the band tables'.  Best of ``--repeat``
passes (the machine is shared).  ``before`` is the figure of the issue: the chain hands' per-state polygon
searches (``benchmarks/bench_plan.py``, issue 15).  The last line measures, at the same time, the figure the paper
hand's ``before`` comes from: today's band tables of ``qsplan demo`` (:func:`qsplan.planner.search.tables.band_tables`,
the inertial wrench box of the task on).

With ``--compare REV`` (a git revision: its package exported beside this tree, :func:`revisions.export_revision`), that
last line is measured for REV and this tree in the same run, each in its own process, interleaved ``--rounds`` times
(the machine's speed drifts between minutes), best of ``--repeat`` band tables per process, best over the rounds, and
printed as a table with their ratio: ``python3 benchmarks/bench_hands.py --compare HEAD~3 [--rounds 5] [--tables-only]``.
"""

import argparse
import os
import subprocess
import sys
import tempfile
import time
import tomllib
from pathlib import Path

import numpy as np

from qsplan.hands.described.build import make_described_hand
from qsplan.hands.description import load_hand
from qsplan.mechanics.bands.batched import LazyScenes, batch_from_arrays
from qsplan.mechanics.bands.batched_robust import robust_band_arrays

from bench_plan import table_rate  # the demo tables' rate, measured as bench_plan.py measures it
from revisions import revision_env

HERE = Path(__file__).resolve().parent

#: What a process of :func:`compare_tables` runs: the demo tables' rate (checks/s) and checks, as the last line.
_TABLE_RATE = "import sys; sys.path.insert(0, {here!r}); from bench_plan import table_rate; print(*table_rate({repeat}))"

#: Half the span (m) of the workpiece x judged: that of ``qsplan demo``'s band tables (the last line's).
SPAN = 0.06

#: The friction box, force margin and slide speed (m/s) of the bands.
MU_RANGE, FORCE_MARGIN, SPEED = (0.0, 0.2), (0.05, 0.05), 0.01

#: The issue's figures before the hand protocol (checks/s): the paper hand's band tables, the chain hands' judge.
BEFORE = {"paper_hand": "~12,000", "two_link_hand": "232-357", "parallel_jaw": "154"}

#: The bundled task whose workpiece (and start) each hand holds.
TASKS = {"paper_hand": "demo_task", "two_link_hand": "two_link_task", "parallel_jaw": "parallel_jaw_task"}

_ARRAYS = ("Wn", "Wt", "Jn", "Jt", "g_obj", "g_man")


def _task(stem):
    from importlib.resources import files

    return tomllib.loads(files("qsplan.planner").joinpath("data", f"{stem}.toml").read_text())


def hand_cases():
    """``[(label, hand file, hand, free rows or None)]``: every bundled hand, the paper hand both ways."""
    out = []
    for name, stem in TASKS.items():
        table = _task(stem)
        wp = table["hand"]["workpiece"]
        for accelerated in ((True, False) if name == "paper_hand" else (True,)):
            mass = table["hand"].get("workpiece_mass", 0.2)
            hand = make_described_hand(load_hand(name), wp, mass, accelerated=accelerated)
            free = None
            if hand.free_joints:
                start = np.array([table["start"][hand.joint_names[j]] for j in hand.free_joints])
                grid = np.meshgrid(*[s + np.array([-0.05, 0.0, 0.05]) for s in start], indexing="ij")
                free = np.column_stack([g.ravel() for g in grid])
            label = name + ("" if name != "paper_hand" else (" (closed forms)" if hand.accelerated else " (generic)"))
            out.append((label, name, hand, free))
    return out


def geometry(hand, grasps, xs, lim):
    """Judge every grasp at ``xs``: ``[(grasp, arrays, rows)]`` with ``rows`` the valid states of ``arrays``."""
    out = []
    for g in grasps:
        states = hand.grasp_states("palm_edge", g, xs)
        arrays = hand.scene_arrays("palm_edge", states)
        q = states.q[arrays.idx]
        valid = arrays.ok & np.all((q >= lim[:, 0]) & (q <= lim[:, 1]), axis=1)
        rows = np.flatnonzero(valid)
        if rows.size:
            hit = hand.collide(states.poses[arrays.idx[rows]], q[rows])
            rows = rows[~hit]
        out.append((g, arrays, rows))
    return out


def bands(hand, judged):
    """The guaranteed bands of every valid state, each closing joint effort-controlled, both directions: checks made."""
    checks = 0
    parts = [(arrays, rows) for _, arrays, rows in judged if rows.size]
    if not parts:
        return 0
    n_j = len(hand.joint_names)
    for k in hand.closing_joints:  # one batch per effort joint: both directions, every grasp (as the band tables)
        e = np.arange(n_j) == k
        stacked = [np.concatenate([getattr(a, f)[r] for _ in (-1, 1) for a, r in parts]) for f in _ARRAYS]
        velocity = np.concatenate([a.dq_dx[r] * (d * SPEED) for d in (-1, 1) for a, r in parts])
        where = [(a, int(s)) for _ in (-1, 1) for a, r in parts for s in r]

        def scene(s, e=e, velocity=velocity, where=where):
            a, i = where[s]
            return hand.state_scene(a, i, e, velocity[s])

        batch = batch_from_arrays(LazyScenes(len(where), scene), *stacked, np.where(e, np.nan, velocity))
        robust_band_arrays(batch, "SSSS", MU_RANGE, force_margin=FORCE_MARGIN)
        checks += len(where)
    return checks


def compare_tables(rev: str, repeat: int, rounds: int) -> dict:
    """The demo tables' rate (checks/s, best) and checks of git revision ``rev`` (``before``) and of this tree
    (``after``): a process per side and round, the sides interleaved; each process takes the best of ``repeat``."""
    with tempfile.TemporaryDirectory(prefix="qsplan-bench-") as tmp:
        sides = {"before": revision_env(rev, Path(tmp) / "rev"), "after": dict(os.environ)}
        best = {side: (0.0, 0) for side in sides}
        code = _TABLE_RATE.format(here=str(HERE), repeat=repeat)
        for i in range(rounds):
            for side, env in sides.items():
                out = subprocess.run([sys.executable, "-c", code], env=env, cwd=tmp, check=True, capture_output=True, text=True)
                rate, checks = out.stdout.split()
                best[side] = max(best[side], (float(rate), int(checks)))
            print(f"round {i + 1} of {rounds} done", file=sys.stderr, flush=True)
    return best


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--step", type=float, default=5e-4, help="grid step of the workpiece x (m)")
    ap.add_argument("--repeat", type=int, default=3, help="passes (best taken)")
    ap.add_argument("--compare", metavar="REV", help="the demo tables' line for git revision REV too, interleaved")
    ap.add_argument("--rounds", type=int, default=5, help="with --compare: processes per side, interleaved (best taken)")
    ap.add_argument("--tables-only", action="store_true", help="only the demo tables' line (and --compare's table)")
    args = ap.parse_args(argv)
    if args.compare:
        best = compare_tables(args.compare, args.repeat, args.rounds)
        (b, n), (a, m) = best["before"], best["after"]
        print(f"paper_hand: band tables of qsplan demo (inertial box on), checks/s, best of {args.rounds} processes x "
              f"{args.repeat} tables, interleaved")  # fmt: skip
        print(f"{'side':<28} {'checks':>7} {'checks/s':>9} {'ms/table':>9} {'target':>7}")
        print(f"{'before (' + args.compare + ')':<28} {n:7d} {b:9.0f} {1e3 * n / b:9.1f} {'10,000':>7}")
        print(f"{'after (this tree)':<28} {m:7d} {a:9.0f} {1e3 * m / a:9.1f} {'10,000':>7}")
        print(f"{'ratio after / before':<28} {'':>7} {a / b:9.2f}")
        if args.tables_only:
            return
        print()
    elif args.tables_only:
        rate, checks = table_rate(args.repeat)
        print(f"{'paper_hand: band tables today':<28} {checks:7d} {rate:9.0f}")
        return
    print(f"{'hand':<28} {'grasps':>6} {'states':>7} {'valid':>6} {'states/s':>9} {'checks':>7} {'checks/s':>9} "
          f"{'before':>8} {'target':>7}")  # fmt: skip
    for label, name, hand, free in hand_cases():
        lim = hand.own_limits[0]
        grasps = hand.grasp_candidates("palm_edge", free)
        lo, hi = hand.palm_range
        xs = np.arange(max(lo, -SPAN), min(hi, SPAN) + 0.5 * args.step, args.step)
        best_geo = best_all = np.inf
        for _ in range(args.repeat):
            hand.closings.clear()  # each pass closes the fingers afresh (the grasps of one pass share closings)
            t0 = time.perf_counter()
            judged = geometry(hand, grasps, xs, lim)
            t1 = time.perf_counter()
            checks = bands(hand, judged)
            t2 = time.perf_counter()
            best_geo, best_all = min(best_geo, t1 - t0), min(best_all, t2 - t0)
        states = len(grasps) * len(xs)
        valid = sum(r.size for _, _, r in judged)
        print(f"{label:<28} {len(grasps):6d} {states:7d} {valid:6d} {states / best_geo:9.0f} {checks:7d} "
              f"{checks / best_all:9.0f} {BEFORE[name]:>8} {'10,000':>7}")  # fmt: skip
    rate, checks = table_rate(args.repeat)
    print(f"{'paper_hand: band tables today':<28} {'':>6} {'':>7} {'':>6} {'':>9} {checks:7d} {rate:9.0f} "
          f"{BEFORE['paper_hand']:>8} {'10,000':>7}")  # fmt: skip


if __name__ == "__main__":
    main()
