"""The grasps worth considering for a described hand: the contact pairs its closing gives along the palm.

For each row of free-joint values (the planner's grid, or a task's ``[start]``; default each free joint at
the middle of its range), the fingers close (:func:`qsplan.hands.described.states.close_states`) at
:data:`CANDIDATE_SAMPLES` workpiece positions along the palm, all at once; every
distinct pair of contacts (each finger touching, neither flush) is a
:class:`~qsplan.hands.protocol.ChainGrasp` with those free joints.  The tables judge them; this only
proposes.  Units SI (m, rad).
"""

from __future__ import annotations

import numpy as np

from qsplan.hands.protocol import CONTACT_KINDS, ChainGrasp, FingerContact
from qsplan.mechanics.errors import QsplanError

__all__ = ["CANDIDATE_SAMPLES", "chain_candidates", "free_rows"]

#: Workpiece positions sampled along the palm for a described hand's grasp candidates: 1 mm steps on the bundled
#: hands' 0.3 m of palm (:data:`qsplan.hands.paper_hand.grasp_geometry.CANDIDATE_SAMPLES`, the paper hand's).
CANDIDATE_SAMPLES = 401


def free_rows(hand, free=None) -> np.ndarray:
    """Free-joint values (m, n_free) (rad or m): ``free`` checked, or one row with each free joint mid-range.

    Raises
    ------
    QsplanError
        Naming ``free`` when its shape or values are wrong.
    """
    n_free = len(hand.free_joints)
    if free is None:
        return hand.description.mid_limits[list(hand.free_joints)][None]
    rows = np.asarray(free, dtype=float)
    rows = rows.reshape(1, -1) if rows.ndim == 1 else rows
    if rows.ndim != 2 or rows.shape[1] != n_free or not np.all(np.isfinite(rows)):
        raise QsplanError(f"free: expected finite free-joint values, shape (m, {n_free}) (rad or m); got shape "
                          f"{np.shape(free)}")  # fmt: skip
    return rows


def chain_candidates(hand, formation, free=None, xs=None) -> tuple:
    """The :class:`~qsplan.hands.protocol.ChainGrasp` candidates of a described hand (see the module docstring).

    Parameters
    ----------
    hand : qsplan.hands.described.hand.DescribedHand
    formation : qsplan.hands.formations.registry.Formation
    free : array-like, shape (m, n_free), optional
        Free-joint values (rad or m), one grasp family per row.
    xs : array-like, shape (k,), optional
        The workpiece positions (m) to close at (default :data:`CANDIDATE_SAMPLES` along the palm; one x: the grasps
        there, as a planner asks at a start or a goal).

    Returns
    -------
    tuple of ChainGrasp
        By ``free``'s rows, then by contact keys.
    """
    from qsplan.hands.described.states import check_formation, close_states

    check_formation(formation)
    rows = free_rows(hand, free)
    xs = np.linspace(*hand.palm_range, CANDIDATE_SAMPLES) if xs is None else np.atleast_1d(np.asarray(xs, float))
    m, n = len(rows), len(xs)
    _, _, _, (left, right) = close_states(hand, np.tile(xs, m), np.repeat(rows, n, axis=0))
    good = left.found & right.found & ~left.flush & ~right.flush
    names = tuple(hand.joint_names[j] for j in hand.free_joints)
    out = []
    for r in range(m):
        at = np.flatnonzero(good[r * n:(r + 1) * n]) + r * n
        pairs = sorted({(int(left.kind[i]), int(left.feature[i]), int(right.kind[i]), int(right.feature[i])) for i in at})
        for kl, fl, kr, fr in pairs:
            contacts = [_contact(hand, c.link, k, f) for c, k, f in ((left, kl, fl), (right, kr, fr))]
            out.append(ChainGrasp(*contacts, tuple(float(v) for v in rows[r]), names))
    return tuple(out)


def _contact(hand, link: int, kind_code: int, feature: int) -> FingerContact:
    """A :class:`FingerContact` from the closing's codes (kind 0: a link corner on workpiece edge ``feature``)."""
    kind = CONTACT_KINDS[1 - kind_code]
    written = hand.user_edges[feature] if kind == "edge" else hand.user_vertices[feature]
    return FingerContact(int(link), hand.joint_names[link], kind, int(feature), int(written))
