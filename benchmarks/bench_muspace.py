"""Benchmark: a 400 x 400 mu-space map of eq. (42) by each method, and its exact boundaries.

Prints one table row per method (best of ``REPEAT`` wall-clock times) with the number of
cells whose mode set differs from the solver's, and the agreement of the exact region
boundaries (zero sets of the boundary polynomials) with the cell labels.  The slice is
mu1 x mu2 in [0, 1.5]^2 at mu3 = 0.5; ``solve`` per cell is timed on a seeded sample and
scaled to the whole map.

Usage, with qsplan installed (``pip install .``) or ``PYTHONPATH=.``:
``python benchmarks/bench_muspace.py [N]`` (default 400).
"""

import sys
import time

import numpy as np

from qsplan.hands.examples.paper import eq42_scene
from qsplan.mechanics import scene_from_dict, solve
from qsplan.mechanics.muspace.maps import feasibility_map, grid_points, polynomial_map
from qsplan.mechanics.muspace.slices import boundary_agreement, mu_slice

SEED = 42
REPEAT = 3
SAMPLE = 2000


def best_of(f, repeat=REPEAT):
    best, out = np.inf, None
    for _ in range(repeat):
        t = time.perf_counter()
        out = f()
        best = min(best, time.perf_counter() - t)
    return best, out


def main(n: int = 400) -> int:
    scene = scene_from_dict(eq42_scene(0.5))
    xs = np.linspace(0.0, 1.5, n)
    pts = grid_points(scene.mu, 0, 1, xs, xs)
    t_fm, ref = best_of(lambda: feasibility_map(scene, pts))
    t_pm, pm = best_of(lambda: polynomial_map(scene, pts))
    t_sl, sl = best_of(lambda: mu_slice(scene, 0, 1, xs, xs))
    t_rg, exact = best_of(lambda: np.column_stack([r.contains(pts) for r in sl.regions]))
    near = np.column_stack([r.near_boundary(pts) for r in sl.regions]) | ref.boundary | ref.degenerate
    rng = np.random.default_rng(SEED)
    sample = rng.choice(pts.shape[0], size=SAMPLE, replace=False)
    t = time.perf_counter()
    solved = [solve(scene.with_mu(pts[i]), residuals=False).feasible_modes for i in sample]
    t_solve = (time.perf_counter() - t) / SAMPLE * pts.shape[0]
    letters = [m.letters for m in ref.modes]
    solve_bad = sum(s != [letters[j] for j in np.flatnonzero(ref.feasible[i])] for s, i in zip(solved, sample))

    def differ(f):
        return int(np.any(f != ref.feasible, axis=1).sum())

    rows = [
        ("solve() per cell (sampled, scaled)", t_solve, f"{solve_bad} of {SAMPLE} sampled"),
        ("feasibility_map (LU per mode, cell)", t_fm, "reference"),
        ("polynomial_map (multilinear c_A)", t_pm, f"{differ(pm.feasible)}"),
        ("mu_slice (polynomial + regions)", t_sl, f"{differ(sl.mumap.feasible)}"),
        ("MuRegion.contains (exact, all modes)", t_rg, f"{int(np.any((exact != ref.feasible) & ~near, axis=1).sum())} "
                                                       f"({int(near.any(axis=1).sum())} cells near a boundary excluded)"),
    ]  # fmt: skip
    print(f"eq. (42), mu1 x mu2 in [0, 1.5]^2 at mu3 = 0.5: {n} x {n} = {pts.shape[0]} cells, {len(ref.modes)} modes")
    print(f"{'method':<40} {'time (s)':>9}  cells differing from feasibility_map")
    for name, sec, note in rows:
        print(f"{name:<40} {sec:9.3f}  {note}")

    t_ag, ag = best_of(lambda: boundary_agreement(sl))
    t_cv, curves = best_of(lambda: sl.boundary_curves())
    worst = 0.0
    for c in curves:
        reg = sl.regions[sl.modes.index(c.mode)]
        polys = {("det Q_AI = 0"): reg.denominator}
        polys.update({f"{lab.split('>=')[0].strip()} = 0": p for lab, p in zip(reg.labels, reg.numerators)})
        mu = np.tile(sl.base_mu, (len(c.points), 1))
        mu[:, 0], mu[:, 1] = c.points[:, 0], c.points[:, 1]
        p = polys[c.label]
        worst = max(worst, float(np.max(np.abs(p(mu)) / np.maximum(p.abs_terms(mu), 1e-300))))
    print()
    print(f"exact boundaries: {len(curves)} curve pieces in {t_cv:.3f} s; largest |p| / sum|terms| on them {worst:.1e}")
    print(f"boundary agreement ({t_ag:.3f} s): {ag.explained} of {ag.label_changes} label changes between adjacent "
          f"cells are crossed by an exact boundary, {ag.unexplained} not, {ag.spurious} crossings without a change, "
          f"{ag.excluded} pairs excluded (a cell centre within 1e-9 of a boundary)")
    return 0


if __name__ == "__main__":
    sys.exit(main(*(int(a) for a in sys.argv[1:2])))
