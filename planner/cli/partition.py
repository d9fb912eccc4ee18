"""``qsplan partition SCENE [--mode LETTERS] [--json]``: the control-mode partitioner (eq. 32).

Without ``--mode``: for each set of effort-controlled joints, the contact modes it admits
(:func:`qsplan.mechanics.partition_table`); with it: the admissible effort-joint sets of one
mode, best conditioned first (:func:`qsplan.mechanics.effort_partitions`).
"""

from __future__ import annotations

import json

__all__ = ["add_parser", "run"]


def add_parser(subparsers):
    t = subparsers.add_parser("partition", help="control-mode partitions admitted by each contact mode (eq. 32)")
    t.add_argument("scene")
    t.add_argument("--mode", metavar="LETTERS", help="rank the effort-joint sets of one mode, e.g. RBS")
    t.add_argument("--json", action="store_true")
    return t


def run(args, out) -> int:
    from qsplan.mechanics import QsplanError, SceneError, effort_partitions, load_scene, mode_from_letters, partition_table

    scene = load_scene(args.scene)
    if scene.virtual_joints:
        raise SceneError(f"{args.scene}: joints: the scene gives contact velocities, not joints; nothing to partition")
    names = scene.joint_names
    if args.mode:
        mode = mode_from_letters(args.mode, scene.n_contacts)
        parts = effort_partitions(scene, mode)
        rows = [
            {"effort_joints": [names[i] for i in p.effort_joints], "rcond_P": p.rcond_P, "rcond_Q": p.rcond_Q}
            for p in parts
        ]
        if args.json:
            json.dump({"mode": mode.letters, "name": mode.name, "partitions": rows}, out)
            out.write("\n")
        else:
            out.write(f"mode {mode.letters} ({mode.name}): {len(rows)} admissible effort-joint sets, best first\n")
            for r in rows:
                out.write(f"  effort {{{', '.join(r['effort_joints'])}}}  rcond P {r['rcond_P']:.3g}  Q {r['rcond_Q']:.3g}\n")
        return 0
    try:
        table = partition_table(scene)
    except QsplanError as exc:  # the size refusal names the library's argument; the command has --mode
        raise QsplanError(str(exc).replace("(mode=LETTERS)", "(--mode LETTERS)")) from None
    if args.json:
        json.dump({"partitions": [{"effort_joints": [names[i] for i in k], "modes": v} for k, v in table.items()]}, out)
        out.write("\n")
    else:
        for k, v in table.items():
            out.write(f"effort {{{', '.join(names[i] for i in k)}}}: {len(v)} modes: {' '.join(v)}\n")
    return 0
