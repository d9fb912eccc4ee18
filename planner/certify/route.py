"""The certifier's plan-level checks: the rows form one motion from the task's start to its goal (issue 21).

Besides each row's own checks (:mod:`qsplan.planner.certify.rows`, :mod:`~qsplan.planner.certify.modes`,
:mod:`~qsplan.planner.certify.bands`), a plan must be one motion the task asks for:

* ``time`` / ``phase`` (:func:`structure_checks`): time starts at 0 and grows strictly inside a phase (rows of two
  phases may share the switch's time); phases are numbered 0, 1, 2, ... in row order, and every row of a phase
  has the phase's mode and effort joint;
* ``start`` / ``goal`` (:func:`endpoint_checks`): the first row is the task's start (the workpiece at
  ``start_x``, the fingers on the start's features, a described hand's free joints at the task's ``[start]``), the
  last row its goal (the goal's ``x`` and features), and for a scripted task each in-contact stretch ends at its
  waypoint, in order;
* ``rest`` (:func:`rest_checks`): on a regrasp (``free``) row the workpiece rests on the palm where the previous
  row left it, as the task assumes (nothing holds it);
* ``overlap`` along free motions (:func:`free_path_checks`): between two regrasp rows the controller moves the
  joints along the straight line, sampled so that no point of any link travels more than :data:`FREE_PATH_STEP`
  from one sample to the next (labelled: an overlap between samples is at most that deep).

A finger's contact features are read from the polygons (:func:`touched_features`), not from the planner.
Each check returns ``(row or None, kind, message)``; ``None``: the plan as a whole.  Units SI.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["ENDPOINT_TOL", "FEATURE_TOL", "FREE_PATH_STEP", "endpoint_checks", "free_path_checks", "orientation_checks", "rest_checks",
           "structure_checks", "touched_features"]

#: Distance (m) between a row's workpiece x and the task's start, goal or waypoint still counted as there: the
#: planner's grids hold those x exactly and the CSV round-trips doubles, so only rounding is forgiven.
ENDPOINT_TOL = 1e-9

#: Distance (m) within which a finger touches a workpiece feature: the contact tolerance of the certifier's
#: contact check (:data:`qsplan.planner.certify.rows.CONTACT_GAP_TOL`, one micron).
FEATURE_TOL = 1e-6

#: Largest travel (m) of any point of a link between two samples of a free motion: an overlap the samples miss is
#: at most this deep (twice it between the two fingers, which move at once).  A quarter millimetre is half the planner's own sweep step along regrasp lines (0.5 mm),
#: and far below a finger's 12 mm width.
FREE_PATH_STEP = 2.5e-4


def structure_checks(cols) -> list:
    """Time order and phase numbering (see the module docstring)."""
    t, ph, mode, eff = cols["t"], cols.get("phase"), cols["mode"], cols["effort_joint"]
    out = []
    if not t[0] == 0.0:
        out.append((0, "time", f"the plan starts at t = {t[0]:.6g} s; expected 0"))
    if ph is None:
        return out + [(None, "phase", "the plan has no phase column")]
    if not np.all(np.isfinite(ph)) or np.any(ph != np.round(ph)):
        k = int(np.flatnonzero(~np.isfinite(ph) | (ph != np.round(ph)))[0])
        return out + [(k, "phase", f"phase {float(ph[k])!r} is not an integer index")]
    if ph[0] != 0:
        out.append((0, "phase", f"the first row is in phase {int(ph[0])}; expected 0"))
    step = np.diff(ph)
    for k in np.flatnonzero((step != 0) & (step != 1))[:1]:
        out.append((int(k) + 1, "phase", f"phase goes from {int(ph[k])} to {int(ph[k + 1])}; expected the same or the next"))
    dt = np.diff(t)
    same = step == 0
    for k in np.flatnonzero(same & ~(dt > 0))[:1]:
        out.append((int(k), "time", f"time goes from {t[k]:.17g} s to {t[k + 1]:.17g} s inside phase {int(ph[k])}; "
                                    "expected it to grow"))  # fmt: skip
    # a phase keeps its mode and effort joint; its mode's letters change only where its contact set does (a pivot's
    # first row judges the transition with the contact that lifts: qsplan.planner.certify.contacts)
    letters = np.array([len(str(m)) for m in mode])
    changed = (mode[:-1] != mode[1:]) & (letters[:-1] == letters[1:])
    for k in np.flatnonzero(same & (changed | (eff[:-1] != eff[1:])))[:1]:
        out.append((int(k) + 1, "phase", f"mode {mode[k + 1]} / effort joint {eff[k + 1]} inside phase {int(ph[k])}, "
                                         f"whose rows before are {mode[k]} / {eff[k]}"))  # fmt: skip
    return out


def _user_edge(hand, e: int) -> int:
    from qsplan.hands.paper_hand.grasps import user_edge

    return user_edge(hand, e)


def touched_features(task, bodies, finger: int) -> set:
    """The workpiece features finger ``finger`` (0 left, 1 right) touches, in the user's numbering: ``("vertex", K)``
    for a workpiece vertex on one of its links, ``("edge", K)`` for a link corner on workpiece edge ``K``."""
    from shapely.geometry import LineString, Point

    polys = bodies["polys"]
    wp = polys["workpiece"]
    W = np.asarray(wp.exterior.coords)[:-1]
    edges = [LineString([W[e], W[(e + 1) % len(W)]]) for e in range(len(W))]
    out = set()
    for name in task.hand.finger_joint_names[finger]:
        link = polys[name]
        if link.distance(wp) > FEATURE_TOL:
            continue
        out |= {("vertex", int(task.hand.vertex_order[i])) for i, v in enumerate(W) if link.distance(Point(v)) <= FEATURE_TOL}
        for u in np.asarray(link.exterior.coords)[:-1]:
            out |= {("edge", _user_edge(task.hand, e)) for e, seg in enumerate(edges) if seg.distance(Point(u)) <= FEATURE_TOL}
    return out


def _feature_text(feature) -> str:
    return f"{feature[0]}:{feature[1]}"


def _finger_claims(task, bodies, wanted, where: str, row: int) -> list:
    """Each finger touches the workpiece, on the feature ``wanted[f]`` names (``None`` or ``("inner", None)``: any vertex
    on its inner edge, the paper hand's default; ``None`` for a described hand: anywhere)."""
    out = []
    for f, side in enumerate(("left", "right")):
        got = touched_features(task, bodies, f)
        want = wanted[f]
        if not got:
            out.append((row, where, f"the {side} finger does not touch the workpiece at the {where}"))
        elif want is not None and want[0] == "inner" and not any(kind == "vertex" for kind, _ in got):
            out.append((row, where, f"the {side} finger touches {', '.join(map(_feature_text, sorted(got)))} at the "
                                    f"{where}; the task's start has its inner edge on a vertex"))  # fmt: skip
        elif want is not None and want[0] != "inner" and tuple(want) not in got:
            out.append((row, where, f"the {side} finger touches {', '.join(map(_feature_text, sorted(got)))} at the "
                                    f"{where}; the task asks for {_feature_text(want)}"))  # fmt: skip
    return out


def endpoint_checks(task, cols, first_bodies, last_bodies) -> list:
    """The first row is the task's start, the last its goal; a scripted task's stretches end at its waypoints."""
    x, n = cols["x_workpiece"], cols["t"].size
    out = []
    if abs(x[0] - task.start_x) > ENDPOINT_TOL:
        out.append((0, "start", f"the workpiece starts at x = {x[0]:.9g} m; the task starts it at {task.start_x:.9g} m"))
    free = bool(task.hand.free_joints)  # a hand with free joints starts from them; the others from features
    out += _finger_claims(task, first_bodies, (None, None) if free else task.start_features, "start", 0)
    if free and task.start_joints is not None:
        names = task.hand.joint_names
        for j in task.hand.free_joints:
            q0 = cols[f"q_{names[j]}"][0]
            if abs(q0 - task.start_joints[j]) > ENDPOINT_TOL:
                out.append((0, "start", f"joint {names[j]} starts at {q0:.9g}; the task's [start] gives "
                                        f"{task.start_joints[j]:.9g}"))  # fmt: skip
    if task.goal is not None:
        out += orientation_checks(task, cols, last_bodies)
        if task.goal.x is not None and abs(x[-1] - task.goal.x) > ENDPOINT_TOL:
            out.append((n - 1, "goal", f"the plan ends with the workpiece at x = {x[-1]:.9g} m; the goal is "
                                       f"{task.goal.x:.9g} m"))  # fmt: skip
        out += _finger_claims(task, last_bodies, (task.goal.left, task.goal.right), "goal", n - 1)
        return out
    contact = cols["mode"] != "free"
    ends = [i for i in range(n) if contact[i] and (i + 1 == n or not contact[i + 1])]
    wp = list(task.waypoints)
    if len(ends) != len(wp):
        out.append((None, "goal", f"{len(ends)} in-contact stretches; the task scripts {len(wp)} segments"))
    for i, (k, w) in enumerate(zip(ends, wp)):
        if abs(x[k] - w) > ENDPOINT_TOL:
            out.append((k, "goal", f"in-contact stretch {i + 1} ends at x = {x[k]:.9g} m; the task's waypoint {i} is {w:.9g} m"))
    return out


def orientation_checks(task, cols, last_bodies) -> list:
    """The plan ends at the goal's orientation: ``theta`` within :data:`ENDPOINT_TOL` (rad), and what the goal's
    ``palm`` names on the palm (``edge:K``: both its ends; ``vertex:K``: that vertex), K as the task writes it."""
    from shapely.geometry import Point

    from qsplan.hands.geometry.workpiece import workpiece_world

    from qsplan.planner.certify.rows import CONTACT_GAP_TOL, row_pose

    goal, n = task.goal, cols["t"].size
    pose = row_pose(cols, n - 1)
    out = []
    if goal.theta is not None and abs(pose[2] - goal.theta) > ENDPOINT_TOL:
        out.append((n - 1, "goal", f"the plan ends with the workpiece at theta = {pose[2]:.9g} rad; the goal is "
                                   f"{goal.theta:.9g} rad"))  # fmt: skip
    if goal.palm is not None:
        kind, k = goal.palm
        hand = task.hand
        internal = list(hand.user_edges if kind == "edge" else hand.user_vertices).index(k)
        ends = [internal, (internal + 1) % len(hand.workpiece)] if kind == "edge" else [internal]
        W = workpiece_world(hand, pose)
        gaps = [Point(W[i]).distance(last_bodies["polys"]["palm"]) for i in ends]
        if max(gaps) > CONTACT_GAP_TOL:
            out.append((n - 1, "goal", f"the goal rests {kind} {k} on the palm; at the plan's end it is "
                                       f"{max(gaps) * 1e3:.4g} mm above it"))  # fmt: skip
    return out


def rest_checks(task, cols, k, bodies, proved=None) -> list:
    """A regrasp row: the workpiece where the previous row left it, resting on the palm on its bottom edge; or, where
    it does not (a finger replaced mid-turn, :mod:`qsplan.planner.plan.replace`), held by what one finger that does
    not move in the phase and the palm touch while the other finger's joints move, that hold proved over the task's
    friction box and disturbance box (:func:`qsplan.planner.plan.replace.lifted_hold`, the planner's rule).
    ``proved``: a dict the moving fingers and the proof are kept in, one per run of free rows (its first row's index).
    """
    from shapely.geometry import Point

    from qsplan.planner.certify.rows import CONTACT_GAP_TOL, JUMP_TOL, moving_fingers, row_pose, row_q

    out = []
    if k > 0:
        moved = np.abs(row_pose(cols, k) - row_pose(cols, k - 1))
        if np.any(moved > JUMP_TOL):
            out.append(("rest", f"the workpiece moves by ({moved[0] * 1e3:.4g} mm, {moved[1] * 1e3:.4g} mm, "
                                f"{moved[2]:.4g} rad) from the previous row while no finger holds it (a free row)"))  # fmt: skip
    W = np.asarray(bodies["polys"]["workpiece"].exterior.coords)[:-1]
    gaps = [Point(W[i]).distance(bodies["polys"]["palm"]) for i in (0, 1)]
    if max(gaps) <= CONTACT_GAP_TOL:
        return out
    first = int(_free_run(cols, k)[0])
    proved = {} if proved is None else proved
    if first not in proved:  # once per run of free rows: the fingers that move, and the hold without the moving one
        from qsplan.planner.plan.replace import lifted_hold

        moving = moving_fingers(task, cols, _free_run(cols, k))
        proof = None if len(moving) != 1 else lifted_hold(task, row_pose(cols, first),
                                                          row_q(cols, first, task.hand.joint_names), moving[0])
        proved[first] = moving, proof
    moving, proof = proved[first]
    if len(moving) != 1:
        out.append(("rest", f"the workpiece does not rest on the palm on its bottom edge on a free row (its ends "
                            f"{gaps[0] * 1e3:.4g} mm and {gaps[1] * 1e3:.4g} mm above it), and "
                            f"{'both fingers move' if moving else 'no finger moves'} in this run of free rows: only "
                            f"a finger replaced while the other holds it is certified"))  # fmt: skip
    elif not proof.proved:
        out.append(("rest", f"the workpiece rests on the palm and the {'right' if moving[0] == 'left' else 'left'} "
                            f"finger while the {moving[0]} finger moves, and that hold is not proved over the "
                            f"friction box: {proof.reason}"))  # fmt: skip
    return out


def _free_run(cols, k) -> np.ndarray:
    """The rows of row ``k``'s run of free rows (consecutive, one phase where the file numbers them)."""
    n = cols["t"].size
    phase = cols.get("phase", np.full(n, np.nan))
    same = lambda i: str(cols["mode"][i]) == "free" and (phase[i] == phase[k] or np.isnan(phase[k]))  # noqa: E731
    lo, hi = k, k
    while lo > 0 and same(lo - 1):
        lo -= 1
    while hi + 1 < n and same(hi + 1):
        hi += 1
    return np.arange(lo, hi + 1)


def _reach(man) -> np.ndarray:
    """Per joint, a bound (m) on how far any point of the links it moves lies from its axis: along the chain, the
    joint offsets and prismatic travel after it plus the farthest link vertex (a prismatic joint: 1, the travel
    itself counts)."""
    n = man.n_joints
    radius = np.array([0.0 if j.link_shape is None else float(np.max(np.hypot(*np.asarray(j.link_shape, float).T)))
                       for j in man.joints])  # fmt: skip
    out = np.zeros(n)
    for j in range(n):
        best = radius[j]
        for i in range(j + 1, n):  # descendants come after their parents
            path, p = 0.0, i
            while p > j:
                path += float(np.hypot(*man.joints[p].origin[:2]))
                p = man.joints[p].parent
            if p == j:
                best = max(best, path + radius[i])
        out[j] = best if man.joints[j].kind == "revolute" else 1.0
    return out


def free_path_checks(task, cols, k, roots) -> list:
    """Overlaps along the straight joint-space line from free row ``k`` to row ``k + 1`` (both free, one phase)."""
    from qsplan.planner.certify.rows import bodies_at, body_overlaps, row_pose, row_q

    names = task.hand.joint_names
    q0, q1 = row_q(cols, k, names), row_q(cols, k + 1, names)
    dq = q1 - q0
    man = task.hand.manipulator
    # a prismatic joint's travel moves the links after it further out: bound it by its largest extension
    extra = sum(max(abs(a), abs(b)) for (a, b), jt in zip(task.joint_limits, man.joints) if jt.kind == "prismatic")
    step = np.abs(dq) * (_reach(man) + extra * np.array([jt.kind == "revolute" for jt in man.joints]))
    # each finger is one body chain: its points move at most the sum over its joints (the fingers move independently)
    travel = max(float(np.sum(step[[names.index(n) for n in chain]])) for chain in task.hand.finger_joint_names)
    n = max(1, math.ceil(travel / FREE_PATH_STEP))
    pose = row_pose(cols, k)
    for s in range(1, n):
        found = body_overlaps(task, bodies_at(task, pose, q0 + dq * (s / n), roots))
        if found:
            return [(kind, f"between this row and the next (free motion, {s} of {n} samples): {msg}") for kind, msg in found]
    return []
