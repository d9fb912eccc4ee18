"""``qsplan muspace``: which contact modes are feasible over a 2-D slice of mu-space (Section 4).

::

    qsplan muspace SCENE --x muI --y muJ [--fix muK=V ...] --range LO HI --n N [--json] [--out FILE.png [--force]]
                   [--workers N] [--scheduler ADDRESS]

Both axes sample ``np.linspace(LO, HI, N)``; contacts are numbered from 1 as
the paper's ``mu_i``; coefficients not named keep the scene's values.  With
``--json`` stdout is one object::

    {"x": [N], "y": [N], "modes": [names in legend order], "cells": [[[letters...]...]...],
     "letters": [letters in legend order], "axes": ["muI", "muJ"], "base_mu": [n_c]}

where ``cells[j][i]`` lists, sorted, the letters (``"RBS"``) of the modes feasible at
``(x[i], y[j])`` and the legend is every mode tested, in enumeration order (3S=1,
R1S2=2, ... for three contacts).  ``--out`` writes the map with the exact region
boundaries; an existing file is replaced only with ``--force``, and never the scene itself or
through a symbolic link (checked before any work).  Bad arguments raise a :class:`qsplan.mechanics.QsplanError` naming the option.
"""

from __future__ import annotations

import json
import re

from qsplan.planner.cli.options import add_parallel_options, parallel_options

__all__ = ["add_parser", "run", "MAX_N"]

#: Largest grid (per axis) the command accepts: 4096^2 points stay within a few seconds and ~1 GB.
MAX_N = 4096

_OUT_FORMATS = (".png", ".svg", ".pdf")


def add_parser(subparsers):
    p = subparsers.add_parser("muspace", help="feasible contact modes over a 2-D slice of mu-space (Figs. 3, 6, 8)")
    p.add_argument("scene", help="scene file (.json or .toml)")
    p.add_argument("--x", required=True, metavar="muI", help="coefficient on the horizontal axis, e.g. mu1")
    p.add_argument("--y", required=True, metavar="muJ", help="coefficient on the vertical axis, e.g. mu2")
    p.add_argument("--fix", action="append", default=[], metavar="muK=V", help="set another coefficient (repeatable)")
    p.add_argument("--range", nargs=2, type=float, required=True, metavar=("LO", "HI"), help="axis range, both axes")
    p.add_argument("--n", type=int, required=True, metavar="N", help=f"samples per axis (2..{MAX_N})")
    p.add_argument("--json", action="store_true", help="machine-readable cells on stdout")
    p.add_argument("--out", metavar="FILE.png", help="write the map (png, svg or pdf)")
    p.add_argument("--force", action="store_true", help="replace an existing --out file (never the scene)")
    add_parallel_options(p)
    return p


def _coefficient(text: str, n_c: int, option: str) -> int:
    """``"mu2"`` -> 1 (0-based), checked against the scene's contacts."""
    from qsplan.mechanics import QsplanError

    m = re.fullmatch(r"\s*mu_?(\d+)\s*", str(text), flags=re.IGNORECASE)
    if not m:
        raise QsplanError(f"{option}: expected a friction coefficient mu1..mu{n_c}; got {text!r}")
    k = int(m.group(1))
    if not 1 <= k <= n_c:
        raise QsplanError(f"{option}: the scene has {n_c} contacts, so mu1..mu{n_c}; got {text!r}")
    return k - 1


def _parse(args, scene):
    import numpy as np

    from qsplan.mechanics import QsplanError
    from qsplan.mechanics.model.friction import MAX_FRICTION

    n_c = scene.n_contacts
    if n_c < 2:
        raise QsplanError(f"--y: a slice needs two coefficients but the scene has {n_c} contact")
    x = _coefficient(args.x, n_c, "--x")
    y = _coefficient(args.y, n_c, "--y")
    if x == y:
        raise QsplanError(f"--y: expected a coefficient other than --x ({args.x}); got {args.y!r}")
    base = np.array(scene.mu, dtype=float)
    seen = set()
    for item in args.fix:
        name, eq, value = str(item).partition("=")
        if not eq:
            raise QsplanError(f"--fix: expected muK=V, e.g. mu3=0.5; got {item!r}")
        k = _coefficient(name, n_c, "--fix")
        if k in (x, y):
            raise QsplanError(f"--fix: mu{k + 1} is an axis of the slice; got {item!r}")
        if k in seen:
            raise QsplanError(f"--fix: mu{k + 1} given twice")
        seen.add(k)
        try:
            v = float(value)
        except ValueError:
            raise QsplanError(f"--fix: expected a number after '='; got {item!r}") from None
        if not np.isfinite(v) or v < 0 or v > MAX_FRICTION:
            raise QsplanError(f"--fix: expected a finite nonnegative friction coefficient, at most {MAX_FRICTION:g} "
                              f"(MAX_FRICTION); got {item!r}")  # fmt: skip
        base[k] = v
    lo, hi = args.range
    if not (np.isfinite(lo) and np.isfinite(hi)):
        raise QsplanError(f"--range: expected finite numbers; got {lo} {hi}")
    if lo < 0:
        raise QsplanError(f"--range: expected LO >= 0 (friction coefficients are nonnegative); got LO = {lo}")
    if lo > hi:
        raise QsplanError(f"--range: expected LO <= HI; got {lo} > {hi}")
    if hi > MAX_FRICTION:
        raise QsplanError(f"--range: expected HI <= {MAX_FRICTION:g} (friction coefficients; MAX_FRICTION); got {hi:g}")
    if not 2 <= args.n <= MAX_N:
        raise QsplanError(f"--n: expected 2..{MAX_N} samples per axis; got {args.n}")
    if args.out is not None and not str(args.out).lower().endswith(_OUT_FORMATS):
        raise QsplanError(f"--out: expected a file name ending in {', '.join(_OUT_FORMATS)}; got {args.out!r}")
    if args.out is not None:
        from qsplan.planner.export.files import check_outputs

        check_outputs([args.out], args.force, inputs=(args.scene,))
    return x, y, base, np.linspace(lo, hi, args.n)


def _write_figure(sl, path, source, force):
    from pathlib import Path


    from qsplan.planner.plotting.muspace import plot_mu_map
    from qsplan.planner.plotting.style import new_axes

    fixed = ", ".join(f"$\\mu_{k + 1}$ = {sl.base_mu[k]:g}" for k in range(sl.base_mu.size) if k not in (sl.x, sl.y))
    fig, axes = new_axes(1, 1, size=(6.5, 5.5))
    plot_mu_map(sl, ax=axes[0, 0], title=f"{Path(source).name}" + (f": {fixed}" if fixed else ""))
    from qsplan.planner.plotting.style import save_figure

    save_figure(fig, path, option="--out", force=force, inputs=(source,))


def run(args, out) -> int:
    from qsplan.mechanics import load_scene
    from qsplan.mechanics.muspace.slices import mu_slice

    scene = load_scene(args.scene)
    x, y, base, xs = _parse(args, scene)
    sl = mu_slice(scene, x, y, xs, xs, base_mu=base, **parallel_options(args))
    if args.out is not None:
        _write_figure(sl, args.out, args.scene, args.force)
    modes = sl.modes
    if args.json:
        doc = {
            "x": xs.tolist(),
            "y": xs.tolist(),
            "modes": [m.name for m in modes],
            "cells": sl.cells(),
            "letters": [m.letters for m in modes],
            "axes": [f"mu{x + 1}", f"mu{y + 1}"],
            "base_mu": [float(v) for v in base],
        }
        json.dump(doc, out)
        out.write("\n")
        return 0
    mm = sl.mumap
    others = ", ".join(f"mu{k + 1} = {base[k]:g}" for k in range(base.size) if k not in (x, y)) or "none"
    out.write(f"scene {args.scene}: {scene.n_contacts} contacts, {len(modes)} modes tested (eq. 49)\n")
    out.write(f"slice mu{x + 1} (x) by mu{y + 1} (y) on [{xs[0]:g}, {xs[-1]:g}], {xs.size} x {xs.size} cells; {others}\n\n")
    out.write("  #  name      letters  kinematics            area\n")
    frac = mm.feasible.mean(axis=0)
    for j, m in enumerate(modes):
        out.write(f"{j + 1:>3}  {m.name:<9} {m.letters:<8} {mm.kinematic_status[j]:<21} {frac[j]:6.1%}\n")
    out.write(f"\njammed {mm.jammed.mean():.1%}, ambiguous {mm.ambiguous.mean():.1%}, "
              f"at most {int(mm.feasible.sum(axis=1).max())} modes at once\n")  # fmt: skip
    if args.out is not None:
        out.write(f"wrote {args.out}\n")
    return 0
