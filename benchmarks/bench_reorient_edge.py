"""Reorienting a workpiece onto another palm edge (issue 23): the mechanics of the route of
``planner/data/reorient_edge_task.toml``, with timings.

The route: the palm-edge slide to the flush instant (the left finger along the longest edge), a hold there, the
transition ``BSSSS`` (the bottom edge's left end lifts), the pivot on vertex 1 (4S: vertex 1 sliding on the palm,
the left finger flush, the right finger on the flush instant's vertex) down to the angle where the next edge
(vertex 1 -> vertex 2) lands flat on the palm, and a hold there.  Printed:

* the flush instant (:func:`qsplan.hands.reorient.flush_instant`), its joints against the task's limits;
* the certified holds at the flush instant (:mod:`qsplan.mechanics.bands.hold`): each finger torque-controlled with
  the other held, the torque intervals (normal forces >= 1e-6 N and >= the task's force margin, with the task's
  inertial box), and every joint held;
* the transition band (:func:`qsplan.mechanics.robust_band`, five contacts) for each torque-controlled finger,
  without and with the task's force margin and inertial box, and the certifier's mode check
  (:func:`qsplan.planner.certify.modes.mode_checks`) just inside each finite edge at the friction box's vertices
  and ``--random`` seeded vectors;
* the pivot (:func:`qsplan.hands.pivot_sweep.sweep_pivot`, the task's force margin): its events, the contact sets
  against the polygon search, the joints; each sample's right-finger 4S band again with the inertial box too; every
  sample's geometry as the planner judges it (:func:`qsplan.planner.states.contact.configuration_problem`: joint
  limits, every pair of bodies, finger against finger too) and the gap between the two fingers;
* the landing (vertices 1 and 2 on the palm, the left finger flush, the right finger): the angle in closed form
  against the sweep's ``palm_v2`` event, the polygon search's contacts, the hold with the right torque at the last
  band's lower edge plus the resolution, and the hold's torque intervals.

The palm-edge slide itself is the planner's: ``qsplan plan`` on this task with ``[goal] x`` just short of the flush
instant (and no ``palm``) plans it.

Usage, from the repository root::

    python3 benchmarks/bench_reorient_edge.py [--task PATH] [--step 0.25] [--every 12] [--random 40] [--seed 23]
"""

import argparse
import time
from dataclasses import replace
from itertools import product
from pathlib import Path

import numpy as np

from qsplan.hands.contact_sets import (ContactSpec, contact_set_scene, finger_inner_edge, flush_contacts,
                                       locate_contacts, palm_top_edge)  # fmt: skip
from qsplan.hands.formations import formation
from qsplan.hands.pivot_sweep import polygon_contacts, same_contacts, sweep_pivot
from qsplan.hands.reorient import (PIVOT_FORMATION, TRANSITION_FORMATION, flush_instant, pivot_configurations,
                                   pivot_scene, transition_scene)  # fmt: skip
from qsplan.mechanics import robust_band
from qsplan.mechanics.bands.hold import hold_torque_interval, prove_hold
from qsplan.planner.certify.modes import mode_checks
from qsplan.planner.certify.rows import friction_points
from qsplan.planner.states.contact import configuration_problem
from qsplan.planner.task.task import load_task

ROOT = Path(__file__).resolve().parent.parent
TASK = ROOT / "planner" / "data" / "reorient_edge_task.toml"
PIVOT = 1  # the internal vertex the workpiece pivots on (the bottom edge's right end)
INSIDE = 1e-6  # N m: how far inside a finite band edge the certifier's mode check runs
INTERVAL_MARGIN = 1e-6  # N: the hold intervals' smallest normal force without the task's force margin


def timed(f, *args, **kwargs):
    """``(f(*args, **kwargs), seconds)``."""
    t0 = time.perf_counter()
    out = f(*args, **kwargs)
    return out, time.perf_counter() - t0


def held(scene, effort):
    """``scene`` with ``effort`` (bool per joint) torque-controlled and every other joint held."""
    e = np.asarray(effort, dtype=bool)
    return scene.with_control(e, np.zeros(len(e)), np.where(e, 0.0, np.nan))


def written(hand, kind, i):
    """An internal vertex or edge as the task's polygon numbers it."""
    return int((hand.user_vertices if kind == "vertex" else hand.user_edges)[i])


def hold_rows(task, label, scene, ramp):
    """The hold intervals of each finger torque-controlled (the other held), and the ramp's proof."""
    box = task.disturbance
    for j, side in enumerate(("left", "right")):
        s = held(scene, [j == 0, j == 1])
        (a, sa), (b, sb) = (timed(hold_torque_interval, s, box, m) for m in (INTERVAL_MARGIN, task.force_margin.normal))
        print(f"  {label}: {side} torque, other held, box: [{a[0]:.5g}, {a[1]:.5g}] (>= 1e-6 N), "
              f"[{b[0]:.5g}, {b[1]:.5g}] (>= {task.force_margin.normal:g} N)   {1e3 * (sa + sb):.1f} ms")  # fmt: skip
    if ramp is not None:
        side, tau = ramp
        s = held(scene, [side == "left", side == "right"])
        proof, sec = timed(prove_hold, s, np.array(tau)[:, None], box)
        print(f"  {label}: {side} ramp [{tau[0]:.4f}, {tau[1]:.4f}] N m with the box: "
              f"{'proved' if proof.proved else 'REFUSED'}, margin {proof.margin:.4g} N   "
              f"{1e3 * sec:.1f} ms")  # fmt: skip
    n = scene.n_joints
    s = scene.with_control(np.zeros(n, dtype=bool), np.zeros(n), np.full(n, np.nan))
    try:
        proof = prove_hold(s, np.zeros((1, 0)), box)
        print(f"  {label}: every joint held: {'proved' if proof.proved else 'REFUSED'}, margin {proof.margin:.4g} N"
              f"{' (capped: immobilised at first order)' if proof.capped else ''}")  # fmt: skip
    except ValueError as exc:
        print(f"  {label}: every joint held: not provable here ({exc})")


def transition_table(task, instant, mus):
    mode = formation(TRANSITION_FORMATION).mode
    names = ", ".join(formation(TRANSITION_FORMATION).contact_names)
    print(f"\ntransition {mode} at the flush instant (contacts {names})")
    print(f"{'torque':>6} {'margin+box':>10} {'lower':>10} {'upper':>10} {'exact':>5} {'ms':>6}   mode check inside "
          f"the edge at {len(mus)} friction vectors (no box)")  # fmt: skip
    edges = {}
    for ej, loaded in product(("right", "left"), (False, True)):
        scene = transition_scene(task.hand, instant, ej)
        margin, box = (task.force_margin, task.disturbance) if loaded else (None, None)
        band, sec = timed(robust_band, scene, mode, task.mu_range, force_margin=margin, disturbance=box)
        edge = band.lower if np.isfinite(band.lower) else band.upper
        tau = edge + (INSIDE if np.isfinite(band.lower) else -INSIDE)
        s = replace(scene, joint_effort=np.where(scene.effort_controlled, tau, np.nan))
        found, aside = mode_checks(task, {"mode": np.array([mode]), "y_workpiece": np.array([0.0])}, 0, mus,
                                   task.force_margin.normal if loaded else 0.0, scene=s)  # fmt: skip
        verdict = f"only {mode}" if not found else "; ".join(m for _, m in found)
        print(f"{ej:>6} {'yes' if loaded else 'no':>10} {band.lower:>10.4f} {band.upper:>10.4f} {band.exact!s:>5} "
              f"{1e3 * sec:>6.1f}   {verdict} ({len(aside)} modes degenerate to machine precision set "
              "aside)")  # fmt: skip
        if loaded:
            edges[ej] = edge
    return edges


def pivot_table(task, sweep, boxed, every):
    c, b = sweep.configurations, sweep.bands["right"]
    rows = set(range(0, len(c.theta), every)) | {len(c.theta) - 1, int(np.argmin(b.width)), int(np.argmin(boxed[0]))}
    print(f"\npivot on v{PIVOT}: {len(c.theta)} samples from 0 to {np.degrees(c.theta[-1]):.2f} deg; right-finger 4S "
          f"bands (N m) with the force margin, and with the inertial box too")  # fmt: skip
    print(f"{'theta':>8} {'x':>9} {'y':>8} {'q_l':>7} {'q_r':>7} | {'lower':>8} {'upper':>8} {'width':>8} | "
          f"{'lower+box':>9} {'upper+box':>9} | poly")  # fmt: skip
    for i in sorted(rows):
        print(f"{np.degrees(c.theta[i]):>8.2f} {c.pose[i, 0]:>9.5f} {c.pose[i, 1]:>8.5f} {np.degrees(c.q[i, 0]):>7.2f} "
              f"{np.degrees(c.q[i, 1]):>7.2f} | {b.lower[i]:>8.4f} {b.upper[i]:>8.4f} {b.width[i]:>8.4g} | "
              f"{boxed[0][i]:>9.4f} {boxed[1][i]:>9.4f} | {'ok' if sweep.agrees[i] else 'differs'}")  # fmt: skip
    i = int(np.argmin(b.width))
    narrowest = "every band unbounded above" if np.isinf(b.width[i]) else \
        f"narrowest width {b.width[i]:.4g} N m at {np.degrees(c.theta[i]):.2f} deg"  # fmt: skip
    print(f"{narrowest}; largest lower edge "
          f"{np.nanmax(b.lower[1:]):.4f} N m after theta = 0; smallest lower edge {np.nanmin(b.lower):.4f} N m at "
          f"{np.degrees(c.theta[int(np.nanargmin(b.lower))]):.2f} deg; every band exact: {b.exact.all()}, "
          f"with the box: {boxed[2].all()}; finite upper edges: {np.isfinite(b.upper).sum()} (with the box "
          f"{np.isfinite(boxed[1]).sum()}); widths >= 0.02 N m at every sample: {(b.width > 0.02).all()} "
          f"(with the box {(boxed[1] - boxed[0] > 0.02).all()})")  # fmt: skip
    print(f"joints along the pivot (deg): left {np.degrees(c.q[:, 0].min()):.2f} to {np.degrees(c.q[:, 0].max()):.2f}, "
          f"right {np.degrees(c.q[:, 1].min()):.2f} to {np.degrees(c.q[:, 1].max()):.2f}; limits "
          f"{np.degrees(task.joint_limits).round(2).tolist()}; polygon search agrees at {sweep.agrees.sum()} of "
          f"{len(c.theta)} samples (not at theta = 0, where v0 still touches the palm)")  # fmt: skip
    from bench_reorient import print_events  # the sibling script's table of events

    print_events(sweep)


def clearance(task, configurations, label):
    """Every sample of ``configurations`` judged by the planner's geometry check, and the gap (m) between the two
    fingers."""
    from shapely.geometry import Polygon

    from qsplan.hands.contact_sets import body_ring

    c = configurations
    problems = [(t, why) for t, p, q in zip(c.theta, c.pose, c.q) if (why := configuration_problem(task, p, q))]
    gap = np.array([Polygon(body_ring(task.hand, "left", q)).distance(Polygon(body_ring(task.hand, "right", q)))
                    for q in c.q])  # fmt: skip
    i = int(np.argmin(gap))
    first = "none" if not problems else f"first at {np.degrees(problems[0][0]):.2f} deg: {problems[0][1]}"
    print(f"{label}: geometry (limits, every body pair) refused at {len(problems)} of {len(c.theta)} samples "
          f"({first}); the fingers' smallest gap {1e3 * gap[i]:.2f} mm at {np.degrees(c.theta[i]):.2f} deg "
          f"(from {1e3 * gap[0]:.2f} to {1e3 * gap[-1]:.2f} mm)")  # fmt: skip


def landing_scene(task, theta, right_vertex, effort):
    """The landing instant's five contacts (vertices 1 and 2 on the palm, the left finger flush, the right finger):
    the configuration, its contact specs and the scene with ``effort`` torque-controlled."""
    hand = task.hand
    c = pivot_configurations(hand, [theta], PIVOT, None, right_vertex)
    pose, q, top = c.pose[0], c.q[0], palm_top_edge(hand)
    contacts = (ContactSpec("palm:1", "palm", ("vertex", PIVOT), ("edge", top)),
                ContactSpec("palm:2", "palm", ("vertex", PIVOT + 1), ("edge", top)),
                *flush_contacts(hand, pose, q, "left", c.edge, finger_inner_edge(hand, "left")),
                ContactSpec("right", "right", ("vertex", right_vertex), ("edge", finger_inner_edge(hand, "right"))))
    return c, contacts, contact_set_scene(hand, pose, q, contacts, effort, np.zeros(2))


def landing(task, sweep, instant, boxed):
    hand, V = task.hand, task.hand.paper.workpiece
    d = V[PIVOT + 1] - V[PIVOT]
    theta = -float(np.arctan2(d[1], d[0]))  # edge 1 -> 2 turned level: vertex 2 at vertex 1's height
    event = next(e.theta for e in sweep.events if e.name == f"palm_v{PIVOT + 1}")
    c, contacts, scene = landing_scene(task, theta, instant.right_vertex, [False, True])
    W, pose = c.vertices[0], c.pose[0]
    found = locate_contacts(hand, pose, c.q[0], contacts)
    reference = polygon_contacts(hand, pose, c.q[0])
    print(f"\nlanding: edge {written(hand, 'edge', PIVOT)} as written (v{PIVOT} -> v{PIVOT + 1}) flat on the palm at "
          f"theta = {np.degrees(theta):.4f} deg = {theta:.6f} rad (closed form; the sweep's palm_v{PIVOT + 1} event "
          f"{np.degrees(event):.4f} deg)")  # fmt: skip
    q = np.degrees(c.q[0])
    inside = min(pose[0] - W[PIVOT, 0], W[PIVOT + 1, 0] - pose[0])  # m from the nearer end of the new bottom edge
    print(f"  pose ({pose[0]:.6f}, {pose[1]:.6f}) m, q = ({q[0]:.2f}, {q[1]:.2f}) deg; the centre of mass at "
          f"x = {pose[0]:.5f} over the new bottom edge [{W[PIVOT, 0]:.5f}, {W[PIVOT + 1, 0]:.5f}] m: {inside > 0}, "
          f"{1e3 * inside:.2f} mm inside")  # fmt: skip
    clearance(task, c, "  landing")
    listed = ", ".join(f"{s.name} {s.workpiece[0][0]}{s.workpiece[1]}/{s.feature[0][0]}{s.feature[1]}"
                       for s in contacts)  # fmt: skip
    print(f"  contacts (workpiece feature/body feature, internal): {listed}; the polygon search finds the same "
          f"{len(reference)}: {same_contacts(found, reference)}")  # fmt: skip
    mode = formation(PIVOT_FORMATION).mode
    last, sec = timed(robust_band, pivot_scene(hand, c, 0, "right"), mode, task.mu_range,
                      force_margin=task.force_margin, disturbance=task.disturbance)  # fmt: skip
    print(f"  the pivot's right band at the landing angle (margin and box): [{last.lower:.4f}, {last.upper:.4f}] N m, "
          f"exact {last.exact}   {1e3 * sec:.1f} ms")  # fmt: skip
    tau = last.lower + task.torque_resolution
    proof, sec = timed(prove_hold, scene, [tau], task.disturbance)
    print(f"  hold, left held, right at {tau:.4f} N m (the band's lower edge + the resolution), with the box: "
          f"{'proved' if proof.proved else 'REFUSED'}, margin {proof.margin:.4g} N   {1e3 * sec:.1f} ms")  # fmt: skip
    ramp = [tau, float(np.nanmax(boxed[0]))]
    proof = prove_hold(scene, np.array(ramp)[:, None], task.disturbance)
    print(f"  hold over [{ramp[0]:.4f}, {ramp[1]:.4f}] N m (up to the pivot's largest lower edge with the box): "
          f"{'proved' if proof.proved else 'REFUSED'}, margin {proof.margin:.4g} N")  # fmt: skip
    hold_rows(task, "landing", scene, None)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--task", default=str(TASK))
    parser.add_argument("--step", type=float, default=0.25, help="sweep step (deg)")
    parser.add_argument("--every", type=int, default=12, help="print every this many samples")
    parser.add_argument("--random", type=int, default=40, help="random friction vectors per mode check")
    parser.add_argument("--seed", type=int, default=23)
    args = parser.parse_args()
    task = load_task(args.task)
    hand = task.hand
    box = task.disturbance
    print(f"task {task.name!r}: workpiece {np.round(hand.paper.workpiece, 5).tolist()} (internal, about the centroid), "
          f"mu in {list(task.mu_range)} per contact, force margin {task.force_margin.normal:g} N, resolution "
          f"{task.torque_resolution:g} N m, inertial box lo {np.round(box.lo, 6).tolist()} hi "
          f"{np.round(box.hi, 6).tolist()}")  # fmt: skip
    instant, sec = timed(flush_instant, hand)
    lim = task.joint_limits
    inside = bool(np.all((lim[:, 0] <= instant.q) & (instant.q <= lim[:, 1])))
    print(f"flush instant: the left finger along edge {written(hand, 'edge', instant.edge)} as written, the right on "
          f"v{written(hand, 'vertex', instant.right_vertex)}: x = {instant.x:.6f} m, q = "
          f"({np.degrees(instant.q[0]):.2f}, {np.degrees(instant.q[1]):.2f}) deg, inside the limits {inside}   "
          f"{1e3 * sec:.2f} ms")  # fmt: skip
    rng = np.random.default_rng(args.seed)
    mus = friction_points(task, args.random, rng, 5)  # the five-contact box's vertices, then seeded draws
    edges = transition_table(task, instant, mus)
    print("\nholds at the flush instant (five contacts; proofs use no friction)")
    flush = transition_scene(hand, instant, "right")
    start = hold_torque_interval(held(flush, [False, True]), box, task.force_margin.normal)[0]
    hold_rows(task, "flush", flush, ("right", [start, edges["right"]]))
    t0 = time.perf_counter()
    sweep = sweep_pivot(hand, task.mu_range, task.force_margin, task.torque_resolution, effort_joints=("right",),
                        limits=task.joint_limits, step=np.radians(args.step), pivot=PIVOT,
                        right_vertex=instant.right_vertex)  # fmt: skip
    total = time.perf_counter() - t0
    c, mode = sweep.configurations, formation(PIVOT_FORMATION).mode
    t0 = time.perf_counter()
    rb = [robust_band(pivot_scene(hand, c, i, "right"), mode, task.mu_range, force_margin=task.force_margin,
                      disturbance=box) for i in range(len(c.theta))]  # fmt: skip
    boxed_s = time.perf_counter() - t0
    boxed = tuple(np.array([getattr(r, f) for r in rb]) for f in ("lower", "upper", "exact"))
    pivot_table(task, sweep, boxed, args.every)
    clearance(task, c, "pivot")
    s = sweep.seconds
    print(f"sweep: {total:.2f} s (manifold, contacts and events {s['manifold']:.2f} s, {len(c.theta)} bands "
          f"{s['bands']:.2f} s, band events {s['band events']:.2f} s); {len(c.theta)} bands with the box "
          f"{boxed_s:.2f} s")  # fmt: skip
    landing(task, sweep, instant, boxed)


if __name__ == "__main__":
    main()
