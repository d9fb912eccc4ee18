"""A scene from contact points: the mechanics' matrices of contacts given by their points, normals and links.

:func:`points_scene` is the one place that turns located contacts (world points, normals into the workpiece, the
manipulator link carrying each, eq. 1) into a :class:`qsplan.mechanics.Scene` (eqs. 1-5): the named contact sets
(:func:`qsplan.hands.contacts.sets.contact_set_scene`) and the contacts the polygons show
(:func:`qsplan.hands.contacts.found.row_contact_scene`) both build theirs here.  Units SI.
"""

from __future__ import annotations

import numpy as np

from qsplan.mechanics.errors import QsplanError

__all__ = ["points_scene"]


def points_scene(hand, pose, q, points, normals, links, names, effort_controlled, velocity, effort=None, mu=None):
    """The :class:`qsplan.mechanics.Scene` of contacts at world ``points`` with ``normals`` into the workpiece (m;
    shape (n_c, 2)), each on manipulator link ``links[i]`` (-1: the palm), named ``names``; the other arguments as
    :func:`contact_set_scene`."""
    from qsplan.mechanics.model.contact import point_wrench, wrench_matrices
    from qsplan.mechanics.model.manipulator import contact_jacobian, gravity_efforts
    from qsplan.mechanics.model.scene import check_finite_array, make_scene

    pose = check_finite_array(pose, "pose", (3,))
    q = check_finite_array(q, "q", (len(hand.joint_names),))
    man, joints, n_c = hand.manipulator, hand.joint_names, len(names)
    n_j = len(joints)
    e = np.asarray(effort_controlled, dtype=bool).reshape(-1)
    if e.shape != (n_j,):
        raise QsplanError(f"effort_controlled: expected {n_j} flags (one per joint); got shape {e.shape}")
    v = np.broadcast_to(np.asarray(velocity, dtype=float), (n_j,))
    tau = np.zeros(n_j) if effort is None else np.broadcast_to(np.asarray(effort, dtype=float), (n_j,))
    points, normals = np.asarray(points, dtype=float).reshape(n_c, 2), np.asarray(normals, dtype=float).reshape(n_c, 2)
    Wn, Wt = wrench_matrices(points, normals)
    Jn, Jt = np.zeros((n_c, n_j)), np.zeros((n_c, n_j))
    for i, link in enumerate(links):
        if link >= 0:
            Jn[i], Jt[i] = contact_jacobian(man, q, int(link), points[i], normals[i])
    mu = np.full(n_c, float(hand.mu)) if mu is None else np.broadcast_to(np.asarray(mu, dtype=float), (n_c,))
    g_obj = point_wrench(pose[:2], (0.0, -float(hand.workpiece_mass) * man.gravity))
    return make_scene(Wn, Wt, Jn, Jt, mu, g_obj, g_man=gravity_efforts(man, q), effort_controlled=e,
                      joint_velocity=np.where(e, np.nan, v), joint_effort=np.where(e, tau, np.nan),
                      joint_names=joints, contact_names=tuple(names))  # fmt: skip


