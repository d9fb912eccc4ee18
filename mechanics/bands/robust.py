"""The guaranteed band of one scene with every competing mode precluded (Section 5.2, Fig. 13).

For the single effort-controlled joint of a scene and friction anywhere in an
uncertainty set (each contact's coefficient in ``[lo, hi]``, or one shared
coefficient), :func:`robust_band` returns the efforts that

1. keep the desired mode feasible for every friction in the set (its guaranteed band:
   :func:`qsplan.mechanics.bands.effort.guaranteed_band_box`, vertex theory, or
   :func:`qsplan.mechanics.bands.effort.guaranteed_band_shared`, polynomial roots), and
2. make every competing mode infeasible for every friction in the set: each competitor's
   possibly-feasible efforts inside that band (:func:`qsplan.mechanics.bands.preclusion.competitor_torques`,
   branch and bound) are cut out; where a competitor's hull lies strictly inside, the larger
   piece is kept.

With a ``disturbance`` (a box of external wrenches on the workpiece, :mod:`qsplan.mechanics.bands.disturbance`)
both hold for every wrench of the box as well.

This is the one implementation: the band sweeps along a segment
(:func:`qsplan.planner.torque.pointwise.guaranteed_sweep`) call it at every sample.  Efforts
are N m (revolute) or N (prismatic); unbounded sides are ``inf``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qsplan.mechanics.bands.disturbance import WrenchBox, check_wrench_box
from qsplan.mechanics.bands.effort import Band, band_kinematics
from qsplan.mechanics.bands.guaranteed import guaranteed_band_box, guaranteed_band_shared
from qsplan.mechanics.bands.preclusion import CompetitorTorques, competitor_torques
from qsplan.mechanics.errors import QsplanError
from qsplan.mechanics.model.friction import check_mu_range
from qsplan.mechanics.modes.contact_mode import enumerate_modes, mode_from_letters
from qsplan.mechanics.modes.kinematics import check_mode_fits
from qsplan.mechanics.numerics import Status

__all__ = ["TOUCH_RTOL", "RobustBand", "admissible_competitors", "assemble_robust_band", "robust_band", "subtract_hull"]

#: Relative distance (of the band's largest finite edge, or 1 N m) within which a
#: competitor's possible efforts only touch the desired mode's band: the two modes
#: share that boundary (eq. 28 holding with equality for both), which cuts nothing.
#: Band edges carry rounding of ~1e-14 relative; 1e-9 is far above it and far below
#: any torque resolution, and a competitor that reaches further in is cut out.
TOUCH_RTOL = 1e-9


@dataclass(frozen=True, slots=True, eq=False)
class RobustBand:
    """A guaranteed band with every competitor precluded, for one scene.

    Attributes
    ----------
    mode : str
        The desired mode's letters.
    lower, upper : float
        Band edges (N m or N), ``-inf`` / ``inf`` for unbounded sides; NaN when ``feasible`` is False.
    feasible : bool
    exact : bool
        Edges exact (to :data:`qsplan.mechanics.bands.preclusion.PRECLUSION_RTOL` where competitors
        were precluded); False where not proved, and ``reason`` says why: conservative (a competitor's
        search ran out of cells: narrower than the true band) or a competitor the solver cannot decide
        (ill-conditioned kinematics, named "undecided").
    split : bool
        A competitor's hull lay strictly inside the band: the larger piece was kept.
    desired : Band
        The desired mode's guaranteed band before precluding competitors.
    competitors : tuple of str
        The competing modes considered.
    precluded : dict of str to CompetitorTorques
        Per competitor possibly feasible inside ``desired``, its hull (the others are precluded there already).
    reason : str or None
        Why there is no band, or remarks (a competitor split the band, a conservative search).
    mu_range : (float, float)
    shared : bool
        One coefficient shared by all contacts (else each contact's independently).
    disturbance : WrenchBox or None
        The box of external wrenches the band withstands (:mod:`qsplan.mechanics.bands.disturbance`); None: none.
    """

    mode: str
    lower: float
    upper: float
    feasible: bool
    exact: bool
    split: bool
    desired: Band
    competitors: tuple
    precluded: dict
    reason: str | None
    mu_range: tuple
    shared: bool
    disturbance: WrenchBox | None = None

    @property
    def width(self) -> float:
        """``upper - lower`` (inf when unbounded, NaN without a band)."""
        return float(self.upper - self.lower) if self.feasible else float("nan")


def subtract_hull(lo, hi, c_lo, c_hi, atol):
    """``[lo, hi]`` minus ``[c_lo, c_hi]``: ``(lo', hi', split)``; NaN edges when nothing is left.

    A competitor that meets the band only at an edge (within ``atol``) leaves it whole:
    the edge is shared by both modes' boundaries, and the command keeps a margin from it.
    Where the hull lies strictly inside, the larger piece is kept and ``split`` is True.
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


def admissible_competitors(scenes, mode) -> tuple:
    """Modes other than ``mode`` kinematically admissible (eqs. 24-25, 16) at one of ``scenes``, in enumeration order.

    A mode whose kinematics fail is infeasible for every effort and friction, so only these can compete.
    """
    scene0 = scenes[0]
    mode = check_mode_fits(scene0, mode)
    return tuple(m.letters for m in enumerate_modes(scene0.n_contacts, scene0.dof)
                 if m.letters != mode.letters and any(band_kinematics(s, m).ok for s in scenes))  # fmt: skip


def check_mu_pair(mu_range):
    """``(lo, hi)`` of a friction range given as a pair, checked (:func:`qsplan.mechanics.model.friction.check_mu_range`)."""
    try:
        lo, hi = (float(v) for v in mu_range)
    except (TypeError, ValueError):
        raise QsplanError(f"mu range: expected (LO, HI); got {mu_range!r}") from None
    return check_mu_range(lo, hi)


def robust_band(scene, mode, mu_range, *, shared: bool = False, competitors=None, force_margin=None,
                disturbance=None) -> RobustBand:  # fmt: skip
    """The efforts that guarantee ``mode`` and preclude every competitor for all friction in the set
    (and every wrench of the disturbance box).

    Parameters
    ----------
    scene : Scene
        Exactly one effort-controlled joint.
    mode : ContactMode or str
        The desired mode.
    mu_range : (float, float)
        ``0 <= lo <= hi``: each contact's coefficient independently in ``[lo, hi]`` (a box), or with
        ``shared=True`` one coefficient for all contacts.
    shared : bool
    competitors : sequence of str, optional
        Competing modes; default :func:`admissible_competitors` of this scene.
    force_margin : ForceMargin or (float, float), optional
        Minimum normal force and Coulomb slack (N) the desired mode keeps for every friction in the set
        (:class:`qsplan.mechanics.bands.effort.ForceMargin`; competitors are precluded without one).
    disturbance : WrenchBox or (array-like, array-like), optional
        A box of external wrenches on the workpiece (N, N, N m, about the point of ``g_obj`` and added to it):
        the desired mode is kept and every competitor precluded for each one (exact or conservative and
        labelled, :mod:`qsplan.mechanics.bands.disturbance`).  None or zeros: no disturbance.

    Returns
    -------
    RobustBand

    Raises
    ------
    QsplanError
        Bad friction range or disturbance box, or the scene has not exactly one effort-controlled joint.

    References
    ----------
    Trinkle & Zeng (1995), Section 5.2 (Figs. 12-13), eq. 28.
    """
    lo, hi = check_mu_pair(mu_range)
    mode = check_mode_fits(scene, mode)
    box = check_wrench_box(disturbance)
    comps = admissible_competitors([scene], mode) if competitors is None else tuple(competitors)
    guaranteed = guaranteed_band_shared if shared else guaranteed_band_box
    desired = guaranteed(scene, mode, lo, hi, force_margin=force_margin, disturbance=box)
    torques = {}
    if desired.feasible:
        g_lo, g_hi = desired.lower + 0.0, desired.upper + 0.0  # + 0.0: no negative zero
        torques = {c: competitor_torques(scene, c, lo, hi, g_lo, g_hi, shared=shared, disturbance=box) for c in comps}
    return assemble_robust_band(mode, desired, comps, torques, (lo, hi), shared, box)


def assemble_robust_band(mode, desired: Band, comps, torques: dict, mu_range, shared, disturbance=None) -> RobustBand:
    """The :class:`RobustBand` from the desired mode's guaranteed band and each competitor's
    :class:`CompetitorTorques` inside it (``torques``: competitor letters to their hulls; empty
    when ``desired`` is infeasible).  The one place :func:`robust_band` and its batched twin
    (:func:`qsplan.mechanics.bands.batched_robust.robust_bands`) cut the competitors out.  ``disturbance``: the
    (checked) wrench box both were computed for, recorded.
    """
    mode = mode_from_letters(mode)
    common = dict(mode=mode.letters, desired=desired, competitors=tuple(comps), mu_range=tuple(mu_range), shared=bool(shared),
                  disturbance=disturbance)  # fmt: skip
    if not desired.feasible:
        return RobustBand(lower=np.nan, upper=np.nan, feasible=False, exact=bool(desired.exact), split=False,
                          precluded={}, reason=desired.reason, **common)  # fmt: skip
    g_lo, g_hi = desired.lower + 0.0, desired.upper + 0.0  # + 0.0: no negative zero
    finite = [abs(x) for x in (g_lo, g_hi) if np.isfinite(x)]
    atol = TOUCH_RTOL * max(finite + [1.0])
    exact, notes, hulls = bool(desired.exact), [], {}
    for c in comps:
        ct: CompetitorTorques = torques[c]
        if ct.empty:
            status = (ct.reason or "").removeprefix("kinematics: ")
            if status in Status.ILL_CONDITIONED:  # the solver cannot decide this mode either: not precluded
                exact = False
                notes.append(f"{c}: undecided ({status}), not precluded")
            continue
        hulls[c] = ct
        exact &= ct.exact
        if not ct.exact:
            notes.append(f"{c}: {ct.reason}")
    # subtract every competitor's hull from the desired mode's band (the hulls lie inside it)
    a, b, split = g_lo, g_hi, False
    for c in comps:
        if np.isnan(a):
            break
        if c not in hulls:
            continue
        a, b, cut = subtract_hull(a, b, hulls[c].lower, hulls[c].upper, atol)
        if cut:
            split = True
            notes.append(f"{c} possible inside the band: kept the larger piece")
    feasible = not np.isnan(a)
    if not feasible:
        notes.append("competitors possible over the whole band" + (" (with the disturbance box)" if disturbance is not None else ""))
        a = b = np.nan
    return RobustBand(lower=a, upper=b, feasible=feasible, exact=exact, split=split, precluded=hulls,
                      reason="; ".join(notes) or desired.reason, **common)  # fmt: skip
