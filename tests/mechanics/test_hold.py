"""Certified holds (:mod:`qsplan.mechanics.bands.hold`): nothing moves while the hand holds still and ramps a torque.

* closed forms: hand-built scenes whose answer is known (a block on a floor alone, between two walls, weightless,
  pressed by a prismatic pusher whose link has weight: the sign of ``g_man``);
* random sampling: in proved cases thousands of random admissible motions all have negative power; in refused
  cases the programme's witness is admissible and the load does work along it;
* the vertex argument: a ramp (and a wrench box) proved at its vertices is proved at 50 interior points;
* the demo's flush instant and slide end, against what the physics says (BSSSS at a small velocity input);
* validation: one ``pytest.raises`` per branch.
"""

from __future__ import annotations

import csv
from functools import cache
from itertools import combinations, product
from pathlib import Path

import numpy as np
import pytest

from qsplan.mechanics import QsplanError, make_scene, point_wrench, solve, wrench_matrices
from qsplan.mechanics.bands.disturbance import WrenchBox
from qsplan.mechanics.bands.hold import (INTERVAL_MARGIN, MARGIN_TOL, hold_load, hold_matrix, hold_torque_interval,
                                         prove_hold)  # fmt: skip

G = 9.81  # m/s^2
MASS = 0.2  # kg, the block
A_HALF = 0.05  # m, half the block's side
WALL_HEIGHT = 0.03  # m, where the walls touch
PUSHER_WEIGHT = 0.5  # N, the prismatic pusher's link weight: g_man = 0.5 N (dV/dq, q upward)
#: Random motions per sampling check (Gaussian ones, and as many combinations of the admissible cone's rays).
N_SAMPLES = 40_000
#: ``A x`` of the witness may be this far below 0, relative to ``|A| |x|``: the programme's rounding.
ADMISSIBLE_TOL = 1e-9
REFERENCE = Path(__file__).resolve().parent.parent / "data" / "reference_plans" / "demo_task.csv"


def _block(walls=True, weight=MASS * G, pusher=False, joints=True):
    """A square block (side 0.1 m, centre of mass at (0, 0.05)) on a floor under vertices (-a, 0), (a, 0); with
    ``walls`` a fixed wall at (-a, h) and one at (a, h) carried by a held prismatic joint; with ``pusher`` an
    effort-controlled vertical prismatic pusher on its top centre whose link weighs PUSHER_WEIGHT."""
    a = A_HALF
    r, n = [(-a, 0.0), (a, 0.0)], [(0.0, 1.0), (0.0, 1.0)]
    if walls:
        r, n = r + [(-a, WALL_HEIGHT), (a, WALL_HEIGHT)], n + [(1.0, 0.0), (-1.0, 0.0)]
    if pusher:
        r, n = r + [(0.0, 2 * a)], n + [(0.0, -1.0)]
    Wn, Wt = wrench_matrices(np.array(r), np.array(n))
    n_c = len(r)
    n_j = (1 + int(pusher)) if joints else 0
    Jn, Jt = np.zeros((n_c, n_j)), np.zeros((n_c, n_j))
    if joints and walls:
        Jn[3, 0] = -1.0  # the right wall moves along +x with joint 0: n . (1, 0)
    if pusher:
        Jn[-1, 1] = -1.0  # the pusher moves along +y with joint 1: n . (0, 1)
    e = np.array([False, True][:n_j])
    return make_scene(Wn, Wt, Jn, Jt, np.zeros(n_c), point_wrench((0.0, a), (0.0, -weight)),
                      g_man=np.array([0.0, PUSHER_WEIGHT][:n_j]), effort_controlled=e,
                      joint_velocity=np.where(e, np.nan, 0.0), joint_effort=np.where(e, 0.0, np.nan))  # fmt: skip


@cache
def _task():
    from qsplan.planner.task.task import demo_task_path, load_task

    return load_task(demo_task_path())


@cache
def _flush_scene():
    from tests.reference.paper_pivot import flush_instant, transition_scene

    return transition_scene(_task().hand, flush_instant(_task().hand), "right")


@cache
def _slide_end():
    """The demo's last row (at rest) and its four-contact scene, the left finger held, the right torque-controlled."""
    from qsplan.hands.described.records import scene_at

    row = list(csv.DictReader(REFERENCE.open()))[-1]
    pose = [float(row[k]) for k in ("x_workpiece", "y_workpiece", "theta_workpiece")]
    q = [float(row["q_left"]), float(row["q_right"])]
    return row, scene_at(_task().hand, pose, q, [False, True], [0.0, np.nan], [np.nan, float(row["tau_right"])])


def _held(scene):
    n = scene.n_joints
    return scene.with_control(np.zeros(n, dtype=bool), np.zeros(n), np.full(n, np.nan))


def _extreme_rays(A):
    """The admissible cone's extreme rays, enumerated without a programme: a ray of ``{x : A x >= 0}`` (pointed)
    is the null direction of ``m - 1`` independent rows that satisfies every other row, shape (r, m)."""
    n, m = A.shape
    rays = []
    for rows in combinations(range(n), m - 1):
        _, s, vt = np.linalg.svd(A[list(rows)])
        if s[-1] < 1e-9 * s[0]:
            continue
        for d in (vt[-1], -vt[-1]):
            if np.all(A @ d >= -1e-12):
                rays.append(d)
    return np.array(rays).reshape(-1, m)


def _admissible_samples(A, seed):
    """Random admissible motions: N_SAMPLES Gaussian ones kept where ``A x >= 0`` (the brief's rejection sampling:
    none where the cone is thinner than the space), then N_SAMPLES random nonnegative combinations of the extreme
    rays, each ray dropped with probability 1/2 to reach the cone's faces."""
    rng = np.random.default_rng(seed)
    x = rng.normal(size=(N_SAMPLES, A.shape[1]))
    kept = x[np.all(x @ A.T >= 0.0, axis=1)]
    rays = _extreme_rays(A)
    if not len(rays):
        return kept, rays
    w = rng.exponential(size=(N_SAMPLES, len(rays))) * (rng.random((N_SAMPLES, len(rays))) < 0.5)
    combos = w[w.sum(axis=1) > 0] @ rays
    return np.vstack([kept, combos]), rays


# --- closed forms -----------------------------------------------------------------------------------------------

def test_block_on_a_floor_alone_slides_sideways_for_free():
    scene = _block(walls=False, joints=False)
    proof = prove_hold(scene)
    assert not proof.proved and proof.rank == 2 and proof.reason.startswith("rank deficient")
    x = proof.witness
    assert abs(x[0]) > 0.99 * np.linalg.norm(x)  # a sideways slide, the floor's two contacts unmoved
    np.testing.assert_allclose(hold_matrix(scene) @ x, 0.0, atol=1e-12)
    assert proof.witness_power == pytest.approx(0.0, abs=1e-12)  # gravity does no work sideways: not strictly held


def test_block_between_two_walls_is_held_by_its_weight():
    scene = _block()
    proof = prove_hold(scene)
    assert proof.proved and proof.rank == 3 and not proof.capped
    # the walls' forces are equal and opposite at one height (their moments cancel): each floor contact carries
    # half the weight, and the squeeze between the walls can be as large as wanted
    assert proof.margin == pytest.approx(MASS * G / 2, rel=1e-9)
    np.testing.assert_allclose(proof.certificates[0, :2], MASS * G / 2, rtol=1e-9)
    assert proof.certificates[0, 2] == pytest.approx(proof.certificates[0, 3], rel=1e-9)


def test_weightless_block_between_walls_lifts_off_for_free():
    proof = prove_hold(_block(weight=0.0))
    assert not proof.proved and proof.margin <= MARGIN_TOL
    assert proof.witness[1] > 0 and proof.witness_power >= -MARGIN_TOL  # lifting costs nothing without weight
    assert np.all(hold_matrix(_block(weight=0.0)) @ proof.witness >= -ADMISSIBLE_TOL)


@pytest.mark.parametrize("margin", [INTERVAL_MARGIN, 0.05, 1.0])
def test_pusher_interval_is_its_link_weight(margin):
    # eq. (3): J^T c = tau - g_man; the pusher (Jn = -1) presses with c_n = g_man - tau, so the hold needs
    # tau < g_man (its weight pressing down) and nothing bounds it below (pressing harder loads the floor)
    lo, hi = hold_torque_interval(_block(pusher=True), margin=margin)
    assert lo == -np.inf
    assert hi == pytest.approx(PUSHER_WEIGHT - margin, abs=1e-9)


def test_pusher_pulled_up_lifts_off_with_the_power_of_its_net_force():
    scene = _block(pusher=True)
    tau = PUSHER_WEIGHT + 0.3
    proof = prove_hold(scene, [tau])
    assert not proof.proved
    np.testing.assert_allclose(proof.witness, [0.0, 0.0, 0.0, 1.0], atol=1e-9)  # the pusher alone rises
    assert proof.witness_power == pytest.approx(tau - PUSHER_WEIGHT, rel=1e-9)
    assert proof.margin == pytest.approx(-proof.witness_power, abs=1e-9)  # the programmes are each other's duals


@pytest.mark.parametrize("tau", [-5.0, 0.0, PUSHER_WEIGHT - 0.1])
def test_certificate_is_a_frictionless_equilibrium(tau):
    scene = _block(pusher=True)
    proof = prove_hold(scene, [tau])
    assert proof.proved
    lam = proof.certificates[0]
    np.testing.assert_allclose(scene.Wn @ lam + scene.g_obj, 0.0, atol=1e-9)  # eq. (2), c_t = 0
    e = scene.effort_joints
    np.testing.assert_allclose((scene.Jn.T @ lam)[e], tau - scene.g_man[e], atol=1e-9)  # eq. (3)
    assert lam[-1] == pytest.approx(PUSHER_WEIGHT - tau, rel=1e-9)


# --- random sampling --------------------------------------------------------------------------------------------

def _proved_cases():
    row, end = _slide_end()
    band = (float(row["tau_right_min"]), float(row["tau_right_max"]))
    return [("walls", _block(), None), ("pusher", _block(pusher=True), [0.2]),
            ("flush 0.171", _flush_scene(), [0.17119036886411212]), ("flush 3.899", _flush_scene(), [3.8994]),
            ("flush 50", _flush_scene(), [50.0]), ("flush all held", _held(_flush_scene()), None),
            ("slide end lo", end, [band[0]]), ("slide end hi", end, [band[1]]),
            ("slide end all held", _held(end), None)]


@pytest.mark.parametrize("case", range(9))
def test_random_admissible_motions_lose_power_when_proved(case):
    name, scene, tau = _proved_cases()[case]
    proof = prove_hold(scene, tau)
    assert proof.proved, name
    A, p = hold_matrix(scene), hold_load(scene, proof.torques[0])
    x, rays = _admissible_samples(A, seed=case)
    if len(rays):
        assert np.all(rays @ p < 0.0), name  # exact: every admissible motion is a nonnegative combination of these
        assert len(x) >= N_SAMPLES // 2, name
        assert np.all(x @ p < 0.0), name
    else:  # no admissible ray: immobilised at first order, and no Gaussian sample is admissible either
        assert len(x) == 0, name


def test_flush_instant_all_held_is_immobilised_at_first_order():
    # palm:0, palm:1, the left finger's two contacts and the right one, every joint held: no admissible motion at
    # all, so any load is held (here a box of 10 N and 1 N m around the weight)
    scene = _held(_flush_scene())
    assert len(_extreme_rays(hold_matrix(scene))) == 0
    proof = prove_hold(scene, disturbance=WrenchBox((-10.0, -10.0, -1.0), (10.0, 10.0, 1.0)))
    assert proof.proved and proof.capped and len(proof.wrenches) == 8


def _refused_cases():
    _, end = _slide_end()
    return [("floor", _block(walls=False, joints=False), None), ("weightless", _block(weight=0.0), None),
            ("pusher lifted", _block(pusher=True), [1.0]), ("flush at 0", _flush_scene(), [0.0]),
            ("flush pulled", _flush_scene(), [-0.5]), ("slide end 0.8", end, [0.8]), ("slide end 0", end, [0.0])]


@pytest.mark.parametrize("case", range(7))
def test_witness_is_admissible_and_the_load_works_along_it(case):
    name, scene, tau = _refused_cases()[case]
    proof = prove_hold(scene, tau)
    assert not proof.proved, name
    x = proof.witness
    A = hold_matrix(scene)
    assert np.all(A @ x >= -ADMISSIBLE_TOL * np.linalg.norm(A) * np.linalg.norm(x)), name
    p = hold_load(scene, proof.torques[proof.witness_vertex], proof.wrenches[proof.witness_vertex])
    assert p @ x == pytest.approx(proof.witness_power, abs=1e-12)
    assert p @ x >= -MARGIN_TOL, name


def test_slide_end_pushed_too_hard_lifts_vertex_0():
    _, end = _slide_end()
    proof = prove_hold(end, [0.8])
    v = hold_matrix(end) @ proof.witness
    assert v[0] > 0.5 * v.sum()  # palm:0 separates: the workpiece tips onto vertex 1
    assert proof.witness[2] < 0  # clockwise


# --- the vertex argument ----------------------------------------------------------------------------------------

def test_ramp_proved_at_its_ends_is_proved_inside():
    scene, ends = _flush_scene(), (0.17119036886411212, 3.8994)
    ramp = prove_hold(scene, list(ends))
    assert ramp.proved
    for tau in np.linspace(*ends, 52)[1:-1]:
        inner = prove_hold(scene, [tau])
        # the certificates' convex combination keeps every normal force above the ends' smallest
        assert inner.proved and inner.margin >= ramp.margin - 1e-9


def test_wrench_box_proved_at_its_vertices_is_proved_inside():
    scene = _slide_end()[1]
    box = _task().dynamics.disturbance
    proof = prove_hold(scene, [0.17119036886411212], box)
    assert proof.proved and len(proof.wrenches) == 4  # the inertial box is flat in y: 2^2 vertices
    lo, hi = np.asarray(box.lo), np.asarray(box.hi)
    for w in np.random.default_rng(3).uniform(lo, hi, (50, 3)):
        inner = prove_hold(scene, [0.17119036886411212], WrenchBox(w, w))
        assert inner.proved and inner.margin >= proof.margin - 1e-9


def test_interval_ends_proved_and_beyond_refused():
    _, end = _slide_end()
    lo, hi = hold_torque_interval(end)
    assert 0.0 < lo < 1e-5 and 0.5 < hi < 1.0
    assert prove_hold(end, [lo, hi]).proved
    assert prove_hold(end, [lo, hi]).margin == pytest.approx(INTERVAL_MARGIN, rel=1e-3)
    assert not prove_hold(end, [lo - 1e-3]).proved and not prove_hold(end, [hi + 1e-3]).proved


def test_friction_does_not_enter_the_proof():
    scene = _flush_scene()
    reference = prove_hold(scene, [0.17119036886411212, 3.8994])
    lo, hi = _task().mu_range
    for mu in product((lo, hi), repeat=scene.n_contacts):
        proof = prove_hold(scene.with_mu(mu), [0.17119036886411212, 3.8994])
        np.testing.assert_array_equal(proof.margins, reference.margins)


def test_default_torques_are_the_scenes_efforts():
    _, end = _slide_end()
    np.testing.assert_array_equal(prove_hold(end).margins, prove_hold(end, [end.joint_effort[1]]).margins)


# --- the physics at the flush instant ---------------------------------------------------------------------------

def test_flush_hold_at_50_nm_agrees_with_bsss_vanishing_with_the_left_finger():
    """With the left finger moving at the pivot's rate BSSSS is the only feasible mode at 50 N m; its motion is
    proportional to the left finger's velocity (positively homogeneous model), so held (velocity 0) the workpiece
    does not move: the hold's proof and BSSSS agree.  At velocity 0 the all-modes solver decides nothing."""
    scene = _flush_scene()
    assert prove_hold(scene, [50.0]).proved
    rates = {}
    for eps in (-0.05, -0.0005):
        result = solve(scene.with_control([False, True], [eps, np.nan], [np.nan, 50.0]).with_mu(0.1), workers=1)
        assert result.feasible_modes == ["BSSSS"]
        rates[eps] = result.solutions[0].qdot / eps
    np.testing.assert_allclose(rates[-0.05], rates[-0.0005], rtol=1e-9)
    still = solve(scene.with_control([False, True], [0.0, np.nan], [np.nan, 50.0]).with_mu(0.1), workers=1)
    assert still.no_feasible_mode and not still.jammed


# --- HiGHS directly against scipy.optimize.linprog -----------------------------------------------------------------

def _scipy_lp(c, A_ub=None, b_ub=None, A_eq=None, b_eq=None, bounds=None):
    """The programmes as they were solved before (``scipy.optimize.linprog``, the same HiGHS behind scipy's wrapper)."""
    from scipy.optimize import linprog

    return linprog(c, A_ub=A_ub, b_ub=b_ub, A_eq=A_eq, b_eq=b_eq, bounds=bounds, method="highs")


def _edge_cases():
    """Every proved and refused case, and torques around each interval end: 1e-3 N m to 1e-9 N m either side of
    where the certified margin crosses MARGIN_TOL (found by the interval at that margin)."""
    cases = [(name, scene, tau, None) for name, scene, tau in _proved_cases() + _refused_cases()]
    box = _task().dynamics.disturbance
    for name, scene, w in (("slide end", _slide_end()[1], None), ("slide end, box", _slide_end()[1], box),
                           ("pusher", _block(pusher=True), None), ("flush", _flush_scene(), None)):  # fmt: skip
        for end in hold_torque_interval(scene, w, margin=2 * MARGIN_TOL):
            if np.isfinite(end):
                cases += [(f"{name} {end:+.6g}{d:+.0e}", scene, [end + d], w)
                          for d in (-1e-3, -1e-6, -1e-9, 0.0, 1e-9, 1e-6, 1e-3)]  # fmt: skip
    return cases


def test_highs_directly_gives_linprogs_verdicts_at_the_edges(monkeypatch):
    """prove_hold on HiGHS directly (no scipy.optimize import) against the same programmes through linprog: the same
    verdict everywhere, near the interval ends too, and the same certified margins to the programmes' rounding."""
    import qsplan.mechanics.bands.hold as hold

    cases = _edge_cases()
    highs = [prove_hold(scene, tau, w) for _, scene, tau, w in cases]
    monkeypatch.setattr(hold, "_lp", _scipy_lp)
    for (name, scene, tau, w), a in zip(cases, highs):
        b = prove_hold(scene, tau, w)
        assert a.proved == b.proved, name
        np.testing.assert_allclose(a.margins, b.margins, rtol=1e-9, atol=1e-10, err_msg=name)
        if not a.proved and a.rank == b.rank == hold_matrix(scene).shape[1]:  # the witnesses: the dual's optimum
            assert a.witness_power == pytest.approx(b.witness_power, rel=1e-9, abs=1e-10), name
    near = [a.margins.min() - MARGIN_TOL for (name, *_), a in zip(cases, highs) if "e-09" in name]
    assert near and min(abs(m) for m in near) < 1e-8  # the scan reaches the edge: margins within 1e-8 N of it


@pytest.mark.parametrize("margin", [INTERVAL_MARGIN, 0.05])
def test_highs_directly_gives_linprogs_intervals(monkeypatch, margin):
    import qsplan.mechanics.bands.hold as hold

    box = _task().dynamics.disturbance
    scenes = [(_slide_end()[1], None), (_slide_end()[1], box), (_block(pusher=True), None), (_flush_scene(), None),
              (_flush_scene(), box)]  # fmt: skip
    highs = [hold_torque_interval(scene, w, margin) for scene, w in scenes]
    monkeypatch.setattr(hold, "_lp", _scipy_lp)
    for (scene, w), a in zip(scenes, highs):
        np.testing.assert_allclose(a, hold_torque_interval(scene, w, margin), rtol=1e-9, atol=1e-10)


def test_the_hold_imports_no_scipy_optimize():
    """Both programmes of prove_hold and hold_torque_interval's run without importing scipy.optimize (~0.5 s)."""
    import inspect
    import subprocess
    import sys

    code = "\n".join([
        "import sys", "import numpy as np",
        "from qsplan.mechanics import make_scene, point_wrench, wrench_matrices",
        "from qsplan.mechanics.bands.hold import hold_torque_interval, prove_hold",
        f"G, MASS, A_HALF, WALL_HEIGHT, PUSHER_WEIGHT = {G}, {MASS}, {A_HALF}, {WALL_HEIGHT}, {PUSHER_WEIGHT}",
        inspect.getsource(_block),
        "assert prove_hold(_block()).proved and not prove_hold(_block(weight=0.0)).proved",
        "assert np.isfinite(hold_torque_interval(_block(pusher=True))[1])",
        "print('scipy.optimize' in sys.modules)"])  # fmt: skip
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


# --- validation -------------------------------------------------------------------------------------------------

def test_scene_must_be_a_scene():
    with pytest.raises(QsplanError, match=r"scene: expected a qsplan.mechanics.Scene; got dict"):
        prove_hold({})


def test_a_hold_needs_a_held_joint():
    scene = _block(pusher=True)
    every = scene.with_control([True, True], [np.nan, np.nan], [0.0, 0.0])
    with pytest.raises(QsplanError, match=r"scene.effort_controlled: a hold needs at least one held"):
        prove_hold(every)


def test_torques_must_be_numbers():
    with pytest.raises(QsplanError, match=r"torques: expected numbers"):
        prove_hold(_block(pusher=True), ["a"])


def test_torques_need_one_column_per_effort_joint():
    with pytest.raises(QsplanError, match=r"torques: expected shape \(k, 1\).*got shape \(2, 2\)"):
        prove_hold(_block(pusher=True), [[0.0, 1.0], [0.0, 1.0]])


def test_torques_must_be_finite():
    with pytest.raises(QsplanError, match=r"torques: expected finite numbers"):
        prove_hold(_block(pusher=True), [np.inf])


def test_disturbance_must_be_a_box():
    with pytest.raises(QsplanError, match=r"disturbance: expected a WrenchBox or \(lo, hi\)"):
        prove_hold(_block(pusher=True), [0.0], disturbance="box")


def test_interval_needs_one_effort_joint():
    with pytest.raises(QsplanError, match=r"scene.effort_controlled: the torque interval needs exactly one"):
        hold_torque_interval(_block())


def test_interval_margin_must_be_a_positive_force():
    with pytest.raises(QsplanError, match=r"margin: expected a force in"):
        hold_torque_interval(_block(pusher=True), margin=0.0)
