"""The certifier's contacts of a row in any formation, found in the polygons (issue 23).

A row's ``mode`` has one letter per contact the row is judged with, in the canonical order of
:mod:`qsplan.hands.contacts.found` (the palm's contacts left to right, then each finger's from its base outward).
Which contacts those are is decided here from the row's geometry alone:

* a moving row, or a row at rest that starts its phase: every contact the polygon search finds (a contact that opens
  toward the next row is judged as breaking, ``B``);
* a row at rest that ends its phase: the same, without the contacts its motion makes only there (open at the previous
  row: :func:`qsplan.hands.contacts.found.made_contacts`), e.g. the slide's last row at the flush instant (its hold,
  :func:`qsplan.planner.certify.timing.hold_checks`, is proved with them: at rest every contact present pushes);
* a **hold row** (every letter ``R``, at rest, its phase not moving): every contact found; nothing moves, and the hold
  proof (:mod:`qsplan.mechanics.bands.hold`), not the mode check, decides it.

Every hand's rows are judged so, whatever the formation: one path.  Units SI.
"""

from __future__ import annotations

import numpy as np

__all__ = ["hold_row", "judged_contacts", "judged_contact_checks", "judged_scene", "row_contact_names"]


def _same_phase(cols, a, b) -> bool:
    ph = cols.get("phase")
    return ph is None or ph[a] == ph[b]


def _configuration(task, cols, k):
    from qsplan.planner.certify.rows import row_pose, row_q

    return row_pose(cols, k), row_q(cols, k, task.hand.joint_names)


def hold_row(cols, k) -> bool:
    """Row ``k`` claims a hold: every letter ``R``, at rest (``speed_scale`` 0, no velocity command but 0)."""
    mode = str(cols["mode"][k])
    if not mode or set(mode) != {"R"} or "speed_scale" not in cols or cols["speed_scale"][k] != 0.0:
        return False
    return all(not np.isfinite(cols[c][k]) or cols[c][k] == 0.0 for c in cols if c.startswith("qd_"))


def judged_contacts(task, cols, k):
    """``(found contacts, drop mask)`` of row ``k`` (the module docstring): the canonical contacts and which of them
    the row's motion makes only there (not judged)."""
    from qsplan.hands.contacts.found import made_contacts, ordered_contacts

    pose, q = _configuration(task, cols, k)
    found = ordered_contacts(task.hand, pose, q)
    n = cols["t"].size
    ends = (k + 1 == n or not _same_phase(cols, k, k + 1)) and k > 0 and _same_phase(cols, k - 1, k)
    resting = "speed_scale" in cols and cols["speed_scale"][k] == 0.0
    if ends and resting and not hold_row(cols, k):
        return found, made_contacts(task.hand, _configuration(task, cols, k - 1), (pose, q), found)
    return found, np.zeros(len(found), dtype=bool)


def row_contact_names(task, cols, k, judged=None) -> tuple:
    """The names of the contacts row ``k``'s mode letters follow, in order: its judged contacts
    (:func:`judged_contacts`, without those its motion makes only there; named by
    :func:`qsplan.hands.contacts.found.contact_names` among themselves: a finger left with one contact is ``left``), or
    without ``judged`` (a hand that does not reorient) the task's formation's."""
    from qsplan.hands.contacts.found import contact_names

    if judged is None:
        return tuple(task.formation.contact_names)
    found, drop = judged
    pose, _ = _configuration(task, cols, k)
    return contact_names(task.hand, pose, [c for c, d in zip(found, drop) if not d])


def judged_contact_checks(task, cols, k, judged) -> list:
    """The row's mode has one letter of R, S, B per judged contact; a hold row's phase does not move."""
    from qsplan.planner.certify.rows import JUMP_TOL

    mode = str(cols["mode"][k])
    names = row_contact_names(task, cols, k, judged)
    out = []
    if len(mode) != len(names) or set(mode) - set("RSB"):
        out.append(("contact", f"mode {mode!r}: expected one letter of R, S, B per contact the row touches "
                               f"({len(names)}: {', '.join(names) or 'none'})"))  # fmt: skip
    if hold_row(cols, k):
        pose_k, q_k = _configuration(task, cols, k)
        for j in (k - 1, k + 1):
            if 0 <= j < cols["t"].size and _same_phase(cols, j, k):
                pose_j, q_j = _configuration(task, cols, j)
                moved = max(float(np.max(np.abs(pose_j - pose_k))), float(np.max(np.abs(q_j - q_k))))
                if moved > JUMP_TOL:
                    out.append(("mode", f"mode {mode} claims a hold (nothing moves) but the phase moves "
                                        f"{moved:.3g} to an adjacent row"))  # fmt: skip
                    break
    return out


def judged_scene(task, cols, k, judged, effort, qd, tau):
    """The row's scene with its judged contacts (:func:`qsplan.hands.contacts.found.row_contact_scene`)."""
    from qsplan.hands.contacts.found import row_contact_scene

    found, drop = judged
    pose, q = _configuration(task, cols, k)
    return row_contact_scene(task.hand, pose, q, effort, qd, effort=tau, drop=drop, found=found)
