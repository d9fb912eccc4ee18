"""The thin rod on two moving supports (Section 5.1, Figs. 7-8) as a :class:`qsplan.mechanics.motion.system.MotionSystem`.

The rod lies along x with its centre of mass at the world origin at t = 0.
Support 1 (contact 1) starts at ``x = -l1``, support 2 (contact 2) at ``x = +l2``;
each is a velocity-controlled prismatic joint along x, support 1 moving right
and support 2 left, both at ``speed``.  Contact normals point up into the rod,
``t = (-1, 0)``; in the raw form of :func:`qsplan.hands.examples.paper.rod_scene` the contact
velocities are ``[v_n, v_t] = [0, -V]`` and ``[0, +V]``, here ``J_t = -I``.

Closed form (derived for :func:`rod_closed_form`)
-------------------------------------------------
Statics.  With weight ``W`` at the centre of mass, moment balance about each
support gives ``c_1n = W l2 / (l1 + l2)`` and ``c_2n = W l1 / (l1 + l2)``;
horizontal balance gives ``c_1t + c_2t = 0``.

Modes.  Only R1S2 (letters ``"RS"``) and R2S1 (``"SR"``) meet the utility
conditions (29)-(32).  In ``"RS"`` contact 2 slides with ``|c_2t| = mu_2S c_2n``
(eq. 17), so ``|c_1t| = mu_2S c_2n <= mu_1R c_1n`` (eq. 9), i.e.

    RS feasible  <=>  l1 mu_2S <= l2 mu_1R  <=>  rho <= b = mu_1R / mu_2S,
    SR feasible  <=>  l2 mu_1S <= l1 mu_2R  <=>  rho >= a = mu_1S / mu_2R,

with ``rho = l1 / l2``: the partition line ``l1 mu_2 = l2 mu_1`` of Fig. 8 through
the friction point of each mode (the rectangle's lower-right corner
``(mu_1R, mu_2S)`` for RS, its upper-left corner ``(mu_1S, mu_2R)`` for SR).
Kinetic <= static gives ``a <= b``.

Kinematics.  In RS the rod moves with support 1: ``l1`` is constant and ``l2``
shrinks at ``2V``; in SR ``l2`` is constant and ``l1`` shrinks at ``2V``.  In both,
``s = l1 + l2 = s0 - 2 V t``.

Switches.  An SR segment from ``(l1, l2)`` ends when ``rho`` falls to ``a``:

    t_end - t_start = (l1 - a l2) / (2V),      l1_end = a l2,   l2_end = l2;

an RS segment ends when ``rho`` rises to ``b``:

    t_end - t_start = (l2 - l1 / b) / (2V),    l2_end = l1 / b, l1_end = l1.

At the end of SR (``rho = a``) RS is feasible with ``rho = a <= b``; it persists iff
``a < b`` (``mu_1S mu_2S < mu_1R mu_2R``), and SR would fail at once: the mode
switches.  Symmetrically at the end of RS.  If ``a = b`` (equal static and kinetic
coefficients) both modes are feasible on the line and each fails at once, the
farther support having slid until ``l1 mu_2 = l2 mu_1``: the motion leaves the model
(only the non-determinate 2S mode would continue) and the run stops there.

Start.  ``rho0 > b``: SR; ``rho0 < a``: RS; ``rho0 = a``: RS (SR fails at once);
``rho0 = b``: SR; ``a < rho0 < b``: both persist, ambiguous (static friction
holds either way), unless an initial mode is given.

Switch instants in closed form.  Let ``s_k`` be ``l1 + l2`` at the k-th switch, so
``t_k = (s0 - s_k) / (2V)``.  At the end of SR ``l1 = a s / (1 + a)``, ``l2 = s / (1 + a)``;
at the end of RS ``l1 = b s / (1 + b)``, ``l2 = s / (1 + b)``.  An RS segment keeps ``l1``,
an SR segment keeps ``l2``, hence

    across RS:  s_{k+1} = r_RS s_k,   r_RS = a (1 + b) / (b (1 + a)),
    across SR:  s_{k+1} = r_SR s_k,   r_SR = (1 + a) / (1 + b),      r_RS r_SR = a / b.

Starting in SR: ``s_1 = (1 + a) l2_0``, then ``s_{2j+1} = s_1 (a/b)^j`` and
``s_{2j+2} = r_RS s_1 (a/b)^j``; starting in RS: ``s_1 = (1 + b) l1_0 / b``, then
``r_SR`` and ``r_RS`` alternate the other way round.

Zeno.  With ``a < b`` the ``s_k`` shrink geometrically, so the ``t_k`` converge to
``t* = (l1_0 + l2_0) / (2V)``, when both supports reach the centre of mass
together: infinitely many switches in finite time.  The simulator (and this
closed form) stops when a segment between two switches lasts less than
``min_segment``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from qsplan.mechanics import QsplanError, Scene, point_wrench
from qsplan.mechanics.motion.simulator import MotionOptions, simulate
from qsplan.mechanics.motion.system import Friction, make_friction, rigid_body_rates

__all__ = [
    "RodOnSupports",
    "make_rod_system",
    "rod_initial_state",
    "rod_distances",
    "simulate_rod",
    "RodSegment",
    "RodClosedForm",
    "rod_closed_form",
    "check_rod_inputs",
]


def check_rod_inputs(l1, l2, mu_static, mu_kinetic, speed, duration=None):
    """Validate the rod's parameters; raise :class:`QsplanError` naming the first bad one.

    Returns ``(l1, l2, mu_static (2,), mu_kinetic (2,), speed, duration)`` as floats/arrays.
    """
    def positive(v, name):
        try:
            f = float(v)
        except (TypeError, ValueError):
            raise QsplanError(f"{name}: expected a number; got {v!r}") from None
        if not np.isfinite(f) or f <= 0:
            raise QsplanError(f"{name}: expected a positive finite number; got {v!r}")
        return f

    l1 = positive(l1, "l1")
    l2 = positive(l2, "l2")
    speed = positive(speed, "speed")
    duration = None if duration is None else positive(duration, "duration")
    for name, mu in (("mu_static", mu_static), ("mu_kinetic", mu_kinetic)):
        arr = np.asarray(mu, dtype=float).reshape(-1)
        if arr.size != 2:
            raise QsplanError(f"{name}: expected 2 coefficients (contact 1, contact 2); got {arr.size}")
    friction = make_friction(mu_static, mu_kinetic)
    return l1, l2, friction.static, friction.kinetic, speed, duration


@dataclass(frozen=True, slots=True, eq=False)
class RodOnSupports:
    """The rod of Fig. 7 as a motion system: state ``[x_c, y_c, theta, s1, s2]``.

    ``(x_c, y_c, theta)`` is the rod's pose (centre of mass, m; angle, rad); ``s1, s2``
    the supports' x positions (m), prismatic joints driven at ``+speed`` and ``-speed``.
    Build it with :func:`make_rod_system`.

    Attributes
    ----------
    friction : Friction
        Static (rolling) and kinetic (sliding) coefficients of supports 1 and 2.
    speed : float
        m/s, each support.
    weight : float
        N; it scales the forces only, never the motion.
    """

    friction: Friction
    speed: float
    weight: float = 1.0
    state_names: ClassVar[tuple] = ("x_c (m)", "y_c (m)", "theta (rad)", "s1 (m)", "s2 (m)")
    contact_names: ClassVar[tuple] = ("support 1", "support 2")
    limit_names: ClassVar[tuple] = (
        "support 1 reaches the centre of mass (l1 = 0)",
        "support 2 reaches the centre of mass (l2 = 0)",
    )

    def scene(self, x, contacts=(0, 1)):
        """The instant at ``x`` (eq. 1 wrenches about the world origin, ``J_n, J_t`` of the supports).

        Built directly (no :func:`qsplan.mechanics.make_scene` checks): every input is validated
        when the system is made, and the simulator never passes a non-finite state.
        """
        x = np.asarray(x, dtype=float)
        c, th = np.cos(x[2]), np.sin(x[2])
        idx = list(contacts)
        r = np.array([[x[3], 0.0], [x[4], 0.0]])[idx]
        n = np.array([-th, c])  # the rod's lower side, up into the rod
        t = np.array([-c, -th])  # tangent_from_normal(n)
        Wn = np.vstack([np.tile(n, (len(idx), 1)).T, r[:, 0] * n[1] - r[:, 1] * n[0]])  # eq. (1)
        Wt = np.vstack([np.tile(t, (len(idx), 1)).T, r[:, 0] * t[1] - r[:, 1] * t[0]])
        Jn = np.zeros((len(idx), 2))
        Jt = np.zeros((len(idx), 2))
        Jn[np.arange(len(idx)), idx] = n[0]  # both prismatic joints slide along +x: j = (1, 0) . (n, t)
        Jt[np.arange(len(idx)), idx] = t[0]
        return Scene(
            Wn=Wn, Wt=Wt, Jn=Jn, Jt=Jt, mu=self.friction.static[idx], g_obj=point_wrench(x[:2], (0.0, -self.weight)),
            g_man=np.zeros(2), effort_controlled=np.zeros(2, dtype=bool),
            joint_velocity=np.array([self.speed, -self.speed]), joint_effort=np.full(2, np.nan),
            joint_names=("support 1", "support 2"), contact_names=tuple(self.contact_names[i] for i in idx),
        )  # fmt: skip

    def rates(self, x, qdot, thetadot):
        """``dx/dt``: the pose from ``qdot`` (:func:`qsplan.mechanics.motion.system.pose_rate`), the supports from ``thetadot``."""
        return rigid_body_rates(x, qdot, thetadot)

    def limits(self, x):
        """``(l1, l2)`` (m): the run stops if a support reaches the centre of mass."""
        return rod_distances(np.asarray(x)[None])[0]


def make_rod_system(mu_static, mu_kinetic, speed, weight=1.0) -> RodOnSupports:
    """Validate and build the rod system (see :func:`check_rod_inputs` for the checks)."""
    _, _, s, k, speed, _ = check_rod_inputs(1.0, 1.0, mu_static, mu_kinetic, speed)
    if not (np.isfinite(weight) and weight > 0):
        raise QsplanError(f"weight: expected a positive finite number; got {weight!r}")
    return RodOnSupports(Friction(s, k), float(speed), float(weight))


def rod_initial_state(l1, l2) -> np.ndarray:
    """State with the rod's centre of mass at the origin and supports at ``-l1``, ``+l2``, shape (5,)."""
    return np.array([0.0, 0.0, 0.0, -float(l1), float(l2)])


def rod_distances(states) -> np.ndarray:
    """Distances ``(l1, l2)`` of the supports from the centre of mass along the rod.

    Parameters
    ----------
    states : array-like, shape (k, 5)

    Returns
    -------
    ndarray, shape (k, 2)
    """
    X = np.asarray(states, dtype=float).reshape(-1, 5)
    u = np.stack([np.cos(X[:, 2]), np.sin(X[:, 2])], axis=1)
    s1 = np.stack([X[:, 3], np.zeros(len(X))], axis=1)
    s2 = np.stack([X[:, 4], np.zeros(len(X))], axis=1)
    l1 = np.einsum("ij,ij->i", X[:, :2] - s1, u)
    l2 = np.einsum("ij,ij->i", s2 - X[:, :2], u)
    return np.stack([l1, l2], axis=1)


def simulate_rod(l1, l2, mu_static, mu_kinetic, speed, duration, options: MotionOptions | None = None,
                 initial_mode: str | None = None, weight: float = 1.0):  # fmt: skip
    """Simulate the rod of Fig. 7 with :func:`qsplan.mechanics.motion.simulator.simulate`.

    Parameters
    ----------
    l1, l2 : float
        Initial distances (m) of supports 1 and 2 from the centre of mass, positive.
    mu_static, mu_kinetic : (float, float)
        Coefficients of contacts 1 and 2; kinetic <= static.
    speed : float
        m/s, each support, toward the other.
    duration : float
        s.
    options : MotionOptions, optional
        Default: ``max_step`` one hundredth of the time the supports take to meet.
    initial_mode : "RS" or "SR", optional
        Resolves an ambiguous start (``a < l1/l2 < b``); ignored when the start is unique.

    Returns
    -------
    Motion
    """
    l1, l2, s, k, speed, duration = check_rod_inputs(l1, l2, mu_static, mu_kinetic, speed, duration)
    system = RodOnSupports(Friction(s, k), speed, float(weight))
    if options is None:
        options = MotionOptions(max_step=(l1 + l2) / (2 * speed) / 100)
    policy = None
    if initial_mode is not None:
        want = str(initial_mode).upper()
        if want not in ("RS", "SR"):
            raise QsplanError(f"initial_mode: expected 'RS' or 'SR'; got {initial_mode!r}")
        policy = lambda t, x, cands: want if t == 0.0 else None  # noqa: E731
    return simulate(system, rod_initial_state(l1, l2), duration, options=options, policy=policy)


@dataclass(frozen=True, slots=True)
class RodSegment:
    """One closed-form segment: mode letters, times (s) and distances (m) at both ends."""

    mode: str
    t_start: float
    t_end: float
    l1_start: float
    l2_start: float
    l1_end: float
    l2_end: float


@dataclass(frozen=True, slots=True, eq=False)
class RodClosedForm:
    """The rod's motion in closed form (module docstring).

    Attributes
    ----------
    segments : tuple of RodSegment
    stopped : str or None
        A :data:`qsplan.mechanics.motion.trajectory.STOP_KINDS` entry, or None when the duration was reached.
    t_star : float
        ``(l1_0 + l2_0) / (2V)``, where switch instants accumulate (s).
    a, b : float
        ``mu_1S / mu_2R`` and ``mu_1R / mu_2S``: ``l1 / l2`` at the ends of SR and RS segments.
    """

    segments: tuple
    stopped: str | None
    t_star: float
    a: float
    b: float

    @property
    def switch_times(self) -> np.ndarray:
        return np.array([s.t_end for s in self.segments[:-1]])


def rod_closed_form(l1, l2, mu_static, mu_kinetic, speed, duration, initial_mode=None,
                    min_segment=None, max_switches=None) -> RodClosedForm:  # fmt: skip
    """Segments of the rod's motion from the closed form of the module docstring.

    Parameters are those of :func:`simulate_rod`; ``min_segment`` (s) and
    ``max_switches`` stop the run exactly as :class:`qsplan.mechanics.motion.simulator.MotionOptions`
    does (defaults: theirs).  Static coefficients must be positive (with a zero one the line never
    reaches the rectangle's corner and the model is ambiguous for all time).
    """
    l1, l2, s, k, V, T = check_rod_inputs(l1, l2, mu_static, mu_kinetic, speed, duration)
    defaults = MotionOptions()
    min_segment = defaults.min_segment if min_segment is None else float(min_segment)
    max_switches = defaults.max_switches if max_switches is None else int(max_switches)
    if np.any(s <= 0):
        raise QsplanError(f"mu_static: the closed form needs positive static coefficients; got {s.tolist()}")
    (m1R, m2R), (m1S, m2S) = s, k
    a, b = m1S / m2R, (m1R / m2S if m2S > 0 else np.inf)
    t_star = (l1 + l2) / (2 * V)
    f_sr = l1 * m2R - l2 * m1S  # SR slack (times a positive factor)
    f_rs = l2 * m1R - l1 * m2S
    if f_sr > 0 and f_rs > 0:
        if initial_mode is None:
            return RodClosedForm((), "ambiguous", t_star, a, b)
        mode = str(initial_mode).upper()
    elif f_sr > 0:
        mode = "SR"
    elif f_rs > 0:
        mode = "RS"
    else:  # both on their bound (a = b = rho0) or neither feasible
        return RodClosedForm((), "no_persistent_mode" if f_sr == 0 or f_rs == 0 else "jam", t_star, a, b)
    segs, t, switches = [], 0.0, 0
    while True:
        if mode == "SR":
            l1_end, l2_end, dt = a * l2, l2, (l1 - a * l2) / (2 * V)
        else:
            l1_end, l2_end, dt = l1, l1 / b, (l2 - l1 / b) / (2 * V)
        if t + dt >= T:
            frac = T - t
            e1, e2 = (l1 - 2 * V * frac, l2) if mode == "SR" else (l1, l2 - 2 * V * frac)
            segs.append(RodSegment(mode, t, T, l1, l2, e1, e2))
            return RodClosedForm(tuple(segs), None, t_star, a, b)
        segs.append(RodSegment(mode, t, t + dt, l1, l2, l1_end, l2_end))
        t, l1, l2 = t + dt, l1_end, l2_end
        if min(l1, l2) <= 0:  # a zero kinetic coefficient: the sliding support reaches the centre of mass
            return RodClosedForm(tuple(segs), "limit", t_star, a, b)
        if dt < min_segment and len(segs) > 1:
            return RodClosedForm(tuple(segs), "zeno", t_star, a, b)
        if not a < b:
            return RodClosedForm(tuple(segs), "no_persistent_mode", t_star, a, b)
        switches += 1
        if switches > max_switches:
            return RodClosedForm(tuple(segs), "max_switches", t_star, a, b)
        mode = "RS" if mode == "SR" else "SR"
