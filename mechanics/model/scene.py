"""The ``Scene`` value: everything one instant of the quasistatic problem needs (Section 3).

A scene holds the contact wrenches ``W_n, W_t`` (eq. 1-2), the contact
Jacobian rows ``J_n, J_t`` (eq. 5), the friction coefficients ``mu`` (eq. 8),
the external loads ``g_obj`` and ``g_man`` (eqs. 2-3), and the control-mode
partition of the joints with its inputs: velocities of the velocity-controlled
joints, efforts of the effort-controlled ones.

All quantities are SI: forces N, moments N m, lengths m, angles rad, joint
velocities rad/s (revolute) or m/s (prismatic), efforts N m or N.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from qsplan.mechanics.model.contact import shift_wrenches
from qsplan.mechanics.errors import SceneError
from qsplan.mechanics.model.friction import check_friction

__all__ = ["Scene", "make_scene", "check_finite_array"]


def check_finite_array(value, field: str, shape: tuple) -> np.ndarray:
    """Convert ``value`` to a float array of ``shape``; raise :class:`SceneError` naming ``field``.

    ``shape`` entries of ``None`` accept any length.
    """
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise SceneError(f"{field}: expected numbers of shape {_fmt(shape)}; got {value!r}") from None
    if arr.ndim != len(shape) or any(s is not None and s != a for s, a in zip(shape, arr.shape)):
        raise SceneError(f"{field}: expected shape {_fmt(shape)}; got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise SceneError(f"{field}: expected finite numbers; got {arr.tolist()}")
    return arr


def _fmt(shape):
    return "(" + ", ".join("any" if s is None else str(s) for s in shape) + ")"


def _frozen(a: np.ndarray) -> np.ndarray:
    a = np.array(a, dtype=a.dtype, copy=True)
    a.setflags(write=False)
    return a


@dataclass(frozen=True, slots=True, eq=False)
class Scene:
    """One instant of a workpiece contacted by a manipulator.

    Build it with :func:`make_scene` (which validates), or load one with
    :func:`qsplan.mechanics.load_scene`.

    Attributes
    ----------
    Wn, Wt : ndarray, shape (3, n_c)
        Normal and tangential contact wrenches about the world origin (eq. 1).
    Jn, Jt : ndarray, shape (n_c, n_j)
        Contact Jacobian rows ``j_in``, ``j_it`` (eq. 5).
    mu : ndarray, shape (n_c,)
        Friction coefficients (eq. 8), nonnegative.
    g_obj : ndarray, shape (3,)
        External wrench on the workpiece about the world origin (eq. 2).
    g_man : ndarray, shape (n_j,)
        Joint efforts induced by external loads on the links (eq. 3).
    effort_controlled : ndarray of bool, shape (n_j,)
        True for effort-controlled joints (``tau_I``), False for velocity-controlled.
    joint_velocity : ndarray, shape (n_j,)
        Commanded velocities; NaN where effort-controlled.
    joint_effort : ndarray, shape (n_j,)
        Commanded efforts; NaN where velocity-controlled.
    joint_names, contact_names : tuple of str
    virtual_joints : bool
        True when the scene gave contact-point velocities instead of joints (the paper's
        examples): one virtual velocity-controlled joint with unit speed carries them, and
        joint quantities are not reported.
    """

    Wn: np.ndarray
    Wt: np.ndarray
    Jn: np.ndarray
    Jt: np.ndarray
    mu: np.ndarray
    g_obj: np.ndarray
    g_man: np.ndarray
    effort_controlled: np.ndarray
    joint_velocity: np.ndarray
    joint_effort: np.ndarray
    joint_names: tuple
    contact_names: tuple
    virtual_joints: bool = False

    @property
    def n_contacts(self) -> int:
        return self.Wn.shape[1]

    @property
    def n_joints(self) -> int:
        return self.Jn.shape[1]

    @property
    def effort_joints(self) -> np.ndarray:
        """0-based indices of effort-controlled joints, shape (n_e,)."""
        return np.flatnonzero(self.effort_controlled)

    @property
    def velocity_joints(self) -> np.ndarray:
        """0-based indices of velocity-controlled joints, shape (n_v,)."""
        return np.flatnonzero(~self.effort_controlled)

    @property
    def dof(self) -> int:
        """``3 + |tau_I|``: the applicable constraints every tested mode has (eq. 49)."""
        return 3 + int(self.effort_controlled.sum())

    @property
    def W(self) -> np.ndarray:
        """Global wrench matrix, shape (3, 2 n_c), columns ``[W_n, W_t]`` (eq. 2, c = [c_n; c_t])."""
        return np.hstack([self.Wn, self.Wt])

    @property
    def J(self) -> np.ndarray:
        """Stacked contact Jacobian ``[J_n; J_t]``, shape (2 n_c, n_j)."""
        return np.vstack([self.Jn, self.Jt])

    def with_mu(self, mu) -> "Scene":
        """The same scene with friction coefficients ``mu`` (scalar or shape (n_c,))."""
        return make_scene(**{**self._fields(), "mu": np.broadcast_to(np.asarray(mu, float), (self.n_contacts,))})

    def with_inputs(self, joint_velocity=None, joint_effort=None) -> "Scene":
        """The same scene with other joint inputs (shape (n_j,); NaN where unused)."""
        f = self._fields()
        if joint_velocity is not None:
            f["joint_velocity"] = joint_velocity
        if joint_effort is not None:
            f["joint_effort"] = joint_effort
        return make_scene(**f)

    def with_control(self, effort_controlled, joint_velocity, joint_effort) -> "Scene":
        """The same scene under another control-mode partition with its inputs.

        Parameters
        ----------
        effort_controlled : array-like of bool, shape (n_j,)
        joint_velocity, joint_effort : array-like, shape (n_j,)
            Inputs of the velocity- and effort-controlled joints (other entries ignored).
        """
        e = np.asarray(effort_controlled, dtype=bool)
        f = self._fields()
        f.update(
            effort_controlled=e,
            joint_velocity=np.where(e, np.nan, np.asarray(joint_velocity, float)),
            joint_effort=np.where(e, np.asarray(joint_effort, float), np.nan),
        )
        return make_scene(**f)

    def moved_origin(self, origin) -> "Scene":
        """The same physical scene expressed about the world point ``origin`` (shape (2,)).

        Wrench moments are re-taken about the new origin; Jacobians and joint
        quantities are unchanged.  The solver's forces, joint velocities and
        efforts are invariant under this; ``qdot`` changes as the velocity of the
        workpiece point at the new origin.
        """
        return replace(
            self,
            Wn=_frozen(shift_wrenches(self.Wn, origin)),
            Wt=_frozen(shift_wrenches(self.Wt, origin)),
            g_obj=_frozen(shift_wrenches(self.g_obj[:, None], origin)[:, 0]),
        )

    def _fields(self) -> dict:
        return {f: getattr(self, f) for f in self.__slots__}


def make_scene(
    Wn,
    Wt,
    Jn,
    Jt,
    mu,
    g_obj,
    g_man=None,
    effort_controlled=None,
    joint_velocity=None,
    joint_effort=None,
    joint_names=None,
    contact_names=None,
    virtual_joints=False,
) -> Scene:
    """Validate and build a :class:`Scene`.

    Parameters are those of :class:`Scene`; ``g_man`` defaults to zeros,
    ``effort_controlled`` to all False (every joint velocity-controlled).

    Raises
    ------
    SceneError
        On a wrong shape, a non-finite number, a negative ``mu``, a missing
        velocity for a velocity-controlled joint or a missing effort for an
        effort-controlled one.
    """
    Wn = check_finite_array(Wn, "Wn", (3, None))
    n_c = Wn.shape[1]
    if n_c == 0:
        raise SceneError("contacts: expected at least one contact; got none")
    Wt = check_finite_array(Wt, "Wt", (3, n_c))
    Jn = np.asarray(Jn, dtype=float)
    n_j = Jn.shape[1] if Jn.ndim == 2 else 0
    Jn = check_finite_array(Jn, "Jn", (n_c, None))
    n_j = Jn.shape[1]
    Jt = check_finite_array(Jt, "Jt", (n_c, n_j))
    mu = check_friction(check_finite_array(mu, "mu", (n_c,)), "mu", element="contacts[{i}].mu")
    g_obj = check_finite_array(g_obj, "g_obj", (3,))
    g_man = np.zeros(n_j) if g_man is None else check_finite_array(g_man, "g_man", (n_j,))
    if effort_controlled is None:
        effort_controlled = np.zeros(n_j, dtype=bool)
    effort_controlled = np.array(effort_controlled, dtype=bool).reshape(-1)
    if effort_controlled.shape != (n_j,):
        raise SceneError(f"effort_controlled: expected shape ({n_j},); got {effort_controlled.shape}")
    jv = np.full(n_j, np.nan) if joint_velocity is None else np.array(joint_velocity, dtype=float).reshape(-1)
    je = np.full(n_j, np.nan) if joint_effort is None else np.array(joint_effort, dtype=float).reshape(-1)
    for name, arr in (("joint_velocity", jv), ("joint_effort", je)):
        if arr.shape != (n_j,):
            raise SceneError(f"{name}: expected shape ({n_j},); got {arr.shape}")
        if np.any(np.isinf(arr)):
            raise SceneError(f"{name}: expected finite numbers; got {arr.tolist()}")
    names = tuple(joint_names) if joint_names is not None else tuple(f"j{i}" for i in range(n_j))
    if len(names) != n_j:
        raise SceneError(f"joint_names: expected {n_j} names; got {len(names)}")
    for i in range(n_j):
        if effort_controlled[i] and not np.isfinite(je[i]):
            raise SceneError(f"joints[{i}].effort: effort-controlled joint {names[i]!r} needs a finite effort")
        if not effort_controlled[i] and not np.isfinite(jv[i]):
            raise SceneError(f"joints[{i}].velocity: velocity-controlled joint {names[i]!r} needs a finite velocity")
    cnames = tuple(contact_names) if contact_names is not None else tuple(f"c{i + 1}" for i in range(n_c))
    if len(cnames) != n_c:
        raise SceneError(f"contact_names: expected {n_c} names; got {len(cnames)}")
    return Scene(
        Wn=_frozen(Wn),
        Wt=_frozen(Wt),
        Jn=_frozen(Jn),
        Jt=_frozen(Jt),
        mu=_frozen(mu),
        g_obj=_frozen(g_obj),
        g_man=_frozen(g_man),
        effort_controlled=_frozen(effort_controlled),
        joint_velocity=_frozen(jv),
        joint_effort=_frozen(je),
        joint_names=names,
        contact_names=cnames,
        virtual_joints=bool(virtual_joints),
    )
