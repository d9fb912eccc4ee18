"""Light commands import only what they need (issue 13, "fast start"): structural, not timed.

Each check runs in a fresh interpreter and looks at ``sys.modules`` afterwards.
"""

import subprocess
import sys

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
