"""The torque command inside a guaranteed band (Section 5.2): the effort with the largest margin.

The paper notes that "the narrowest portion of the region specifies the resolution
of the torque controller"; the command exported for a controller sits where a
torque error is least likely to leave the band.  :data:`PLAN_FORCE_MARGIN` keeps the
band itself away from the brink of eq. (28) for what the torque does not cover.
"""

from __future__ import annotations

import numpy as np

from qsplan.mechanics.bands.effort import ForceMargin
from qsplan.mechanics.errors import NoAnswerError, QsplanError

__all__ = ["PLAN_FORCE_MARGIN", "choose_command", "default_safety_margin", "plan_force_margin"]

#: The force margin of plans (task files' ``[controller] min_normal_force`` and
#: ``min_coulomb_slack``), N.  At a band edge of eq. (28) some normal force or cone slack is
#: zero, and near steep edges the model's normal forces are a few mN: any load the model
#: leaves out lifts that contact.  The torque error is covered by the band's width (the
#: command sits mid-band, at least the torque resolution wide); the margin covers the
#: rest.  0.05 N is 2.5 % of the demo workpiece's weight (0.2 kg, 1.96 N): the weight of
#: a 5 g mass error, or the inertial force of the workpiece accelerating at 0.25 m/s^2
#: (reaching the 0.01 m/s default speed limit in 40 ms), and ten times the few mN seen
#: near steep edges.  It costs the demo little: its narrowest guaranteed band goes from
#: 0.164 to 0.139 N m (normal forces change by ~2-4 N per N m of finger torque there),
#: still seven times the 0.02 N m torque resolution.
#: The slack margin binds only rolling contacts (the planner's 4S mode has none: a sliding
#: contact is on its cone's edge by definition, eq. 17).
PLAN_FORCE_MARGIN = ForceMargin(normal=0.05, slack=0.05)


def plan_force_margin(min_normal_force=None, min_coulomb_slack=None, field: str = "controller") -> ForceMargin:
    """A plan's :class:`ForceMargin` (N), :data:`PLAN_FORCE_MARGIN`'s value where one is not given.

    Errors name ``<field>.min_normal_force`` / ``<field>.min_coulomb_slack`` (the task file's keys).
    """
    values = []
    for name, v, default in (("min_normal_force", min_normal_force, PLAN_FORCE_MARGIN.normal),
                             ("min_coulomb_slack", min_coulomb_slack, PLAN_FORCE_MARGIN.slack)):  # fmt: skip
        v = default if v is None else v
        try:
            x = float(v) if not isinstance(v, (bool, str)) else np.nan
        except OverflowError:  # an integer of hundreds of digits
            x = np.inf
        except (TypeError, ValueError):
            x = np.nan
        if not (np.isfinite(x) and x >= 0):
            text = repr(v) if len(repr(v)) <= 40 else repr(v)[:20] + "..."
            raise QsplanError(f"{field}.{name}: expected a nonnegative finite force (N); got {text}")
        values.append(x)
    return ForceMargin(*values)


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
