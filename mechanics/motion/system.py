"""The system a finite motion integrates (Section 5.1): per-contact friction, the protocol, rigid-body rates.

A :class:`MotionSystem` gives, at a configuration ``x``, the scene of the contacts in
force and the rates ``dx/dt`` for the mode's velocities; :class:`FrozenScene` wraps a
fixed scene as one.  :class:`Friction` holds the static and kinetic coefficients of
every potential contact.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np

from qsplan.mechanics.errors import QsplanError
from qsplan.mechanics.model.friction import check_friction
from qsplan.mechanics.model.scene import Scene, check_finite_array
from qsplan.mechanics.modes.contact_mode import ContactMode

__all__ = [
    "Friction",
    "make_friction",
    "MotionSystem",
    "pose_rate",
    "rigid_body_rates",
    "FrozenScene",
    "frozen_scene_system",
]


@dataclass(frozen=True, slots=True, eq=False)
class Friction:
    """Static and kinetic Coulomb coefficients of every potential contact (eq. 8).

    Attributes
    ----------
    static : ndarray, shape (n_p,)
        ``mu_R``: used while the contact rolls (sticks) and while it breaks.
    kinetic : ndarray, shape (n_p,)
        ``mu_S``: used while it slides; ``0 <= kinetic <= static``.
    """

    static: np.ndarray
    kinetic: np.ndarray

    def for_mode(self, mode: ContactMode, contacts) -> np.ndarray:
        """Coefficients of the contacts ``contacts`` (indices, shape (n_c,)) under ``mode``."""
        idx = np.asarray(contacts, dtype=int)
        sliding = np.array([c == "S" for c in mode.letters], dtype=bool)
        mu = np.where(sliding, self.kinetic[idx], self.static[idx])
        mu.setflags(write=False)
        return mu


def make_friction(static, kinetic) -> Friction:
    """Validate and build :class:`Friction`.

    Parameters
    ----------
    static, kinetic : array-like, shape (n_p,)

    Raises
    ------
    QsplanError
        Shapes differ, a coefficient is negative or not finite, or a kinetic
        coefficient exceeds its static one (Coulomb friction: sliding never holds
        more than sticking).  Equal coefficients are allowed.
    """
    s = check_finite_array(np.atleast_1d(static), "friction.static", (None,))
    k = check_finite_array(np.atleast_1d(kinetic), "friction.kinetic", (s.size,))
    for name, arr in (("static", s), ("kinetic", k)):
        check_friction(arr, f"friction.{name}", element=f"friction.{name}[{{i}}]")
    if np.any(k > s):
        i = int(np.flatnonzero(k > s)[0])
        raise QsplanError(f"friction.kinetic[{i}]: expected at most the static coefficient {s[i]}; got {k[i]}")
    s.setflags(write=False)
    k.setflags(write=False)
    return Friction(s, k)


@runtime_checkable
class MotionSystem(Protocol):
    """A hand and workpiece whose configuration ``x`` evolves under velocity inputs.

    Required attributes and methods:

    * ``state_names`` : tuple of str, length n_x (with units, e.g. ``"x (m)"``).
    * ``contact_names`` : tuple of str, length n_p, the potential contacts.
    * ``friction`` : :class:`Friction` over the potential contacts.
    * ``scene(x, contacts) -> Scene``: the instant at ``x`` with the potential
      contacts ``contacts`` (tuple of indices, in that order); its ``mu`` is ignored.
    * ``rates(x, qdot, thetadot) -> ndarray (n_x,)``: ``dx/dt`` when the workpiece
      point at the world origin moves at ``qdot`` (3,) and the joints at ``thetadot``.

    Optional:

    * ``gaps(x) -> ndarray (n_p,)``: signed distances (m) of the potential contacts,
      0 when touching; without it every contact is always in contact.
    * ``limits(x) -> ndarray (n_l,)`` and ``limit_names``: the run stops when one
      reaches zero (the configuration leaves the system's valid range).
    """

    state_names: tuple
    contact_names: tuple
    friction: Friction

    def scene(self, x, contacts) -> Scene: ...

    def rates(self, x, qdot, thetadot) -> np.ndarray: ...


def pose_rate(pose, qdot) -> np.ndarray:
    """``d(x, y, theta)/dt`` of a workpiece pose from ``qdot``.

    Parameters
    ----------
    pose : array-like, shape (3,)
        Position (m) of the workpiece's reference point (its centre of mass) and angle (rad).
    qdot : array-like, shape (3,)
        Velocity of the workpiece point at the world origin (m/s) and angular velocity (rad/s).

    Returns
    -------
    ndarray, shape (3,)
        ``qdot[:2] + qdot[2] * perp(p)`` with ``perp(p) = (-p_y, p_x)``, and ``qdot[2]``.
    """
    p = np.asarray(pose, dtype=float)
    w = float(qdot[2])
    return np.array([qdot[0] - w * p[1], qdot[1] + w * p[0], w])


def rigid_body_rates(x, qdot, thetadot) -> np.ndarray:
    """Rates of the usual state layout ``x = [pose (3,), joint positions (n_j,)]``, shape (3 + n_j,)."""
    return np.concatenate([pose_rate(x[:3], qdot), np.asarray(thetadot, dtype=float)])


@dataclass(frozen=True, slots=True, eq=False)
class FrozenScene:
    """One instant held fixed while the state moves: a raw scene (e.g. eq. 37, 42) as a system.

    The state is the workpiece pose and the joint positions (``3 + n_j``); wrenches and
    Jacobians do not change with it, so every condition stays constant.  Use it to ask
    the simulator's start-up question of one configuration: which mode starts, or is
    the start ambiguous or jammed.  Build it with :func:`frozen_scene_system`.
    """

    base: Scene
    friction: Friction

    @property
    def state_names(self) -> tuple:
        return ("x (m)", "y (m)", "theta (rad)") + tuple(f"{j} (rad or m)" for j in self.base.joint_names)

    @property
    def contact_names(self) -> tuple:
        return self.base.contact_names

    def scene(self, x, contacts) -> Scene:
        if tuple(contacts) != tuple(range(self.base.n_contacts)):
            raise QsplanError(f"contacts: a frozen scene has all its contacts; got {contacts}")
        return self.base

    def rates(self, x, qdot, thetadot) -> np.ndarray:
        return rigid_body_rates(x, qdot, thetadot)


def frozen_scene_system(scene: Scene, mu_kinetic=None) -> FrozenScene:
    """Wrap ``scene`` as a :class:`FrozenScene`; static friction ``scene.mu``, kinetic
    ``mu_kinetic`` (scalar or shape (n_c,); default equal to the static)."""
    kinetic = scene.mu if mu_kinetic is None else np.broadcast_to(np.asarray(mu_kinetic, float), scene.mu.shape)
    return FrozenScene(scene, make_friction(scene.mu, kinetic))
