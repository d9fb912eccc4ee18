"""Scenes of a grasp at many workpiece positions at once (Section 3, eqs. 1-5), for planners.

:func:`scene_arrays` stacks the model's matrices of the states of a
:class:`~qsplan.hands.grasp_geometry.GraspConfigurations` (``W_n, W_t`` by
:func:`qsplan.mechanics.model.contact.wrench_matrices`, ``J_n, J_t`` by
:func:`qsplan.hands.two_finger_analytic.finger_jacobians`: the same functions the one-state scenes use);
:func:`grasp_scenes` turns them into :class:`qsplan.mechanics.Scene` objects for a slide at a
given speed, each checked (by default) to be the scene the polygon search would give.  Units SI.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qsplan.hands.grasp_geometry import GraspConfigurations
from qsplan.hands.two_finger import JOINT_NAMES, TwoFingerHand
from qsplan.hands.two_finger_analytic import finger_jacobians, grasp_contacts, gravity_efforts, scene_from_contacts
from qsplan.mechanics.errors import SceneError
from qsplan.mechanics.model.contact import wrench_matrices
from qsplan.mechanics.model.friction import check_friction

__all__ = ["SceneArrays", "grasp_scenes", "scene_arrays"]


@dataclass(frozen=True, slots=True, eq=False)
class SceneArrays:
    """The model's matrices at ``n`` states of one grasp, contacts in the hand's order (palm, palm, left, right).

    Attributes
    ----------
    Wn, Wt : ndarray, shape (n, 3, 4)
        Normal and tangential wrench matrices (eq. 1), about the world origin.
    Jn, Jt : ndarray, shape (n, 4, 2)
        Contact Jacobians (eq. 5; zero rows on the palm) (m).
    g_obj : ndarray, shape (n, 3)
        The workpiece's weight as a wrench about the origin (eq. 2) (N, N, N m).
    g_man : ndarray, shape (n, 2)
        The fingers' gravity efforts (eq. 3) (N m).
    """

    Wn: np.ndarray
    Wt: np.ndarray
    Jn: np.ndarray
    Jt: np.ndarray
    g_obj: np.ndarray
    g_man: np.ndarray


def scene_arrays(hand: TwoFingerHand, configs: GraspConfigurations) -> SceneArrays:
    """:class:`SceneArrays` at every state of ``configs`` (nan where it has no contacts: ``configs.q`` nan; validity is
    ``configs.ok``)."""
    n = len(configs.x)
    has = np.all(np.isfinite(configs.points) & np.isfinite(configs.normals), axis=(1, 2))
    m = int(has.sum())
    Wn, Wt = np.full((n, 3, 4), np.nan), np.full((n, 3, 4), np.nan)
    W = wrench_matrices(configs.points[has].reshape(-1, 2), configs.normals[has].reshape(-1, 2)) if m else (Wn[:0],) * 2
    Wn[has], Wt[has] = (w.reshape(3, m, 4).transpose(1, 0, 2) for w in W)
    J = finger_jacobians(hand, configs.points[:, 2:], configs.normals[:, 2:])
    Jn, Jt = np.zeros((n, 4, 2)), np.zeros((n, 4, 2))
    Jn[:, 2:], Jt[:, 2:] = J[:, :, 0], J[:, :, 1]
    weight = -hand.workpiece_mass * hand.gravity
    g_obj = np.column_stack([np.zeros(n), np.full(n, weight), configs.x * weight - hand.rest_height * 0.0])
    return SceneArrays(Wn, Wt, Jn, Jt, g_obj, gravity_efforts(hand, configs.q))


def grasp_scenes(hand: TwoFingerHand, configs: GraspConfigurations, effort_joint: str = "right", speed: float = 0.0,
                 mu=None, check: bool = True) -> list:  # fmt: skip
    """The scenes of a slide through the states of ``configs``: the workpiece moving along x at ``speed``.

    Parameters
    ----------
    effort_joint : {"left", "right"}
        The torque-controlled joint; the other turns at ``configs.dq_dx * speed`` (rad/s).
    speed : float
        Workpiece velocity along x (m/s).
    mu : float, optional
        Friction of every contact; default ``hand.mu``.
    check : bool
        Build a state's scene only where :func:`qsplan.hands.two_finger_analytic.grasp_contacts` finds exactly the
        expected contacts (the scene the polygon search would give, to round-off); False trusts ``configs.ok``.

    Returns
    -------
    list of Scene or None, length n
        None where ``configs.ok`` is False, or the check fails (the generic path of
        :func:`qsplan.hands.two_finger_scene.hand_scene` says what the polygons give there).
    """
    if effort_joint not in JOINT_NAMES:
        raise SceneError(f"effort_joint: expected one of {JOINT_NAMES}; got {effort_joint!r}")
    mu = None if mu is None else float(check_friction(mu, "mu"))
    e = np.array([name == effort_joint for name in JOINT_NAMES])
    v = JOINT_NAMES.index(effort_joint) ^ 1
    poses = configs.poses(hand.rest_height)
    out = []
    for i in range(len(configs.x)):
        points, normals = configs.points[i], configs.normals[i]
        if not configs.ok[i]:
            out.append(None)
            continue
        if check:
            found = grasp_contacts(hand, poses[i], configs.q[i])
            if found is None or not np.array_equal(found.features[2:], configs.touched[i]) \
                    or not np.array_equal(found.tips, configs.tip):
                out.append(None)
                continue
            points, normals = found.points, found.normals
        velocity = float(configs.dq_dx[i, v] * speed)
        out.append(scene_from_contacts(hand, poses[i], configs.q[i], points, normals, e, velocity, 0.0, mu))
    return out
