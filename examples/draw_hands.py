"""Draw every bundled hand file (issue 15): ``hand_<name>.png`` for paper_hand, two_link_hand, parallel_jaw.

Each hand is loaded from its TOML file (``qsplan hands NAME`` prints the same hand), its joints put at
the middle of their limits, and its palm, links and joints drawn; the paper hand is also drawn with
the default workpiece resting on the palm, its fingers at the tangency angles of
:func:`qsplan.hands.finger_angles`.  No randomness.  These pictures are ``docs/hand_*.png``.

Usage, with qsplan installed (``pip install .``) or ``PYTHONPATH=.``:
``python examples/draw_hands.py [OUT_DIR]`` (default ``docs/``).
"""

import sys
from pathlib import Path

from qsplan.hands import default_hand, finger_angles, workpiece_world
from qsplan.hands.description import bundled_hands, load_hand
from qsplan.planner import new_axes, save_figure
from qsplan.planner import plot_hand_description


def main(out_dir="docs") -> int:
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    for name in bundled_hands():
        desc = load_hand(name)
        fig, axes = new_axes(1, 1, size=(6.0, 3.8))
        plot_hand_description(desc, ax=axes[0, 0])
        save_figure(fig, out / f"hand_{name}.png")
        print(f"wrote {out / f'hand_{name}.png'}: {desc.name}, joints {', '.join(desc.joint_names)}")
    hand = default_hand()
    pose = (0.0, hand.rest_height, 0.0)
    fig, axes = new_axes(1, 1, size=(6.0, 3.8))
    ax = plot_hand_description(load_hand("paper_hand"), q=finger_angles(hand, pose)[0],
                               workpiece=workpiece_world(hand, pose), ax=axes[0, 0])
    ax.set_title("paper hand holding the default workpiece", fontsize=10)
    save_figure(fig, out / "hand_paper_hand_grasp.png")
    print(f"wrote {out / 'hand_paper_hand_grasp.png'}")
    return 0


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:2]))
