"""The finite-motion simulator: mode conditions as functions, events, selection rule, stops (Section 5.1)."""

import numpy as np
import pytest

from qsplan.hands.examples.paper import eq37_scene, eq42_scene
from qsplan.hands.examples.pushing import make_pushed_polygon, tilted_box_example
from qsplan.hands.examples.rod import make_rod_system, rod_initial_state
from qsplan.mechanics import ContactMode, QsplanError, Status, check_mode, enumerate_modes, planted_scene, scene_from_dict
from qsplan.mechanics.motion.conditions import mode_values
from qsplan.mechanics.motion.events import rk4_step
from qsplan.mechanics.numerics import hadamard_ratio
from qsplan.mechanics.motion.simulator import MotionOptions, simulate
from qsplan.mechanics.motion.system import frozen_scene_system, make_friction, pose_rate
from qsplan.mechanics.motion.trajectory import STOP_KINDS

# --- the conditions of one mode as numbers (eqs. 15, 16, 24-28) -----------------------------


def test_mode_values_agree_with_check_mode_on_random_scenes():
    rng = np.random.default_rng(11)
    compared = 0
    for _ in range(25):
        nc = int(rng.integers(2, 5))
        ne = int(rng.integers(0, min(2, 2 * nc - 3) + 1))
        scene, _ = planted_scene(rng, nc, ne)
        for mode in enumerate_modes(nc, scene.dof):
            status = check_mode(scene, mode).status
            if status in Status.DEGENERATE:
                continue
            v = mode_values(scene, mode)
            ok = bool(np.all(v.values >= -1e-9 * v.scales))
            assert ok == (status == Status.FEASIBLE), (mode, status, v.values)
            compared += 1
    assert compared > 50


def test_mode_values_forces_match_the_solution():
    scene = scene_from_dict(eq42_scene(0.5))
    for letters in ("SSS", "RBS", "SRB"):
        sol = check_mode(scene, ContactMode(letters)).solution
        v = mode_values(scene, ContactMode(letters))
        np.testing.assert_allclose(v.c_n, sol.c_n, atol=1e-12)
        np.testing.assert_allclose(v.c_t, sol.c_t, atol=1e-12)
        np.testing.assert_allclose(v.qdot, sol.qdot, atol=1e-12)
        assert len(v.labels) == v.values.size == len(v.kinds) == v.scales.size


def test_frozen_sliding_direction_turns_a_sign_change_into_a_zero_crossing():
    scene = scene_from_dict(eq42_scene(0.5))
    mode = ContactMode("SSS")
    v = mode_values(scene, mode)
    flipped = mode_values(scene, mode, xi=-v.xi)
    sliding = [k for k, kind in enumerate(v.kinds) if kind == "sliding"]
    assert np.all(v.values[sliding] > 0) and np.all(flipped.values[sliding] < 0)


def test_signed_hadamard_sign_and_scale():
    A = np.array([[2.0, 0.0], [0.0, 3.0]])
    assert hadamard_ratio(A, signed=True) == pytest.approx(1.0)
    assert hadamard_ratio(A[::-1], signed=True) == pytest.approx(-1.0)
    assert hadamard_ratio(A[::-1]) == pytest.approx(1.0)
    assert hadamard_ratio(np.array([[1.0, 2.0], [2.0, 4.0]]), signed=True) == 0.0
    assert hadamard_ratio(np.zeros((0, 0)), signed=True) == 1.0


def test_rk4_is_exact_for_constant_rates_and_fourth_order_otherwise():
    x = rk4_step(lambda y: np.array([2.0, -1.0]), np.zeros(2), 0.3)
    np.testing.assert_allclose(x, [0.6, -0.3])
    errs = [abs(rk4_step(lambda y: -y, np.array([1.0]), h)[0] - np.exp(-h)) for h in (0.1, 0.05)]
    assert errs[0] / errs[1] == pytest.approx(32, rel=0.1)  # local error O(h^5)


def test_pose_rate_of_a_rotation_about_the_centre_is_a_pure_spin():
    c, w = np.array([0.7, -0.2]), 1.3
    qdot = np.array([w * c[1], -w * c[0], w])  # velocity of the point at the origin: w x (0 - c)
    np.testing.assert_allclose(pose_rate([c[0], c[1], 0.4], qdot), [0.0, 0.0, w], atol=1e-15)


# --- validation ----------------------------------------------------------------------------


@pytest.mark.parametrize(
    "static,kinetic,match",
    [
        ([0.3, -0.1], [0.2, 0.0], r"friction.static\[1\]: expected a nonnegative"),
        ([0.3, 0.4], [0.2, -0.1], r"friction.kinetic\[1\]: expected a nonnegative"),
        ([0.3, 0.4], [0.5, 0.1], r"friction.kinetic\[0\]: expected at most the static coefficient"),
        ([0.3, 0.4], [0.2], r"friction.kinetic: expected shape"),
        ([0.3, np.nan], [0.2, 0.1], r"friction.static: expected finite"),
    ],
)
def test_make_friction_rejects(static, kinetic, match):
    with pytest.raises(QsplanError, match=match):
        make_friction(static, kinetic)


def test_make_friction_allows_equal_coefficients():
    fr = make_friction([0.3, 0.4], [0.3, 0.2])
    np.testing.assert_array_equal(fr.for_mode(ContactMode("SR"), (0, 1)), [0.3, 0.4])
    np.testing.assert_array_equal(fr.for_mode(ContactMode("RS"), (0, 1)), [0.3, 0.2])


@pytest.mark.parametrize(
    "kwargs,match",
    [
        ({"max_step": 0.0}, r"options.max_step: expected a positive"),
        ({"event_xtol": -1.0}, r"options.event_xtol"),
        ({"min_segment": np.inf}, r"options.min_segment"),
        ({"probe_time": 1e-5}, r"options.probe_time: expected at least .* and below min_segment"),
        ({"probe_time": 1e-11}, r"options.probe_time"),
        ({"max_switches": -1}, r"options.max_switches"),
    ],
)
def test_motion_options_reject(kwargs, match):
    with pytest.raises(QsplanError, match=match):
        MotionOptions(**kwargs)


def _rod(mu_s=(0.5, 0.5), mu_k=(0.4, 0.4)):
    return make_rod_system(mu_s, mu_k, 0.1)


@pytest.mark.parametrize(
    "x0,duration,policy,match",
    [
        (np.zeros(4), 1.0, None, r"x0: expected shape \(5\); got \(4,\)"),
        (rod_initial_state(1, 0.6), 0.0, None, r"duration: expected a positive"),
        (rod_initial_state(1, 0.6), np.nan, None, r"duration"),
        (rod_initial_state(1, 0.6), 1.0, "last", r"policy: expected None, 'first' or a callable"),
        ([0, 0, 0, np.nan, 1], 1.0, None, r"x0: expected finite"),
    ],
)
def test_simulate_rejects(x0, duration, policy, match):
    with pytest.raises(QsplanError, match=match):
        simulate(_rod(), x0, duration, policy=policy)


def test_simulate_rejects_a_penetrating_start():
    system, x0 = tilted_box_example()
    x0 = x0 + np.array([0.0, -0.01, 0.0, 0.0])
    with pytest.raises(QsplanError, match=r"x0: contact 'floor@v1' penetrates by 0.01 m"):
        simulate(system, x0, 1.0)


def test_simulate_rejects_a_non_system():
    with pytest.raises(QsplanError, match="system: expected a MotionSystem"):
        simulate(object(), np.zeros(3), 1.0)


# --- selection at the start: ambiguity (eq. 42), jam, unique -----------------------------


def test_eq42_three_feasible_modes_is_reported_ambiguous():
    system = frozen_scene_system(scene_from_dict(eq42_scene(0.5)))
    motion = simulate(system, np.zeros(4), 1.0)
    assert motion.segments == ()
    assert motion.stopped.kind == "ambiguous" and motion.stopped.time == 0.0
    assert motion.stopped.candidates == ("SSS", "RBS", "SRB")  # 3S, R1S3, R2S1 (Fig. 6)
    assert "3 modes are feasible" in motion.stopped.message


def test_policies_resolve_the_ambiguity():
    system = frozen_scene_system(scene_from_dict(eq42_scene(0.5)))
    first = simulate(system, np.zeros(4), 1.0, policy="first")
    assert first.stopped is None and first.labels == ["SSS"] and first.segments[0].t_end == 1.0
    picked = simulate(system, np.zeros(4), 1.0, policy=lambda t, x, cands: cands[1].mode.letters)
    assert picked.labels == ["RBS"]
    unresolved = simulate(system, np.zeros(4), 1.0, policy=lambda t, x, cands: None)
    assert unresolved.stopped.kind == "ambiguous"
    with pytest.raises(QsplanError, match="policy: returned 'BBB'"):
        simulate(system, np.zeros(4), 1.0, policy=lambda t, x, cands: "BBB")


def test_eq42_low_friction_is_a_jam_and_eq37_starts_uniquely():
    jam = simulate(frozen_scene_system(scene_from_dict(eq42_scene(0.05))), np.zeros(4), 1.0)
    assert jam.stopped.kind == "jam" and jam.stopped.candidates == ()
    system = frozen_scene_system(scene_from_dict(eq37_scene(0.3)))
    motion = simulate(system, np.zeros(4), 2.0, options=MotionOptions(max_step=0.5))
    assert motion.stopped is None and motion.labels == ["SSS"]
    sol = motion.segments[0].solution
    assert sol.max_residual < 1e-9
    # a frozen scene moves at constant qdot: the pose integrates exactly
    np.testing.assert_allclose(motion.segments[0].x_end[2], 2.0 * sol.qdot[2], rtol=1e-12)


def test_stop_kinds_are_documented():
    assert set(STOP_KINDS) == {"ambiguous", "jam", "no_persistent_mode", "zeno", "limit", "max_switches"}


# --- events: a contact appearing (the pushed box) -------------------------------------------


@pytest.fixture(scope="module")
def pushed():
    system, x0 = tilted_box_example()
    return system, x0, simulate(system, x0, 6.0, options=MotionOptions(max_step=0.02))


def test_contact_appears_and_the_mode_changes_at_that_event(pushed):
    system, _, motion = pushed
    assert motion.labels == ["R-S", "SSS"]
    ev = motion.events[0]
    assert ev.kind == "contact" and ev.labels == ("floor@v0 comes into contact (gap = 0)",)
    assert (ev.before, ev.after) == ("R-S", "SSS")
    assert abs(system.gaps(ev.state)[1]) < 1e-9  # the corner is on the floor at the event
    assert motion.segments[1].contacts == (0, 1, 2)
    assert abs(ev.state[2]) < 1e-9  # the box lands flat
    for seg in motion.segments:
        assert seg.solution.max_residual < 1e-9


def test_contact_event_does_not_depend_on_the_step(pushed):
    system, x0, motion = pushed
    half = simulate(system, x0, 6.0, options=MotionOptions(max_step=0.01))
    assert half.labels == motion.labels
    for a, b in zip(motion.events, half.events):
        assert abs(a.time - b.time) < 1e-9
        np.testing.assert_allclose(a.state, b.state, atol=1e-9)


def test_limit_stops_the_run_and_contacts_move_along_the_boundary(pushed):
    system, _, motion = pushed
    assert motion.stopped.kind == "limit"
    assert "finger tip leaves edge 3 past vertex 0" in motion.stopped.message
    assert system.limits(motion.stopped.state)[1] == pytest.approx(0.0, abs=1e-9)
    # while sliding, the tip stays on the edge's line and the floor vertices on the floor
    for x in motion.segments[1].states:
        g = system.gaps(x)
        assert np.all(np.abs(g) < 1e-9)


def test_time_to_land_matches_the_geometry_of_R_S(pushed):
    """In R-S the tip carries a body point; v1 slides on the floor.  The box is flat when v0 lands."""
    system, x0, motion = pushed
    end = motion.segments[0].x_end
    tip_body = np.linalg.solve(
        np.array([[np.cos(x0[2]), -np.sin(x0[2])], [np.sin(x0[2]), np.cos(x0[2])]]), system.tip(x0) - x0[:2]
    )
    # the body point under the rolling tip is still under the tip at the event
    R = np.array([[np.cos(end[2]), -np.sin(end[2])], [np.sin(end[2]), np.cos(end[2])]])
    np.testing.assert_allclose(R @ tip_body + end[:2], system.tip(end), atol=1e-9)


def test_pushed_polygon_validation():
    V = [[-0.1, -0.1], [0.1, -0.1], [0.1, 0.1], [-0.1, 0.1]]
    ok = dict(vertices=V, finger_origin=(-0.1, 0.0), finger_axis=(1, 0), finger_speed=0.1, pushed_edge=3,
              floor_vertices=(0, 1), mu_static=(0.5, 0.5, 0.5), mu_kinetic=(0.4, 0.4, 0.4))  # fmt: skip
    make_pushed_polygon(**ok)
    make_pushed_polygon(**{**ok, "vertices": V[::-1]})  # clockwise input is reoriented
    for key, value, match in [
        ("vertices", [[0, 0], [1, 0]], "vertices: expected at least 3"),
        ("vertices", [[0, 0], [1, 1], [1, 0], [0, 1]], "vertices: expected a simple convex polygon"),
        ("finger_axis", (0, 0), "finger_axis: expected a finite nonzero"),
        ("finger_speed", 0.0, "finger_speed"),
        ("pushed_edge", 4, "pushed_edge"),
        ("floor_vertices", (0, 0), "floor_vertices"),
        ("mu_static", (0.5, 0.5), "friction.kinetic: expected shape"),
    ]:
        with pytest.raises(QsplanError, match=match):
            make_pushed_polygon(**{**ok, key: value})


# --- the rod through the generic machinery --------------------------------------------------


def test_max_switches_stops_the_run():
    system = _rod()
    motion = simulate(system, rod_initial_state(1.0, 0.6), 20.0, options=MotionOptions(max_step=0.1, max_switches=3))
    assert motion.stopped.kind == "max_switches" and len(motion.segments) == 4


def test_zeno_is_detected_with_the_accumulation_instant():
    system = make_rod_system((0.6, 0.6), (0.3, 0.3), 0.1)  # a/b = 1/4: few switches
    motion = simulate(system, rod_initial_state(1.0, 0.4), 20.0, options=MotionOptions(max_step=0.1))
    assert motion.stopped.kind == "zeno"
    assert "converge to about t = 7 s" in motion.stopped.message  # (l1 + l2) / (2V)
    assert np.all(np.diff(motion.switch_times) > 0) and motion.switch_times[-1] < 7.0


def test_the_current_mode_is_kept_while_feasible():
    """Start with SR well inside its region: one segment to the duration, no re-selection."""
    motion = simulate(_rod(), rod_initial_state(1.0, 0.3), 1.0, options=MotionOptions(max_step=0.1))
    assert motion.labels == ["SR"] and motion.stopped is None and motion.events == ()
    assert motion.times[0] == 0.0 and motion.times[-1] == 1.0


def test_pushed_scene_matches_the_shared_geometric_scene(pushed):
    """Cross-check against qsplan.mechanics.model.geometry.find_contacts / geometric_scene along the motion."""
    from qsplan.mechanics import scene_from_dict

    system, _, motion = pushed
    checked = 0
    for seg in motion.segments:
        for x in seg.states[:: max(1, len(seg.states) // 4)][:-1]:  # not the limit state (vertex on vertex)
            geo = scene_from_dict(system.geometry_document(x))
            mine = system.scene(x, seg.contacts)
            assert geo.n_contacts == mine.n_contacts
            for i in range(mine.n_contacts):  # geo orders the palm (floor) first: match columns
                dist = np.abs(geo.Wn - mine.Wn[:, [i]]).sum(axis=0) + np.abs(geo.Wt - mine.Wt[:, [i]]).sum(axis=0)
                j = int(np.argmin(dist))
                np.testing.assert_allclose(geo.Wn[:, j], mine.Wn[:, i], atol=1e-9)
                np.testing.assert_allclose(geo.Wt[:, j], mine.Wt[:, i], atol=1e-9)
                np.testing.assert_allclose(geo.Jn[j], mine.Jn[i], atol=1e-9)
                np.testing.assert_allclose(geo.Jt[j], mine.Jt[i], atol=1e-9)
            np.testing.assert_allclose(geo.g_obj, mine.g_obj, atol=1e-12)
            checked += 1
    assert checked >= 6


def test_rod_on_a_table_with_one_contact_has_no_quasistatic_solution():
    """Section 2.2: a rod touching a table at one point off its centre of mass."""
    from qsplan.mechanics import make_scene, wrench_matrices

    Wn, Wt = wrench_matrices([[0.5, 0.0]], [[0.0, 1.0]])
    scene = make_scene(Wn, Wt, np.zeros((1, 1)), np.zeros((1, 1)), [0.5], [0.0, -1.0, 0.0], joint_velocity=[0.0])
    motion = simulate(frozen_scene_system(scene), np.zeros(4), 1.0)
    assert motion.stopped.kind == "jam" and motion.segments == ()
    assert "no solution (Section 2.2)" in motion.stopped.message and "(eq. 29)" in motion.stopped.message
