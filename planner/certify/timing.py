"""The certifier's time-scaling checks: stops, accelerations and the inertial load (issue 24).

The plan's rows are timed by one rule (:mod:`qsplan.planner.plan.timing`): every phase starts and ends at rest;
between two rows of a phase the speed scale ``u`` (the ``speed_scale`` column) changes linearly in time and
every joint and the workpiece move along the straight line between the rows in proportion to the path covered.
From the rows alone, then, each interval's velocities at its ends and its accelerations follow
(:func:`interval_rates`).  :func:`timing_checks` refuses

* ``timing``: a plan without ``speed_scale``, a value outside ``[0, 1]``, a phase whose first or last row is not
  at rest (``speed_scale`` 0 and every velocity command 0), or a velocity command that disagrees with the rule
  (exactly on a regrasp's straight legs to :data:`~qsplan.planner.certify.rows.JUMP_TOL` per second of
  :data:`RATE_TOL`; in contact, where the commands sample a smooth path's tangent, to
  :data:`~qsplan.planner.certify.rows.COMMAND_RTOL` and the path's bend between the rows,
  :func:`~qsplan.planner.certify.rows.path_bend`);
* ``acceleration``: a velocity command changing faster than its joint's acceleration limit over an interval (on a
  regrasp's first and last legs, which leave and reach the workpiece, its release acceleration), or
  the workpiece's inertial wrench (its mass times its acceleration between the rows, at its centre of mass)
  outside the task's disturbance box, which every band was recomputed with.

At a row at rest the quasistatic model decides nothing (every mode degenerate at zero input).  The model is
homogeneous in the velocity input: its modes and bands are those of any positive speed in the same direction.  A
row at rest is therefore judged for the motion that leaves it (a phase's first row) or reaches it (its last): the
straight line to the adjacent row, as the controller moves (:func:`row_velocity`).  And at the instant of rest
itself :func:`hold_checks` proves that nothing moves, the velocity-controlled joints held and the effort joint at
its command, with every contact present there (a contact the reaching motion makes included: at rest it pushes as
well as any other), for every friction and every wrench of the box (kind ``hold``;
:func:`qsplan.mechanics.bands.hold.prove_hold`: a frictionless equilibrium with every contact strictly loaded);
the certificate records each proof.  Units SI.
"""

from __future__ import annotations

import numpy as np

__all__ = ["ACCEL_RTOL", "HOLD_PROOF", "RATE_TOL", "hold_checks", "interval_rates", "row_com_velocity", "row_velocity",
           "timing_checks"]

#: Relative excess tolerated on an acceleration limit and on the disturbance box: the planner times the rows to
#: reach the limits exactly, and the rows' times are sums of durations, positions differences of nearby floats
#: (~1e-15 relative each, a few hundred deep).
ACCEL_RTOL = 1e-7

#: Velocity (rad/s, m/s) within which a regrasp row's command must match the rule's rate: rounding of rows
#: written to full precision over intervals of at least ~10 ms.
RATE_TOL = 1e-7


def _phase_rows(cols) -> list:
    """The rows of each phase in order, ``[ndarray of int]``."""
    ph = np.asarray(cols["phase"], float)
    return [np.flatnonzero(ph == p) for p in np.unique(ph[np.isfinite(ph)])]


def interval_rates(cols, a: int, b: int):
    """``(rate at a, rate at b, acceleration)`` (1/s, 1/s, 1/s^2) of the fraction of the interval from row ``a`` to
    row ``b`` covered, by the rule: a quantity ``z`` moves at ``dz * rate`` and accelerates at ``dz * acceleration``."""
    from qsplan.planner.plan.sampling import path_fraction  # the rule, in one place

    tr = np.array([cols["t"][a], cols["t"][b]], dtype=float)
    u = np.array([cols["speed_scale"][a], cols["speed_scale"][b]], dtype=float)
    _, _, rate = path_fraction(tr, tr, u)
    return float(rate[0]), float(rate[1]), float((rate[1] - rate[0]) / (tr[1] - tr[0]))


def row_velocity(cols, k, names):
    """``(joint velocities (n_j,), workpiece x velocity)`` (rad/s or m/s; m/s) the rows give at in-contact row ``k``:
    its commands and the rule's workpiece rate; at rest (``speed_scale`` 0), the straight line to the adjacent row of
    its phase per second (the direction of the motion that leaves or reaches it, see the module docstring).
    ``None`` for a phase of one row, or where no adjacent row of its phase comes later in time (a repeated or
    reordered time: the ``time`` check names it; no velocity follows from it)."""
    t = cols["t"]
    same = _chords(cols, k)
    if not same:
        return None
    a, b = same[0]
    dq = np.array([cols[f"q_{m}"][b] - cols[f"q_{m}"][a] for m in names], dtype=float)
    dx = float(cols["x_workpiece"][b] - cols["x_workpiece"][a])
    if "speed_scale" in cols and cols["speed_scale"][k] == 0.0:
        dt = float(t[b] - t[a])
        return dq / dt, dx / dt
    qd = np.array([cols[f"qd_{m}"][k] for m in names], dtype=float)
    if "speed_scale" not in cols:
        return qd, dx / float(t[b] - t[a])
    return qd, _rule_velocity(cols, k, a, b)


def row_com_velocity(cols, k, names):
    """The workpiece's centre-of-mass velocity ``(vx, vy)`` (m/s) the rows give at moving in-contact row ``k``: per
    coordinate the rule's rate on the chord to the next row of its phase (at rest, or without the time scaling, the
    chord per second: :func:`row_velocity`'s), and where rows of its phase come both before and after it, the mean with
    the rule's rate on the chord from the row before (a central difference).  A straight slide's two chords give the
    same velocity; a pivot's rows lie on a curve, where one chord is off the instantaneous velocity by half a step of
    its curvature (1 to 3 % along ``full_turn_task``'s pivot at 0.25 deg a row) and the mean only by the step squared
    (within 0.9 % there, 0.02 % in the median).  ``None`` where :func:`row_velocity` gives none."""
    if row_velocity(cols, k, names) is None:
        return None
    same = _chords(cols, k)
    t = cols["t"]
    (a, b), out = same[0], []
    for column in ("x_workpiece", "y_workpiece"):
        if "speed_scale" not in cols or cols["speed_scale"][k] == 0.0:
            out.append(float(cols[column][b] - cols[column][a]) / float(t[b] - t[a]))
            continue
        v = _rule_velocity(cols, k, a, b, column)
        if len(same) >= 2:
            v = 0.5 * (v + _rule_velocity(cols, k, *same[1], column))
        out.append(v)
    return np.array(out)


def _chords(cols, k) -> list:
    """The chords ``(a, b)`` of row ``k``'s phase through it, forward in time: to the next row, then from the one
    before, where each is in the phase and later in time."""
    t, ph = cols["t"], cols["phase"]
    n = t.size
    return [(a, b) for a, b in ((k, k + 1), (k - 1, k))
            if 0 <= a and b < n and ph[a] == ph[k] and ph[b] == ph[k] and t[b] > t[a]]  # fmt: skip


def _rule_velocity(cols, k, a, b, column: str = "x_workpiece") -> float:
    """The rate (m/s) of the workpiece's ``column`` at row ``k``, an end of the chord ``(a, b)``, by the time scaling's
    rule."""
    r0, r1, _ = interval_rates(cols, a, b)
    return float(cols[column][b] - cols[column][a]) * (r0 if k == a else r1)


def timing_checks(task, cols) -> list:
    """Stops, the rule's velocities, acceleration limits and the inertial load (the module docstring); returns
    ``[(row, kind, message)]``, at most one per kind and phase."""
    from qsplan.planner.certify.rows import COMMAND_RTOL, path_bend
    from qsplan.planner.task.dynamics import task_dynamics, turning_wrench

    if "speed_scale" not in cols:
        return [(None, "timing", "the plan has no speed_scale column: its phases do not start and end at rest")]
    names, units = task.hand.joint_names, task.hand.joint_units()
    u = np.asarray(cols["speed_scale"], float)
    bad = np.flatnonzero(~(np.isfinite(u) & (u >= 0) & (u <= 1)))
    out = [(int(bad[0]), "timing", f"speed_scale {float(u[bad[0]])!r} outside [0, 1]")] if bad.size else []
    if bad.size:
        return out
    dyn = task_dynamics(task)
    box = task.disturbance
    m = float(task.hand.workpiece_mass)
    from qsplan.hands.geometry.workpiece import polygon_inertia

    inertia = polygon_inertia(task.hand.workpiece, m)[1]  # about the centre of mass: the turning term
    for rows in _phase_rows(cols):
        found = {}
        for k in (rows[0], rows[-1]):
            moving = [n for n in names if np.isfinite(cols[f"qd_{n}"][k]) and cols[f"qd_{n}"][k] != 0.0]
            if u[k] != 0.0 or moving:
                found.setdefault("timing", (int(k), f"phase {int(cols['phase'][k])} does not "
                                            f"{'start' if k == rows[0] else 'end'} at rest (speed_scale {float(u[k])!r}"
                                            + (f"; {', '.join(moving)} commanded to move" if moving else "") + ")"))
        free = str(cols["mode"][rows[0]]) == "free"
        stops = rows[u[rows] == 0.0]  # a regrasp's legs run from rest to rest; its first and last touch the workpiece
        for a, b in zip(rows[:-1], rows[1:]):
            touching = free and (a < stops[1] or b > stops[-2]) if stops.size > 1 else free
            acc = dyn.release_accelerations if touching else dyn.joint_accelerations
            what = "release acceleration" if touching else "acceleration limit"
            dt = float(cols["t"][b] - cols["t"][a])
            if not dt > 0:
                continue  # the structure check names it
            r0, r1, ra = interval_rates(cols, a, b)
            for j, n in enumerate(names):
                qa, qb = cols[f"qd_{n}"][a], cols[f"qd_{n}"][b]
                if not (np.isfinite(qa) and np.isfinite(qb)):
                    continue
                dq = float(cols[f"q_{n}"][b] - cols[f"q_{n}"][a])
                want = dq * r0
                bend = path_bend(cols, a, b, n) * r0  # the tangent against the chord, per second at this speed
                tol = RATE_TOL + (0.0 if free else COMMAND_RTOL * abs(want) + bend)
                if abs(qa - want) > tol and "timing" not in found:
                    found["timing"] = (int(a), f"{n} joint's velocity command {qa:.6g} {units[j]}/s; the rows and "
                                               f"speed_scale give {want:.6g} {units[j]}/s")  # fmt: skip
                rate = abs(qb - qa) / dt
                if rate > acc[j] * (1 + ACCEL_RTOL) and "acceleration" not in found:
                    found["acceleration"] = (int(a), f"{n} joint's velocity command changes at {rate:.4g} "
                                                     f"{units[j]}/s^2 to the next row; {what} {acc[j]:g} "
                                                     f"{units[j]}/s^2")  # fmt: skip
            dp = np.array([float(cols[f"{c}_workpiece"][b] - cols[f"{c}_workpiece"][a]) for c in ("x", "y", "theta")])
            acc = dp * ra  # the pose moves along the chord in proportion to the path (the rule)
            ax = float(np.max(np.abs(acc)))
            if box is not None and ax != 0.0 and "acceleration" not in found:
                com = np.array([cols["x_workpiece"][a], cols["y_workpiece"][a]], dtype=float)
                w = turning_wrench(m, inertia, com, acc[:2], acc[2])
                lo, hi = np.asarray(box.lo, float), np.asarray(box.hi, float)
                slack = ACCEL_RTOL * np.maximum(np.abs(lo), np.abs(hi))
                if np.any(w < lo - slack) or np.any(w > hi + slack):
                    found["acceleration"] = (int(a), f"the workpiece accelerates at ({acc[0]:.4g} m/s^2, {acc[1]:.4g} m/s^2, "
                                                     f"{acc[2]:.4g} rad/s^2) to the next row: its "
                                                     f"inertial wrench [{w[0]:.4g} N, {w[1]:.4g} N, {w[2]:.4g} N m] "
                                                     "lies outside the disturbance box the bands withstand")  # fmt: skip
            elif box is None and ax != 0.0 and "acceleration" not in found:
                found["acceleration"] = (int(a), f"the workpiece accelerates at {ax:.4g} (m/s^2 or rad/s^2) and the task's bands "
                                                 "withstand no disturbance")  # fmt: skip
        out += [(row, kind, msg) for kind, (row, msg) in found.items()]
    return out


#: What :func:`hold_checks` records as the proof of a hold (the certificate's ``holds``).
HOLD_PROOF = ("frictionless equilibrium with every contact strictly loaded, at the row's torque and every vertex of "
              "the disturbance box: the loads do negative work along every admissible motion, so nothing moves for "
              "any friction (qsplan.mechanics.bands.hold)")


def hold_checks(task, cols, scenes) -> tuple:
    """Every in-contact row at rest (``speed_scale`` 0; ``scenes``: ``{row: Scene}``, the rows judged) holds:
    ``(violations [(row, kind, message)], records [{row, t_s, proved, margin_N, proof}])``.

    The hold is proved with every contact present at the row (:func:`qsplan.hands.contacts.found.hold_scene`, the
    contacts found in the polygons), not only the contacts the row's mode judges: at a phase's last row the mode
    leaves out a contact the motion makes there (it opens along that motion), and at rest that contact pushes as
    well as any other."""
    from qsplan.hands.contacts.found import hold_scene
    from qsplan.mechanics.bands.hold import prove_hold
    from qsplan.mechanics.errors import QsplanError

    from qsplan.planner.certify.rows import row_pose, row_q

    if "speed_scale" not in cols:
        return [], []
    found, records = [], []
    names = task.hand.joint_names
    for k in sorted(scenes):
        if cols["speed_scale"][k] != 0.0:
            continue
        e = str(cols["effort_joint"][k])
        tau = float(cols[f"tau_{e}"][k]) if f"tau_{e}" in cols else float("nan")
        if not np.isfinite(tau):
            continue  # no command: the torque check names it
        effort = np.array(names) == e  # every contact the polygons show (the reference search), made ones too
        try:
            scene = hold_scene(task.hand, row_pose(cols, k), row_q(cols, k, names), effort, np.where(effort, tau, 0.0))
        except QsplanError as exc:
            found.append((int(k), "hold", f"at rest, the row's contacts cannot be found: {exc}"))
            continue
        proof = prove_hold(scene, torques=[tau], disturbance=task.disturbance)
        records.append({"row": int(k), "t_s": float(cols["t"][k]), "proved": bool(proof.proved),
                        "margin_N": float(proof.margin), "proof": HOLD_PROOF})  # fmt: skip
        if not proof.proved:
            found.append((int(k), "hold", f"at rest, with {e} at {tau:.6g} and every other joint held, nothing is proved "
                                          f"to stay: {proof.reason}"))  # fmt: skip
    return found, records
