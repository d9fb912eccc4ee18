"""Scenes of the two-finger hand of Fig. 9 (Section 5.2) at a configuration.

:func:`hand_geometric_scene` turns a configuration (workpiece pose, joint angles)
of a :class:`~qsplan.hands.paper_hand.two_finger.TwoFingerHand` into the geometric scene form,
and :func:`hand_scene` into a :class:`qsplan.mechanics.Scene`: at a grasp from the
contacts the hand knows (:mod:`qsplan.hands.paper_hand.analytic`), elsewhere, and as
the reference, from contacts found in the polygons by :func:`qsplan.mechanics.find_contacts`.  Contacts are
ordered palm (left end, right end of the bottom edge), left finger, right finger
(:data:`qsplan.hands.paper_hand.two_finger.CONTACT_ROLES`).
"""

from __future__ import annotations

import numpy as np

from qsplan.hands.paper_hand.two_finger import (JOINT_NAMES, TwoFingerHand, finger_angles, hand_manipulator,
                                                workpiece_world)  # fmt: skip
from qsplan.mechanics.errors import SceneError
from qsplan.mechanics.model.friction import check_friction

__all__ = ["hand_manipulator", "hand_geometric_scene", "hand_contacts", "hand_scene", "hand_polygons"]


def hand_geometric_scene(hand: TwoFingerHand, pose, q=None, effort_joint="right", velocity=0.0, effort=0.0, mu=None):
    """The instant as a :class:`qsplan.mechanics.GeometricScene` (polygons, joints, inputs).

    Parameters
    ----------
    pose : array-like, shape (3,)
        Workpiece ``(x, y, theta)`` (m, m, rad).
    q : array-like, shape (2,), optional
        Joint angles (rad); default :func:`finger_angles` (both inner edges on vertices; a fingertip grasp's
        come from :func:`qsplan.hands.paper_hand.grasp_geometry.grasp_configurations`).
    effort_joint : {"left", "right"}
        The effort-controlled (torque) joint; the other is velocity-controlled.
    velocity : float
        Velocity of the velocity-controlled joint (rad/s).
    effort : float
        Torque of the effort-controlled joint (N m); band computations ignore it.
    mu : float, optional
        Friction of every contact; default ``hand.mu``.
    """
    from qsplan.mechanics.model.geometric_scene import GeometricScene
    from qsplan.mechanics.model.geometry import CONTACT_TOL

    e = _effort_mask(effort_joint)
    pose = np.asarray(pose, dtype=float)
    q = finger_angles(hand, pose)[0] if q is None else np.asarray(q, dtype=float)
    V = workpiece_world(hand, pose)
    com = pose[:2].copy()
    frozen = []
    for a in (V, com, np.zeros(3), q, e, np.where(e, np.nan, float(velocity)), np.where(e, float(effort), np.nan)):
        a = np.array(a, copy=True)
        a.setflags(write=False)
        frozen.append(a)
    V, com, extra, q, e, jv, je = frozen
    return GeometricScene(
        workpiece=V, com=com, mass=hand.workpiece_mass, extra_wrench=extra, manipulator=hand_manipulator(hand),
        q=q, effort_controlled=e, joint_velocity=jv, joint_effort=je,
        mu=hand.mu if mu is None else float(check_friction(mu, "mu")),
        contact_mu=(), contact_tolerance=CONTACT_TOL,
    )  # fmt: skip


def _effort_mask(effort_joint) -> np.ndarray:
    if effort_joint not in JOINT_NAMES:
        raise SceneError(f"effort_joint: expected one of {JOINT_NAMES}; got {effort_joint!r}")
    return np.array([name == effort_joint for name in JOINT_NAMES])


def hand_contacts(gs) -> list:
    """The contacts of a hand's geometric scene, checked to be the expected four (see
    :data:`qsplan.hands.paper_hand.two_finger.CONTACT_ROLES`).

    Raises
    ------
    SceneError
        When the geometry gives another contact set (e.g. a finger flush with an
        edge, which gives two contacts on it): the hand's segments end before that.
    """
    from qsplan.mechanics.model.geometric_scene import find_scene_contacts

    found = find_scene_contacts(gs)
    bodies = [c.body for c in found]
    if bodies != [-1, -1, 0, 1]:
        names = [gs.body_name(b) for b in bodies]
        raise SceneError(
            f"contacts: expected palm, palm, left, right (one contact per finger); found {names} at q = {np.round(gs.q, 6).tolist()}"
        )
    return found


def hand_scene(hand: TwoFingerHand, pose, q=None, effort_joint="right", velocity=0.0, effort=0.0, mu=None,
               method="auto"):  # fmt: skip
    """The :class:`qsplan.mechanics.Scene` of the hand at ``pose``.

    Parameters are those of :func:`hand_geometric_scene`, and

    method : {"auto", "generic"}
        ``"auto"`` builds the scene from the grasp's known contacts
        (:func:`qsplan.hands.paper_hand.analytic.analytic_hand_scene`) where the
        configuration is one, else from the polygons; ``"generic"`` always from the
        polygons (:func:`qsplan.mechanics.find_contacts`, the reference: both give
        the same scene to round-off).

    Returns
    -------
    Scene
        Four contacts ``palm:0, palm:1, left:2, right:3``; joints ``left, right``.
    """
    from qsplan.mechanics.model.geometric_scene import scene_from_geometric_scene

    if method not in ("auto", "generic"):
        raise SceneError(f"method: expected 'auto' or 'generic'; got {method!r}")
    if method == "auto":
        from qsplan.hands.paper_hand.analytic import analytic_hand_scene

        e = _effort_mask(effort_joint)
        pose = np.asarray(pose, dtype=float)
        q = finger_angles(hand, pose)[0] if q is None else np.asarray(q, dtype=float)
        mu_ = None if mu is None else float(check_friction(mu, "mu"))
        inputs = np.array([float(velocity), float(effort)])
        if pose.shape == (3,) and q.shape == (2,) and np.all(np.isfinite(pose)) and np.all(np.isfinite(q)) \
                and np.all(np.isfinite(inputs)):  # else the generic path validates and says what is wrong
            scene = analytic_hand_scene(hand, pose, q, e, inputs[0], inputs[1], mu_)
            if scene is not None:
                return scene
    gs = hand_geometric_scene(hand, pose, q, effort_joint, velocity, effort, mu)
    return scene_from_geometric_scene(gs, hand_contacts(gs))


def hand_polygons(hand: TwoFingerHand, pose, q=None) -> dict:
    """World polygons (m) for drawing: ``{"palm", "left", "right", "workpiece"}`` -> ndarray (k, 2)."""
    from qsplan.mechanics.model.manipulator import link_polygons

    pose = np.asarray(pose, dtype=float)
    q = finger_angles(hand, pose)[0] if q is None else np.asarray(q, dtype=float)
    man = hand_manipulator(hand)
    links = link_polygons(man, q)
    out = {"palm": np.asarray(man.base_shape, dtype=float), "workpiece": workpiece_world(hand, pose)}
    for name, poly in zip(JOINT_NAMES, links):
        out[name] = np.asarray(poly.exterior.coords, dtype=float)[:-1]
    return out
