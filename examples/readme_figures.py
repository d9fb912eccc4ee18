"""Regenerate every figure the README and docs/science.md show (``docs/*.png``) from the scripts that draw them.

``python examples/readme_figures.py [--with-benchmark]``: each producer runs into a temporary folder and the
README's file is copied from it into ``docs/``.  ``--with-benchmark`` also reruns ``benchmarks/bench_bands.py``
(about a minute; it copies ``docs/bands_speed_accuracy.png`` itself).  Deterministic: no randomness, seeded plans.
"""

import runpy
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
DOCS = ROOT / "docs"

#: README figure -> (the example script that draws it, the file it writes).
EXAMPLE_FIGURES = {
    "fig3_eq37.png": ("fig3_eq37.py", "fig3_eq37.png"),
    "fig4_eq37_scene.png": ("fig3_eq37.py", "fig4_eq37_scene.png"),
    "fig13_guaranteed_band.png": ("fig10_13_bands.py", "fig13_guaranteed.png"),
    "rod_bouncing.png": ("rod_bouncing.py", "rod_bouncing.png"),
}

#: README figures of ``qsplan demo``'s run (its plots).
DEMO_FIGURES = ("plan_card.png", "plan_bands.png")


def main(argv=None) -> int:
    args = sys.argv[1:] if argv is None else argv
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        done = {}
        for target, (script, produced) in EXAMPLE_FIGURES.items():
            out = tmp / script
            if script not in done:
                runpy.run_path(str(ROOT / "examples" / script), run_name="readme_figures")["main"](str(out))
                done[script] = out
            shutil.copyfile(done[script] / produced, DOCS / target)
            print(f"docs/{target} <- examples/{script}")
        runpy.run_path(str(ROOT / "examples" / "draw_hands.py"), run_name="readme_figures")["main"](str(DOCS))
        print("docs/hand_*.png <- examples/draw_hands.py")
        demo = tmp / "demo"
        subprocess.run([sys.executable, "-m", "qsplan.planner.cli", "demo", "--out", str(demo), "--quiet"], check=True,
                       stdout=subprocess.DEVNULL)  # fmt: skip
        for name in DEMO_FIGURES:
            shutil.copyfile(demo / name, DOCS / name)
            print(f"docs/{name} <- qsplan demo")
    if "--with-benchmark" in args:
        subprocess.run([sys.executable, str(ROOT / "benchmarks" / "bench_bands.py")], check=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
