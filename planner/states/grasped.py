"""Samples and scenes of a named grasp (which feature each finger touches) along the palm.

The scripted tasks touch the workpiece with both fingers' inner edges at the vertices of
tangency (:func:`qsplan.hands.two_finger.finger_angles`); the automatic planner
(:mod:`qsplan.planner.search`) also puts fingertips on edges.  :func:`grasp_samples` is the
grasp form of :func:`qsplan.planner.states.contact.contact_samples` (its callers pass
``grasp``), :func:`grasp_scenes` the scenes the band tables need; both build on the closed forms
of :func:`qsplan.hands.grasp_geometry.grasp_configurations` and the hand's scenes
(:func:`qsplan.hands.two_finger_scene.hand_scene`: analytic at a grasp, from the polygons
elsewhere).  Units SI (m, rad, m/s, rad/s).
"""

from __future__ import annotations

import numpy as np

from qsplan.mechanics.errors import QsplanError, SceneError

__all__ = ["controlled", "grasp_samples", "grasp_scene_arrays", "grasp_scenes"]


def _frozen(a):
    a = np.asarray(a)
    a.setflags(write=False)
    return a


def controlled(scene, effort_joint: int, velocity: float):
    """``scene`` with joint ``effort_joint`` effort-controlled (effort 0) and the other moving at ``velocity``
    (rad/s): the same contacts, wrenches and Jacobians (eqs. 1-5), other inputs; 10-20 times cheaper than
    building the scene again (the band tables need four control variants of every configuration)."""
    from dataclasses import replace

    e = np.arange(scene.n_joints) == effort_joint
    return replace(scene, effort_controlled=_frozen(e), joint_velocity=_frozen(np.where(e, np.nan, float(velocity))),
                   joint_effort=_frozen(np.where(e, 0.0, np.nan)))  # fmt: skip


def grasp_scenes(hand, conf, idx, effort_joint, xdot, reasons: dict | None = None) -> list:
    """Scenes of the configurations ``conf`` (:class:`qsplan.hands.grasp_geometry.GraspConfigurations`) at
    indices ``idx`` with the workpiece moving at ``xdot`` (m/s) and ``effort_joint`` (0/1 or "left"/"right")
    effort-controlled; the other joint moves at ``dq_dx * xdot`` (rad/s), keeping both contacts.  Built from the
    grasp's known contacts (:func:`qsplan.hands.batch_scenes.grasp_scenes`, checked to be the polygon search's),
    else by :func:`qsplan.hands.two_finger_scene.hand_scene`, which says what the polygons give.  Where they
    give no four-contact scene, the error is raised, or, with ``reasons`` (a dict), the scene is None and
    ``reasons[k]`` (``k`` the position in ``idx``) says why."""
    from qsplan.hands.batch_scenes import grasp_scenes as known_contact_scenes
    from qsplan.hands.two_finger import JOINT_NAMES
    from qsplan.hands.two_finger_scene import hand_scene

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


def grasp_scene_arrays(hand, conf, idx, reasons: dict | None = None):
    """The model arrays of the scenes :func:`grasp_scenes` builds at the indices ``idx`` of ``conf``, with no object per
    state (the band tables): the closed form's contacts for all states at once
    (:func:`qsplan.hands.batch_scenes.checked_scene_arrays`), :func:`qsplan.hands.two_finger_scene.hand_scene` where it
    refuses.  Where the polygons give no four-contact scene, the error is raised, or, with ``reasons`` (a dict), the
    state's arrays are NaN and ``reasons[k]`` (``k`` the position in ``idx``) says why.

    Returns
    -------
    arrays : qsplan.hands.batch_scenes.SceneArrays
        ``len(idx)`` states; the scenes' ``Wn, Wt, Jn, Jt, g_obj, g_man`` bit for bit.
    generic : dict of int to Scene
        The scenes the generic path built (``k`` to scene; :func:`controlled` gives their control variants).
    """
    from qsplan.hands.batch_scenes import checked_scene_arrays
    from qsplan.hands.two_finger_scene import hand_scene

    sub = conf.take(np.asarray(list(idx), dtype=int))
    arrays, ok = checked_scene_arrays(hand, sub)
    poses = sub.poses(hand.rest_height)
    generic = {}
    for k in np.flatnonzero(~ok):
        try:
            scene = hand_scene(hand, poses[k], sub.q[k], "right", velocity=float(sub.dq_dx[k, 0] * 0.0))
        except QsplanError as exc:  # the polygons give no four-contact scene here (e.g. vertex on vertex)
            if reasons is None:
                raise
            reasons[int(k)] = f"no four-contact scene: {exc}"
            continue
        generic[int(k)] = scene
        for name in ("Wn", "Wt", "Jn", "Jt", "g_obj", "g_man"):
            getattr(arrays, name)[k] = getattr(scene, name)
    return arrays, generic


def grasp_samples(hand, grasp, xs, effort_joint, speed):
    """``(poses (n, 3), q (n, 2), qd (n, 2), touching (n, 2), scenes)`` of ``grasp`` at workpiece ``xs`` (m)
    moving at ``speed`` (m/s, signed), as :func:`qsplan.planner.states.contact.contact_samples` needs.

    Raises
    ------
    SceneError
        Where the grasp has no configuration (naming the first such x).
    """
    from qsplan.hands.grasp_geometry import grasp_configurations

    xs = np.atleast_1d(np.asarray(xs, float))
    conf = grasp_configurations(hand, grasp, xs)
    if not np.all(conf.ok):
        k = int(np.argmin(conf.ok))
        raise SceneError(f"grasp: {grasp.label} has no configuration at x = {xs[k]:.6g} m")
    scenes = grasp_scenes(hand, conf, range(len(xs)), effort_joint, speed)
    return conf.poses(hand.rest_height), conf.q, conf.dq_dx * speed, conf.touched, scenes
