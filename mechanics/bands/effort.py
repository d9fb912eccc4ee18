"""Effort bands: the efforts of one effort-controlled joint for which a contact mode is feasible.

With one effort-controlled joint, the kinematics of a mode (eq. 24) do not
depend on the effort or on friction, and the wrench intensities are affine in
the effort: ``c_A(tau) = Q_AI^{-1} ([-g_obj; -g_man_I] + tau e)`` (eq. 26).
Every Coulomb inequality of eq. (28) is then ``s_r(tau) = s0_r + tau s1_r >= 0``,
a half-line of efforts, and the band is their intersection (Section 5.2,
Figs. 10-12).  A :class:`ForceMargin` asks for ``s_r >= m_r`` instead: every loaded
contact's normal force at least ``normal`` and every rolling contact's cone slacks at
least ``slack`` (N); still a half-line per row.  An extra wrench on the workpiece moves
every row affinely (``band_rows(..., loads=True)``; bands robust to a box of them:
:mod:`qsplan.mechanics.bands.disturbance`).  Bands over uncertain friction
(guaranteed, possible, sampled) are in :mod:`qsplan.mechanics.bands.guaranteed`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qsplan.mechanics.bands.disturbance import (
    check_wrench_box,
    load_columns,
    loaded_reason,
    worst_over_wrenches,
    wrench_vertex_rows,
)
from qsplan.mechanics.errors import QsplanError, SceneError
from qsplan.mechanics.modes.contact_mode import ContactMode
from qsplan.mechanics.numerics import DEFAULT_TOLERANCES, Status, Tolerances, singular_matrices
from qsplan.mechanics.model.scene import Scene
from qsplan.mechanics.modes.equilibrium import coulomb_slacks, equilibrium_matrix
from qsplan.mechanics.modes.kinematics import ScenePool, check_mode_fits, single_mode_kinematics

__all__ = [
    "Band",
    "ForceMargin",
    "check_force_margin",
    "row_margins",
    "ModeKinematics",
    "check_one_effort_joint",
    "band_kinematics",
    "band_rows",
    "coulomb_rows",
    "coulomb_columns",
    "intersect_rows",
    "effort_band",
    "effort_bands",
]


@dataclass(frozen=True, slots=True)
class Band:
    """An interval of efforts ``[lower, upper]`` of the effort-controlled joint (N m or N).

    Attributes
    ----------
    mode : str
        Mode letters.
    joint : int
        0-based index of the effort-controlled joint.
    lower, upper : float
        Band edges; ``-inf`` / ``inf`` for an unbounded side (never a large number).
    feasible : bool
        False when no effort works (empty band, kinematics fail, or degenerate).
    reason : str or None
        Why it is infeasible, or a remark on how it was computed.
    method : str
        ``"point"``, ``"box-vertices"``, ``"shared-roots"``, ``"sampled"`` or ``"possible-superset"``.
    exact : bool
        True when the band is exact; False when conservative (narrower than or
        equal to the true guaranteed band, or for ``possible_band_box`` wider).
    """

    mode: str
    joint: int
    lower: float
    upper: float
    feasible: bool
    reason: str | None = None
    method: str = "point"
    exact: bool = True

    @property
    def width(self) -> float:
        """``upper - lower`` (inf when unbounded, 0 when infeasible)."""
        return self.upper - self.lower if self.feasible else 0.0

    def contains(self, tau: float) -> bool:
        """Whether ``tau`` lies in the band (edges included)."""
        return self.feasible and self.lower <= tau <= self.upper

    def to_dict(self) -> dict:
        """The ``qsplan band --json`` document: ``null`` for an unbounded side."""
        d = {
            "mode": self.mode,
            "feasible": self.feasible,
            "lower": None if not np.isfinite(self.lower) else float(self.lower),
            "upper": None if not np.isfinite(self.upper) else float(self.upper),
        }
        if not self.feasible:
            d["lower"] = d["upper"] = None
            d["reason"] = self.reason
        d["method"] = self.method
        d["exact"] = self.exact
        return d


@dataclass(frozen=True, slots=True)
class ForceMargin:
    """How far inside eq. (28) a band keeps the mode: a minimum normal force and a minimum Coulomb slack.

    Exactly at a band edge some normal force or cone slack of eq. (28) is zero: the model is
    on the brink of another mode, and any unmodelled load (a mass error, an inertial force,
    a torque error) tips it over.  With a margin every row ``s_r >= 0`` becomes ``s_r >= m_r``.

    Attributes
    ----------
    normal : float
        N, >= 0: every rolling and sliding contact's normal force ``c_n >= normal`` (eq. 9, made strict).
        Breaking contacts carry no force by definition and are not constrained.
    slack : float
        N, >= 0: both cone slacks ``mu c_n + c_t`` and ``mu c_n - c_t`` of every rolling contact
        ``>= slack`` (eqs. 21, 28, made strict).  A sliding contact lies on its cone's edge by
        definition (eq. 17): its only row is ``c_n``.  At ``mu = 0`` a rolling contact's slacks
        are ``+-c_t``, so any positive ``slack`` empties a band whose friction set reaches 0.

    Raises
    ------
    QsplanError
        A field negative, non-finite or not a number (the message names it).
    """

    normal: float = 0.0
    slack: float = 0.0

    def __post_init__(self):
        for name in ("normal", "slack"):
            v = getattr(self, name)
            if (isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating))
                    or not (np.isfinite(v) and v >= 0)):
                raise QsplanError(f"force_margin.{name}: expected a nonnegative finite force (N); got {v!r}")
            object.__setattr__(self, name, float(v))

    @property
    def is_zero(self) -> bool:
        """Both margins 0: the plain eq. (28)."""
        return self.normal == 0.0 and self.slack == 0.0

    def to_dict(self) -> dict:
        """``{"min_normal_force_N", "min_coulomb_slack_N"}`` for exports."""
        return {"min_normal_force_N": self.normal, "min_coulomb_slack_N": self.slack}


def check_force_margin(force_margin) -> ForceMargin:
    """A :class:`ForceMargin` from ``None`` (no margin), a ForceMargin, or a pair ``(normal, slack)`` (N)."""
    if force_margin is None:
        return ForceMargin()
    if isinstance(force_margin, ForceMargin):
        return force_margin
    if isinstance(force_margin, (tuple, list)) and len(force_margin) == 2:
        return ForceMargin(*force_margin)
    raise QsplanError(f"force_margin: expected a ForceMargin or (normal, slack) in N; got {force_margin!r}")


def row_margins(mode: ContactMode, force_margin) -> np.ndarray:
    """The margin of each row of :func:`band_rows` for ``mode``, shape (r,) (N).

    Rows in :func:`band_rows`' order: per rolling contact ``slack, slack, normal``, per sliding one ``normal``.
    """
    fm = check_force_margin(force_margin)
    out = []
    for letter in mode.letters:
        if letter == "R":
            out += [fm.slack, fm.slack, fm.normal]
        elif letter != "B":
            out.append(fm.normal)
    return np.array(out, dtype=float)


@dataclass(frozen=True, slots=True, eq=False)
class ModeKinematics:
    """A mode's mu- and effort-independent kinematic solution, or why it has none."""

    mode: ContactMode
    status: str
    pool: ScenePool
    kin: object  # modes.kinematics.Kinematics with one row, or None

    @property
    def ok(self) -> bool:
        return self.status == Status.FEASIBLE


def check_one_effort_joint(scene: Scene) -> int:
    """The index of the scene's one effort-controlled joint; SceneError if it has another number."""
    E = scene.effort_joints
    if E.size != 1:
        raise SceneError(
            f"joints: effort bands need exactly one effort-controlled joint; the scene has {E.size}"
        )
    return int(E[0])


def band_kinematics(scene: Scene, mode: ContactMode, tol: Tolerances = DEFAULT_TOLERANCES) -> ModeKinematics:
    """Run the kinematic stage (eqs. 24-25, 16) for one mode."""
    return ModeKinematics(*single_mode_kinematics(scene, mode, tol))


def band_rows(scene: Scene, mk: ModeKinematics, mu_rows, force_margin=None, *, loads: bool = False) -> tuple:
    """Coulomb slacks of eq. (28) as affine functions of the effort, at each mu row.

    Parameters
    ----------
    scene : Scene
        With exactly one effort-controlled joint.
    mk : ModeKinematics
        With ``mk.ok``.
    mu_rows : array-like, shape (N, n_c)
    force_margin : ForceMargin, optional
        Subtracted from ``s0`` (:func:`row_margins`): the rows then read ``s(tau) - m >= 0``.
        ``det Q_AI (s - m)`` stays multilinear in the mu's (``det`` is), so the vertex and root
        arguments of :mod:`qsplan.mechanics.bands.guaranteed` hold unchanged.
    loads : bool
        Also return ``s2``: the rows' change per unit of an external wrench added to ``g_obj``
        (:mod:`qsplan.mechanics.bands.disturbance`; eq. 26 is affine in it).

    Returns
    -------
    s0, s1 : ndarray, shape (N, r)
        ``s(tau) = s0 + tau * s1`` for the mode's r Coulomb rows: ``mu c_n + c_t`` and
        ``mu c_n - c_t`` and ``c_n`` per rolling contact, ``c_n`` per sliding contact
        (minus their margins with ``force_margin``).
    det : ndarray, shape (N,)
        ``det Q_AI``; exactly 0 where ``Q_AI`` counts as singular (its Hadamard ratio below
        ``Tolerances.singular``, :func:`qsplan.mechanics.numerics.singular_matrices`: a determinant within
        rounding of zero has no sign), and there ``s0``, ``s1`` (and ``s2``) are NaN.
    scale : ndarray, shape (N,)
        Force scale of each row set (N), for tolerances.
    s2 : ndarray, shape (N, r, 3)
        With ``loads`` only: ``s = s0 + tau s1 + s2 . w`` under an extra wrench ``w`` on the workpiece (N, N, N m).
    """
    mu_rows = np.atleast_2d(np.asarray(mu_rows, dtype=float))
    N = mu_rows.shape[0]
    kin = mk.kin.take(np.zeros(N, dtype=int))
    Q = equilibrium_matrix(mk.pool, kin, mu_rows)
    det = np.linalg.det(Q)
    E = mk.pool.E
    r0 = np.concatenate([-scene.g_obj, -scene.g_man[E]])
    bad = singular_matrices(Q, det)  # the solver's singularity test: a det within rounding of 0 has no sign
    det = np.where(bad & np.isfinite(det), 0.0, det)
    Qs = Q.copy()
    Qs[bad] = np.eye(Q.shape[1])
    rhs = load_columns(r0, loads)
    sol = np.linalg.solve(Qs, np.broadcast_to(rhs, (N,) + rhs.shape))  # (N, k, 2), or (N, k, 5) with loads
    if loads:
        rows = coulomb_columns(mk.mode, kin.idx[0], kin.contact[0], mu_rows, sol)
        s0, s1, s2 = rows[..., 0], rows[..., 1], rows[..., 2:]
        s2[bad] = np.nan
    else:
        s0, s1 = coulomb_rows(mk.mode, kin.idx[0], kin.contact[0], mu_rows, sol)
    scale = np.maximum(np.max(np.abs(sol[:, :, 0]), axis=1), np.max(np.abs(r0)))
    if force_margin is not None:
        s0 = s0 - row_margins(mk.mode, force_margin)[None, :]
    s0[bad] = np.nan
    s1[bad] = np.nan
    return (s0, s1, det, scale, s2) if loads else (s0, s1, det, scale)


def coulomb_rows(mode: ContactMode, idx, contact, mu_rows, sol) -> tuple:
    """The Coulomb rows of eq. (28) from the solution of eq. (26), any leading batch shape.

    Parameters
    ----------
    mode : ContactMode
    idx, contact : ndarray of int, shape (k,)
        The mode's applicable rows and their contacts (:class:`ModeKinematics`' ``kin``).
    mu_rows : ndarray, shape (..., n_c)
    sol : ndarray, shape (..., k, 2)
        ``c_A`` at ``tau = 0`` and its slope in ``tau`` (eq. 26).

    Returns
    -------
    s0, s1 : ndarray, shape (..., r)
        In :func:`band_rows`' order, without margins.
    """
    rows = coulomb_columns(mode, idx, contact, mu_rows, sol)
    return np.ascontiguousarray(rows[..., 0]), np.ascontiguousarray(rows[..., 1])


def coulomb_columns(mode: ContactMode, idx, contact, mu_rows, sol) -> np.ndarray:
    """:func:`coulomb_rows` for every column of ``sol`` (..., k, n): the rows of eq. (28), shape (..., r, n).

    The rows are linear in ``c_A``, so each column (the value at zero effort, the slope in the effort, the
    slopes in a wrench) maps alike.
    """
    n_c = mu_rows.shape[-1]
    rows_n = idx < n_c
    out = []
    for c, letter in enumerate(mode.letters):
        if letter == "B":
            continue
        jn = int(np.flatnonzero(rows_n & (contact == c))[0])
        cn = sol[..., jn, :]  # (..., n): value at tau = 0, slope, ...
        if letter == "R":
            jt = int(np.flatnonzero(~rows_n & (contact == c))[0])
            out += coulomb_slacks(mu_rows[..., c : c + 1], cn, sol[..., jt, :])  # linear: every column alike
        out.append(cn)  # c_n >= 0 (eq. 9); for rolling contacts implied by the cone rows only when mu > 0
    return np.stack(out, axis=-2)


#: Rows x friction points from which :func:`intersect_rows` folds the rows column by column: numpy's reductions along
#: a short last axis (a mode has 1 to 3 n_c rows) cost ~10x an elementwise pass per element, so large batches (the
#: band tables': ~10^5) take r elementwise passes instead; small ones (a per-state search's cells) keep the fewer calls.
#: Both give the same numbers (a maximum, a minimum and a conjunction do not depend on the order of their terms).
#: (``np.putmask`` stands for ``np.where`` there: the same values, but no branch per element, which a mask as
#: unpredictable as the rows' signs makes ~5x slower.)
COLUMNS_FROM = 2048


def intersect_rows(s0, s1, scale, tol: Tolerances):
    """Band edges of ``s0 + tau s1 >= 0`` over rows, per mu row: lower, upper, ok (N,).

    ``s0, s1`` (N, r) and ``scale`` (N,) are :func:`band_rows`' output; any leading shape (...) instead of (N,) with
    ``s1`` and ``scale`` broadcasting against ``s0`` (the rows under each wrench vertex share ``s1``,
    :func:`qsplan.mechanics.bands.disturbance.wrench_vertex_parts`): the edges of the broadcast rows.  A row the effort
    does not move (its slope at most ``tol.force`` of the largest) bounds nothing and must hold as it is (within
    ``tol.force * scale``).  Edges are never a negative zero, and NaN is numpy's own (:func:`_canonical`).
    """
    ftol = tol.force * scale[..., None]
    if s0.size < COLUMNS_FROM:
        big = np.max(np.abs(s1), axis=-1, keepdims=True)
        flat = np.abs(s1) <= tol.force * big  # effort does not move this row (relative to the mode's largest slope)
        with np.errstate(divide="ignore", invalid="ignore"):
            edge = -s0 / s1
        lower = np.max(np.where(~flat & (s1 > 0), edge, -np.inf), axis=-1)
        upper = np.min(np.where(~flat & (s1 < 0), edge, np.inf), axis=-1)
        flat_ok = np.all(~flat | (s0 >= -ftol), axis=-1)
        ok = flat_ok & (lower <= upper) & np.all(np.isfinite(s0), axis=-1)
        return _canonical(lower), _canonical(upper), ok
    return _intersect_columns(s0, s1, -ftol[..., 0], tol)


def _canonical(edge):
    """Band edges with one zero and one NaN (no negative zero, numpy's NaN): the same bits whichever order the rows
    were folded in (:data:`COLUMNS_FROM`)."""
    return np.where(np.isnan(edge), np.nan, edge + 0.0)


def _intersect_columns(s0, s1, neg_ftol, tol: Tolerances):
    """:func:`intersect_rows`' answer folded column by column (elementwise passes only; the same numbers), what depends
    on ``s1`` alone at its own (broadcast) shape."""
    a1 = np.abs(s1)
    big = a1[..., 0]
    for j in range(1, s1.shape[-1]):
        big = np.maximum(big, a1[..., j])
    big = tol.force * big
    lower, upper, ok = None, None, None
    with np.errstate(divide="ignore", invalid="ignore"):
        for j in range(s1.shape[-1]):
            c0, c1 = s0[..., j], s1[..., j]
            moves = ~(a1[..., j] <= big)  # not flat (NaN slopes count as moving, as in intersect_rows)
            lo_j = -c0 / c1  # the edge, kept where the row bounds from below (np.where's value, without its branches)
            up_j = lo_j.copy()
            np.putmask(lo_j, np.broadcast_to(~(moves & (c1 > 0)), lo_j.shape), -np.inf)
            np.putmask(up_j, np.broadcast_to(~(moves & (c1 < 0)), up_j.shape), np.inf)
            ok_j = (moves | (c0 >= neg_ftol)) & np.isfinite(c0)
            if j == 0:
                lower, upper, ok = lo_j, up_j, ok_j
            else:
                lower, upper, ok = np.maximum(lower, lo_j), np.minimum(upper, up_j), ok & ok_j
    return _canonical(lower), _canonical(upper), ok & (lower <= upper)


def effort_bands(scene: Scene, mode: ContactMode, mu_rows, tol: Tolerances = DEFAULT_TOLERANCES, *, force_margin=None,
                 disturbance=None):  # fmt: skip
    """Bands of ``mode`` at many friction points at once (``force_margin``: see :class:`ForceMargin`).

    ``disturbance`` (:class:`qsplan.mechanics.bands.disturbance.WrenchBox` or ``(lo, hi)``): each band holds for
    every wrench of the box added to ``g_obj`` (the intersection over the box's vertices, exact: eq. 26 is affine
    in the wrench).

    Returns
    -------
    lower, upper : ndarray, shape (N,)
    ok : ndarray of bool, shape (N,)
        False where the band is empty, the kinematics fail or ``Q_AI`` is singular.
    """
    check_one_effort_joint(scene)
    force_margin = None if force_margin is None else check_force_margin(force_margin)
    box = check_wrench_box(disturbance)
    mu_rows = np.atleast_2d(np.asarray(mu_rows, dtype=float))
    mk = band_kinematics(scene, mode, tol)
    N = mu_rows.shape[0]
    if not mk.ok:
        return np.full(N, np.nan), np.full(N, np.nan), np.zeros(N, dtype=bool)
    if box is not None:
        rows = wrench_vertex_rows(*band_rows(scene, mk, mu_rows, force_margin, loads=True), box.vertices())
        return worst_over_wrenches(*intersect_rows(rows[0], rows[1], rows[3], tol), len(box.vertices()))
    s0, s1, _, scale = band_rows(scene, mk, mu_rows, force_margin)
    lower, upper, ok = intersect_rows(s0, s1, scale, tol)
    return lower, upper, ok


def effort_band(scene: Scene, mode: ContactMode | str, mu=None, tol: Tolerances = DEFAULT_TOLERANCES, *,
                force_margin=None, disturbance=None) -> Band:
    """The band of ``mode`` at the scene's friction (or at ``mu``), eq. (28).

    Parameters
    ----------
    scene : Scene
        Exactly one effort-controlled joint; its commanded effort is ignored.
    mode : ContactMode or str
        Letters are checked against the scene (one per contact, eq. 29): a ModeError names ``mode``.
    mu : array-like, shape (n_c,), optional
    force_margin : ForceMargin or (float, float), optional
        Minimum normal force and Coulomb slack (N) the band keeps (default none: eq. 28 as is).
    disturbance : WrenchBox or (array-like, array-like), optional
        A box of external wrenches on the workpiece (N, N, N m, added to ``g_obj``): the band holds for every
        one (:mod:`qsplan.mechanics.bands.disturbance`).
    """
    joint = check_one_effort_joint(scene)
    mode = check_mode_fits(scene, mode)
    force_margin = None if force_margin is None else check_force_margin(force_margin)
    box = check_wrench_box(disturbance)
    mk = band_kinematics(scene, mode, tol)
    if not mk.ok:
        return Band(mode.letters, joint, np.nan, np.nan, False, f"kinematics: {mk.status}")
    mu = scene.mu if mu is None else np.broadcast_to(np.asarray(mu, float), (scene.n_contacts,))
    rows = band_rows(scene, mk, mu[None], force_margin, loads=box is not None)
    s0, s1, det, scale = rows if box is None else wrench_vertex_rows(*rows, box.vertices())
    if not np.isfinite(s0).all():
        return Band(mode.letters, joint, np.nan, np.nan, False, "equilibrium_singular")
    lower, upper, ok = intersect_rows(s0, s1, scale, tol)
    if box is not None:
        lower, upper, ok = worst_over_wrenches(lower, upper, ok, s0.shape[0])
    if not ok[0]:
        return Band(mode.letters, joint, np.nan, np.nan, False, loaded_reason("coulomb: no effort satisfies eq. (28)", box))
    return Band(mode.letters, joint, float(lower[0]), float(upper[0]), True)
