"""stdout carries only qsplan's output: no external library writes there (issue 21, item 4).

highspy prints a banner on file descriptor 1 when its first solver is built, which
``contextlib.redirect_stdout`` cannot catch; the pruned mode search builds one.  These tests run
the CLI in a fresh process (the banner is printed once per process) on a scene large enough for
the pruned search, with ``--search prune`` and with the default ``auto``.
"""

import json
import subprocess
import sys

import numpy as np
import pytest

from qsplan.mechanics import planted_scene, scene_to_dict

#: A scene whose default search (``auto``) prunes breaking sets by programmes: n_c = 14 contacts,
#: 4 effort joints (45,474 modes, eq. 49), about a second a run.
N_CONTACTS, N_EFFORT = 14, 4

#: Words of the banners HiGHS prints ("Running HiGHS 1.16.0 ...: Copyright (c) ...").
BANNER_WORDS = ("HiGHS", "Copyright")


@pytest.fixture(scope="module")
def big_scene(tmp_path_factory):
    scene, planted = planted_scene(np.random.default_rng([21, N_CONTACTS, N_EFFORT]), N_CONTACTS, N_EFFORT)
    path = tmp_path_factory.mktemp("stdout") / "n14.json"
    path.write_text(json.dumps(scene_to_dict(scene)))
    return path, planted


def _modes(path, *args):
    cmd = [sys.executable, "-m", "qsplan.planner.cli", "modes", str(path), "--workers", "1", *args]
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    return r


@pytest.mark.parametrize("search", [[], ["--search", "prune"]], ids=["auto", "prune"])
def test_json_output_is_json_when_the_pruned_search_runs(big_scene, search):
    path, planted = big_scene
    doc = json.loads(_modes(path, "--json", *search).stdout)  # the whole of stdout
    assert planted.letters in [m["mode"] for m in doc["feasible"]]
    pruned = sum(v for k, v in doc["counts"].items() if k.startswith("pruned"))
    assert pruned > 0.5 * doc["modes_tested"]  # the pruned search ran (its programmes build the solver)


@pytest.mark.parametrize("search", [[], ["--search", "prune"]], ids=["auto", "prune"])
def test_text_output_has_no_banner(big_scene, search):
    path, planted = big_scene
    r = _modes(path, *search)
    assert r.stdout.startswith(f"scene {path}: {N_CONTACTS} contacts")
    assert planted.letters in r.stdout
    assert not any(word in r.stdout for word in BANNER_WORDS)

