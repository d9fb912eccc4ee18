"""``qsplan sweep``: torque bands along a two-finger hand segment (Section 5.2, Figs. 9-13), plots and export.

::

    qsplan sweep [--segment 1] [--mu-range LO HI] [--shared-mu] [--samples N] [--duration T]
                 [--effort-joint left|right] [--paper-samples K] [--torque-resolution R]
                 [--safety-margin M] [--max-margin M] [--min-normal N] [--min-slack N]
                 [--display-limit L] [--out DIR] [--force] [--no-plots] [--json]
                 [--workers N] [--scheduler ADDRESS]

Builds the default two-finger hand (:func:`qsplan.hands.default_hand`) and the
segment (1: translate the workpiece left until the left finger meets its longest
edge), samples it at N instants over T seconds and computes, for the
effort-controlled finger: the desired mode's band without friction (Fig. 10) and
at mu = HI (Fig. 11), the competing modes' bands at mu = HI (Fig. 12) and the
band guaranteeing the mode and precluding every competitor for friction in
[LO, HI] (Fig. 13; independent per contact, or with ``--shared-mu`` one shared
coefficient), exactly, beside the paper's sampled method with K values: all by
:func:`qsplan.planner.reports.segment.sweep_segment`.  ``--min-normal`` and
``--min-slack`` (N, default 0) narrow Fig. 13's bands (exact and sampled) to efforts
that keep every loaded contact's normal force and every rolling contact's cone
slacks at least that large for all friction in the range (Figs. 10-12 stay eq. 28 as is).
The exported command follows the plans' rule (:func:`qsplan.planner.torque.command.segment_command`):
one margin kept from both band edges along the whole segment, half the narrowest band and at most
two torque resolutions (``--torque-resolution``, N m), so it is continuous and near the torque
the mode needs, with or without ``--shared-mu``.

Into DIR (default ``out/sweep``) it writes ``segment1.csv`` and ``segment1.json``
(the torque schedule: see :mod:`qsplan.planner.export.schedule`) and, unless ``--no-plots``,
``fig10_frictionless.png``, ``fig11_mu_high.png``, ``fig12_competitors.png``,
``fig13_guaranteed.png`` and ``hand_strip.png``.  Existing files are not
overwritten without ``--force`` (checked before anything is written).

stdout: a summary; with ``--json`` one object::

    {"segment", "duration", "samples", "mode", "effort_joint", "velocity_joint", "mu_range", "shared_mu",
     "competitors": {LETTERS: {"name", "feasible_at_mu_high": [[t0, t1], ...]}},
     "frictionless_upper_infinite": [[t0, t1], ...], "mu_high_upper_infinite": [[t0, t1], ...],
     "guaranteed": {"exact", "points_without_band", "split_points", "narrowest": {"t", "width", "lower", "upper"}},
     "paper_method": {"samples", "narrowest": {...}, "wider_than_exact_points"},
     "safety_margin", "max_margin", "torque_resolution", "force_margin": {"min_normal_force_N", "min_coulomb_slack_N"},
     "command_max", "files": [...]}

Efforts in N m, times in s.  Bad arguments raise a :class:`qsplan.mechanics.QsplanError` naming the option (exit 2).
"""

from __future__ import annotations

import json
import math

from qsplan.planner.cli.band import add_force_margin_options, force_margin_option
from qsplan.planner.cli.options import add_parallel_options, parallel_options

__all__ = ["add_parser", "run"]



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
    p.add_argument("--torque-resolution", type=float, default=0.02, metavar="R",
                   help="the controller's torque resolution, N m (default 0.02, the bundled tasks'): the command's "
                        "margin is at most two of it")  # fmt: skip
    p.add_argument("--safety-margin", type=float, metavar="M",
                   help="N m kept from both band edges along the segment (default: half the narrowest band, at most "
                        "two torque resolutions)")  # fmt: skip
    p.add_argument("--max-margin", type=float, metavar="M",
                   help="N m: a larger margin where the band is bounded: lower + M where wider than 2 M (default: "
                        "the safety margin)")  # fmt: skip
    add_force_margin_options(p)
    p.add_argument("--display-limit", type=float, metavar="L", help="N m at which plotted bands are truncated (default: per figure)")
    p.add_argument("--out", default="out/sweep", metavar="DIR", help="output directory (default out/sweep)")
    p.add_argument("--force", action="store_true", help="overwrite existing files in DIR")
    p.add_argument("--no-plots", action="store_true", help="write the schedule only")
    p.add_argument("--json", action="store_true", help="machine-readable summary on stdout")
    add_parallel_options(p)
    return p


def _check(args):
    from qsplan.mechanics import QsplanError

    parallel = parallel_options(args)
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
                      ("--display-limit", args.display_limit), ("--torque-resolution", args.torque_resolution)):  # fmt: skip
        if v is not None and not (math.isfinite(v) and v > 0):
            raise QsplanError(f"{option}: expected a positive finite torque (N m); got {v}")
    force_margin_option(args)
    return parallel


def run(args, out) -> int:
    from qsplan.hands import default_hand, first_segment, sample_segment

    from qsplan.planner.reports.segment import sweep_segment

    parallel = _check(args)
    samples = sample_segment(first_segment(default_hand(), duration=args.duration, effort_joint=args.effort_joint),
                             args.samples)  # fmt: skip
    result = sweep_segment(samples, args.out, tuple(args.mu_range), shared=args.shared_mu,
                           paper_samples=args.paper_samples, safety_margin=args.safety_margin,
                           max_margin=args.max_margin, display_limit=args.display_limit, force=args.force,
                           plots=not args.no_plots, force_margin=force_margin_option(args),
                           resolution=args.torque_resolution, **parallel)  # fmt: skip
    if args.json:
        json.dump(result.document, out)
        out.write("\n")
        return 0
    _summary(result.document, out)
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
    fm = doc["force_margin"]
    kept = (f"; c_n >= {fm['min_normal_force_N']:g} N, Coulomb slacks >= {fm['min_coulomb_slack_N']:g} N"
            if fm["min_normal_force_N"] or fm["min_coulomb_slack_N"] else "")  # fmt: skip
    out.write(f"Fig. 13 ({kind} in [{lo:g}, {hi:g}]{kept}): " + ("exact" if g["exact"] else "conservative at some points")
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
