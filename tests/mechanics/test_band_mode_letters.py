"""Every public band and preclusion function takes a mode as letters or as a ContactMode (issue 21, item 12).

Letters give the same answer as the ContactMode; a mode that does not fit the scene is a ModeError
naming ``mode`` (bad letter, wrong count, wrong number of constraints for eq. 29), never an
AttributeError or IndexError.
"""

import numpy as np
import pytest

from qsplan.mechanics import (
    ModeError,
    effort_band,
    effort_bands,
    guaranteed_band_box,
    guaranteed_band_shared,
    planted_scene,
    possible_band_box,
    robust_band,
    sampled_band,
)
from qsplan.mechanics.bands.batched import state_batch
from qsplan.mechanics.bands.batched_robust import admissible_competitors_batch, robust_band_arrays, robust_bands
from qsplan.mechanics.bands.preclusion import competitor_torques
from qsplan.mechanics.bands.robust import admissible_competitors

SCENE, MODE = planted_scene(np.random.default_rng(5), 4, 1)  # one effort joint (dof 4); MODE is RBRB
MU = (0.2, 0.3)

CALLS = {
    "effort_band": lambda m: effort_band(SCENE, m),
    "effort_bands": lambda m: effort_bands(SCENE, m, [SCENE.mu]),
    "guaranteed_band_box": lambda m: guaranteed_band_box(SCENE, m, *MU),
    "guaranteed_band_shared": lambda m: guaranteed_band_shared(SCENE, m, *MU),
    "possible_band_box": lambda m: possible_band_box(SCENE, m, *MU),
    "sampled_band": lambda m: sampled_band(SCENE, m, list(MU)),
    "robust_band": lambda m: robust_band(SCENE, m, MU),
    "admissible_competitors": lambda m: admissible_competitors([SCENE], m),
    "competitor_torques": lambda m: competitor_torques(SCENE, m, *MU, -1.0, 1.0),
    "robust_bands": lambda m: robust_bands([SCENE], m, MU),
    "robust_band_arrays": lambda m: robust_band_arrays(state_batch([SCENE]), m, MU),
    "admissible_competitors_batch": lambda m: admissible_competitors_batch(state_batch([SCENE]), m),
}


def _same(a, b):
    """Two results equal field by field (NaN equal to NaN; arrays elementwise)."""
    if isinstance(a, (tuple, list)):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b))
    if isinstance(a, np.ndarray):
        return np.array_equal(a, b, equal_nan=True)
    if hasattr(a, "__slots__") and not isinstance(a, str):
        return all(_same(getattr(a, f), getattr(b, f)) for f in a.__slots__)
    if isinstance(a, dict):
        return a.keys() == b.keys() and all(_same(a[k], b[k]) for k in a)
    if isinstance(a, float) and np.isnan(a):
        return isinstance(b, float) and np.isnan(b)
    return a == b


@pytest.mark.parametrize("name", CALLS)
def test_letters_give_the_contact_mode_answer(name):
    call = CALLS[name]
    assert _same(call(MODE.letters), call(MODE))
    assert _same(call(MODE.letters.lower()), call(MODE))


def test_effort_band_of_letters_is_the_feasible_planted_band():
    band = effort_band(SCENE, MODE.letters)
    assert band.feasible and band.mode == MODE.letters
    assert band.contains(float(SCENE.joint_effort[SCENE.effort_controlled][0]))


@pytest.mark.parametrize("name", CALLS)
def test_wrong_letter_count_names_mode(name):
    with pytest.raises(ModeError, match=r"mode: expected 4 letters \(one per contact\); got 'SSS'"):
        CALLS[name]("SSS")


@pytest.mark.parametrize("name", CALLS)
def test_unknown_letter_names_mode(name):
    with pytest.raises(ModeError, match=r"mode: expected letters R, S or B \(one per contact\); got 'XBRR'"):
        CALLS[name]("XBRR")


@pytest.mark.parametrize("name", CALLS)
def test_wrong_constraint_count_names_mode(name):
    with pytest.raises(ModeError, match=r"mode RRRR: has 8 applicable constraints but the scene's partition needs 4"):
        CALLS[name]("RRRR")
