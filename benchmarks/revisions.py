"""A git revision of qsplan laid out as installed, to run beside the working tree (``--compare REV`` of
``bench_whole.py``, ``bench_hands.py`` and ``bench_certify.py``): :func:`export_revision`, :func:`revision_env`."""

import os
import shutil
import subprocess
import sysconfig
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: The compiled reduced screen of the mode search, relative to the package (``pyproject.toml``'s ext-module).
_KERNEL = Path("mechanics") / "solver"


def export_revision(rev: str, into: Path) -> Path:
    """REV's package laid out as installed (``into/lib/qsplan``); returns the directory to put on ``PYTHONPATH``."""
    tree = into / "tree"
    tree.mkdir(parents=True)
    archive = subprocess.run(["git", "-C", str(ROOT), "archive", rev, "src/qsplan", "mechanics", "hands", "planner"],
                             check=True, capture_output=True).stdout  # fmt: skip
    subprocess.run(["tar", "-x", "-C", str(tree)], input=archive, check=True)
    lib = into / "lib"
    package = lib / "qsplan"
    shutil.copytree(tree / "src" / "qsplan", package)
    for folder in ("mechanics", "hands", "planner"):
        shutil.move(str(tree / folder), str(package / folder))
    source = package / _KERNEL / "screen_kernel.c"
    built = sorted((ROOT / _KERNEL).glob("screen_kernel*.so"))
    if built and source.is_file() and source.read_bytes() == (ROOT / _KERNEL / "screen_kernel.c").read_bytes():
        shutil.copy(built[0], package / _KERNEL / built[0].name)
    elif source.is_file():  # REV's own kernel, built as setuptools would
        suffix = sysconfig.get_config_var("EXT_SUFFIX")
        cc = os.environ.get("CC", "cc")
        subprocess.run([cc, "-O3", "-fno-math-errno", "-shared", "-fPIC", f"-I{sysconfig.get_paths()['include']}",
                        str(source), "-o", str(package / _KERNEL / f"screen_kernel{suffix}")], check=True)  # fmt: skip
    return lib




def revision_env(rev: str, into: Path) -> dict:
    """This process's environment with git revision ``rev`` (:func:`export_revision` into ``into``) first on
    ``PYTHONPATH``: a Python started with it imports that revision's qsplan."""
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(export_revision(rev, into)), env.get("PYTHONPATH")]))
    return env
