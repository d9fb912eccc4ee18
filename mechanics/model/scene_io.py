"""Loading scenes from TOML or JSON: the raw form (wrenches and Jacobian rows) and the geometric form.

Raw form (used by external tools and the paper's examples)::

    {"g_obj": [fx, fy, m],
     "joints": [{"control": "velocity", "velocity": 0.5, "g_man": 0.0},
                {"control": "effort", "effort": 1.2, "g_man": 0.0}],
     "contacts": [{"wn": [3 numbers], "wt": [3 numbers], "mu": 0.3,
                   "jn": [one per joint], "jt": [one per joint]}]}

A contact may give ``"r": [x, y], "n": [x, y]`` instead of ``wn``/``wt``.  A
scene with no ``joints`` gives each contact ``"velocity": [v_n, v_t]`` (the
manipulator contact point's velocity ``J_i thetadot`` in the contact frame) and
is solved as noncompliant.  Optional extras: ``"name"`` on joints and contacts,
``"name"``/``"description"`` at the top.  A document with a ``"workpiece"``
table is in the geometric form (:mod:`qsplan.mechanics.model.geometric_scene`).
"""

from __future__ import annotations

import numpy as np

from qsplan.mechanics.model.contact import check_contact_frame, wrench_matrices
from qsplan.mechanics.model.fields import check_keys, number, read_document, vector
from qsplan.mechanics.model.friction import check_friction
from qsplan.mechanics.errors import SceneError
from qsplan.mechanics.model.scene import Scene, make_scene

__all__ = ["load_scene", "scene_from_dict", "check_mu_override"]

_TOP_KEYS = {"g_obj", "joints", "contacts", "name", "description"}
_JOINT_KEYS = {"control", "velocity", "effort", "g_man", "name"}
_CONTACT_KEYS = {"wn", "wt", "r", "n", "mu", "jn", "jt", "velocity", "name"}


def load_scene(path, mu=None) -> Scene:
    """Load a scene file (raw or geometric form).

    Parameters
    ----------
    path : str or Path
        ``.toml`` is read as TOML, anything else as JSON.
    mu : float or sequence of float, optional
        Overrides the friction coefficients (one for all contacts or one per contact).
    """
    return scene_from_dict(read_document(path), mu=mu)


def check_mu_override(mu, n_c: int) -> np.ndarray:
    """Broadcast a friction override (one value or one per contact) to shape (n_c,)."""
    vals = np.atleast_1d(check_friction(mu, "mu"))
    if vals.size not in (1, n_c):
        raise SceneError(f"mu: expected 1 or {n_c} values (one per contact); got {vals.size}")
    return np.broadcast_to(vals, (n_c,)).copy()


def scene_from_dict(doc: dict, mu=None) -> Scene:
    """Build a :class:`Scene` from a parsed raw-form (or geometric-form) document.

    Raises
    ------
    SceneError
        Naming the field and the problem: missing or wrong-length fields, NaN,
        negative or non-numeric mu, zero normals, Jacobian rows without joints,
        unknown fields.
    """
    if not isinstance(doc, dict):
        raise SceneError(f"scene: expected an object/table; got {type(doc).__name__}")
    if "workpiece" in doc:
        from qsplan.mechanics.model.geometric_scene import scene_from_geometry

        scene = scene_from_geometry(doc)
        return scene if mu is None else scene.with_mu(check_mu_override(mu, scene.n_contacts))
    check_keys(doc, _TOP_KEYS, "scene")
    for key in ("g_obj", "contacts"):
        if key not in doc:
            raise SceneError(f"{key}: missing (required in a raw scene)")
    g_obj = vector(doc["g_obj"], "g_obj", 3)
    contacts = doc["contacts"]
    if not isinstance(contacts, list) or not contacts:
        raise SceneError(f"contacts: expected a non-empty list of contacts; got {contacts!r}")
    n_c = len(contacts)

    has_joints = "joints" in doc
    joints = doc.get("joints", [])
    if has_joints and (not isinstance(joints, list) or not joints):
        raise SceneError("joints: expected a non-empty list (omit 'joints' and give each contact a 'velocity' instead)")
    n_j = len(joints)
    effort = np.zeros(n_j, dtype=bool)
    jvel = np.full(n_j, np.nan)
    jeff = np.full(n_j, np.nan)
    g_man = np.zeros(n_j)
    jnames = []
    for i, j in enumerate(joints):
        f = f"joints[{i}]"
        check_keys(j, _JOINT_KEYS, f)
        control = j.get("control")
        if control not in ("velocity", "effort"):
            raise SceneError(f"{f}.control: expected 'velocity' or 'effort'; got {control!r}")
        effort[i] = control == "effort"
        if control not in j:
            raise SceneError(f"{f}.{control}: missing (a {control}-controlled joint needs its {control})")
        for key, arr in (("velocity", jvel), ("effort", jeff)):
            if key in j:
                arr[i] = number(j[key], f"{f}.{key}")
        g_man[i] = number(j.get("g_man", 0.0), f"{f}.g_man")
        jnames.append(str(j.get("name", f"j{i}")))

    Wn = np.zeros((3, n_c))
    Wt = np.zeros((3, n_c))
    Jn = np.zeros((n_c, n_j if has_joints else 1))
    Jt = np.zeros_like(Jn)
    mus = np.full(n_c, np.nan)
    cnames = []
    for i, c in enumerate(contacts):
        f = f"contacts[{i}]"
        check_keys(c, _CONTACT_KEYS, f)
        if "wn" in c or "wt" in c:
            if "r" in c or "n" in c:
                raise SceneError(f"{f}: give either wn/wt or r/n, not both")
            for key in ("wn", "wt"):
                if key not in c:
                    raise SceneError(f"{f}.{key}: missing")
            Wn[:, i] = vector(c["wn"], f"{f}.wn", 3)
            Wt[:, i] = vector(c["wt"], f"{f}.wt", 3)
            check_contact_frame(Wn[:, i], Wt[:, i], f)
        elif "r" in c or "n" in c:
            for key in ("r", "n"):
                if key not in c:
                    raise SceneError(f"{f}.{key}: missing")
            r = vector(c["r"], f"{f}.r", 2)
            n = vector(c["n"], f"{f}.n", 2)
            if np.hypot(*n) < 1e-12:
                raise SceneError(f"{f}.n: zero normal; expected a nonzero direction into the workpiece")
            wn, wt = wrench_matrices(r[None], n[None])
            Wn[:, i], Wt[:, i] = wn[:, 0], wt[:, 0]
        else:
            raise SceneError(f"{f}: missing the contact geometry (wn and wt, or r and n)")
        if "mu" in c:
            mus[i] = check_friction(number(c["mu"], f"{f}.mu"), f"{f}.mu")
        elif mu is None:
            raise SceneError(f"{f}.mu: missing (give it in the scene, or override it)")
        if has_joints:
            if "velocity" in c:
                raise SceneError(f"{f}.velocity: only for scenes without joints (this scene has joints; give jn and jt)")
            for key, J in (("jn", Jn), ("jt", Jt)):
                if key not in c:
                    raise SceneError(f"{f}.{key}: missing (one number per joint, {n_j} joints)")
                J[i] = vector(c[key], f"{f}.{key}", n_j)
        else:
            for key in ("jn", "jt"):
                if key in c:
                    raise SceneError(f"{f}.{key}: Jacobian rows given but the scene has no joints")
            if "velocity" not in c:
                raise SceneError(f"{f}.velocity: missing (a scene without joints gives [v_n, v_t] per contact)")
            Jn[i, 0], Jt[i, 0] = vector(c["velocity"], f"{f}.velocity", 2)
        cnames.append(str(c.get("name", f"c{i + 1}")))
    if mu is not None:
        mus = check_mu_override(mu, n_c)

    if not has_joints:
        return make_scene(
            Wn, Wt, Jn, Jt, mus, g_obj,
            joint_velocity=[1.0], joint_names=("contact_velocities",),
            contact_names=cnames, virtual_joints=True,
        )  # fmt: skip
    return make_scene(
        Wn, Wt, Jn, Jt, mus, g_obj, g_man=g_man, effort_controlled=effort,
        joint_velocity=np.where(effort, np.nan, jvel), joint_effort=np.where(effort, jeff, np.nan),
        joint_names=jnames, contact_names=cnames,
    )  # fmt: skip
