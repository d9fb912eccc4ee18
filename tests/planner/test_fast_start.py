"""Light commands import only what they need (issue 13, "fast start"): structural, not timed.

Each check runs in a fresh interpreter and looks at ``sys.modules`` afterwards.
"""

import subprocess
import sys
from pathlib import Path

import pytest

#: Modules a light command must not load: numpy and everything built on it, the solver, OMPL.
HEAVY = ("numpy", "scipy", "shapely", "matplotlib", "ompl", "qsplan.mechanics.solver", "qsplan.mechanics.bands")


def _loaded_after(code):
    probe = f"{code}\nimport sys\nprint('loaded:', *sorted(m for m in {HEAVY!r} if m in sys.modules))"
    p = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True)
    return p.stdout.splitlines()[-1].removeprefix("loaded:").strip()


def test_count_imports_nothing_heavy():
    code = ("from qsplan.planner.cli.main import main\n"
            "assert main(['count', '--contacts', '4', '--dof', '3']) == 0")  # fmt: skip
    assert _loaded_after(code) == ""


@pytest.mark.parametrize("argv", [["--help"], ["plan", "--help"], ["modes", "--help"], ["demo", "--help"]])
def test_help_imports_nothing_heavy(argv):
    code = f"from qsplan.planner.cli.main import main\ntry:\n    main({argv!r})\nexcept SystemExit:\n    pass"
    assert _loaded_after(code) == ""


@pytest.mark.parametrize("package", ["qsplan.mechanics", "qsplan.mechanics.errors", "qsplan.planner", "qsplan.hands"])
def test_packages_import_nothing_heavy(package):
    assert _loaded_after(f"import {package}") == ""


def test_count_answers_as_before(capsys):
    from qsplan.planner.cli.main import main

    assert main(["count", "--contacts", "4", "--dof", "3"]) == 0
    assert capsys.readouterr().out == "16\n"


def test_count_modes_is_one_function_everywhere():
    import qsplan.mechanics as mechanics
    from qsplan.mechanics.modes import contact_mode, counting

    assert mechanics.count_modes is counting.count_modes is contact_mode.count_modes


@pytest.mark.parametrize("argv", [["verify", "--help"], ["replay", "--help"]])
def test_more_help_imports_nothing_heavy(argv):
    code = f"from qsplan.planner.cli.main import main\ntry:\n    main({argv!r})\nexcept SystemExit:\n    pass"
    assert _loaded_after(code) == ""


def _modules_after(code, names):
    probe = f"{code}\nimport sys\nprint('loaded:', *sorted(m for m in {names!r} if m in sys.modules))"
    p = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True)
    return p.stdout.splitlines()[-1].removeprefix("loaded:").strip()


@pytest.mark.ompl
def test_verify_and_modes_never_import_matplotlib(bundled_plan, tmp_path):
    """Issue 33: ``qsplan verify`` and ``qsplan modes`` load no plotting (nor OMPL)."""
    plan_dir = bundled_plan("demo_task")
    code = f"from qsplan.planner.cli.main import main\nassert main(['verify', {str(plan_dir)!r}]) == 0"
    assert _modules_after(code, ("matplotlib", "ompl", "PIL")) == ""
    scene = str(Path(__file__).resolve().parents[2] / "examples" / "scenes" / "eq42.json")
    code = f"from qsplan.planner.cli.main import main\nassert main(['modes', {scene!r}]) == 0"
    assert _modules_after(code, ("matplotlib", "ompl", "PIL", "shapely")) == ""


@pytest.mark.ompl
def test_the_demo_draws_in_its_second_process_only(tmp_path):
    """Issue 33: ``qsplan demo`` draws its plan card in the second process: the run itself never loads matplotlib."""
    code = ("from qsplan.planner.cli.main import main\n"
            f"assert main(['demo', '--out', {str(tmp_path / 'out')!r}, '--verify', '0', '--quiet']) == 0")  # fmt: skip
    assert _modules_after(code, ("matplotlib",)) == ""
    assert (tmp_path / "out" / "plan_card.png").is_file()
