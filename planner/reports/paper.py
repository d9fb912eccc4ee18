"""Reproduce the paper's worked examples (Sections 4.1, 4.3, 5.1, 4.7) into a folder.

Writes ``fig3_eq37.png`` (four slices perpendicular to mu3), ``fig6_eq42.png``,
``fig8_rod.png``, ``table1.txt`` and ``paper_results.json`` with the modes found
and the checks of the paper's statements.  The maps come from
:func:`qsplan.mechanics.muspace.slices.mu_slice` (the polynomial path, equal to the solver) and
show each region's exact boundary; every slice also records how its cell labels
agree with those boundaries.
"""

from __future__ import annotations

import json
import time

import numpy as np

from qsplan.hands.examples.paper import eq37_scene, eq42_scene, rod_scene
from qsplan.mechanics import count_modes, scene_from_dict
from qsplan.mechanics.muspace.maps import polynomial_map
from qsplan.mechanics.muspace.slices import boundary_agreement, mu_slice

__all__ = ["reproduce_paper", "PAPER_FILES", "TABLE1"]

#: The files :func:`reproduce_paper` writes into its folder.
PAPER_FILES = ("fig3_eq37.png", "fig6_eq42.png", "fig8_rod.png", "table1.txt", "paper_results.json")

#: Fig. 8's friction rectangle: rolling (static) and sliding (kinetic) coefficients of the rod's supports,
#: those of ``examples/rod_bouncing.py``; it lies inside the R2S1 region as in the paper's figure.
ROD_FRICTION = ((0.5, 0.5), (0.4, 0.4))

#: The paper's Table 1: contact modes tested for n_c = 3..8 (rows dof = n_c - 1, n_c, n_c + 1).
TABLE1 = {
    -1: [6, 16, 45, 126, 357, 1016],
    0: [7, 19, 51, 141, 393, 1107],
    1: [6, 16, 45, 126, 357, 1016],
}


def _agreement(sl) -> dict:
    a = boundary_agreement(sl)
    return {"label_changes": a.label_changes, "explained": a.explained, "unexplained": a.unexplained,
            "spurious": a.spurious, "excluded": a.excluded}  # fmt: skip


def _summary(mm, n):
    names = [m.name for m in mm.modes]
    frac = mm.feasible.mean(axis=0)
    return {
        "modes_feasible_somewhere": [names[j] for j in np.flatnonzero(frac > 0)],
        "area_fraction": {names[j]: float(frac[j]) for j in range(len(names)) if frac[j] > 0},
        "jam_fraction": float(mm.jammed.mean()),
        "ambiguous_fraction": float(mm.ambiguous.mean()),
        "max_modes_at_once": int(mm.feasible.sum(axis=1).max()),
        "grid": n,
    }


def reproduce_paper(out_dir, n: int = 161, progress=None, force: bool = False) -> str:
    """Run the examples, write figures and results to ``out_dir``; return a text summary.

    Parameters
    ----------
    out_dir : str or Path
        Created if missing; nothing but :data:`PAPER_FILES` is touched.  Each file is written
        atomically (a temporary name, then renamed).
    force : bool
        Replace existing files of those names (checked before any work; without it an existing
        one raises :class:`~qsplan.planner.export.files.OutputExistsError`).  The folder is held
        by this run alone (:func:`~qsplan.planner.export.files.locked_out_dir`); one that cannot
        be created or written raises :class:`~qsplan.mechanics.QsplanError` before any work.
    n : int
        Grid points per mu axis.
    progress : file-like, optional
        Receives one line per step.
    """
    from qsplan.planner.export.files import check_out_dir, check_outputs, locked_out_dir

    say = (lambda s: print(s, file=progress, flush=True)) if progress else (lambda s: None)
    with locked_out_dir(check_out_dir(out_dir)) as out:  # created, writable, and written by this run alone
        check_outputs([out / name for name in PAPER_FILES], force)
        return _reproduce(out, n, say)


def _reproduce(out, n, say) -> str:
    """The work of :func:`reproduce_paper` into the checked directory ``out``."""
    from qsplan.planner.plotting.muspace import mu_slices_figure, rod_mu_figure

    from qsplan.planner.export.files import atomic_write
    from qsplan.planner.plotting.style import save_figure

    results = {}
    t0 = time.perf_counter()

    # Fig. 3: eq. (37), slices perpendicular to mu3.
    say("eq. (37): mu-space slices (Fig. 3)")
    scene = scene_from_dict(eq37_scene())
    xs = np.linspace(0.0, 2.0, n)
    slices, drawn, agreement = {}, [], []
    for mu3 in (0.0, 0.5, 1.0, 2.0):
        sl = mu_slice(scene, 0, 1, xs, xs, base_mu=[0, 0, mu3])
        slices[f"mu3={mu3}"] = {**_summary(sl.mumap, n), "boundary_agreement": _agreement(sl)}
        agreement.append(slices[f"mu3={mu3}"]["boundary_agreement"])
        drawn.append(sl)
    fig = mu_slices_figure(drawn, [f"$\\mu_3$ = {mu3:g}" for mu3 in (0.0, 0.5, 1.0, 2.0)],
                           "Fig. 3 reproduced, eq. (37): the 3S region (1) shrinks as $\\mu_3$ grows; R1S2 (2) does not change")
    save_figure(fig, out / "fig3_eq37.png", option="out_dir")
    modes37 = sorted({m for s in slices.values() for m in s["modes_feasible_somewhere"]})
    areas3s = [s["area_fraction"].get("3S", 0.0) for s in slices.values()]
    areasrs = [s["area_fraction"].get("R1S2", 0.0) for s in slices.values()]
    results["eq37"] = {
        "slices": slices,
        "modes": modes37,
        "check_only_3S_and_R1S2": modes37 == ["3S", "R1S2"],
        "check_3S_shrinks_with_mu3": all(a > b for a, b in zip(areas3s, areas3s[1:])),
        "check_R1S2_unchanged": max(areasrs) - min(areasrs) == 0.0,
        "check_jam_present": all(s["jam_fraction"] > 0 for s in slices.values()),
        "check_exact_boundaries_match_cells": all(a["unexplained"] == 0 and a["spurious"] == 0 for a in agreement),
    }

    # Fig. 6: eq. (42).
    say("eq. (42): several modes at once (Fig. 6)")
    scene = scene_from_dict(eq42_scene())
    xs = np.linspace(0.0, 1.5, n)
    slices, drawn, agreement = {}, [], []
    for mu3 in (0.1, 0.3, 0.6, 1.0):
        sl = mu_slice(scene, 0, 1, xs, xs, base_mu=[0, 0, mu3])
        slices[f"mu3={mu3}"] = {**_summary(sl.mumap, n), "boundary_agreement": _agreement(sl)}
        agreement.append(slices[f"mu3={mu3}"]["boundary_agreement"])
        drawn.append(sl)
    diag = polynomial_map(scene, np.repeat(np.linspace(0, 1.5, n)[:, None], 3, axis=1))
    fig = mu_slices_figure(drawn, [f"$\\mu_3$ = {mu3:g}" for mu3 in (0.1, 0.3, 0.6, 1.0)],
                           "Fig. 6 reproduced, eq. (42): four modes, up to three feasible at once (stripes: ambiguous)")
    save_figure(fig, out / "fig6_eq42.png", option="out_dir")
    modes42 = sorted({m for s in slices.values() for m in s["modes_feasible_somewhere"]})
    first = int(np.flatnonzero(~diag.jammed)[0])
    results["eq42"] = {
        "slices": slices,
        "modes": modes42,
        "check_exactly_four_modes": modes42 == sorted(["3S", "R1S3", "R2S1", "R3S1"]),
        "check_three_at_once": max(s["max_modes_at_once"] for s in slices.values()) == 3,
        "smallest_equal_mu_with_a_mode": float(diag.mu[first, 0]),
        "check_none_near_origin": bool(diag.jammed[: max(1, first)].all() and first > 0),
        "check_exact_boundaries_match_cells": all(a["unexplained"] == 0 and a["spurious"] == 0 for a in agreement),
    }

    # Fig. 8: the rod on two supports.
    say("rod on two supports (Figs. 7-8)")
    l1, l2 = 1.0, 0.6
    scene = scene_from_dict(rod_scene(l1=l1, l2=l2))
    xs = np.linspace(0.0, 1.0, n)
    sl = mu_slice(scene, 0, 1, xs, xs, base_mu=[0, 0])
    mm = sl.mumap
    fig = rod_mu_figure(sl, l1, l2, ROD_FRICTION[0], ROD_FRICTION[1])
    save_figure(fig, out / "fig8_rod.png", option="out_dir")
    curve_pts = np.vstack([c.points for c in sl.boundary_curves()])
    names = [m.name for m in mm.modes]
    r2s1 = mm.feasible[:, names.index("R2S1")]
    line = l1 * mm.mu[:, 1] - l2 * mm.mu[:, 0]
    off_line = np.abs(line) > 1e-9
    results["rod"] = {
        "l1": l1,
        "l2": l2,
        "modes": sorted({names[j] for j in np.flatnonzero(mm.feasible.any(axis=0))}),
        "check_R2S1_iff_l1mu2_ge_l2mu1": bool(np.array_equal(r2s1[off_line], line[off_line] > 0)),
        "check_exact_boundary_is_the_line": bool(np.max(np.abs(l1 * curve_pts[:, 1] - l2 * curve_pts[:, 0])) < 1e-12),
        "boundary_agreement": _agreement(sl),
    }

    # Table 1.
    say("Table 1: modes tested (eq. 49)")
    rows = []
    ok = True
    for off, paper in TABLE1.items():
        ours = [count_modes(nc, nc + off) for nc in range(3, 9)]
        ok &= ours == paper
        rows.append(f"3+|tau_I| = n_c{off:+d}: " + " ".join(f"{v:>6d}" for v in ours) + ("" if ours == paper else "  MISMATCH"))
    table = "n_c:              " + " ".join(f"{v:>6d}" for v in range(3, 9)) + "\n" + "\n".join(rows) + "\n"
    table += f"n_c = 20, dof = 20: {count_modes(20, 20):,}\n"
    atomic_write(out / "table1.txt", table)
    results["table1"] = {"check_matches_paper": ok, "n20_dof20": count_modes(20, 20)}
    results["seconds"] = round(time.perf_counter() - t0, 3)
    atomic_write(out / "paper_results.json", json.dumps(results, indent=2) + "\n")

    checks = {f"{ex}.{k}": v for ex, r in results.items() if isinstance(r, dict) for k, v in r.items() if k.startswith("check_")}
    lines = [f"wrote {out}/fig3_eq37.png, fig6_eq42.png, fig8_rod.png, table1.txt, paper_results.json"]
    lines += [f"  {'ok  ' if v else 'FAIL'} {k}" for k, v in checks.items()]
    lines.append(f"eq. (37) modes: {', '.join(results['eq37']['modes'])}; eq. (42) modes: {', '.join(results['eq42']['modes'])}")
    lines.append(f"done in {results['seconds']} s")
    return "\n".join(lines) + "\n"
