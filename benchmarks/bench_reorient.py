"""Reorientation mechanics of the demo's hand and workpiece (issue 23): the flush instant, the transition bands, the
pivot swept to its events, with timings.

* the flush instant ending the palm-edge slide (:func:`qsplan.hands.reorient.flush_instant`, closed form), against
  the root of segment 1's flush angle (:func:`qsplan.hands.segments.flush_angle`, brentq);
* the transition mode's robust band at that instant (five contacts, :func:`qsplan.mechanics.robust_band`), each
  finger torque-controlled, without and with the task's force margin, and the certifier's mode check
  (:func:`qsplan.planner.certify.modes.mode_checks`) at every friction-box vertex and ``--random`` seeded random
  vectors: just inside each finite edge, far along each unbounded side, just outside each finite edge;
* the pivot formation (:func:`qsplan.hands.pivot_sweep.sweep_pivot`): each finger's 4S band with the force margin
  every ``--every`` samples and at the events, the events located by bisection.

Usage, from the repository root::

    python3 benchmarks/bench_reorient.py [--step 0.25] [--every 20] [--random 40] [--seed 23] [--figure PATH]
"""

import argparse
import time
from dataclasses import replace
from itertools import product

import numpy as np
from scipy.optimize import brentq

from qsplan.hands.formations import formation
from qsplan.hands.pivot_sweep import sweep_pivot
from qsplan.hands.reorient import TRANSITION_FORMATION, flush_instant, pivot_configurations, transition_scene
from qsplan.hands.segments import flush_angle
from qsplan.mechanics import DEFAULT_TOLERANCES, robust_band, solve_many
from qsplan.planner.certify.modes import mode_checks
from qsplan.planner.certify.rows import friction_points
from qsplan.planner.task.task import demo_task_path, load_task

INSIDE, OUTSIDE, FAR = 1e-6, 1e-3, 100.0  # N m: inside a finite edge, outside it, along an unbounded side


def check(task, scene, mode, tau, margin, mus):
    """The certifier's mode check at effort ``tau``, plus the sliding and rolling contacts' normal forces against the
    margin (breaking ones carry none): a list of failures."""
    s = replace(scene, joint_effort=np.where(scene.effort_controlled, tau, np.nan))
    found, _ = mode_checks(task, {"mode": np.array([mode]), "y_workpiece": np.array([0.0])}, 0, mus, 0.0, scene=s)
    if margin is not None:
        sv = solve_many(s, mus, DEFAULT_TOLERANCES)
        j, held = sv.letters.index(mode), [i for i, c in enumerate(mode) if c != "B"]
        low = sv.c_n[sv.codes[:, j] == 0, j][:, held].min(initial=np.inf)
        if low < margin.normal * (1 - 1e-9):
            found.append(("force margin", f"{low:.3g} N"))
    return found


def transition_table(task, instant, mus):
    mode = formation(TRANSITION_FORMATION).mode
    names = ", ".join(formation(TRANSITION_FORMATION).contact_names)
    print(f"\ntransition mode {mode} at the flush instant (contacts {names})")
    print(f"{'torque':>6} {'margin':>7} {'lower':>10} {'upper':>10} {'exact':>5} {'band s':>7}   "
          f"all-modes check at {len(mus)} friction vectors")  # fmt: skip
    for ej, margin in product(("right", "left"), (None, task.force_margin)):
        scene = transition_scene(task.hand, instant, ej)
        t0 = time.perf_counter()
        band = robust_band(scene, mode, task.mu_range, force_margin=margin)
        seconds = time.perf_counter() - t0
        verdicts = []
        for edge, sign in ((band.lower, 1.0), (band.upper, -1.0)):
            if np.isfinite(edge):
                inside = check(task, scene, mode, edge + sign * INSIDE, margin, mus)
                outside = check(task, scene, mode, edge - sign * OUTSIDE, margin, mus)
                verdicts.append(f"edge{sign * INSIDE:+.0e}: {'only ' + mode if not inside else inside[0][1]}; "
                                f"edge{-sign * OUTSIDE:+.0e}: {outside[0][1] if outside else 'no failure'}")  # fmt: skip
            else:
                finite = band.upper if sign > 0 else band.lower
                far = check(task, scene, mode, finite - sign * FAR, margin, mus)
                verdicts.append(f"edge{-sign * FAR:+g}: {'only ' + mode if not far else far[0][1]}")
        name = "0.05 N" if margin is not None else "none"
        print(f"{ej:>6} {name:>7} {band.lower:>10.4f} {band.upper:>10.4f} {str(band.exact):>5} {seconds:>7.3f}   "
              + " | ".join(verdicts))  # fmt: skip


def sweep_table(sweep, every):
    c, bands = sweep.configurations, sweep.bands
    rows = set(range(0, len(c.theta), every)) | {len(c.theta) - 1}
    for e in sweep.events:  # the samples either side of each event
        i = int(np.searchsorted(-c.theta, -e.theta))
        rows |= {max(i - 1, 0), min(i, len(c.theta) - 1)}
    print(f"\npivot on v{c.pivot}: {len(c.theta)} samples from 0 to {np.degrees(c.theta[-1]):.2f} deg "
          f"(4S bands with the task's force margin, N m)")  # fmt: skip
    print(f"{'theta':>8} {'x':>9} {'q_l':>7} {'q_r':>7} {'left:tip':>14} | {'right lo':>9} {'right hi':>9} "
          f"{'width':>8} | {'left lo':>9} {'left hi':>9} {'width':>8} poly")  # fmt: skip
    for i in sorted(rows):
        tip = sweep.contacts[i].specs[2]
        feature = f"v{tip.workpiece[1]}" if tip.workpiece[0] == "vertex" else f"corner {tip.feature[1]}"
        r, l_ = bands["right"], bands["left"]
        print(f"{np.degrees(c.theta[i]):>8.2f} {c.pose[i, 0]:>9.5f} {np.degrees(c.q[i, 0]):>7.2f} "
              f"{np.degrees(c.q[i, 1]):>7.2f} {feature:>14} | {r.lower[i]:>9.5f} {r.upper[i]:>9.5f} {r.width[i]:>8.5f} | "
              f"{l_.lower[i]:>9.5f} {l_.upper[i]:>9.5f} {l_.width[i]:>8.5f} "
              f"{'ok' if sweep.agrees[i] else 'differs'}")  # fmt: skip
    print_events(sweep)
    print(f"exact bands: right {bands['right'].exact.all()}, left {bands['left'].exact.all()}; polygon search agrees at "
          f"{sweep.agrees.sum()} of {len(c.theta)} samples (not at theta = 0, where v0 still touches the palm)")  # fmt: skip


def print_events(sweep):
    """The sweep's events, in the order they occur (bench_reorient_edge.py prints its own with this)."""
    print("\nevents (bisection to 1e-6 rad)")
    for e in sweep.events:
        ends = "  (ends the formation)" if e.ends else ""
        print(f"  {np.degrees(e.theta):>10.4f} deg  {e.name:<18} {e.description}{ends}")


def figure(task, instant, sweep, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from qsplan.hands.interface import hand_body_polygons

    fig, (ax0, ax1) = plt.subplots(1, 2, figsize=(12, 5))
    shown = np.radians([0.0, -20.0, -40.0, -54.0])
    c = pivot_configurations(task.hand, shown)
    for k, (pose, q) in enumerate(zip(c.pose, c.q)):
        polys = hand_body_polygons(task.hand, pose, q)
        colour = plt.cm.viridis(k / (len(shown) - 1))
        for name in ("left", "right", "workpiece"):
            P = np.vstack([polys[name], polys[name][:1]])
            ax0.plot(P[:, 0], P[:, 1], color=colour, lw=1.5 if name == "workpiece" else 0.8,
                     label=f"theta = {np.degrees(c.theta[k]):.0f} deg" if name == "workpiece" else None)  # fmt: skip
    palm = np.vstack([polys["palm"], polys["palm"][:1]])
    ax0.fill(palm[:, 0], palm[:, 1], color="0.8")
    ax0.set_aspect("equal")
    ax0.set_xlim(-0.12, 0.2)
    ax0.set_ylim(-0.03, 0.2)
    ax0.set_xlabel("x (m)")
    ax0.set_ylabel("y (m)")
    ax0.set_title("pivot on v1, the left finger flush on edge 3->0")
    ax0.legend(fontsize=8)
    th = np.degrees(sweep.configurations.theta)
    for ej, colour in (("right", "C0"), ("left", "C3")):
        b = sweep.bands[ej]
        # the left finger's band is negative (it pushes clockwise): drawn as -tau on the log axis
        lo, hi = (b.lower, b.upper) if ej == "right" else (-b.upper, -b.lower)
        ax1.fill_between(th, lo, np.minimum(hi, 1.0), color=colour, alpha=0.3,
                         label=f"{ej} finger torque{'' if ej == 'right' else ' (negated)'}")  # fmt: skip
        ax1.plot(th, lo, color=colour, lw=1)
    for k, e in enumerate(sweep.events):  # numbered (several lie within a degree), listed in a box
        ax1.axvline(np.degrees(e.theta), color="0.5", lw=0.6, ls="--")
        ax1.text(np.degrees(e.theta), (0.98, 0.93)[k % 2], str(k + 1), fontsize=7, ha="center", va="top",
                 transform=ax1.get_xaxis_transform())  # fmt: skip
    listing = "\n".join(f"{k + 1} {np.degrees(e.theta):.2f} deg {e.name}" for k, e in enumerate(sweep.events))
    ax1.text(0.99, 0.02, listing, fontsize=7, ha="right", va="bottom", family="monospace", transform=ax1.transAxes,
             bbox={"facecolor": "white", "edgecolor": "0.7"})  # fmt: skip
    ax1.set_yscale("log")
    ax1.set_ylim(1e-4, 1.0)
    ax1.set_xlabel("theta (deg)")
    ax1.set_ylabel("guaranteed 4S band (N m), 0.05 N margin")
    mode = formation(TRANSITION_FORMATION).mode
    start = robust_band(transition_scene(task.hand, instant, "right"), mode, task.mu_range, force_margin=task.force_margin)
    ax1.set_title(f"4S bands along the pivot (transition {mode} at 0: right >= {start.lower:.3f} N m)", fontsize=10)
    ax1.invert_xaxis()
    ax1.legend(fontsize=8, loc="lower left")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    print(f"\nfigure: {path}")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--step", type=float, default=0.25, help="sweep step (deg)")
    parser.add_argument("--every", type=int, default=20, help="print every this many samples (and those at events)")
    parser.add_argument("--random", type=int, default=40, help="random friction vectors per check")
    parser.add_argument("--seed", type=int, default=23)
    parser.add_argument("--figure", default=None, help="write the figure here (PNG)")
    args = parser.parse_args()
    task = load_task(demo_task_path())
    hand, paper = task.hand, task.hand.paper
    t0 = time.perf_counter()
    instant = flush_instant(hand)
    closed = time.perf_counter() - t0
    t0 = time.perf_counter()
    root = brentq(lambda x: flush_angle(paper, [x, paper.rest_height, 0.0]), instant.x - 5e-6, instant.x + 5e-3,
                  xtol=1e-15)  # fmt: skip
    reference = time.perf_counter() - t0
    print(f"flush instant (left finger along edge {instant.edge}, right finger on v{instant.right_vertex}): "
          f"x = {instant.x:.6f} m, q_left = {np.degrees(instant.q[0]):.2f} deg, "
          f"q_right = {np.degrees(instant.q[1]):.2f} deg; closed form {closed * 1e3:.2f} ms; brentq on the flush angle "
          f"{root:.9f} m (|diff| {abs(root - instant.x):.1e} m, {reference * 1e3:.2f} ms)")  # fmt: skip
    rng = np.random.default_rng(args.seed)
    mus = friction_points(task, args.random, rng, 5)  # the five-contact box's vertices, then seeded draws
    transition_table(task, instant, mus)
    t0 = time.perf_counter()
    sweep = sweep_pivot(hand, task.mu_range, task.force_margin, task.torque_resolution, limits=task.joint_limits,
                        step=np.radians(args.step))  # fmt: skip
    total = time.perf_counter() - t0
    sweep_table(sweep, args.every)
    s = sweep.seconds
    print(f"sweep: {total:.2f} s (manifold, contacts and geometric events {s['manifold']:.2f} s, "
          f"{2 * len(sweep.configurations.theta)} robust bands {s['bands']:.2f} s, "
          f"band events {s['band events']:.2f} s)")  # fmt: skip
    if args.figure:
        figure(task, instant, sweep, args.figure)


if __name__ == "__main__":
    main()
