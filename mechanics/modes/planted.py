"""Seeded random scenes built around a planted feasible mode (for tests and benchmarks).

The construction guarantees the planted mode is feasible: a random workpiece
twist and joint velocities are drawn, the Jacobian rows are adjusted so that
the planted mode's kinematic constraints (13) hold exactly, breaking contacts
separate and sliding contacts slip at speeds of order one; contact forces are
drawn strictly inside their friction cones (rolling) or on the edge opposing
the slip (sliding, eq. 17), and ``g_obj`` and the commanded efforts are set
so that the equilibrium equations (2)-(3) hold.  Every other mode is whatever
the random geometry makes it.
"""

from __future__ import annotations

import numpy as np

from qsplan.mechanics.model.contact import wrench_matrices
from qsplan.mechanics.modes.contact_mode import ContactMode, random_mode
from qsplan.mechanics.model.scene import Scene, make_scene

__all__ = ["planted_scene"]


def planted_scene(
    rng: np.random.Generator,
    n_contacts: int,
    n_effort: int = 0,
    n_joints: int | None = None,
    mode: ContactMode | None = None,
    mu_range=(0.1, 0.8),
) -> tuple[Scene, ContactMode]:
    """A random scene in which ``mode`` (random if None) is feasible.

    Parameters
    ----------
    rng : numpy.random.Generator
    n_contacts : int
        ``n_c``.
    n_effort : int
        Number of effort-controlled joints ``|tau_I|``; modes tested have ``3 + n_effort`` constraints.
    n_joints : int, optional
        Total joints (default ``n_effort + 2``); at least ``n_effort + 1``.
    mode : ContactMode, optional
        With ``2 n_R + n_S = 3 + n_effort``.
    mu_range : (float, float)
        Friction coefficients are uniform in this range.

    Returns
    -------
    scene : Scene
    mode : ContactMode
        The planted mode.
    """
    n_j = n_effort + 2 if n_joints is None else n_joints
    if n_j < n_effort + 1:
        raise ValueError("n_joints: need at least one velocity-controlled joint to drive the motion")
    dof = 3 + n_effort
    if mode is None:
        mode = random_mode(rng, n_contacts, dof)  # uniform over eq. (49) without listing it
    r = rng.uniform(-1, 1, size=(n_contacts, 2))
    ang = rng.uniform(0, 2 * np.pi, size=n_contacts)
    Wn, Wt = wrench_matrices(r, np.column_stack([np.cos(ang), np.sin(ang)]))
    mu = rng.uniform(*mu_range, size=n_contacts)
    Jn = rng.normal(size=(n_contacts, n_j))
    Jt = rng.normal(size=(n_contacts, n_j))
    effort = np.zeros(n_j, dtype=bool)
    effort[rng.choice(n_j, size=n_effort, replace=False)] = True
    vel_joints = np.flatnonzero(~effort)
    qdot = rng.normal(size=3)
    thetadot = rng.normal(size=n_j)
    drive = vel_joints[np.argmax(np.abs(thetadot[vel_joints]))]
    if abs(thetadot[drive]) < 0.5:
        thetadot[drive] = 0.5 * np.sign(thetadot[drive] or 1.0)

    def set_row(J, w, i, target):
        # choose J[i, drive] so that w . qdot - J[i] . thetadot == target
        J[i, drive] += (w @ qdot - J[i] @ thetadot - target) / thetadot[drive]

    c_n = np.zeros(n_contacts)
    c_t = np.zeros(n_contacts)
    for i, letter in enumerate(mode.letters):
        if letter == "R":
            set_row(Jn, Wn[:, i], i, 0.0)
            set_row(Jt, Wt[:, i], i, 0.0)
            c_n[i] = rng.uniform(0.5, 2.0)
            c_t[i] = mu[i] * c_n[i] * rng.uniform(-0.8, 0.8)
        elif letter == "S":
            set_row(Jn, Wn[:, i], i, 0.0)
            slip = rng.choice([-1.0, 1.0]) * rng.uniform(0.2, 1.0)
            set_row(Jt, Wt[:, i], i, slip)
            c_n[i] = rng.uniform(0.5, 2.0)
            c_t[i] = -mu[i] * np.sign(slip) * c_n[i]
        else:
            set_row(Jn, Wn[:, i], i, rng.uniform(0.2, 1.0))
    g_obj = -(Wn @ c_n + Wt @ c_t)
    g_man = rng.normal(size=n_j) * 0.1
    tau = Jn.T @ c_n + Jt.T @ c_t + g_man
    scene = make_scene(
        Wn, Wt, Jn, Jt, mu, g_obj, g_man=g_man, effort_controlled=effort,
        joint_velocity=np.where(effort, np.nan, thetadot), joint_effort=np.where(effort, tau, np.nan),
    )  # fmt: skip
    return scene, mode
