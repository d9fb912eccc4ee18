"""The paper's two-finger hand (Section 5.2, Fig. 9) as a :class:`HandDescription`, and back.

A description has the paper's structure when it is two single-link revolute fingers on the palm at
``(-b, 0, 0)`` and ``(+b, 0, 0)``, both links the rectangle ``(0, -w), (L, -w), (L, w), (0, w)`` (the
same ``L > 2 w > 0``) of equal mass with its centre at ``(L / 2, 0)``, and the palm the rectangle
``[-P, P] x [-T, 0]``: then :func:`two_finger_parameters` gives the arguments of
:func:`qsplan.hands.paper_hand.two_finger.make_two_finger_hand` that reproduce it, so the closed forms of
:mod:`qsplan.hands.paper_hand.two_finger` apply.  :func:`describe_two_finger_hand` goes the other way.
"""

from __future__ import annotations

import numpy as np

from qsplan.hands.description.model import HandDescription, make_hand_description
from qsplan.hands.paper_hand.two_finger import JOINT_NAMES, TwoFingerHand
from qsplan.mechanics.errors import SceneError

__all__ = ["FORM_TOL", "two_finger_parameters", "describe_two_finger_hand"]

#: Tolerance (m, and kg for the masses) within which a description matches the paper's form:
#: coordinates written in a file are exact to ~1e-17 m at hand scale.
FORM_TOL = 1e-12


def _rectangle(shape, tol):
    """``(x0, x1, y0, y1)`` when ``shape`` (4 vertices) is an axis-aligned rectangle, else None."""
    if shape is None or len(shape) != 4:
        return None
    v = np.asarray(shape, dtype=float)
    x0, y0 = v.min(axis=0)
    x1, y1 = v.max(axis=0)
    corners = np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]])
    # each vertex a corner and each corner a vertex (the polygon is valid, so the order is a ring)
    d = np.abs(v[:, None, :] - corners[None]).max(axis=2)
    if not (np.all(d.min(axis=1) <= tol) and np.all(d.min(axis=0) <= tol)):
        return None
    return float(x0), float(x1), float(y0), float(y1)


def two_finger_parameters(desc: HandDescription, tol: float = FORM_TOL) -> dict | None:
    """The arguments of :func:`qsplan.hands.paper_hand.two_finger.make_two_finger_hand` that reproduce ``desc``, or
    None.

    Parameters
    ----------
    desc : HandDescription
    tol : float
        Tolerance (m; kg for the masses) of the comparisons.

    Returns
    -------
    dict or None
        ``finger_base, finger_length, finger_width, finger_mass, palm_halfwidth, palm_thickness``
        (m, kg) and ``gravity`` (m/s^2) when ``desc`` has the paper's structure (module docstring),
        else None.
    """
    man = desc.manipulator
    if man.n_joints != 2 or desc.joint_kinds != ("revolute", "revolute"):
        return None
    if tuple(f.joints for f in desc.fingers) != ((0,), (1,)):
        return None
    left, right = man.joints
    b = float(right.origin[0])
    if b <= 0 or np.abs(left.origin - (-b, 0.0, 0.0)).max() > tol or np.abs(right.origin - (b, 0.0, 0.0)).max() > tol:
        return None
    rects = [_rectangle(j.link_shape, tol) for j in (left, right)]
    if rects[0] is None or rects[1] is None:
        return None
    x0, L, y0, w = rects[0]
    if abs(x0) > tol or abs(y0 + w) > tol or np.abs(np.subtract(rects[1], rects[0])).max() > tol:
        return None
    if not 0 < 2 * w < L or abs(left.link_mass - right.link_mass) > tol:
        return None
    if any(np.abs(j.link_com - (0.5 * L, 0.0)).max() > tol for j in (left, right)):
        return None
    palm = _rectangle(man.base_shape, tol)
    if palm is None:
        return None
    p0, P, t0, top = palm
    if P <= 0 or abs(p0 + P) > tol or abs(top) > tol or t0 >= 0:
        return None
    return {"finger_base": b, "finger_length": L, "finger_width": 2.0 * w, "finger_mass": float(left.link_mass),
            "palm_halfwidth": P, "palm_thickness": -t0, "gravity": float(man.gravity)}  # fmt: skip


def describe_two_finger_hand(hand: TwoFingerHand, joint_limits, joint_speed, name="two-finger hand",
                             source="inline") -> HandDescription:  # fmt: skip
    """A :class:`TwoFingerHand`'s palm and fingers as a :class:`HandDescription` (joints ``"left"``, ``"right"``).

    The manipulator equals :func:`qsplan.hands.paper_hand.scene.hand_manipulator`'s (joints, origins, link
    shapes, masses and centres, palm, gravity); the workpiece and friction are not part of a hand.

    Parameters
    ----------
    hand : TwoFingerHand
    joint_limits : array-like, shape (2, 2) or (2,)
        ``[lo, hi]`` of the left and right joint (rad), or one pair for both.
    joint_speed : float or array-like, shape (2,)
        Largest speed of each joint (rad/s).
    name, source : str
        Recorded in the description.

    Raises
    ------
    SceneError
        Naming the field: limits not ``lo < hi``, a non-positive speed, limits of the wrong shape.
    """
    lim = np.asarray(joint_limits, dtype=float)
    if lim.shape not in ((2,), (2, 2)):
        raise SceneError(f"joint_limits: expected [lo, hi] or one [lo, hi] per finger (rad), shape (2, 2); "
                         f"got shape {lim.shape}")
    lim = np.broadcast_to(lim, (2, 2))
    speed = np.asarray(joint_speed, dtype=float)
    if speed.shape not in ((), (2,)):
        raise SceneError(f"joint_speed: expected one speed or one per finger (rad/s); got shape {speed.shape}")
    speed = np.broadcast_to(speed, (2,))
    for k in range(2):
        if not (np.all(np.isfinite(lim[k])) and lim[k, 0] < lim[k, 1]):
            raise SceneError(f"joint_limits[{k}]: expected [lo, hi] with lo < hi (rad); got [{lim[k, 0]:g}, {lim[k, 1]:g}]")
        if not (np.isfinite(speed[k]) and speed[k] > 0):
            raise SceneError(f"joint_speed: expected a positive speed (rad/s); got {speed[k]:g}")
    L, w = hand.finger_length, 0.5 * hand.finger_width
    P, T = hand.palm_halfwidth, hand.palm_thickness
    link = {"polygon": [(0.0, -w), (L, -w), (L, w), (0.0, w)], "mass": hand.finger_mass, "com": [0.5 * L, 0.0]}
    fingers = [
        {"name": finger, "joints": [{"name": finger, "type": "revolute", "origin": [x, 0.0, 0.0],
                                     "limits": lim[k].tolist(), "speed": float(speed[k]), "link": link}]}
        for k, (finger, x) in enumerate(zip(JOINT_NAMES, (-hand.finger_base, hand.finger_base)))
    ]  # fmt: skip
    return make_hand_description(name, [(-P, -T), (P, -T), (P, 0.0), (-P, 0.0)], fingers, hand.gravity, source)
