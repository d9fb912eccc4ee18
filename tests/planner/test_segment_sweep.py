"""The dense sweep that replaced OMPL on in-contact segments judges every sample as the per-state
validity checker does (:func:`check_contact_state`, the reference), on seeded random segments.

Seeded segments of the demo hand: random start, length, direction, effort finger, friction range and
torque resolution, some reaching where the band closes or no grasp exists; 25 samples each.
"""

import numpy as np
import pytest

from qsplan.hands import default_hand
from qsplan.planner.plan.scripted import sweep_contact_segment
from qsplan.planner.states.contact import check_contact_state, contact_samples
from qsplan.planner.task.task import make_task
from qsplan.planner.torque.sweep import competing_modes

#: Seeded cases (each 25 configurations, compared one by one).
CASES = 10


def _case(seed):
    rng = np.random.default_rng([13, seed])
    x0 = float(rng.uniform(-0.03, 0.02))
    x1 = float(np.clip(x0 + rng.choice([-1, 1]) * rng.uniform(0.005, 0.03), -0.05, 0.045))
    mu_hi = float(rng.choice([0.1, 0.2, 0.3]))
    resolution = float(rng.choice([0.01, 0.05, 0.15, 0.3]))
    effort = str(rng.choice(["left", "right"]))
    return make_task(default_hand(), x0, [x1], mu_range=(0.0, mu_hi), torque_resolution=resolution), x0, x1, effort


@pytest.mark.parametrize("seed", range(CASES))
def test_sweep_finds_the_first_invalid_sample_of_the_reference(seed):
    task, x0, x1, effort = _case(seed)
    direction = float(np.sign(x1 - x0))
    # the start's contacts and competitors, from the part of the line that has a grasp
    line = np.linspace(x0, x1, 9)
    for m in range(9, 1, -1):
        try:
            base = contact_samples(task, line[:m], effort, direction * task.workpiece_speed)
            break
        except Exception:
            continue
    else:
        pytest.skip("no grasp at the start")
    touching, comps = base.touching[0], competing_modes(base)
    xs = np.linspace(x0, x1, 25)
    ref = [check_contact_state(task, x, effort, direction, touching, comps) for x in xs]
    k_ref = next((k for k, c in enumerate(ref) if not c.ok), None)
    k, S, band, speed, _ = sweep_contact_segment(task, "case", xs, effort, direction, touching, comps)
    assert k == k_ref, (k, k_ref, ref[k_ref].reason if k_ref is not None else None)
    if k is None:
        lo = np.array([c.lower for c in ref])
        hi = np.array([c.upper for c in ref])
        assert np.array_equal(np.isinf(band.lower), np.isinf(lo)) and np.array_equal(np.isinf(band.upper), np.isinf(hi))
        fin = np.isfinite(lo) & np.isfinite(hi)
        np.testing.assert_allclose(band.lower[fin], lo[fin], rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(band.upper[fin], hi[fin], rtol=1e-9, atol=1e-12)
        assert 0 < speed <= task.workpiece_speed and np.array_equal(S.touching, np.repeat(touching[None], 25, 0))


def test_cases_cover_valid_and_invalid_segments():
    """The seeded cases exercise both outcomes (else the comparison above proves little)."""
    outcomes = set()
    for seed in range(CASES):
        task, x0, x1, effort = _case(seed)
        d = float(np.sign(x1 - x0))
        outcomes.add(all(check_contact_state(task, x, effort, d).ok for x in (x0, 0.5 * (x0 + x1), x1)))
    assert outcomes == {True, False}
