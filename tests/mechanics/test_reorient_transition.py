"""Guaranteed bands of the reorientation (issue 23) against the all-modes solver the certifier uses.

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

from qsplan.hands.formations import formation
from qsplan.hands.pivot_sweep import pivot_band, sweep_pivot
from qsplan.hands.reorient import (PIVOT_FORMATION, TRANSITION_FORMATION, flush_instant, pivot_configurations,
                                   pivot_scene, transition_scene)  # fmt: skip
from qsplan.mechanics import DEFAULT_TOLERANCES, robust_band, solve_many
from qsplan.planner.certify.modes import mode_checks
from qsplan.planner.task.task import demo_task_path, load_task

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
    mode = formation(TRANSITION_FORMATION).mode
    assert mode == "BSSSS"
    band = robust_band(scene, mode, task.mu_range, force_margin=_margin(with_margin))
    _edge_checks(scene, mode, band, _margin(with_margin), seed=23)


def test_transition_band_reproduces_the_issue():
    task, hand = _task(), _task().hand
    fi = flush_instant(hand)
    mode = formation(TRANSITION_FORMATION).mode
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
    mode = formation(TRANSITION_FORMATION).mode
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
    _edge_checks(scene, formation(PIVOT_FORMATION).mode, band, task.force_margin, seed=int(-theta_deg * 10))


@pytest.mark.slow
def test_pivot_sweep_bands_and_their_events():
    task, hand = _task(), _task().hand
    sweep = sweep_pivot(hand, task.mu_range, task.force_margin, task.torque_resolution, limits=task.joint_limits)
    events = {e.name: e.theta for e in sweep.events}
    theta = sweep.configurations.theta
    right, left = sweep.bands["right"], sweep.bands["left"]
    assert right.exact.all() and left.exact.all()
    # the right finger pushes: its band is unbounded above while the centre of mass lies left of the pivot (the
    # weight resists the tipping); past it a push can be too strong
    before = theta > events["com"]
    assert np.all(np.isinf(right.upper[before])) and np.any(np.isfinite(right.upper[~before]))
    # the band events: the width crosses the resolution there, and stays below it to the formation's end
    for name, bands in (("band_right", right), ("band_left", left)):
        at = events[name]
        widths = [pivot_band(hand, t, bands.effort_joint, task.mu_range, task.force_margin) for t in (at + 1e-5, at - 1e-5)]
        w = [b.width if b.feasible else 0.0 for b in widths]
        assert w[0] > task.torque_resolution > w[1]
        assert np.all(bands.width[theta < at] < task.torque_resolution)
        assert np.all(bands.width[theta > at] >= task.torque_resolution)
    for name in ("band_closed_right", "band_closed_left"):  # no band past the event, a band before it
        at = events[name]
        assert [pivot_band(hand, t, name.rpartition("_")[2], task.mu_range, task.force_margin).feasible
                for t in (at + 1e-5, at - 1e-5)] == [True, False]  # fmt: skip
    assert events["right_flush_12"] < events["band_right"] < events["slip_right"] < events["com"] < events["left_tip"] < 0.0


def test_the_certifier_s_force_margin_binds_the_contacts_the_mode_keeps():
    """BSSSS breaks palm:0 (no force there by definition): the certifier's force-margin check binds the four
    contacts the mode keeps, so just inside the margin's band it finds nothing, and just outside it names one."""
    task, hand = _task(), _task().hand
    scene = transition_scene(hand, flush_instant(hand), "right")
    mode = formation(TRANSITION_FORMATION).mode
    band = robust_band(scene, mode, task.mu_range, force_margin=task.force_margin)
    mus = _frictions(scene.n_contacts, 5)
    cols = {"mode": np.array([mode]), "y_workpiece": np.array([0.0])}
    for tau, clean in ((band.lower + INSIDE, True), (band.lower - OUTSIDE, False)):
        s = replace(scene, joint_effort=np.where(scene.effort_controlled, tau, np.nan))
        found, _ = mode_checks(task, cols, 0, mus, task.force_margin.normal, scene=s)
        assert (found == []) is clean, (tau, found)
