"""Manipulation segments of the two-finger hand (Section 5.2): a path of configurations with a desired mode.

A segment moves the workpiece's pose linearly from ``pose_start`` to ``pose_end``
over ``duration`` seconds; along it both fingers stay on the workpiece
(:func:`qsplan.hands.paper_hand.two_finger.finger_angles`), the velocity-controlled finger turns at
the path's rate (:func:`qsplan.hands.paper_hand.two_finger.finger_angle_rates`) and the
effort-controlled one is given a torque chosen inside a band (Figs. 10-13).
:func:`sample_segment` gives the configurations and the :class:`qsplan.mechanics.Scene`
of each sample.

The paper's plan has three 4S segments; :func:`first_segment` builds the first:
the workpiece translates left along the palm until the left finger's inner edge
is about to lie flush with the workpiece's longest edge.

All quantities are SI (m, rad, s, rad/s).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qsplan.mechanics.errors import SceneError

from qsplan.hands.paper_hand.two_finger import (JOINT_NAMES, TwoFingerHand, finger_angle_rates, finger_angles,
                                                workpiece_world)  # fmt: skip
from qsplan.hands.paper_hand.scene import hand_scene

__all__ = [
    "DEFAULT_SAMPLES",
    "FLUSH_CLEARANCE",
    "ManipulationSegment",
    "SegmentSamples",
    "first_segment",
    "flush_angle",
    "sample_segment",
]

#: Angle (rad) between the left finger's inner edge and the workpiece's longest edge
#: at which segment 1 ends.  At 0 the two edges are flush and the finger touches
#: the workpiece along a whole edge (two contacts: the next segment's contact set).
#: 1e-3 rad keeps the far end of the edge 1e-3 x its length (about 0.1 mm for the
#: default hand) off the finger, a hundred times the contact tolerance
#: (:data:`qsplan.mechanics.model.geometry.CONTACT_TOL`), so each sample still has one
#: contact per finger; it shortens the path by well under 1 %.
FLUSH_CLEARANCE = 1e-3

#: Samples along a segment for the band plots and the export: 0.05 s apart over a 10 s
#: segment, enough for smooth curves and to place the narrowest point to within that.
DEFAULT_SAMPLES = 200


@dataclass(frozen=True, slots=True, eq=False)
class ManipulationSegment:
    """A path of the hand with the contact mode it should keep.

    Attributes
    ----------
    hand : TwoFingerHand
    name : str
    pose_start, pose_end : ndarray, shape (3,)
        Workpiece ``(x, y, theta)`` at the start and the end (m, m, rad); the pose moves linearly.
    duration : float
        s; the path parameter ``s = t / duration`` runs from 0 to 1 at constant speed.
    mode : str
        Desired contact mode, one letter per contact in the hand's contact order (e.g. ``"SSSS"``).
    effort_joint : str
        The torque-controlled finger; the other is velocity-controlled.
    """

    hand: TwoFingerHand
    name: str
    pose_start: np.ndarray
    pose_end: np.ndarray
    duration: float
    mode: str
    effort_joint: str

    @property
    def pose_rate(self) -> np.ndarray:
        """Constant ``(xdot, ydot, thetadot)`` (m/s, m/s, rad/s), shape (3,)."""
        return (self.pose_end - self.pose_start) / self.duration

    @property
    def effort_index(self) -> int:
        return self.hand.joint_names.index(self.effort_joint)

    @property
    def velocity_index(self) -> int:
        return 1 - self.effort_index

    def pose(self, s) -> np.ndarray:
        """Poses at path parameters ``s`` (shape (n,)), shape (n, 3)."""
        s = np.atleast_1d(np.asarray(s, dtype=float))
        return self.pose_start + s[:, None] * (self.pose_end - self.pose_start)


@dataclass(frozen=True, slots=True, eq=False)
class SegmentSamples:
    """A segment sampled at ``n`` instants.

    Attributes
    ----------
    segment : ManipulationSegment
    t : ndarray, shape (n,)
        Times (s) from the segment's start.
    s : ndarray, shape (n,)
        Path parameters in [0, 1].
    pose : ndarray, shape (n, 3)
        Workpiece poses (m, m, rad).
    q : ndarray, shape (n, 2)
        Joint angles (rad), left and right.
    qd : ndarray, shape (n, 2)
        Joint velocities along the path (rad/s); the velocity-controlled joint is
        commanded this, the effort-controlled one follows it in the desired mode.
    touching : ndarray of int, shape (n, 2)
        Workpiece vertex each finger touches.
    scenes : tuple of Scene
        One per sample, friction ``hand.mu``, the effort-controlled joint's torque 0 (a placeholder: bands ignore it).
    """

    segment: ManipulationSegment
    t: np.ndarray
    s: np.ndarray
    pose: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    touching: np.ndarray
    scenes: tuple

    def __len__(self) -> int:
        return self.t.size


def _frozen(a):
    a = np.array(a, copy=True)
    a.setflags(write=False)
    return a


def flush_angle(hand: TwoFingerHand, pose) -> float:
    """Angle (rad) from the left finger's direction up to the workpiece's longest edge (0 when flush).

    Positive while the finger leans further in than the edge, i.e. before the
    finger lies flush along it.
    """
    V = workpiece_world(hand, pose)
    k = hand.longest_edge
    a, b = V[k], V[(k + 1) % len(V)]
    if b[1] < a[1]:
        a, b = b, a
    edge = np.arctan2(b[1] - a[1], b[0] - a[0])
    return float(edge - finger_angles(hand, pose)[0][0])


def first_segment(hand: TwoFingerHand, duration: float = 10.0, effort_joint: str = "right",
                  flush_clearance: float = FLUSH_CLEARANCE) -> ManipulationSegment:  # fmt: skip
    """Segment 1 of the paper's plan: translate the workpiece left along the palm in mode 4S.

    Starts with the workpiece's bottom edge on the palm, its centre of mass at
    ``x = 0``; ends when the left finger is ``flush_clearance`` (rad) short of lying
    flush with the longest edge (found with :func:`scipy.optimize.brentq` on
    :func:`flush_angle`).

    Parameters
    ----------
    hand : TwoFingerHand
        Its longest edge must be the one the left finger closes on (its left side).
    duration : float
        s, positive.
    effort_joint : {"left", "right"}
        Torque-controlled finger (default the right one, which pushes; the left retreats at a set speed).
    flush_clearance : float
        rad, in (0, 0.1].

    Raises
    ------
    SceneError
        If the left finger does not close on the longest edge while the workpiece moves left.
    """
    from scipy.optimize import brentq

    if not (np.isfinite(duration) and duration > 0):
        raise SceneError(f"duration: expected a positive finite time (s); got {duration!r}")
    if not (np.isfinite(flush_clearance) and 0 < flush_clearance <= 0.1):
        raise SceneError(f"flush_clearance: expected an angle in (0, 0.1] rad; got {flush_clearance!r}")
    if effort_joint not in JOINT_NAMES:
        raise SceneError(f"effort_joint: expected one of {JOINT_NAMES}; got {effort_joint!r}")
    start = np.array([0.0, hand.rest_height, 0.0])

    def gap(d):
        return flush_angle(hand, start - [d, 0.0, 0.0]) - flush_clearance

    g0 = gap(0.0)
    if g0 <= 0:
        raise SceneError("workpiece: the left finger is already flush with (or past) the longest edge at the start")
    k = hand.longest_edge
    a, b = hand.workpiece[k], hand.workpiece[(k + 1) % len(hand.workpiece)]
    if b[1] < a[1]:
        a, b = b, a
    psi = float(np.arctan2(b[1] - a[1], b[0] - a[0]))
    if not 0.0 < psi < 0.5 * np.pi:
        raise SceneError("workpiece: its longest edge must be the left side, leaning right, so that the left finger "
                         "closes on it while the workpiece moves left")  # fmt: skip
    # exactly flush: the edge's line is the finger's inner edge, at half the finger width from the joint
    d_hi = float(a[0] + hand.finger_base - 0.5 * hand.finger_width / np.sin(psi))
    if d_hi <= 0 or gap(d_hi) > 0:
        raise SceneError("workpiece: the left finger does not close on its longest edge while it moves left")
    d_end = brentq(gap, 0.0, d_hi, xtol=1e-12)
    end = start - [d_end, 0.0, 0.0]
    return ManipulationSegment(hand, "segment 1: translate left until the left finger meets the longest edge",
                               _frozen(start), _frozen(end), float(duration), "SSSS", effort_joint)  # fmt: skip


def sample_segment(segment: ManipulationSegment, n: int = DEFAULT_SAMPLES, mu=None) -> SegmentSamples:
    """The segment at ``n`` evenly spaced instants, with a scene per instant.

    Parameters
    ----------
    segment : ManipulationSegment
    n : int
        At least 2.
    mu : float, optional
        Friction of the scenes; default ``segment.hand.mu``.

    Returns
    -------
    SegmentSamples
    """
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 2:
        raise SceneError(f"samples: expected an integer of at least 2; got {n!r}")
    s = np.linspace(0.0, 1.0, int(n))
    poses = segment.pose(s)
    rate = segment.pose_rate
    q = np.empty((n, 2))
    qd = np.empty((n, 2))
    touching = np.empty((n, 2), dtype=int)
    scenes = []
    v = segment.velocity_index
    for k, pose in enumerate(poses):
        q[k], touching[k] = finger_angles(segment.hand, pose)
        qd[k] = finger_angle_rates(segment.hand, pose, rate)
        scenes.append(hand_scene(segment.hand, pose, q[k], segment.effort_joint, velocity=qd[k, v], effort=0.0, mu=mu))
    changed = np.flatnonzero(np.any(touching != touching[0], axis=1))
    if changed.size:
        k = int(changed[0])
        side = JOINT_NAMES[int(np.flatnonzero(touching[k] != touching[0])[0])]
        raise SceneError(f"segment: the {side} finger moves from workpiece vertex {touching[0][JOINT_NAMES.index(side)]} to "
                         f"another at s = {s[k]:.4g} (a contact change inside the segment)")  # fmt: skip
    return SegmentSamples(segment, _frozen(s * segment.duration), _frozen(s), _frozen(poses), _frozen(q), _frozen(qd),
                          _frozen(touching), tuple(scenes))  # fmt: skip
