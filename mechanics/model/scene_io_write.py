"""Writing scenes in the raw form that :func:`qsplan.mechanics.scene_from_dict` reads.

:func:`scene_to_dict` is the inverse of :func:`~qsplan.mechanics.scene_from_dict` for
raw-form scenes: ``scene_from_dict(scene_to_dict(s))`` rebuilds ``s`` with every
array bit for bit (Python floats carry doubles exactly, and ``json`` writes them
with ``repr``, so a JSON file round-trips too).  A scene with real joints is
written with a ``"joints"`` list; a scene with ``virtual_joints`` (the paper's
examples: contact-point velocities instead of joints) is written without one,
each contact carrying ``"velocity": [v_n, v_t]``.
"""

from __future__ import annotations

import numpy as np

from qsplan.mechanics.errors import SceneError
from qsplan.mechanics.model.scene import Scene

__all__ = ["scene_to_dict"]


def _floats(a) -> list:
    return [float(x) for x in np.asarray(a).reshape(-1)]


def scene_to_dict(scene: Scene) -> dict:
    """The raw-form document of ``scene`` (see :mod:`qsplan.mechanics.model.scene_io`).

    Parameters
    ----------
    scene : Scene

    Returns
    -------
    dict
        ``{"g_obj": [3], "joints": [...], "contacts": [...]}`` of plain Python
        floats, strings and lists, ready for ``json.dump``.  Joints carry
        ``control``, their input (``velocity`` or ``effort``), ``g_man`` and
        ``name``; contacts carry ``wn``, ``wt``, ``mu``, ``jn``, ``jt`` and
        ``name`` (or ``velocity`` instead of ``jn``, ``jt`` for a scene with
        ``virtual_joints``).

    Raises
    ------
    SceneError
        For a ``virtual_joints`` scene that the raw form cannot hold: more than
        one joint, an effort-controlled joint, or a nonzero ``g_man``.
    """
    doc = {"g_obj": _floats(scene.g_obj)}
    contacts = []
    for i in range(scene.n_contacts):
        contacts.append(
            {
                "name": scene.contact_names[i],
                "wn": _floats(scene.Wn[:, i]),
                "wt": _floats(scene.Wt[:, i]),
                "mu": float(scene.mu[i]),
            }
        )
    if scene.virtual_joints:
        if scene.n_joints != 1 or scene.effort_controlled[0] or scene.g_man[0] != 0:
            raise SceneError(
                "virtual_joints: a scene without joints has one velocity-controlled virtual joint with g_man = 0; "
                f"got {scene.n_joints} joint(s), effort_controlled={scene.effort_controlled.tolist()}, "
                f"g_man={scene.g_man.tolist()}"
            )
        speed = float(scene.joint_velocity[0])
        for i, c in enumerate(contacts):
            c["velocity"] = [float(scene.Jn[i, 0] * speed), float(scene.Jt[i, 0] * speed)]
    else:
        joints = []
        for j in range(scene.n_joints):
            if scene.effort_controlled[j]:
                joint = {"control": "effort", "effort": float(scene.joint_effort[j])}
            else:
                joint = {"control": "velocity", "velocity": float(scene.joint_velocity[j])}
            joint.update(g_man=float(scene.g_man[j]), name=scene.joint_names[j])
            joints.append(joint)
        doc["joints"] = joints
        for i, c in enumerate(contacts):
            c["jn"] = _floats(scene.Jn[i])
            c["jt"] = _floats(scene.Jt[i])
    doc["contacts"] = contacts
    return doc
