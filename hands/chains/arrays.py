"""The model's matrices of a described hand's grasps at many states at once (Section 3, eqs. 1-5).

The batched twins of what :func:`qsplan.mechanics.model.geometric_scene.scene_from_geometric_scene` builds
one scene at a time (the reference the tests compare against): ``W_n, W_t`` by
:func:`qsplan.mechanics.model.contact.wrench_matrices` itself (eq. 1), the contact Jacobians ``J_n, J_t``
(eq. 5) of :func:`qsplan.mechanics.model.manipulator.contact_jacobian` over states, the workpiece's weight
``g_obj`` (eq. 2) and the links' gravity efforts ``g_man`` (eq. 3) of
:func:`qsplan.mechanics.model.manipulator.gravity_efforts` over states.  Any serial tree of revolute and
prismatic joints, any number of contacts.  Units SI (m, rad, N, N m).
"""

from __future__ import annotations

import numpy as np

from qsplan.mechanics.model.contact import wrench_matrices

__all__ = ["contact_jacobians", "gravity_efforts_batch", "joint_paths", "scene_arrays_of"]


def joint_paths(man) -> np.ndarray:
    """``paths[k, i]``: joint ``i`` lies on the path from the palm to link ``k``, shape (n_j, n_j)."""
    n = man.n_joints
    paths = np.zeros((n, n), dtype=bool)
    for i, j in enumerate(man.joints):
        if j.parent >= 0:
            paths[i] = paths[j.parent]
        paths[i, i] = True
    return paths


def _columns(man, poses, points) -> np.ndarray:
    """Linear-velocity Jacobian columns of world ``points`` (n, c, 2) as if fixed to every link, at link ``poses``
    (n, n_j, 3): ``z x (p - o_i)`` for a revolute joint, its axis ``(cos a_i, sin a_i)`` for a prismatic one;
    shape (n, c, 2, n_j)."""
    rev = np.array([j.kind == "revolute" for j in man.joints], dtype=bool)
    rel = points[:, :, None, :] - poses[:, None, :, :2]  # (n, c, n_j, 2): lever arms from the revolute axes
    rot = np.stack([-rel[..., 1], rel[..., 0]], axis=2)  # (n, c, 2, n_j)
    axis = np.stack([np.cos(poses[..., 2]), np.sin(poses[..., 2])], axis=1)[:, None]  # (n, 1, 2, n_j)
    return np.where(rev, rot, axis)


def contact_jacobians(man, poses, points, normals, bodies) -> tuple:
    """``J_n, J_t`` (eq. 5) of ``c`` contacts at ``n`` states.

    Parameters
    ----------
    man : qsplan.mechanics.model.manipulator.Manipulator
    poses : ndarray, shape (n, n_j, 3)
        Link poses (:func:`qsplan.hands.chains.closing_batch.link_poses_batch`).
    points, normals : ndarray, shape (n, c, 2)
        Contact points (m) and normals into the workpiece (normalised here).
    bodies : ndarray of int, shape (n, c)
        The link carrying each contact, -1 for the palm (a zero row).

    Returns
    -------
    Jn, Jt : ndarray, shape (n, c, n_j)
        ``[n^T; t^T] J_p`` with ``t`` the normal turned +90 degrees (m per rad, or m/m).
    """
    cols = _columns(man, poses, points)
    on_path = np.where(bodies[..., None] >= 0, joint_paths(man)[np.maximum(bodies, 0)], False)  # (n, c, n_j)
    cols = np.where(on_path[:, :, None, :], cols, 0.0)
    unit = normals / np.hypot(normals[..., 0], normals[..., 1])[..., None]
    Jn = unit[..., 0, None] * cols[:, :, 0] + unit[..., 1, None] * cols[:, :, 1]
    Jt = -unit[..., 1, None] * cols[:, :, 0] + unit[..., 0, None] * cols[:, :, 1]
    return Jn, Jt


def gravity_efforts_batch(man, poses) -> np.ndarray:
    """``g_man`` (eq. 3) at ``n`` states: ``sum_k m_k g d y_com,k / d q_i``, shape (n, n_j) (N m or N).

    Parameters
    ----------
    poses : ndarray, shape (n, n_j, 3)
        Link poses.
    """
    n = len(poses)
    mass = np.array([j.link_mass for j in man.joints], dtype=float)
    if man.n_joints == 0 or not np.any(mass):
        return np.zeros((n, man.n_joints))
    com = np.array([j.link_com for j in man.joints], dtype=float)
    c, s = np.cos(poses[..., 2]), np.sin(poses[..., 2])
    world = poses[..., :2] + np.stack([c * com[:, 0] - s * com[:, 1], s * com[:, 0] + c * com[:, 1]], axis=-1)
    jy = _columns(man, poses, world)[:, :, 1, :] * joint_paths(man)  # d y_com,k / d q_i: (n, links, joints)
    return np.einsum("k,nki->ni", mass * man.gravity, jy)


def scene_arrays_of(man, workpiece_mass: float, poses_wp, link_poses, points, normals, bodies) -> tuple:
    """The model's matrices of ``n`` states with ``c`` contacts each.

    Parameters
    ----------
    man : qsplan.mechanics.model.manipulator.Manipulator
    workpiece_mass : float
        kg.
    poses_wp : ndarray, shape (n, 3)
        Workpiece poses ``(x, y, theta)``: its centre of mass at ``(x, y)`` (m).
    link_poses : ndarray, shape (n, n_j, 3)
    points, normals : ndarray, shape (n, c, 2)
        Finite (m; into the workpiece).
    bodies : ndarray of int, shape (n, c)

    Returns
    -------
    tuple
        ``Wn, Wt`` (n, 3, c) (eq. 1), ``Jn, Jt`` (n, c, n_j) (eq. 5), ``g_obj`` (n, 3) (eq. 2), ``g_man`` (n, n_j) (eq. 3).
    """
    n, c = points.shape[:2]
    Wn, Wt = wrench_matrices(points.reshape(-1, 2), normals.reshape(-1, 2)) if n else (np.zeros((3, 0)),) * 2
    Wn, Wt = (w.reshape(3, n, c).transpose(1, 0, 2) for w in (Wn, Wt))
    Jn, Jt = contact_jacobians(man, link_poses, points, normals, bodies)
    weight = -workpiece_mass * man.gravity
    # qsplan.mechanics.model.contact.point_wrench of (0, weight) at the centre of mass
    g_obj = np.column_stack([np.zeros(n), np.full(n, weight), poses_wp[:, 0] * weight - poses_wp[:, 1] * 0.0])
    return Wn, Wt, Jn, Jt, g_obj, gravity_efforts_batch(man, link_poses)
