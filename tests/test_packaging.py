"""What ``pip install .`` puts into site-packages: one top-level package, ``qsplan``, with every module
and the bundled task files; and the repository's folders refuse to load under their bare names."""

from __future__ import annotations

import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
FOLDERS = {"mechanics": "qsplan/mechanics", "hands": "qsplan/hands", "planner": "qsplan/planner"}


@pytest.fixture(scope="module")
def wheel(tmp_path_factory) -> zipfile.ZipFile:
    """The wheel pip builds from the working tree (the same build ``pip install .`` runs)."""
    out = tmp_path_factory.mktemp("wheel")
    # a copy of what the build reads, so setuptools' build/ folder never lands in the working tree
    src = tmp_path_factory.mktemp("source")
    for name in ("pyproject.toml", "README.md"):
        shutil.copy(ROOT / name, src / name)
    for folder in ("src", *FOLDERS):
        shutil.copytree(ROOT / folder, src / folder, ignore=shutil.ignore_patterns("__pycache__"))
    r = subprocess.run([sys.executable, "-m", "pip", "wheel", "-q", "--no-deps", "-w", str(out), str(src)],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr[-2000:]
    (path,) = out.glob("qsplan-*.whl")
    return zipfile.ZipFile(path)


@pytest.mark.slow
def test_wheel_installs_one_top_level_package(wheel):
    names = wheel.namelist()
    tops = {n.split("/")[0] for n in names if not n.split("/")[0].endswith(".dist-info")}
    assert tops == {"qsplan"}
    top_level = next(n for n in names if n.endswith("top_level.txt"))
    assert wheel.read(top_level).decode().split() == ["qsplan"]


@pytest.mark.slow
def test_wheel_holds_every_module_and_the_task_files(wheel):
    names = set(wheel.namelist())
    expected = {"qsplan/__init__.py"}
    for folder, target in FOLDERS.items():
        expected |= {f"{target}/{p.relative_to(ROOT / folder).as_posix()}" for p in (ROOT / folder).rglob("*.py")}
        expected |= {f"{target}/{p.relative_to(ROOT / folder).as_posix()}" for p in (ROOT / folder).rglob("*.toml")}
    assert expected <= names, sorted(expected - names)
    assert "qsplan/planner/data/demo_task.toml" in names


@pytest.mark.slow
def test_wheel_console_script(wheel):
    entry = next(n for n in wheel.namelist() if n.endswith("entry_points.txt"))
    assert "qsplan = qsplan.planner.cli:main" in wheel.read(entry).decode()


@pytest.mark.parametrize("folder", sorted(FOLDERS))
def test_bare_folder_names_do_not_import(folder):
    """With the repository root on sys.path, ``import mechanics`` must not load a second copy."""
    r = subprocess.run([sys.executable, "-c", f"import {folder}"], cwd=ROOT, capture_output=True, text=True)
    assert r.returncode != 0
    assert f"import qsplan.{folder}" in r.stderr


def test_qsplan_imports_from_the_repository_root():
    r = subprocess.run([sys.executable, "-c", "import qsplan, qsplan.mechanics, qsplan.planner, qsplan.hands;"
                        "print(qsplan.__version__)"], cwd=ROOT, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    from importlib.metadata import version

    assert r.stdout.strip() == version("qsplan")
