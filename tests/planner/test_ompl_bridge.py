"""The OMPL bridge: deterministic, validated paths, honest failures."""

import numpy as np
import pytest

from qsplan.mechanics import QsplanError
from qsplan.planner.search.ompl_bridge import PlannerOptions, ompl_available, plan_path

pytestmark = [pytest.mark.ompl, pytest.mark.skipif(not ompl_available(), reason="OMPL bindings not installed")]


def _disk_free(x):
    return bool(np.hypot(x[0], x[1]) > 0.3)


def test_path_avoids_obstacle_and_is_deterministic():
    opts = PlannerOptions(interpolate=40)
    a = plan_path([-1, -1], [1, 1], [-0.8, 0], [0.8, 0], _disk_free, opts)
    b = plan_path([-1, -1], [1, 1], [-0.8, 0], [0.8, 0], _disk_free, opts)
    assert a.exact and a.path.shape == (40, 2)
    np.testing.assert_array_equal(a.path, b.path)
    np.testing.assert_allclose(a.path[0], [-0.8, 0]) and np.testing.assert_allclose(a.path[-1], [0.8, 0])
    # every state, and states between them at a fine resolution, are valid
    fine = np.concatenate([np.linspace(p, q, 20) for p, q in zip(a.path[:-1], a.path[1:])])
    assert all(_disk_free(x) for x in fine)
    assert a.validity_checks > 0


def test_blocked_goal_reports_no_exact_path():
    r = plan_path([-1, -1], [1, 1], [-0.8, 0], [0.8, 0], lambda x: bool(abs(x[0]) > 0.1), PlannerOptions(iterations=300))
    assert not r.exact and r.path.shape == (0, 2)


def test_state_cost_steers_an_optimizing_planner():
    opts = PlannerOptions(planner="BITstar", iterations=3000, interpolate=50)
    r = plan_path([-1, -1], [1, 1], [-0.8, -0.5], [0.8, -0.5], lambda x: True, opts, state_cost=lambda x: 1.0 + 50.0 * (x[1] < 0))
    assert r.exact and np.mean(r.path[:, 1] > 0) > 0.3  # detours through the cheap upper half


@pytest.mark.parametrize(
    "kwargs,match",
    [
        (dict(start=[2.0, 0.0]), "start: outside"),
        (dict(goal=[0.0, 0.0]), "goal: the state is not valid"),
        (dict(low=[1, 1]), "bounds"),
    ],
)
def test_bad_problems(kwargs, match):
    args = dict(low=[-1, -1], high=[1, 1], start=[-0.8, 0], goal=[0.8, 0], is_valid=_disk_free)
    args.update(kwargs)
    with pytest.raises(QsplanError, match=match):
        plan_path(**args)


@pytest.mark.parametrize("kwargs", [dict(planner="Magic"), dict(time_limit=0), dict(iterations=0), dict(validity_resolution=2)])
def test_bad_options(kwargs):
    with pytest.raises(QsplanError):
        PlannerOptions(**kwargs)
