"""A grasp held while the workpiece slides along the palm: the configurations, joint rates and scenes of a slide.

:func:`slide_motion` is what the planner asks of any hand (:class:`qsplan.hands.protocol.Hand`) to judge a
slide sample by sample: at every workpiece ``x`` of a batch, the closed configuration of the grasp, the joint
rates that keep every contact closed while the workpiece moves at ``xdot`` along x (the free joints at their
given rates; each finger's closing joint from eq. 6 with equality), which features the fingers touch, and the
scene with one joint effort-controlled and the others driven at their rates (eqs. 1-5).

The generic path builds them from :meth:`~qsplan.hands.protocol.Hand.grasp_states`,
:meth:`~qsplan.hands.protocol.Hand.scene_arrays` and :meth:`~qsplan.hands.protocol.Hand.state_scene`; the
paper's hand answers with its closed forms (:mod:`qsplan.hands.paper_hand.motion`), the numbers the planner has
always used.  Units SI (m, rad, m/s, rad/s).
"""

from __future__ import annotations

import numpy as np

from qsplan.hands.protocol import SlideMotion
from qsplan.mechanics.errors import SceneError

__all__ = ["CLOSING_JN_TOL", "SlideMotion", "closed_configuration", "closing_rates", "generic_slide_motion",
           "slide_motion", "touch_codes"]

#: ``|J_n|`` (m per rad, or m/m) of a closing joint at its contact below which it cannot move the contact along the
#: normal (a singular grasp): link lengths are centimetres, so a regular grasp's entry is 1e-3 or more.
CLOSING_JN_TOL = 1e-12


def touch_codes(states) -> np.ndarray:
    """What each finger touches (n, 2): :meth:`qsplan.hands.protocol.GraspStates.touching`."""
    return states.touching()


def closing_rates(hand, formation, arrays, xdot, free_rates=None) -> np.ndarray:
    """Joint rates (m, n_j) keeping every finger contact closed (eq. 6 with equality, ``W_n^T nu = J_n qdot``) while the
    workpiece moves at ``xdot`` (m/s) along x and the free joints at ``free_rates`` (m, n_j; closing entries ignored;
    default held), from the scene arrays (:meth:`~qsplan.hands.protocol.Hand.scene_arrays`).

    Raises
    ------
    SceneError
        Where a closing joint cannot move its contact along the normal (:data:`CLOSING_JN_TOL`).
    """
    m, n_j = arrays.Jn.shape[0], arrays.Jn.shape[2]
    qd = np.zeros((m, n_j)) if free_rates is None else np.array(free_rates, dtype=float).reshape(m, n_j)
    nu = np.array([float(xdot), 0.0, 0.0])
    left, right = formation.finger_contacts
    for i, k in zip((left[0], right[0]), hand.closing_joints):
        qd[:, k] = 0.0
        jn = arrays.Jn[:, i, :]
        small = np.abs(jn[:, k]) < CLOSING_JN_TOL
        if small.any():
            raise SceneError(f"q: a finger's last joint ({hand.joint_names[k]}) cannot move its contact along the normal "
                             f"(a singular grasp at state {int(np.flatnonzero(small)[0])})")  # fmt: skip
        qd[:, k] = (arrays.Wn[:, :, i] @ nu - np.einsum("mj,mj->m", jn, qd)) / jn[:, k]
    return qd


def generic_slide_motion(hand, formation, grasp, xs, xdot, effort_joint: int, free=None, free_rates=None) -> SlideMotion:
    """:class:`SlideMotion` by the generic path (see the module docstring).

    Parameters
    ----------
    grasp : qsplan.hands.protocol.ChainGrasp or qsplan.hands.paper_hand.grasps.Grasp or None
        None: each finger closes onto whatever it touches first (the grasp of the start's free joints).
    xs : ndarray, shape (n,)
    xdot : float
        Workpiece speed (m/s, signed).
    effort_joint : int
        The effort-controlled joint.
    free : ndarray, shape (n, n_free), optional
        Each state's free joints (default the grasp's).
    free_rates : ndarray, shape (n, n_j), optional
        The free joints' rates (rad/s or m/s) (default held).

    Raises
    ------
    SceneError
        Naming the first x where the grasp has no configuration or no four-contact scene.
    """
    xs = np.atleast_1d(np.asarray(xs, dtype=float))
    states = hand.grasp_states(formation, grasp, xs, free)
    bad = np.flatnonzero(~states.ok)
    if bad.size:
        k = int(bad[0])
        raise SceneError(f"grasp: no configuration at x = {xs[k]:.6g} m: {states.why(k)}")
    arrays = hand.scene_arrays(formation, states, np.arange(len(xs)))
    if not np.all(arrays.ok):
        k = int(np.argmin(arrays.ok))
        raise SceneError(f"grasp: at x = {xs[k]:.6g} m {arrays.reasons[k]}")
    qd = closing_rates(hand, formation, arrays, xdot, free_rates)
    e = np.arange(qd.shape[1]) == int(effort_joint)
    scenes = tuple(hand.state_scene(arrays, s, e, np.where(e, 0.0, qd[s])) for s in range(len(xs)))
    return SlideMotion(states.poses, states.q, qd, touch_codes(states), scenes)


def slide_motion(hand, formation, grasp, xs, xdot, effort_joint: int, free=None, free_rates=None) -> SlideMotion:
    """The grasp held while the workpiece slides at ``xdot`` (m/s): configurations, joint rates, contacts and scenes
    with joint ``effort_joint`` effort-controlled at every x of ``xs`` (n,) (``free``, ``free_rates`` (n, n_free),
    (n, n_j): the free joints and their rates, default the grasp's, held).  ``grasp`` None: the paper hand's default
    grasp (the inner edges' tangency), or on any other hand the grasp its closing gives at ``xs[0]``.  The paper's
    closed forms answer where the hand is accelerated (:mod:`qsplan.hands.paper_hand.motion`).

    Raises
    ------
    SceneError
        Naming the first x without a configuration or a four-contact scene.
    """
    from qsplan.hands.formations.registry import FORMATIONS

    if hand.accelerated and formation == FORMATIONS["palm_edge"] and free is None and free_rates is None:
        from qsplan.hands.paper_hand.motion import paper_slide_motion

        return paper_slide_motion(hand.paper, grasp, xs, float(xdot), int(effort_joint))
    if grasp is None:
        grasp = _first_grasp(hand, formation, xs[0], None if free is None else np.asarray(free)[:1])
    return generic_slide_motion(hand, formation, grasp, xs, float(xdot), int(effort_joint), free, free_rates)


def _first_grasp(hand, formation, x: float, free):
    """The grasp the fingers' closing gives at ``x`` (free joints ``free`` (1, n_free), default mid-range): the paper's
    form its inner edges' tangency, any other hand its first valid candidate there."""
    if hand.paper_form:
        from qsplan.hands.paper_hand.grasps import Grasp, OnVertex

        return Grasp(OnVertex(), OnVertex())
    for grasp in hand.grasp_candidates(formation, free):
        if hand.grasp_states(formation, grasp, np.array([x])).ok[0]:
            return grasp
    raise SceneError(f"grasp: the fingers close onto no grasp at x = {x:.6g} m")


def closed_configuration(hand, formation, grasp, x: float, free=None) -> np.ndarray:
    """The joints (n_j,) of ``grasp`` closed at workpiece ``x`` (m), free joints ``free`` (n_free,) (default the grasp's):
    geometry only (no scene).  ``grasp`` None as in :func:`slide_motion` (the paper's hand: its tangency,
    :func:`qsplan.hands.paper_hand.two_finger.finger_angles`).

    Raises
    ------
    SceneError
        Where the grasp has no configuration at ``x`` (the closed form's words).
    """
    from qsplan.hands.formations.registry import FORMATIONS

    free = None if free is None else np.asarray(free, dtype=float).reshape(1, -1)
    if hand.accelerated and formation == FORMATIONS["palm_edge"] and grasp is None and free is None:
        from qsplan.hands.paper_hand.two_finger import finger_angles

        return finger_angles(hand.paper, hand.pose(x))[0]
    if grasp is None:
        grasp = _first_grasp(hand, formation, x, free)
    states = hand.grasp_states(formation, grasp, np.array([float(x)]), free)
    if not states.ok[0]:
        raise SceneError(f"grasp: no configuration at x = {float(x):.6g} m: {states.why(0)}")
    return states.q[0]
