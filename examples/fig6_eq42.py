"""Fig. 6 of Trinkle & Zeng (1995): several contact modes feasible at once (eq. 42).

Slices of mu-space perpendicular to mu3 (mu3 = 0.1, 0.3, 0.6, 1.0) over mu1, mu2 in
[0, 1.5], with every region's boundary drawn as the exact zero set of its polynomial.
The paper's statements checked here: exactly four modes occur, 3S (1), R1S3 (3),
R2S1 (4) and R3S1 (6), three of them feasible at once over large areas, and no mode is
feasible near the origin (friction is needed for equilibrium).  Also drawn: the
configuration of Fig. 5 with the graphical test of Corollary 1 for the 3S mode.

Usage, with qsplan installed (``pip install .``) or ``PYTHONPATH=.``:
``python examples/fig6_eq42.py [OUT_DIR]`` (default ``out/``).
"""

import sys
from pathlib import Path

import numpy as np

from qsplan.hands import eq42_scene
from qsplan.mechanics import boundary_agreement, mu_slice, polynomial_map, scene_from_dict, solve
from qsplan.planner import new_axes, plot_contact_scene, save_figure
from qsplan.planner.plotting.muspace import mu_slices_figure

SEED = 42
MU3 = (0.1, 0.3, 0.6, 1.0)
N = 401


def main(out_dir="out") -> int:
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    scene = scene_from_dict(eq42_scene())
    xs = np.linspace(0.0, 1.5, N)
    rng = np.random.default_rng(SEED)
    slices, seen, most = [], set(), 0
    for mu3 in MU3:
        sl = mu_slice(scene, 0, 1, xs, xs, base_mu=[0.0, 0.0, mu3])
        slices.append(sl)
        mm = sl.mumap
        seen |= {sl.modes[j].name for j in np.flatnonzero(mm.feasible.any(axis=0))}
        most = max(most, int(mm.feasible.sum(axis=1).max()))
        agree = boundary_agreement(sl)
        cells, cellsets = rng.integers(0, xs.size, size=(100, 2)), sl.cells()
        bad = sum(
            sorted(solve(scene.with_mu([xs[i], xs[j], mu3]), residuals=False).feasible_modes) != cellsets[j][i]
            for i, j in cells
        )
        print(f"mu3 = {mu3:<4g} ambiguous {mm.ambiguous.mean():.1%}, jam {mm.jammed.mean():.1%}; boundary: "
              f"{agree.explained}/{agree.label_changes} label changes on exact curves, {agree.spurious} spurious, "
              f"{agree.excluded} excluded; solver spot-check mismatches {bad}/100")
    fig = mu_slices_figure(slices, [f"$\\mu_3$ = {mu3:g}" for mu3 in MU3],
                           "Fig. 6 reproduced, eq. (42): four modes, up to three feasible at once (stripes: ambiguous)")
    save_figure(fig, out / "fig6_eq42.png")

    diagonal = np.repeat(np.linspace(0.0, 1.5, 1501)[:, None], 3, axis=1)
    first = int(np.flatnonzero(~polynomial_map(scene, diagonal).jammed)[0])
    print("modes seen:", sorted(seen), "(paper: 3S, R1S3, R2S1, R3S1)")
    print("most modes feasible at once:", most, "(paper: 3)")
    print(f"on mu1 = mu2 = mu3 no mode is feasible below {diagonal[first, 0]:.3f} (paper: jam near the origin)")

    fig, axes = new_axes(1, 1, size=(6.5, 7.5))
    plot_contact_scene(scene, mode="SSS", ax=axes[0, 0])
    save_figure(fig, out / "fig5_eq42_scene.png")
    print(f"wrote {out / 'fig6_eq42.png'} and {out / 'fig5_eq42_scene.png'}")
    return 0


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:2]))
