"""Everything downstream of the planner for any two-finger hand (issue 15): export, certifier, replay, collisions and
plots on plans of described chain hands, built here without the planner.

A synthetic in-contact segment holds the fingers' free joints (each finger's joints but its last) and closes the
last joints onto the workpiece at every row (:func:`qsplan.hands.chains.hand.close_grasp`); the velocities are
finite differences, the mode follows from the kinematics, the band is
:func:`qsplan.mechanics.bands.batched_robust.robust_bands` on the rows' scenes and the command keeps the plans' margin
inside it (:func:`qsplan.planner.torque.command.segment_command`).
"""

import csv
import json

import numpy as np
import pytest

from qsplan.hands.chains.hand import chain_scene, close_grasp, make_chain_hand
from qsplan.hands.description import load_hand, make_hand_description
from qsplan.hands.paper_hand.two_finger import DEFAULT_WORKPIECE
from qsplan.mechanics import QsplanError
from qsplan.mechanics.bands.batched_robust import robust_bands
from qsplan.planner.certify.certify import certify_plan, read_plan, task_from_metadata
from qsplan.planner.export.plan_files import export_plan, plan_columns, read_plan_csv
from qsplan.planner.plan.table import is_word_column
from qsplan.planner.export.schema import check_schedule_document, check_schedule_files
from qsplan.planner.plan.results import ContactSegmentPlan, Plan, RegraspPlan
from qsplan.planner.plan.timing import time_scale
from qsplan.planner.replay.replay import replay_plan
from qsplan.planner.search.ompl_bridge import PlanResult
from qsplan.hands.geometry.collision import find_collisions, find_collisions_batch, shapely_collisions
from qsplan.planner.task.task import make_task
from qsplan.planner.torque.command import MAX_MARGIN_RESOLUTIONS, segment_command

#: The hexagon the parallel-jaw gripper holds by its side corners (m, as written).
HEXAGON = [[0.0, 0.0], [0.06, 0.0], [0.08, 0.05], [0.05, 0.09], [0.01, 0.09], [-0.02, 0.05]]

#: Free joints of the two-link hand's grasp (rad): proximal joints held at 1.4 and 1.9 rad (at 1.74 rad the
#: right finger's band closes near x = -0.007 m: no effort keeps 4S at some friction vertex).
FREE = [1.4, 0.0, 1.9, 0.0]

#: Tangential speed, relative to the workpiece's, below which a contact rolls: a rolling contact's computes as
#: ~1e-16 of it, a sliding one's is 1e-3 of it or more on these hands.
SLIP_TOL = 1e-9

#: Largest distance (m) between the re-simulated and the planned workpiece x: the velocity commands are finite
#: differences (second order, 0.5 mm rows), interpolated linearly; they move the workpiece within 2e-6 m.
REPLAY_X_TOL = 1e-5


def kinematic_mode(scene, qd, xdot) -> str:
    """The mode letters of the motion: ``S`` where a contact's tangential velocity (eq. 6) is not zero, else ``R``."""
    vt = scene.Wt.T @ np.array([xdot, 0.0, 0.0]) - scene.Jt @ qd
    return "".join("S" if abs(v) > SLIP_TOL * abs(xdot) else "R" for v in vt)


def segment(task, name, x0, x1, free, effort_joint, t0=0.0, n=21) -> ContactSegmentPlan:
    """A synthetic in-contact segment sliding the workpiece from ``x0`` to ``x1`` (m) at the task's speed, the free
    joints held at ``free`` (n_j,) or moved as ``free(x)``."""
    hand = task.hand.chain
    e = np.array([n_ == effort_joint for n_ in hand.joint_names])
    v = task.workpiece_speed
    xs = np.linspace(x0, x1, n)
    t = t0 + np.abs(xs - x0) / v
    closed = [close_grasp(hand, x, free(x) if callable(free) else free) for x in xs]
    assert all(c is not None for c in closed) and len({tuple(f.key for f in c[1]) for c in closed}) == 1
    q = np.array([c[0] for c in closed])
    qd = np.gradient(q, t, axis=0, edge_order=2)
    if not callable(free):
        qd[:, hand.free_joints()] = 0.0  # held: exactly zero, not a rounding of it
    scenes = [chain_scene(hand, task.pose(x), qk, e, np.where(e, 0.0, d)) for x, qk, d in zip(xs, q, qd)]
    mode = kinematic_mode(scenes[0], qd[0], np.sign(x1 - x0) * v)
    bands = robust_bands(scenes, mode, task.mu_range, shared=task.shared_mu, force_margin=task.force_margin,
                         disturbance=task.disturbance)
    assert all(b.feasible for b in bands), next(b.reason for b in bands if not b.feasible)
    lower, upper = np.array([b.lower for b in bands]), np.array([b.upper for b in bands])
    m = min(0.5 * float(np.min(upper - lower)), MAX_MARGIN_RESOLUTIONS * task.torque_resolution)
    command, margin = segment_command(lower, upper, m)
    competitors = tuple(sorted({c for b in bands for c in b.competitors}))
    return ContactSegmentPlan(name, effort_joint, mode, np.array([x0, x1]), t, xs, q, np.where(e, np.nan, qd), lower,
                              upper, command, margin, competitors, v, PlanResult(xs[:, None], True, "synthetic", n, 0.0))  # fmt: skip


def regrasp(name, x, q_from, q_open, t0, duration=0.5) -> RegraspPlan:
    """Open the fingers to ``q_open`` and close them back, every joint velocity-controlled."""
    q = np.array([q_from, q_open, q_from])
    qd = np.array([(q_open - q_from) / duration, (q_from - q_open) / duration, np.zeros_like(q_from)])
    return RegraspPlan(name, float(x), t0 + np.array([0.0, duration, 2 * duration]), q, qd, ())


def plan_of(task, phases) -> Plan:
    """The phases as a plan, timed as the planner times its plans (stops at every phase's ends)."""
    return time_scale(Plan(task, tuple(phases), 0.0, sum(p.t.size for p in phases), 0.0))


@pytest.fixture(scope="module")
def two_link(tmp_path_factory):
    """The two-link hand slides the workpiece 1 cm left (the right distal joint torque-controlled), regrasps, slides it
    back (the left distal joint torque-controlled): ``(plan, out_dir)``."""
    hand = make_chain_hand(load_hand("two_link_hand"), DEFAULT_WORKPIECE)
    task = make_task(hand, 0.0, [-0.01, 0.0], name="synthetic two-link")
    s1 = segment(task, "segment 1: x 0 -> -0.01 m", 0.0, -0.01, FREE, "right_distal")
    r = regrasp("regrasp 1", -0.01, s1.q[-1], s1.q[-1] + [0.0, 0.2, 0.0, -0.2], s1.t[-1])
    s2 = segment(task, "segment 2: x -0.01 -> 0 m", -0.01, 0.0, FREE, "left_distal", t0=r.t[-1])
    plan = plan_of(task, (s1, r, s2))
    out = tmp_path_factory.mktemp("two_link")
    export_plan(plan, out)
    return plan, out


@pytest.fixture(scope="module")
def jaws(tmp_path_factory):
    """The bundled parallel-jaw gripper slides the hexagon 1 cm left, the left jaw force-controlled."""
    hand = make_chain_hand(load_hand("parallel_jaw"), HEXAGON)
    task = make_task(hand, 0.0, [-0.01], name="synthetic jaws")
    plan = plan_of(task, (segment(task, "segment 1: x 0 -> -0.01 m", 0.0, -0.01, [0.0, 0.0], "left_jaw"),))
    out = tmp_path_factory.mktemp("jaws")
    export_plan(plan, out)
    return plan, out


def test_the_synthetic_plans_are_what_the_kinematics_gives(two_link, jaws):
    (plan, _), (jplan, _) = two_link, jaws
    s1, _, s2 = plan.phases
    assert (s1.mode, s2.mode, jplan.phases[0].mode) == ("SSSS", "SSSS", "SSSS")  # the tilted jaws slide down the corners
    assert np.all(np.isposinf(s1.upper)) and np.all(np.isneginf(s2.lower))  # a finger squeezing one way
    assert np.all(s1.command > s1.lower) and np.all(s2.command < s2.upper)
    b = jplan.phases[0]
    assert np.all(np.isfinite(b.upper)) and np.all(b.command > b.lower) and np.all(b.command < b.upper)


def test_export_has_every_joint_with_its_units(two_link, jaws):
    (plan, out), (jplan, jout) = two_link, jaws
    cols, units = plan_columns(plan)
    names = plan.task.hand.joint_names
    assert list(cols)[: 1 + 2 * len(names)] == ["t", *(f"q_{n}" for n in names), *(f"qd_{n}" for n in names)]
    assert [k for k in cols if k.startswith("tau_")] == [f"tau_{n}{s}" for n in names for s in ("", "_min", "_max")]
    assert units["q_left_distal"] == "rad" and units["tau_right_distal_max"] == "N m"
    jcols, junits = plan_columns(jplan)
    assert [junits[f"{c}_left_jaw"] for c in ("q", "qd", "tau", "tau")] == ["m", "m/s", "N", "N"]
    for d in (out, jout):
        assert check_schedule_files(d / "plan.json") == []
    doc = json.loads((jout / "plan.json").read_text())
    assert doc["descriptions"]["q_right_jaw"] == "joint position" and "force" in doc["descriptions"]["tau_left_jaw"]
    assert doc["metadata"]["limits"]["joints"]["left_jaw"] == {"range": [0.0, 0.1], "unit": "m", "speed": 0.05,
                                                              "speed_unit": "m/s"}  # fmt: skip
    assert doc["metadata"]["phases"][0]["effort_unit"] == "N"
    assert doc["units"]["margin"] == "N" and units["margin"] == "N m"  # the effort joint's unit
    assert [k for k in cols if k.startswith("control_")] == [f"control_{n}" for n in names]  # after the old columns
    back = read_plan_csv(out / "plan.csv")
    for k, v in cols.items():
        if is_word_column(k):
            assert back[k].tolist() == v
        else:
            np.testing.assert_array_equal(back[k], np.asarray(v, float))
    assert set(back["effort_joint"]) == {"right_distal", "none", "left_distal"}


@pytest.mark.parametrize("mutate, match", [
    (lambda d: d["data"].pop("tau_left_distal_max"), "missing 'tau_left_distal_max'"),
    (lambda d: d["units"].update(q_left_distal="m"), r"units.q_left_distal: expected 'rad'"),
    (lambda d: d["data"]["effort_joint"].__setitem__(0, "left"), "'left' is no joint of the hand"),
    (lambda d: d["metadata"]["hand"].pop("description"), "hand"),
])  # fmt: skip
def test_the_schema_checks_a_chain_plans_joints(two_link, mutate, match):
    doc = json.loads((two_link[1] / "plan.json").read_text())
    mutate(doc)
    errors = check_schedule_document(doc)
    assert errors and any(match in e for e in errors), errors


def test_export_refuses_joint_names_that_cannot_name_a_column(tmp_path):
    def jaw(name, x):
        return {"name": name, "joints": [{"name": f"{name.title()} Jaw", "type": "prismatic", "origin": [x, 0.0, 0.0],
                                          "limits": [-0.1, 0.1], "speed": 0.05,
                                          "link": {"polygon": [[0, 0.003], [0.012, 0.003], [0.012, 0.13], [0, 0.13]]}}]}  # fmt: skip

    desc = make_hand_description("jaws", [[-0.16, -0.02], [0.16, -0.02], [0.16, 0.0], [-0.16, 0.0]],
                                 [jaw("left", -0.09), jaw("right", 0.09)])  # fmt: skip
    task = make_task(make_chain_hand(desc, HEXAGON), 0.0, [-0.01])
    plan = plan_of(task, (regrasp("r", 0.0, np.zeros(2), np.zeros(2), 0.0),))
    with pytest.raises(QsplanError, match="^hand.joint_names: 'Left Jaw' cannot name a plan column"):
        export_plan(plan, tmp_path)


def test_genuine_chain_plans_certify_from_the_task_and_from_the_metadata(two_link, jaws):
    for plan, out in (two_link, jaws):
        cert = certify_plan(out, plan.task, n_random=2, force_margin=plan.task.force_margin.normal)
        assert cert.ok, "\n".join(map(str, cert.violations[:5]))
        assert all(r.friction_points == 16 + 2 for r in cert.rows if r.mode != "free")
        cols, meta = read_plan(out)
        task = task_from_metadata(meta, cols)
        assert type(task.hand) is type(plan.task.hand) and task.hand.joint_names == plan.task.hand.joint_names
        np.testing.assert_array_equal(task.joint_limits, plan.task.joint_limits)
        np.testing.assert_array_equal(task.joint_speeds, plan.task.joint_speeds)
        assert task.start_x == 0.0 and task.waypoints.tolist() == plan.task.waypoints.tolist()
        assert certify_plan(out / "plan.json", task, n_random=0).ok


def _corrupt(src, dst, edit):
    """Copy plan.csv from ``src`` into ``dst`` with ``edit(rows: list of dict)`` applied."""
    dst.mkdir()
    with open(src / "plan.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    edit(rows)
    with open(dst / "plan.csv", "w", newline="") as f:
        w = csv.DictWriter(f, list(rows[0]), lineterminator="\n")
        w.writeheader()
        w.writerows(rows)
    return dst


def test_a_torque_outside_its_band_and_a_joint_beyond_its_limit_are_named(two_link, tmp_path):
    plan, out = two_link

    def edit(rows):
        rows[5]["tau_right_distal"] = repr(float(rows[5]["tau_right_distal_min"]) - 0.5)
        rows[10]["q_left_proximal"] = repr(3.2)

    bad = certify_plan(_corrupt(out, tmp_path / "bad", edit), plan.task, n_random=0)
    assert not bad.ok and {v.row for v in bad.violations} <= {4, 5, 9, 10}
    torque = [v for v in bad.violations if v.kind == "torque"]
    assert len(torque) == 1 and torque[0].row == 5
    assert torque[0].message.startswith("right_distal joint torque ") and "0.5 N m past the edge" in torque[0].message
    assert any(v.kind == "mode" and v.row == 5 for v in bad.violations)  # beyond the lower edge: 4S is not guaranteed
    limit = [v for v in bad.violations if v.kind == "joint limit"]
    assert [(v.row, v.message) for v in limit] == [(10, "left_proximal joint at 3.2 rad, outside its limits "
                                                        "[0.05, 3.09] rad")]  # fmt: skip
    assert any(v.kind == "speed" and v.row == 9 for v in bad.violations)  # the step into row 10


def test_a_jaw_beyond_its_limit_is_named_in_metres(jaws, tmp_path):
    plan, out = jaws

    def edit(rows):
        rows[3]["q_right_jaw"] = repr(0.12)
        rows[7]["tau_left_jaw"] = "nan"

    bad = certify_plan(_corrupt(out, tmp_path / "bad", edit), plan.task, n_random=0)
    messages = {(v.row, v.kind): v.message for v in bad.violations}
    assert messages[(3, "joint limit")] == "right_jaw joint at 0.12 m, outside its limits [0, 0.1] m"
    assert messages[(2, "speed")].startswith("right_jaw joint moves") and "m/s > limit 0.05 m/s" in messages[(2, "speed")]
    assert messages[(7, "torque")].startswith("left_jaw joint: no force command or band (f = nan")


def test_a_link_folded_onto_its_parent_overlaps_outside_the_housing(two_link, tmp_path):
    plan, out = two_link

    def edit(rows):  # the left distal link folded back over its proximal link
        rows[2]["q_left_distal"] = repr(-2.6)

    bad = certify_plan(_corrupt(out, tmp_path / "bad", edit), plan.task, n_random=0)
    overlaps = [v.message for v in bad.violations if v.kind == "overlap" and v.row == 2]
    assert any(m.startswith("left_proximal link / left_distal link overlap") for m in overlaps), overlaps
    hand, q = plan.task.hand, plan.phases[0].q[2].copy()
    assert find_collisions(hand, plan.task.pose(plan.phases[0].x[2]), q) == []  # the distal root turns in its housing
    q[1] = -2.6
    assert ("left_proximal link", "left_distal link") in {c.bodies for c in find_collisions(hand, plan.task.pose(0), q)}


def test_collisions_of_chain_hands_agree_with_shapely():
    rng = np.random.default_rng(15)
    for name, workpiece in (("two_link_hand", DEFAULT_WORKPIECE), ("parallel_jaw", HEXAGON)):
        hand = make_chain_hand(load_hand(name), workpiece)
        lim = hand.description.joint_limits
        poses, qs = [], []
        for i in range(300):
            x = rng.uniform(-0.03, 0.03)
            q = rng.uniform(lim[:, 0], lim[:, 1])
            closed = close_grasp(hand, x, q) if i % 2 else None
            if closed is not None:
                q = closed[0] + (rng.normal(0.0, 1e-3, q.size) if i % 4 == 1 else 0.0)
            poses.append(hand.pose(x))
            qs.append(q)
        poses, qs = np.array(poses), np.array(qs)
        hit = find_collisions_batch(hand, poses, qs)
        for i in range(len(poses)):
            ref = shapely_collisions(hand, poses[i], qs[i])
            assert hit[i] == bool(ref) and find_collisions(hand, poses[i], qs[i]) == ref, (name, i)
        assert 0 < hit.sum() < len(hit)


def test_a_prismatic_jaw_has_no_housing(jaws):
    plan, _ = jaws
    hand, pose = plan.task.hand, plan.task.pose(0.0)
    q = plan.phases[0].q[0]
    assert find_collisions(hand, pose, q) == []
    away = plan.task.pose(0.3)  # the workpiece out of the way
    # the left jaw's axis leans down toward the palm: 2 cm past its limit the jaw's foot dips 1 mm into the palm,
    # which a revolute joint's housing (1.12 times the link's y-extent: ~0.1 m for the jaw) would have hidden
    assert find_collisions(hand, away, [0.1, 0.05]) == []
    assert [c.bodies for c in find_collisions(hand, away, [0.12, 0.05])] == [("palm", "left_jaw link")]


def test_replays_follow_the_planned_modes(two_link, jaws):
    rng = np.random.default_rng(7)
    for plan, out in (two_link, jaws):
        cols, scenes = read_plan_csv(out / "plan.csv"), {}
        for mu in (np.zeros(4), np.full(4, 0.2), rng.uniform(0.0, 0.2, 4)):
            r = replay_plan(cols, plan.task.hand, mu, scenes=scenes)
            assert r.followed, r.summary()
            assert [s.labels for s in r.segments] == [(s.mode,) for s in plan.segments]
            assert r.x_error < REPLAY_X_TOL


def test_replay_catches_a_command_outside_the_band(two_link):
    plan, out = two_link
    cols = read_plan_csv(out / "plan.csv")
    bad = dict(cols, tau_right_distal=cols["tau_right_distal_min"] - 0.5)
    r = replay_plan(bad, plan.task.hand, 0.2)
    assert not r.followed and r.segments[0].phase == 0 and "feasible modes" in r.segments[0].stop
    with pytest.raises(QsplanError, match="row 0's mode SSSS has 4 letters, and the polygons show 3 contacts"):
        replay_plan(dict(cols, q_left_distal=cols["q_left_distal"] + 0.1), plan.task.hand, 0.2)


def test_horizontal_jaws_roll_in_a_mode_outside_the_model():
    """Jaws sliding along x carry the workpiece: its contacts roll (SSRR), six constraints on the four unknowns of a
    force-controlled jaw (eq. 29): the quasistatic model has no such mode, so no band exists.  (The bundled jaws lean:
    their contacts slide, 4S.)"""
    from qsplan.mechanics.errors import ModeError

    def jaw(name, x, polygon, limits):
        return {"name": name, "joints": [{"name": f"{name}_jaw", "type": "prismatic", "origin": [x, 0.0, 0.0],
                                          "limits": limits, "speed": 0.05, "link": {"polygon": polygon}}]}  # fmt: skip

    desc = make_hand_description("horizontal jaws", [[-0.16, -0.02], [0.16, -0.02], [0.16, 0.0], [-0.16, 0.0]], [
        jaw("left", -0.09, [[-0.012, 0.003], [0, 0.003], [0, 0.13], [-0.012, 0.13]], [0.0, 0.085]),
        jaw("right", 0.09, [[0, 0.003], [0.012, 0.003], [0.012, 0.13], [0, 0.13]], [-0.085, 0.0])])  # fmt: skip
    hand = make_chain_hand(desc, HEXAGON)
    q, _ = close_grasp(hand, 0.0, [0.0, 0.0])
    e = np.array([True, False])
    scene = chain_scene(hand, hand.pose(0.0), q, e, [0.0, -0.01])
    assert kinematic_mode(scene, np.array([-0.01, -0.01]), -0.01) == "SSRR"
    with pytest.raises(ModeError, match="SSRR: has 6 applicable constraints but the scene's partition needs 4"):
        robust_bands([scene], "SSRR", (0.0, 0.2))


def test_plots_draw_every_link_and_a_row_per_velocity_controlled_joint(two_link, jaws):
    from matplotlib.patches import Polygon as Patch

    from qsplan.planner.plotting.card import plan_card
    from qsplan.planner.plotting.hands import plot_hand
    from qsplan.planner.plotting.plan import plot_plan_bands

    plan, _ = two_link
    ax = plot_hand(plan.task.hand, plan.task.pose(0.0), plan.phases[0].q[0], effort_joint="right_distal",
                   label_joints=True)  # fmt: skip
    assert sum(type(p) is Patch for p in ax.patches) == 6  # palm, four links, workpiece (arrows aside)
    assert max(p.get_linewidth() for p in ax.patches) == 2.4 and any("tau" in t.get_text() for t in ax.texts)
    assert {t.get_text() for t in ax.texts} >= set(plan.task.hand.joint_names)
    titles = [a.get_title(loc="left") for a in plan_card(plan).axes]
    for joint in plan.task.hand.joint_names:
        assert f"{joint} joint: velocity command" in titles
    assert "left_distal joint: torque command inside its guaranteed band; +: counter-clockwise" in titles
    jplan, _ = jaws
    card = plan_card(jplan)
    assert "left_jaw joint: force command inside its guaranteed band; +: along +q" in [a.get_title(loc="left")
                                                                                     for a in card.axes]
    assert any(a.get_ylabel() == "$\\dot q$ (m/s)" for a in card.axes)
    assert plot_plan_bands(jplan)[0].get_ylabel() == "$f_{left\\_jaw}$ (N)"


def test_a_sliding_direction_that_reverses_between_rows_is_a_mode_change(tmp_path):
    """The proximal joints turning while the workpiece slides 3 cm left: the right fingertip's sliding velocity crosses
    zero near x = -12.75 mm (t = 1.275 s).  Every row's letters read SSSS and every row's mode check passes, but the
    contact stops sliding in between (eq. 16): the certifier names the row after the reversal, and the replay stops
    at the reversal."""
    hand = make_chain_hand(load_hand("two_link_hand"), DEFAULT_WORKPIECE)
    task = make_task(hand, 0.0, [-0.03], name="slip reversal")

    def free(x):  # linear in x, as a planner's straight path in the free joints
        s_ = x / -0.03
        return [1.4 + 0.17 * s_, 0.0, 1.74 + 0.6985714285714284 * s_, 0.0]

    plan = plan_of(task, (segment(task, "slide", 0.0, -0.03, free, "left_proximal", n=61),))
    export_plan(plan, tmp_path)
    cert = certify_plan(tmp_path, task, n_random=0)
    assert [(v.row, v.kind) for v in cert.violations] == [(26, "mode")]
    assert cert.violations[0].message.startswith("contact right slides at 0.14")
    assert "its sliding direction reverses in between" in cert.violations[0].message
    r = replay_plan(read_plan_csv(tmp_path / "plan.csv"), hand, 0.2)
    assert not r.followed and r.segments[0].stop.startswith("at t = 1.27") and "jam" in r.segments[0].stop
