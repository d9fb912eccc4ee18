"""The demo's turn as the formation search sees it (issues 23, 32): the flush instant, the transition bands, the pivot
swept to its end, with timings.

* the flush instant ending the palm-edge slide (:func:`qsplan.hands.formations.pivots.pivot_formations`: Newton's method
  on the five gap constraints, :mod:`qsplan.hands.formations.manifold`), against the root of segment 1's flush angle
  (:func:`qsplan.hands.paper_hand.segments.flush_angle`, brentq, an independent closed form);
* the transition mode's robust band at that instant (the five contacts the polygons show,
  :func:`qsplan.hands.contacts.found.row_contact_scene`; :func:`qsplan.mechanics.robust_band`), each finger
  torque-controlled, without and with the task's force margin, and the certifier's mode check
  (:func:`qsplan.planner.certify.modes.mode_checks`) at every friction-box vertex and ``--random`` seeded random
  vectors: just inside each finite edge, far along each unbounded side, just outside each finite edge;
* the clockwise pivot swept to its end (:func:`qsplan.planner.plan.pivot.pivot_geometry`: rows every 0.25 deg, its
  ending event, the slip reversals where the search cuts it): each finger's 4S band with the force margin at every
  row (printed every ``--every`` rows), and where each band falls below the resolution or closes, bisected.

Usage, from the repository root::

    python3 benchmarks/bench_reorient.py [--every 20] [--random 40] [--seed 23] [--figure PATH]
"""

import argparse
import time
from dataclasses import replace
from itertools import product

import numpy as np
from scipy.optimize import brentq

from qsplan.hands.contacts.found import row_contact_scene
from qsplan.hands.formations.pivots import pivot_formations, pivot_path
from qsplan.hands.paper_hand.segments import flush_angle
from qsplan.mechanics import DEFAULT_TOLERANCES, robust_band, solve_many
from qsplan.planner.certify.modes import mode_checks
from qsplan.planner.certify.rows import friction_points
from qsplan.planner.plan.pivot import pivot_geometry
from qsplan.planner.task.task import demo_task_path, load_task

INSIDE, OUTSIDE, FAR = 1e-6, 1e-3, 100.0  # N m: inside a finite edge, outside it, along an unbounded side
THETA_RATE = -0.05  # rad/s: the turning rate the scenes are built for (a band depends on its sign only)
BEYOND = -1.6  # rad: a goal past any event, so that the sweep runs to the formation's end
BISECT_TOL = 1e-6  # rad: the bracket to which a band event is bisected


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


def scene_at(task, pose, q, dq, effort_joint):
    """The row's scene (the contacts the polygons show), ``effort_joint`` torque-controlled, the other closing joint
    driven at its manifold rate for the workpiece turning at :data:`THETA_RATE`."""
    effort = np.array(task.hand.joint_names) == effort_joint
    return row_contact_scene(task.hand, pose, q, effort, np.asarray(dq) * THETA_RATE)


def transition_mode(scene, pivot):
    """The transition's letters: ``B`` for the bottom edge's lifting vertex, ``S`` for every other contact."""
    lifting = f"palm:{pivot.lifting_vertex()}"
    return "".join("B" if name == lifting else "S" for name in scene.contact_names)


def transition_table(task, pivot, start, tangent, mus):
    scene = scene_at(task, start[:3], start[3:], tangent, "right")
    mode = transition_mode(scene, pivot)
    print(f"\ntransition mode {mode} at the flush instant (contacts {', '.join(scene.contact_names)})")
    print(f"{'torque':>6} {'margin':>7} {'lower':>10} {'upper':>10} {'exact':>5} {'band s':>7}   "
          f"all-modes check at {len(mus)} friction vectors")  # fmt: skip
    for ej, margin in product(("right", "left"), (None, task.force_margin)):
        scene = scene_at(task, start[:3], start[3:], tangent, ej)
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


def band_at(task, pivot, c0, theta, effort_joint):
    """The 4S band (force margin) at angle ``theta`` on ``pivot``'s manifold, reached from configuration ``c0``."""
    p = pivot_path(task.hand, pivot, c0, [theta])
    scene = scene_at(task, p.pose[0], p.q[0], p.dq[0], effort_joint)
    return robust_band(scene, "S" * scene.n_contacts, task.mu_range, force_margin=task.force_margin)


def bisect(f, a, b):
    """The angle (rad) between ``a`` (``f`` true) and ``b`` (false) where ``f`` turns false, to :data:`BISECT_TOL`."""
    while abs(b - a) > BISECT_TOL:
        mid = 0.5 * (a + b)
        a, b = (mid, b) if f(mid) else (a, mid)
    return 0.5 * (a + b)


def sweep(task, pivot, start):
    """The pivot's rows to its end, both fingers' bands at every row but the first (the transition's), and the band
    events: ``(geometry, rows, bands, events, seconds)``."""
    t0 = time.perf_counter()
    geometry = pivot_geometry(task, pivot, start, BEYOND)
    path = geometry.path
    rows = np.arange(1, geometry.end.row if geometry.end is not None else path.theta.size)
    t1 = time.perf_counter()
    bands = {}
    for ej in ("right", "left"):
        out = []
        for i in rows:
            scene = scene_at(task, path.pose[i], path.q[i], path.dq[i], ej)
            out.append(robust_band(scene, "S" * scene.n_contacts, task.mu_range, force_margin=task.force_margin))
        bands[ej] = out
    t2 = time.perf_counter()
    events = [(t, "slip reversal", "a contact's sliding direction reverses (the search cuts the pivot there)")
              for t in geometry.cuts]
    if geometry.end is not None:
        events.append((geometry.end.theta, "the formation ends",
                       f"the formation ends ({geometry.end.event}): {geometry.end.words}"))
    for ej, out in bands.items():
        for name, ok in (("narrower than the resolution", lambda b: b.feasible and b.width >= task.torque_resolution),
                         ("closes (no band)", lambda b: b.feasible)):
            k = next((k for k, b in enumerate(out) if not ok(b)), None)
            if k is None or k == 0:
                continue
            i = rows[k - 1]
            c0 = np.concatenate([path.pose[i], path.q[i]])
            at = bisect(lambda t, ej=ej, ok=ok, c0=c0: ok(band_at(task, pivot, c0, t, ej)), path.theta[i],
                        path.theta[rows[k]])  # fmt: skip
            short = f"{ej} band " + ("< resolution" if name.startswith("narrower") else "closes")
            events.append((at, short, f"the {ej}-torque band {name}" + (f" ({task.torque_resolution:g} N m)"
                                                                         if name.startswith("narrower") else "")))
    seconds = {"geometry": t1 - t0, "bands": t2 - t1, "band events": time.perf_counter() - t2}
    return geometry, rows, bands, sorted(events, key=lambda e: -e[0]), seconds


def sweep_table(geometry, rows, bands, events, every):
    path = geometry.path
    shown = set(range(0, len(rows), every)) | {len(rows) - 1}
    print(f"\n{geometry.path.pivot.name}: {len(rows) + 1} rows from 0 to {np.degrees(path.theta[rows[-1]]):.2f} deg "
          f"(4S bands with the task's force margin, N m)")  # fmt: skip
    print(f"{'theta':>8} {'x':>9} {'q_l':>7} {'q_r':>7} | {'right lo':>9} {'right hi':>9} {'width':>8} | "
          f"{'left lo':>9} {'left hi':>9} {'width':>8}")  # fmt: skip
    for k in sorted(shown):
        i = rows[k]
        r, l_ = bands["right"][k], bands["left"][k]
        print(f"{np.degrees(path.theta[i]):>8.2f} {path.pose[i, 0]:>9.5f} {np.degrees(path.q[i, 0]):>7.2f} "
              f"{np.degrees(path.q[i, 1]):>7.2f} | {r.lower:>9.5f} {r.upper:>9.5f} {r.width if r.feasible else 0:>8.5f} | "
              f"{l_.lower:>9.5f} {l_.upper:>9.5f} {l_.width if l_.feasible else 0:>8.5f}")  # fmt: skip
    print("\nevents (bisection to 1e-6 rad)")
    for theta, _, words in events:
        print(f"  {np.degrees(theta):>10.4f} deg  {words}")
    exact = {ej: all(b.exact for b in out) for ej, out in bands.items()}
    print(f"exact bands: right {exact['right']}, left {exact['left']}")


def figure(task, geometry, rows, bands, events, path_png):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    path = geometry.path
    fig, (ax0, ax1) = plt.subplots(1, 2, figsize=(12, 5))
    shown = [int(np.argmin(np.abs(path.theta - np.radians(d)))) for d in (0.0, -20.0, -40.0, -54.0)]
    for k, i in enumerate(shown):
        polys = task.hand.body_polygons(path.pose[i], path.q[i])
        colour = plt.cm.viridis(k / (len(shown) - 1))
        for name in ("left", "right", "workpiece"):
            P = np.vstack([polys[name], polys[name][:1]])
            ax0.plot(P[:, 0], P[:, 1], color=colour, lw=1.5 if name == "workpiece" else 0.8,
                     label=f"theta = {np.degrees(path.theta[i]):.0f} deg" if name == "workpiece" else None)  # fmt: skip
    palm = np.vstack([polys["palm"], polys["palm"][:1]])
    ax0.fill(palm[:, 0], palm[:, 1], color="0.8")
    ax0.set_aspect("equal")
    ax0.set_xlim(-0.12, 0.2)
    ax0.set_ylim(-0.03, 0.2)
    ax0.set_xlabel("x (m)")
    ax0.set_ylabel("y (m)")
    ax0.set_title(path.pivot.words(task.hand), fontsize=9)
    ax0.legend(fontsize=8)
    th = np.degrees(path.theta[rows])
    for ej, colour in (("right", "C0"), ("left", "C3")):
        lower = np.array([b.lower if b.feasible else np.nan for b in bands[ej]])
        upper = np.array([b.upper if b.feasible else np.nan for b in bands[ej]])
        # the left finger's band is negative (it pushes clockwise): drawn as -tau on the log axis
        lo, hi = (lower, upper) if ej == "right" else (-upper, -lower)
        ax1.fill_between(th, lo, np.minimum(hi, 1.0), color=colour, alpha=0.3,
                         label=f"{ej} finger torque{'' if ej == 'right' else ' (negated)'}")  # fmt: skip
        ax1.plot(th, lo, color=colour, lw=1)
    for k, (theta, _, _) in enumerate(events):  # numbered (several lie within a degree), listed in a box
        ax1.axvline(np.degrees(theta), color="0.5", lw=0.6, ls="--")
        ax1.text(np.degrees(theta), (0.98, 0.93)[k % 2], str(k + 1), fontsize=7, ha="center", va="top",
                 transform=ax1.get_xaxis_transform())  # fmt: skip
    listing = "\n".join(f"{k + 1} {np.degrees(t):.2f} deg {short}" for k, (t, short, _) in enumerate(events))
    ax1.text(0.99, 0.02, listing, fontsize=7, ha="right", va="bottom", family="monospace", transform=ax1.transAxes,
             bbox={"facecolor": "white", "edgecolor": "0.7"})  # fmt: skip
    ax1.set_yscale("log")
    ax1.set_ylim(1e-4, 1.0)
    ax1.set_xlabel("theta (deg)")
    ax1.set_ylabel("guaranteed 4S band (N m), 0.05 N margin")
    ax1.set_title("4S bands along the pivot (the formation search's rows)", fontsize=10)
    ax1.invert_xaxis()
    ax1.legend(fontsize=8, loc="upper left")
    fig.tight_layout()
    fig.savefig(path_png, dpi=110)
    print(f"\nfigure: {path_png}")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--every", type=int, default=20, help="print every this many rows (and the last)")
    parser.add_argument("--random", type=int, default=40, help="random friction vectors per check")
    parser.add_argument("--seed", type=int, default=23)
    parser.add_argument("--figure", default=None, help="write the figure here (PNG)")
    args = parser.parse_args()
    task = load_task(demo_task_path())
    hand, paper = task.hand, task.hand.paper
    t0 = time.perf_counter()
    formations = pivot_formations(hand)
    generated = time.perf_counter() - t0
    pivot, start = formations[0]  # the left finger flush, clockwise on vertex 1 (the paper's)
    t0 = time.perf_counter()
    root = brentq(lambda x: flush_angle(paper, [x, paper.rest_height, 0.0]), start[0] - 5e-6, start[0] + 5e-3,
                  xtol=1e-15)  # fmt: skip
    reference = time.perf_counter() - t0
    print(f"{len(formations)} pivot formations generated in {generated * 1e3:.1f} ms: "
          f"{', '.join(p.name for p, _ in formations)}")  # fmt: skip
    print(f"flush instant of {pivot.name}: x = {start[0]:.6f} m, q_left = {np.degrees(start[3]):.2f} deg, "
          f"q_right = {np.degrees(start[4]):.2f} deg; brentq on the flush angle {root:.9f} m "
          f"(|diff| {abs(root - start[0]):.1e} m, {reference * 1e3:.2f} ms)")  # fmt: skip
    tangent = pivot_path(hand, pivot, start, [0.0]).dq[0]
    print(f"joint rates per unit turn at the flush instant: left {tangent[0]:.4f}, right {tangent[1]:.4f}")
    rng = np.random.default_rng(args.seed)
    mus = friction_points(task, args.random, rng, 5)  # the five-contact box's vertices, then seeded draws
    transition_table(task, pivot, start, tangent, mus)
    t0 = time.perf_counter()
    geometry, rows, bands, events, seconds = sweep(task, pivot, start)
    total = time.perf_counter() - t0
    sweep_table(geometry, rows, bands, events, args.every)
    print(f"sweep: {total:.2f} s (the geometry: rows, contacts, events and slip reversals {seconds['geometry']:.2f} s; "
          f"{2 * len(rows)} robust bands {seconds['bands']:.2f} s; band events {seconds['band events']:.2f} s)")
    if args.figure:
        figure(task, geometry, rows, bands, events, args.figure)


if __name__ == "__main__":
    main()
