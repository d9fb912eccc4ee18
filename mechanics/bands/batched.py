"""Effort bands for a batch of states at once (eqs. 23-28, Section 5.2).

A *state batch* is a list of scenes with the same contacts count, joints and effort-controlled
joint (the samples of a segment, or unrelated scenes of one shape).  For one mode, the
kinematic stage (eqs. 23-25, 16), the equilibrium matrices ``Q_AI`` at many friction points
(eq. 26) and the Coulomb rows (eq. 28) of every state are computed with a few numpy calls on
stacked arrays, instead of a few hundred per state.  Results are bit-identical to the
per-state reference (:mod:`qsplan.mechanics.bands.effort`, :mod:`.guaranteed`): the same
floating-point operations on the same numbers, the same LAPACK calls per matrix (one ``det``
and one ``solve`` per distinct ``Q_AI``), and the rows assembled by the same function
(:func:`qsplan.mechanics.bands.effort.coulomb_rows`); ``tests/mechanics/test_bands_batched.py``
compares them on hundreds of states.

Nothing of eqs. (23)-(26) is restated here: a :class:`StateBatch` holds the rows of
:class:`qsplan.mechanics.modes.kinematics.ScenePool` with a leading state axis, and the
kinematic stage (:func:`qsplan.mechanics.modes.kinematics.kinematic_tests`) and ``Q_AI``
(:func:`qsplan.mechanics.modes.equilibrium.equilibrium_columns`) are the solver's own
functions, which serve modes of one scene and states of a batch alike
(:mod:`qsplan.mechanics.bands.batched_modes` calls them on many modes at once).  A batch is
built from scenes (:func:`state_batch`) or from their stacked arrays
(:func:`batch_from_arrays`: the band tables, whose scenes are built only where a per-state
search needs one, :class:`LazyScenes`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from qsplan.mechanics.bands.batched_modes import BatchKinematics, batch_kinematics, batch_rows_many
from qsplan.mechanics.bands.disturbance import (
    check_wrench_box,
    loaded_reason,
    worst_over_wrenches,
    wrench_vertex_parts,
    wrench_vertex_rows,
)
from qsplan.mechanics.bands.effort import Band, check_force_margin, check_one_effort_joint, intersect_rows
from qsplan.mechanics.bands.guaranteed import shared_band_from_rows, shared_band_over_wrenches, shared_nodes
from qsplan.mechanics.errors import SceneError
from qsplan.mechanics.model.friction import check_mu_range
from qsplan.mechanics.modes.contact_mode import ContactMode
from qsplan.mechanics.modes.kinematics import kinematics_rows
from qsplan.mechanics.numerics import DEFAULT_TOLERANCES, Tolerances

__all__ = [
    "StateBatch",
    "BatchKinematics",
    "LazyScenes",
    "state_batch",
    "batch_from_arrays",
    "take_states",
    "batch_signature",
    "map_batches",
    "effort_bands_batch",
    "batch_kinematics",
    "batch_rows",
    "point_bands_batch",
    "BOX_REASONS",
    "box_band_arrays",
    "box_bands",
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
    scenes : sequence of Scene
        A tuple, or a :class:`LazyScenes` (built from arrays).
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


class LazyScenes(Sequence):
    """The scenes of a batch built from arrays, each made on first use (:func:`batch_from_arrays`).

    ``build(s)`` returns the :class:`qsplan.mechanics.Scene` of state ``s``; only the per-state searches the
    batched root cell leaves open need one, so most are never built.
    """

    def __init__(self, size: int, build, rows=None):
        self._build = build
        self._rows = np.arange(size) if rows is None else np.asarray(rows)
        self._made = {}

    def __len__(self) -> int:
        return self._rows.size

    def __getitem__(self, s):
        if isinstance(s, slice):
            return self.take(np.arange(len(self))[s])
        s = int(self._rows[s])
        if s not in self._made:
            self._made[s] = self._build(s)
        return self._made[s]

    def take(self, rows) -> "LazyScenes":
        """The scenes ``rows`` (array of int), still built on first use."""
        out = LazyScenes(0, self._build, self._rows[np.asarray(rows, dtype=int)])
        out._made = self._made
        return out


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
    stack = lambda name: np.stack([getattr(s, name) for s in scenes])  # noqa: E731
    return batch_from_arrays(scenes, stack("Wn"), stack("Wt"), stack("Jn"), stack("Jt"), stack("g_obj"), stack("g_man"),
                             stack("joint_velocity"), tol)  # fmt: skip


def batch_from_arrays(scenes, Wn, Wt, Jn, Jt, g_obj, g_man, joint_velocity, tol: Tolerances = DEFAULT_TOLERANCES) -> StateBatch:
    """A :class:`StateBatch` from the stacked arrays of its scenes (what :func:`state_batch` stacks).

    Parameters
    ----------
    scenes : sequence of Scene
        The states' scenes (a :class:`LazyScenes` builds them on use), one :func:`batch_signature`; the
        first one gives the control partition (exactly one effort-controlled joint).
    Wn, Wt : ndarray, shape (S, 3, n_c)
    Jn, Jt : ndarray, shape (S, n_c, n_j)
    g_obj : ndarray, shape (S, 3)
    g_man, joint_velocity : ndarray, shape (S, n_j)
        The scenes' attributes stacked (:class:`qsplan.mechanics.Scene`), equal to ``scenes``' own.
    """
    joint = check_one_effort_joint(scenes[0])
    E, V = scenes[0].effort_joints, scenes[0].velocity_joints
    Wrows = np.concatenate([Wn, Wt], axis=2).transpose(0, 2, 1)
    Jrows = np.concatenate([Jn, Jt], axis=1)
    M, log_row_norm, drive = kinematics_rows(Wrows, Jrows, joint_velocity, E, V)
    speed = np.max(np.abs(drive), axis=1) if drive.shape[1] else np.zeros(len(scenes))
    vtol = tol.velocity * np.where(speed > 0, speed, 1.0)
    r0 = np.concatenate([-g_obj, -g_man[:, E]], axis=1)
    return StateBatch(scenes, joint, E, V, Wrows, Jrows, M, log_row_norm, drive, vtol, r0, joint_velocity)


def take_states(batch: StateBatch, rows) -> StateBatch:
    """The states ``rows`` (array of int) of a batch, as a batch (itself when ``rows`` is all of them in order)."""
    rows = np.asarray(rows)
    if rows.size == batch.size and np.array_equal(rows, np.arange(batch.size)):
        return batch
    scenes = batch.scenes.take(rows) if isinstance(batch.scenes, LazyScenes) else tuple(batch.scenes[s] for s in rows)
    return StateBatch(scenes, batch.joint, batch.E, batch.V, batch.Wrows[rows], batch.Jrows[rows], batch.M[rows],
                      batch.log_row_norm[rows], batch.drive[rows], batch.vtol[rows], batch.r0[rows], batch.velocity[rows])  # fmt: skip


def batch_rows(batch: StateBatch, bk: BatchKinematics, mu_rows, force_margin=None, loads: bool = False):
    """:func:`qsplan.mechanics.bands.effort.band_rows` at every state: the rows ``s0 + tau s1`` of eq. (28).

    Parameters
    ----------
    mu_rows : array-like, shape (N, n_c) or (S, N, n_c)
        Friction points, the same for every state or one set per state.
    force_margin : ForceMargin, optional
    loads : bool
        Also return the slopes in an extra wrench on the workpiece, ``s2`` (S, N, r, 3).

    Returns
    -------
    s0, s1 : ndarray, shape (S, N, r)
        NaN where ``Q_AI`` is singular; meaningless at states where ``bk.ok`` is False.
    det, scale : ndarray, shape (S, N)
    """
    return batch_rows_many([(batch, bk, mu_rows)], force_margin, loads)[0]


def _intersect(s0, s1, scale, tol):
    S, N, r = s0.shape
    lower, upper, ok = intersect_rows(s0.reshape(S * N, r), s1.reshape(S * N, r), scale.reshape(S * N), tol)
    return lower.reshape(S, N), upper.reshape(S, N), ok.reshape(S, N)


def effort_bands_batch(batch: StateBatch, mode, mu_rows, tol: Tolerances = DEFAULT_TOLERANCES, *, force_margin=None,
                       disturbance=None):  # fmt: skip
    """:func:`qsplan.mechanics.bands.effort.effort_bands` at every state: lower, upper, ok, each (S, N).

    ``mu_rows`` (N, n_c) or (S, N, n_c); NaN edges and ``ok`` False where the kinematics fail.
    """
    force_margin = None if force_margin is None else check_force_margin(force_margin)
    box = check_wrench_box(disturbance)
    bk = batch_kinematics(batch, mode, tol)
    rows = batch_rows(batch, bk, mu_rows, force_margin, box is not None)
    s0, s1, _, scale = rows if box is None else wrench_vertex_rows(*rows, box.vertices())
    lower, upper, ok = _intersect(s0, s1, scale, tol)
    if box is not None:
        lower, upper, ok = worst_over_wrenches(lower, upper, ok, len(box.vertices()))
    fail = ~bk.ok
    lower[fail], upper[fail], ok[fail] = np.nan, np.nan, False
    return lower, upper, ok


def point_bands_batch(batch: StateBatch, mode, mu, tol: Tolerances = DEFAULT_TOLERANCES, *, force_margin=None,
                      method: str = "point", bk: BatchKinematics | None = None, disturbance=None) -> list:  # fmt: skip
    """:func:`qsplan.mechanics.bands.effort.effort_band` at every state, friction ``mu`` (n_c,) or (S, n_c)."""
    force_margin = None if force_margin is None else check_force_margin(force_margin)
    box = check_wrench_box(disturbance)
    bk = batch_kinematics(batch, mode, tol) if bk is None else bk
    mu = np.broadcast_to(np.asarray(mu, dtype=float), (batch.size, batch.n_c))
    rows = batch_rows(batch, bk, mu[:, None, :], force_margin, box is not None)
    s0, s1, _, scale = rows if box is None else wrench_vertex_rows(*rows, box.vertices())
    lower, upper, ok = _intersect(s0, s1, scale, tol)
    finite = np.all(np.isfinite(s0), axis=(1, 2))
    if box is not None:
        lower, upper, ok = worst_over_wrenches(lower, upper, ok, s0.shape[1])
    letters, joint, out, kin_ok = bk.mode.letters, batch.joint, [], bk.ok
    for s in range(batch.size):
        if not kin_ok[s]:
            out.append(Band(letters, joint, np.nan, np.nan, False, f"kinematics: {bk.status_name(s)}", method))
        elif not finite[s]:
            out.append(Band(letters, joint, np.nan, np.nan, False, "equilibrium_singular", method))
        elif not ok[s, 0]:
            out.append(Band(letters, joint, np.nan, np.nan, False, loaded_reason("coulomb: no effort satisfies eq. (28)", box), method))
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


#: Why :func:`box_band_arrays` found no band, by its code (0: a band): the reasons of
#: :func:`qsplan.mechanics.bands.guaranteed.guaranteed_band_box` (code 1, the kinematics, names its status).
BOX_REASONS = (None, "kinematics", "equilibrium_singular: det Q_AI changes sign inside the mu box (the mode is degenerate there)",
               "coulomb: no effort works at some vertex of the mu box", "coulomb: vertex bands do not overlap")  # fmt: skip


def box_band_arrays(batch: StateBatch, bk: BatchKinematics, lo, hi, tol: Tolerances = DEFAULT_TOLERANCES, force_margin=None,
                    disturbance=None):  # fmt: skip
    """:func:`guaranteed_bands_box`'s numbers: ``lower, upper`` (S,) (meaningful where ``why`` is 0) and ``why`` (S,)
    of int, the index of the reason in :data:`BOX_REASONS` (``lo, hi`` checked, ``force_margin`` a ForceMargin,
    ``disturbance`` a WrenchBox or None: the vertices of the friction box times the wrench box)."""
    rows = batch_rows(batch, bk, box_vertices(bk.mode, lo, hi), force_margin, disturbance is not None)
    det = rows[2]  # per friction vertex: the wrench does not move it
    steady = np.all(det > 0, axis=1) | np.all(det < 0, axis=1)
    if disturbance is None:
        lower, upper, ok = _intersect(rows[0], rows[1], rows[3], tol)
    else:  # the rows at every (wrench, friction) vertex pair, wrench-major, s1 shared (not repeated)
        s0, s1, scale = wrench_vertex_parts(rows[0], rows[1], rows[3], rows[4], disturbance.vertices())
        lower, upper, ok = (x.reshape(batch.size, -1) for x in intersect_rows(s0, s1, scale, tol))
    lo_, up_ = lower.max(axis=1), upper.min(axis=1)
    why = np.select([~bk.ok, ~steady, ~ok.all(axis=1), lo_ > up_], [1, 2, 3, 4], 0)
    return lo_, up_, why


def box_bands(bk: BatchKinematics, joint: int, lower, upper, why, disturbance=None) -> list:
    """The :class:`qsplan.mechanics.bands.effort.Band` of every state from :func:`box_band_arrays` (``disturbance``: its box)."""
    letters, m, out = bk.mode.letters, "box-vertices", []
    for s, w in enumerate(why.tolist()):
        if w == 0:
            out.append(Band(letters, joint, float(lower[s]), float(upper[s]), True, None, m))
        else:
            why_s = f"kinematics: {bk.status_name(s)}" if w == 1 else loaded_reason(BOX_REASONS[w], disturbance)
            out.append(Band(letters, joint, np.nan, np.nan, False, why_s, m))
    return out


def guaranteed_bands_box(batch: StateBatch, mode, lo, hi, tol: Tolerances = DEFAULT_TOLERANCES, *,
                         force_margin=None, bk: BatchKinematics | None = None, disturbance=None) -> list:  # fmt: skip
    """:func:`qsplan.mechanics.bands.guaranteed.guaranteed_band_box` at every state (vertex method, exact).
    ``bk``: ``mode``'s kinematic stage on ``batch`` if already computed."""
    force_margin = None if force_margin is None else check_force_margin(force_margin)
    box = check_wrench_box(disturbance)
    lo, hi = check_mu_range(lo, hi, n=batch.n_c)
    bk = batch_kinematics(batch, mode, tol) if bk is None else bk
    return box_bands(bk, batch.joint, *box_band_arrays(batch, bk, lo, hi, tol, force_margin, box), box)


def guaranteed_bands_shared(batch: StateBatch, mode, lo: float, hi: float, tol: Tolerances = DEFAULT_TOLERANCES, *,
                            force_margin=None, bk: BatchKinematics | None = None, disturbance=None) -> list:  # fmt: skip
    """:func:`qsplan.mechanics.bands.guaranteed.guaranteed_band_shared` at every state (polynomial roots, exact).

    The rows at the Chebyshev nodes are batched; the roots of each state's polynomials are found
    by the reference's own function (:func:`qsplan.mechanics.bands.guaranteed.shared_band_from_rows`).
    """
    force_margin = None if force_margin is None else check_force_margin(force_margin)
    box = check_wrench_box(disturbance)
    lo, hi = check_mu_range(lo, hi)
    if hi == lo:
        return point_bands_batch(batch, mode, np.full(batch.n_c, lo), tol, force_margin=force_margin, method="shared-roots", bk=bk,
                                 disturbance=box)  # fmt: skip
    bk = batch_kinematics(batch, mode, tol) if bk is None else bk
    nodes = shared_nodes(bk.mode, lo, hi)
    rows = batch_rows(batch, bk, np.repeat(nodes[:, None], batch.n_c, axis=1), force_margin, box is not None)
    letters, joint, out, kin_ok = bk.mode.letters, batch.joint, [], bk.ok
    for s in range(batch.size):
        if not kin_ok[s]:
            out.append(Band(letters, joint, np.nan, np.nan, False, f"kinematics: {bk.status_name(s)}", "shared-roots"))
        elif box is None:
            out.append(shared_band_from_rows(bk.mode, joint, nodes, *(x[s] for x in rows), lo, hi, tol))
        else:
            out.append(shared_band_over_wrenches(bk.mode, joint, nodes, *(x[s] for x in rows), box, lo, hi, tol))
    return out
