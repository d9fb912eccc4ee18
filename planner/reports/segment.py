"""Figs. 10-13 for one segment, written out: the torque schedule, the figures and a summary document.

:func:`sweep_segment` is what ``qsplan sweep`` runs: it checks its outputs before computing
(nothing is overwritten without ``force``), computes the bands
(:func:`qsplan.planner.torque.sweep.segment_bands`), exports the schedule
(:func:`qsplan.planner.export.schedule.export_schedule`), draws the figures
(:func:`qsplan.planner.plotting.bands.segment_band_figures`) and returns the summary
(:func:`segment_document`): where bounds are infinite, where competitors are feasible, the
narrowest guaranteed band and how often the paper's sampled method is wider than the exact band.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from qsplan.planner.export.files import check_out_dir, check_outputs
from qsplan.planner.torque.sweep import (
    DEFAULT_MU_RANGE,
    PAPER_MU_SAMPLES,
    SegmentBands,
    narrowest,
    paper_method_wider,
    segment_bands,
)

__all__ = ["DEFAULT_TORQUE_RESOLUTION", "SEGMENT_FILES", "SEGMENT_PLOTS", "SweepRun", "segment_document", "segment_outputs", "sweep_segment"]

#: The torque resolution (N m) ``qsplan sweep`` sizes the command's margin with: the bundled tasks' controller.
DEFAULT_TORQUE_RESOLUTION = 0.02

#: The schedule files :func:`sweep_segment` writes.
SEGMENT_FILES = ("segment1.csv", "segment1.json")

#: Its figures (``<name>.png``) unless ``plots=False``.
SEGMENT_PLOTS = ("fig10_frictionless", "fig11_mu_high", "fig12_competitors", "fig13_guaranteed", "hand_strip")


@dataclass(frozen=True, slots=True, eq=False)
class SweepRun:
    """What :func:`sweep_segment` did: the bands, the files written and the summary document."""

    bands: SegmentBands
    files: tuple
    document: dict


def segment_outputs(out_dir, plots: bool = True) -> list:
    """The paths :func:`sweep_segment` writes into ``out_dir``."""
    out = Path(out_dir)
    return [out / f for f in SEGMENT_FILES] + ([out / f"{n}.png" for n in SEGMENT_PLOTS] if plots else [])


def _runs(runs):
    return [[round(a, 9), round(b, 9)] for a, b in runs]


def _narrow(sweep):
    k, w = narrowest(sweep)
    if k is None:
        return None
    return {"t": float(sweep.t[k]), "width": w, "lower": float(sweep.lower[k]), "upper": float(sweep.upper[k])}


def segment_document(sb: SegmentBands, paper_samples: int, files=(), resolution=None) -> dict:
    """The summary of Figs. 10-13 for one segment (the ``qsplan sweep --json`` document).

    Efforts in N m, times in s; ``paper_method.wider_than_exact_points`` counts the samples where the
    paper's sampled band reaches outside the exact one (:func:`qsplan.planner.torque.sweep.paper_method_wider`).
    """
    from qsplan.mechanics.bands.effort import check_force_margin
    from qsplan.mechanics.modes.contact_mode import ContactMode

    S = sb.samples
    seg = S.segment
    g = sb.guaranteed
    band = g.band
    comps = {}
    for c, sw in sb.competitors_at_high_mu.items():
        comps[c] = {"name": f"{ContactMode(c).kind} ({ContactMode(c).name})", "feasible_at_mu_high": _runs(sw.feasible_spans())}
    return {
        "segment": seg.name, "duration": seg.duration, "samples": len(S), "mode": band.mode,
        "effort_joint": seg.effort_joint, "velocity_joint": S.scenes[0].joint_names[seg.velocity_index],
        "mu_range": list(g.mu_range), "shared_mu": g.shared,
        "competitors": comps,
        "frictionless_upper_infinite": _runs(sb.frictionless.infinite_upper_spans()),
        "mu_high_upper_infinite": _runs(sb.at_high_mu.infinite_upper_spans()),
        "guaranteed": {"exact": bool(band.exact[band.feasible].all()), "points_without_band": int((~band.feasible).sum()),
                       "split_points": int(g.split.sum()), "narrowest": _narrow(band)},
        "paper_method": {"samples": paper_samples, "narrowest": _narrow(sb.sampled),
                         "wider_than_exact_points": int(paper_method_wider(sb).sum())},
        "safety_margin": sb.safety_margin, "max_margin": sb.max_margin, "torque_resolution": resolution,
        "force_margin": check_force_margin(g.force_margin).to_dict(),
        "command_max": float(np.nanmax(sb.command)) if np.isfinite(sb.command).any() else None,
        "files": [str(f) for f in files],
    }  # fmt: skip


def sweep_segment(samples, out_dir, mu_range=DEFAULT_MU_RANGE, *, shared: bool = False,
                  paper_samples: int = PAPER_MU_SAMPLES, safety_margin=None, max_margin=None, display_limit=None,
                  force: bool = False, plots: bool = True, workers=None, scheduler=None,
                  force_margin=None, resolution=DEFAULT_TORQUE_RESOLUTION) -> SweepRun:  # fmt: skip
    """Compute Figs. 10-13 for a sampled segment and write the schedule and figures into ``out_dir``.

    Parameters as in :func:`qsplan.planner.torque.sweep.segment_bands` (``force_margin``: the minimum
    normal force and Coulomb slack, N, of the guaranteed and sampled bands, default none);
    ``display_limit`` (N m) truncates the plotted bands (default per figure); ``force`` overwrites
    existing files (checked before computing).  The command follows the plans' rule
    (:func:`qsplan.planner.torque.command.with_segment_command`): one margin along the whole
    segment, half the narrowest band and at most two torque resolutions (``resolution``, N m),
    unless ``safety_margin`` / ``max_margin`` (N m) set it.
    """
    from qsplan.planner.torque.command import with_segment_command

    out = check_out_dir(out_dir)
    check_outputs(segment_outputs(out, plots), force)
    sb = segment_bands(samples, tuple(mu_range), shared, paper_samples, safety_margin, max_margin,
                       workers=workers, scheduler=scheduler, force_margin=force_margin)  # fmt: skip
    sb = with_segment_command(sb, resolution, safety_margin, max_margin)
    from qsplan.planner.export.schedule import export_schedule

    files = [str(p) for p in export_schedule(sb, out, force=True, resolution=resolution)]
    if plots:
        from qsplan.planner.plotting.bands import segment_band_figures
        from qsplan.planner.plotting.style import save_figure

        for name, fig in segment_band_figures(sb, display_limit).items():
            path = f"{out_dir}/{name}.png"
            save_figure(fig, path, option="out_dir")
            files.append(path)
    return SweepRun(sb, tuple(files), segment_document(sb, paper_samples, files, resolution))
