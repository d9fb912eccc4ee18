"""A pivot realised: its rows along the manifold, where its formation ends, its pieces' bands, the holds between them.

A pivot formation (:class:`qsplan.hands.formations.pivots.Pivot`) is swept from its start (a flush instant, theta 0)
toward a goal angle at rows at most :data:`PIVOT_STEP` apart (:func:`pivot_geometry`), and ends at its first **event**
(:class:`PivotEnd`): no configuration (a finger out of reach), a joint limit or two bodies overlapping, the polygons
showing another contact set (a contact made or lost), a contact leaving its edge.  Along the valid rows a contact's
sliding direction may **reverse** (eq. 16: it rolls for an instant, 4S does not hold there): the pivot is then cut
into pieces at each reversal's angle, each piece a 4S phase that starts and ends at rest, joined by a certified hold
(:func:`hold_phase`) in which the torque-controlled finger's torque ramps from one piece's command to the next.

Each piece's rows are judged as the certifier judges them (:mod:`qsplan.planner.certify`): the contacts the polygons
show, in the canonical order (:func:`qsplan.hands.contacts.found.row_contact_scene`); a row at rest (a piece's ends)
for the straight line to its neighbour; the first piece's first row with the bottom edge's lifting vertex too (its
letter ``B``: the transition from the flush instant); the last row without a contact it makes there (an edge
landing).  Its band is :func:`qsplan.mechanics.robust_band`'s for 4S with every competitor precluded (exact or
conservative and labelled), and at its rows at rest also the proved hold interval.  Of the two closing joints the one
whose narrowest band is widest is torque-controlled (the finger not lying flush on a tie: it pushes, as in the
paper's Fig. 9).  Units SI (m, rad, s, N m; N for a prismatic joint's effort).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from qsplan.planner.plan.results import HoldPhase, PivotPhase, PlanFailure

__all__ = ["AFTER_SLIDE", "IN_SEARCH", "HOLD_MIN_DURATION", "HOLD_ROWS", "HOLD_TORQUE_RATE", "PIVOT_STEP", "PivotEnd",
           "PivotGeometry", "hold_phase", "piece_phase", "pivot_geometry", "pivot_thetas", "widest_piece"]

#: The pivot's rows are at most this far apart in the workpiece's angle (rad): 0.25 deg, 0.4 mm at the farthest
#: vertex of the demo's workpiece, like the slides' 0.5 mm rows.
PIVOT_STEP = np.radians(0.25)

#: The rate (N m/s) at which a hold ramps the torque-controlled finger's torque: the demo's step of ~3.7 N m takes
#: about 1.9 s, slow beside a servo's torque loop (ms) so the finger's compliance follows it without a kick.
HOLD_TORQUE_RATE = 2.0

#: Rows of a hold (the ramp's ends decide its proof; the rows between are for plots and a controller's table).
HOLD_ROWS = 11

#: The shortest hold (s), when its ramp is short or nothing ramps: its rows' times must grow, and a controller
#: switching which joint it drives by torque gets a tenth of a second at rest to settle.
HOLD_MIN_DURATION = 0.1

#: Bracket (rad) to which a slip reversal's angle is bisected: 5.7e-5 deg, far below a row's step.
REVERSAL_TOL = 1e-6

#: ``planner_status`` of a hold that fails after the slide to its flush instant was planned.
AFTER_SLIDE = "ran: the slide to the flush instant planned; the hold and pivot stopped here"

#: ``planner_status`` of a pivot's piece without a band: the formation search judges a pivot before its slide.
IN_SEARCH = "ran: the formation search, which judges a pivot before the slide to it; this pivot stops here"


@dataclass(frozen=True, slots=True)
class PivotEnd:
    """Where a pivot's formation ends before its goal: the first row past it (``row``), its angle (rad), the event's
    kind (``"reach"``, ``"configuration"``, ``"contacts"``, ``"edge"``) and the event in words."""

    row: int
    theta: float
    event: str
    words: str


@dataclass(frozen=True, slots=True, eq=False)
class PivotGeometry:
    """A pivot swept toward its goal (:func:`pivot_geometry`).

    Attributes
    ----------
    path : qsplan.hands.formations.pivots.PivotPath
        Every row, its goal's included (rows past ``end`` are not part of the formation).
    end : PivotEnd or None
        The first event before the goal; None: the rows reach the goal.
    cuts : tuple of float
        The angles (rad) at which a contact's sliding direction reverses, in turning order: the pieces' ends.
    """

    path: object
    end: PivotEnd | None
    cuts: tuple


def pivot_thetas(theta0: float, theta1: float, step: float = PIVOT_STEP) -> np.ndarray:
    """Rows' angles (rad) from ``theta0`` to ``theta1``, both included, at most ``step`` apart."""
    n = int(np.ceil(abs(theta1 - theta0) / step)) + 1
    return np.linspace(theta0, theta1, max(n, 2))


def _expected_contacts(i: int, flush: bool) -> int:
    """Contacts a pivot's row touches: the flush instant's five at its first row (``flush``: the pivot starts there),
    then four."""
    return 5 if i == 0 and flush else 4


def pivot_geometry(task, pivot, start, theta_goal: float, step: float = PIVOT_STEP) -> PivotGeometry:
    """``pivot`` swept from configuration ``start`` (its flush instant, or a configuration on it mid-turn: a finger
    replaced there, :mod:`qsplan.planner.plan.replace`) to ``theta_goal`` (rad), its first event and the slip
    reversals before it (module docstring); ``step``: the rows' spacing (rad; a coarser one screens a formation
    cheaply: an event it finds is one, while one it misses between its rows the fine sweep finds)."""
    from qsplan.hands.contacts.found import made_contacts, ordered_contacts
    from qsplan.hands.formations.manifold import along_edges
    from qsplan.hands.formations.pivots import pivot_path
    from qsplan.mechanics.errors import SceneError
    from qsplan.planner.states.contact import configuration_problem

    hand = task.hand
    flush = float(start[2]) == 0.0  # the flush instant (theta 0 exactly); mid-turn otherwise
    path = pivot_path(hand, pivot, start, pivot_thetas(float(start[2]), theta_goal, step))
    cons = pivot.constraints(hand)
    n, end, contacts = path.theta.size, None, []
    for i in range(n):
        if i >= path.reached:
            end = PivotEnd(i, float(path.theta[i]), "reach", "no configuration of the formation: a finger cannot "
                                                             "close onto its feature there")  # fmt: skip
            break
        pose, q = path.pose[i], path.q[i]
        why = configuration_problem(task, pose, q)
        if why:
            end = PivotEnd(i, float(path.theta[i]), "configuration", why)
            break
        along = along_edges(hand, cons, np.concatenate([pose, q]))
        off = [j for j in (0, 3) if not 0.0 <= along[j] <= 1.0]
        if off:
            what = "the pivot vertex leaves the palm's top" if off[0] == 0 else "the other finger's contact leaves its edge"
            end = PivotEnd(i, float(path.theta[i]), "edge", what)
            break
        try:
            found = ordered_contacts(hand, pose, q)
        except SceneError as exc:
            end = PivotEnd(i, float(path.theta[i]), "configuration", str(exc))
            break
        contacts.append(found)
        if i == n - 1 and i > 0:  # the goal's row may make a contact (an edge landing): not in the motion
            prev = (path.pose[i - 1], path.q[i - 1])
            found = [f for f, m in zip(found, made_contacts(hand, prev, (pose, q), found)) if not m]
        if len(found) != _expected_contacts(i, flush):
            end = PivotEnd(i, float(path.theta[i]), "contacts", f"the polygons show {len(found)} contacts; the "
                                                                f"formation has {_expected_contacts(i, flush)}")  # fmt: skip
            break
    valid = n if end is None else end.row
    cuts = _reversals(task, pivot, path, valid, contacts, 1 if flush else 0)
    return PivotGeometry(path, end, cuts)


def _slips(hand, pose, q, dpose, dq, found=None) -> np.ndarray:
    """Each contact's sliding speed per unit turning rate (m/rad) at one row of a pivot, canonical order (eq. 6's
    ``W_t^T nu - J_t qdot`` with the manifold's tangent); ``found``: the row's contacts when already searched."""
    from qsplan.hands.contacts.found import row_contact_scene

    n_j = len(hand.joint_names)
    scene = row_contact_scene(hand, pose, q, np.zeros(n_j, bool), dq, found=found)
    nu = np.array([dpose[0] + dpose[2] * pose[1], dpose[1] - dpose[2] * pose[0], dpose[2]])
    return scene.Wt.T @ nu - scene.Jt @ dq


def _reversals(task, pivot, path, valid: int, contacts, first: int = 1) -> tuple:
    """The angles (rad, bisected to :data:`REVERSAL_TOL`) where a contact's sliding direction reverses along the
    four-contact rows ``first .. valid - 1`` of ``path`` (``contacts``: each row's, searched; ``first`` 1 after a flush
    instant, whose row has five); each later cut from the previous one's side."""
    from qsplan.hands.formations.pivots import pivot_path

    hand = task.hand
    rows = range(first, valid)
    if len(rows) < 2:
        return ()
    slips = [_slips(hand, path.pose[i], path.q[i], path.dpose[i], path.dq[i], contacts[i]) for i in rows]
    signs = [np.sign(s) for s in slips]
    cuts = []
    for a, b in zip(range(len(rows) - 1), range(1, len(rows))):
        if signs[a].size != signs[b].size:  # the goal's row makes a contact (an edge landing): nothing to compare
            continue
        flips = np.flatnonzero((signs[a] != signs[b]) & (signs[a] != 0))
        if not flips.size:
            continue
        j, i0 = int(flips[0]), rows[a]
        c0 = np.concatenate([path.pose[i0], path.q[i0]])
        lo, hi = float(path.theta[i0]), float(path.theta[rows[b]])

        def slip_at(theta, j=j, c0=c0):
            p = pivot_path(hand, pivot, c0, [theta])
            return np.sign(_slips(hand, p.pose[0], p.q[0], p.dpose[0], p.dq[0])[j])

        s_lo = signs[a][j]
        while abs(hi - lo) > REVERSAL_TOL:
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if slip_at(mid) == s_lo else (lo, mid)
        # the cut on the bracket's far side: the next piece starts with the contact's new sliding direction (a start
        # exactly at the zero is degenerate: the simulator's and a controller's first instant would read the old one);
        # the piece before ends at most REVERSAL_TOL past the zero, its slip there ~1e-8 m/rad, below any resolution
        cuts.append(hi)
    return tuple(cuts)


def _chord_rates(path, i: int, other: int) -> tuple:
    """``(d pose, d q)`` per unit of theta along the straight line from row ``i`` toward row ``other`` (a row at rest
    is judged for the motion that leaves or reaches it, as the certifier judges it)."""
    dth = float(path.theta[other] - path.theta[i])
    return (path.pose[other] - path.pose[i]) / dth, (path.q[other] - path.q[i]) / dth


def piece_phase(task, name, pivot, path, rows, effort_joint: str, rate: float, transition: bool,
                contacts=None) -> PivotPhase:  # fmt: skip
    """One piece of a pivot: ``path``'s ``rows`` (indices, in order), ``effort_joint`` torque-controlled, the other
    joints driven along the manifold at turning ``rate`` (rad/s, its sign the pivot's direction); ``transition``: the
    first row is the flush instant (the lifting vertex's letter ``B``); ``contacts``: each row's contacts, when
    already searched (:func:`qsplan.hands.contacts.found.ordered_contacts`).  Times from 0 at the quasistatic speed.

    Raises
    ------
    PlanFailure
        A row without a guaranteed band at least the torque resolution wide (naming the row's angle and why).
    """
    from qsplan.hands.contacts.found import made_contacts, ordered_contacts, row_contact_scene
    from qsplan.mechanics.bands.batched_robust import robust_bands
    from qsplan.planner.torque.command import plan_command, smooth_command

    hand = task.hand
    rows = np.asarray(rows, dtype=int)
    n = rows.size
    effort = np.array(hand.joint_names) == effort_joint
    scenes, modes = [], []
    for k, i in enumerate(rows):
        # the joints' rates: at rest the chord to the neighbour (the workpiece's follow from the contacts)
        dq = _chord_rates(path, i, rows[1] if k == 0 else rows[-2])[1] if k in (0, n - 1) else path.dq[i]
        found = ordered_contacts(hand, path.pose[i], path.q[i]) if contacts is None else contacts[k]
        drop = None
        if k == n - 1 and n > 1:  # a contact the motion makes at its last row (an edge landing) is not in it
            prev = rows[-2]
            drop = made_contacts(hand, (path.pose[prev], path.q[prev]), (path.pose[i], path.q[i]), found)
        scene = row_contact_scene(hand, path.pose[i], path.q[i], effort, dq * rate, drop=drop, found=found)
        scenes.append(scene)
        letters = ["S"] * scene.n_contacts
        if transition and k == 0:
            letters[scene.contact_names.index(f"palm:{pivot.lifting_vertex()}")] = "B"
        modes.append("".join(letters))
    kw = dict(shared=task.shared_mu, force_margin=task.force_margin, disturbance=task.disturbance)
    bands = [None] * n
    for mode in dict.fromkeys(modes):
        ks = [k for k in range(n) if modes[k] == mode]
        for k, b in zip(ks, robust_bands([scenes[k] for k in ks], mode, task.mu_range, **kw)):
            bands[k] = b
    lower = np.array([b.lower if b.feasible else np.nan for b in bands])
    upper = np.array([b.upper if b.feasible else np.nan for b in bands])
    for k in (0, n - 1):  # at rest: the hold must be proved too, with every contact there (as certified)
        held = held_interval(task, path.pose[rows[k]], path.q[rows[k]], effort)[1]
        lower[k], upper[k] = max(lower[k], held[0]), min(upper[k], held[1])
    width = upper - lower
    bad = np.flatnonzero(~(width >= task.torque_resolution))
    if bad.size:
        k = int(bad[0])
        why = bands[k].reason if not bands[k].feasible else f"the band is {width[k]:.3g} N m wide"
        raise _row_failure(task, name, path, rows[k], f"no guaranteed band at least the torque resolution "
                                                      f"({task.torque_resolution:g} N m) wide: {why}")  # fmt: skip
    command, margin = smooth_command(*plan_command(lower, upper, task.torque_resolution), lower, upper)
    dq_rows = path.dq[rows] * rate
    qd = np.where(effort[None, :], np.nan, dq_rows)
    com_rate = float(np.max(np.hypot(path.dpose[rows, 0], path.dpose[rows, 1])))
    comps = tuple(sorted({m for b in bands for m in getattr(b, "competitors", ())}))
    theta = path.theta[rows]
    return PivotPhase(name=name, effort_joint=effort_joint, mode="S" * scenes[-1].n_contacts,
                      x_path=path.pose[rows[[0, -1]], 0], t=np.abs(theta - theta[0]) / abs(rate), x=path.pose[rows, 0],
                      q=path.q[rows], qd=qd, lower=lower, upper=upper, command=command, margin=margin,
                      competitors=comps, speed=com_rate * abs(rate), planning=None, speed_scale=None,
                      formation=pivot.name, pose=path.pose[rows], row_modes=tuple(modes),
                      contacts=tuple(tuple(s.contact_names) for s in scenes))


def pivot_rate(task, path, rows) -> float:
    """The fastest turning rate (rad/s, signed: the path's direction) the speed limits allow along ``rows``: the
    workpiece's centre of mass within ``workpiece_speed``, each joint within its speed."""
    speeds = np.asarray(task.joint_speeds, float)
    rates = np.max(np.abs(path.dq[rows]), axis=0)
    com_rate = float(np.max(np.hypot(path.dpose[rows, 0], path.dpose[rows, 1])))
    limits = [task.workpiece_speed / com_rate] + [float(speeds[j] / rates[j]) for j in np.flatnonzero(rates)]
    return float(np.sign(path.theta[rows[-1]] - path.theta[rows[0]])) * min(limits)


def widest_piece(task, name, pivot, path, rows, transition: bool, progress=None) -> PivotPhase:
    """:func:`piece_phase` with each closing joint torque-controlled in turn, the one whose narrowest band is widest
    (the finger not lying flush first: it keeps a tie, and when its bands are all unbounded above the other is not
    computed); the first one's failure when neither has a band."""
    from qsplan.hands.contacts.found import ordered_contacts

    hand = task.hand
    fingers = (pivot.other_finger, pivot.flush)
    joints = [hand.joint_names[hand.closing_joints[0 if f == "left" else 1]] for f in fingers]
    rate = pivot_rate(task, path, rows)
    contacts = [ordered_contacts(hand, path.pose[i], path.q[i]) for i in rows]  # searched once for both joints
    found, first_failure = [], None
    for e in joints:
        if found and np.isinf(np.min(found[0].width)):
            break  # unbounded everywhere: nothing is wider
        try:
            found.append(piece_phase(task, name, pivot, path, rows, e, rate, transition, contacts))
        except PlanFailure as exc:
            first_failure = first_failure or exc
            if progress:
                progress(f"  {name} with {e} torque-controlled: {exc}")
    if not found:
        raise first_failure
    return max(found, key=lambda p: float(np.min(p.width)))  # max keeps the first of equals


def _row_failure(task, name, path, i, why) -> PlanFailure:
    """The report of row ``i`` of a pivot's ``path``: its angle, pose and joints, and ``why``."""
    from qsplan.planner.plan.failure import configuration_report

    q = None if np.any(np.isnan(path.q[i])) else path.q[i]
    where = f"theta = {np.degrees(path.theta[i]):.4g} deg"
    return PlanFailure(configuration_report(task, name, where, float(path.pose[i, 0]), q, why, IN_SEARCH,
                                            path.pose[i]))  # fmt: skip


def held_interval(task, pose, q, effort):
    """``(scene, (lo, hi))``: every contact present at ``pose``, ``q`` (:func:`qsplan.hands.contacts.found.hold_scene`,
    the certifier's rule: the polygons' contacts), the ``effort`` joints (bool) torque-controlled and the others held,
    and the torques at which the hold is proved with every contact loaded by the task's force margin at every vertex
    of its disturbance box (N m; nan when none)."""
    from qsplan.hands.contacts.found import hold_scene
    from qsplan.mechanics.bands.hold import hold_torque_interval

    scene = hold_scene(task.hand, pose, q, effort)
    return scene, hold_torque_interval(scene, task.disturbance, margin=task.force_margin.normal)


def hold_phase(task, name, pose, q, effort_joint, tau_from, tau_to, t0, formation: str, held=None) -> HoldPhase:
    """A hold at one configuration: ``effort_joint``'s torque ramps from ``tau_from`` to ``tau_to`` (N m) at
    :data:`HOLD_TORQUE_RATE`, every other joint held; its band the proved hold interval (:func:`held_interval`).
    ``tau_from`` None: the joint is taken over at rest (the phase before had another effort joint) and starts one
    torque resolution inside the proved interval.  ``formation``: the name the phase is recorded under.  ``held``:
    :func:`held_interval` at this configuration with ``effort_joint`` torque-controlled, when the caller has it.

    Raises
    ------
    PlanFailure
        No hold is proved there, or the ramp leaves its interval (the report names the torques).
    """
    from qsplan.mechanics.bands.hold import prove_hold
    from qsplan.planner.plan.failure import configuration_report

    effort = np.array(task.hand.joint_names) == effort_joint
    scene, (lo, hi) = held_interval(task, pose, q, effort) if held is None else held
    if tau_from is None:  # the effort joint taken over at rest: from a resolution inside the proved interval
        tau_from = float(min(lo + task.torque_resolution, tau_to)) if np.isfinite(lo) else float(tau_to)
    proofs = [prove_hold(scene, torques=[t], disturbance=task.disturbance) for t in (tau_from, tau_to)]
    room = 0.5 * task.torque_resolution  # the certifier's least slack to a band's edge (a controller's rounding)
    inside = bool(lo + room <= min(tau_from, tau_to) and max(tau_from, tau_to) <= hi - room)  # False when empty
    if not (inside and all(p.proved for p in proofs)):
        where = "the hold" if pose[2] == 0.0 else f"the hold at theta = {np.degrees(pose[2]):.4g} deg"
        raise PlanFailure(configuration_report(task, name, where, float(pose[0]), q,
                                               f"no hold is proved from {tau_from:.4g} to {tau_to:.4g} N m (proved "
                                               f"interval [{lo:.4g}, {hi:.4g}] N m)", AFTER_SLIDE, pose))  # fmt: skip
    n = HOLD_ROWS
    s = np.linspace(0.0, 1.0, n)
    command = tau_from + s * (tau_to - tau_from)
    t = t0 + s * max(abs(tau_to - tau_from) / HOLD_TORQUE_RATE, HOLD_MIN_DURATION)
    lower, upper = np.full(n, lo), np.full(n, hi)
    margin = np.minimum(command - lower, upper - command)
    qd = np.where(effort[None, :], np.nan, 0.0) * np.ones((n, 1))
    return HoldPhase(name=name, effort_joint=effort_joint, mode="R" * len(scene.contact_names),
                     x_path=np.array([pose[0]]), t=t, x=np.full(n, pose[0]), q=np.tile(q, (n, 1)), qd=qd, lower=lower,
                     upper=upper, command=command, margin=margin, competitors=(), speed=0.0, planning=None,
                     speed_scale=np.zeros(n), formation=formation, pose=np.tile(pose, (n, 1)),
                     contacts=(tuple(scene.contact_names),) * n)


def shifted(phase, dt: float):
    """``phase`` with its times moved by ``dt`` (s)."""
    return replace(phase, t=phase.t + dt)
