"""Everything Figs. 10-13 and the export need for one segment, in chunks over the samples (Section 5.2).

:func:`segment_bands` runs the sweeps of :mod:`qsplan.planner.torque.pointwise` (Figs. 10-12 at
points, Fig. 13 exact and by the paper's sampled method) and chooses the command
(:func:`qsplan.planner.torque.command.choose_command`); consecutive ranges of samples go to
local processes or a Dask cluster (:func:`qsplan.mechanics.parallel.map_chunks`), and every
sample is computed alone, so the result is the same however it was split.  The pointwise
sweeps are re-exported here, so this module is the one to import.
:func:`paper_method_wider` says where the paper's sampled band is wider (unsafe) than the exact one.
"""

from __future__ import annotations

from dataclasses import dataclass, fields, replace

import numpy as np

from qsplan.mechanics.bands.effort import check_force_margin
from qsplan.mechanics.bands.robust import TOUCH_RTOL
from qsplan.mechanics.errors import QsplanError
from qsplan.mechanics.modes.contact_mode import ContactMode, enumerate_modes
from qsplan.mechanics.parallel import chunk_count, map_chunks, split_range

from qsplan.planner.torque.command import choose_command, default_safety_margin
from qsplan.planner.torque.pointwise import (
    DEFAULT_MU_RANGE,
    PAPER_MU_SAMPLES,
    BandSweep,
    GuaranteedSweep,
    admissible_competitors,
    check_mu_range,
    frozen_array,
    guaranteed_sweep,
    narrowest,
    point_band_sweep,
    sampled_guaranteed_sweep,
)

__all__ = [
    "DEFAULT_MU_RANGE",
    "MIN_CHUNK_KINEMATIC_SAMPLES",
    "MIN_CHUNK_SAMPLES",
    "PAPER_MU_SAMPLES",
    "TOUCH_RTOL",
    "BandSweep",
    "GuaranteedSweep",
    "SegmentBands",
    "competing_modes",
    "guaranteed_sweep",
    "narrowest",
    "paper_method_wider",
    "point_band_sweep",
    "sampled_guaranteed_sweep",
    "segment_bands",
]

#: Fewest samples worth a chunk of their own in :func:`segment_bands`: one core does
#: ~2,700 samples/s of segment 1 (all five sweeps, batched over the samples; ~600 with one
#: shared coefficient), so 200 are ~0.1 s, several times a local pool's start-up.
MIN_CHUNK_SAMPLES = 200


#: The same for :func:`competing_modes` (~40,000 samples/s on one core, batched).
MIN_CHUNK_KINEMATIC_SAMPLES = 4000


@dataclass(frozen=True, slots=True, eq=False)
class SegmentBands:
    """Everything Figs. 10-13 and the export need for one segment.

    Attributes
    ----------
    samples : qsplan.hands.paper_hand.segments.SegmentSamples
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


def _admissible_modes(job) -> set:
    """Modes other than ``letters`` kinematically admissible at one of ``scenes`` (one chunk, batched)."""
    scenes, letters = job
    return set(admissible_competitors(scenes, ContactMode(letters)))


def competing_modes(samples, mode=None, *, workers=None, scheduler=None) -> tuple:
    """Modes of the segment's control partition, other than ``mode``, kinematically admissible at some sample.

    The partition (one effort-controlled joint) fixes ``2 n_R + n_S = 4`` (eq. 29); a mode
    whose kinematics fail (eqs. 24-25, 16) at a sample is infeasible there for every
    effort and friction, so only these can compete.  ``workers`` and ``scheduler`` as in
    :func:`segment_bands` (chunks of at least :data:`MIN_CHUNK_KINEMATIC_SAMPLES`).
    """
    letters = samples.segment.mode if mode is None else (mode.letters if isinstance(mode, ContactMode) else str(mode).upper())
    mode = ContactMode(letters)
    n_chunks = chunk_count(len(samples), MIN_CHUNK_KINEMATIC_SAMPLES, workers=workers, scheduler=scheduler)
    jobs = [(samples.scenes[a:b], mode.letters) for a, b in split_range(len(samples), n_chunks)]
    found = set().union(*map_chunks(_admissible_modes, jobs, workers=workers, scheduler=scheduler))
    scene0 = samples.scenes[0]
    return tuple(m.letters for m in enumerate_modes(scene0.n_contacts, scene0.dof) if m.letters in found)


def _sample_range(samples, lo: int, hi: int):
    """Samples ``lo <= k < hi`` of a sampled segment, as a sampled segment."""
    per_sample = [f.name for f in fields(samples) if f.name != "segment"]
    return replace(samples, **{name: getattr(samples, name)[lo:hi] for name in per_sample})


def _concat_sweeps(parts) -> BandSweep:
    """One BandSweep from sweeps of consecutive sample ranges (label, mode and method from the first)."""
    cat = lambda name: frozen_array(np.concatenate([getattr(p, name) for p in parts]))  # noqa: E731
    return replace(parts[0], t=cat("t"), lower=cat("lower"), upper=cat("upper"), feasible=cat("feasible"),
                   exact=cat("exact"), reasons=tuple(r for p in parts for r in p.reasons))  # fmt: skip


def _bands_chunk(job):
    """The pointwise sweeps of :func:`segment_bands` on one range of samples."""
    samples, lo, hi, shared, paper_samples, mode, comps, force_margin = job
    frictionless = point_band_sweep(samples, 0.0, mode, f"{mode.name}, frictionless (mu = 0)")
    at_hi = point_band_sweep(samples, hi, mode, f"{mode.name}, mu = {hi:g}")
    comp_hi = {c: point_band_sweep(samples, hi, c, f"{ContactMode(c).name} ({c}), mu = {hi:g}") for c in comps}
    guaranteed = guaranteed_sweep(samples, (lo, hi), shared, mode, comps, force_margin=force_margin)
    sampled = sampled_guaranteed_sweep(samples, np.linspace(lo, hi, int(paper_samples)), mode, comps,
                                       force_margin=force_margin)  # fmt: skip
    return frictionless, at_hi, comp_hi, guaranteed, sampled


def _merge_chunks(parts):
    """:func:`_bands_chunk` results of consecutive sample ranges, as one."""
    if len(parts) == 1:
        return parts[0]
    frictionless, at_hi, comp_hi, guaranteed, sampled = zip(*parts)
    g0 = guaranteed[0]
    hulls = {c: tuple(frozen_array(np.concatenate([g.competitors[c][i] for g in guaranteed])) for i in (0, 1))
             for c in g0.competitors}  # fmt: skip
    merged_g = replace(g0, band=_concat_sweeps([g.band for g in guaranteed]),
                       desired=_concat_sweeps([g.desired for g in guaranteed]), competitors=hulls,
                       split=frozen_array(np.concatenate([g.split for g in guaranteed])))  # fmt: skip
    return (_concat_sweeps(frictionless), _concat_sweeps(at_hi),
            {c: _concat_sweeps([d[c] for d in comp_hi]) for c in comp_hi[0]}, merged_g, _concat_sweeps(sampled))  # fmt: skip


def segment_bands(samples, mu_range=DEFAULT_MU_RANGE, shared=False, paper_samples=PAPER_MU_SAMPLES,
                  safety_margin=None, max_margin=None, *, workers=None, scheduler=None,
                  force_margin=None) -> SegmentBands:  # fmt: skip
    """Figs. 10-13 for a sampled segment, and the command to export.

    Parameters
    ----------
    samples : qsplan.hands.paper_hand.segments.SegmentSamples
    mu_range : (float, float)
        Friction uncertainty ``[lo, hi]``; Figs. 11-12 use ``hi``.
    shared : bool
        One coefficient for all contacts (else independent per contact, a box).
    paper_samples : int
        Friction values of the paper's sampled method, evenly spaced on the range (21: 0, 0.01, ..., 0.2).
    safety_margin : float, optional
        N m; default :func:`qsplan.planner.torque.command.default_safety_margin`.
    max_margin : float, optional
        N m; cap on the command's margin (default none: the midpoint of every bounded band).
    force_margin : ForceMargin or (float, float), optional
        Minimum normal force and Coulomb slack (N) of Fig. 13's bands, exact and sampled
        (:class:`qsplan.mechanics.bands.effort.ForceMargin`; default none: eq. 28 as is).
    workers : int or None
        Local processes for chunks of consecutive samples (``None``: all cores, 1:
        in-process); fewer than ``2 * MIN_CHUNK_SAMPLES`` samples stay in-process.
    scheduler : str or dask.distributed.Client, optional
        Send the chunks to a Dask cluster instead (:func:`qsplan.mechanics.parallel.map_chunks`).
        Every sample is computed alone, so the result is the same however it was split.  The pointwise
sweeps are re-exported here, so this module is the one to import.
    """
    lo, hi = check_mu_range(*mu_range)
    if isinstance(paper_samples, bool) or not isinstance(paper_samples, (int, np.integer)) or paper_samples < 1:
        raise QsplanError(f"paper samples: expected a positive integer; got {paper_samples!r}")
    force_margin = None if force_margin is None else check_force_margin(force_margin)
    mode = ContactMode(samples.segment.mode)
    comps = competing_modes(samples, mode, workers=workers, scheduler=scheduler)
    n_chunks = chunk_count(len(samples), MIN_CHUNK_SAMPLES, workers=workers, scheduler=scheduler)
    jobs = [(_sample_range(samples, a, b) if n_chunks > 1 else samples, lo, hi, shared, paper_samples, mode, comps,
             force_margin) for a, b in split_range(len(samples), n_chunks)]  # fmt: skip
    parts = map_chunks(_bands_chunk, jobs, workers=workers, scheduler=scheduler)
    frictionless, at_hi, comp_hi, guaranteed, sampled = _merge_chunks(parts)
    band = guaranteed.band
    if safety_margin is None:
        safety_margin = default_safety_margin(band) if band.feasible.any() else 1.0
    if max_margin is not None:
        max_margin = max(float(max_margin), float(safety_margin))
    command, margin = choose_command(band.lower, band.upper, safety_margin, max_margin)
    return SegmentBands(samples, frictionless, at_hi, comp_hi, guaranteed, sampled, frozen_array(command), frozen_array(margin),
                        float(safety_margin), max_margin)  # fmt: skip


def paper_method_wider(bands: SegmentBands) -> np.ndarray:
    """Samples where the paper's sampled band reaches outside the exact guaranteed band, shape (n,) of bool.

    There the sampled method (friction values on a grid) misses the worst friction and would
    command an effort that does not guarantee the mode.  Edges within :data:`TOUCH_RTOL`
    (relative) of each other count as equal.
    """
    band, s = bands.guaranteed.band, bands.sampled
    both = band.feasible & s.feasible
    with np.errstate(invalid="ignore"):
        tol = TOUCH_RTOL * np.maximum(1.0, np.abs(band.lower))
        return both & ((s.lower < band.lower - tol) | (s.upper > band.upper + tol))
