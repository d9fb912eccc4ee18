"""Many contact modes at every state of a batch at once (eqs. 23-28, Section 5.2).

A robust band judges every competitor of the desired mode at every state: the kinematic stage
of each mode (eqs. 23-25, 16) and the rows of eq. (28) at each competitor's friction points.
Mode by mode that is one small numpy call after another; here the same work is one call over
all (mode, state) pairs:

* :func:`modes_kinematics` runs the solver's own kinematic stage
  (:func:`qsplan.mechanics.modes.kinematics.kinematic_tests`) once on a row pool whose rows are
  the pairs, each pair's ``P_AI`` rows gathered in its mode's order;
* :func:`batch_rows_many` factorises the ``Q_AI`` of eq. (26) of many (batch, mode, friction
  points) jobs in one ``det`` and one ``solve`` (:func:`qsplan.mechanics.bands.batched.batch_rows`
  is its one-job case).

Every matrix meets the same LAPACK call and every row the same floating-point operations as
mode by mode, so the results are bit-identical (``tests/mechanics/test_bands_batched.py``,
``tests/mechanics/test_bands_batched_arrays.py``); a matrix that several friction points share
(equal at the mode's sliding contacts) is factorised once.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qsplan.mechanics.bands.disturbance import load_columns
from qsplan.mechanics.bands.effort import coulomb_columns, coulomb_rows, row_margins
from qsplan.mechanics.modes.contact_mode import ContactMode, letters_to_codes
from qsplan.mechanics.modes.equilibrium import equilibrium_columns
from qsplan.mechanics.modes.kinematics import applicable_rows, check_mode_fits, kinematic_tests, sliding_directions
from qsplan.mechanics.numerics import DEFAULT_TOLERANCES, Status, StatusCode, Tolerances, singular_matrices

__all__ = ["BatchKinematics", "PairRows", "batch_equations", "batch_kinematics", "batch_rows_many", "modes_kinematics"]


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

    def take(self, rows) -> "BatchKinematics":
        """The stage at the states ``rows`` (array of int) only."""
        return BatchKinematics(self.mode, self.idx, self.contact, self.slide, self.status[rows], self.xi[rows])


@dataclass(frozen=True, slots=True, eq=False)
class PairRows:
    """A row pool (:class:`qsplan.mechanics.modes.kinematics.ScenePool`'s attributes) over ``m S`` (mode, state)
    pairs, mode-major: the rows of ``P_AI`` already gathered in each pair's mode order (so the applicable rows are
    ``0..k-1`` for every pair), the contact rows ``Wrows``, ``Jrows`` as the state has them (eq. 5).

    Attributes
    ----------
    E, V : ndarray of int
    M : ndarray, shape (m S, k, 3 + n_e)
    log_row_norm, drive : ndarray, shape (m S, k)
    Wrows : ndarray, shape (m S, 2 n_c, 3)
    Jrows : ndarray, shape (m S, 2 n_c, n_j)
    velocity : ndarray, shape (m S, n_j)
    """

    E: np.ndarray
    V: np.ndarray
    M: np.ndarray
    log_row_norm: np.ndarray
    drive: np.ndarray
    Wrows: np.ndarray
    Jrows: np.ndarray
    velocity: np.ndarray


def _pairs(a, m):
    """``a`` (S, ...) repeated for ``m`` modes, mode-major: (m S, ...)."""
    return np.broadcast_to(a, (m,) + a.shape).reshape((m * a.shape[0],) + a.shape[1:])


def modes_kinematics(batch, modes, tol: Tolerances = DEFAULT_TOLERANCES) -> dict:
    """The kinematic stage (eqs. 23-25, 16) of every mode of ``modes`` at every state of ``batch``: one call of
    :func:`qsplan.mechanics.modes.kinematics.kinematic_tests` over the (mode, state) pairs (:class:`PairRows`).

    Parameters
    ----------
    batch : StateBatch
    modes : sequence of ContactMode or str
        Each fitting the batch's scenes (one letter per contact, eq. 29).

    Returns
    -------
    dict of str to BatchKinematics
        In the order of ``modes``; each the arrays :func:`batch_kinematics` gives for the mode alone.
    """
    scene0 = batch.scenes[0]
    modes = [check_mode_fits(scene0, m) for m in modes]
    if not modes:
        return {}
    codes = np.stack([letters_to_codes(m.letters) for m in modes])  # (m, n_c)
    idx, contact, slide = applicable_rows(scene0, codes)  # (m, k): every mode has k = dof rows (eq. 29)
    m, S, k = len(modes), batch.size, idx.shape[1]
    rows = (np.arange(S)[None, :, None] * batch.M.shape[1] + idx[:, None, :]).reshape(-1)  # into (S 2 n_c) rows

    def gathered(a):  # (S, 2 n_c, ...) -> (m S, k, ...): each pair's rows in its mode's order
        return a.reshape((-1,) + a.shape[2:]).take(rows, axis=0).reshape((m * S, k) + a.shape[2:])

    pool = PairRows(batch.E, batch.V, gathered(batch.M), gathered(batch.log_row_norm), gathered(batch.drive),
                    _pairs(batch.Wrows, m), _pairs(batch.Jrows, m), _pairs(batch.velocity, m))  # fmt: skip
    pair_codes = np.repeat(codes, S, axis=0)
    status, _, _, v_t = kinematic_tests(pool, np.arange(k), pair_codes, tol, _pairs(batch.vtol, m)[:, None])
    xi = sliding_directions(pair_codes, v_t, status == StatusCode.FEASIBLE).reshape(m, S, -1)
    status = status.reshape(m, S)
    return {mode.letters: BatchKinematics(mode, idx[j], contact[j], slide[j], status[j], xi[j]) for j, mode in enumerate(modes)}


def batch_kinematics(batch, mode, tol: Tolerances = DEFAULT_TOLERANCES) -> BatchKinematics:
    """:func:`qsplan.mechanics.modes.kinematics.kinematics_stage` of one mode at every state."""
    mode = check_mode_fits(batch.scenes[0], mode)
    return modes_kinematics(batch, [mode], tol)[mode.letters]


def batch_equations(batch, bk, mu_rows):
    """``Q_AI`` of eq. (26) at every state and friction point: ``(Q (S, N, k, k), mu (S, N, n_c))``.

    ``mu_rows``: shape (N, n_c), the same for every state, or (S, N, n_c)."""
    mu = np.asarray(mu_rows, dtype=float)
    mu = np.broadcast_to(mu, (batch.size,) + mu.shape[-2:]) if mu.ndim == 2 else mu
    Q = equilibrium_columns(batch.Wrows[:, None], batch.Jrows[:, None], batch.E, bk.idx, bk.contact, bk.slide,
                            mu, bk.xi[:, None, :])  # fmt: skip
    return Q, mu


def _distinct_points(bk: BatchKinematics, mu):
    """The friction points (N, n_c) at which ``Q_AI`` differs: ``(points (U, n_c), inverse (N,))``.  ``Q_AI`` depends on
    friction only at the mode's sliding contacts (eqs. 18-20); points equal there, bit for bit, share one matrix."""
    cols = np.unique(bk.contact[bk.slide])
    keys = np.ascontiguousarray(mu[:, cols]).view(np.int64)  # a point's bits there (a few dozen points: a dict)
    first, inverse = {}, np.empty(len(mu), dtype=np.intp)
    for n, key in enumerate(map(bytes, keys)):
        inverse[n] = first.setdefault(key, len(first))
    index = np.zeros(len(first), dtype=np.intp)
    index[inverse[::-1]] = np.arange(len(mu))[::-1]  # each distinct point's first occurrence
    return mu[index], inverse


def batch_rows_many(jobs, force_margin=None, loads: bool = False) -> list:
    """:func:`qsplan.mechanics.bands.batched.batch_rows` of every job ``(batch, bk, mu_rows)``, one ``det`` and one
    ``solve`` for all (every batch with the same joints, so ``Q_AI`` is k x k throughout).  Friction points shared by
    the states and equal at the mode's sliding contacts share their matrix (a rolling contact's friction enters its
    Coulomb rows only, eq. 28): it is factorised once.

    ``loads``: also each job's slopes in an extra wrench on the workpiece, ``s2`` (S, N, r, 3), as
    :func:`qsplan.mechanics.bands.effort.band_rows` gives them (the same right-hand sides, :func:`load_columns`).

    Returns
    -------
    list of (s0, s1, det, scale) or, with ``loads``, (s0, s1, det, scale, s2)
        Per job, shapes (S, N, r), (S, N, r), (S, N), (S, N), as ``batch_rows`` returns them.
    """
    eqs, inverses = [], []
    for b, bk, mu in jobs:
        mu = np.asarray(mu, dtype=float)
        inverse = None
        if mu.ndim == 2:
            points, inverse = _distinct_points(bk, mu)
            eqs.append((batch_equations(b, bk, points)[0], np.broadcast_to(mu, (b.size,) + mu.shape)))
        else:
            eqs.append(batch_equations(b, bk, mu))
        inverses.append(inverse)
    k = eqs[0][0].shape[-1]
    # Q_AI comes transposed in memory (equilibrium_columns builds its columns as rows): stacked so, a plain copy
    Q = np.concatenate([q.swapaxes(-1, -2).reshape(-1, k, k) for q, _ in eqs]).swapaxes(-1, -2)
    det = np.linalg.det(Q)
    bad = singular_matrices(Q, det)  # as band_rows: a det within rounding of 0 has no sign
    det = np.where(bad & np.isfinite(det), 0.0, det)
    Q[bad] = np.eye(k)  # a singular Q_AI: any solve, its rows are NaN below
    n = 5 if loads else 2
    rhs = np.concatenate([np.broadcast_to(load_columns(b.r0, loads)[:, None], q.shape[:2] + (k, n)).reshape(-1, k, n)
                          for (b, _, _), (q, _) in zip(jobs, eqs)])  # fmt: skip
    sol = np.linalg.solve(Q, rhs)
    out, at = [], 0
    for (b, bk, _), (q, mu), inverse in zip(jobs, eqs, inverses):
        S, U = q.shape[:2]
        part = slice(at, at + S * U)
        at += S * U
        sol_j, bad_j, det_j = sol[part].reshape(S, U, k, n), bad[part].reshape(S, U), det[part].reshape(S, U)
        if inverse is not None:
            sol_j, bad_j, det_j = sol_j[:, inverse], bad_j[:, inverse], det_j[:, inverse]
        if loads:
            rows = coulomb_columns(bk.mode, bk.idx, bk.contact, mu, sol_j)
            s0, s1, s2 = rows[..., 0], rows[..., 1], rows[..., 2:]
            s2[bad_j] = np.nan
        else:
            s0, s1 = coulomb_rows(bk.mode, bk.idx, bk.contact, mu, sol_j)
        largest = np.abs(sol_j[..., 0, 0])  # the largest |c_A| at zero effort, folded over the k rows (a short axis)
        for i in range(1, k):
            largest = np.maximum(largest, np.abs(sol_j[..., i, 0]))
        scale = np.maximum(largest, np.max(np.abs(b.r0), axis=1)[:, None])
        if force_margin is not None:
            s0 = s0 - row_margins(bk.mode, force_margin)
        s0[bad_j] = np.nan
        s1[bad_j] = np.nan
        out.append((s0, s1, det_j, scale, s2) if loads else (s0, s1, det_j, scale))
    return out
