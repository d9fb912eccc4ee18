"""``qsplan hands [REF] [--out DIR [--force]]``: the bundled hand files, or one hand checked and shown (issue 15).

Without REF: one line per bundled hand (its name, the joints of each finger with their kinds,
its source).  With REF (a bundled name such as ``two_link_hand``, or a path to a ``.toml`` hand
file, see :mod:`qsplan.hands.description.files`): the file is validated and summarised (palm,
gravity, whether it is the paper's two-finger form, and each joint's finger, kind, origin, limits
and speed with their units); with ``--out`` the hand is drawn at mid-limits into
``DIR/hand_<name>.png`` (an existing file is replaced only with ``--force``).  A bad file exits 2
with one line naming the file and the field.

Nothing heavy is imported until :func:`run`.
"""

from __future__ import annotations

import re

from qsplan.planner.cli.options import UsageError

__all__ = ["add_parser", "run"]


def add_parser(subparsers):
    h = subparsers.add_parser("hands", help="list the bundled hand files, or check and show one (REF) and draw it")
    h.add_argument("ref", nargs="?", metavar="REF", help="a bundled hand name (e.g. two_link_hand) or a .toml hand file")
    h.add_argument("--out", metavar="DIR", help="draw the hand into DIR/hand_<name>.png")
    h.add_argument("--force", action="store_true", help="replace an existing picture in DIR")
    return h


def _kinds(desc, finger) -> str:
    return ", ".join(desc.joint_kinds[i] for i in finger.joints)


def _list(out) -> int:
    from qsplan.hands.description.files import bundled_hands, load_hand

    rows = [("name", "hand", "left finger", "right finger", "source")]
    for name in bundled_hands():
        desc = load_hand(name)
        rows.append((name, desc.name, *(_kinds(desc, f) for f in desc.fingers), desc.source))
    widths = [max(len(r[k]) for r in rows) for k in range(len(rows[0]) - 1)]
    out.write("bundled hands (`qsplan hands NAME` shows one; a path to a .toml hand file works too):\n")
    for r in rows:
        out.write("  " + "  ".join(c.ljust(w) for c, w in zip(r, widths)) + "  " + r[-1] + "\n")
    return 0


def _number(x: float) -> str:
    return f"{x:.6g}"


def _summary(desc) -> str:
    import numpy as np

    from qsplan.hands.description.two_finger_form import two_finger_parameters

    palm = desc.palm
    lo, hi = desc.palm_top
    lines = [f"hand: {desc.name}", f"source: {desc.source}",
             f"palm: {len(palm)} vertices; top edge y = 0 m from x = {_number(lo)} to {_number(hi)} m; "
             f"{_number(-palm[:, 1].min())} m thick",
             f"gravity: {_number(desc.manipulator.gravity)} m/s^2 along -y"]  # fmt: skip
    form = two_finger_parameters(desc)
    if form is None:
        lines.append("paper's two-finger form: no")
    else:
        units = {"finger_mass": "kg", "gravity": "m/s^2"}
        lines.append("paper's two-finger form: yes, make_two_finger_hand(" +
                     ", ".join(f"{k} = {_number(v)} {units.get(k, 'm')}" for k, v in form.items()) + ")")
    rows = [("finger", "joint", "kind", "on", "origin (x m, y m, angle rad)", "limits", "speed", "link mass")]
    for i, joint in enumerate(desc.manipulator.joints):
        unit = desc.joint_units[i]
        lim = desc.joint_limits[i]
        limits = f"[{_number(lim[0])}, {_number(lim[1])}] {unit}"
        if unit == "rad":
            limits += f" ([{np.degrees(lim[0]):.1f}, {np.degrees(lim[1]):.1f}] deg)"
        on = "palm" if joint.parent < 0 else desc.joint_names[joint.parent]
        origin = "(" + ", ".join(_number(v) for v in joint.origin) + ")"
        rows.append((desc.finger_of_joint[i], joint.name, joint.kind, on, origin, limits,
                     f"{_number(desc.joint_speeds[i])} {unit}/s", f"{_number(joint.link_mass)} kg"))  # fmt: skip
    widths = [max(len(r[k]) for r in rows) for k in range(len(rows[0]))]
    lines.append(f"joints ({desc.n_joints}, left finger's then right finger's, base to tip):")
    lines += ["  " + "  ".join(c.ljust(w) for c, w in zip(r, widths)).rstrip() for r in rows]
    return "\n".join(lines) + "\n"


def run(args, out) -> int:
    if args.ref is None:
        if args.out is not None:
            raise UsageError("qsplan: error: --out: expected the hand to draw (REF) with it")
        return _list(out)
    from pathlib import Path

    from qsplan.hands.description.files import bundled_hands, load_hand

    desc = load_hand(args.ref)
    path = None
    if args.out is not None:  # the output checked before any work
        from qsplan.planner.export.files import check_outputs

        stem = args.ref if args.ref in bundled_hands() else Path(args.ref).stem
        path = Path(args.out) / f"hand_{re.sub(r'[^A-Za-z0-9_.-]+', '_', stem)}.png"
        check_outputs([path], force=args.force)
    out.write(_summary(desc))
    if path is not None:
        from qsplan.planner.plotting.hand_files import plot_hand_description
        from qsplan.planner.plotting.style import new_axes, save_figure

        fig, axes = new_axes(1, 1, size=(6.0, 3.8))
        plot_hand_description(desc, ax=axes[0, 0])
        save_figure(fig, path, option="out_dir")
        out.write(f"wrote {path}\n")
    return 0
