"""Fig. 8 of Trinkle & Zeng (1995): the rod on two supports moving together (Section 5.1).

A thin rod rests on two point supports at distances l1 and l2 from its centre of mass.
Only R1S2 and R2S1 satisfy the utility conditions; inequalities (40)-(41) put R2S1 above
or on the line l1 mu2 = l2 mu1 and R1S2 below or on it.  The map over mu1, mu2 in [0, 1]
is drawn with the exact region boundaries, which here are that one line through the
origin, and with the paper's friction rectangle (sliding to rolling coefficients, those
of ``rod_bouncing.py``), which lies inside the R2S1 region as in the paper's figure; the
script checks that every boundary point satisfies l1 mu2 = l2 mu1.

Usage, with qsplan installed (``pip install .``) or ``PYTHONPATH=.``:
``python examples/fig8_rod.py [OUT_DIR]`` (default ``out/``).
"""

import sys
from pathlib import Path

import numpy as np

from qsplan.hands import rod_scene
from qsplan.mechanics import boundary_agreement, mu_slice, scene_from_dict, solve
from qsplan.planner import save_figure
from qsplan.planner.plotting.muspace import rod_mu_figure

SEED = 8
L1, L2 = 1.0, 0.6
MU_STATIC, MU_KINETIC = (0.5, 0.5), (0.4, 0.4)  # the friction rectangle (rolling, sliding values), as in rod_bouncing.py
N = 401


def main(out_dir="out") -> int:
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    scene = scene_from_dict(rod_scene(l1=L1, l2=L2))
    xs = np.linspace(0.0, 1.0, N)
    sl = mu_slice(scene, 0, 1, xs, xs)
    save_figure(rod_mu_figure(sl, L1, L2, MU_STATIC, MU_KINETIC), out / "fig8_rod.png")

    curves = sl.boundary_curves()
    pts = np.vstack([c.points for c in curves])
    off_line = float(np.max(np.abs(L1 * pts[:, 1] - L2 * pts[:, 0])))
    agree = boundary_agreement(sl)
    names = sorted({sl.modes[j].name for j in np.flatnonzero(sl.mumap.feasible.any(axis=0))})
    rng = np.random.default_rng(SEED)
    mu = rng.uniform(0.0, 1.0, size=(200, 2))
    above = L1 * mu[:, 1] > L2 * mu[:, 0]
    found = [solve(scene.with_mu(m), residuals=False).feasible_modes for m in mu]
    ok = all(f == (["SR"] if a else ["RS"]) for f, a in zip(found, above))
    print("modes seen:", names, "(paper: R1S2, R2S1)")
    print(f"{len(curves)} boundary curve pieces ({', '.join(sorted({c.label for c in curves}))}); "
          f"largest |l1 mu2 - l2 mu1| on them: {off_line:.2e}")
    print(f"boundary: {agree.explained}/{agree.label_changes} label changes on exact curves, {agree.spurious} spurious, "
          f"{agree.excluded} pairs with a cell centre on the line excluded")
    print("200 random points: R2S1 exactly above the line, R1S2 exactly below:", ok)
    print(f"wrote {out / 'fig8_rod.png'}")
    return 0 if ok and off_line < 1e-12 else 1


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:2]))
