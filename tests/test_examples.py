"""Every example script imports cleanly: the public names it uses exist (their main() is not run here)."""

import runpy
from pathlib import Path

import pytest

EXAMPLES = sorted((Path(__file__).resolve().parents[1] / "examples").glob("*.py"))


def test_there_are_planning_examples_for_two_workpieces():
    names = {p.stem for p in EXAMPLES}
    assert {"plan_regrasp_quadrilateral", "plan_pentagon"} <= names


@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.stem)
def test_example_imports(path):
    namespace = runpy.run_path(str(path), run_name="example_import_check")
    assert callable(namespace.get("main")), f"{path.name}: expected a main() function"
