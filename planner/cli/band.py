"""``qsplan band SCENE --mode LETTERS [--mu-range LO HI [--shared-mu]] [--json]``.

Prints the interval of the (single) effort-controlled joint's effort for which
the mode is feasible: at the scene's mu; with ``--mu-range`` for every mu vector
with each contact's coefficient independently in [LO, HI] (exact, vertex
theory); with ``--shared-mu`` for one coefficient shared by all contacts in
[LO, HI] (exact, polynomial roots).  JSON: ``{"mode", "feasible", "lower",
"upper"}`` with ``null`` for an unbounded side, plus ``"reason"`` when no effort
works, and ``"method"``, ``"exact"``, ``"joint"``, ``"units"``.
"""

from __future__ import annotations

import json
import math


def add_parser(sub):
    p = sub.add_parser("band", help="effort band of the effort-controlled joint for a mode (eq. 28)")
    p.add_argument("scene", help="scene file with exactly one effort-controlled joint")
    p.add_argument("--mode", required=True, metavar="LETTERS", help="contact mode, one letter R/S/B per contact")
    p.add_argument("--mu-range", type=float, nargs=2, metavar=("LO", "HI"), help="guarantee for every mu in [LO, HI]")
    p.add_argument("--shared-mu", action="store_true", help="with --mu-range: one coefficient shared by all contacts")
    p.add_argument("--json", action="store_true")


def run(args, out) -> int:
    from qsplan.mechanics import QsplanError, load_scene, mode_from_letters
    from qsplan.mechanics.bands.effort import effort_band
    from qsplan.mechanics.bands.guaranteed import guaranteed_band_box, guaranteed_band_shared

    scene = load_scene(args.scene)
    mode = mode_from_letters(args.mode, scene.n_contacts)
    if args.shared_mu and args.mu_range is None:
        raise QsplanError("--shared-mu: needs --mu-range LO HI")
    if args.mu_range is not None:
        lo, hi = args.mu_range
        if not (math.isfinite(lo) and math.isfinite(hi)) or lo < 0 or lo > hi:
            raise QsplanError(f"--mu-range: expected 0 <= LO <= HI (finite); got {lo} {hi}")
        band = guaranteed_band_shared(scene, mode, lo, hi) if args.shared_mu else guaranteed_band_box(scene, mode, lo, hi)
    else:
        band = effort_band(scene, mode)
    joint = scene.joint_names[band.joint]
    if args.json:
        doc = band.to_dict()
        doc["joint"] = joint
        doc["units"] = "N m (revolute) or N (prismatic)"
        json.dump(doc, out)
        out.write("\n")
        return 0
    where = "at the scene's mu" if args.mu_range is None else (
        f"for one shared mu in [{args.mu_range[0]}, {args.mu_range[1]}]" if args.shared_mu
        else f"for every mu_i in [{args.mu_range[0]}, {args.mu_range[1]}]"
    )  # fmt: skip
    if not band.feasible:
        out.write(f"mode {mode.letters} ({mode.name}) {where}: no effort of joint {joint} works ({band.reason})\n")
    else:
        out.write(f"mode {mode.letters} ({mode.name}) {where}: effort of joint {joint} in [{band.lower:.6g}, {band.upper:.6g}]\n")
    return 0
