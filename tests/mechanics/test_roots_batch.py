"""roots_batch gives numpy's polyroots roots, bit for bit (the shared bands' exactness rests on the same roots)."""

import numpy as np
import pytest

from qsplan.mechanics.bands.roots import roots_batch


def _polyroots(c):
    return np.polynomial.polynomial.polyroots(c)


def test_random_polynomials_of_mixed_sizes_bit_for_bit():
    rng = np.random.default_rng(7)
    coefs = [rng.normal(size=rng.integers(1, 9)) * 10.0 ** rng.integers(-8, 8) for _ in range(400)]
    coefs += [np.array([1.0, -3.0, 3.0, -1.0]), np.array([2.0, 0.0, 0.0]), np.array([0.0, 0.0]), np.array([5.0]),
              np.array([1.0, 0.0, 1.0, 0.0, 0.0]), np.array([-2.0, 1.0])]  # fmt: skip
    for c, got in zip(coefs, roots_batch(coefs)):
        want = _polyroots(c)
        assert got.shape == want.shape
        np.testing.assert_array_equal(np.asarray(got, complex), np.asarray(want, complex))


def test_a_nan_coefficient_raises_as_polyroots_does():
    with pytest.raises(np.linalg.LinAlgError):
        _polyroots([1.0, np.nan, 1.0])
    with pytest.raises(np.linalg.LinAlgError):
        roots_batch([np.array([1.0, np.nan, 1.0])])


def test_critical_polynomial_is_numpys_bit_for_bit():
    from qsplan.mechanics.bands.roots import critical_polynomial

    P = np.polynomial.polynomial
    rng = np.random.default_rng(3)
    for _ in range(500):
        n0, n1 = (rng.normal(size=rng.integers(1, 8)) for _ in range(2))
        if rng.random() < 0.2:
            n0[-1] = 0.0
        want = P.polysub(P.polymul(P.polyder(n0), n1), P.polymul(n0, P.polyder(n1)))
        np.testing.assert_array_equal(critical_polynomial(n0, n1), want)
