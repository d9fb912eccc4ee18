"""Certified holds on the demo's hand and workpiece (issue 23, item 3): nothing moves while the hand holds still and
ramps a torque, proved for every friction (:mod:`qsplan.mechanics.bands.hold`), with timings.

* (a) the flush instant (five contacts: the clockwise pivot's start,
  :func:`qsplan.hands.formations.pivots.pivot_formations`, its scene from the contacts the polygons show,
  :func:`qsplan.hands.contacts.found.row_contact_scene`), the left finger held and the right finger's torque ramped from
  the slide's end (the demo's last command, or its band's lower edge) to the transition band's edge (3.8994 N m with the
  0.05 N margin, ``docs/reorientation.md``); the interval of right torques a hold is proved at (normal forces >= 1e-6 N,
  and >= the task's force margin); without and with the demo's inertial box; and, for the route search, the left finger
  torque-controlled with the right one held;
* (b) the demo's slide end at rest (its last row: four contacts), the left finger held, the right torque anywhere in
  its exported band; beyond the interval, the witness motion;
* (c) every joint held (a release instant), at both;
* (d) the programmes on HiGHS directly (:func:`qsplan.mechanics.solver.lp.solve_lp`; ``scipy.optimize.linprog``
  before issue 33): the time of every proof above, and what importing ``scipy.optimize`` costs a fresh process.

The friction set does not enter the proof: the margins at the 32 vertices of the friction box are compared with the
scene's own (equal bit for bit).

Usage, from the repository root::

    python3 benchmarks/bench_hold.py [--repeat 20]
"""

import argparse
import csv
import subprocess
import sys
import time
from itertools import product
from pathlib import Path

import numpy as np

from qsplan.hands.contacts.found import row_contact_scene
from qsplan.hands.formations.pivots import pivot_formations
from qsplan.mechanics.bands.hold import hold_matrix, hold_torque_interval, prove_hold
from qsplan.mechanics.solver.lp import solve_lp
from qsplan.planner.task.dynamics import inertial_box
from qsplan.planner.task.task import demo_task_path, load_task

ROOT = Path(__file__).resolve().parent.parent
DEMO_PLAN = ROOT / "tests" / "data" / "reference_plans" / "demo_task.csv"
TRANSITION_EDGE = 3.8994  # N m: the right finger's BSSSS band's lower edge with the 0.05 N margin (bench_reorient)
LEFT_TRANSITION_EDGE = -2.8977  # N m: the left finger's, torque-controlled (bench_reorient)
FAR = 50.0  # N m: far above the ramp


def timed(f, repeat):
    """``(f(), median seconds)``."""
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = f()
        times.append(time.perf_counter() - t0)
    return out, float(np.median(times))


def held(scene):
    n = scene.n_joints
    return scene.with_control(np.zeros(n, dtype=bool), np.zeros(n), np.full(n, np.nan))


def immobilised(scene):
    """No motion ``x != 0`` with ``A x >= 0`` (every joint held): ``sum(A x) = 1`` is infeasible."""
    A = hold_matrix(scene)
    res = solve_lp(np.zeros(A.shape[1]), A_ub=-A, b_ub=np.zeros(len(A)), A_eq=A.sum(axis=0)[None], b_eq=[1.0],
                   bounds=[(None, None)] * A.shape[1])  # fmt: skip
    return res.status == 2


def centre(nu):
    """The instantaneous centre (m) of a workpiece twist about the world origin (m/s, m/s, rad/s)."""
    return np.array([-nu[1], nu[0]]) / nu[2]


def interval_row(label, scene, box, margin, repeat):
    (lo, hi), s = timed(lambda: hold_torque_interval(scene, box, margin), repeat)
    print(f"  {label:<46} {'box' if box else '-':>4} {margin:>8.0e} N   [{lo:.6g}, {hi:.6g}]   {1e3 * s:6.2f} ms")
    return lo, hi


#: Every proof :func:`proof_row` printed: ``(label, scene, torques, box)``, for section (d).
PROOFS = []


def highs_directly(repeat):
    """Section (d): the time of every proof of (a)-(c), and what importing scipy.optimize costs a fresh process (the
    proofs ran ``scipy.optimize.linprog`` before issue 33; ``tests/mechanics/test_hold.py`` compares the verdicts)."""
    total = sum(timed(lambda: prove_hold(sc, tau, b), repeat)[1] for _, sc, tau, b in PROOFS)
    code = "import time; t = time.perf_counter(); import scipy.optimize; print(time.perf_counter() - t)"
    imports = min(float(subprocess.run([sys.executable, "-c", code], capture_output=True, text=True).stdout)
                  for _ in range(3))  # fmt: skip
    print(f"\n(d) the {len(PROOFS)} proofs above on HiGHS directly: {1e3 * total:.2f} ms together (medians); importing "
          f"scipy.optimize, which they no longer need, costs a fresh process {imports:.3f} s (best of 3)")  # fmt: skip


def proof_row(label, scene, torques, box, repeat):
    PROOFS.append((label, scene, torques, box))
    proof, s = timed(lambda: prove_hold(scene, torques, box), repeat)
    verdict = "proved" if proof.proved else "REFUSED"
    where = "" if torques is None else "[" + ", ".join(f"{t:.4g}" for t in np.ravel(torques)) + "]"
    print(f"  {label:<46} {'box' if box else '-':>4} {where:>18}  {verdict:>8}  margin {proof.margin + 0.0:10.4g} N"
          f"  {len(proof.margins):>2} vertices  {1e3 * s:6.2f} ms")  # fmt: skip
    return proof


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=20, help="timing repetitions (the median is printed)")
    args = ap.parse_args()
    task = load_task(demo_task_path())
    hand, margin = task.hand, task.force_margin.normal
    row = list(csv.DictReader(DEMO_PLAN.open()))[-1]
    command, band = float(row["tau_right"]), (float(row["tau_right_min"]), float(row["tau_right_max"]))
    (pivot, start), t_fi = timed(lambda: pivot_formations(hand)[0], args.repeat)  # the clockwise pivot: the left flush
    pose_fi, q_fi = start[:3], start[3:]
    flush = row_contact_scene(hand, pose_fi, q_fi, [False, True], np.zeros(2))  # a hold: the velocities play no part
    box = inertial_box(0.2, pose_fi[1], 0.02)
    print(f"demo task: friction box {task.mu_range} per contact (not used by the proof), force margin {margin} N, "
          f"inertial box lo={box.lo} hi={box.hi} (N, N, N m)")  # fmt: skip
    print(f"slide end (last row of {DEMO_PLAN.name}): x = {row['x_workpiece']} m, right command {command:.5f} N m, "
          f"band [{band[0]:.5f}, {band[1]:.5f}] N m")  # fmt: skip

    print(f"\n(a) flush instant of {pivot.name}: x = {pose_fi[0]:.6f} m (every pivot formation generated in "
          f"{1e3 * t_fi:.2f} ms), contacts {', '.join(flush.contact_names)}; "
          "left finger held, right torque-controlled")  # fmt: skip
    print(f"  {'proved torque interval':<46} {'box':>4} {'margin':>10}   interval (N m)")
    for b, m in product((None, box), (1e-6, margin)):
        interval_row("right torque", flush, b, m, args.repeat)
    for b in (None, box):
        proof_row("ramp: slide's end command -> transition edge", flush, [command, TRANSITION_EDGE], b, args.repeat)
        proof_row("ramp: band's lower edge -> transition edge", flush, [band[0], TRANSITION_EDGE], b, args.repeat)
        proof_row("ramp: end command -> far above", flush, [command, FAR], b, args.repeat)
    p0 = proof_row("right torque 0", flush, [0.0], None, args.repeat)
    print(f"    {p0.reason}")
    left = row_contact_scene(hand, pose_fi, q_fi, [True, False], np.zeros(2))
    print("  the left finger torque-controlled, the right one held:")
    for b in (None, box):
        interval_row("left torque", left, b, margin, args.repeat)
        proof_row("ramp: -0.01 -> left transition edge", left, [-0.01, LEFT_TRANSITION_EDGE], b, args.repeat)
    mus = np.array(list(product(task.mu_range, repeat=flush.n_contacts)))
    ref = prove_hold(flush, [command, TRANSITION_EDGE], box).margins
    ramp = [command, TRANSITION_EDGE]
    same = all(np.array_equal(prove_hold(flush.with_mu(mu), ramp, box).margins, ref) for mu in mus)
    print(f"  at the {len(mus)} friction-box vertices the ramp's margins are {'identical' if same else 'DIFFERENT'}")

    pose = [float(row[k]) for k in ("x_workpiece", "y_workpiece", "theta_workpiece")]
    q = [float(row["q_left"]), float(row["q_right"])]
    end = hand.scene(pose, q, [False, True], [0.0, np.nan], [np.nan, command])
    print(f"\n(b) slide end at rest, contacts {', '.join(end.contact_names)}; "
          "left finger held, right torque-controlled")
    print(f"  {'proved torque interval':<46} {'box':>4} {'margin':>10}   interval (N m)")
    for b, m in product((None, box), (1e-6, margin)):
        interval_row("right torque", end, b, m, args.repeat)
    for b in (None, box):
        proof_row("the exported band", end, list(band), b, args.repeat)
    _, hi = hold_torque_interval(end)
    beyond = proof_row("just above the interval", end, [hi + 0.01], None, args.repeat)
    c = centre(beyond.witness[:3])
    v = hand.workpiece + np.asarray(pose[:2])
    print(f"    {beyond.reason}")
    print(f"    instantaneous centre ({c[0]:.4f}, {c[1]:.4f}) m; vertex 0 at ({v[0, 0]:.4f}, {v[0, 1]:.4f}), "
          f"vertex 1 at ({v[1, 0]:.4f}, {v[1, 1]:.4f})")  # fmt: skip

    print("\n(c) every joint held (a release instant)")
    for name, scene in (("flush instant", flush), ("slide end", end)):
        for b in (None, box):
            p = proof_row(f"{name}, all held", held(scene), None, b, args.repeat)
            if p.capped:
                still = "no admissible motion at all: immobilised at first order" if immobilised(held(scene)) else \
                    "an internal squeeze"
                print(f"    capped at {p.margin:.6g} N: the normal forces can be as large as wanted ({still})")
            elif p.proved:
                lam = ", ".join(f"{n} {x:.4g}" for n, x in zip(p.contact_names, p.certificates[0]))
                print(f"    certificate (N, frictionless equilibrium, first vertex): {lam}")
    highs_directly(args.repeat)


if __name__ == "__main__":
    main()
