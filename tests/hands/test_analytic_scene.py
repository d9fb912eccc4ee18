"""Analytic scenes of the two-finger hand against the generic polygon path, on hundreds of seeded configurations.

Wherever the generic path (:func:`qsplan.mechanics.find_contacts` on the hand's polygons) builds a
scene, ``hand_scene``'s default path gives the same one to round-off (every array, the contacts in
the same order, the names); wherever the generic path refuses, so does the default one.  The
closed form batched over states (:func:`qsplan.hands.paper_hand.batch_scenes.grasp_contacts_batch`, the band
tables' path) is the one-state closed form bit for bit, and so are the scene arrays built from it.
"""

import numpy as np
import pytest

from qsplan.hands.paper_hand.batch_scenes import checked_scene_arrays, grasp_contacts_batch, grasp_scenes
from qsplan.hands.paper_hand.segments import first_segment
from qsplan.hands.paper_hand.two_finger import default_hand, finger_angles, make_two_finger_hand
from qsplan.hands.paper_hand.analytic import analytic_hand_scene, grasp_contacts, scene_from_arrays
from qsplan.hands.paper_hand.scene import hand_scene
from qsplan.mechanics import SceneError
from qsplan.planner.task.task import load_task, task_paths

from tests.hands.scenes import assert_same_scene



def _compare(hand, pose, q, effort_joint="right", velocity=0.1, effort=0.0, mu=None) -> bool:
    """Both paths at one configuration: the same scene, or both refuse.  True when the analytic one applied."""
    kw = dict(effort_joint=effort_joint, velocity=velocity, effort=effort, mu=mu)
    try:
        g = hand_scene(hand, pose, q, method="generic", **kw)
    except SceneError:
        with pytest.raises(SceneError):
            hand_scene(hand, pose, q, **kw)
        assert grasp_contacts(hand, pose, q) is None
        return False
    assert_same_scene(hand_scene(hand, pose, q, **kw), g)
    return grasp_contacts(hand, pose, q) is not None


@pytest.mark.parametrize("effort_joint", ["left", "right"])
@pytest.mark.parametrize("finger_mass", [0.0, 0.05])
def test_demo_hand_along_segment_1(effort_joint, finger_mass):
    hand = default_hand(finger_mass=finger_mass)
    segment = first_segment(hand)
    used = 0
    for s in np.linspace(0.0, 1.0, 101):
        pose = segment.pose(s)[0]
        q = finger_angles(hand, pose)[0]
        used += _compare(hand, pose, q, effort_joint, velocity=-0.03, effort=0.4, mu=0.15)
    assert used == 101  # every configuration of the segment is a grasp the hand knows


def _paper_task_names() -> list:
    """The bundled tasks of the paper's hand (a described hand has no closed-form grasps: tests/hands/test_closing.py)."""
    return sorted(name for name, path in task_paths().items() if 'file = "' not in path.read_text()
                  or 'file = "paper_hand"' in path.read_text())  # fmt: skip


@pytest.mark.parametrize("name", _paper_task_names())
def test_bundled_tasks_along_their_segments(name):
    from qsplan.hands.paper_hand.grasp_geometry import grasp_configurations

    task = load_task(task_paths()[name])
    if task.goal is not None and task.goal.x is None:  # a turning goal: its palm-edge slide ends at the flush instant
        from tests.reference.paper_pivot import flush_instant

        end = [flush_instant(task.hand).x]
    else:
        end = [task.goal.x] if task.goal is not None else task.waypoints
    stops = np.concatenate([[task.start_x], end])
    used = total = 0
    for a, b in zip(stops[:-1], stops[1:]):
        xs = np.linspace(a, b, 60)
        if task.goal is None:  # the scripted tasks: both inner edges at the vertices of tangency
            for x in xs:
                pose = task.pose(x)
                try:
                    q = finger_angles(task.hand.paper, pose)[0]
                except SceneError:
                    continue
                total += 1
                used += _compare(task.hand.paper, pose, q)
            continue
        for grasp in task.hand.grasp_candidates(task.formation):  # the automatic tasks: every grasp the planner may use
            conf = grasp_configurations(task.hand.paper, grasp, xs)
            for k in np.flatnonzero(conf.ok):
                total += 1
                used += _compare(task.hand.paper, task.pose(xs[k]), conf.q[k])
    assert total > 50 and used >= 0.9 * total


def _random_hand(rng):
    """A convex polygon with a level bottom edge from a seeded rng, or None when the hand refuses it."""
    w = rng.uniform(0.04, 0.09)
    k = int(rng.integers(2, 5))
    ang = np.sort(rng.uniform(0.15, np.pi - 0.15, k))
    top = np.column_stack([0.5 * w - rng.uniform(0.6, 1.0) * 0.5 * w * np.cos(ang),
                           rng.uniform(0.03, 0.1) * np.sin(ang) + 0.005])  # fmt: skip
    try:
        return make_two_finger_hand(np.vstack([[(0.0, 0.0), (w, 0.0)], top[::-1]]), finger_length=0.15,
                                    mu=rng.uniform(0.0, 0.5), finger_mass=rng.choice([0.0, 0.03]))  # fmt: skip
    except SceneError:
        return None


def test_random_polygons_and_configurations():
    rng = np.random.default_rng(1995)
    used = refused = 0
    hands = [h for h in (_random_hand(rng) for _ in range(40)) if h is not None][:12]
    assert len(hands) >= 8
    for hand in hands:
        for _ in range(30):
            pose = np.array([rng.uniform(-0.06, 0.06), hand.rest_height, 0.0])
            try:
                q = finger_angles(hand, pose)[0]
            except SceneError:
                continue
            used += _compare(hand, pose, q, effort_joint=rng.choice(["left", "right"]), velocity=rng.normal())
            # off the grasp: a finger turned into or away from the workpiece, the workpiece lifted or tilted
            dq = rng.choice([1e-9, 1e-7, 1e-5]) * rng.choice([-1.0, 1.0])
            refused += not _compare(hand, pose, q + np.array([dq, 0.0]))
            refused += not _compare(hand, pose + [0.0, rng.choice([2e-7, 5e-6]), 0.0], q)
            refused += not _compare(hand, pose + [0.0, 0.0, 1e-4], q)
    assert used >= 200 and refused >= 100


def test_near_flush_finger_falls_back_to_the_same_refusal():
    hand = default_hand()
    for clearance in (1e-9, 1e-7, 5e-7, 2e-6, 1e-5):
        pose = first_segment(hand, flush_clearance=clearance).pose_end
        _compare(hand, pose, finger_angles(hand, pose)[0])


def test_analytic_scene_off_a_grasp_is_none():
    hand = default_hand()
    pose = np.array([0.0, hand.rest_height + 1e-3, 0.0])
    assert analytic_hand_scene(hand, pose, finger_angles(hand, pose)[0], np.array([False, True])) is None


def test_method_is_validated():
    hand = default_hand()
    with pytest.raises(SceneError, match="method: expected 'auto' or 'generic'"):
        hand_scene(hand, np.array([0.0, hand.rest_height, 0.0]), method="fast")


def test_the_manipulator_is_built_once_per_hand():
    from qsplan.hands.paper_hand.scene import hand_manipulator

    hand, other = default_hand(), default_hand()
    assert hand_manipulator(hand) is hand_manipulator(hand)
    assert hand_manipulator(other) is not hand_manipulator(hand)  # hands compare by identity


def _bits(a, b) -> bool:
    a, b = np.asarray(a), np.asarray(b)
    return a.shape == b.shape and a.dtype == b.dtype and a.tobytes() == b.tobytes()


def _two_finger_tasks():
    tasks = [load_task(p) for p in task_paths().values()]
    return [t for t in tasks if t.hand.accelerated and t.goal is not None]


def _assert_batch_is_the_closed_form(hand, poses, q) -> tuple:
    """:func:`grasp_contacts_batch` against :func:`grasp_contacts` at every state: ``(found, tips)`` counts."""
    batch = grasp_contacts_batch(hand, poses, q)
    found = tips = 0
    for k in range(len(poses)):
        one = grasp_contacts(hand, poses[k], q[k])
        assert batch.ok[k] == (one is not None), k
        if one is None:
            continue
        found += 1
        tips += int(one.tips.sum())
        for f in ("points", "normals", "features", "tips"):
            assert _bits(getattr(batch, f)[k], getattr(one, f)), (k, f)
    return found, tips


def test_batched_closed_form_is_the_one_state_closed_form_bit_for_bit():
    """Every grasp of the bundled goal tasks along the palm, the same turned by 1e-9 to 1e-3 rad or lifted and
    tilted (refusals at the margins), and random polygons at their vertices of tangency."""
    from qsplan.hands.paper_hand.grasp_geometry import grasp_configurations

    rng = np.random.default_rng(2025)
    found = tips = total = 0
    for task in _two_finger_tasks():
        xs = np.linspace(-0.15, 0.15, 121)
        for grasp in task.hand.grasp_candidates(task.formation):
            conf = grasp_configurations(task.hand.paper, grasp, xs)
            poses, q = conf.poses(task.hand.rest_height)[conf.ok], conf.q[conf.ok]
            dq = rng.choice([0.0, 1e-9, 1e-7, 1e-5, 1e-3], size=q.shape) * rng.choice([-1.0, 1.0], size=q.shape)
            lift = np.column_stack([np.zeros(len(poses)), rng.choice([0.0, 2e-7, 5e-6], len(poses)),
                                    rng.choice([0.0, 1e-4], len(poses))])  # fmt: skip
            for p, a in ((poses, q), (poses, q + dq), (poses + lift, q)):
                counts = _assert_batch_is_the_closed_form(task.hand.paper, p, a)
                found, tips, total = found + counts[0], tips + counts[1], total + len(p)
    hands = [h for h in (_random_hand(rng) for _ in range(30)) if h is not None][:8]
    for hand in hands:
        poses = np.column_stack([rng.uniform(-0.06, 0.06, 40), np.full(40, hand.rest_height), np.zeros(40)])
        q = np.array([finger_angles(hand, p)[0] if _reaches(hand, p) else [np.nan, np.nan] for p in poses])
        counts = _assert_batch_is_the_closed_form(hand, poses, q)
        found, tips, total = found + counts[0], tips + counts[1], total + len(poses)
    assert found > 500 and tips > 50 and total - found > 300  # contacts found, fingertips among them, and refusals


def _reaches(hand, pose) -> bool:
    try:
        finger_angles(hand, pose)
    except SceneError:
        return False
    return True


def test_checked_scene_arrays_are_the_scenes_of_grasp_scenes():
    """The band tables' arrays (no object per state) are the arrays of the scenes the one-state path builds, bit
    for bit, and :func:`scene_from_arrays` rebuilds those scenes."""
    from qsplan.hands.paper_hand.grasp_geometry import candidate_grasps, grasp_configurations

    used = 0
    for task in _two_finger_tasks():
        hand = task.hand.paper
        for grasp in candidate_grasps(hand):
            conf = grasp_configurations(hand, grasp, np.linspace(-0.12, 0.12, 97))
            arrays, ok = checked_scene_arrays(hand, conf)
            scenes = grasp_scenes(hand, conf, "left", -0.02)
            for k, scene in enumerate(scenes):
                assert ok[k] == (scene is not None), k
                if scene is None:
                    continue
                used += 1
                rows = [getattr(arrays, f)[k] for f in ("Wn", "Wt", "Jn", "Jt", "g_obj", "g_man")]
                for f, row in zip(("Wn", "Wt", "Jn", "Jt", "g_obj", "g_man"), rows):
                    assert _bits(row, getattr(scene, f)), f
                again = scene_from_arrays(hand, *rows, scene.effort_controlled, conf.dq_dx[k, 1] * -0.02)
                for f in ("mu", "effort_controlled", "joint_velocity", "joint_effort"):
                    assert _bits(getattr(again, f), getattr(scene, f)), f
                assert (again.joint_names, again.contact_names) == (scene.joint_names, scene.contact_names)
    assert used > 150
