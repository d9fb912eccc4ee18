"""Torque bands along a manipulation segment (Section 5.2, Figs. 10-13).

Pointwise along a sampled segment (:func:`qsplan.hands.sample_segment`), for
its single effort-controlled joint:

* :func:`point_band_sweep` - the band of one mode at one friction (Figs. 10-12);
* :func:`guaranteed_sweep` - the band that keeps the desired mode feasible for
  every friction in an uncertainty set and precludes every competing mode there
  (Fig. 13), exact: :func:`qsplan.mechanics.robust_band` at every sample (computed for all samples
  at once by :func:`qsplan.mechanics.bands.batched_robust.robust_bands`, bit-identical);
* :func:`sampled_guaranteed_sweep` - the paper's method: at each listed friction
  value the desired mode's band minus the competitors' bands, intersected over
  the list.

:func:`qsplan.planner.torque.sweep.segment_bands` runs all of them, with the command,
for the figures and the export.  Efforts are N m (revolute) or N (prismatic); unbounded
sides are ``inf``, never a large number; NaN marks points without a band.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qsplan.mechanics.bands.batched import effort_bands_batch, map_batches, point_bands_batch
from qsplan.mechanics.bands.batched_robust import admissible_competitors_batch, robust_bands
from qsplan.mechanics.bands.robust import TOUCH_RTOL, subtract_hull
from qsplan.mechanics.errors import QsplanError
from qsplan.mechanics.model.friction import check_mu_range
from qsplan.mechanics.modes.contact_mode import ContactMode, enumerate_modes

__all__ = [
    "DEFAULT_MU_RANGE",
    "PAPER_MU_SAMPLES",
    "TOUCH_RTOL",
    "BandSweep",
    "GuaranteedSweep",
    "check_mu_range",
    "frozen_array",
    "guaranteed_sweep",
    "narrowest",
    "point_band_sweep",
    "sampled_guaranteed_sweep",
]

#: The paper's friction uncertainty (Section 5.2): mu in [0, 0.2].
DEFAULT_MU_RANGE = (0.0, 0.2)

#: The paper's sampled friction values 0, 0.01, ..., 0.20: 21 of them.
PAPER_MU_SAMPLES = 21




@dataclass(frozen=True, slots=True, eq=False)
class BandSweep:
    """One band along a segment.

    Attributes
    ----------
    label : str
        What it is, e.g. ``"4S, mu = 0.2"``.
    mode : str
        Mode letters.
    joint : str
        Name of the effort-controlled joint.
    t : ndarray, shape (n,)
        Times (s).
    lower, upper : ndarray, shape (n,)
        Band edges (N m or N), ``-inf`` / ``inf`` for unbounded sides, NaN where ``feasible`` is False.
    feasible : ndarray of bool, shape (n,)
    exact : ndarray of bool, shape (n,)
        Edges exact (to :data:`qsplan.mechanics.bands.preclusion.PRECLUSION_RTOL` where competitors were precluded);
        False where conservative (narrower than the true band).
    method : str
        ``"point"``, ``"box-vertices"``, ``"shared-roots"`` or ``"sampled"``.
    reasons : tuple of (str or None), length n
        Why a point has no band, or a remark (e.g. a competitor split the band).
    """

    label: str
    mode: str
    joint: str
    t: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    feasible: np.ndarray
    exact: np.ndarray
    method: str
    reasons: tuple

    @property
    def width(self) -> np.ndarray:
        """``upper - lower`` (inf when unbounded, NaN where infeasible), shape (n,)."""
        return np.where(self.feasible, self.upper - self.lower, np.nan)

    def feasible_spans(self) -> list:
        """``[(t_first, t_last), ...]`` of the runs of samples that have a band (s)."""
        return _runs(self.t, self.feasible)

    def infinite_upper_spans(self) -> list:
        """``[(t_first, t_last), ...]`` of the runs of samples whose upper edge is infinite (s)."""
        return _runs(self.t, self.feasible & np.isposinf(self.upper))


@dataclass(frozen=True, slots=True, eq=False)
class GuaranteedSweep:
    """The guaranteed band of a mode along a segment, and how the competitors cut it.

    Attributes
    ----------
    band : BandSweep
        The final band: desired mode guaranteed, every competitor precluded.
    desired : BandSweep
        The desired mode's guaranteed band before precluding competitors.
    competitors : dict of str to (ndarray, ndarray)
        Per competing mode, the hull ``(lower, upper)`` (n,) of its possibly-feasible
        efforts inside ``desired``; NaN where it is precluded there already.
    split : ndarray of bool, shape (n,)
        A competitor's hull lay strictly inside the band: the larger piece was kept.
    mu_range : (float, float)
    shared : bool
        One coefficient shared by all contacts (else independent per contact).
    force_margin : ForceMargin or None
        Minimum normal force and Coulomb slack (N) the desired mode keeps (None: eq. 28 as is).
    disturbance : WrenchBox or (lo, hi) or None
        The box of external wrenches on the workpiece the band withstands (None: none).
    """

    band: BandSweep
    desired: BandSweep
    competitors: dict
    split: np.ndarray
    mu_range: tuple
    shared: bool
    force_margin: object = None
    disturbance: object = None



def frozen_array(a):
    """A read-only copy of ``a``."""
    a = np.array(a, copy=True)
    a.setflags(write=False)
    return a


def _runs(t, mask) -> list:
    out, start = [], None
    for k, m in enumerate(mask):
        if m and start is None:
            start = k
        if not m and start is not None:
            out.append((float(t[start]), float(t[k - 1])))
            start = None
    if start is not None:
        out.append((float(t[start]), float(t[-1])))
    return out


def _mode(samples, mode) -> ContactMode:
    letters = samples.segment.mode if mode is None else (mode.letters if isinstance(mode, ContactMode) else str(mode).upper())
    return ContactMode(letters)


def admissible_competitors(scenes, mode) -> tuple:
    """:func:`qsplan.mechanics.bands.robust.admissible_competitors`, batched over the scenes."""
    found = set().union(*map_batches(scenes, lambda batch: [admissible_competitors_batch(batch, mode)[1]] * batch.size))
    scene0 = scenes[0]
    return tuple(m.letters for m in enumerate_modes(scene0.n_contacts, scene0.dof) if m.letters in found and m.letters != mode.letters)


def _sweep(label, mode, samples, bands, method) -> BandSweep:
    feas = np.array([b.feasible for b in bands])
    lower = np.array([b.lower + 0.0 if b.feasible else np.nan for b in bands])  # + 0.0: no negative zero
    upper = np.array([b.upper + 0.0 if b.feasible else np.nan for b in bands])
    exact = np.array([b.exact for b in bands])
    joint = samples.scenes[0].joint_names[samples.segment.effort_index]
    return BandSweep(label, mode.letters, joint, frozen_array(samples.t), frozen_array(lower), frozen_array(upper), frozen_array(feas),
                     frozen_array(exact), method, tuple(b.reason for b in bands))  # fmt: skip



def point_band_sweep(samples, mu, mode=None, label=None) -> BandSweep:
    """The band of ``mode`` (default the segment's) at friction ``mu`` at every sample (eq. 28).

    Parameters
    ----------
    samples : qsplan.hands.paper_hand.segments.SegmentSamples
    mu : float or array-like, shape (n_c,)
    mode : str or ContactMode, optional
    label : str, optional
    """
    mode = _mode(samples, mode)
    mu_arr = np.broadcast_to(np.asarray(mu, dtype=float), (samples.scenes[0].n_contacts,))
    if not np.all(np.isfinite(mu_arr)) or np.any(mu_arr < 0):
        raise QsplanError(f"mu: expected nonnegative finite coefficients; got {mu!r}")
    bands = map_batches(samples.scenes, lambda batch: point_bands_batch(batch, mode, mu_arr))  # effort_band at every sample
    if label is None:
        where = f"{mu_arr[0]:g}" if np.ptp(mu_arr) == 0 else str(mu_arr.tolist())
        label = f"{mode.name}, mu = {where}"
    return _sweep(label, mode, samples, bands, "point")


def guaranteed_sweep(samples, mu_range=DEFAULT_MU_RANGE, shared=False, mode=None, competitors=None, *,
                     force_margin=None, disturbance=None) -> GuaranteedSweep:  # fmt: skip
    """The band guaranteeing ``mode`` and precluding every competitor for all friction in the set (Fig. 13).

    Parameters
    ----------
    samples : qsplan.hands.paper_hand.segments.SegmentSamples
    mu_range : (float, float)
        ``0 <= lo <= hi``: each contact's coefficient independently in ``[lo, hi]``, or
        with ``shared=True`` one coefficient for all contacts.
    shared : bool
    mode : str, optional
        Default the segment's desired mode.
    competitors : sequence of str, optional
        Default: every mode kinematically admissible at some sample
        (:func:`qsplan.mechanics.bands.robust.admissible_competitors`; in chunks: :func:`qsplan.planner.torque.sweep.competing_modes`).
    force_margin : ForceMargin or (float, float), optional
        Minimum normal force and Coulomb slack (N) kept for all friction in the set (:func:`qsplan.mechanics.robust_band`).
    disturbance : WrenchBox or (lo, hi), optional
        A box of external wrenches on the workpiece (N, N, N m) the band withstands too (:func:`qsplan.mechanics.robust_band`).

    Returns
    -------
    GuaranteedSweep
        :func:`qsplan.mechanics.robust_band` at every sample.  The final band is exact where its
        ``exact`` flag is set; a competitor whose hull splits the band leaves the larger piece (``split``).
    """
    lo, hi = check_mu_range(*mu_range)
    mode = _mode(samples, mode)
    comps = admissible_competitors(samples.scenes, mode) if competitors is None else tuple(competitors)
    # robust_band at every sample, batched over the samples (bit-identical: tests/mechanics/test_bands_batched.py)
    robust = robust_bands(samples.scenes, mode, (lo, hi), shared=shared, competitors=comps, force_margin=force_margin,
                          disturbance=disturbance)
    desired = [r.desired for r in robust]
    method = desired[0].method
    where = f"mu in [{lo:g}, {hi:g}]" + (" (shared)" if shared else " (each contact)")
    dsweep = _sweep(f"{mode.name} guaranteed, {where}", mode, samples, desired, method)
    nan = np.nan
    hulls = {c: (frozen_array([r.precluded[c].lower if c in r.precluded else nan for r in robust]),
                 frozen_array([r.precluded[c].upper if c in r.precluded else nan for r in robust])) for c in comps}  # fmt: skip
    band = BandSweep(f"{mode.name} guaranteed, competitors precluded, {where}", mode.letters, dsweep.joint, dsweep.t,
                     frozen_array([r.lower for r in robust]), frozen_array([r.upper for r in robust]),
                     frozen_array([r.feasible for r in robust]), frozen_array([r.exact for r in robust]), method,
                     tuple(r.reason for r in robust))  # fmt: skip
    split = frozen_array(np.array([r.split for r in robust], dtype=bool))
    return GuaranteedSweep(band, dsweep, hulls, split, (lo, hi), bool(shared), force_margin, disturbance)


def sampled_guaranteed_sweep(samples, mu_values, mode=None, competitors=None, *, force_margin=None) -> BandSweep:
    """The paper's method: at each listed friction, the mode's band minus the competitors', intersected.

    Parameters
    ----------
    samples : qsplan.hands.paper_hand.segments.SegmentSamples
    mu_values : array-like, shape (m,) or (m, n_c)
        Friction points: one shared coefficient per row, or one per contact.
    mode, competitors, force_margin
        As in :func:`guaranteed_sweep` (the margin binds the desired mode only).

    Returns
    -------
    BandSweep
        ``exact`` is False everywhere: sampling can only miss the worst friction, so the
        band is never narrower than the exact one and may be wider (unsafe).
    """
    mode = _mode(samples, mode)
    comps = admissible_competitors(samples.scenes, mode) if competitors is None else tuple(competitors)
    n_c = samples.scenes[0].n_contacts
    mus = np.asarray(mu_values, dtype=float)
    mus = np.repeat(mus[:, None], n_c, axis=1) if mus.ndim == 1 else mus
    if mus.ndim != 2 or mus.shape[1] != n_c or mus.shape[0] < 1 or not np.all(np.isfinite(mus)) or np.any(mus < 0):
        raise QsplanError(f"mu samples: expected nonnegative finite values, shape (m,) or (m, {n_c}); got shape {mus.shape}")
    n = len(samples)
    lower, upper, feas = np.full(n, -np.inf), np.full(n, np.inf), np.ones(n, dtype=bool)
    # effort_bands of the mode and of every competitor at every sample, batched over the samples
    des = map_batches(samples.scenes, lambda b: list(zip(*effort_bands_batch(b, mode, mus, force_margin=force_margin))))
    com = {c: map_batches(samples.scenes, lambda b, c=c: list(zip(*effort_bands_batch(b, c, mus)))) for c in comps}
    for k in range(n):
        l, u, ok = (a.copy() for a in des[k])
        for c in comps:
            cl, cu, cok = com[c][k]
            for j in np.flatnonzero(ok & cok):  # at each friction sample: the mode's band minus the competitor's
                l[j], u[j], _ = subtract_hull(l[j], u[j], cl[j], cu[j], 0.0)
        ok &= ~np.isnan(l)
        if not ok.all():
            feas[k] = False
            continue
        lower[k], upper[k] = float(np.max(l)), float(np.min(u))
        feas[k] = lower[k] <= upper[k]
    lower = np.where(feas, lower + 0.0, np.nan)
    upper = np.where(feas, upper + 0.0, np.nan)
    label = f"{mode.name} guaranteed by sampling {mus.shape[0]} friction values (the paper's method)"
    joint = samples.scenes[0].joint_names[samples.segment.effort_index]
    return BandSweep(label, mode.letters, joint, frozen_array(samples.t), frozen_array(lower), frozen_array(upper), frozen_array(feas),
                     frozen_array(np.zeros(n, dtype=bool)), "sampled", tuple([None] * n))  # fmt: skip


def narrowest(sweep: BandSweep):
    """``(index, width)`` of the narrowest feasible point of a band (the controller's torque resolution).

    Returns ``(None, nan)`` when no point has a band.
    """
    idx = np.flatnonzero(sweep.feasible)
    if not idx.size:
        return None, float("nan")
    k = int(idx[np.argmin(sweep.width[idx])])
    return k, float(sweep.width[k])

