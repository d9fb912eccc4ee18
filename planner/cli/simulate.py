"""``qsplan simulate``: a finite quasistatic motion with mode switches (Section 5.1, Figs. 7-8).

::

    qsplan simulate rod --l1 A --l2 B --mu-static M1 M2 --mu-kinetic K1 K2 --speed V --duration T
                        [--initial-mode RS|SR] [--max-step S] [--min-segment S] [--max-switches N]
                        [--json] [--out FILE.png [--force]]

The rod of Fig. 7: supports start at horizontal distances A (left, contact 1) and
B (right, contact 2) from the rod's centre of mass and each moves toward the
other at V (m/s) for T seconds.  Friction takes the static coefficient (M1, M2)
while a support rolls (sticks) and the kinetic one (K1, K2) while it slides;
kinetic must not exceed static (equal is allowed: the farther support slides
until ``l1 mu2 = l2 mu1`` and the run stops there, honestly).

With ``--json`` stdout is one object::

    {"segments": [{"mode": "SR", "t_start": 0.0, "t_end": ..., "l1_start": ..., "l2_start": ...,
                   "l1_end": ..., "l2_end": ..., "name": "R2S1", "sliding_support": 1}, ...],
     "stopped": null or "KIND: reason",
     "stop": null or {"kind", "time", "l1", "l2", "candidates", "message"},
     "events": [{"time", "kind", "labels", "before", "after"}, ...],
     "closed_form": {"t_star", "a", "b", "stopped", "n_segments", "max_abs_error"} or null,
     "inputs": {...}}

``mode`` has one letter per contact (``"SR"``: contact 1 slides, contact 2 rolls); a
segment ends at each mode switch.  ``stopped`` is null when the duration was
reached; otherwise its kind is one of ``ambiguous`` (both modes possible, e.g. at
the start when ``mu_1S/mu_2R < l1/l2 < mu_1R/mu_2S``; pass ``--initial-mode``),
``no_persistent_mode``, ``jam``, ``zeno`` (switches accumulate as the supports
meet at ``t* = (A + B) / (2V)``; a segment shorter than ``--min-segment``),
``limit`` or ``max_switches``.  ``--out`` writes l1(t), l2(t) with the sliding
support drawn thick, and the mu-space picture with the partition line at each
switch (an existing file is replaced only with ``--force``, never through a symbolic
link; checked before the run).  Bad arguments raise a :class:`qsplan.mechanics.QsplanError` naming the option.
"""

from __future__ import annotations

import json
import math

__all__ = ["add_parser", "run", "SIM_RANGES", "MAX_STEPS"]

_OUT_FORMATS = (".png", ".svg", ".pdf")

#: Shortest ``--min-segment`` accepted (s): a thousand times the root finder's time
#: tolerance (``MotionOptions.event_xtol``), so that segments stay resolvable.
MIN_SEGMENT_FLOOR = 1e-9

#: Plausible range ``(lo, hi)`` of each input of the rod (SI).  Outside it the answer is not slow but
#: wrong: supports 1e300 m away reported a jam, a speed of 1e300 m/s "no persistent mode", both
#: from overflow.  Lengths from 0.1 mm to 1 km, speeds from 1 um/s to 1 km/s, durations from the
#: shortest segment to 10^6 s cover any rod a quasistatic model describes.
SIM_RANGES = {"length": (1e-4, 1e3), "speed": (1e-6, 1e3), "duration": (MIN_SEGMENT_FLOOR, 1e6)}

#: Most integration steps of one run (``duration / max_step``): a tiny ``--max-step`` otherwise runs forever.
MAX_STEPS = 10_000_000


def add_parser(subparsers):
    p = subparsers.add_parser("simulate", help="finite motion with mode switches: the rod of Figs. 7-8")
    p.add_argument("system", choices=("rod",), help="system to simulate (rod: Fig. 7)")
    p.add_argument("--l1", type=float, required=True, metavar="A", help="initial distance of support 1 from the centre (m)")
    p.add_argument("--l2", type=float, required=True, metavar="B", help="initial distance of support 2 from the centre (m)")
    p.add_argument("--mu-static", type=float, nargs=2, required=True, metavar=("M1", "M2"),
                   help="static (rolling) coefficients of contacts 1, 2")  # fmt: skip
    p.add_argument("--mu-kinetic", type=float, nargs=2, required=True, metavar=("K1", "K2"),
                   help="kinetic (sliding) coefficients, at most the static ones")  # fmt: skip
    p.add_argument("--speed", type=float, required=True, metavar="V", help="speed of each support toward the other (m/s)")
    p.add_argument("--duration", type=float, required=True, metavar="T", help="duration (s)")
    p.add_argument("--initial-mode", choices=("RS", "SR"),
                   help="resolves an ambiguous start (ignored when the start is unique)")  # fmt: skip
    p.add_argument("--max-step", type=float, metavar="S", help="integration step (s); default (A + B) / (2V) / 100")
    p.add_argument("--min-segment", type=float, metavar="S", help="shortest segment before a zeno stop (s); default 1e-6")
    p.add_argument("--max-switches", type=int, metavar="N", help="cap on mode switches; default 10000")
    p.add_argument("--json", action="store_true", help="machine-readable segments on stdout")
    p.add_argument("--out", metavar="FILE.png", help="write the plots (png, svg or pdf)")
    p.add_argument("--force", action="store_true", help="replace an existing --out file")
    return p


def _check(args):
    from qsplan.mechanics import QsplanError
    from qsplan.mechanics.model.friction import MAX_FRICTION

    def positive(value, option, unit, kind=None):
        if not (math.isfinite(value) and value > 0):
            raise QsplanError(f"{option}: expected a positive finite {unit}; got {value}")
        if kind is not None and not SIM_RANGES[kind][0] <= value <= SIM_RANGES[kind][1]:
            lo, hi = SIM_RANGES[kind]
            raise QsplanError(f"{option}: expected a {unit} from {lo:g} to {hi:g} (SIM_RANGES); got {value:g}")

    positive(args.l1, "--l1", "length (m)", "length")
    positive(args.l2, "--l2", "length (m)", "length")
    for option, values in (("--mu-static", args.mu_static), ("--mu-kinetic", args.mu_kinetic)):
        for i, v in enumerate(values):
            if not (math.isfinite(v) and 0 <= v <= MAX_FRICTION):
                raise QsplanError(f"{option}: expected nonnegative finite coefficients, at most {MAX_FRICTION:g} "
                                  f"(MAX_FRICTION); got {v} for contact {i + 1}")  # fmt: skip
    for i, (s, k) in enumerate(zip(args.mu_static, args.mu_kinetic)):
        if k > s:
            raise QsplanError(f"--mu-kinetic: contact {i + 1} has kinetic {k} above its static {s}; "
                              "kinetic friction must not exceed static (equal is allowed)")  # fmt: skip
    positive(args.speed, "--speed", "speed (m/s)", "speed")
    positive(args.duration, "--duration", "duration (s)", "duration")
    if args.max_step is not None:
        positive(args.max_step, "--max-step", "step (s)")
        if args.duration / args.max_step > MAX_STEPS:
            raise QsplanError(f"--max-step: expected at least --duration / {MAX_STEPS:g} = "
                              f"{args.duration / MAX_STEPS:g} s (at most {MAX_STEPS:g} steps); got {args.max_step:g}")  # fmt: skip
    if args.min_segment is not None:
        positive(args.min_segment, "--min-segment", "duration (s)")
        if args.min_segment < MIN_SEGMENT_FLOOR:
            raise QsplanError(f"--min-segment: expected at least {MIN_SEGMENT_FLOOR:g} s (switch instants are located "
                              f"to 1e-12 s); got {args.min_segment:g}")  # fmt: skip
    if args.max_switches is not None and args.max_switches < 0:
        raise QsplanError(f"--max-switches: expected a nonnegative integer; got {args.max_switches}")
    if args.out is not None and not str(args.out).lower().endswith(_OUT_FORMATS):
        raise QsplanError(f"--out: expected a file name ending in {', '.join(_OUT_FORMATS)}; got {args.out!r}")
    if args.out is not None:
        from qsplan.planner.export.files import check_outputs

        check_outputs([args.out], args.force)


def _options(args):
    from qsplan.mechanics.motion.simulator import MotionOptions

    d = MotionOptions()
    min_segment = d.min_segment if args.min_segment is None else args.min_segment
    return MotionOptions(
        max_step=args.max_step if args.max_step is not None else (args.l1 + args.l2) / (2 * args.speed) / 100,
        min_segment=min_segment,
        probe_time=min(d.probe_time, 0.1 * min_segment),
        max_switches=d.max_switches if args.max_switches is None else args.max_switches,
    )


def _document(args, motion, cf):
    import numpy as np

    from qsplan.hands.examples.rod import rod_distances
    from qsplan.mechanics import ContactMode

    segs = []
    for s in motion.segments:
        L = rod_distances(np.array([s.x_start, s.x_end]))
        segs.append({
            "mode": s.label, "t_start": float(s.t_start), "t_end": float(s.t_end),
            "l1_start": float(L[0, 0]), "l2_start": float(L[0, 1]), "l1_end": float(L[1, 0]), "l2_end": float(L[1, 1]),
            "name": ContactMode(s.label).name, "sliding_support": s.label.index("S") + 1 if "S" in s.label else None,
        })  # fmt: skip
    stop = motion.stopped
    stop_doc = None
    if stop is not None:
        l1, l2 = rod_distances(stop.state[None])[0]
        stop_doc = {"kind": stop.kind, "time": stop.time, "l1": float(l1), "l2": float(l2),
                    "candidates": list(stop.candidates), "message": stop.message}  # fmt: skip
    cf_doc = None
    if cf is not None:
        n = min(len(cf.segments), len(segs))
        err = 0.0
        for s, c in zip(segs[:n], cf.segments[:n]):
            keys = ("t_start", "t_end", "l1_start", "l2_start", "l1_end", "l2_end")
            err = max(err, *(abs(s[k] - getattr(c, k)) for k in keys))
        cf_doc = {"t_star": cf.t_star, "a": float(cf.a), "b": float(cf.b), "stopped": cf.stopped,
                  "n_segments": len(cf.segments), "max_abs_error": err,
                  "modes_match": [s["mode"] for s in segs] == [c.mode for c in cf.segments]}  # fmt: skip
    reason = None if stop is None else f"{stop.kind}: {stop.message}"
    if stop is not None and stop.kind == "no_persistent_mode":
        reason += (f"; the rod: l1 = {stop_doc['l1']:.9g} m and l2 = {stop_doc['l2']:.9g} m put the partition line "
                   "l1 mu2 = l2 mu1 through the friction point, where only the 2S mode (both supports sliding, "
                   "excluded by the utility condition (31), rank W_Amu < 3) could continue")  # fmt: skip
    return {
        "segments": segs,
        "stopped": reason,
        "stop": stop_doc,
        "events": [{"time": e.time, "kind": e.kind, "labels": list(e.labels), "before": e.before, "after": e.after}
                   for e in motion.events],  # fmt: skip
        "closed_form": cf_doc,
        "inputs": {"system": args.system, "l1": args.l1, "l2": args.l2, "mu_static": list(args.mu_static),
                   "mu_kinetic": list(args.mu_kinetic), "speed": args.speed, "duration": args.duration,
                   "initial_mode": args.initial_mode},  # fmt: skip
    }


def _write_figure(motion, cf, path, force):


    from qsplan.planner.plotting.motion import rod_motion_figure

    fig = rod_motion_figure(motion, closed_form=cf)
    from qsplan.planner.plotting.style import save_figure

    save_figure(fig, path, option="--out", force=force)


def run(args, out) -> int:
    from qsplan.hands.examples.rod import rod_closed_form, simulate_rod

    _check(args)
    options = _options(args)
    params = dict(l1=args.l1, l2=args.l2, mu_static=args.mu_static, mu_kinetic=args.mu_kinetic, speed=args.speed,
                  duration=args.duration)  # fmt: skip
    motion = simulate_rod(**params, options=options, initial_mode=args.initial_mode)
    cf = None
    if min(args.mu_static) > 0:
        cf = rod_closed_form(**params, initial_mode=args.initial_mode, min_segment=options.min_segment,
                             max_switches=options.max_switches)  # fmt: skip
    if args.out is not None:
        _write_figure(motion, cf, args.out, args.force)
    doc = _document(args, motion, cf)
    if args.json:
        json.dump(doc, out)
        out.write("\n")
        return 0
    out.write(f"rod: l1 = {args.l1:g} m, l2 = {args.l2:g} m, mu static {args.mu_static}, kinetic {args.mu_kinetic}, "
              f"V = {args.speed:g} m/s, T = {args.duration:g} s\n")  # fmt: skip
    out.write(f"{len(doc['segments'])} segments ('SR': support 1 slides, support 2 rolls)\n")
    out.write("  mode  name       t_start        t_end     l1_end     l2_end\n")
    rows = doc["segments"]
    shown = rows if len(rows) <= 24 else rows[:12] + [None] + rows[-11:]
    for r in shown:
        if r is None:
            out.write(f"  ... {len(rows) - 23} more\n")
            continue
        out.write(f"  {r['mode']:<4}  {r['name']:<6} {r['t_start']:12.9g} {r['t_end']:12.9g} "
                  f"{r['l1_end']:10.6g} {r['l2_end']:10.6g}\n")  # fmt: skip
    out.write(f"stopped: {doc['stopped'] or 'no (duration reached)'}\n")
    if doc["closed_form"] is not None:
        c = doc["closed_form"]
        out.write(f"closed form: {c['n_segments']} segments, max |difference| {c['max_abs_error']:.3g}, "
                  f"switches accumulate at t* = {c['t_star']:.9g} s\n")  # fmt: skip
    if args.out is not None:
        out.write(f"wrote {args.out}\n")
    return 0
