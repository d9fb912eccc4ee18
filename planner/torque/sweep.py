"""Torque bands along a manipulation segment (Section 5.2, Figs. 10-13).

Pointwise along a sampled segment (:func:`hands.segments.sample_segment`), for
its single effort-controlled joint:

* :func:`point_band_sweep` - the band of one mode at one friction (Figs. 10-12);
* :func:`guaranteed_sweep` - the band that keeps the desired mode feasible for
  every friction in an uncertainty set and precludes every competing mode there
  (Fig. 13), exact: the desired mode's band by the vertex theory (box) or by
  polynomial roots (one shared coefficient), each competitor's possible efforts
  by branch and bound (:mod:`planner.preclusion`);
* :func:`sampled_guaranteed_sweep` - the paper's method: at each listed friction
  value the desired mode's band minus the competitors' bands, intersected over
  the list;
and :func:`segment_bands` runs all of them, with the command of
:mod:`planner.command`, for the figures and the export.  Efforts
are N m (revolute) or N (prismatic); unbounded sides are ``inf``, never a large
number; NaN marks points without a band.
"""

from __future__ import annotations

from dataclasses import dataclass, fields, replace

import numpy as np

from qsplan.mechanics.bands.effort import (
    band_kinematics,
    effort_band,
    guaranteed_band_box,
    guaranteed_band_shared,
)
from qsplan.mechanics.errors import QsplanError
from qsplan.mechanics.modes.contact_mode import ContactMode, enumerate_modes
from qsplan.mechanics.parallel import chunk_count, map_chunks, split_range

from qsplan.planner.torque.command import choose_command, default_safety_margin
from qsplan.mechanics.bands.preclusion import competitor_torques

__all__ = [
    "DEFAULT_MU_RANGE",
    "PAPER_MU_SAMPLES",
    "TOUCH_RTOL",
    "BandSweep",
    "GuaranteedSweep",
    "SegmentBands",
    "competing_modes",
    "guaranteed_sweep",
    "narrowest",
    "point_band_sweep",
    "sampled_guaranteed_sweep",
    "segment_bands",
]

#: The paper's friction uncertainty (Section 5.2): mu in [0, 0.2].
DEFAULT_MU_RANGE = (0.0, 0.2)

#: The paper's sampled friction values 0, 0.01, ..., 0.20: 21 of them.
PAPER_MU_SAMPLES = 21

#: Relative distance (of the band's largest finite edge, or 1 N m) within which a
#: competitor's possible efforts only touch the desired mode's band: the two modes
#: share that boundary (eq. 28 holding with equality for both), which cuts nothing.
#: Band edges carry rounding of ~1e-14 relative; 1e-9 is far above it and far below
#: any torque resolution, and a competitor that reaches further in is cut out.
TOUCH_RTOL = 1e-9

#: Fewest samples worth a chunk of their own in :func:`segment_bands`: one core does
#: ~100 samples/s of segment 1 (all five sweeps), so 12 are ~0.1 s, several times a
#: local pool's start-up.
MIN_CHUNK_SAMPLES = 12

#: The same for :func:`competing_modes` (~300 samples/s on one core).
MIN_CHUNK_KINEMATIC_SAMPLES = 30


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
        Edges exact (to :data:`planner.preclusion.PRECLUSION_RTOL` where competitors were precluded);
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
    """

    band: BandSweep
    desired: BandSweep
    competitors: dict
    split: np.ndarray
    mu_range: tuple
    shared: bool


@dataclass(frozen=True, slots=True, eq=False)
class SegmentBands:
    """Everything Figs. 10-13 and the export need for one segment.

    Attributes
    ----------
    samples : hands.segments.SegmentSamples
    frictionless : BandSweep
        Desired mode, mu = 0 (Fig. 10).
    at_high_mu : BandSweep
        Desired mode at the upper end of the friction range (Fig. 11).
    competitors_at_high_mu : dict of str to BandSweep
        Each competing mode at that friction (Fig. 12 shows the feasible ones).
    guaranteed : GuaranteedSweep
        Fig. 13, exact.
    sampled : BandSweep
        Fig. 13 by the paper's method (shared friction values).
    command : ndarray, shape (n,)
        Effort to command (N m or N), NaN without a guaranteed band.
    margin : ndarray, shape (n,)
        Distance from the command to the nearest band edge (N m or N).
    safety_margin : float
        The margin used where the band is unbounded on one side (see :func:`choose_command`).
    max_margin : float or None
        Cap on the margin of bounded bands (None: midpoints).
    """

    samples: object
    frictionless: BandSweep
    at_high_mu: BandSweep
    competitors_at_high_mu: dict
    guaranteed: GuaranteedSweep
    sampled: BandSweep
    command: np.ndarray
    margin: np.ndarray
    safety_margin: float
    max_margin: float | None = None


def _frozen(a):
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


def _sweep(label, mode, samples, bands, method) -> BandSweep:
    feas = np.array([b.feasible for b in bands])
    lower = np.array([b.lower + 0.0 if b.feasible else np.nan for b in bands])  # + 0.0: no negative zero
    upper = np.array([b.upper + 0.0 if b.feasible else np.nan for b in bands])
    exact = np.array([b.exact for b in bands])
    joint = samples.scenes[0].joint_names[samples.segment.effort_index]
    return BandSweep(label, mode.letters, joint, _frozen(samples.t), _frozen(lower), _frozen(upper), _frozen(feas),
                     _frozen(exact), method, tuple(b.reason for b in bands))  # fmt: skip


def _check_mu_range(lo, hi):
    if not (np.isfinite(lo) and np.isfinite(hi)) or lo < 0 or lo > hi:
        raise QsplanError(f"mu range: expected 0 <= LO <= HI (finite); got {lo} {hi}")
    return float(lo), float(hi)


def point_band_sweep(samples, mu, mode=None, label=None) -> BandSweep:
    """The band of ``mode`` (default the segment's) at friction ``mu`` at every sample (eq. 28).

    Parameters
    ----------
    samples : hands.segments.SegmentSamples
    mu : float or array-like, shape (n_c,)
    mode : str or ContactMode, optional
    label : str, optional
    """
    mode = _mode(samples, mode)
    mu_arr = np.broadcast_to(np.asarray(mu, dtype=float), (samples.scenes[0].n_contacts,))
    if not np.all(np.isfinite(mu_arr)) or np.any(mu_arr < 0):
        raise QsplanError(f"mu: expected nonnegative finite coefficients; got {mu!r}")
    bands = [effort_band(s, mode, mu_arr) for s in samples.scenes]
    if label is None:
        where = f"{mu_arr[0]:g}" if np.ptp(mu_arr) == 0 else str(mu_arr.tolist())
        label = f"{mode.name}, mu = {where}"
    return _sweep(label, mode, samples, bands, "point")


def _admissible_modes(job) -> set:
    """Modes other than ``letters`` kinematically admissible at one of ``scenes`` (one chunk)."""
    scenes, letters = job
    return {m.letters for m in enumerate_modes(scenes[0].n_contacts, scenes[0].dof)
            if m.letters != letters and any(band_kinematics(s, m).ok for s in scenes)}  # fmt: skip


def competing_modes(samples, mode=None, *, workers=None, scheduler=None) -> tuple:
    """Modes of the segment's control partition, other than ``mode``, kinematically admissible at some sample.

    The partition (one effort-controlled joint) fixes ``2 n_R + n_S = 4`` (eq. 29); a mode
    whose kinematics fail (eqs. 24-25, 16) at a sample is infeasible there for every
    effort and friction, so only these can compete.  ``workers`` and ``scheduler`` as in
    :func:`segment_bands` (chunks of at least :data:`MIN_CHUNK_KINEMATIC_SAMPLES`).
    """
    mode = _mode(samples, mode)
    n_chunks = chunk_count(len(samples), MIN_CHUNK_KINEMATIC_SAMPLES, workers=workers, scheduler=scheduler)
    jobs = [(samples.scenes[a:b], mode.letters) for a, b in split_range(len(samples), n_chunks)]
    found = set().union(*map_chunks(_admissible_modes, jobs, workers=workers, scheduler=scheduler))
    scene0 = samples.scenes[0]
    return tuple(m.letters for m in enumerate_modes(scene0.n_contacts, scene0.dof) if m.letters in found)


def _subtract(lo, hi, c_lo, c_hi, atol):
    """``[lo, hi]`` minus ``[c_lo, c_hi]``: ``(lo', hi', split)``; NaN edges when nothing is left.

    A competitor that meets the band only at an edge (within ``atol``) leaves it whole:
    the edge is shared by both modes' boundaries, and the command keeps a margin from it.
    """
    if np.isnan(c_lo) or c_hi <= lo + atol or c_lo >= hi - atol:
        return lo, hi, False
    left = (lo, c_lo) if c_lo > lo + atol else None
    right = (c_hi, hi) if c_hi < hi - atol else None
    if left and right:
        keep = right if right[1] - right[0] > left[1] - left[0] else left
        return keep[0], keep[1], True
    if left or right:
        return (left or right)[0], (left or right)[1], False
    return np.nan, np.nan, False


def guaranteed_sweep(samples, mu_range=DEFAULT_MU_RANGE, shared=False, mode=None, competitors=None) -> GuaranteedSweep:
    """The band guaranteeing ``mode`` and precluding every competitor for all friction in the set (Fig. 13).

    Parameters
    ----------
    samples : hands.segments.SegmentSamples
    mu_range : (float, float)
        ``0 <= lo <= hi``: each contact's coefficient independently in ``[lo, hi]``, or
        with ``shared=True`` one coefficient for all contacts.
    shared : bool
    mode : str, optional
        Default the segment's desired mode.
    competitors : sequence of str, optional
        Default :func:`competing_modes`.

    Returns
    -------
    GuaranteedSweep
        The final band is exact where its ``exact`` flag is set; a competitor whose
        hull splits the band leaves the larger piece (``split``).
    """
    lo, hi = _check_mu_range(*mu_range)
    mode = _mode(samples, mode)
    comps = competing_modes(samples, mode) if competitors is None else tuple(competitors)
    if shared:
        desired = [guaranteed_band_shared(s, mode, lo, hi) for s in samples.scenes]
    else:
        desired = [guaranteed_band_box(s, mode, lo, hi) for s in samples.scenes]
    method = desired[0].method
    where = f"mu in [{lo:g}, {hi:g}]" + (" (shared)" if shared else " (each contact)")
    dsweep = _sweep(f"{mode.name} guaranteed, {where}", mode, samples, desired, method)
    n = len(samples)
    hulls = {c: (np.full(n, np.nan), np.full(n, np.nan)) for c in comps}
    lower, upper = dsweep.lower.copy(), dsweep.upper.copy()
    feas, exact, split = dsweep.feasible.copy(), dsweep.exact.copy(), np.zeros(n, dtype=bool)
    reasons = list(dsweep.reasons)
    for k, scene in enumerate(samples.scenes):
        if not feas[k]:
            continue
        g_lo, g_hi = lower[k], upper[k]
        finite = [abs(x) for x in (g_lo, g_hi) if np.isfinite(x)]
        atol = TOUCH_RTOL * max(finite + [1.0])
        notes = []
        for c in comps:
            ct = competitor_torques(scene, c, lo, hi, g_lo, g_hi, shared=shared)
            if ct.empty:
                continue
            hulls[c][0][k], hulls[c][1][k] = ct.lower, ct.upper
            exact[k] &= ct.exact
            if not ct.exact:
                notes.append(f"{c}: {ct.reason}")
        # subtract every competitor's hull from the desired mode's band (the hulls lie inside it)
        a, b = g_lo, g_hi
        for c in comps:
            if np.isnan(a):
                break
            a, b, cut = _subtract(a, b, hulls[c][0][k], hulls[c][1][k], atol)
            if cut:
                split[k] = True
                notes.append(f"{c} possible inside the band: kept the larger piece")
        if np.isnan(a):
            feas[k] = False
            notes.append("competitors possible over the whole band")
        lower[k], upper[k] = (a, b) if feas[k] else (np.nan, np.nan)
        reasons[k] = "; ".join(notes) or reasons[k]
    band = BandSweep(f"{mode.name} guaranteed, competitors precluded, {where}", mode.letters, dsweep.joint,
                     dsweep.t, _frozen(lower), _frozen(upper), _frozen(feas), _frozen(exact), method,
                     tuple(reasons))  # fmt: skip
    hulls = {c: (_frozen(v[0]), _frozen(v[1])) for c, v in hulls.items()}
    return GuaranteedSweep(band, dsweep, hulls, _frozen(split), (lo, hi), bool(shared))


def sampled_guaranteed_sweep(samples, mu_values, mode=None, competitors=None) -> BandSweep:
    """The paper's method: at each listed friction, the mode's band minus the competitors', intersected.

    Parameters
    ----------
    samples : hands.segments.SegmentSamples
    mu_values : array-like, shape (m,) or (m, n_c)
        Friction points: one shared coefficient per row, or one per contact.
    mode, competitors
        As in :func:`guaranteed_sweep`.

    Returns
    -------
    BandSweep
        ``exact`` is False everywhere: sampling can only miss the worst friction, so the
        band is never narrower than the exact one and may be wider (unsafe).
    """
    mode = _mode(samples, mode)
    comps = competing_modes(samples, mode) if competitors is None else tuple(competitors)
    n_c = samples.scenes[0].n_contacts
    mus = np.asarray(mu_values, dtype=float)
    mus = np.repeat(mus[:, None], n_c, axis=1) if mus.ndim == 1 else mus
    if mus.ndim != 2 or mus.shape[1] != n_c or mus.shape[0] < 1 or not np.all(np.isfinite(mus)) or np.any(mus < 0):
        raise QsplanError(f"mu samples: expected nonnegative finite values, shape (m,) or (m, {n_c}); got shape {mus.shape}")
    from qsplan.mechanics.bands.effort import effort_bands

    n = len(samples)
    lower, upper, feas = np.full(n, -np.inf), np.full(n, np.inf), np.ones(n, dtype=bool)
    for k, scene in enumerate(samples.scenes):
        l, u, ok = effort_bands(scene, mode, mus)
        for c in comps:
            cl, cu, cok = effort_bands(scene, c, mus)
            for j in np.flatnonzero(ok & cok):  # at each friction sample: the mode's band minus the competitor's
                l[j], u[j], _ = _subtract(l[j], u[j], cl[j], cu[j], 0.0)
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
    return BandSweep(label, mode.letters, joint, _frozen(samples.t), _frozen(lower), _frozen(upper), _frozen(feas),
                     _frozen(np.zeros(n, dtype=bool)), "sampled", tuple([None] * n))  # fmt: skip


def narrowest(sweep: BandSweep):
    """``(index, width)`` of the narrowest feasible point of a band (the controller's torque resolution).

    Returns ``(None, nan)`` when no point has a band.
    """
    idx = np.flatnonzero(sweep.feasible)
    if not idx.size:
        return None, float("nan")
    k = int(idx[np.argmin(sweep.width[idx])])
    return k, float(sweep.width[k])


def _sample_range(samples, lo: int, hi: int):
    """Samples ``lo <= k < hi`` of a sampled segment, as a sampled segment."""
    per_sample = [f.name for f in fields(samples) if f.name != "segment"]
    return replace(samples, **{name: getattr(samples, name)[lo:hi] for name in per_sample})


def _concat_sweeps(parts) -> BandSweep:
    """One BandSweep from sweeps of consecutive sample ranges (label, mode and method from the first)."""
    cat = lambda name: _frozen(np.concatenate([getattr(p, name) for p in parts]))  # noqa: E731
    return replace(parts[0], t=cat("t"), lower=cat("lower"), upper=cat("upper"), feasible=cat("feasible"),
                   exact=cat("exact"), reasons=tuple(r for p in parts for r in p.reasons))  # fmt: skip


def _bands_chunk(job):
    """The pointwise sweeps of :func:`segment_bands` on one range of samples."""
    samples, lo, hi, shared, paper_samples, mode, comps = job
    frictionless = point_band_sweep(samples, 0.0, mode, f"{mode.name}, frictionless (mu = 0)")
    at_hi = point_band_sweep(samples, hi, mode, f"{mode.name}, mu = {hi:g}")
    comp_hi = {c: point_band_sweep(samples, hi, c, f"{ContactMode(c).name} ({c}), mu = {hi:g}") for c in comps}
    guaranteed = guaranteed_sweep(samples, (lo, hi), shared, mode, comps)
    sampled = sampled_guaranteed_sweep(samples, np.linspace(lo, hi, int(paper_samples)), mode, comps)
    return frictionless, at_hi, comp_hi, guaranteed, sampled


def _merge_chunks(parts):
    """:func:`_bands_chunk` results of consecutive sample ranges, as one."""
    if len(parts) == 1:
        return parts[0]
    frictionless, at_hi, comp_hi, guaranteed, sampled = zip(*parts)
    g0 = guaranteed[0]
    hulls = {c: tuple(_frozen(np.concatenate([g.competitors[c][i] for g in guaranteed])) for i in (0, 1))
             for c in g0.competitors}  # fmt: skip
    merged_g = replace(g0, band=_concat_sweeps([g.band for g in guaranteed]),
                       desired=_concat_sweeps([g.desired for g in guaranteed]), competitors=hulls,
                       split=_frozen(np.concatenate([g.split for g in guaranteed])))  # fmt: skip
    return (_concat_sweeps(frictionless), _concat_sweeps(at_hi),
            {c: _concat_sweeps([d[c] for d in comp_hi]) for c in comp_hi[0]}, merged_g, _concat_sweeps(sampled))  # fmt: skip


def segment_bands(samples, mu_range=DEFAULT_MU_RANGE, shared=False, paper_samples=PAPER_MU_SAMPLES,
                  safety_margin=None, max_margin=None, *, workers=None, scheduler=None) -> SegmentBands:  # fmt: skip
    """Figs. 10-13 for a sampled segment, and the command to export.

    Parameters
    ----------
    samples : hands.segments.SegmentSamples
    mu_range : (float, float)
        Friction uncertainty ``[lo, hi]``; Figs. 11-12 use ``hi``.
    shared : bool
        One coefficient for all contacts (else independent per contact, a box).
    paper_samples : int
        Friction values of the paper's sampled method, evenly spaced on the range (21: 0, 0.01, ..., 0.2).
    safety_margin : float, optional
        N m; default :func:`planner.command.default_safety_margin`.
    max_margin : float, optional
        N m; cap on the command's margin (default none: the midpoint of every bounded band).
    workers : int or None
        Local processes for chunks of consecutive samples (``None``: all cores, 1:
        in-process); fewer than ``2 * MIN_CHUNK_SAMPLES`` samples stay in-process.
    scheduler : str or dask.distributed.Client, optional
        Send the chunks to a Dask cluster instead (:func:`mechanics.parallel.map_chunks`).
        Every sample is computed alone, so the result is the same however it was split.
    """
    lo, hi = _check_mu_range(*mu_range)
    if isinstance(paper_samples, bool) or not isinstance(paper_samples, (int, np.integer)) or paper_samples < 1:
        raise QsplanError(f"paper samples: expected a positive integer; got {paper_samples!r}")
    mode = _mode(samples, None)
    comps = competing_modes(samples, mode, workers=workers, scheduler=scheduler)
    n_chunks = chunk_count(len(samples), MIN_CHUNK_SAMPLES, workers=workers, scheduler=scheduler)
    jobs = [(_sample_range(samples, a, b) if n_chunks > 1 else samples, lo, hi, shared, paper_samples, mode, comps)
            for a, b in split_range(len(samples), n_chunks)]  # fmt: skip
    parts = map_chunks(_bands_chunk, jobs, workers=workers, scheduler=scheduler)
    frictionless, at_hi, comp_hi, guaranteed, sampled = _merge_chunks(parts)
    band = guaranteed.band
    if safety_margin is None:
        safety_margin = default_safety_margin(band) if band.feasible.any() else 1.0
    if max_margin is not None:
        max_margin = max(float(max_margin), float(safety_margin))
    command, margin = choose_command(band.lower, band.upper, safety_margin, max_margin)
    return SegmentBands(samples, frictionless, at_hi, comp_hi, guaranteed, sampled, _frozen(command), _frozen(margin),
                        float(safety_margin), max_margin)  # fmt: skip

