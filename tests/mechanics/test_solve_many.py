"""Every mode's status at many friction vectors (solve_many) equals the solver at each vector, bit for bit; with a load
per vector; and at many scenes at once (solve_many_scenes) each scene's solve_many."""

from dataclasses import replace

import numpy as np
import pytest

from qsplan.hands import hand_scene
from qsplan.hands.examples.paper import eq42_scene
from qsplan.hands.paper_hand.two_finger import default_hand
from qsplan.mechanics import (
    DEFAULT_TOLERANCES,
    SceneError,
    Status,
    Tolerances,
    planted_scene,
    scene_from_dict,
    solve_many,
    solve_many_reference,
)
from qsplan.mechanics.muspace.maps import feasibility_map
from qsplan.planner import make_task

#: Machine-precision tolerances (the certifier's second look at degenerate modes) and coarse ones that
#: make many modes degenerate: the equality must hold on both sides of every singularity test.
EXACT = Tolerances(singular=1e-15, velocity=1e-13)
COARSE = Tolerances(singular=0.05)

FIELDS = ("kinematic", "codes", "boundary", "c_n", "qdot")


def _same(fast, ref):
    assert fast.letters == ref.letters
    for name in FIELDS:
        a, b = getattr(fast, name), getattr(ref, name)
        assert a.dtype == b.dtype and np.array_equal(a, b), name


def _hand_scenes(rng, n):
    task = make_task(default_hand(), 0.0, [0.01])
    for _ in range(n):
        e = str(rng.choice(["left", "right"]))
        yield hand_scene(task.hand.paper, task.pose(rng.uniform(-0.02, 0.02)), None, e, velocity=rng.uniform(-0.3, 0.3),
                         effort=rng.uniform(-1.0, 1.0))  # fmt: skip


def test_hand_scenes_match_the_solver_per_vector():
    """Statuses, boundary flags, c_n and qdot on seeded hand scenes, with and without degenerate modes."""
    rng = np.random.default_rng(11)
    seen = set()
    for scene in _hand_scenes(rng, 12):
        mus = np.vstack([np.zeros(4), np.full(4, 0.2), rng.uniform(0.0, 0.6, (6, 4))])
        for tol in (DEFAULT_TOLERANCES, EXACT, COARSE):
            fast = solve_many(scene, mus, tol)
            _same(fast, solve_many_reference(scene, mus, tol))
            seen |= {Status.ORDER[c] for c in np.unique(fast.codes)}
    assert {Status.FEASIBLE, Status.COULOMB_VIOLATED} <= seen and seen & Status.DEGENERATE


def test_planted_scenes_match_the_solver_per_vector_in_any_batch():
    rng = np.random.default_rng(5)
    singular = 0
    for _ in range(8):
        n_c = int(rng.integers(3, 6))
        scene, _ = planted_scene(rng, n_c, int(rng.integers(0, 2)))
        mus = rng.uniform(0.0, 1.2, (9, n_c))
        for tol in (DEFAULT_TOLERANCES, COARSE):
            ref = solve_many_reference(scene, mus, tol)
            for batch in (1, 7, 1 << 16):
                _same(solve_many(scene, mus, tol, batch=batch), ref)
            singular += int((ref.codes == Status.ORDER.index(Status.EQUILIBRIUM_SINGULAR)).sum())
    assert singular > 0


def test_feasible_rows_hold_the_forces_and_the_rest_is_zero():
    scene = scene_from_dict(eq42_scene())
    sv = solve_many(scene, [[0.5, 0.5, 0.5], [0.0, 0.0, 0.0]])
    assert sorted(sv.letters[j] for j in np.flatnonzero(sv.codes[0] == 0)) == ["RBS", "SRB", "SSS"]
    assert not (sv.codes[1] == 0).any()  # jammed without friction (Fig. 6)
    off = sv.codes != 0
    assert not sv.c_n[off].any() and not sv.qdot[off].any()
    assert (sv.c_n[~off] >= 0).all() and sv.c_n[~off].any()


def test_without_forces_the_statuses_are_the_same():
    rng = np.random.default_rng(3)
    scene = next(_hand_scenes(rng, 1))
    mus = rng.uniform(0.0, 0.6, (40, 4))
    full, bare = solve_many(scene, mus), solve_many(scene, mus, forces=False)
    assert bare.c_n is None and bare.qdot is None
    for name in ("kinematic", "codes", "boundary"):
        assert np.array_equal(getattr(full, name), getattr(bare, name)), name


def test_no_vectors_still_gives_the_kinematic_stage():
    scene = scene_from_dict(eq42_scene())
    sv, ref = solve_many(scene, np.zeros((0, 3))), solve_many_reference(scene, np.zeros((0, 3)))
    assert sv.codes.shape == (0, len(sv.letters))
    _same(sv, ref)
    assert (sv.kinematic == 0).any() and (sv.kinematic != 0).any()


def test_the_map_is_solve_many():
    scene = scene_from_dict(eq42_scene())
    pts = np.random.default_rng(42).uniform(0.0, 1.5, (300, 3))
    mm, sv = feasibility_map(scene, pts, COARSE, workers=1), solve_many(scene, pts, COARSE)
    assert [m.letters for m in mm.modes] == list(sv.letters)
    assert mm.kinematic_status == tuple(Status.ORDER[c] for c in sv.kinematic)
    assert np.array_equal(mm.feasible, sv.codes == 0)
    assert np.array_equal(mm.degenerate, sv.codes == Status.ORDER.index(Status.EQUILIBRIUM_SINGULAR))
    assert np.array_equal(mm.boundary, sv.boundary)
    assert mm.degenerate.any() and mm.feasible.any()


@pytest.mark.parametrize("solver", [solve_many, solve_many_reference])
def test_negative_or_not_finite_friction_is_refused(solver):
    with pytest.raises(SceneError, match="mu_vectors: expected nonnegative finite friction"):
        solver(scene_from_dict(eq42_scene()), [[0.1, -0.2, 0.3]])


@pytest.mark.parametrize("solver", [solve_many, solve_many_reference])
def test_a_vector_of_the_wrong_length_is_refused(solver):
    with pytest.raises(SceneError, match=r"mu_vectors: expected shape \(N, 3\); got \(2, 4\)"):
        solver(scene_from_dict(eq42_scene()), np.zeros((2, 4)))


# --- loads per vector, and many scenes at once ------------------------------------------------------------------

def _wrenches(rng, m):
    """Loads of ``m`` vectors: a scene's weight and each plus a random wrench (N, N, N m), as a disturbance box adds."""
    return rng.uniform(-3.0, 3.0, (m, 3)) * [1.0, 1.0, 0.05]


def test_loads_per_vector_match_the_solver_at_each_load():
    """A vector's load replaces the scene's g_obj (the certifier's wrench vertices): the solver on that scene."""
    rng = np.random.default_rng(23)
    for scene in _hand_scenes(rng, 4):
        mus = np.vstack([np.zeros(4), np.full(4, 0.2), rng.uniform(0.0, 0.6, (4, 4))])
        loads = scene.g_obj + _wrenches(rng, len(mus))
        for tol in (DEFAULT_TOLERANCES, EXACT):
            fast = solve_many(scene, mus, tol, loads=loads)
            _same(fast, solve_many_reference(scene, mus, tol, loads=loads))
            for i in (0, len(mus) - 1):  # one vector alone: the scene with that g_obj
                alone = solve_many(replace(scene, g_obj=loads[i]), mus[[i]], tol)
                assert np.array_equal(fast.codes[i], alone.codes[0]) and np.array_equal(fast.c_n[i], alone.c_n[0])


def _mixed_scenes(rng):
    """Hand scenes (4 contacts, either finger effort-controlled) and planted ones of 3-5 contacts: several shapes,
    each several times, in a shuffled order."""
    scenes = list(_hand_scenes(rng, 6))
    for _ in range(6):
        scenes.append(planted_scene(rng, int(rng.integers(3, 6)), int(rng.integers(0, 2)))[0])
    return [scenes[i] for i in rng.permutation(len(scenes))]


@pytest.mark.parametrize("tol", [DEFAULT_TOLERANCES, EXACT, COARSE], ids=["default", "exact", "coarse"])
def test_many_scenes_are_each_scenes_solve_many_bit_for_bit(tol):
    """solve_many_scenes (the kinematic stage of every scene in one call per batch of modes, the equilibrium rows of
    all of them together) gives each scene solve_many's arrays exactly, with and without loads, in any row batch."""
    from qsplan.mechanics.solver.many import solve_many_scenes

    rng = np.random.default_rng(7)
    scenes = _mixed_scenes(rng)
    mus = [rng.uniform(0.0, 1.0, (int(rng.integers(0, 12)), s.n_contacts)) for s in scenes]
    loads = [None if i % 3 == 0 else s.g_obj + _wrenches(rng, len(mu)) for i, (s, mu) in enumerate(zip(scenes, mus))]
    shapes = {(s.n_contacts, s.effort_controlled.tobytes()) for s in scenes}
    assert len(shapes) >= 3 and any(len(mu) == 0 for mu in mus)
    statuses = set()
    for batch in (1, 13, 1 << 16):
        many = solve_many_scenes(scenes, mus, tol, loads=loads, batch=batch)
        for s, mu, g, fast in zip(scenes, mus, loads, many):
            _same(fast, solve_many(s, mu, tol, loads=g))
            statuses |= set(np.unique(fast.codes).tolist())
    assert 0 in statuses and len(statuses) >= 3
    bare = solve_many_scenes(scenes, mus, tol, loads=loads, forces=False)
    assert all(b.c_n is None and np.array_equal(b.codes, f.codes) for b, f in zip(bare, many))


def test_many_scenes_refuse_vectors_not_one_per_scene():
    from qsplan.mechanics.solver.many import solve_many_scenes

    scene = scene_from_dict(eq42_scene())
    with pytest.raises(SceneError, match=r"mu_vectors, loads: expected one per scene \(2\); got 1 and 2"):
        solve_many_scenes([scene, scene], [np.zeros((1, 3))])
    with pytest.raises(SceneError, match=r"mu_vectors\[1\]: expected shape \(N, 3\); got \(2, 4\)"):
        solve_many_scenes([scene, scene], [np.zeros((1, 3)), np.zeros((2, 4))])
    with pytest.raises(SceneError, match=r"loads\[0\]: expected finite numbers of shape \(1, 3\)"):
        solve_many_scenes([scene], [np.zeros((1, 3))], loads=[np.zeros((2, 3))])


@pytest.mark.parametrize("solver", [solve_many, solve_many_reference])
def test_loads_of_the_wrong_shape_are_refused(solver):
    with pytest.raises(SceneError, match=r"loads: expected finite numbers of shape \(2, 3\)"):
        solver(scene_from_dict(eq42_scene()), np.zeros((2, 3)), loads=np.zeros((2, 2)))
