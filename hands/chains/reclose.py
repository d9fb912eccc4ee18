"""Closing the fingers again on a workpiece that moved: a plan's grasp at another pose (the replay's regrasps).

After a re-simulated segment the workpiece may stand a little away from where the plan put it; the plan's
regrasp closes the fingers on it there, with the grasp the plan uses: the paper's fingers by their closed
forms (:func:`grasp_angles`), any described hand by closing each finger's last joint from the plan's free
joints (:func:`chain_grasp`); :func:`reclose` picks by the hand (the paper's closed forms where they answer).
Units SI (m, rad).
"""

from __future__ import annotations

import numpy as np

from qsplan.mechanics.errors import QsplanError

__all__ = ["GRASP_MATCH_TOL", "chain_grasp", "grasp_angles", "reclose"]

#: Joint angles (rad) within which an exported row's fingers are taken to realise a grasp's closed form:
#: the export writes angles to 1e-12 or better (repr of floats), tangency round-off is ~1e-15.
GRASP_MATCH_TOL = 1e-9


def grasp_angles(hand, pose, q_planned, planned_pose) -> np.ndarray:
    """Joint angles (rad, shape (2,)) that put both fingers on the workpiece at ``pose`` with the grasp the plan
    uses at ``planned_pose`` (its exported angles ``q_planned``): both inner edges on their vertices of
    tangency (:func:`qsplan.hands.paper_hand.two_finger.finger_angles`) when those are the planned angles, else the
    candidate grasp (:func:`qsplan.hands.paper_hand.grasp_geometry.candidate_grasps`) whose closed form gives them.
    At the planned pose these are the planned angles; after a re-simulated segment the workpiece may stand a
    little elsewhere and the fingers close on it there, with the same grasp."""
    from qsplan.hands.paper_hand.two_finger import finger_angles

    try:
        q_inner = finger_angles(hand, planned_pose)[0]
    except QsplanError:
        q_inner = None
    if q_inner is not None and np.allclose(q_inner, q_planned, rtol=0.0, atol=GRASP_MATCH_TOL):
        return finger_angles(hand, pose)[0]
    from qsplan.hands.paper_hand.grasp_geometry import candidate_grasps, grasp_configurations

    for grasp in candidate_grasps(hand):
        at = grasp_configurations(hand, grasp, np.array([planned_pose[0], pose[0]]))
        if at.ok[0] and np.allclose(at.q[0], q_planned, rtol=0.0, atol=GRASP_MATCH_TOL) and at.ok[1]:
            return at.q[1]
    raise QsplanError(f"q: the planned angles {np.round(q_planned, 6).tolist()} rad at x = {planned_pose[0]:.6g} m "
                      "are no grasp of this hand")  # fmt: skip


def chain_grasp(hand, pose, q_planned, planned_pose) -> np.ndarray:
    """A chain hand's joint positions (rad or m, shape (n_j,)) closing both fingers on the workpiece at ``pose`` from
    the free joints of the plan's ``q_planned`` (:func:`qsplan.hands.chains.hand.close_grasp`), after checking that
    closing at ``planned_pose`` gives the planned positions (the plan's grasp is this hand's closing)."""
    from qsplan.hands.chains.hand import close_grasp

    q_planned = np.asarray(q_planned, dtype=float)
    at_plan = close_grasp(hand, float(planned_pose[0]), q_planned)
    if at_plan is None or not np.allclose(at_plan[0], q_planned, rtol=0.0, atol=GRASP_MATCH_TOL):
        raise QsplanError(f"q: the planned positions {np.round(q_planned, 6).tolist()} at x = {planned_pose[0]:.6g} m "
                          "are no closed grasp of this hand")  # fmt: skip
    here = close_grasp(hand, float(pose[0]), q_planned)
    if here is None:
        raise QsplanError(f"q: the fingers close onto nothing at x = {pose[0]:.6g} m from the planned free joints")
    return here[0]


def reclose(hand, pose, q_planned, planned_pose) -> np.ndarray:
    """The plan's grasp (its joints ``q_planned`` at ``planned_pose``) closed on the workpiece at ``pose``, shape (n_j,)
    (:class:`qsplan.hands.described.hand.DescribedHand`: its paper record's closed forms where accelerated, else its
    chain record's closing)."""
    if hand.accelerated:
        return grasp_angles(hand.paper, pose, q_planned, planned_pose)
    return chain_grasp(hand.chain, pose, q_planned, planned_pose)
