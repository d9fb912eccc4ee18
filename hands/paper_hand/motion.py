"""The paper hand's slides in closed form: the motion of :mod:`qsplan.hands.formations.motion` for the hand of Fig. 9.

For the paper's hand (:class:`qsplan.hands.paper_hand.two_finger.TwoFingerHand`, the accelerator of a described hand of
its form) a slide's configurations come from the closed forms the planner has always used: the inner edges'
tangency (:func:`qsplan.hands.paper_hand.two_finger.finger_angles`, the default grasp of scripted tasks) or a named
grasp's configurations (:func:`qsplan.hands.paper_hand.grasp_geometry.grasp_configurations`), and the scenes from the
grasp's known contacts (:func:`qsplan.hands.paper_hand.batch_scenes.grasp_scenes`), else the polygon search
(:func:`qsplan.hands.paper_hand.scene.hand_scene`).  Units SI (m, rad, m/s, rad/s).
"""

from __future__ import annotations

import numpy as np

from qsplan.mechanics.errors import QsplanError, SceneError

__all__ = ["grasp_samples", "grasp_scenes", "paper_slide_motion", "tangency_samples"]


def tangency_samples(hand, xs, effort_joint, speed):
    """``(poses (n, 3), q (n, 2), qd (n, 2), touching (n, 2), scenes)`` of the inner edges' tangency (the vertex of
    tangency wherever the geometry puts it) at workpiece ``xs`` (m) moving at ``speed`` (m/s, signed).

    Raises
    ------
    SceneError
        Where a configuration has no four-contact grasp.
    """
    from qsplan.hands.paper_hand.two_finger import JOINT_NAMES, finger_angle_rates, finger_angles
    from qsplan.hands.paper_hand.scene import hand_scene

    v = 1 - JOINT_NAMES.index(effort_joint)
    poses, qs, qds, touch, scenes = [], [], [], [], []
    for x in np.atleast_1d(np.asarray(xs, float)):
        pose = np.array([float(x), hand.rest_height, 0.0])
        qd = finger_angle_rates(hand, pose, (speed, 0.0, 0.0))
        q, t = finger_angles(hand, pose)
        scene = hand_scene(hand, pose, q, effort_joint, velocity=qd[v], effort=0.0)
        poses.append(pose), qs.append(q), qds.append(qd), touch.append(t), scenes.append(scene)
    return np.array(poses), np.array(qs), np.array(qds), np.array(touch), scenes


def paper_slide_motion(hand, grasp, xs, xdot, effort_joint: int):
    """:class:`qsplan.hands.formations.motion.SlideMotion` of the paper's hand: ``grasp`` None is the tangency
    (:func:`tangency_samples`), a :class:`qsplan.hands.paper_hand.grasps.Grasp` its closed form
    (:func:`grasp_samples`)."""
    from qsplan.hands.protocol import SlideMotion
    from qsplan.hands.paper_hand.two_finger import JOINT_NAMES

    name = JOINT_NAMES[int(effort_joint)]
    if grasp is None:
        out = tangency_samples(hand, xs, name, xdot)
    else:
        out = grasp_samples(hand, grasp, xs, name, xdot)
    poses, q, qd, touch, scenes = out
    return SlideMotion(np.asarray(poses), np.asarray(q), np.asarray(qd), np.asarray(touch), tuple(scenes))


def grasp_scenes(hand, conf, idx, effort_joint, xdot, reasons: dict | None = None) -> list:
    """Scenes of the configurations ``conf`` (:class:`qsplan.hands.paper_hand.grasp_geometry.GraspConfigurations`) at
    indices ``idx`` with the workpiece moving at ``xdot`` (m/s) and ``effort_joint`` (0/1 or "left"/"right")
    effort-controlled; the other joint moves at ``dq_dx * xdot`` (rad/s), keeping both contacts.  Built from the
    grasp's known contacts (:func:`qsplan.hands.paper_hand.batch_scenes.grasp_scenes`, checked to be the polygon
    search's), else by :func:`qsplan.hands.paper_hand.scene.hand_scene`, which says what the polygons give.  Where they
    give no four-contact scene, the error is raised, or, with ``reasons`` (a dict), the scene is None and
    ``reasons[k]`` (``k`` the position in ``idx``) says why."""
    from qsplan.hands.paper_hand.batch_scenes import grasp_scenes as known_contact_scenes
    from qsplan.hands.paper_hand.two_finger import JOINT_NAMES
    from qsplan.hands.paper_hand.scene import hand_scene

    name = JOINT_NAMES[effort_joint] if isinstance(effort_joint, (int, np.integer)) else effort_joint
    v = 1 - JOINT_NAMES.index(name)
    sub = conf.take(np.asarray(list(idx), dtype=int))
    scenes = known_contact_scenes(hand, sub, name, xdot)
    poses = sub.poses(hand.rest_height)
    out = []
    for k, scene in enumerate(scenes):
        if scene is None:
            try:
                scene = hand_scene(hand, poses[k], sub.q[k], name, velocity=float(sub.dq_dx[k, v] * xdot))
            except QsplanError as exc:  # the polygons give no four-contact scene here (e.g. vertex on vertex)
                if reasons is None:
                    raise
                reasons[k] = f"no four-contact scene: {exc}"
        out.append(scene)
    return out


def grasp_samples(hand, grasp, xs, effort_joint, speed):
    """``(poses (n, 3), q (n, 2), qd (n, 2), touching (n, 2), scenes)`` of ``grasp`` at workpiece ``xs`` (m)
    moving at ``speed`` (m/s, signed), as a slide needs (:func:`paper_slide_motion`).

    Raises
    ------
    SceneError
        Where the grasp has no configuration (naming the first such x).
    """
    from qsplan.hands.paper_hand.grasp_geometry import grasp_configurations

    xs = np.atleast_1d(np.asarray(xs, float))
    conf = grasp_configurations(hand, grasp, xs)
    if not np.all(conf.ok):
        k = int(np.argmin(conf.ok))
        raise SceneError(f"grasp: {grasp.label} has no configuration at x = {xs[k]:.6g} m")
    scenes = grasp_scenes(hand, conf, range(len(xs)), effort_joint, speed)
    return conf.poses(hand.rest_height), conf.q, conf.dq_dx * speed, conf.touched, scenes
