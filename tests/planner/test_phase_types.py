"""A plan's phases are typed (issue 32): :class:`SlidePhase`, :class:`HoldPhase`, :class:`PivotPhase` (in contact,
:class:`ContactSegmentPlan` their base) and :class:`RegraspPhase`; what differs per kind is a type's fields, class
attributes and methods, and the old names and the ``kind`` strings still read as before."""

from __future__ import annotations

import pickle
from dataclasses import FrozenInstanceError, replace

import numpy as np
import pytest
from qsplan.planner.plan.results import (
    ContactSegmentPlan,
    HoldPhase,
    PivotPhase,
    RegraspPhase,
    RegraspPlan,
    SlidePhase,
)

N = 4
REST = 0.0125  # m, a made-up rest height


def _common(n=N, mode="SSSS"):
    """The fields every in-contact phase has, positionally as ``ContactSegmentPlan`` took them."""
    x = np.linspace(0.0, 0.003, n)
    q = np.column_stack([np.linspace(2.0, 2.1, n), np.linspace(1.0, 1.1, n)])
    lo, hi = np.full(n, 0.1), np.full(n, 0.3)
    return ("p", "right", mode, x[[0, -1]], np.linspace(0.0, 1.0, n), x, q, np.zeros((n, 2)), lo, hi,
            0.5 * (lo + hi), np.full(n, 0.1), (), 0.003, None)  # fmt: skip


def test_the_old_name_builds_a_slide_that_reads_as_before():
    ph = ContactSegmentPlan(*_common())
    assert type(ph) is SlidePhase and isinstance(ph, ContactSegmentPlan)
    assert ph.kind == "slide" and ph.formation == "palm_edge" and ph.in_contact
    assert ph.pose is None and ph.row_modes is None and ph.contacts is None  # the slide's, read as before
    assert ph.modes() == ("SSSS",) * N
    np.testing.assert_array_equal(ph.poses(REST), np.column_stack([ph.x, np.full(N, REST), np.zeros(N)]))
    with pytest.raises((FrozenInstanceError, AttributeError, TypeError)):
        ph.kind = "hold"  # read-only
    with pytest.raises(TypeError):
        ContactSegmentPlan(*_common(), kind="hold")  # the kind is the type now, not an argument
    again = pickle.loads(pickle.dumps(replace(ph, speed=0.004)))
    assert type(again) is SlidePhase and again.speed == 0.004


def test_each_kind_says_what_it_does():
    pose = np.tile([0.01, REST, -0.3], (N, 1))
    slide = SlidePhase(*_common())
    hold = HoldPhase(*_common(mode="RRRRR"), formation="flush", pose=pose)
    pivot = PivotPhase(*_common(), formation="pivot", pose=pose, row_modes=("SBSSS",) + ("SSSS",) * (N - 1))
    assert [p.kind for p in (slide, hold, pivot)] == ["slide", "hold", "pivot"]
    assert [p.moves for p in (slide, hold, pivot)] == [True, False, True]  # a hold's rows keep their ramp's times
    assert [p.rest_rows_judged for p in (slide, hold, pivot)] == [False, True, True]  # only a slide's judged again
    assert [p.state_word for p in (slide, hold, pivot)] == [None, "holding", "pivoting"]
    assert [p.title_prefix for p in (slide, hold, pivot)] == ["", "hold: ", "pivot: "]
    for p in (hold, pivot):  # a turned pose is the row's pose, not the palm edge's
        np.testing.assert_array_equal(p.poses(REST), pose)
    assert pivot.transition and pivot.modes()[0] == "SBSSS" and pivot.modes()[1:] == ("SSSS",) * (N - 1)
    assert not replace(pivot, row_modes=None).transition
    assert hold.modes() == ("RRRRR",) * N
    # a hold on the palm edge (a release hold after a slide): at rest at x, the formation's contacts
    rest = HoldPhase(*_common(mode="RRRR"))
    np.testing.assert_array_equal(rest.poses(REST)[:, 1:], np.column_stack([np.full(N, REST), np.zeros(N)]))
    assert rest.row_contacts() == slide.row_contacts() == (("palm:0", "palm:1", "left", "right"),) * N
    named = ("palm:1", "left", "left", "right", "right")
    assert replace(hold, contacts=(named,) * N).row_contacts() == (named,) * N


def test_a_regrasp_is_the_old_regrasp_plan():
    assert RegraspPlan is RegraspPhase
    rg = RegraspPlan("r", 0.01, np.array([0.0, 0.5, 1.0]), np.zeros((3, 2)), np.zeros((3, 2)), ())
    assert rg.kind == "regrasp" and not rg.in_contact and not isinstance(rg, ContactSegmentPlan)
    np.testing.assert_array_equal(rg.poses(REST), np.tile([0.01, REST, 0.0], (3, 1)))


def test_a_turning_plan_is_typed_and_exports_its_kinds():
    from qsplan.planner.export.plan_files import plan_metadata
    from qsplan.planner.plan.pivot import HOLD_MIN_DURATION, HOLD_TORQUE_RATE

    from tests.planner.bundled import planned

    plan = planned("reorient_task")
    assert [type(p) for p in plan.phases] == [SlidePhase, HoldPhase, PivotPhase]
    _, hold, pivot = plan.phases
    assert plan.segments == plan.phases and pivot.transition  # the first piece starts at the flush instant
    assert [d["phase_kind"] for d in plan_metadata(plan)["phases"]] == ["slide", "hold", "pivot"]
    # the time scaling kept the hold's ramp: evenly spaced rows over |tau_to - tau_from| / rate (or the least time)
    span = max(abs(hold.command[-1] - hold.command[0]) / HOLD_TORQUE_RATE, HOLD_MIN_DURATION)
    np.testing.assert_allclose(hold.t - hold.t[0], np.linspace(0.0, span, hold.t.size), rtol=0, atol=1e-12)
    assert not np.any(hold.speed_scale) and np.all(np.ptp(hold.q, axis=0) == 0)
