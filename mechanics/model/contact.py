"""Contact frames and wrench matrices (Section 3, eq. 1).

Conventions (the paper's): the normal ``n`` of contact *i* points **into the
workpiece**, the tangent is ``t = n`` rotated by +90 degrees, so ``n x t``
points out of the plane, and the wrench matrix of a contact at ``r`` (world
frame, about the world origin) is

    W_i = [[n, t], [r (x) n, r (x) t]]            (3, 2)

with the planar cross product ``a (x) b = a_x b_y - a_y b_x``.
"""

from __future__ import annotations

import numpy as np

from qsplan.mechanics.errors import SceneError

__all__ = [
    "cross2",
    "tangent_from_normal",
    "wrench_matrix",
    "wrench_matrices",
    "shift_wrenches",
    "point_wrench",
    "NORMAL_LENGTH_TOL",
    "FRAME_TOL",
    "check_contact_frame",
]

#: A contact normal shorter than this (m, or unitless) is rejected as "zero":
#: normalising it would amplify rounding noise into an arbitrary direction.
NORMAL_LENGTH_TOL = 1e-12

#: Tolerance (unitless) of the contact-frame check on raw wrench columns: ``|n|`` within this of 1
#: and ``t`` within this of ``n`` turned by +90 degrees.  The paper prints its wrenches to three
#: significant digits, which leaves unit vectors off by up to 3e-4 (0.707, 0.707 has length
#: 0.99985); 2e-3 accepts those and refuses real mistakes (a non-unit normal, ``wt`` equal to
#: ``wn``, a tangent of the wrong sense).
FRAME_TOL = 2e-3


def cross2(a, b):
    """Planar cross product ``a (x) b = a_x b_y - a_y b_x`` (eq. 1).

    Parameters
    ----------
    a, b : array-like, shape (..., 2)

    Returns
    -------
    ndarray, shape (...)
    """
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def tangent_from_normal(n):
    """Tangent ``t`` = ``n`` rotated by +90 degrees.

    Parameters
    ----------
    n : array-like, shape (..., 2)

    Returns
    -------
    t : ndarray, shape (..., 2)
    """
    n = np.asarray(n, dtype=float)
    return np.stack([-n[..., 1], n[..., 0]], axis=-1)


def _unit_normals(n):
    n = np.asarray(n, dtype=float)
    length = np.linalg.norm(n, axis=-1)
    ok = np.isfinite(length) & (length >= NORMAL_LENGTH_TOL)
    if not np.all(ok):
        bad = int(np.flatnonzero(~ok.reshape(-1))[0])
        raise SceneError(f"contacts[{bad}].n: normal must be a finite nonzero 2-vector; got {n.reshape(-1, 2)[bad].tolist()}")
    return n / length[..., None]


def check_contact_frame(wn, wt, field: str = "contact") -> np.ndarray:
    """Check raw wrench columns as one contact frame (eq. 1); return the contact point ``r``.

    ``wn = [n, r (x) n]`` and ``wt = [t, r (x) t]`` need a unit ``n`` and ``t = n`` turned by
    +90 degrees (within :data:`FRAME_TOL`).  The two moments then always fix exactly one point:
    ``r (x) n = wn[2]`` and ``r (x) t = r . n = wt[2]`` give ``r = wt[2] n - wn[2] t`` (the 2x2
    system has determinant ``n (x) t = 1``), so the moment parts are consistent with a contact
    point as soon as the force parts are a frame; ``r`` is returned for the caller's range checks.

    Parameters
    ----------
    wn, wt : array-like, shape (3,)
        Normal and tangential wrench columns about the world origin.
    field : str
        Names the contact in errors (``"contacts[2]"``).

    Returns
    -------
    r : ndarray, shape (2,)
        The contact point (m) the moments imply.

    Raises
    ------
    SceneError
        A force part that is not a unit vector, or a tangent that is not the normal's +90 degree turn.
    """
    wn = np.asarray(wn, dtype=float)
    wt = np.asarray(wt, dtype=float)
    n, t = wn[:2], wt[:2]
    length = float(np.hypot(*n))
    if not abs(length - 1.0) <= FRAME_TOL:
        raise SceneError(f"{field}.wn: the force part (first two numbers) {n.tolist()} has length {length:.6g}; "
                         f"expected a unit normal (length 1 within {FRAME_TOL:g})")  # fmt: skip
    turned = tangent_from_normal(n)
    if not float(np.hypot(*(t - turned))) <= FRAME_TOL:
        raise SceneError(f"{field}.wt: the force part (first two numbers) {t.tolist()} is not the normal turned by "
                         f"+90 degrees, {turned.tolist()} (within {FRAME_TOL:g})")  # fmt: skip
    return wt[2] * n - wn[2] * t


def wrench_matrix(r, n):
    """Wrench matrix ``W_i`` of one contact (eq. 1).

    Parameters
    ----------
    r : array-like, shape (2,)
        Contact point in the world frame (m).
    n : array-like, shape (2,)
        Inward normal (into the workpiece); normalised here.

    Returns
    -------
    W : ndarray, shape (3, 2)
        Columns ``w_n`` and ``w_t``; rows force x, force y, moment about the world origin.
    """
    wn, wt = wrench_matrices(np.reshape(r, (1, 2)), np.reshape(n, (1, 2)))
    return np.column_stack([wn[:, 0], wt[:, 0]])


def wrench_matrices(r, n):
    """Normal and tangential wrench matrices ``W_n``, ``W_t`` of all contacts (eqs. 1-2).

    Parameters
    ----------
    r : array-like, shape (n_c, 2)
        Contact points, world frame (m).
    n : array-like, shape (n_c, 2)
        Inward normals; each is normalised.

    Returns
    -------
    Wn, Wt : ndarray, shape (3, n_c)
    """
    r = np.asarray(r, dtype=float).reshape(-1, 2)
    n = _unit_normals(np.asarray(n, dtype=float).reshape(-1, 2))
    t = tangent_from_normal(n)
    Wn = np.vstack([n.T, cross2(r, n)])
    Wt = np.vstack([t.T, cross2(r, t)])
    return Wn, Wt


def shift_wrenches(W, origin):
    """Re-express wrenches about a new world origin.

    A wrench ``[f; m]`` about the old origin is ``[f; m - origin (x) f]`` about
    ``origin`` (given in old coordinates).  Works for wrench matrices and for
    ``g_obj``.

    Parameters
    ----------
    W : array-like, shape (3, ...) 
    origin : array-like, shape (2,)

    Returns
    -------
    ndarray, same shape as ``W``
    """
    W = np.array(W, dtype=float, copy=True)
    ox, oy = np.asarray(origin, dtype=float)
    W[2] = W[2] - (ox * W[1] - oy * W[0])
    return W


def point_wrench(point, force):
    """Wrench ``[f; p (x) f]`` of a force applied at a point, about the world origin.

    Parameters
    ----------
    point : array-like, shape (2,)
    force : array-like, shape (2,)

    Returns
    -------
    ndarray, shape (3,)
    """
    f = np.asarray(force, dtype=float)
    return np.array([f[0], f[1], float(cross2(point, f))])
