"""The pivot formation swept densely, with its guaranteed 4S bands and its events located (issue 23).

:func:`sweep_pivot` samples the pivot manifold (:func:`qsplan.hands.reorient.pivot_configurations`) from the flush
instant (theta = 0) down to an end angle, builds each sample's four-contact scene (the left finger's two contacts
follow the flush overlap's ends, :func:`qsplan.hands.contact_sets.flush_contacts`), computes the 4S band of each
torque-controlled finger with :func:`qsplan.mechanics.robust_band` (every admissible competitor precluded, the friction
box and force margin given) and locates the events by bisection (:data:`EVENT_TOL`):

* geometric, from the closed form: a workpiece vertex passing a fingertip or a finger's base, the centre of mass over
  the pivot vertex, the right finger flush on an edge at its vertex, the pivot leaving the palm, another vertex
  reaching the palm, a joint limit;
* a contact's sliding direction reversing (:func:`slip_speeds`: it rolls for an instant, where 4S does not hold);
* the band of a torque-controlled finger falling below the torque resolution, and closing (no band at all).

Events marked ``ends`` end the formation (a contact made or lost, a limit): the sweep stops at the first.  Each sample's
contact set is also checked against the mechanics' polygon search (:func:`polygon_contacts`, the reference).  Units SI
(m, rad, N m, s).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from qsplan.hands.contact_sets import ContactSet, locate_contacts
from qsplan.hands.found_contacts import polygon_contacts
from qsplan.hands.formations import formation
from qsplan.hands.reorient import PIVOT_FORMATION, THETA_RATE, paper_form, pivot_configurations, pivot_contacts, pivot_scene
from qsplan.mechanics.errors import QsplanError, SceneError
from qsplan.mechanics.model.geometry import CONTACT_TOL

__all__ = ["DEFAULT_RESOLUTION", "EVENT_TOL", "SWEEP_END", "SWEEP_STEP", "PivotBands", "PivotEvent", "PivotSweep",
           "geometric_events", "locate_event", "pivot_band", "polygon_contacts", "same_contacts", "slip_events", "slip_speeds",
           "sweep_pivot"]

#: Bracket (rad) to which :func:`locate_event` bisects an event's angle: 5.7e-5 deg, far below the sweep's step.
EVENT_TOL = 1e-6

#: The sweep's step (rad): 0.25 deg, some 220 samples over the pivot (~6 s of bands on this machine).
SWEEP_STEP = np.radians(0.25)

#: The default end of the sweep (rad): -55 deg, just past the right finger lying flush on edge 1->2 (-54.85 deg)
#: for the demo's hand and workpiece; the sweep stops earlier at the first event that ends the formation.
SWEEP_END = np.radians(-55.0)

#: The default torque resolution (N m) below which a band's width is an event: the bundled tasks' controller's.
DEFAULT_RESOLUTION = 0.02


@dataclass(frozen=True, slots=True)
class PivotEvent:
    """An event of the pivot: ``name`` (a key), ``theta`` (rad, to :data:`EVENT_TOL`), ``description`` (words),
    ``ends`` (whether the formation ends there)."""

    name: str
    theta: float
    description: str
    ends: bool


@dataclass(frozen=True, slots=True, eq=False)
class PivotBands:
    """One torque-controlled finger's robust 4S band at every sample (N m): ``lower``, ``upper`` (+-inf unbounded,
    nan without a band), ``exact`` (bool) and ``reason`` (str or None) per sample, shape (n,)."""

    effort_joint: str
    lower: np.ndarray
    upper: np.ndarray
    exact: np.ndarray
    reason: tuple

    @property
    def width(self) -> np.ndarray:
        """``upper - lower`` (inf unbounded, 0 without a band), shape (n,)."""
        w = self.upper - self.lower
        return np.where(np.isnan(w), 0.0, w)


@dataclass(frozen=True, slots=True, eq=False)
class PivotSweep:
    """The pivot formation swept (:func:`sweep_pivot`).

    Attributes
    ----------
    configurations : PivotConfigurations
        The samples up to the formation's end.
    contacts : tuple of ContactSet
        Each sample's contact set, located.
    agrees : ndarray of bool, shape (n,)
        The polygon search finds exactly that contact set (:func:`same_contacts`).
    bands : dict of str to PivotBands
        By torque-controlled finger.
    events : tuple of PivotEvent
        In the order they occur (theta decreasing).
    seconds : dict of str to float
        Wall time of the manifold, the bands and the events.
    """

    configurations: object
    contacts: tuple
    agrees: np.ndarray
    bands: dict
    events: tuple
    seconds: dict


def same_contacts(found: ContactSet, reference, tol: float = CONTACT_TOL) -> bool:
    """Whether ``reference`` (:func:`polygon_contacts`) is the contact set ``found``: as many contacts, each of
    ``found`` matching one of the same body within ``tol`` (m) in its point and normal."""
    if len(reference) != len(found.specs):
        return False
    return all(any(c.body == link and np.hypot(*(c.point - p)) <= tol and np.hypot(*(c.normal - n)) <= tol
                   for c in reference) for p, n, link in zip(found.points, found.normals, found.links))  # fmt: skip


def geometric_events(hand, configurations, limits=None) -> dict:
    """The geometric event functions at the configurations: ``{name: (description, ends, g)}`` with ``g`` shape (n,);
    an event lies where ``g`` changes sign.

    Parameters
    ----------
    configurations : PivotConfigurations
    limits : array-like, shape (2, 2), optional
        Joint ranges (rad), left then right, rows ``(lo, hi)``; None: no limit events.
    """
    paper = paper_form(hand)
    c = configurations
    W, L, k = c.vertices, paper.finger_length, len(paper.workpiece)
    lo, hi, p, r = (c.edge + 1) % k, c.edge, c.pivot, c.right_vertex
    u = np.stack([np.cos(c.q), np.sin(c.q)], axis=-1)  # (n, 2 fingers, 2)

    def along(vertex, finger):
        return np.sum((W[:, vertex] - paper.pivots[finger]) * u[:, finger], axis=1)

    out = {
        "left_tip": (f"v{hi} passes the left fingertip", False, L - along(hi, 0)),
        "left_base": (f"v{lo} passes the left finger's base", True, along(lo, 0)),
        "com": (f"the centre of mass over v{p}", False, c.pose[:, 0] - W[:, p, 0]),
        "right_tip": (f"v{r} passes the right fingertip", True, L - along(r, 1)),
        "right_base": (f"v{r} passes the right finger's base", True, along(r, 1)),
        "palm_end": (f"v{p} leaves the palm's top", True, paper.palm_halfwidth - np.abs(W[:, p, 0])),
    }
    for a, b in (((r - 1) % k, r), (r, (r + 1) % k)):
        d = W[:, b] - W[:, a]
        out[f"right_flush_{a}{b}"] = (f"the right finger flush on edge {a}->{b}", True,
                                      (u[:, 1, 0] * d[:, 1] - u[:, 1, 1] * d[:, 0]) / np.hypot(d[:, 0], d[:, 1]))
    for j in range(k):
        if j != p:
            out[f"palm_v{j}"] = (f"v{j} reaches the palm", True, W[:, j, 1])
    if limits is not None:
        for f, side in enumerate(("left", "right")):
            out[f"limit_{side}_lo"] = (f"the {side} joint at its lower limit {limits[f][0]:g} rad", True,
                                       c.q[:, f] - limits[f][0])
            out[f"limit_{side}_hi"] = (f"the {side} joint at its upper limit {limits[f][1]:g} rad", True,
                                       limits[f][1] - c.q[:, f])
    return out


def slip_speeds(hand, configurations) -> np.ndarray:
    """Each contact's sliding speed per unit turning rate along the manifold (m/rad), shape (n, n_c): eq. 6's
    ``W_t^T nu - J_t thetadot`` with the manifold's tangent (``d pose/d theta``, ``d q/d theta``).  Where one changes
    sign that contact's sliding direction reverses: for an instant it rolls, and 4S does not hold (eq. 16)."""
    c = configurations
    out = []
    for i in range(len(c.theta)):
        scene = pivot_scene(hand, c, i)
        nu = np.array([c.dpose[i, 0] + c.dpose[i, 2] * c.pose[i, 1], c.dpose[i, 1] - c.dpose[i, 2] * c.pose[i, 0],
                       c.dpose[i, 2]])  # the twist at the world origin  # fmt: skip
        out.append(scene.Wt.T @ nu - scene.Jt @ c.dq[i])
    return np.array(out)


def _first_crossing(g) -> int | None:
    """The first sample whose sign is opposite to (or zero after) the first nonzero sample's; None if none."""
    s = np.sign(np.nan_to_num(g, nan=-1.0))
    nonzero = np.flatnonzero(s)
    if nonzero.size == 0:
        return None
    after = np.flatnonzero(s[nonzero[0]:] != s[nonzero[0]])
    return None if after.size == 0 else int(nonzero[0] + after[0])


def slip_events(hand, configurations) -> list:
    """Each contact's first reversal of its sliding direction along ``configurations`` (:func:`slip_speeds`),
    bisected to :data:`EVENT_TOL`: :class:`PivotEvent` ``slip_<contact>`` (not ending the formation: the 4S phase
    does), in contact order."""
    c = configurations
    args = (c.pivot, c.edge, c.right_vertex)
    slips = slip_speeds(hand, c)
    out = []
    for j, name in enumerate(formation(PIVOT_FORMATION).contact_names):
        i = _first_crossing(slips[:, j])
        if i is not None:
            at = locate_event(lambda t, j=j: slip_speeds(hand, pivot_configurations(hand, [t], *args))[0, j],
                              c.theta[i - 1], c.theta[i])  # fmt: skip
            words = f"contact {name} stops sliding (its sliding direction reverses: it rolls for an instant, 4S breaks)"
            out.append(PivotEvent(f"slip_{name}", at, words, False))
    return out


def locate_event(f, a: float, b: float, tol: float = EVENT_TOL) -> float:
    """Bisection of a sign change of the scalar ``f`` between angles ``a`` (before it) and ``b`` (at or after it)
    to a bracket of ``tol`` (rad); the bracket's midpoint."""
    fa = np.sign(f(a))
    while abs(b - a) > tol:
        mid = 0.5 * (a + b)
        if np.sign(f(mid)) == fa:
            a = mid
        else:
            b = mid
    return 0.5 * (a + b)


def _band(scene, mu_range, force_margin, shared):
    """The robust band of the pivot formation's mode (4S)."""
    from qsplan.mechanics.bands.robust import robust_band

    return robust_band(scene, formation(PIVOT_FORMATION).mode, mu_range, shared=shared, force_margin=force_margin)


def pivot_band(hand, theta: float, effort_joint: str, mu_range, force_margin=None, shared: bool = False,
               theta_rate: float = THETA_RATE, pivot: int = 1, edge=None, right_vertex: int = 2):  # fmt: skip
    """The robust band of the pivot's mode (4S, :func:`qsplan.mechanics.robust_band`) at angle
    ``theta`` (rad), ``effort_joint`` torque-controlled: a :class:`qsplan.mechanics.RobustBand`."""
    c = pivot_configurations(hand, [theta], pivot, edge, right_vertex)
    return _band(pivot_scene(hand, c, 0, effort_joint, theta_rate), mu_range, force_margin, shared)


def _limits(hand, limits):
    if limits is None:
        limits = getattr(getattr(hand, "description", None), "joint_limits", None)
        if limits is None:
            return None
    arr = np.asarray(limits, dtype=float)
    if arr.shape != (2, 2) or not np.all(np.isfinite(arr)) or np.any(arr[:, 0] >= arr[:, 1]):
        raise QsplanError(f"limits: expected [[lo, hi], [lo, hi]] (rad, lo < hi) for the left and right joints; "
                          f"got {limits!r}")  # fmt: skip
    return arr


def sweep_pivot(hand, mu_range, force_margin=None, resolution: float = DEFAULT_RESOLUTION,
                effort_joints=("right", "left"), limits=None, theta_end: float = SWEEP_END, step: float = SWEEP_STEP,
                shared: bool = False, theta_rate: float = THETA_RATE, pivot: int = 1, edge=None,
                right_vertex: int = 2) -> PivotSweep:  # fmt: skip
    """The pivot formation from the flush instant (theta = 0) down to ``theta_end``, or its first ending event.

    Parameters
    ----------
    hand
        A paper-form hand.
    mu_range : (float, float)
        Each contact's friction coefficient in ``[lo, hi]`` (``shared``: one for all).
    force_margin : ForceMargin or (float, float), optional
        N (:class:`qsplan.mechanics.ForceMargin`).
    resolution : float
        N m: the controller's torque resolution; a band narrower than it is an event.
    effort_joints : sequence of {"left", "right"}
        The torque-controlled fingers to band, each separately (the other driven at its manifold rate).
    limits : array-like, shape (2, 2), optional
        Joint ranges (rad); default the hand description's, if any.
    theta_end, step : float
        rad: the end (negative) and the sampling step (positive).
    theta_rate, pivot, edge, right_vertex
        As :func:`qsplan.hands.reorient.pivot_configurations` and :func:`~qsplan.hands.reorient.pivot_scene`.

    Returns
    -------
    PivotSweep
    """
    if not (np.isfinite(theta_end) and theta_end < 0 and np.isfinite(step) and 0 < step <= -theta_end):
        raise QsplanError(f"theta_end, step: expected theta_end < 0 and 0 < step <= -theta_end (rad); got {theta_end!r}, "
                          f"{step!r}")  # fmt: skip
    if not (np.isfinite(resolution) and resolution >= 0):
        raise QsplanError(f"resolution: expected a nonnegative torque (N m); got {resolution!r}")
    limits = _limits(hand, limits)
    started = time.perf_counter()
    n = int(round(-theta_end / step)) + 1
    theta = np.linspace(0.0, theta_end, n)
    args = (pivot, edge, right_vertex)
    c = pivot_configurations(hand, theta, *args)
    geo = geometric_events(hand, c, limits)
    events = []
    for name, (words, ends, g) in geo.items():
        i = _first_crossing(g)
        if i is not None:
            at = locate_event(lambda t, name=name: geometric_events(hand, pivot_configurations(hand, [t], *args),
                                                                    limits)[name][2][0], theta[i - 1], theta[i])  # fmt: skip
            events.append(PivotEvent(name, at, words, ends))
    end = max([e.theta for e in events if e.ends], default=theta_end)
    keep = np.flatnonzero(theta > end) if end > theta_end else np.arange(n)
    c = pivot_configurations(hand, theta[keep], *args)
    located, agrees = [], np.zeros(len(keep), dtype=bool)
    for i in range(len(keep)):
        contacts = pivot_contacts(hand, c.pose[i], c.q[i], *args)
        located.append(locate_contacts(hand, c.pose[i], c.q[i], contacts))
        try:
            agrees[i] = same_contacts(located[-1], polygon_contacts(hand, c.pose[i], c.q[i]))
        except SceneError:
            agrees[i] = False
    events += slip_events(hand, c)
    manifold = time.perf_counter() - started
    bands = {}
    for ej in effort_joints:
        rows = [_band(pivot_scene(hand, c, i, ej, theta_rate), mu_range, force_margin, shared) for i in range(len(keep))]
        bands[ej] = PivotBands(ej, np.array([b.lower for b in rows]), np.array([b.upper for b in rows]),
                               np.array([b.exact for b in rows]), tuple(b.reason for b in rows))  # fmt: skip
    banded = time.perf_counter() - started - manifold
    for ej, b in bands.items():
        narrow = f"the {ej}-torque band narrower than {resolution:g} N m"
        for name, g, words in ((f"band_{ej}", b.width - resolution, narrow),
                               (f"band_closed_{ej}", np.where(np.isnan(b.lower), -1.0, 1.0), f"no {ej}-torque band")):
            i = _first_crossing(g)
            if i is not None:
                closed = name.startswith("band_closed")

                def f(t, ej=ej, closed=closed):
                    rb = pivot_band(hand, t, ej, mu_range, force_margin, shared, theta_rate, *args)
                    return (1.0 if rb.feasible else -1.0) if closed else (rb.width if rb.feasible else 0.0) - resolution

                events.append(PivotEvent(name, locate_event(f, c.theta[i - 1], c.theta[i]), words, False))
    seconds = {"manifold": manifold, "bands": banded, "band events": time.perf_counter() - started - manifold - banded}
    return PivotSweep(c, tuple(located), agrees, bands, tuple(sorted(events, key=lambda e: -e.theta)), seconds)
