"""The certifier's band checks: every exported band is a claim, recomputed from the task (issue 21).

An in-contact row exports the torque-controlled joint's guaranteed band ``[tau_<j>_min, tau_<j>_max]`` and the
command's ``margin``.  :func:`recomputed_bands` recomputes the band at the row's scene (rebuilt from the task:
:func:`qsplan.planner.certify.modes.row_scene`) with the mechanics' batched
:func:`~qsplan.mechanics.bands.batched_robust.robust_bands` (the answers of :func:`qsplan.mechanics.robust_band`):
the planned mode feasible for every friction in the task's set with the task's force margin, every
competitor precluded (all the modes admissible at the row, not the planner's list); :func:`band_checks`
compares.  A row is refused when

* ``band``: no such band exists there, or the exported band reaches beyond the recomputed one (by more than
  :data:`BAND_RTOL`; a recomputation that is only conservative proves nothing beyond itself), or the exported
  band is narrower than the task's torque resolution (the controller cannot hold it);
* ``margin``: the ``margin`` cell is not the command's distance to the nearer exported edge, or that distance
  is under half the torque resolution (a controller holding the command to within half its resolution would
  leave the band; the command rule keeps at least that, :func:`qsplan.planner.torque.command.default_safety_margin`).

Since the command lies in a band proved for the whole friction set, the planned mode is the only feasible one
for every friction in the set, not only at the points the mode check samples.  Units: N m (N for a prismatic joint).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["BAND_RTOL", "band_checks", "free_row_cells", "hold_band", "recomputed_bands"]

#: Relative excess (of the larger finite edge, at least 1 N m) tolerated of an exported band edge over the
#: recomputed one.  Planner and certifier compute the band with the same equations from scenes that agree to
#: ~1e-12 m (the closed-form grasp against the polygon search); the bundled plans' edges agree bit for bit.
#: 1e-9 N m is three orders below the finest torque resolution a task may ask (1e-6 N m).
BAND_RTOL = 1e-9


def _fmt(v) -> str:
    return f"{v:.6g}" if math.isfinite(v) else ("-inf" if v < 0 else "inf")


def recomputed_bands(task, cols, scenes: dict) -> dict:
    """``{row: RobustBand}``: the guaranteed band of every in-contact row's scene (``scenes``: ``{row: Scene}``),
    every competitor precluded, for the task's friction set and force margin.

    :func:`qsplan.mechanics.bands.batched_robust.robust_bands` batches the rows of one mode (the same answers as
    :func:`qsplan.mechanics.robust_band` row by row, bit for bit: ``tests/mechanics/test_bands_batched.py``).
    """
    from qsplan.mechanics.bands.batched_robust import robust_bands

    from qsplan.planner.certify.contacts import hold_row

    groups = {}
    for k in scenes:
        groups.setdefault(str(cols["mode"][k]), []).append(k)
    out = {}
    for mode, rows in groups.items():
        if all(hold_row(cols, k) for k in rows):  # a hold: its band is the proved hold interval
            out.update((k, hold_band(task, scenes[k])) for k in rows)
            continue
        bands = robust_bands([scenes[k] for k in rows], mode, task.mu_range, shared=task.shared_mu,
                             force_margin=task.force_margin, disturbance=task.disturbance)  # fmt: skip
        out.update(zip(rows, bands))
    return out


def hold_band(task, scene):
    """A hold row's band recomputed: the torques at which a hold is proved with every contact loaded by at least the
    task's force margin, at every vertex of the disturbance box (:func:`qsplan.mechanics.bands.hold.
    hold_torque_interval`; exact: the proved set is an interval), in :func:`band_checks`' terms."""
    from types import SimpleNamespace

    from qsplan.mechanics.bands.hold import hold_torque_interval

    lo, hi = hold_torque_interval(scene, task.disturbance, margin=task.force_margin.normal)
    ok = not (np.isnan(lo) or np.isnan(hi))
    return SimpleNamespace(feasible=ok, lower=lo, upper=hi, exact=True,
                           reason=None if ok else "no torque proves the hold (no frictionless equilibrium with every "
                                                  "contact loaded by the force margin)")  # fmt: skip


def band_checks(task, cols, k, rb) -> list:
    """The exported band and margin of in-contact row ``k`` against ``rb``, its recomputation (:func:`recomputed_bands`)."""
    e = str(cols["effort_joint"][k])
    tau, lo, hi = (float(cols[f"tau_{e}{s}"][k]) for s in ("", "_min", "_max"))
    if not (math.isfinite(tau) and not math.isnan(lo) and not math.isnan(hi)):
        return []  # no command or band: the torque check names it
    unit = task.hand.joint_unit(e, "tau") if e in task.hand.joint_names else "N m"
    out = []
    if not rb.feasible:
        out.append(("band", f"no guaranteed band exists here (recomputed: {rb.reason}); the file claims "
                            f"[{_fmt(lo)}, {_fmt(hi)}] {unit}"))  # fmt: skip
    else:
        finite = [abs(v) for v in (rb.lower, rb.upper, lo, hi) if math.isfinite(v)]
        tol = BAND_RTOL * max(finite + [1.0])
        if lo < rb.lower - tol or hi > rb.upper + tol:
            how = "" if rb.exact else f" (recomputed conservatively: {rb.reason})"
            out.append(("band", f"the exported band [{_fmt(lo)}, {_fmt(hi)}] {unit} reaches beyond the guaranteed band "
                                f"[{_fmt(rb.lower)}, {_fmt(rb.upper)}] {unit} recomputed from the task{how}"))  # fmt: skip
    if not hi - lo >= task.torque_resolution * (1 - 1e-12):
        out.append(("band", f"the exported band [{_fmt(lo)}, {_fmt(hi)}] {unit} is {hi - lo:.3g} {unit} wide, narrower "
                            f"than the torque resolution {task.torque_resolution:g}"))  # fmt: skip
    slack = min(tau - lo, hi - tau)
    margin = float(cols["margin"][k]) if "margin" in cols else math.nan
    tol = BAND_RTOL * max([abs(v) for v in (tau, lo, hi) if math.isfinite(v)] + [1.0])
    if not (math.isfinite(margin) and abs(margin - slack) <= tol):
        out.append(("margin", f"margin {float(margin)!r} {unit}; the command {tau:.6g} {unit} is {_fmt(slack)} {unit} from the "
                              "nearer band edge"))  # fmt: skip
    if slack < 0.5 * task.torque_resolution - tol and lo <= tau <= hi:
        out.append(("margin", f"the command {tau:.6g} {unit} is {slack:.3g} {unit} from its band's edge, less than half "
                              f"the torque resolution ({task.torque_resolution:g})"))  # fmt: skip
    return out


def free_row_cells(cols, k, names) -> list:
    """A free (regrasp) row commands every joint's velocity and no effort: no ``tau``, band or margin cell."""
    out = []
    filled = [n for n in names if any(not np.isnan(cols[f"tau_{n}{s}"][k]) for s in ("", "_min", "_max"))]
    if filled:
        out.append(("input", f"a regrasp row with an effort or band for {', '.join(filled)} (every joint is "
                             "velocity-controlled there)"))  # fmt: skip
    if "margin" in cols and not np.isnan(cols["margin"][k]):
        out.append(("input", f"a regrasp row with a margin {float(cols['margin'][k])!r}"))
    if str(cols["effort_joint"][k]) != "none":
        out.append(("input", f"a regrasp row names effort_joint {str(cols['effort_joint'][k])!r}; expected none"))
    return out
