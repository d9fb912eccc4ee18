"""Mu-space maps equal the solver point by point."""

import numpy as np
import pytest

from qsplan.hands.examples.paper import eq42_scene
from qsplan.mechanics import SceneError, planted_scene, scene_from_dict, solve
from qsplan.mechanics.muspace.maps import feasibility_map, grid_points


def test_map_equals_solver_at_every_point():
    rng = np.random.default_rng(21)
    for _ in range(6):
        scene, _ = planted_scene(rng, int(rng.integers(3, 6)), int(rng.integers(0, 2)))
        pts = rng.uniform(0, 1.2, size=(150, scene.n_contacts))
        mm = feasibility_map(scene, pts, batch=97)
        for i in range(len(pts)):
            assert solve(scene.with_mu(pts[i])).feasible_modes == [
                m.letters for m, f in zip(mm.modes, mm.feasible[i]) if f
            ]


def test_grid_points_layout():
    pts = grid_points([9.0, 9.0, 0.5], 0, 1, [0.0, 1.0, 2.0], [10.0, 20.0])
    assert pts.shape == (6, 3)
    np.testing.assert_array_equal(pts[1 * 3 + 2], [2.0, 20.0, 0.5])  # row j * nx + i


def test_labels_and_jams():
    scene = scene_from_dict(eq42_scene())
    mm = feasibility_map(scene, [[0.0, 0.0, 0.0], [0.5, 0.5, 0.5]])
    assert mm.jammed.tolist() == [True, False]
    assert mm.labels(1) == ["RBS", "SRB", "SSS"] and mm.ambiguous.tolist() == [False, True]


@pytest.mark.parametrize("pts", [np.zeros((4, 2)), -np.ones((2, 3)), np.full((1, 3), np.nan)])
def test_bad_points(pts):
    with pytest.raises(SceneError, match="mu_points"):
        feasibility_map(scene_from_dict(eq42_scene()), pts)
