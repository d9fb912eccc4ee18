"""Robust bands for a batch of states at once (Section 5.2, Figs. 12-13).

:func:`robust_bands` is :func:`qsplan.mechanics.bands.robust.robust_band` at every state of a
:class:`qsplan.mechanics.bands.batched.StateBatch`: the kinematic stage of every mode in one call
(:func:`qsplan.mechanics.bands.batched_modes.modes_kinematics`), the desired mode's guaranteed band
(:func:`qsplan.mechanics.bands.batched.box_band_arrays`, or the shared-friction roots), every
competitor's hull inside it (:func:`qsplan.mechanics.bands.batched_preclusion.competitor_hulls`) and
the reference's own assembly per state (:func:`qsplan.mechanics.bands.robust.assemble_robust_band`).
:func:`robust_band_arrays` gives the same numbers as arrays, cut out for all states at once by
:func:`assemble_band_arrays` (the twin of ``assemble_robust_band`` the tests compare it with): the band
tables' path, with no object per state.  Both take the reference's ``disturbance`` (a box of wrenches on the workpiece)
and pass it to each part.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qsplan.mechanics.bands.batched import StateBatch, box_band_arrays, box_bands, guaranteed_bands_shared, map_batches
from qsplan.mechanics.bands.batched_modes import modes_kinematics
from qsplan.mechanics.bands.batched_preclusion import RootStats, competitor_hulls, competitor_torques_batch
from qsplan.mechanics.bands.disturbance import check_wrench_box
from qsplan.mechanics.bands.effort import check_force_margin
from qsplan.mechanics.bands.robust import TOUCH_RTOL, assemble_robust_band, check_mu_pair
from qsplan.mechanics.model.friction import check_mu_range
from qsplan.mechanics.modes.contact_mode import enumerate_modes, mode_from_letters
from qsplan.mechanics.modes.kinematics import check_mode_fits
from qsplan.mechanics.numerics import DEFAULT_TOLERANCES, Status, Tolerances

__all__ = ["RobustArrays", "RootStats", "admissible_competitors_batch", "assemble_band_arrays", "competitor_torques_batch",
           "robust_band_arrays", "robust_bands"]  # fmt: skip

#: The kinematic status codes of modes the solver cannot decide (``Status.ILL_CONDITIONED``).
_ILL_CODES = [Status.ORDER.index(name) for name in sorted(Status.ILL_CONDITIONED)]


@dataclass(frozen=True, slots=True, eq=False)
class RobustArrays:
    """:class:`qsplan.mechanics.bands.robust.RobustBand`'s numbers at every state of a batch.

    Attributes
    ----------
    lower, upper : ndarray, shape (S,)
        Band edges (N m or N), ``-inf`` / ``inf`` for unbounded sides; NaN where not ``feasible``.
    feasible, exact, split : ndarray of bool, shape (S,)
    desired_lower, desired_upper : ndarray, shape (S,)
        The desired mode's guaranteed band before precluding competitors (NaN where it has none).
    desired_feasible : ndarray of bool, shape (S,)
    """

    lower: np.ndarray
    upper: np.ndarray
    feasible: np.ndarray
    exact: np.ndarray
    split: np.ndarray
    desired_lower: np.ndarray
    desired_upper: np.ndarray
    desired_feasible: np.ndarray


def admissible_competitors_batch(batch: StateBatch, mode, tol: Tolerances = DEFAULT_TOLERANCES, kin: dict | None = None) -> tuple:
    """Per state, the modes other than ``mode`` kinematically admissible there, in enumeration order;
    and the union (:func:`qsplan.mechanics.bands.robust.admissible_competitors` of the whole batch).
    ``kin``, if given, receives each mode's :class:`BatchKinematics` (the competitors' preclusion reuses them).

    Returns
    -------
    per_state : list of tuple of str, length S
    union : tuple of str
    """
    s0 = batch.scenes[0]
    mode = check_mode_fits(s0, mode)
    kin = {} if kin is None else kin
    kin.update(modes_kinematics(batch, [m for m in enumerate_modes(s0.n_contacts, s0.dof) if m.letters != mode.letters], tol))
    oks = [(c, bk.ok) for c, bk in kin.items()]
    per_state = [tuple(c for c, ok in oks if ok[s]) for s in range(batch.size)]
    return per_state, tuple(c for c, ok in oks if ok.any())


def _subtract_hulls(lo, hi, c_lo, c_hi, atol):
    """:func:`qsplan.mechanics.bands.robust.subtract_hull` elementwise (the same comparisons and differences)."""
    with np.errstate(invalid="ignore"):
        whole = np.isnan(c_lo) | (c_hi <= lo + atol) | (c_lo >= hi - atol)
        left, right = c_lo > lo + atol, c_hi < hi - atol
        keep_right = hi - c_hi > c_lo - lo
    both = left & right
    new_lo = np.where(both, np.where(keep_right, c_hi, lo), np.where(left, lo, np.where(right, c_hi, np.nan)))
    new_hi = np.where(both, np.where(keep_right, hi, c_lo), np.where(left, c_lo, np.where(right, hi, np.nan)))
    return np.where(whole, lo, new_lo), np.where(whole, hi, new_hi), ~whole & both


def assemble_band_arrays(lower, upper, feasible, exact, hulls, admissible: dict | None = None) -> RobustArrays:
    """:func:`qsplan.mechanics.bands.robust.assemble_robust_band` at every state: the desired band minus each
    competitor's hull, in the competitors' order.

    Parameters
    ----------
    lower, upper : ndarray, shape (S,)
        The desired mode's guaranteed band (N m or N).
    feasible, exact : ndarray of bool, shape (S,)
        Its flags (:class:`qsplan.mechanics.bands.effort.Band`).
    hulls : sequence of HullArrays
        The competitors (:func:`qsplan.mechanics.bands.batched_preclusion.competitor_hulls`), in order.
    admissible : dict of str to ndarray of bool, shape (S,), optional
        Where each competitor competes (default: everywhere).
    """
    feasible = np.asarray(feasible, dtype=bool)
    a = np.where(feasible, lower + 0.0, np.nan)  # + 0.0: no negative zero
    b = np.where(feasible, upper + 0.0, np.nan)
    finite = lambda x: np.where(np.isfinite(x), np.abs(x), 0.0)  # noqa: E731
    atol = TOUCH_RTOL * np.maximum(np.maximum(finite(a), finite(b)), 1.0)
    exact = np.array(exact, dtype=bool)
    split = np.zeros(a.shape, bool)
    for h in hulls:
        competes = feasible if admissible is None else feasible & admissible[h.mode]
        ill = h.empty & np.isin(h.status, _ILL_CODES)
        for s, ct in h.searched.items():
            ill[s] = ct.empty and (ct.reason or "").removeprefix("kinematics: ") in Status.ILL_CONDITIONED
        exact &= ~(competes & ill) & ~(competes & ~h.empty & ~h.exact)
    for h in hulls:
        cut = (feasible if admissible is None else feasible & admissible[h.mode]) & ~h.empty & ~np.isnan(a)
        if cut.any():
            a[cut], b[cut], pieces = _subtract_hulls(a[cut], b[cut], h.lower[cut], h.upper[cut], atol[cut])
            split[cut] |= pieces
    ok = ~np.isnan(a)
    return RobustArrays(np.where(ok, a, np.nan), np.where(ok, b, np.nan), ok, exact, split,
                        np.where(feasible, lower, np.nan), np.where(feasible, upper, np.nan), feasible)  # fmt: skip


def _robust_batch(batch: StateBatch, mode, lo, hi, shared, competitors, force_margin, stats, box=None):
    """The parts of every state's robust band: ``(union, admissible, desired, hulls)``: the competitors, where each
    competes (None: everywhere), the desired band as ``(lower, upper, feasible, exact, bands)`` (``bands()`` makes
    its :class:`~qsplan.mechanics.bands.effort.Band` objects) and each competitor's :class:`HullArrays`; ``box``: the
    checked disturbance (a WrenchBox or None)."""
    s0 = batch.scenes[0]
    if competitors is None:
        others = [m.letters for m in enumerate_modes(s0.n_contacts, s0.dof) if m.letters != mode.letters]
        kin = modes_kinematics(batch, [mode] + others)
        union = tuple(c for c in others if kin[c].ok.any())
        admissible = {c: kin[c].ok for c in union}
    else:
        kin, union, admissible = modes_kinematics(batch, [mode]), tuple(competitors), None
    bk = kin[mode.letters]
    if shared:
        bands = guaranteed_bands_shared(batch, mode, lo, hi, force_margin=force_margin, bk=bk, disturbance=box)
        d_lo, d_up = np.array([d.lower for d in bands], float), np.array([d.upper for d in bands], float)
        feasible, exact = np.array([d.feasible for d in bands], bool), np.array([d.exact for d in bands], bool)
        desired = (d_lo, d_up, feasible, exact, lambda: bands)
    else:
        margin = None if force_margin is None else check_force_margin(force_margin)
        lo_a, hi_a = check_mu_range(lo, hi, n=batch.n_c)
        d_lo, d_up, why = box_band_arrays(batch, bk, lo_a, hi_a, force_margin=margin, disturbance=box)
        feasible = why == 0
        desired = (d_lo, d_up, feasible, np.ones(batch.size, bool), lambda: box_bands(bk, batch.joint, d_lo, d_up, why, box))
    idx = np.flatnonzero(feasible)
    hulls = {}
    if idx.size and union:
        if competitors is not None:
            kin = {**kin, **modes_kinematics(batch, [c for c in dict.fromkeys(union) if c not in kin])}
        hulls = competitor_hulls(batch, kin, list(dict.fromkeys(union)), lo, hi, d_lo + 0.0, d_up + 0.0, shared, stats=stats, states=idx,
                                 disturbance=box)  # fmt: skip
    return union, admissible, desired, hulls


def robust_bands(scenes, mode, mu_range, *, shared: bool = False, competitors=None, force_margin=None,
                 stats: RootStats | None = None, disturbance=None) -> list:  # fmt: skip
    """:func:`qsplan.mechanics.bands.robust.robust_band` at every scene, batched (same results).

    Scenes are grouped by :func:`qsplan.mechanics.bands.batched.batch_signature`; each group is one batch.
    ``stats`` (:class:`RootStats`) counts the competitor searches the batched root cell resolved.
    ``disturbance``: a box of external wrenches on the workpiece, as in ``robust_band``.

    Returns
    -------
    list of RobustBand, one per scene
    """
    lo, hi = check_mu_pair(mu_range)
    mode = mode_from_letters(mode)
    box = check_wrench_box(disturbance)

    def per_batch(batch):
        union, admissible, desired, hulls = _robust_batch(batch, mode, lo, hi, shared, competitors, force_margin, stats, box)
        out = []
        for s, d in enumerate(desired[4]()):
            comps = union if admissible is None else tuple(c for c in union if admissible[c][s])
            torques = {c: h.torques(s) for c, h in hulls.items()} if d.feasible else {}
            out.append(assemble_robust_band(mode, d, comps, torques, (lo, hi), shared, box))
        return out

    return map_batches(scenes, per_batch)


def robust_band_arrays(batch: StateBatch, mode, mu_range, *, shared: bool = False, competitors=None, force_margin=None,
                       stats: RootStats | None = None, disturbance=None) -> RobustArrays:  # fmt: skip
    """:func:`robust_bands`' numbers at every state of ``batch`` as arrays (:class:`RobustArrays`; no reasons)."""
    lo, hi = check_mu_pair(mu_range)
    mode = mode_from_letters(mode)
    box = check_wrench_box(disturbance)
    union, admissible, desired, hulls = _robust_batch(batch, mode, lo, hi, shared, competitors, force_margin, stats, box)
    return assemble_band_arrays(*desired[:4], [hulls[c] for c in union] if hulls else [], admissible)
