"""The rod of Figs. 7-8 bouncing between its supports (Trinkle & Zeng 1995, Section 5.1).

A thin rod rests on two point supports that move toward each other.  Friction
takes its static value while a support sticks and its kinetic value while it
slides, so the partition line ``l1 mu2 = l2 mu1`` chases the active corner of the
friction rectangle and the supports alternate: the simulator switches mode at
each corner, and the switch instants accumulate where the supports meet under
the centre of mass (it stops there, reporting Zeno).  With equal static and
kinetic coefficients the farther support slides until ``l1 mu2 = l2 mu1`` and the
run stops: only the indeterminate 2S mode could continue.

Usage::

    python examples/rod_bouncing.py [OUT_DIR]     # default out/

Writes ``rod_bouncing.png`` and ``rod_equal_friction.png`` and prints the switch
table against the closed form (:func:`qsplan.hands.examples.rod.rod_closed_form`), including three
random starts drawn with a fixed seed.
"""

import sys
from pathlib import Path

import numpy as np

from qsplan.hands import rod_closed_form, simulate_rod
from qsplan.planner import rod_motion_figure, save_figure

SEED = 20250105


def compare(params, label):
    """Simulate and print the largest difference from the closed form."""
    motion = simulate_rod(**params)
    cf = rod_closed_form(**params)
    sim = np.array([[s.t_start, s.t_end] for s in motion.segments])
    ref = np.array([[c.t_start, c.t_end] for c in cf.segments])
    n = min(len(sim), len(ref))
    err = float(np.max(np.abs(sim[:n] - ref[:n]))) if n else 0.0
    stop = motion.stopped.kind if motion.stopped else "duration reached"
    print(f"{label}: {len(motion.segments)} segments ({len(cf.segments)} closed form), max |dt| = {err:.2e} s, {stop}")
    return motion, cf


def main(out_dir="out"):
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(SEED)

    bouncing = dict(l1=1.0, l2=0.6, mu_static=(0.5, 0.5), mu_kinetic=(0.4, 0.4), speed=0.1, duration=20.0)
    motion, cf = compare(bouncing, "bouncing (static 0.5, kinetic 0.4)")
    print("  first switches (s):", np.round(motion.switch_times[:6], 6).tolist())
    print("  closed form       :", np.round(cf.switch_times[:6], 6).tolist())
    print(f"  {motion.stopped.message}")
    save_figure(rod_motion_figure(motion, closed_form=cf), out / "rod_bouncing.png")

    equal = dict(l1=1.0, l2=0.6, mu_static=(0.3, 0.3), mu_kinetic=(0.3, 0.3), speed=0.1, duration=20.0)
    motion, cf = compare(equal, "equal static and kinetic (0.3)")
    print(f"  {motion.stopped.message}")
    save_figure(rod_motion_figure(motion, closed_form=cf), out / "rod_equal_friction.png")

    for k in range(3):
        l1, l2 = rng.uniform(0.2, 1.0, size=2)
        mu_s = rng.uniform(0.3, 0.8, size=2)
        mu_k = mu_s * rng.uniform(0.5, 0.95, size=2)
        params = dict(l1=l1, l2=l2, mu_static=mu_s, mu_kinetic=mu_k, speed=0.1, duration=3.0)
        compare(params, f"random start {k + 1} (l1 = {l1:.3f}, l2 = {l2:.3f})")
    print(f"wrote {out / 'rod_bouncing.png'}, {out / 'rod_equal_friction.png'}")


if __name__ == "__main__":
    main(*sys.argv[1:2])
