"""``qsplan band SCENE --mode LETTERS [--mu-range LO HI [--shared-mu]] [--min-normal N] [--min-slack N] [--json]``.

Prints the interval of the (single) effort-controlled joint's effort for which
the mode is feasible: at the scene's mu; with ``--mu-range`` for every mu vector
with each contact's coefficient independently in [LO, HI] (exact, vertex
theory); with ``--shared-mu`` for one coefficient shared by all contacts in
[LO, HI] (exact, polynomial roots).  ``--min-normal`` and ``--min-slack`` (N, default
0) narrow the band to efforts that keep every loaded contact's normal force and
every rolling contact's friction-cone slacks at least that large, for every mu
(:class:`qsplan.mechanics.bands.effort.ForceMargin`).  JSON: ``{"mode", "feasible",
"lower", "upper"}`` with ``null`` for an unbounded side, plus ``"reason"`` when no
effort works, and ``"method"``, ``"exact"``, ``"joint"``, ``"units"``; with a nonzero
margin also ``"min_normal_force"`` and ``"min_coulomb_slack"`` (N).
"""

from __future__ import annotations

import json
import math

__all__ = ["add_force_margin_options", "add_parser", "force_margin_option", "run"]


def add_force_margin_options(p):
    """``--min-normal N`` and ``--min-slack N`` (N, default 0): the :class:`ForceMargin` of a band."""
    p.add_argument("--min-normal", type=float, default=0.0, metavar="N",
                   help="minimum normal force (N) at every loaded contact, for every mu (default 0)")  # fmt: skip
    p.add_argument("--min-slack", type=float, default=0.0, metavar="N",
                   help="minimum friction-cone slack mu c_n -+ c_t (N) at every rolling contact (default 0)")  # fmt: skip


def force_margin_option(args):
    """The ForceMargin of ``--min-normal`` / ``--min-slack``; QsplanError naming the option."""
    from qsplan.mechanics import QsplanError
    from qsplan.mechanics.bands.effort import ForceMargin

    for option, v in (("--min-normal", args.min_normal), ("--min-slack", args.min_slack)):
        if not (math.isfinite(v) and v >= 0):
            raise QsplanError(f"{option}: expected a nonnegative finite force (N); got {v}")
    return ForceMargin(args.min_normal, args.min_slack)


def add_parser(sub):
    p = sub.add_parser("band", help="effort band of the effort-controlled joint for a mode (eq. 28)")
    p.add_argument("scene", help="scene file with exactly one effort-controlled joint")
    p.add_argument("--mode", required=True, metavar="LETTERS", help="contact mode, one letter R/S/B per contact")
    p.add_argument("--mu-range", type=float, nargs=2, metavar=("LO", "HI"), help="guarantee for every mu in [LO, HI]")
    p.add_argument("--shared-mu", action="store_true", help="with --mu-range: one coefficient shared by all contacts")
    add_force_margin_options(p)
    p.add_argument("--json", action="store_true")


def run(args, out) -> int:
    from qsplan.mechanics import QsplanError, load_scene, mode_from_letters
    from qsplan.mechanics.bands.effort import effort_band
    from qsplan.mechanics.bands.guaranteed import guaranteed_band_box, guaranteed_band_shared

    margin = force_margin_option(args)
    fm = None if margin.is_zero else margin
    scene = load_scene(args.scene)
    mode = mode_from_letters(args.mode, scene.n_contacts)
    if args.shared_mu and args.mu_range is None:
        raise QsplanError("--shared-mu: needs --mu-range LO HI")
    if args.mu_range is not None:
        lo, hi = args.mu_range
        if not (math.isfinite(lo) and math.isfinite(hi)) or lo < 0 or lo > hi:
            raise QsplanError(f"--mu-range: expected 0 <= LO <= HI (finite); got {lo} {hi}")
        guaranteed = guaranteed_band_shared if args.shared_mu else guaranteed_band_box
        band = guaranteed(scene, mode, lo, hi, force_margin=fm)
    else:
        band = effort_band(scene, mode, force_margin=fm)
    joint = scene.joint_names[band.joint]
    if args.json:
        doc = band.to_dict()
        doc["joint"] = joint
        doc["units"] = "N m (revolute) or N (prismatic)"
        if fm is not None:
            doc["min_normal_force"], doc["min_coulomb_slack"] = fm.normal, fm.slack
        json.dump(doc, out)
        out.write("\n")
        return 0
    where = "at the scene's mu" if args.mu_range is None else (
        f"for one shared mu in [{args.mu_range[0]}, {args.mu_range[1]}]" if args.shared_mu
        else f"for every mu_i in [{args.mu_range[0]}, {args.mu_range[1]}]"
    )  # fmt: skip
    if fm is not None:
        where += f" with c_n >= {fm.normal:g} N and Coulomb slacks >= {fm.slack:g} N"
    if not band.feasible:
        out.write(f"mode {mode.letters} ({mode.name}) {where}: no effort of joint {joint} works ({band.reason})\n")
    else:
        out.write(f"mode {mode.letters} ({mode.name}) {where}: effort of joint {joint} in [{band.lower:.6g}, {band.upper:.6g}]\n")
    return 0
