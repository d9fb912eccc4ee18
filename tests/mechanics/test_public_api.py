"""The public API of qsplan.mechanics: one list, each name once, every name importable, the import light."""

import subprocess
import sys

import pytest

import qsplan.mechanics as mechanics


def test_all_has_no_duplicates():
    seen = set()
    duplicates = [n for n in mechanics.__all__ if n in seen or seen.add(n)]
    assert duplicates == []


@pytest.mark.parametrize("name", sorted(mechanics.__all__))
def test_every_public_name_resolves(name):
    assert getattr(mechanics, name) is not None


def test_infrastructure_is_not_public():
    assert "map_chunks" not in mechanics.__all__
    from qsplan.mechanics.parallel import map_chunks  # still importable from its module

    assert callable(map_chunks)


def test_import_stays_light():
    code = "import sys, qsplan.mechanics; print(sorted(m for m in ('scipy', 'shapely', 'matplotlib') if m in sys.modules))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip()
    assert out == "[]"


@pytest.mark.parametrize("package", ["model", "modes", "solver", "muspace", "bands", "motion", "crosscheck"])
def test_every_subpackage_documents_its_modules(package):
    import importlib

    doc = importlib.import_module(f"qsplan.mechanics.{package}").__doc__
    assert doc and "eq" in doc
