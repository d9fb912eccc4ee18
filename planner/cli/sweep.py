"""``qsplan sweep``: torque bands along a two-finger hand segment (Section 5.2, Figs. 9-13), plots and export.

::

    qsplan sweep [--segment 1] [--mu-range LO HI] [--shared-mu] [--samples N] [--duration T]
                 [--effort-joint left|right] [--paper-samples K] [--safety-margin M] [--max-margin M]
                 [--display-limit L] [--out DIR] [--force] [--no-plots] [--json]
                 [--workers N] [--scheduler ADDRESS]

Builds the default two-finger hand (:func:`hands.two_finger.default_hand`) and the
segment (1: translate the workpiece left until the left finger meets its longest
edge), samples it at N instants over T seconds and computes, for the
effort-controlled finger: the desired mode's band without friction (Fig. 10) and
at mu = HI (Fig. 11), the competing modes' bands at mu = HI (Fig. 12) and the
band guaranteeing the mode and precluding every competitor for friction in
[LO, HI] (Fig. 13; independent per contact, or with ``--shared-mu`` one shared
coefficient), exactly, beside the paper's sampled method with K values.

Into DIR (default ``out/sweep``) it writes ``segment1.csv`` and ``segment1.json``
(the torque schedule: see :mod:`planner.export`) and, unless ``--no-plots``,
``fig10_frictionless.png``, ``fig11_mu_high.png``, ``fig12_competitors.png``,
``fig13_guaranteed.png`` and ``hand_strip.png``.  Existing files are not
overwritten without ``--force`` (checked before anything is written).

stdout: a summary; with ``--json`` one object::

    {"segment", "duration", "samples", "mode", "effort_joint", "velocity_joint", "mu_range", "shared_mu",
     "competitors": {LETTERS: {"name", "feasible_at_mu_high": [[t0, t1], ...]}},
     "frictionless_upper_infinite": [[t0, t1], ...], "mu_high_upper_infinite": [[t0, t1], ...],
     "guaranteed": {"exact", "points_without_band", "split_points", "narrowest": {"t", "width", "lower", "upper"}},
     "paper_method": {"samples", "narrowest": {...}, "wider_than_exact_points"},
     "safety_margin", "max_margin", "command_max", "files": [...]}

Efforts in N m, times in s.  Bad arguments raise a :class:`mechanics.QsplanError` naming the option (exit 2).
"""

from __future__ import annotations

import json
import math

__all__ = ["add_parser", "run"]

_PLOTS = ("fig10_frictionless", "fig11_mu_high", "fig12_competitors", "fig13_guaranteed", "hand_strip")


def add_parser(subparsers):
    p = subparsers.add_parser("sweep", help="torque bands along a two-finger hand segment (Figs. 10-13), plots and export")
    p.add_argument("--segment", type=int, default=1, choices=(1,), help="segment of the paper's plan (1: translate left)")
    p.add_argument("--mu-range", type=float, nargs=2, default=(0.0, 0.2), metavar=("LO", "HI"),
                   help="friction uncertainty (default 0 0.2, the paper's)")  # fmt: skip
    p.add_argument("--shared-mu", action="store_true", help="one coefficient shared by all contacts (default: independent)")
    p.add_argument("--samples", type=int, default=200, metavar="N", help="instants along the segment (default 200)")
    p.add_argument("--duration", type=float, default=10.0, metavar="T", help="segment duration (s, default 10)")
    p.add_argument("--effort-joint", choices=("left", "right"), default="right",
                   help="torque-controlled finger (default right; the other is velocity-controlled)")  # fmt: skip
    p.add_argument("--paper-samples", type=int, default=21, metavar="K",
                   help="friction values of the paper's sampled method (default 21: 0, 0.01, ..., 0.2)")  # fmt: skip
    p.add_argument("--safety-margin", type=float, metavar="M",
                   help="N m kept from a finite edge where the band is unbounded (default: half the narrowest band)")  # fmt: skip
    p.add_argument("--max-margin", type=float, metavar="M",
                   help="N m cap on the command's margin: a wider band gets lower + M (default: midpoints)")  # fmt: skip
    p.add_argument("--display-limit", type=float, metavar="L", help="N m at which plotted bands are truncated (default: per figure)")
    p.add_argument("--out", default="out/sweep", metavar="DIR", help="output directory (default out/sweep)")
    p.add_argument("--force", action="store_true", help="overwrite existing files in DIR")
    p.add_argument("--no-plots", action="store_true", help="write the schedule only")
    p.add_argument("--json", action="store_true", help="machine-readable summary on stdout")
    from qsplan.planner.cli.main import add_parallel_options

    add_parallel_options(p)
    return p


def _check(args):
    from qsplan.mechanics import QsplanError

    from qsplan.planner.cli.main import parallel_options

    parallel_options(args)
    lo, hi = args.mu_range
    if not (math.isfinite(lo) and math.isfinite(hi)) or lo < 0 or lo > hi:
        raise QsplanError(f"--mu-range: expected 0 <= LO <= HI (finite); got {lo} {hi}")
    if args.samples < 2:
        raise QsplanError(f"--samples: expected at least 2 instants; got {args.samples}")
    if not (math.isfinite(args.duration) and args.duration > 0):
        raise QsplanError(f"--duration: expected a positive finite time (s); got {args.duration}")
    if args.paper_samples < 1:
        raise QsplanError(f"--paper-samples: expected a positive integer; got {args.paper_samples}")
    for option, v in (("--safety-margin", args.safety_margin), ("--max-margin", args.max_margin),
                      ("--display-limit", args.display_limit)):  # fmt: skip
        if v is not None and not (math.isfinite(v) and v > 0):
            raise QsplanError(f"{option}: expected a positive finite torque (N m); got {v}")


def _planned_files(args):
    from pathlib import Path

    out = Path(args.out)
    files = [out / "segment1.csv", out / "segment1.json"]
    if not args.no_plots:
        files += [out / f"{name}.png" for name in _PLOTS]
    return files


def _runs(runs):
    return [[round(a, 9), round(b, 9)] for a, b in runs]


def _narrow(sweep):
    from qsplan.planner.torque.sweep import narrowest

    k, w = narrowest(sweep)
    if k is None:
        return None
    return {"t": float(sweep.t[k]), "width": w, "lower": float(sweep.lower[k]), "upper": float(sweep.upper[k])}


def _document(args, sb, files):
    import numpy as np

    from qsplan.mechanics.modes.contact_mode import ContactMode

    from qsplan.planner.torque.sweep import TOUCH_RTOL

    S = sb.samples
    seg = S.segment
    g = sb.guaranteed
    band = g.band
    s = sb.sampled
    both = band.feasible & s.feasible
    with np.errstate(invalid="ignore"):
        tol = TOUCH_RTOL * np.maximum(1.0, np.abs(band.lower))
        wider = both & ((s.lower < band.lower - tol) | (s.upper > band.upper + tol))
    comps = {}
    for c, sw in sb.competitors_at_high_mu.items():
        comps[c] = {"name": f"{ContactMode(c).kind} ({ContactMode(c).name})", "feasible_at_mu_high": _runs(sw.feasible_spans())}
    return {
        "segment": seg.name, "duration": seg.duration, "samples": len(S), "mode": band.mode,
        "effort_joint": seg.effort_joint, "velocity_joint": S.scenes[0].joint_names[seg.velocity_index],
        "mu_range": list(g.mu_range), "shared_mu": g.shared,
        "competitors": comps,
        "frictionless_upper_infinite": _runs(sb.frictionless.infinite_upper_spans()),
        "mu_high_upper_infinite": _runs(sb.at_high_mu.infinite_upper_spans()),
        "guaranteed": {"exact": bool(band.exact[band.feasible].all()), "points_without_band": int((~band.feasible).sum()),
                       "split_points": int(g.split.sum()), "narrowest": _narrow(band)},
        "paper_method": {"samples": args.paper_samples, "narrowest": _narrow(s), "wider_than_exact_points": int(wider.sum())},
        "safety_margin": sb.safety_margin, "max_margin": sb.max_margin,
        "command_max": float(np.nanmax(sb.command)) if np.isfinite(sb.command).any() else None,
        "files": [str(f) for f in files],
    }  # fmt: skip


def run(args, out) -> int:
    from qsplan.hands.segments import first_segment, sample_segment
    from qsplan.hands.two_finger import default_hand
    from qsplan.mechanics import QsplanError

    from qsplan.planner.torque.sweep import segment_bands

    _check(args)
    planned = _planned_files(args)
    clash = [str(p) for p in planned if p.exists()]
    if clash and not args.force:
        raise QsplanError(f"--out: {clash[0]!r} exists ({len(clash)} of the output files do); "
                          "pass --force to overwrite or choose another --out")  # fmt: skip
    seg = first_segment(default_hand(), duration=args.duration, effort_joint=args.effort_joint)
    samples = sample_segment(seg, args.samples)
    from qsplan.planner.cli.main import parallel_options

    sb = segment_bands(samples, tuple(args.mu_range), args.shared_mu, args.paper_samples, args.safety_margin,
                       args.max_margin, **parallel_options(args))  # fmt: skip
    from qsplan.planner.export.schedule import export_schedule

    files = export_schedule(sb, args.out, force=True)
    if not args.no_plots:
        from qsplan.planner.plotting.bands import segment_band_figures
        from qsplan.planner.plotting.style import save_figure

        for name, fig in segment_band_figures(sb, args.display_limit).items():
            path = f"{args.out}/{name}.png"
            save_figure(fig, path)
            files.append(path)
    doc = _document(args, sb, files)
    if args.json:
        json.dump(doc, out)
        out.write("\n")
        return 0
    _summary(doc, out)
    return 0


def _when(spans):
    return ("for t in " + ", ".join(f"[{a:.3g}, {b:.3g}] s" for a, b in spans)) if spans else "nowhere on the segment"


def _summary(doc, out):
    g = doc["guaranteed"]
    lo, hi = doc["mu_range"]
    out.write(f"{doc['segment']}: {doc['samples']} samples over {doc['duration']:g} s; mode {doc['mode']}; "
              f"{doc['effort_joint']} finger torque-controlled, {doc['velocity_joint']} velocity-controlled\n")  # fmt: skip
    spans = doc["frictionless_upper_infinite"]
    out.write("Fig. 10 (mu = 0): upper bound infinite " + _when(spans) + "\n")
    spans = doc["mu_high_upper_infinite"]
    out.write(f"Fig. 11 (mu = {hi:g}): upper bound infinite " + _when(spans) + "\n")
    for c, d in doc["competitors"].items():
        runs = d["feasible_at_mu_high"]
        out.write(f"Fig. 12: competitor {c} {d['name']}: feasible at mu = {hi:g} {_when(runs)}\n")
    kind = "one shared mu" if doc["shared_mu"] else "each contact's mu"
    n = g["narrowest"]
    out.write(f"Fig. 13 ({kind} in [{lo:g}, {hi:g}]): " + ("exact" if g["exact"] else "conservative at some points")
              + f"; {g['points_without_band']} samples without a guaranteed band; {g['split_points']} split\n")
    if n:
        out.write(f"  narrowest guaranteed band: [{n['lower']:.6g}, {n['upper']:.6g}] N m, width {n['width']:.6g} N m "
                  f"at t = {n['t']:.4g} s (the torque resolution the controller needs)\n")  # fmt: skip
    p = doc["paper_method"]
    if p["narrowest"]:
        out.write(f"  paper's method ({p['samples']} shared mu values): narrowest width {p['narrowest']['width']:.6g} N m; "
                  f"wider than the exact band at {p['wider_than_exact_points']} samples\n")  # fmt: skip
    for f in doc["files"]:
        out.write(f"wrote {f}\n")
