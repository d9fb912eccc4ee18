"""The paper hand's closed forms behind the :class:`qsplan.hands.protocol.Hand` methods (Section 5.2, Fig. 9).

A described hand of the paper's form (two single-link revolute fingers,
:func:`qsplan.hands.description.two_finger_form.two_finger_parameters`) answers the ``"palm_edge"``
formation's questions with the closed forms of :class:`qsplan.hands.paper_hand.two_finger.TwoFingerHand` (its
parameter record): grasps as placements (:mod:`qsplan.hands.paper_hand.grasps`), their configurations along the palm
(:func:`qsplan.hands.paper_hand.grasp_geometry.grasp_configurations`), the scene arrays from the known contacts
checked against the polygon search (:func:`qsplan.hands.paper_hand.batch_scenes.checked_scene_arrays`, the polygons
where the check refuses), scenes (:func:`qsplan.hands.paper_hand.scene.hand_scene`) and the fingers'
opening directions.  The numbers are exactly those the planner computed before the hand protocol.
Units SI (m, rad, N, N m).
"""

from __future__ import annotations

import numpy as np

from qsplan.hands.protocol import NO_PLACEMENT, GraspSceneArrays, GraspStates
from qsplan.mechanics.errors import QsplanError

__all__ = ["NUMBER_WORDS", "paper_opening", "paper_scene_arrays", "paper_state_scene", "paper_states"]

#: Counts of contacts in words, for the reasons the planner reports (``"no four-contact scene: ..."``).
NUMBER_WORDS = {1: "one", 2: "two", 3: "three", 4: "four", 5: "five", 6: "six", 7: "seven", 8: "eight"}

#: The body of each contact of the paper's formation: the palm twice, then the left and the right finger's link.
_BODIES = (-1, -1, 0, 1)


def paper_states(paper, formation, grasp, xs) -> GraspStates:
    """:func:`qsplan.hands.paper_hand.grasp_geometry.grasp_configurations` as :class:`GraspStates` (reason
    :data:`qsplan.hands.protocol.NO_PLACEMENT` where a placement has no valid configuration)."""
    from qsplan.hands.paper_hand.grasp_geometry import grasp_configurations
    from qsplan.hands.paper_hand.grasps import Grasp

    if not isinstance(grasp, Grasp):
        raise QsplanError(f"grasp: expected a Grasp of the paper's hand (placements); got {type(grasp).__name__}")
    conf = grasp_configurations(paper, grasp, xs)
    reason = np.where(conf.ok, 0, NO_PLACEMENT).astype(np.int8)
    bodies = np.broadcast_to(np.array(_BODIES), (len(conf.x), 4)).copy()
    return GraspStates(formation, grasp, conf.x, conf.poses(paper.rest_height), conf.q, conf.ok, reason, conf.finger_ok,
                       conf.touched, conf.touched_as_written, conf.tip, conf.points, conf.normals, bodies,
                       conf.dq_dx)  # fmt: skip


def _configurations(states: GraspStates):
    """The :class:`qsplan.hands.paper_hand.grasp_geometry.GraspConfigurations` of paper ``states``."""
    from qsplan.hands.paper_hand.grasp_geometry import GraspConfigurations

    s = states
    return GraspConfigurations(s.grasp, s.x, s.q, s.ok, s.finger_ok, s.touched, s.touched_as_written, s.tip, s.points,
                               s.normals, s.dq_dx)  # fmt: skip


def paper_scene_arrays(paper, states: GraspStates, idx=None) -> GraspSceneArrays:
    """The scene arrays of paper ``states`` at ``idx`` (default: where ok): the closed form's contacts where they are
    the polygon search's (:func:`qsplan.hands.paper_hand.batch_scenes.checked_scene_arrays`), the polygon search's scene
    (:func:`qsplan.hands.paper_hand.scene.hand_scene`) where it refuses; as the band tables built them."""
    from qsplan.hands.paper_hand.batch_scenes import checked_scene_arrays
    from qsplan.hands.paper_hand.scene import hand_scene

    idx = np.flatnonzero(states.ok) if idx is None else np.asarray(idx, dtype=int).reshape(-1)
    sub = states.take(idx)
    arrays, checked = checked_scene_arrays(paper, _configurations(sub))
    ok = sub.ok.copy()
    reasons = [None if o else states.why(int(i)) for o, i in zip(ok, idx)]
    fallback = {}
    for k in np.flatnonzero(ok & ~checked).tolist():
        try:
            scene = hand_scene(paper, sub.poses[k], sub.q[k], "right", velocity=float(sub.dq_dx[k, 0] * 0.0))
        except QsplanError as exc:  # the polygons give no four-contact scene here (e.g. vertex on vertex)
            ok[k], reasons[k] = False, f"no {NUMBER_WORDS[4]}-contact scene: {exc}"
            continue
        fallback[k] = scene
        for name in ("Wn", "Wt", "Jn", "Jt", "g_obj", "g_man"):
            getattr(arrays, name)[k] = getattr(scene, name)
    return GraspSceneArrays(idx, arrays.Wn, arrays.Wt, arrays.Jn, arrays.Jt, arrays.g_obj, arrays.g_man,
                            sub.bodies.copy(), sub.dq_dx.copy(), ok, tuple(reasons), fallback, True)  # fmt: skip


def paper_state_scene(paper, arrays: GraspSceneArrays, s: int, effort_controlled, velocity, effort=None, mu=None):
    """The scene of state ``s``: the polygon search's with these joint inputs where it built one, else
    :func:`qsplan.hands.paper_hand.analytic.scene_from_arrays` (exactly one joint effort-controlled)."""
    from dataclasses import replace

    from qsplan.hands.paper_hand.analytic import scene_from_arrays
    from qsplan.mechanics.model.friction import check_friction

    e = np.asarray(effort_controlled, dtype=bool).reshape(-1)
    if e.shape != (2,) or e.sum() != 1:
        raise QsplanError(f"effort_controlled: expected exactly one of the two fingers effort-controlled; got "
                          f"{e.tolist()}")  # fmt: skip
    k = int(np.flatnonzero(e)[0])
    v = float(np.broadcast_to(np.asarray(velocity, dtype=float), (2,))[1 - k])
    tau = 0.0 if effort is None else float(np.broadcast_to(np.asarray(effort, dtype=float), (2,))[k])
    mu = None if mu is None else float(check_friction(mu, "mu"))
    if s in arrays.fallback:
        scene = arrays.fallback[s]
        frozen = {"effort_controlled": e, "joint_velocity": np.where(e, np.nan, v),
                  "joint_effort": np.where(e, tau, np.nan)}  # fmt: skip
        if mu is not None:
            frozen["mu"] = np.full(4, mu)
        for value in frozen.values():
            value.setflags(write=False)
        return replace(scene, **frozen)
    return scene_from_arrays(paper, *(getattr(arrays, f)[s].copy() for f in ("Wn", "Wt", "Jn", "Jt", "g_obj", "g_man")),
                             e, v, tau, mu)  # fmt: skip


def paper_opening(paper, grasp, x: float) -> np.ndarray:
    """Each finger's opening direction at ``x`` (m): the sign of the joint rate that moves its contact point out of
    the workpiece, ``-sign(j_n)`` with ``j_n = n . (e_z x (p - a))`` (eq. 5), shape (2,)."""
    from qsplan.hands.paper_hand.grasp_geometry import grasp_configurations

    conf = grasp_configurations(paper, grasp, np.array([x]))
    out = np.empty(2)
    for k in range(2):
        p, n = conf.points[0, 2 + k], conf.normals[0, 2 + k]
        r = p - paper.pivots[k]
        jn = n[0] * (-r[1]) + n[1] * r[0]
        out[k] = -np.sign(jn) if jn != 0 else (1.0 if k == 0 else -1.0)
    return out
