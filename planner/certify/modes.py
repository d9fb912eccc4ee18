"""The mode check of the plan certifier (:mod:`qsplan.planner.certify.certify`): the planned mode, alone.

:func:`mode_checks` rebuilds a row's scene from the task (:meth:`qsplan.hands.protocol.Hand.scene`:
the effort-controlled joints those with a torque command, the others driven at their ``qd``)
and asks which modes its commands make feasible at every friction vector to test, with the
mechanics' :func:`qsplan.mechanics.solve_many` (the kinematic stage once, the equilibrium and
Coulomb stage for every vector in one batch: the solver's own decisions, bit for bit) or its
reference :func:`qsplan.mechanics.solve_many_reference` (the solver once per vector);
:func:`disturbance_checks` asks again at every vertex of the task's wrench box.

:func:`plan_mode_checks` gives both checks' answers for every row of a plan at once: every row x wrench vertex x
friction vector in one call of :func:`qsplan.mechanics.solver.many.solve_many_scenes` (each row's statuses those of
:func:`~qsplan.mechanics.solve_many`, bit for bit), the second look at degenerate modes in one more, and the same
verdicts and messages as :func:`mode_checks` then :func:`disturbance_checks` row by row (the reference; the tests
compare the certificates).

Both share the mechanics library (the model), nothing of the planner's bookkeeping.
Units SI (m, rad, s, N, N m).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qsplan.mechanics import DEFAULT_TOLERANCES, Tolerances, solve_many, solve_many_reference

__all__ = ["MOTION_RTOL", "EXACT_TOLERANCES", "FORCES_PER_CALL", "PARALLEL_TOL", "SLIP_SIGN_TOL", "ModeJob", "disturbance_checks", "mode_checks", "rigid_pairs", "structural_degeneracy",
           "mode_misfit", "plan_mode_checks", "row_scene", "slip_velocities", "slip_reversals"]

#: Relative difference tolerated between the workpiece's centre-of-mass velocity the solver computes from the exported
#: velocity command and the one the rows' poses show, as a vector relative to the rows' speed (finite differences of a
#: straight slide are exact, a pivot's central differences within 0.9 %; the command is the closed-form derivative):
#: 1 %.
MOTION_RTOL = 1e-2

#: Tolerances at which a mode that was degenerate at the default ones is tested again.  A
#: mode still degenerate at these is degenerate to machine precision (e.g. a finger breaking
#: from a workpiece held by rolling contacts leaves its joint's velocity undetermined):
#: outside the model (eq. 32, the strict inequalities 11, 15, 16), no competitor.  One that
#: turns decided at these was only nearly degenerate: its feasibility is not decided at the
#: default tolerances, and the row is not certified.  1e-15 is the lowest singularity
#: threshold at which the stability study (``benchmarks/bench_stability.py``) saw no LU failure.
EXACT_TOLERANCES = Tolerances(singular=1e-15, velocity=1e-13)

#: Numbers (normal forces and workpiece velocities, 8 bytes each) one call of
#: :func:`qsplan.mechanics.solver.many.solve_many_scenes` keeps for :func:`plan_mode_checks` (every mode at every row x
#: wrench vertex x friction vector): 2^22, ~32 MB, so that a long plan's rows are solved in several calls (the demo's
#: 81 rows need ~1.3 M: one call); the answers do not depend on it.
FORCES_PER_CALL = 1 << 22

#: Sliding speed (m/s) within which a contact's sliding direction is not compared between rows: the rows'
#: positions are written to full precision, so a finite difference over a 0.05 s step is exact to ~1e-15 m/s;
#: a sliding direction that reverses between two rows shows speeds of 1e-4 m/s on either side.
SLIP_SIGN_TOL = 1e-12


#: Sine of the angle within which two contact normals are parallel (a flush pair): the manifold and the polygon
#: search give a flush pair's normals parallel to ~1e-15, and contacts meeting at an angle differ by far more.
PARALLEL_TOL = 1e-9


def rigid_pairs(scene) -> tuple:
    """Pairs ``(i, j)`` of the scene's contacts between the workpiece and one body (the body their names give:
    ``palm``, ``left``, ``right``) with parallel normals at distinct points along them (the workpiece's bottom edge
    on the palm, a finger flush on an edge).  While both contacts hold, the relative motion of the two bodies cannot
    turn (each normal velocity zero at two points off one normal line), so their sliding speeds are equal (eq. 6):
    a mode that rolls one and slides the other slides it at zero speed, degenerate by the contacts' geometry alone
    (:func:`structural_degeneracy`)."""
    names = [str(n).partition(":")[0] for n in scene.contact_names]
    normals, moments = scene.Wn[:2].T, scene.Wn[2]
    out = []
    for i in range(len(names)):
        for j in range(i + 1, len(names)):
            parallel = abs(normals[i, 0] * normals[j, 1] - normals[i, 1] * normals[j, 0]) <= PARALLEL_TOL
            if names[i] == names[j] and parallel and normals[i] @ normals[j] > 0 and abs(moments[i] - moments[j]) > PARALLEL_TOL:
                out.append((i, j))
    return tuple(out)


def structural_degeneracy(letters, pairs) -> np.ndarray:
    """For each mode of ``letters`` (sequence of str), whether it rolls one contact of a rigid pair
    (:func:`rigid_pairs`) and slides the other: degenerate exactly, whatever the numbers (bool, shape (n_modes,))."""
    return np.array([any({m[i], m[j]} == {"R", "S"} for i, j in pairs) for m in letters], dtype=bool)


def _fmt_mu(mu) -> str:
    return "[" + ", ".join(f"{m:.4g}" for m in mu) + "]"


# The messages of the mode check (one per kind, at the first friction vector showing it), shared by the row-by-row
# reference (mode_checks) and the plan at once (plan_mode_checks).

def _competitor_msg(others, mu, mode) -> str:
    return f"competitor {'/'.join(others)} feasible at mu = {_fmt_mu(mu)} (planned {mode})"


def _planned_msg(mode, mu, why) -> str:
    return f"planned mode {mode} not feasible at mu = {_fmt_mu(mu)} ({why})"


def _undecided_msg(letters, status, mu, tight) -> str:
    return (f"mode {letters} is nearly degenerate ({status.replace('_', ' ')}) at mu = {_fmt_mu(mu)}: its feasibility "
            f"is not decided ({tight.replace('_', ' ')} at machine precision)")  # fmt: skip


def _force_msg(c_n, i_c, force_margin, mu) -> str:
    return f"normal force {c_n:.4g} N at contact {i_c} below the margin {force_margin:g} N at mu = {_fmt_mu(mu)}"


def _com_velocity(qdot, x: float, y: float) -> np.ndarray:
    """The workpiece's centre-of-mass velocity ``(vx, vy)`` (m/s, shape (..., 2)) from the solver's ``qdot`` (the
    velocity of the workpiece point at the world origin, and its rate of turn), its centre of mass at ``(x, y)``."""
    return np.stack([qdot[..., 0] - qdot[..., 2] * y, qdot[..., 1] + qdot[..., 2] * x], axis=-1)


def _motion_off(v, v_rows) -> np.ndarray:
    """Whether the commanded centre-of-mass velocity ``v`` (shape (..., 2)) is off the rows' ``v_rows`` (2,) by more
    than :data:`MOTION_RTOL` of the rows' speed (a relative error of the vector: a coordinate passing through zero,
    as the x velocity of a pivot's centre of mass at its leftmost, is judged against the whole motion)."""
    return np.linalg.norm(v - v_rows, axis=-1) > MOTION_RTOL * np.linalg.norm(v_rows)


def _motion_msg(v, v_rows, mu) -> str:
    return (f"the commands move the workpiece's centre of mass at ({v[0] * 1e3:.4g}, {v[1] * 1e3:.4g}) mm/s at mu = "
            f"{_fmt_mu(mu)}; the rows show ({v_rows[0] * 1e3:.4g}, {v_rows[1] * 1e3:.4g}) mm/s")  # fmt: skip


def _under_msg(msg, w) -> str:
    return f"{msg}, under the disturbance wrench [{w[0]:.4g} N, {w[1]:.4g} N, {w[2]:.4g} N m]"


def row_scene(task, cols, k, judged=None):
    """The scene of in-contact row ``k`` rebuilt from the task (:meth:`qsplan.hands.protocol.Hand.scene`): the joints
    with a torque command (and the row's ``effort_joint``) effort-controlled at it, the others at their ``qd`` (a row
    at rest: the direction of the motion that leaves or reaches it, :func:`qsplan.planner.certify.timing.row_velocity`).

    Raises
    ------
    QsplanError
        When the row's polygons give no four-contact grasp.
    """
    from qsplan.planner.certify.rows import row_pose, row_q

    names = task.hand.joint_names
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
    # closed-form grasp the planner uses (qsplan.hands.paper_hand.analytic): a certifier shares no
    # shortcut with what it certifies (~2 ms per row); a chain hand's contacts are always found so
    return task.hand.scene(row_pose(cols, k), row_q(cols, k, names), effort, qd, effort=tau, method="generic")


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
    from qsplan.planner.certify.rows import row_pose, row_q

    t, ph = cols["t"], cols.get("phase")
    same = (lambda i: ph[i] == ph[k]) if ph is not None else (lambda i: cols["mode"][i] != "free")
    names = task.hand.joint_names
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


def mode_checks(task, cols, k, mus, force_margin=0.0, v_rows=np.nan, batched=True, scene=None) -> tuple:
    """Check 4: with the row's commands the planned mode is the only feasible one at every friction vector.

    Parameters
    ----------
    mus : ndarray, shape (m, n_c)
        Friction vectors, one coefficient per contact of the row's scene.
    force_margin : float
        N: the planned mode's normal forces must be at least this at every contact it keeps (a breaking contact,
        ``B``, carries none).
    v_rows : ndarray, shape (2,), or float
        The workpiece's centre-of-mass velocity ``(vx, vy)`` (m/s) the rows show (finite differences); nan: not
        checked.
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
    structural = structural_degeneracy(letters, rigid_pairs(scene))
    held = np.array([i for i, letter in enumerate(mode) if letter != "B"], dtype=int)
    for i, mu in enumerate(mus):
        row = sv.codes[i]
        if n_feasible[i] > planned[i] and "mode" not in found:
            others = [letters[j] for j in np.flatnonzero(feasible[i]) if letters[j] != mode]
            found["mode"] = _competitor_msg(others, mu, mode)
        if not planned[i] and "planned" not in found:
            why = "not tested" if j_mode is None else names[row[j_mode]]
            found["planned"] = _planned_msg(mode, mu, why)
        if degenerate[i].any():
            key = tuple(mu) if np.any(degenerate[i] & (row == singular)) else "kinematic"
            if key not in exact_cache:
                tight = solve_at(scene, mu[None, :], EXACT_TOLERANCES).codes[0]
                exact_cache[key] = tight, np.isin(tight, degenerate_codes)
            tight, still = exact_cache[key]
            still = still | structural  # a rigid pair rolled and slid: degenerate by geometry, not by numbers
            excluded |= degenerate[i] & still
            undecided = np.flatnonzero(degenerate[i] & ~still)
            if undecided.size and "undecided" not in found:
                j = undecided[0]
                found["undecided"] = _undecided_msg(letters[j], names[row[j]], mu, names[tight[j]])
        if not planned[i]:
            continue
        c_n, qdot = sv.c_n[i, j_mode], sv.qdot[i, j_mode]
        loaded = c_n[held]  # a breaking contact carries no force: the margin binds the others (eq. 28 made strict)
        if force_margin > 0 and loaded.size and loaded.min() < force_margin and "force margin" not in found:
            i_c = int(held[np.argmin(loaded)])
            found["force margin"] = _force_msg(c_n[i_c], i_c, force_margin, mu)
        if np.all(np.isfinite(v_rows)) and "motion" not in found:
            v = _com_velocity(qdot, float(cols["x_workpiece"][k]), float(cols["y_workpiece"][k]))
            if _motion_off(v, v_rows):
                found["motion"] = _motion_msg(v, v_rows, mu)
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
            found.setdefault(kind, _under_msg(msg, w))
    return list(found.items())


@dataclass(frozen=True, slots=True, eq=False)
class ModeJob:
    """One in-contact row for :func:`plan_mode_checks`: what :func:`mode_checks` takes for it.

    Attributes
    ----------
    row : int
    scene : Scene
        The row's scene (:func:`row_scene`).
    mus : ndarray, shape (m, n_c)
        Its friction vectors.
    v_rows : ndarray, shape (2,), or float
        The workpiece's centre-of-mass velocity ``(vx, vy)`` (m/s) the rows show; nan: not checked.
    """

    row: int
    scene: object
    mus: np.ndarray
    v_rows: object


def _position(cols, job):
    """The workpiece's centre of mass ``(x, y)`` (m) at the job's row, where its motion is checked (else None)."""
    if not np.all(np.isfinite(job.v_rows)):
        return None
    return float(cols["x_workpiece"][job.row]), float(cols["y_workpiece"][job.row])


def _first(flags) -> np.ndarray:
    """The first True along the last axis of ``flags`` (..., m): its index, or ``m`` where none."""
    m = flags.shape[-1]
    return np.where(flags.any(axis=-1), flags.argmax(axis=-1), m)


class _RowJudge:
    """:func:`mode_checks` at the undisturbed scene and at each wrench vertex (the row's blocks) of one row, from
    its statuses at every block x friction vector (``sv``: shape (B m, n_modes), block-major)."""

    def __init__(self, job, mode, sv, n_blocks):
        from qsplan.mechanics import Status

        self.job, self.mode, self.sv = job, mode, sv
        m = len(job.mus)
        self.codes = sv.codes.reshape(n_blocks, m, -1)
        letters = sv.letters
        self.j_mode = letters.index(mode) if mode in letters else None
        feasible = self.codes == 0
        self.feasible = feasible
        self.planned = feasible[..., self.j_mode] if self.j_mode is not None else np.zeros((n_blocks, m), dtype=bool)
        degenerate_codes = [Status.ORDER.index(s) for s in sorted(Status.DEGENERATE)]
        self.degenerate_codes = degenerate_codes
        self.degenerate = np.isin(self.codes, degenerate_codes)
        self.structural = structural_degeneracy(letters, rigid_pairs(job.scene))
        deg_any = self.degenerate.any(axis=-1)
        singular = self.degenerate & (self.codes == Status.ORDER.index(Status.EQUILIBRIUM_SINGULAR))
        self.by_mu = singular.any(axis=-1)  # mode_checks' cache key: the friction vector itself
        kinematic = deg_any & ~self.by_mu  # ... or "kinematic": the first such vector's answer serves them all
        self.kin_first = _first(kinematic)
        # the second look (EXACT_TOLERANCES) each block needs: (block, vector), in order
        self.looks = [(b, int(i)) for b in range(n_blocks) for i in sorted(
            set(np.flatnonzero(self.by_mu[b])) | ({int(self.kin_first[b])} if self.kin_first[b] < m else set()))]

    def verdicts(self, tight, force_margin, position, wrenches):
        """``(found, excluded)`` as :func:`mode_checks` then :func:`disturbance_checks` give them; ``tight``: the
        codes of :attr:`looks`, shape (len(looks), n_modes); ``position``: the centre of mass ``(x, y)`` (m) where
        the row's motion is checked, else None."""
        from qsplan.mechanics import Status

        names, letters, mode, mus = Status.ORDER, self.sv.letters, self.mode, self.job.mus
        B, m = self.codes.shape[:2]
        at = {key: r for r, key in enumerate(self.looks)}
        which = np.full((B, m), len(self.looks))  # each vector's second look (its row of tight), or none
        for b in range(B):
            which[b, self.degenerate[b].any(axis=-1) & ~self.by_mu[b]] = at.get((b, int(self.kin_first[b])), len(at))
            for i in np.flatnonzero(self.by_mu[b]):
                which[b, i] = at[(b, int(i))]
        tight = np.vstack([tight, np.zeros((1, self.codes.shape[-1]), dtype=tight.dtype)])  # none: nothing degenerate
        still = np.isin(tight, self.degenerate_codes)[which] | self.structural  # degenerate at machine precision too
        undecided = self.degenerate & ~still
        excluded = (self.degenerate[0] & still[0]).any(axis=0)
        competitor = self.feasible.sum(axis=-1) > self.planned
        first = {"mode": _first(competitor), "planned": _first(~self.planned), "undecided": _first(undecided.any(-1))}
        held = np.array([i for i, letter in enumerate(mode) if letter != "B"], dtype=int)
        if self.j_mode is not None:
            c_n = self.sv.c_n.reshape(B, m, len(letters), -1)[:, :, self.j_mode]
            qdot = self.sv.qdot.reshape(B, m, len(letters), 3)[:, :, self.j_mode]
            if force_margin > 0 and held.size:
                first["force margin"] = _first(self.planned & (c_n[..., held].min(axis=-1) < force_margin))
            if position is not None:
                v = _com_velocity(qdot, *position)
                off = _motion_off(v[0], np.asarray(self.job.v_rows, dtype=float))
                first["motion"] = np.concatenate([_first(self.planned[0] & off)[None], np.full(B - 1, m)])
        order = ("mode", "planned", "undecided", "force margin", "motion")  # mode_checks' order at one vector
        kinds = {"planned": "mode"}
        blocks = []
        for b in range(B):
            found = []
            for i, _, kind in sorted((int(first[kind][b]), r, kind) for r, kind in enumerate(order) if kind in first):
                if i == m:
                    continue
                mu, row = mus[i], self.codes[b, i]
                if kind == "mode":
                    others = [letters[j] for j in np.flatnonzero(self.feasible[b, i]) if letters[j] != mode]
                    msg = _competitor_msg(others, mu, mode)
                elif kind == "planned":
                    msg = _planned_msg(mode, mu, "not tested" if self.j_mode is None else names[row[self.j_mode]])
                elif kind == "undecided":
                    j = int(np.flatnonzero(undecided[b, i])[0])
                    msg = _undecided_msg(letters[j], names[row[j]], mu, names[tight[which[b, i], j]])
                elif kind == "force margin":
                    loaded = c_n[b, i, held]
                    i_c = int(held[np.argmin(loaded)])
                    msg = _force_msg(c_n[b, i, i_c], i_c, force_margin, mu)
                else:
                    msg = _motion_msg(v[b, i], self.job.v_rows, mu)
                found.append((kinds.get(kind, kind), msg))
            blocks.append(found)
        out, disturbed = list(blocks[0]), {}
        for w, found in zip(wrenches, blocks[1:]):
            for kind, msg in found:
                disturbed.setdefault(kind, _under_msg(msg, w))
        set_aside = tuple(sorted(letters[j] for j in np.flatnonzero(excluded)))
        return out + list(disturbed.items()), set_aside


def plan_mode_checks(task, cols, jobs, force_margin=0.0) -> dict:
    """:func:`mode_checks` (with the job's ``v_rows``) then, with a task's disturbance, :func:`disturbance_checks`
    at every row of ``jobs`` at once: the same verdicts and messages.

    Every row x block (the undisturbed scene, then each vertex of ``task.disturbance``) x friction vector is solved in
    one call of :func:`qsplan.mechanics.solver.many.solve_many_scenes` (a block's load, ``g_obj`` plus its wrench,
    as :func:`disturbance_checks` builds it; a long plan's rows in several, :data:`FORCES_PER_CALL`), the vectors
    whose degenerate modes need a second look at :data:`EXACT_TOLERANCES` in one more.

    Parameters
    ----------
    jobs : sequence of ModeJob
    force_margin : float
        N (:func:`mode_checks`).

    Returns
    -------
    dict of int to (list of (kind, message), tuple of str)
        Per row: its failures (the mode check's, then the disturbance check's) and the modes set aside as degenerate
        to machine precision (the undisturbed scene's, as :func:`mode_checks` returns them).
    """
    from qsplan.mechanics.modes.counting import count_modes

    wrenches = [] if task.disturbance is None else [np.asarray(w, dtype=float) for w in task.disturbance.vertices()]
    out, part, size = {}, [], 0
    for job in jobs:
        n_c = job.scene.n_contacts
        need = (1 + len(wrenches)) * len(job.mus) * count_modes(n_c, job.scene.dof) * (n_c + 3)
        if part and size + need > FORCES_PER_CALL:
            out.update(_mode_checks_call(cols, part, force_margin, wrenches))
            part, size = [], 0
        part.append(job)
        size += need
    if part:
        out.update(_mode_checks_call(cols, part, force_margin, wrenches))
    return out


def _mode_checks_call(cols, jobs, force_margin, wrenches) -> dict:
    """:func:`plan_mode_checks` of ``jobs`` in one call of the solver (and one for the second looks)."""
    from qsplan.mechanics.solver.many import solve_many_scenes

    B = 1 + len(wrenches)

    def block_loads(scene, m):  # (B m, 3): the scene's g_obj, then g_obj + w for each vertex, m vectors each
        return np.concatenate([np.broadcast_to(g, (m, 3)) for g in [scene.g_obj] + [scene.g_obj + w for w in wrenches]])

    scenes = [job.scene for job in jobs]
    answers = solve_many_scenes(scenes, [np.tile(job.mus, (B, 1)) for job in jobs], DEFAULT_TOLERANCES,
                                loads=[block_loads(job.scene, len(job.mus)) for job in jobs])  # fmt: skip
    judges = [_RowJudge(job, str(cols["mode"][job.row]), sv, B) for job, sv in zip(jobs, answers)]
    loads = [block_loads(job.scene, 1) for job in jobs]
    tight = solve_many_scenes(scenes, [job.mus[[i for _, i in judge.looks]].reshape(-1, job.mus.shape[1])
                                       for job, judge in zip(jobs, judges)], EXACT_TOLERANCES,
                              loads=[g[[b for b, _ in judge.looks]].reshape(-1, 3) for g, judge in zip(loads, judges)],
                              forces=False)  # fmt: skip
    return {job.row: judge.verdicts(t.codes, force_margin, _position(cols, job), wrenches)
            for job, judge, t in zip(jobs, judges, tight)}
