"""Guaranteed bands of the reorientation (issue 23) against the all-modes solver the certifier uses.

The scenes come from the paper hand's closed form (``tests/reference/paper_pivot.py``), derived apart from the
planner's formation search.

At the flush instant ending the demo's slide (five contacts) the transition mode BSSSS (vertex 0 lifts, the workpiece
pivots on vertex 1) has a robust band (:func:`qsplan.mechanics.robust_band`, every admissible competitor precluded);
along the pivot formation the 4S mode has one.  Inside a band the certifier's mode check
(:func:`qsplan.planner.certify.modes.mode_checks`: :func:`qsplan.mechanics.solve_many` at every friction vector,
modes degenerate to machine precision set aside) must find the desired mode and nothing else at the friction box's
vertices and random points, near each finite edge and far along an unbounded side; just outside a finite edge it
must find a failure (the edge is exact, not conservative).
"""

from __future__ import annotations

from dataclasses import replace
from functools import lru_cache
from itertools import product

import numpy as np
import pytest

from qsplan.mechanics import DEFAULT_TOLERANCES, robust_band, solve_many
from qsplan.planner.certify.modes import mode_checks
from qsplan.planner.task.task import demo_task_path, load_task

from tests.reference.paper_pivot import (PIVOT, TRANSITION, flush_instant, pivot_band, pivot_configurations,
                                         pivot_scene, transition_scene)  # fmt: skip

#: N m inside a finite band edge at which the mode is checked: above the band edges' rounding (~1e-14 relative) and
#: the solver's decisions, far below any torque resolution.
INSIDE = 1e-6
#: N m outside a finite edge at which the check must fail: an exact edge has nothing beyond it.
OUTSIDE = 1e-3
#: N m along an unbounded side: far from the finite edge (some 30 times the transition's torques).
FAR = 100.0
#: Random friction vectors per check (the brief's 40), besides every vertex of the box.
N_RANDOM = 40


@lru_cache(maxsize=None)
def _task():
    return load_task(demo_task_path())


def _frictions(n_contacts, seed):
    lo, hi = _task().mu_range
    rng = np.random.default_rng(seed)
    return np.vstack([np.array(list(product((lo, hi), repeat=n_contacts))), rng.uniform(lo, hi, (N_RANDOM, n_contacts))])


def _failures(scene, mode, tau, margin, seed):
    """The certifier's mode check at effort ``tau`` (every vertex and N_RANDOM random friction vectors), and where
    ``margin`` is given, every sliding or rolling contact's normal force below ``margin.normal`` (breaking contacts
    carry none)."""
    s = replace(scene, joint_effort=np.where(scene.effort_controlled, tau, np.nan))
    mus = _frictions(scene.n_contacts, seed)
    cols = {"mode": np.array([mode]), "y_workpiece": np.array([0.0])}
    found, _ = mode_checks(_task(), cols, 0, mus, 0.0, scene=s)
    if margin is not None:
        sv = solve_many(s, mus, DEFAULT_TOLERANCES)
        j = sv.letters.index(mode)
        held = [i for i, letter in enumerate(mode) if letter != "B"]
        ok = sv.codes[:, j] == 0
        low = sv.c_n[ok, j][:, held].min(initial=np.inf)
        if low < margin.normal * (1 - 1e-9):
            found.append(("force margin", f"normal force {low:.4g} N below {margin.normal:g} N"))
    return found


def _edge_checks(scene, mode, band, margin, seed):
    """The band's mode alone just inside each finite edge and far along each unbounded side; a failure just outside
    each finite edge."""
    assert band.feasible and band.exact
    inside = []
    for edge, sign in ((band.lower, 1.0), (band.upper, -1.0)):
        if np.isfinite(edge):
            inside.append(edge + sign * INSIDE)
            assert _failures(scene, mode, edge - sign * OUTSIDE, margin, seed), f"nothing fails just outside {edge}"
        else:
            finite = band.upper if sign > 0 else band.lower
            inside.append(finite - sign * FAR)
    for tau in inside:
        assert _failures(scene, mode, tau, margin, seed) == [], tau


def _margin(with_margin):
    return _task().force_margin if with_margin else None


@pytest.mark.parametrize("with_margin", [False, True])
@pytest.mark.parametrize("effort_joint", ["right", "left"])
def test_transition_band_is_the_only_mode_at_every_checked_friction(effort_joint, with_margin):
    task, hand = _task(), _task().hand
    scene = transition_scene(hand, flush_instant(hand), effort_joint)
    mode = TRANSITION.mode
    assert mode == "BSSSS"
    band = robust_band(scene, mode, task.mu_range, force_margin=_margin(with_margin))
    _edge_checks(scene, mode, band, _margin(with_margin), seed=23)


def test_transition_band_reproduces_the_issue():
    task, hand = _task(), _task().hand
    fi = flush_instant(hand)
    mode = TRANSITION.mode
    right = [robust_band(transition_scene(hand, fi, "right"), mode, task.mu_range, force_margin=m)
             for m in (None, task.force_margin)]  # fmt: skip
    left = robust_band(transition_scene(hand, fi, "left"), mode, task.mu_range)
    assert task.force_margin.normal == 0.05
    # the issue's numbers, to the digits it prints
    assert (right[0].lower, right[0].upper) == (pytest.approx(3.655, abs=5e-4), np.inf)
    assert (right[1].lower, right[1].upper) == (pytest.approx(3.899, abs=5e-4), np.inf)
    assert (left.lower, left.upper) == (-np.inf, pytest.approx(-2.721, abs=5e-4))
    assert all(b.exact for b in (*right, left))


@pytest.mark.parametrize("effort_joint", ["right", "left"])
def test_bands_depend_on_the_turning_direction_only(effort_joint):
    """The quasistatic model is positively homogeneous in the velocities: the rate's size does not change a band."""
    task, hand = _task(), _task().hand
    fi = flush_instant(hand)
    mode = TRANSITION.mode
    slow, fast = (robust_band(transition_scene(hand, fi, effort_joint, theta_rate=r), mode, task.mu_range)
                  for r in (-0.01, -0.4))  # fmt: skip
    assert slow.lower == pytest.approx(fast.lower, rel=1e-9) and slow.upper == pytest.approx(fast.upper, rel=1e-9)


@pytest.mark.parametrize("theta_deg, effort_joint", [(-10.0, "right"), (-10.0, "left"), (-36.0, "right"),
                                                     (-45.0, "right"), (-45.0, "left"), (-46.0, "right"),
                                                     (-48.5, "right")])  # fmt: skip
def test_pivot_band_is_the_only_mode_at_every_checked_friction(theta_deg, effort_joint):
    task, hand = _task(), _task().hand
    theta = np.radians(theta_deg)
    band = pivot_band(hand, theta, effort_joint, task.mu_range, task.force_margin)
    scene = pivot_scene(hand, pivot_configurations(hand, [theta]), 0, effort_joint)
    _edge_checks(scene, PIVOT.mode, band, task.force_margin, seed=int(-theta_deg * 10))


def test_pivot_bands_along_the_turn():
    """Both fingers' 4S bands (the task's force margin) every degree of the closed-form pivot: exact; the right finger's
    unbounded above while the centre of mass lies left of the pivot vertex (the weight resists the tipping; past it a
    push can be too strong); its width falls below the resolution once, at the issue's -48.98 deg (where the formation
    search's second piece stops: tests/planner/test_reorient_route.py), and stays below to -54 deg; the left finger's
    band closes once and does not reopen."""
    from scipy.optimize import brentq

    task, hand = _task(), _task().hand
    theta = np.radians(np.arange(-1.0, -54.5, -1.0))
    right = [pivot_band(hand, t, "right", task.mu_range, task.force_margin) for t in theta]
    left = [pivot_band(hand, t, "left", task.mu_range, task.force_margin) for t in theta]
    assert all(b.exact for b in right + left) and all(b.feasible for b in right)

    def com_right_of_pivot(t):  # m: the centre of mass's x minus the pivot vertex's
        c = pivot_configurations(hand, t)
        return c.pose[..., 0] - c.vertices[:, c.pivot, 0]

    before = com_right_of_pivot(theta) < 0.0
    com = brentq(lambda t: com_right_of_pivot([t])[0], theta[0], theta[-1])
    assert np.degrees(com) == pytest.approx(-40.32, abs=5e-3)
    upper = np.array([b.upper for b in right])
    assert np.all(np.isinf(upper[before])) and np.any(np.isfinite(upper[~before]))
    width = np.array([b.width for b in right])
    narrow = width < task.torque_resolution
    k = int(np.argmax(narrow))
    assert 0 < k and np.all(narrow[k:]) and not np.any(narrow[:k])
    at = brentq(lambda t: pivot_band(hand, t, "right", task.mu_range, task.force_margin).width - task.torque_resolution,
                theta[k - 1], theta[k])  # fmt: skip
    assert np.degrees(at) == pytest.approx(-48.98, abs=5e-3)
    closed = np.array([not b.feasible for b in left])
    j = int(np.argmax(closed))
    assert 0 < j and np.all(closed[j:]) and not np.any(closed[:j])


def test_the_certifier_s_force_margin_binds_the_contacts_the_mode_keeps():
    """BSSSS breaks palm:0 (no force there by definition): the certifier's force-margin check binds the four
    contacts the mode keeps, so just inside the margin's band it finds nothing, and just outside it names one."""
    task, hand = _task(), _task().hand
    scene = transition_scene(hand, flush_instant(hand), "right")
    mode = TRANSITION.mode
    band = robust_band(scene, mode, task.mu_range, force_margin=task.force_margin)
    mus = _frictions(scene.n_contacts, 5)
    cols = {"mode": np.array([mode]), "y_workpiece": np.array([0.0])}
    for tau, clean in ((band.lower + INSIDE, True), (band.lower - OUTSIDE, False)):
        s = replace(scene, joint_effort=np.where(scene.effort_controlled, tau, np.nan))
        found, _ = mode_checks(task, cols, 0, mus, task.force_margin.normal, scene=s)
        assert (found == []) is clean, (tau, found)
