"""The mode check of the plan certifier (:mod:`qsplan.planner.certify.certify`): the planned mode, alone.

:func:`mode_checks` rebuilds a row's scene from the task (:func:`qsplan.hands.interface.scene_at`:
the effort-controlled joints those with a torque command, the others driven at their ``qd``)
and asks which modes its commands make feasible at every friction vector to test, with the
mechanics' :func:`qsplan.mechanics.solve_many` (the kinematic stage once, the equilibrium and
Coulomb stage for every vector in one batch: the solver's own decisions, bit for bit) or its
reference :func:`qsplan.mechanics.solve_many_reference` (the solver once per vector).

Both share the mechanics library (the model), nothing of the planner's bookkeeping.
Units SI (m, rad, s, N, N m).
"""

from __future__ import annotations

import numpy as np

from qsplan.mechanics import DEFAULT_TOLERANCES, Tolerances, solve_many, solve_many_reference

__all__ = ["MOTION_RTOL", "EXACT_TOLERANCES", "SLIP_SIGN_TOL", "disturbance_checks", "mode_checks", "mode_misfit", "row_scene", "slip_velocities",
           "slip_reversals"]

#: Relative difference tolerated between the workpiece speed the solver computes from
#: the exported velocity command and the one the rows' poses show (finite differences of
#: a straight slide are exact; the command is the closed-form derivative): 1 %.
MOTION_RTOL = 1e-2

#: Tolerances at which a mode that was degenerate at the default ones is tested again.  A
#: mode still degenerate at these is degenerate to machine precision (e.g. a finger breaking
#: from a workpiece held by rolling contacts leaves its joint's velocity undetermined):
#: outside the model (eq. 32, the strict inequalities 11, 15, 16), no competitor.  One that
#: turns decided at these was only nearly degenerate: its feasibility is not decided at the
#: default tolerances, and the row is not certified.  1e-15 is the lowest singularity
#: threshold at which the stability study (``benchmarks/bench_stability.py``) saw no LU failure.
EXACT_TOLERANCES = Tolerances(singular=1e-15, velocity=1e-13)

#: Sliding speed (m/s) within which a contact's sliding direction is not compared between rows: the rows'
#: positions are written to full precision, so a finite difference over a 0.05 s step is exact to ~1e-15 m/s;
#: a sliding direction that reverses between two rows shows speeds of 1e-4 m/s on either side.
SLIP_SIGN_TOL = 1e-12


def _fmt_mu(mu) -> str:
    return "[" + ", ".join(f"{m:.4g}" for m in mu) + "]"


def row_scene(task, cols, k, judged=None):
    """The scene of in-contact row ``k`` rebuilt from the task (:func:`qsplan.hands.interface.scene_at`): the joints
    with a torque command (and the row's ``effort_joint``) effort-controlled at it, the others at their ``qd`` (a row
    at rest: the direction of the motion that leaves or reaches it, :func:`qsplan.planner.certify.timing.row_velocity`).

    Raises
    ------
    QsplanError
        When the row's polygons give no four-contact grasp.
    """
    from qsplan.hands.interface import joint_names, scene_at

    from qsplan.planner.certify.rows import row_pose, row_q

    names = joint_names(task.hand)
    tau = np.array([cols[f"tau_{n}"][k] for n in names], dtype=float)
    effort = np.isfinite(tau) | (np.array(names) == str(cols["effort_joint"][k]))
    qd = np.array([cols[f"qd_{n}"][k] for n in names], dtype=float)
    if "speed_scale" in cols and cols["speed_scale"][k] == 0.0:  # at rest: the motion that leaves or reaches it
        from qsplan.planner.certify.timing import row_velocity

        moving = row_velocity(cols, k, names)
        qd = np.where(effort, np.nan, moving[0]) if moving is not None else qd
    if judged is not None:  # any formation: the row's judged contacts (qsplan.planner.certify.contacts)
        from qsplan.planner.certify.contacts import judged_scene

        return judged_scene(task, cols, k, judged, effort, qd, tau)
    # method="generic": contacts found by polygon contact finding, the reference path, not the
    # closed-form grasp the planner uses (qsplan.hands.two_finger_analytic): a certifier shares no
    # shortcut with what it certifies (~2 ms per row); a chain hand's contacts are always found so
    return scene_at(task.hand, row_pose(cols, k), row_q(cols, k, names), effort, qd, effort=tau, method="generic")


def mode_misfit(scene, mode: str) -> str | None:
    """Why the letters ``mode`` are not a mode of ``scene`` (:func:`qsplan.mechanics.modes.kinematics.check_mode_fits`:
    one letter per contact, and eq. 29's count with the scene's control partition), or None."""
    from qsplan.mechanics import QsplanError
    from qsplan.mechanics.modes.kinematics import check_mode_fits

    try:
        check_mode_fits(scene, mode)
    except QsplanError as exc:
        return (f"mode {mode} is not a mode of the row's scene ({scene.n_contacts} contacts "
                f"{', '.join(scene.contact_names)}): {exc}")  # fmt: skip
    return None


def slip_velocities(task, cols, k, scene):
    """Each contact's tangential velocity (m/s, shape (n_c,); eq. 6: ``W_t^T nu - J_t thetadot``) at row ``k`` from the
    rows' own motion: finite differences of the workpiece pose and every joint to the next row of the phase (the
    previous one at its end); None when the phase has one row."""
    from qsplan.hands.interface import joint_names

    from qsplan.planner.certify.rows import row_pose, row_q

    t, ph = cols["t"], cols.get("phase")
    same = (lambda i: ph[i] == ph[k]) if ph is not None else (lambda i: cols["mode"][i] != "free")
    names = joint_names(task.hand)
    for a, b in ((k, k + 1), (k - 1, k)):
        if 0 <= a and b < t.size and same(a) and same(b) and t[b] > t[a]:
            dt = float(t[b] - t[a])
            (x, y, _), rate = row_pose(cols, k), (row_pose(cols, b) - row_pose(cols, a)) / dt
            nu = np.array([rate[0] + rate[2] * y, rate[1] - rate[2] * x, rate[2]])  # the point at the world origin
            qdot = (row_q(cols, b, names) - row_q(cols, a, names)) / dt
            return scene.Wt.T @ nu - scene.Jt @ qdot
    return None


def slip_reversals(mode: str, contacts, before, after) -> list:
    """A sliding contact whose direction reverses between two rows of a phase: it stops sliding in between, a change
    of mode (eq. 16: a sliding speed keeps its sign) the rows' letters do not show.

    Parameters
    ----------
    mode : str
        The planned mode's letters.
    contacts : sequence of str
        The contacts' names, in the mode's order.
    before, after : ndarray, shape (n_c,)
        :func:`slip_velocities` at the two rows (m/s).
    """
    for i, letter in enumerate(mode):
        if letter == "S" and min(abs(before[i]), abs(after[i])) > SLIP_SIGN_TOL and before[i] * after[i] < 0:
            return [("mode", f"contact {contacts[i]} slides at {before[i] * 1e3:.4g} mm/s at the previous row and "
                             f"{after[i] * 1e3:.4g} mm/s here: its sliding direction reverses in between, where it "
                             f"stops sliding (eq. 16), outside the planned mode {mode}")]  # fmt: skip
    return []


def mode_checks(task, cols, k, mus, force_margin=0.0, xdot_rows=np.nan, batched=True, scene=None) -> tuple:
    """Check 4: with the row's commands the planned mode is the only feasible one at every friction vector.

    Parameters
    ----------
    mus : ndarray, shape (m, n_c)
        Friction vectors, one coefficient per contact of the row's scene.
    force_margin : float
        N: the planned mode's normal forces must be at least this at every contact it keeps (a breaking contact,
        ``B``, carries none).
    xdot_rows : float
        The workpiece's ``x`` velocity (m/s) the rows show (finite difference); nan: not checked.
    batched : bool
        Every friction vector in one batch (:func:`qsplan.mechanics.solve_many`); False: the
        reference, one solve per vector (:func:`qsplan.mechanics.solve_many_reference`).  Same verdicts.
    scene : Scene, optional
        The row's scene when already built (:func:`row_scene`).

    Returns
    -------
    (list of (kind, message), tuple of str)
        The failures (at most one per kind: the first friction vector that shows it) and
        the modes set aside as degenerate to machine precision (outside the model).
    """
    from qsplan.mechanics import QsplanError, Status

    mode = str(cols["mode"][k])
    if scene is None:
        try:
            scene = row_scene(task, cols, k)
        except QsplanError as exc:
            return [("contact", f"the row's scene cannot be built: {exc}")], ()
    solve_at = solve_many if batched else solve_many_reference
    names = Status.ORDER
    degenerate_codes = [names.index(s) for s in sorted(Status.DEGENERATE)]
    singular = names.index(Status.EQUILIBRIUM_SINGULAR)
    found = {}
    exact_cache = {}  # statuses at machine precision: per friction vector, or once for kinematic degeneracy
    sv = solve_at(scene, mus, DEFAULT_TOLERANCES)
    letters = sv.letters
    j_mode = letters.index(mode) if mode in letters else None
    feasible = sv.codes == 0
    n_feasible = feasible.sum(axis=1)
    planned = feasible[:, j_mode] if j_mode is not None else np.zeros(len(mus), dtype=bool)
    degenerate = np.isin(sv.codes, degenerate_codes)
    excluded = np.zeros(len(letters), dtype=bool)
    held = np.array([i for i, letter in enumerate(mode) if letter != "B"], dtype=int)
    for i, mu in enumerate(mus):
        row = sv.codes[i]
        if n_feasible[i] > planned[i] and "mode" not in found:
            others = [letters[j] for j in np.flatnonzero(feasible[i]) if letters[j] != mode]
            found["mode"] = f"competitor {'/'.join(others)} feasible at mu = {_fmt_mu(mu)} (planned {mode})"
        if not planned[i] and "planned" not in found:
            why = "not tested" if j_mode is None else names[row[j_mode]]
            found["planned"] = f"planned mode {mode} not feasible at mu = {_fmt_mu(mu)} ({why})"
        if degenerate[i].any():
            key = tuple(mu) if np.any(degenerate[i] & (row == singular)) else "kinematic"
            if key not in exact_cache:
                tight = solve_at(scene, mu[None, :], EXACT_TOLERANCES).codes[0]
                exact_cache[key] = tight, np.isin(tight, degenerate_codes)
            tight, still = exact_cache[key]
            excluded |= degenerate[i] & still
            undecided = np.flatnonzero(degenerate[i] & ~still)
            if undecided.size and "undecided" not in found:
                j = undecided[0]
                found["undecided"] = (f"mode {letters[j]} is nearly degenerate ({names[row[j]].replace('_', ' ')}) "
                                      f"at mu = {_fmt_mu(mu)}: its feasibility is not decided "
                                      f"({names[tight[j]].replace('_', ' ')} at machine precision)")  # fmt: skip
        if not planned[i]:
            continue
        c_n, qdot = sv.c_n[i, j_mode], sv.qdot[i, j_mode]
        loaded = c_n[held]  # a breaking contact carries no force: the margin binds the others (eq. 28 made strict)
        if force_margin > 0 and loaded.size and loaded.min() < force_margin and "force margin" not in found:
            i_c = int(held[np.argmin(loaded)])
            found["force margin"] = (f"normal force {c_n[i_c]:.4g} N at contact {i_c} below the margin "
                                     f"{force_margin:g} N at mu = {_fmt_mu(mu)}")  # fmt: skip
        xdot = qdot[0] - qdot[2] * float(cols["y_workpiece"][k])  # qdot is the world origin's velocity
        if np.isfinite(xdot_rows) and "motion" not in found:
            if np.sign(xdot) != np.sign(xdot_rows) or abs(xdot - xdot_rows) > MOTION_RTOL * abs(xdot_rows):
                found["motion"] = (f"the commands move the workpiece at {xdot * 1e3:.4g} mm/s at mu = {_fmt_mu(mu)}; "
                                   f"the rows show {xdot_rows * 1e3:.4g} mm/s")  # fmt: skip
    kinds = {"planned": "mode", "mode": "mode"}
    set_aside = tuple(sorted(letters[j] for j in np.flatnonzero(excluded)))
    return [(kinds.get(kind, kind), msg) for kind, msg in found.items()], set_aside


def disturbance_checks(task, cols, k, mus, force_margin, batched, scene) -> list:
    """Check 4 under the task's disturbance (``task.disturbance``, a box of wrenches on the workpiece): the row's
    commands keep the planned mode the only feasible one at every friction vector **and** every vertex of the wrench
    box (each added to the scene's ``g_obj``, eq. 2).  For the planned mode the vertices decide (for fixed friction its
    rows are affine in the wrench); for the competitors this samples what the exact preclusion proved.  Returns
    ``[(kind, message)]``, the first vertex showing each kind."""
    from dataclasses import replace

    found = {}
    for w in task.disturbance.vertices():
        loaded = replace(scene, g_obj=scene.g_obj + w)
        more, _ = mode_checks(task, cols, k, mus, force_margin, np.nan, batched, loaded)
        for kind, msg in more:
            found.setdefault(kind, f"{msg}, under the disturbance wrench [{w[0]:.4g} N, {w[1]:.4g} N, {w[2]:.4g} N m]")
    return list(found.items())
