"""Analytic scenes of the two-finger hand against the generic polygon path, on hundreds of seeded configurations.

Wherever the generic path (:func:`qsplan.mechanics.find_contacts` on the hand's polygons) builds a
scene, ``hand_scene``'s default path gives the same one to round-off (every array, the contacts in
the same order, the names); wherever the generic path refuses, so does the default one.
"""

import numpy as np
import pytest

from qsplan.hands.segments import first_segment
from qsplan.hands.two_finger import default_hand, finger_angles, make_two_finger_hand
from qsplan.hands.two_finger_analytic import analytic_hand_scene, grasp_contacts
from qsplan.hands.two_finger_scene import hand_scene
from qsplan.mechanics import SceneError
from qsplan.planner.planning.task import load_task, task_paths

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


@pytest.mark.parametrize("name", sorted(task_paths()))
def test_bundled_tasks_along_their_segments(name):
    from qsplan.hands.grasp_geometry import candidate_grasps, grasp_configurations

    task = load_task(task_paths()[name])
    end = [task.goal.x] if task.goal is not None else task.waypoints
    stops = np.concatenate([[task.start_x], end])
    used = total = 0
    for a, b in zip(stops[:-1], stops[1:]):
        xs = np.linspace(a, b, 60)
        if task.goal is None:  # the scripted tasks: both inner edges at the vertices of tangency
            for x in xs:
                pose = task.pose(x)
                try:
                    q = finger_angles(task.hand, pose)[0]
                except SceneError:
                    continue
                total += 1
                used += _compare(task.hand, pose, q)
            continue
        for grasp in candidate_grasps(task.hand):  # the automatic tasks: every grasp the planner may use
            conf = grasp_configurations(task.hand, grasp, xs)
            for k in np.flatnonzero(conf.ok):
                total += 1
                used += _compare(task.hand, task.pose(xs[k]), conf.q[k])
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
    from qsplan.hands.two_finger_scene import hand_manipulator

    hand, other = default_hand(), default_hand()
    assert hand_manipulator(hand) is hand_manipulator(hand)
    assert hand_manipulator(other) is not hand_manipulator(hand)  # hands compare by identity
