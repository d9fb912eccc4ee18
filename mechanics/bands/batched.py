"""Effort bands for a batch of states at once (eqs. 23-28, Section 5.2).

A *state batch* is a list of scenes with the same contacts count, joints and effort-controlled
joint (the samples of a segment, or unrelated scenes of one shape).  For one mode, the
kinematic stage (eqs. 23-25, 16), the equilibrium matrices ``Q_AI`` at many friction points
(eq. 26) and the Coulomb rows (eq. 28) of every state are computed with a few numpy calls on
stacked arrays, instead of a few hundred per state.  Results are bit-identical to the
per-state reference (:mod:`qsplan.mechanics.bands.effort`, :mod:`.guaranteed`): the same
floating-point operations on the same numbers, the same LAPACK calls per matrix (one ``det``
and one ``solve``), and the rows assembled by the same function
(:func:`qsplan.mechanics.bands.effort.coulomb_rows`); ``tests/mechanics/test_bands_batched.py``
compares them on hundreds of states.

Nothing of eqs. (23)-(26) is restated here: a :class:`StateBatch` holds the rows of
:class:`qsplan.mechanics.modes.kinematics.ScenePool` with a leading state axis, and the
kinematic stage (:func:`qsplan.mechanics.modes.kinematics.kinematic_tests`) and ``Q_AI``
(:func:`qsplan.mechanics.modes.equilibrium.equilibrium_columns`) are the solver's own
functions, which serve modes of one scene and states of a batch alike.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qsplan.mechanics.bands.effort import Band, check_force_margin, check_one_effort_joint, coulomb_rows, intersect_rows, row_margins
from qsplan.mechanics.bands.guaranteed import shared_band_from_rows, shared_nodes
from qsplan.mechanics.errors import SceneError
from qsplan.mechanics.model.friction import check_mu_range
from qsplan.mechanics.modes.contact_mode import ContactMode, letters_to_codes
from qsplan.mechanics.modes.equilibrium import equilibrium_columns
from qsplan.mechanics.modes.kinematics import applicable_rows, check_mode_fits, kinematic_tests, kinematics_rows, sliding_directions
from qsplan.mechanics.numerics import DEFAULT_TOLERANCES, Status, StatusCode, Tolerances

__all__ = [
    "StateBatch",
    "BatchKinematics",
    "state_batch",
    "take_states",
    "batch_signature",
    "map_batches",
    "effort_bands_batch",
    "batch_kinematics",
    "batch_rows",
    "point_bands_batch",
    "guaranteed_bands_box",
    "guaranteed_bands_shared",
]


def batch_signature(scene) -> tuple:
    """What scenes of one batch share: contacts count and which joints are effort-controlled."""
    return (scene.n_contacts, scene.effort_controlled.tobytes())


def map_batches(scenes, per_batch) -> list:
    """``per_batch(batch)`` (a list, one item per state) on the scenes grouped by :func:`batch_signature`,
    as one list in the order of ``scenes``."""
    scenes = tuple(scenes)
    groups = {}
    for k, s in enumerate(scenes):
        groups.setdefault(batch_signature(s), []).append(k)
    out = [None] * len(scenes)
    for rows in groups.values():
        for k, item in zip(rows, per_batch(state_batch([scenes[k] for k in rows]))):
            out[k] = item
    return out


@dataclass(frozen=True, slots=True, eq=False)
class StateBatch:
    """Per-state arrays of ``S`` scenes of one shape (:func:`batch_signature`).

    Attributes
    ----------
    scenes : tuple of Scene
    joint : int
        The effort-controlled joint.
    E, V : ndarray of int
        Effort- and velocity-controlled joints.
    Wrows : ndarray, shape (S, 2 n_c, 3)
        ``[W_n^T; W_t^T]`` of each state (the per-scene ``ScenePool.Wrows``).
    Jrows : ndarray, shape (S, 2 n_c, n_j)
    M : ndarray, shape (S, 2 n_c, 4)
        The rows ``P_AI`` gathers from (eq. 23, :func:`~qsplan.mechanics.modes.kinematics.kinematics_rows`).
    log_row_norm : ndarray, shape (S, 2 n_c)
        Log norms of the rows of ``P_AI`` (eq. 23).
    drive : ndarray, shape (S, 2 n_c)
        ``J thetadot_V`` (m/s), the right-hand side of eq. (24).
    vtol : ndarray, shape (S,)
        Velocity tolerance (m/s): ``tol.velocity`` times the largest driving speed (1 if none).
    r0 : ndarray, shape (S, 4)
        ``[-g_obj; -g_man_E]`` (N, N m), the right-hand side of eq. (26) at zero effort.
    velocity : ndarray, shape (S, n_j)
        Joint velocities (rad/s or m/s; those of effort-controlled joints unused).
    """

    scenes: tuple
    joint: int
    E: np.ndarray
    V: np.ndarray
    Wrows: np.ndarray
    Jrows: np.ndarray
    M: np.ndarray
    log_row_norm: np.ndarray
    drive: np.ndarray
    vtol: np.ndarray
    r0: np.ndarray
    velocity: np.ndarray

    @property
    def size(self) -> int:
        return len(self.scenes)

    @property
    def n_c(self) -> int:
        return self.Wrows.shape[1] // 2


def state_batch(scenes, tol: Tolerances = DEFAULT_TOLERANCES) -> StateBatch:
    """Stack ``scenes`` (a non-empty sequence of one :func:`batch_signature`, one effort-controlled joint)."""
    scenes = tuple(scenes)
    if not scenes:
        raise SceneError("states: expected at least one scene; got none")
    sig = batch_signature(scenes[0])
    for k, s in enumerate(scenes):
        if batch_signature(s) != sig:
            raise SceneError(f"states: scene {k} has {s.n_contacts} contacts and effort-controlled joints "
                             f"{s.effort_joints.tolist()}; expected those of scene 0")  # fmt: skip
    joint = check_one_effort_joint(scenes[0])
    E, V = scenes[0].effort_joints, scenes[0].velocity_joints
    stack = lambda name: np.stack([getattr(s, name) for s in scenes])  # noqa: E731
    Wrows = np.concatenate([stack("Wn"), stack("Wt")], axis=2).transpose(0, 2, 1)
    Jrows = np.concatenate([stack("Jn"), stack("Jt")], axis=1)
    velocity = stack("joint_velocity")
    M, log_row_norm, drive = kinematics_rows(Wrows, Jrows, velocity, E, V)
    speed = np.max(np.abs(drive), axis=1) if drive.shape[1] else np.zeros(len(scenes))
    vtol = tol.velocity * np.where(speed > 0, speed, 1.0)
    r0 = np.concatenate([-stack("g_obj"), -stack("g_man")[:, E]], axis=1)
    return StateBatch(scenes, joint, E, V, Wrows, Jrows, M, log_row_norm, drive, vtol, r0, velocity)


def take_states(batch: StateBatch, rows) -> StateBatch:
    """The states ``rows`` (array of int) of a batch, as a batch (itself when ``rows`` is all of them in order)."""
    rows = np.asarray(rows)
    if rows.size == batch.size and np.array_equal(rows, np.arange(batch.size)):
        return batch
    return StateBatch(tuple(batch.scenes[s] for s in rows), batch.joint, batch.E, batch.V, batch.Wrows[rows], batch.Jrows[rows],
                      batch.M[rows], batch.log_row_norm[rows], batch.drive[rows], batch.vtol[rows], batch.r0[rows],
                      batch.velocity[rows])  # fmt: skip


@dataclass(frozen=True, slots=True, eq=False)
class BatchKinematics:
    """One mode's kinematic stage (eqs. 24-25, 16) at every state of a batch.

    Attributes
    ----------
    mode : ContactMode
    idx, contact : ndarray of int, shape (k,)
        Applicable rows and their contacts (the same at every state).
    slide : ndarray of bool, shape (k,)
    status : ndarray of int8, shape (S,)
        ``Status.ORDER`` codes; 0 where the mode passed.
    xi : ndarray, shape (S, n_c)
        Sliding directions (eq. 16), 0 at rolling and breaking contacts.
    """

    mode: ContactMode
    idx: np.ndarray
    contact: np.ndarray
    slide: np.ndarray
    status: np.ndarray
    xi: np.ndarray

    @property
    def ok(self) -> np.ndarray:
        """(S,) of bool: the mode passed the kinematic stage."""
        return self.status == StatusCode.FEASIBLE

    def status_name(self, s: int) -> str:
        return Status.ORDER[int(self.status[s])]


def batch_kinematics(batch: StateBatch, mode, tol: Tolerances = DEFAULT_TOLERANCES) -> BatchKinematics:
    """:func:`qsplan.mechanics.modes.kinematics.kinematics_stage` of one mode at every state."""
    mode = check_mode_fits(batch.scenes[0], mode)
    codes = letters_to_codes(mode.letters)
    idx, contact, slide = (a[0] for a in applicable_rows(batch.scenes[0], codes[None, :]))
    status, _, _, v_t = kinematic_tests(batch, idx, codes, tol, batch.vtol[:, None])
    xi = sliding_directions(codes, v_t, status == StatusCode.FEASIBLE)
    return BatchKinematics(mode, idx, contact, slide, status, xi)


def batch_rows(batch: StateBatch, bk: BatchKinematics, mu_rows, force_margin=None):
    """:func:`qsplan.mechanics.bands.effort.band_rows` at every state: the rows ``s0 + tau s1`` of eq. (28).

    Parameters
    ----------
    mu_rows : array-like, shape (N, n_c) or (S, N, n_c)
        Friction points, the same for every state or one set per state.
    force_margin : ForceMargin, optional

    Returns
    -------
    s0, s1 : ndarray, shape (S, N, r)
        NaN where ``Q_AI`` is singular; meaningless at states where ``bk.ok`` is False.
    det, scale : ndarray, shape (S, N)
    """
    S = batch.size
    mu = np.asarray(mu_rows, dtype=float)
    mu = np.broadcast_to(mu, (S,) + mu.shape[-2:]) if mu.ndim == 2 else mu
    N = mu.shape[1]
    # Q_AI of eq. (26), (S, N, k, k): the solver's function with the rows of each state
    Q = equilibrium_columns(batch.Wrows[:, None], batch.Jrows[:, None], batch.E, bk.idx, bk.contact, bk.slide,
                            mu, bk.xi[:, None, :])  # fmt: skip
    det = np.linalg.det(Q)
    k = Q.shape[-1]
    e = np.zeros(k)
    e[3] = 1.0
    bad = ~np.isfinite(det) | (det == 0)
    Qs = Q.copy()
    Qs[bad] = np.eye(k)
    rhs = np.broadcast_to(np.stack([batch.r0, np.broadcast_to(e, batch.r0.shape)], axis=2)[:, None], (S, N, k, 2))
    sol = np.linalg.solve(Qs, rhs)
    s0, s1 = coulomb_rows(bk.mode, bk.idx, bk.contact, mu, sol)
    scale = np.maximum(np.max(np.abs(sol[..., 0]), axis=2), np.max(np.abs(batch.r0), axis=1)[:, None])
    if force_margin is not None:
        s0 = s0 - row_margins(bk.mode, force_margin)
    s0[bad] = np.nan
    s1[bad] = np.nan
    return s0, s1, det, scale


def _intersect(s0, s1, scale, tol):
    S, N, r = s0.shape
    lower, upper, ok = intersect_rows(s0.reshape(S * N, r), s1.reshape(S * N, r), scale.reshape(S * N), tol)
    return lower.reshape(S, N), upper.reshape(S, N), ok.reshape(S, N)


def effort_bands_batch(batch: StateBatch, mode, mu_rows, tol: Tolerances = DEFAULT_TOLERANCES, *, force_margin=None):
    """:func:`qsplan.mechanics.bands.effort.effort_bands` at every state: lower, upper, ok, each (S, N).

    ``mu_rows`` (N, n_c) or (S, N, n_c); NaN edges and ``ok`` False where the kinematics fail.
    """
    force_margin = None if force_margin is None else check_force_margin(force_margin)
    bk = batch_kinematics(batch, mode, tol)
    s0, s1, _, scale = batch_rows(batch, bk, mu_rows, force_margin)
    lower, upper, ok = _intersect(s0, s1, scale, tol)
    fail = ~bk.ok
    lower[fail], upper[fail], ok[fail] = np.nan, np.nan, False
    return lower, upper, ok


def point_bands_batch(batch: StateBatch, mode, mu, tol: Tolerances = DEFAULT_TOLERANCES, *, force_margin=None,
                      method: str = "point") -> list:  # fmt: skip
    """:func:`qsplan.mechanics.bands.effort.effort_band` at every state, friction ``mu`` (n_c,) or (S, n_c)."""
    force_margin = None if force_margin is None else check_force_margin(force_margin)
    bk = batch_kinematics(batch, mode, tol)
    mu = np.broadcast_to(np.asarray(mu, dtype=float), (batch.size, batch.n_c))
    s0, s1, _, scale = batch_rows(batch, bk, mu[:, None, :], force_margin)
    lower, upper, ok = _intersect(s0, s1, scale, tol)
    finite = np.all(np.isfinite(s0[:, 0]), axis=1)
    letters, joint, out, kin_ok = bk.mode.letters, batch.joint, [], bk.ok
    for s in range(batch.size):
        if not kin_ok[s]:
            out.append(Band(letters, joint, np.nan, np.nan, False, f"kinematics: {bk.status_name(s)}", method))
        elif not finite[s]:
            out.append(Band(letters, joint, np.nan, np.nan, False, "equilibrium_singular", method))
        elif not ok[s, 0]:
            out.append(Band(letters, joint, np.nan, np.nan, False, "coulomb: no effort satisfies eq. (28)", method))
        else:
            out.append(Band(letters, joint, float(lower[s, 0]), float(upper[s, 0]), True, None, method))
    return out


def box_vertices(mode: ContactMode, lo, hi) -> np.ndarray:
    """The vertices of the friction box over the contacts that are not breaking, in
    :func:`qsplan.mechanics.bands.guaranteed.guaranteed_band_box`'s order, shape (2^m, n_c)."""
    free = [c for c in range(lo.size) if mode.letters[c] != "B" and hi[c] > lo[c]]
    bits = (np.arange(2 ** len(free))[:, None] >> np.arange(len(free))[::-1][None]) & 1  # itertools.product order
    verts = np.tile(lo, (2 ** len(free), 1))
    verts[:, free] = np.where(bits.astype(bool), hi[free], lo[free])
    return verts


def guaranteed_bands_box(batch: StateBatch, mode, lo, hi, tol: Tolerances = DEFAULT_TOLERANCES, *,
                         force_margin=None) -> list:  # fmt: skip
    """:func:`qsplan.mechanics.bands.guaranteed.guaranteed_band_box` at every state (vertex method, exact)."""
    force_margin = None if force_margin is None else check_force_margin(force_margin)
    lo, hi = check_mu_range(lo, hi, n=batch.n_c)
    bk = batch_kinematics(batch, mode, tol)
    s0, s1, det, scale = batch_rows(batch, bk, box_vertices(bk.mode, lo, hi), force_margin)
    steady = np.all(det > 0, axis=1) | np.all(det < 0, axis=1)
    lower, upper, ok = _intersect(s0, s1, scale, tol)
    lo_, up_ = lower.max(axis=1), upper.min(axis=1)
    letters, joint, out, m, kin_ok = bk.mode.letters, batch.joint, [], "box-vertices", bk.ok
    for s in range(batch.size):
        if not kin_ok[s]:
            out.append(Band(letters, joint, np.nan, np.nan, False, f"kinematics: {bk.status_name(s)}", m))
        elif not steady[s]:
            out.append(Band(letters, joint, np.nan, np.nan, False,
                            "equilibrium_singular: det Q_AI changes sign inside the mu box (the mode is degenerate there)", m))  # fmt: skip
        elif not ok[s].all():
            out.append(Band(letters, joint, np.nan, np.nan, False, "coulomb: no effort works at some vertex of the mu box", m))
        elif lo_[s] > up_[s]:
            out.append(Band(letters, joint, np.nan, np.nan, False, "coulomb: vertex bands do not overlap", m))
        else:
            out.append(Band(letters, joint, float(lo_[s]), float(up_[s]), True, None, m))
    return out


def guaranteed_bands_shared(batch: StateBatch, mode, lo: float, hi: float, tol: Tolerances = DEFAULT_TOLERANCES, *,
                            force_margin=None) -> list:  # fmt: skip
    """:func:`qsplan.mechanics.bands.guaranteed.guaranteed_band_shared` at every state (polynomial roots, exact).

    The rows at the Chebyshev nodes are batched; the roots of each state's polynomials are found
    by the reference's own function (:func:`qsplan.mechanics.bands.guaranteed.shared_band_from_rows`).
    """
    force_margin = None if force_margin is None else check_force_margin(force_margin)
    lo, hi = check_mu_range(lo, hi)
    if hi == lo:
        return point_bands_batch(batch, mode, np.full(batch.n_c, lo), tol, force_margin=force_margin, method="shared-roots")
    bk = batch_kinematics(batch, mode, tol)
    nodes = shared_nodes(bk.mode, lo, hi)
    s0, s1, det, scale = batch_rows(batch, bk, np.repeat(nodes[:, None], batch.n_c, axis=1), force_margin)
    letters, joint, out, kin_ok = bk.mode.letters, batch.joint, [], bk.ok
    for s in range(batch.size):
        if not kin_ok[s]:
            out.append(Band(letters, joint, np.nan, np.nan, False, f"kinematics: {bk.status_name(s)}", "shared-roots"))
        else:
            out.append(shared_band_from_rows(bk.mode, joint, nodes, s0[s], s1[s], det[s], scale[s], lo, hi, tol))
    return out
