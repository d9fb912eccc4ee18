"""Figs. 10-13 of Trinkle & Zeng (1995), Section 5.2, for our two-finger hand: torque bands along a 4S segment.

The hand of Fig. 9 (a fixed palm, two single-link fingers; the paper does not
give its dimensions, ours are in :func:`qsplan.hands.paper_hand.two_finger.default_hand`) holds an
irregular quadrilateral on the palm.  Segment 1 of the paper's plan translates
it left until the left finger meets its longest edge, in mode 4S: the left
finger is velocity-controlled, the right one torque-controlled.  Along it we
compute the right finger's torque band without friction (Fig. 10), at mu = 0.2
(Fig. 11), the competing R2S mode's band at mu = 0.2 (Fig. 12), and the band that
guarantees 4S and precludes every competitor for friction in [0, 0.2] (Fig. 13):
exactly, for independent coefficients (vertex theory) and for one shared
coefficient (polynomial roots), beside the paper's sampled method.  The
schedule a controller needs is exported as CSV and JSON, with the plans' command
rule (one margin along the whole segment, at most two torque resolutions of
0.02 N m), with or without a shared coefficient.

A seeded spot check draws random instants, friction vectors in the box and
torques in the guaranteed band, and confirms with the full solver that 4S is the
only feasible mode there.

Usage::

    python examples/fig10_13_bands.py [OUT_DIR]     # default out/

Writes ``fig10_frictionless.png``, ``fig11_mu_high.png``, ``fig12_competitors.png``,
``fig13_guaranteed.png``, ``fig13_guaranteed_shared.png``, ``hand_strip.png``,
``segment1.csv`` and ``segment1.json`` (overwriting them).
"""

import sys
from pathlib import Path

import numpy as np

from qsplan.hands import default_hand, first_segment, sample_segment
from qsplan.mechanics import robust_band, solve
from qsplan.planner import (
    export_schedule,
    narrowest,
    new_axes,
    plot_guaranteed,
    save_figure,
    segment_band_figures,
    segment_bands,
)
from qsplan.planner.torque.command import with_segment_command

SEED = 1995
MU_RANGE = (0.0, 0.2)
RESOLUTION = 0.02  # N m: the controller's torque resolution (the bundled tasks')


def spot_check(bands, rng, n=40):
    """Solve random instants at random friction in the box with a torque inside the guaranteed band."""
    S, band = bands.samples, bands.guaranteed.band
    ok = 0
    for k in rng.choice(np.flatnonzero(band.feasible), size=n):
        lo, hi = band.lower[k], band.upper[k]
        tau = rng.uniform(lo, hi if np.isfinite(hi) else lo + 1.0)
        scene = S.scenes[k].with_mu(rng.uniform(*MU_RANGE, size=S.scenes[k].n_contacts))
        tau_in = np.where(scene.effort_controlled, tau, np.nan)
        ok += solve(scene.with_inputs(joint_effort=tau_in)).feasible_modes == [band.mode]
    return ok


def main(out_dir="out"):
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(SEED)
    hand = default_hand()
    samples = sample_segment(first_segment(hand, duration=10.0), 200)
    box = with_segment_command(segment_bands(samples, MU_RANGE, shared=False), RESOLUTION)
    shared = with_segment_command(segment_bands(samples, MU_RANGE, shared=True), RESOLUTION)

    for name, fig in segment_band_figures(box).items():
        save_figure(fig, out / f"{name}.png")
    fig, ax = new_axes(1, 1, size=(8.0, 5.4))
    plot_guaranteed(shared, ax[0, 0])
    ax[0, 0].set_title("Fig. 13: " + ax[0, 0].get_title(), fontsize=9.5)
    save_figure(fig, out / "fig13_guaranteed_shared.png")
    export_schedule(box, out, stem="segment1", force=True, resolution=RESOLUTION)

    t = samples.t
    print(f"hand: workpiece {hand.workpiece_mass} kg, fingers {hand.finger_length} x {hand.finger_width} m at "
          f"x = +-{hand.finger_base} m; segment: {-(samples.pose[-1, 0] - samples.pose[0, 0]) * 1000:.1f} mm left "
          f"in {t[-1]:g} s")  # fmt: skip
    print("Fig. 10 (mu = 0): upper bound infinite for t in", box.frictionless.infinite_upper_spans(),
          f"then finite, {box.frictionless.upper[-1]:.4g} N m at the end; lower bound 0 throughout:",
          bool(np.all(box.frictionless.lower == 0)))  # fmt: skip
    print("Fig. 11 (mu = 0.2): lower bound", f"{box.at_high_mu.lower[0]:.4g} -> {box.at_high_mu.lower[-1]:.4g} N m;",
          "upper infinite for t in", box.at_high_mu.infinite_upper_spans())  # fmt: skip
    for c, s in box.competitors_at_high_mu.items():
        print(f"Fig. 12: {c} feasible at mu = 0.2 for t in {s.feasible_spans()}")
    for label, b in (("independent mu (box)", box), ("one shared mu", shared)):
        k, w = narrowest(b.guaranteed.band)
        g = b.guaranteed.band
        print(f"Fig. 13, {label}: exact at {int(g.exact.sum())}/{len(t)} samples; narrowest [{g.lower[k]:.4g}, "
              f"{g.upper[k]:.4g}] N m, width {w:.4g} N m at t = {t[k]:.3g} s")  # fmt: skip
    k, w = narrowest(box.sampled)
    print(f"paper's method (21 shared values): narrowest width {w:.4g} N m at t = {t[k]:.3g} s")
    print(f"spot check: 4S the only feasible mode in {spot_check(box, rng)} of 40 random draws in the box")
    one = robust_band(samples.scenes[k], box.guaranteed.band.mode, MU_RANGE, competitors=box.guaranteed.competitors)
    print(f"one scene alone (t = {t[k]:.3g} s): robust_band [{one.lower:.4g}, {one.upper:.4g}] N m, "
          f"competitors precluded: {', '.join(one.competitors) or 'none'}")  # fmt: skip
    print(f"wrote {out}/")


if __name__ == "__main__":
    main(*sys.argv[1:2])
