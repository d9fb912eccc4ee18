"""Friction ranges of any width down to zero (issue 21, item 8): a band, never a LinAlgError.

The shared coefficient's polynomials were fitted in powers of mu, singular for a range like
``[0, 1e-100]`` or ``[0.3, 0.30001]``; they are fitted on ``[-1, 1]`` now.  For every range the
guaranteed band is checked against the point bands at its ends and inside it (it must lie in each,
to rounding), the preclusion and the batched path answer as for a wide range, and ``qsplan band``
prints one line.
"""

import json
import subprocess
import sys

import numpy as np
import pytest

from qsplan.mechanics import effort_bands, guaranteed_band_shared, planted_scene, robust_band, scene_to_dict
from qsplan.mechanics.bands.batched import guaranteed_bands_shared, state_batch
from qsplan.mechanics.bands.batched_robust import robust_bands
from qsplan.mechanics.bands.preclusion import competitor_torques
from tests.mechanics.test_bands_batched import band_key, robust_key, same

#: ``(lo, hi)``: ranges from a few ulps to the smallest positive double wide, at 0 and away from it.
RANGES = [(0.0, 1e-100), (0.0, 5e-324), (0.0, 1e-300), (0.3, 0.3 + 1e-16), (0.3, float(np.nextafter(0.3, 1.0))),
          (0.3, 0.30001), (0.1, 0.1 + 1e-9), (0.2, 0.25)]  # fmt: skip
#: A band edge may differ from the point bands' by rounding of this size (relative to the edge, or 1 N m):
#: the polynomials reproduce the rows to ~1e-15 of their scale.
EDGE_RTOL = 1e-9
N_SCENES = 24


def _scenes():
    for k in range(N_SCENES):
        rng = np.random.default_rng([21, 8, k])
        scene, planted = planted_scene(rng, int(rng.integers(3, 6)), 1)
        yield scene, planted.letters


def _inside(band, lower, upper, ok):
    """The band lies in every point band ``[lower, upper]`` (all ``ok``), to rounding."""
    scale = max([abs(x) for x in (band.lower, band.upper) if np.isfinite(x)] + [1.0])
    return bool(np.all(ok) and np.all(lower <= band.lower + EDGE_RTOL * scale) and np.all(band.upper <= upper + EDGE_RTOL * scale))


@pytest.mark.parametrize(("lo", "hi"), RANGES)
def test_shared_band_of_a_narrow_range_is_guaranteed_over_it(lo, hi):
    judged = same_point = 0
    for scene, mode in _scenes():
        band = guaranteed_band_shared(scene, mode, lo, hi)
        mus = np.repeat(np.unique(np.linspace(lo, hi, 9))[:, None], scene.n_contacts, axis=1)
        lower, upper, ok = effort_bands(scene, mode, mus)
        if band.feasible:
            assert _inside(band, lower, upper, ok), (mode, band)
            judged += 1
        if ok.all() and np.allclose(lower, lower[0], rtol=1e-14, atol=0) and np.allclose(upper, upper[0], rtol=1e-14, atol=0) \
                and upper[0] - lower[0] > 1e-6:
            # the rows do not tell the range's frictions apart: the band is, in effect, the one at lo
            assert band.feasible and band.lower == pytest.approx(lower[0], rel=EDGE_RTOL, abs=EDGE_RTOL)
            assert band.upper == pytest.approx(upper[0], rel=EDGE_RTOL, abs=EDGE_RTOL)
            same_point += 1
    assert judged >= N_SCENES // 3
    assert same_point > 0 or hi - lo > 1e-12  # the ranges narrower than rounding reach the comparison


def _close(a, b):
    if not (np.isfinite(a) and np.isfinite(b)):
        return a == b or (np.isnan(a) and np.isnan(b))
    return abs(a - b) <= EDGE_RTOL * max(abs(a), abs(b), 1.0)


@pytest.mark.parametrize(("lo", "hi"), [(0.0, 1e-100), (0.0, 5e-324), (0.3, float(np.nextafter(0.3, 1.0)))])
def test_preclusion_and_the_batched_path_over_a_narrow_range(lo, hi):
    """Batched as per state; and, the range being narrower than rounding, the answer at the point ``lo``."""
    groups = {}
    for s, mode in _scenes():
        groups.setdefault((s.n_contacts, s.effort_controlled.tobytes()), (mode, []))[1].append(s)
    bands = 0
    for mode, group in groups.values():
        got = robust_bands(group, mode, (lo, hi), shared=True)
        shared = guaranteed_bands_shared(state_batch(group), mode, lo, hi)
        for s, g, b in zip(group, got, shared):
            ref = robust_band(s, mode, (lo, hi), shared=True)
            assert same(robust_key(g), robust_key(ref)) and same(band_key(b), band_key(guaranteed_band_shared(s, mode, lo, hi)))
            point = robust_band(s, mode, (lo, lo), shared=True)
            assert (ref.feasible, ref.exact) == (point.feasible, point.exact)
            assert _close(ref.lower, point.lower) and _close(ref.upper, point.upper)
            for c, ct in ref.precluded.items():
                pt = competitor_torques(s, c, lo, lo, ref.desired.lower, ref.desired.upper, shared=True)
                assert ct.empty == pt.empty and _close(ct.lower, pt.lower) and _close(ct.upper, pt.upper), c
            bands += ref.feasible
    assert bands > 0


@pytest.fixture(scope="module")
def band_scene(tmp_path_factory):
    scene, mode = next(_scenes())
    path = tmp_path_factory.mktemp("narrow") / "scene.json"
    path.write_text(json.dumps(scene_to_dict(scene)))
    return path, mode


@pytest.mark.parametrize("hi", ["1e-100", "5e-324"])
def test_band_command_over_a_narrow_shared_range(band_scene, hi):
    path, mode = band_scene
    cmd = [sys.executable, "-m", "qsplan.planner.cli", "band", str(path), "--mode", mode, "--mu-range", "0", hi, "--shared-mu"]
    text = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    assert text.returncode == 0 and text.stderr == "", text.stderr
    assert text.stdout.startswith(f"mode {mode} ") and f"for one shared mu in [0.0, {float(hi)}]" in text.stdout
    doc = json.loads(subprocess.run(cmd + ["--json"], capture_output=True, text=True, timeout=120, check=True).stdout)
    assert doc["mode"] == mode and doc["method"] == "shared-roots" and doc["exact"] is True


@pytest.mark.slow
@pytest.mark.parametrize("shared", ["true", "false"])
def test_plan_of_a_task_with_a_narrow_friction_range(tmp_path, shared):
    """The bundled demo task with ``[friction] range = [0, 1e-100]``: planned and certified (or a one-line refusal)."""
    from qsplan.planner import task_paths

    text = task_paths()["demo_task"].read_text()
    assert "range = [0.0, 0.2]" in text and "shared = false" in text
    task = tmp_path / "narrow.toml"
    task.write_text(text.replace("range = [0.0, 0.2]", "range = [0.0, 1e-100]").replace("shared = false", f"shared = {shared}"))
    cmd = [sys.executable, "-m", "qsplan.planner.cli", "plan", str(task), "--out", str(tmp_path / "out")]
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    assert "Traceback" not in r.stderr and r.returncode in (0, 2), r.stderr[-2000:]
    if r.returncode == 0:
        assert "certified:" in r.stdout and "no violation" in r.stdout
    else:
        assert r.stderr.startswith("qsplan: error: ") and len(r.stderr.splitlines()) == 1
