"""The torque command inside a guaranteed band (Section 5.2): one margin kept along the whole segment.

The paper notes that "the narrowest portion of the region specifies the resolution
of the torque controller"; the command exported for a controller keeps one margin
``m`` from both band edges along the whole segment (:func:`segment_command`, the rule of
plans and of ``qsplan sweep``): ``lower + m`` where the band is wider than ``2 m``, its
midpoint where it is not, so the command is continuous and close to the torque the mode
needs.  ``m`` is half the segment's narrowest band (the largest margin that holds
everywhere), at most :data:`MAX_MARGIN_RESOLUTIONS` torque resolutions
(:func:`default_safety_margin`): a very wide band buys no more than that.
:data:`qsplan.planner.task.fields.PLAN_FORCE_MARGIN` keeps the band itself away from the brink of
eq. (28) for what the torque does not cover.
"""

from __future__ import annotations

import numpy as np

from qsplan.mechanics.errors import NoAnswerError, QsplanError

__all__ = ["COMMAND_STEP", "MAX_MARGIN_RESOLUTIONS", "choose_command", "command_rule", "default_safety_margin",
           "plan_command", "segment_command", "smooth_command", "with_segment_command"]

#: Largest change of a pivot's torque command between two rows, as a fraction of its largest command: the
#: transition's band starts at ~4 N m and the 4S bands fall to a tenth of it within a few degrees; hugging the lower
#: edge would step 0.45 N m in the first 0.25 deg.  5 % keeps every step under a tenth of the command.
COMMAND_STEP = 0.05

#: The largest margin (in torque resolutions) a command keeps from its band's edges.  A plan
#: accepts a band one resolution wide (the command mid-band, half a resolution from each
#: edge): that is the torque error the controller is trusted with.  Two resolutions are four
#: times it; beyond that a wider band would only raise the command (and the contact forces)
#: far above the torque the mode needs: the demo's third segment, whose narrowest band is
#: 1.76 N m wide, would command ~0.93 N m where its lower edge asks ~0.05 N m.
MAX_MARGIN_RESOLUTIONS = 2.0

def choose_command(lower, upper, safety_margin, max_margin=None):
    """The effort with the largest margin inside each band.

    * bounded band: the midpoint, margin = half the width; with ``max_margin``, a band
      wider than twice it gets ``max_margin`` inside the edge nearer zero instead (no torque far beyond the one
      the mode needs: near a blow-up of the far edge the midpoint runs away): ``lower + max_margin`` in a segment
      that pushes with positive efforts, ``upper - max_margin`` in one that pushes with negative efforts (its bands
      unbounded below and nowhere unbounded above, a finger squeezing whose lower edge blows up; or, bounded
      everywhere, their midpoints' median negative).  The edge is the same along the segment, so the command stays
      continuous where an unbounded edge becomes finite; and the rule is the mirror image of itself (an effort's
      sign flipped, the command's is);
    * unbounded above (below): ``lower + safety_margin`` (``upper - safety_margin``), margin = ``safety_margin``
      (a midpoint does not exist);
    * unbounded on both sides: 0, margin inf;
    * no band (NaN edges): NaN, NaN.

    Parameters
    ----------
    lower, upper : array-like, shape (n,)
        N m or N.
    safety_margin : float
        Positive (N m or N).
    max_margin : float, optional
        Positive (N m or N), at least ``safety_margin``.

    Returns
    -------
    command, margin : ndarray, shape (n,)
    """
    lower = np.asarray(lower, dtype=float)
    upper = np.asarray(upper, dtype=float)
    if not (np.isfinite(safety_margin) and safety_margin > 0):
        raise QsplanError(f"safety margin: expected a positive finite effort (N m or N); got {safety_margin!r}")
    if max_margin is not None and not (np.isfinite(max_margin) and max_margin >= safety_margin):
        raise QsplanError(f"max margin: expected a finite effort of at least the safety margin {safety_margin:g}; "
                          f"got {max_margin!r}")  # fmt: skip
    lo_f, up_f = np.isfinite(lower), np.isfinite(upper)
    bounded = lo_f & up_f
    if np.any(np.isinf(lower)) or np.any(np.isinf(upper)):
        from_upper = bool(np.any(np.isneginf(lower) & up_f)) and not np.any(np.isposinf(upper))
    else:  # bounded everywhere: the side of zero the bands lie on (their midpoints' median)
        from_upper = bool(bounded.any() and np.median(0.5 * (lower[bounded] + upper[bounded])) < 0.0)
    with np.errstate(invalid="ignore"):
        half = 0.5 * (upper - lower)
        if max_margin is not None:
            half = np.minimum(half, max_margin)
        command = np.select(
            [lo_f & up_f, lo_f & np.isposinf(upper), np.isneginf(lower) & up_f, np.isneginf(lower) & np.isposinf(upper)],
            [upper - half if from_upper else lower + half, lower + safety_margin, upper - safety_margin, 0.0],
            np.nan,
        )
        margin = np.select(
            [lo_f & up_f, lo_f ^ up_f, np.isneginf(lower) & np.isposinf(upper)],
            [half, np.full_like(lower, safety_margin), np.full_like(lower, np.inf)],
            np.nan,
        )
    return command + 0.0, margin


def segment_command(lower, upper, safety_margin, max_margin=None):
    """The command of a whole segment: one margin kept from both band edges everywhere (the plans' rule).

    :func:`choose_command` with ``max_margin`` defaulting to ``safety_margin``: ``lower + m``
    where the band is wider than ``2 m``, the midpoint where it is narrower, ``lower + m``
    (``upper - m``) where it is unbounded above (below).  With ``m`` at most half the
    segment's narrowest band (:func:`default_safety_margin`) the margin ``m`` holds at every
    sample and the command is continuous; it never runs up a blown-up upper edge.

    Parameters and returns as :func:`choose_command`.
    """
    return choose_command(lower, upper, safety_margin, safety_margin if max_margin is None else max_margin)


def command_rule(safety_margin, max_margin=None, resolution=None) -> dict:
    """The command rule in words and numbers, for export metadata (N m).

    Parameters
    ----------
    safety_margin : float
        The margin kept where the band is unbounded on one side.
    max_margin : float or None
        The cap on the margin of bounded bands (None: midpoints).
    resolution : float, optional
        The controller's torque resolution the margin was sized with.
    """
    if max_margin is None:
        rule = ("midpoint of a bounded band; lower + safety_margin where unbounded above (upper - safety_margin "
                "where unbounded below); 0 where unbounded on both sides")
    else:
        rule = ("one margin m = max_margin kept from both edges along the whole segment: m inside the edge nearer "
                "zero where the band is wider than 2 m (lower + m in a segment pushing with positive efforts, upper - "
                "m in one pushing with negative efforts), its midpoint where it is narrower; lower + safety_margin "
                "where unbounded above (upper - safety_margin where unbounded below); m = min(half the segment's "
                f"narrowest band, {MAX_MARGIN_RESOLUTIONS:g} torque resolutions) unless given")
    out = {"rule": rule, "safety_margin_N_m": float(safety_margin),
           "max_margin_N_m": None if max_margin is None else float(max_margin)}  # fmt: skip
    if resolution is not None:
        out.update(torque_resolution_N_m=float(resolution), max_margin_resolutions=MAX_MARGIN_RESOLUTIONS)
    return out


def default_safety_margin(band, resolution=None) -> float:
    """The margin (N m) a command keeps along a segment: half its narrowest bounded band, at most
    :data:`MAX_MARGIN_RESOLUTIONS` times ``resolution``.

    The narrowest point sets the torque resolution the controller needs anyway (Fig. 13),
    so keeping that margin from a finite edge where the band is unbounded asks nothing
    more of it; with ``resolution`` (the controller's, N m) a very wide band keeps no more
    than a few resolutions, so the command stays near the torque the mode needs.  With
    no bounded point, the largest finite edge (the size of the torque the mode needs), at least half the
    resolution and capped alike; with none, :class:`qsplan.mechanics.NoAnswerError` (no band to size it from).

    Parameters
    ----------
    band : qsplan.planner.torque.pointwise.BandSweep
    resolution : float, optional
        Positive (N m or N): the controller's torque resolution.
    """
    if resolution is not None and not (np.isfinite(resolution) and resolution > 0):
        raise QsplanError(f"torque resolution: expected a positive finite effort (N m or N); got {resolution!r}")
    cap = np.inf if resolution is None else MAX_MARGIN_RESOLUTIONS * float(resolution)
    w = band.width
    bounded = band.feasible & np.isfinite(w) & (w > 0)
    if bounded.any():
        return min(0.5 * float(np.min(w[bounded])), cap)
    edges = np.abs(np.concatenate([band.lower[np.isfinite(band.lower)], band.upper[np.isfinite(band.upper)]]))
    if edges.size and edges.max() > 0:
        # no bounded point: the size of the effort the mode needs, but at least half the resolution (a controller
        # holding the command to within half its resolution stays in the band; the certifier checks it)
        floor = 0.0 if resolution is None else 0.5 * float(resolution)
        return min(max(float(edges.max()), floor), cap)
    raise NoAnswerError("safety margin: no bounded band along the segment to size it from; pass one explicitly")


def plan_command(lower, upper, resolution, feasible=None) -> tuple:
    """A planned segment's command and margin from its band arrays (N m or N, shape (n,)): the margin sized by
    :func:`default_safety_margin` (the torque ``resolution`` where no band along it is bounded), kept from both
    edges (:func:`segment_command`).  ``feasible``: where a band exists (default everywhere)."""
    from types import SimpleNamespace

    lower, upper = np.asarray(lower, float), np.asarray(upper, float)
    ok = np.ones(lower.shape, bool) if feasible is None else np.asarray(feasible, bool)
    try:
        m = default_safety_margin(SimpleNamespace(lower=lower, upper=upper, width=upper - lower, feasible=ok), resolution)
    except NoAnswerError:  # unbounded everywhere: keep the controller's resolution from the finite edge
        m = float(resolution)
    return segment_command(lower, upper, m)


def with_segment_command(bands, resolution=None, safety_margin=None, max_margin=None):
    """``bands`` with the plans' command (:func:`segment_command`) in place of its own.

    Parameters
    ----------
    bands : qsplan.planner.torque.sweep.SegmentBands
    resolution : float, optional
        The controller's torque resolution (N m): caps the default margin (:func:`default_safety_margin`).
    safety_margin : float, optional
        The margin ``m`` (N m); default :func:`default_safety_margin` of the guaranteed band.
    max_margin : float, optional
        A larger cap on bounded bands' margin (N m); default ``m``.

    Returns
    -------
    qsplan.planner.torque.sweep.SegmentBands
        With ``command``, ``margin``, ``safety_margin`` and ``max_margin`` replaced.
    """
    from dataclasses import replace

    band = bands.guaranteed.band
    if safety_margin is None:
        try:
            safety_margin = default_safety_margin(band, resolution)
        except NoAnswerError:  # unbounded everywhere: keep the controller's resolution from the finite edge
            safety_margin = 1.0 if resolution is None else float(resolution)
    cap = float(safety_margin) if max_margin is None else max(float(max_margin), float(safety_margin))
    command, margin = segment_command(band.lower, band.upper, float(safety_margin), cap)
    command.setflags(write=False)
    margin.setflags(write=False)
    return replace(bands, command=command, margin=margin, safety_margin=float(safety_margin), max_margin=cap)


def smooth_command(command, margin, lower, upper):
    """The slide's command (:func:`qsplan.planner.torque.command.plan_command`: ``margin`` from the nearer edge)
    with its steps between rows cut to :data:`COMMAND_STEP` of its largest value: where the band is open above (a pivot's,
    after the transition's steep lower edge) it comes down gradually instead of hugging the lower edge, never nearer
    an edge than the slide's rule keeps it.  Returns ``(command, margin)``, the margin to the nearer edge per row."""
    floor = np.where(np.isfinite(lower), lower + margin, -np.inf)
    ceil = np.where(np.isfinite(upper), upper - margin, np.inf)
    step = COMMAND_STEP * (float(np.max(np.abs(command))) + float(np.min(margin)))
    out = command.copy()
    for k in range(1, out.size):  # forward: come down (or up) from the previous row by at most a step
        out[k] = np.clip(out[k], out[k - 1] - step, out[k - 1] + step)
    for k in range(out.size - 2, -1, -1):  # backward: anticipate a rise of the floor
        out[k] = max(out[k], out[k + 1] - step)
    out = np.minimum(np.maximum(out, floor), ceil)  # the rule's margin first: never nearer an edge
    return out, np.minimum(out - lower, upper - out)
