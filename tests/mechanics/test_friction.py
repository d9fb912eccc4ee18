"""The one friction validator (eq. 8), the letter and status codes, and the shared slack of eq. (28)."""

import numpy as np
import pytest

from qsplan.mechanics import SceneError, Status
from qsplan.mechanics.model.friction import check_friction, check_mu_range
from qsplan.mechanics.modes.contact_mode import LETTERS, Letter, codes_to_letters, letters_to_codes
from qsplan.mechanics.modes.equilibrium import coulomb_slacks, sliding_friction, worst_slack
from qsplan.mechanics.numerics import StatusCode


def test_check_friction_accepts_and_converts():
    assert check_friction(0.3) == 0.3 and isinstance(check_friction(0), float)
    np.testing.assert_array_equal(check_friction([0.0, 0.5]), [0.0, 0.5])


@pytest.mark.parametrize(
    "mu,kwargs,match",
    [
        (-0.1, {}, r"mu: expected a nonnegative friction coefficient; got -0.1"),
        (float("nan"), {"field": "x.mu"}, r"x\.mu: expected a nonnegative friction coefficient"),
        ([0.1, -1.0], {}, r"mu: expected nonnegative finite friction coefficients; got \[0.1, -1.0\]"),
        ([0.1, np.inf], {"element": "contacts[{i}].mu"}, r"contacts\[1\]\.mu: expected a nonnegative"),
        ("high", {}, r"mu: expected nonnegative finite friction coefficients; got 'high'"),
    ],
)
def test_check_friction_names_the_field(mu, kwargs, match):
    with pytest.raises(SceneError, match=match):
        check_friction(mu, **kwargs)


def test_check_mu_range():
    assert check_mu_range(0, 0.5) == (0.0, 0.5)
    lo, hi = check_mu_range(0.1, [0.2, 0.3], n=2)
    np.testing.assert_array_equal(lo, [0.1, 0.1])
    np.testing.assert_array_equal(hi, [0.2, 0.3])


@pytest.mark.parametrize(
    "lo,hi,kwargs,match",
    [
        (0.5, 0.1, {}, r"mu range: expected 0 <= LO <= HI \(finite\); got 0.5 0.1"),
        (-0.1, 0.1, {"field": "friction.range"}, r"friction\.range: expected 0 <= LO"),
        (0.0, np.inf, {}, r"mu range"),
        ([0.0, 0.0, 0.0], [1.0, 1.0], {"n": 3}, r"mu range: expected 0 <= LO"),
    ],
)
def test_check_mu_range_rejects(lo, hi, kwargs, match):
    with pytest.raises(SceneError, match=match):
        check_mu_range(lo, hi, **kwargs)


def test_letter_and_status_codes_are_one_table_each():
    assert LETTERS == "BRS" and [int(c) for c in Letter] == [0, 1, 2]
    assert codes_to_letters(letters_to_codes("RBSS")) == "RBSS"
    assert tuple(Status.ORDER[c] for c in StatusCode) == Status.ORDER


def test_worst_slack_is_eq_28():
    codes = letters_to_codes("RSB")[None]
    mu = np.array([[0.5, 0.2, 0.9]])
    c_n = np.array([[2.0, 1.0, 0.0]])
    c_t = np.array([[0.4, sliding_friction(0.2, -1, 1.0), 0.0]])
    plus, minus = coulomb_slacks(mu, c_n, c_t)
    assert worst_slack(codes, mu, c_n, c_t)[0] == pytest.approx(min(plus[0, 0], minus[0, 0], 2.0, 1.0))
    assert c_t[0, 1] == pytest.approx(0.2)  # eq. (17): -mu xi c_n with xi = -1
