"""The torque command inside a guaranteed band (Section 5.2): the effort with the largest margin.

The paper notes that "the narrowest portion of the region specifies the resolution
of the torque controller"; the command exported for a controller sits where a
torque error is least likely to leave the band.
"""

from __future__ import annotations

import numpy as np

from qsplan.mechanics.errors import NoAnswerError, QsplanError

__all__ = ["choose_command", "default_safety_margin"]


def choose_command(lower, upper, safety_margin, max_margin=None):
    """The effort with the largest margin inside each band.

    * bounded band: the midpoint, margin = half the width; with ``max_margin``, a band
      wider than twice it gets ``lower + max_margin`` instead (no torque far above the
      one the mode needs: near a blow-up of the upper edge the midpoint runs away);
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
    with np.errstate(invalid="ignore"):
        half = 0.5 * (upper - lower)
        if max_margin is not None:
            half = np.minimum(half, max_margin)
        command = np.select(
            [lo_f & up_f, lo_f & np.isposinf(upper), np.isneginf(lower) & up_f, np.isneginf(lower) & np.isposinf(upper)],
            [lower + half, lower + safety_margin, upper - safety_margin, 0.0],
            np.nan,
        )
        margin = np.select(
            [lo_f & up_f, lo_f ^ up_f, np.isneginf(lower) & np.isposinf(upper)],
            [half, np.full_like(lower, safety_margin), np.full_like(lower, np.inf)],
            np.nan,
        )
    return command + 0.0, margin


def default_safety_margin(band) -> float:
    """The safety margin (N m) for a band along a segment: half its narrowest bounded width.

    The narrowest point sets the torque resolution the controller needs anyway (Fig. 13),
    so keeping that margin from a finite edge where the band is unbounded asks nothing
    more of it.  With no bounded point, the largest finite edge (the size of the
    torque the mode needs); with none, :class:`qsplan.mechanics.NoAnswerError` (no band to size it from).

    Parameters
    ----------
    band : qsplan.planner.torque.pointwise.BandSweep
    """
    w = band.width
    bounded = band.feasible & np.isfinite(w) & (w > 0)
    if bounded.any():
        return 0.5 * float(np.min(w[bounded]))
    edges = np.abs(np.concatenate([band.lower[np.isfinite(band.lower)], band.upper[np.isfinite(band.upper)]]))
    if edges.size and edges.max() > 0:
        return float(edges.max())  # no bounded point: the size of the effort the mode needs
    raise NoAnswerError("safety margin: no bounded band along the segment to size it from; pass one explicitly")
