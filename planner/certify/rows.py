"""The row checks of the plan certifier (:mod:`qsplan.planner.certify.certify`), each rebuilt from the task alone.

Every function here takes the task, the plan's columns (``{name: ndarray}`` as
:func:`qsplan.planner.export.plan_files.read_plan_csv` returns them) and a row
index, and returns ``(kind, message)`` pairs: nothing of the planner's own
validity checker or band computation is used.  The geometry comes from the
hand's polygons (:meth:`qsplan.hands.protocol.Hand.body_polygons`: the paper's hand or any
described chain hand, every joint of it); the mechanics of a row (the mode check) is in
:mod:`qsplan.planner.certify.modes`.  Units SI (m, rad, s, N, N m; a prismatic joint's
positions, speeds and efforts in m, m/s and N).
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "OVERLAP_DEPTH_TOL",
    "CONTACT_GAP_TOL",
    "JOINT_HOUSING",
    "LIMIT_TOL",
    "SPEED_RTOL",
    "JUMP_TOL",
    "COMMAND_RTOL",
    "row_pose",
    "row_q",
    "moving_fingers",
    "joint_speeds",
    "overlap_pairs",
    "joint_housings",
    "row_bodies",
    "bodies_at",
    "body_overlaps",
    "overlap_checks",
    "limit_checks",
    "step_checks",
    "command_step_checks",
    "friction_points",
]

#: Penetration (m) tolerated between two bodies: the depth (the narrowest width) of
#: their intersection.  The fingers touch the workpiece by tangency and the workpiece
#: rests on the palm, so touching bodies compute as overlapping by ~1e-15 m per metre of
#: scene; one micron is :data:`qsplan.mechanics.CONTACT_TOL`, the distance the contact
#: finder itself treats as touching, far below any overlap a planar hand could tolerate.
OVERLAP_DEPTH_TOL = 1e-6

#: Distance (m) within which a contact the mode lists counts as present (the same micron).
CONTACT_GAP_TOL = 1e-6

#: Radius of a revolute joint's housing in link widths: a link's root turns inside the body
#: that carries it (the palm, or the parent link: its rectangle is centred on the joint axis),
#: so the link is checked against its carrier only outside a disk this many widths about its
#: joint.  1.12 is the disk through the corners of one link width of root (hypot(1, 1/2)).  A
#: prismatic joint's link never turns inside its carrier: no housing.
JOINT_HOUSING = float(np.hypot(1.0, 0.5))

#: Joint positions (rad or m) beyond a limit by less than this are inside: the CSV holds full
#: double precision (repr round trip), so only the planner's own rounding is forgiven.
LIMIT_TOL = 1e-9

#: Relative excess tolerated on a speed limit (finite differences and exported commands).
#: A finite difference of a path that respects the limit never exceeds it (mean value
#: theorem), so this only absorbs rounding of ``dt`` (decimal times) and of the angles.
SPEED_RTOL = 1e-6

#: Jump (rad or m) tolerated between two rows at the same time (a phase switch): rounding.
JUMP_TOL = 1e-9

#: Relative difference tolerated between an in-contact step of a velocity-controlled joint and the trapezoid of
#: its velocity commands: the commands sample the closed-form rate of a smooth path at 0.5 mm of workpiece
#: travel, whose trapezoid errs by about dt^3 (d3q/dt3) / 12, well under 1 % of a step on the bundled plans.
COMMAND_RTOL = 1e-2

def row_pose(cols, k) -> np.ndarray:
    """Workpiece ``(x, y, theta)`` of row ``k`` (m, m, rad), shape (3,)."""
    return np.array([cols["x_workpiece"][k], cols["y_workpiece"][k], cols["theta_workpiece"][k]], dtype=float)


def row_q(cols, k, names=("left", "right")) -> np.ndarray:
    """Joint positions of row ``k`` over the joints ``names`` (the hand's, in its order) (rad or m), shape (n_j,)."""
    return np.array([cols[f"q_{n}"][k] for n in names], dtype=float)


def moving_fingers(task, cols, rows) -> list:
    """The fingers (``"left"``, ``"right"``) whose joints change over ``rows`` (a run of rows), in the hand's order."""
    names = task.hand.joint_names
    q = np.array([row_q(cols, k, names) for k in rows])
    return [f for f, joints in zip(("left", "right"), task.hand.finger_joints) if np.any(np.ptp(q[:, list(joints)], axis=0) > 0)]


def joint_speeds(task) -> np.ndarray:
    """Speed limit of each joint (rad/s or m/s), shape (n_j,): :attr:`Task.joint_speeds`."""
    return np.asarray(task.joint_speeds, dtype=float)


def joint_housings(hand) -> dict:
    """``{link: (carrier, joint index, radius (m), disk or None)}`` for every revolute joint's link: the disk (shapely)
    about the joint's axis inside which the link may overlap its carrier (``"palm"`` or the parent link's name).

    The disk is built here when the axis cannot move (a joint on the palm), else per row (:func:`row_bodies`).
    """
    from shapely.geometry import Point

    man = hand.manipulator
    axes = hand.joint_axes(np.zeros(man.n_joints))
    out = {}
    for j, joint in enumerate(man.joints):
        if joint.kind != "revolute" or joint.link_shape is None:
            continue
        y = np.asarray(joint.link_shape, dtype=float)[:, 1]
        radius = JOINT_HOUSING * float(y.max() - y.min())  # the link's width across its axis
        fixed = joint.parent < 0
        carrier = "palm" if fixed else man.joints[joint.parent].name
        out[joint.name] = (carrier, j, radius, Point(axes[j]).buffer(radius, 64) if fixed else None)
    return out


def row_bodies(task, cols, k, roots=None) -> dict:
    """The bodies of row ``k`` as shapely geometry: ``{"polys": {name: Polygon}, "roots": {link: (carrier, disk)}}``.

    Built once per row and passed to :func:`overlap_checks` and :func:`rest_checks`;
    ``roots``: :func:`joint_housings` of the task's hand, when already built (a joint on a moving link gets its
    disk about its axis at the row's joint positions).
    """
    return bodies_at(task, row_pose(cols, k), row_q(cols, k, task.hand.joint_names), roots)


def bodies_at(task, pose, q, roots=None) -> dict:
    """:func:`row_bodies` at workpiece pose ``pose`` (3,) and joint positions ``q`` (n_j,) (m, rad)."""
    from shapely.geometry import Point, Polygon

    polys = {name: Polygon(v) for name, v in task.hand.body_polygons(pose, q).items()}
    housings = joint_housings(task.hand) if roots is None else roots
    axes = None
    disks = {}
    for link, (carrier, j, radius, disk) in housings.items():
        if disk is None:
            axes = task.hand.joint_axes(q) if axes is None else axes
            disk = Point(axes[j]).buffer(radius, 64)
        disks[link] = (carrier, disk)
    return {"polys": polys, "roots": disks}


def _depth(inter) -> float:
    """Narrowest width (m) of an intersection: per part, its convex hull's smallest extent across one of the
    hull's edges (the penetration depth of a vertex or an edge pushed in); the largest over parts."""
    best = 0.0
    for part in getattr(inter, "geoms", (inter,)):
        if part.is_empty or part.area == 0.0:
            continue
        hull = np.asarray(part.convex_hull.exterior.coords)[:-1]
        edges = np.roll(hull, -1, axis=0) - hull
        lengths = np.hypot(edges[:, 0], edges[:, 1])
        normals = np.stack([-edges[:, 1], edges[:, 0]], axis=1)[lengths > 0] / lengths[lengths > 0, None]
        widths = hull @ normals.T
        best = max(best, float((widths.max(axis=0) - widths.min(axis=0)).min()))
    return best


def _label(name: str) -> str:
    """A body in words: the paper's fingers ``"left finger"``, a chain hand's links ``"left_distal link"``."""
    if name in ("palm", "workpiece"):
        return name
    return f"{name} finger" if name in ("left", "right") else f"{name} link"


def overlap_pairs(hand) -> tuple:
    """The pairs :func:`overlap_checks` tests, in order: every two links, each link and the workpiece, the workpiece
    and the palm, each link and the palm (the paper's hand: left/right, left/workpiece, right/workpiece,
    workpiece/palm, left/palm, right/palm)."""
    from itertools import combinations

    links = hand.joint_names
    return (tuple(combinations(links, 2)) + tuple((n, "workpiece") for n in links) + (("workpiece", "palm"),)
            + tuple((n, "palm") for n in links))  # fmt: skip


def overlap_checks(task, cols, k, bodies=None) -> list:
    """Check 1: no two bodies (links, palm, workpiece) overlap deeper than :data:`OVERLAP_DEPTH_TOL`; a link and its
    carrier outside the link's joint housing.

    ``bodies``: :func:`row_bodies` of the row, when already built.
    """
    return body_overlaps(task, row_bodies(task, cols, k) if bodies is None else bodies)


def body_overlaps(task, bodies) -> list:
    """:func:`overlap_checks` of bodies built by :func:`bodies_at`."""
    polys, roots, out = bodies["polys"], bodies["roots"], []
    for a, c in overlap_pairs(task.hand):
        A, C = polys[a], polys[c]
        if a in roots and roots[a][0] == c:  # the link first, clipped, as its housing allows
            A = A.difference(roots[a][1])
        elif c in roots and roots[c][0] == a:
            C = C.difference(roots[c][1])
        inter = A.intersection(C)
        depth = _depth(inter)
        if depth > OVERLAP_DEPTH_TOL:
            out.append(("overlap", f"{_label(a)} / {_label(c)} overlap {inter.area * 1e6:.3g} mm^2, "
                                   f"{depth * 1e3:.3g} mm deep"))  # fmt: skip
    return out


def limit_checks(task, cols, k) -> list:
    """Check 2 (one row): joint limits, exported joint-speed commands, the effort inside its band, one command per
    joint (a torque for the row's ``effort_joint``, a velocity for every other joint)."""
    names = task.hand.joint_names
    units, speeds = task.hand.joint_units(), joint_speeds(task)
    out = []
    q = row_q(cols, k, names)
    if not np.all(np.isfinite(q)) or not np.all(np.isfinite(row_pose(cols, k))):
        return [("input", "a joint angle or the workpiece pose is not a finite number")]
    for j, side in enumerate(names):
        lo, hi = task.joint_limits[j]
        u = units[j]
        if q[j] < lo - LIMIT_TOL or q[j] > hi + LIMIT_TOL:
            out.append(("joint limit", f"{side} joint at {q[j]:.6g} {u}, outside its limits [{lo:g}, {hi:g}] {u}"))
        qd = cols[f"qd_{side}"][k]
        if np.isfinite(qd) and abs(qd) > speeds[j] * (1 + SPEED_RTOL):
            out.append(("speed", f"{side} joint speed command {qd:.6g} {u}/s beyond the limit {speeds[j]:g} {u}/s"))
    out += control_checks(cols, k, names)
    if cols["mode"][k] == "free":
        return out
    e = str(cols["effort_joint"][k])
    if e not in names:
        listed = " or ".join(repr(n) for n in names)
        return out + [("input", f"effort_joint {e!r}: expected {listed} on an in-contact row")]
    revolute = units[names.index(e)] == "rad"
    unit, what, symbol = ("N m", "torque", "tau") if revolute else ("N", "force", "f")
    tau, lo, hi = (float(cols[f"tau_{e}{s}"][k]) for s in ("", "_min", "_max"))
    if not np.isfinite(tau) or np.isnan(lo) or np.isnan(hi):
        out.append(("torque", f"{e} joint: no {what} command or band ({symbol} = {tau}, band [{lo}, {hi}])"))
    elif not lo <= tau <= hi:
        edge = lo if tau < lo else hi
        out.append(("torque", f"{e} joint {what} {tau:.6g} {unit} outside its band [{lo:.6g}, {hi:.6g}] {unit} "
                              f"({abs(tau - edge):.3g} {unit} past the edge)"))  # fmt: skip
    if not np.isnan(cols[f"qd_{e}"][k]):
        out.append(("input", f"{e} joint (torque-controlled): a velocity command {float(cols[f'qd_{e}'][k])!r} beside its "
                             f"{what}; one command per joint"))  # fmt: skip
    for v in names:
        if v == e:
            continue
        if not np.isfinite(cols[f"qd_{v}"][k]):
            out.append(("input", f"{v} joint (velocity-controlled): no velocity command"))
        if any(not np.isnan(cols[f"tau_{v}{s}"][k]) for s in ("", "_min", "_max")):
            out.append(("input", f"{v} joint: a torque command or band on a row whose effort_joint is {e}"))
    return out


def step_checks(task, cols, k) -> list:
    """Check 2 (rows ``k`` and ``k + 1``): time order, speed limits over the step, no jump at a switch."""
    names, units, speeds = task.hand.joint_names, task.hand.joint_units(), joint_speeds(task)
    t0, t1 = cols["t"][k], cols["t"][k + 1]
    dt = t1 - t0
    if not (np.isfinite(dt) and dt >= 0):
        return [("time", f"time goes from {t0:.6g} s to {t1:.6g} s at the next row")]
    dq = row_q(cols, k + 1, names) - row_q(cols, k, names)
    p0, p1 = row_pose(cols, k), row_pose(cols, k + 1)
    dx = float(np.hypot(*(p1[:2] - p0[:2])))
    dth = abs(p1[2] - p0[2])
    if dt == 0.0:
        jumps = [f"{s} joint {abs(d):.3g} {u}" for s, u, d in zip(names, units, dq) if abs(d) > JUMP_TOL]
        jumps += [f"workpiece {dx * 1e3:.3g} mm"] if dx > JUMP_TOL else []
        jumps += [f"workpiece {dth:.3g} rad"] if dth > JUMP_TOL else []
        return [("continuity", f"jump at t = {t0:.6g} s to the next row: " + ", ".join(jumps))] if jumps else []
    out = command_step_checks(cols, k, names, units, dq, dt)
    for side, u, limit, d in zip(names, units, speeds, dq):
        if abs(d) > limit * dt * (1 + SPEED_RTOL) + JUMP_TOL:
            out.append(("speed", f"{side} joint moves {abs(d):.4g} {u} in {dt:.4g} s to the next row: "
                                 f"{abs(d) / dt:.4g} {u}/s > limit {limit:g} {u}/s"))  # fmt: skip
    if dx > task.workpiece_speed * dt * (1 + SPEED_RTOL) + JUMP_TOL:
        out.append(("speed", f"workpiece moves {dx * 1e3:.4g} mm in {dt:.4g} s to the next row: "
                             f"{dx / dt:.4g} m/s > limit {task.workpiece_speed:g} m/s"))  # fmt: skip
    return out


def path_bend(cols, a: int, b: int, name: str) -> float:
    """How much joint ``name``'s path bends around the rows ``a``, ``b`` of one phase (rad or m): the largest change
    of its step between adjacent intervals of that phase (a second difference; 0 on a straight leg).  A velocity
    command sampled from the path's tangent and a step between rows differ by at most about this much where one
    end is at rest (the one-sided estimate errs to first order, ``q'' ds^2 / 2``)."""
    ph, q = cols["phase"], cols[f"q_{name}"]
    out = 0.0
    for i in (a - 1, a, b):
        if 0 <= i and i + 2 < q.size and ph[i] == ph[i + 2] == ph[a]:
            out = max(out, abs(float(q[i + 2] - 2 * q[i + 1] + q[i])))
    return out


def command_step_checks(cols, k, names, units, dq, dt) -> list:
    """The velocity commands reach the next row: a controller that follows them arrives where the rows say.

    Between two rows every velocity changes linearly in time (the time scaling's rule,
    :mod:`qsplan.planner.plan.timing`), so the step is the trapezoid ``(qd[k] + qd[k+1]) dt / 2``: on a regrasp
    (straight legs) exactly, to :data:`JUMP_TOL`; in contact, where ``qd`` samples the velocity of a smooth path,
    to :data:`COMMAND_RTOL` of the step (and :data:`JUMP_TOL`), and where one end is at rest (a one-sided estimate)
    to the path's bend there as well (:func:`path_bend`).
    """
    free = str(cols["mode"][k]) == "free"
    if "phase" in cols and cols["phase"][k] != cols["phase"][k + 1]:
        return []
    out = []
    for j, (n, u) in enumerate(zip(names, units)):
        a, b = cols[f"qd_{n}"][k], cols[f"qd_{n}"][k + 1]
        if np.isnan(a):
            continue  # torque-controlled: its motion follows from the contacts
        step = 0.5 * (a + b) * dt if np.isfinite(b) else np.nan
        if np.isnan(step):
            continue
        rest = "speed_scale" in cols and 0.0 in (cols["speed_scale"][k], cols["speed_scale"][k + 1])
        tol = JUMP_TOL + (0.0 if free else COMMAND_RTOL * abs(dq[j]) + (path_bend(cols, k, k + 1, n) if rest else 0.0))
        if abs(step - dq[j]) > tol:
            rule = "the trapezoid of qd"
            out.append(("motion", f"{n} joint's velocity command moves it {step:.6g} {u} to the next row ({rule}); "
                                  f"the rows move it {dq[j]:.6g} {u}"))  # fmt: skip
    return out


def friction_points(task, n_random, rng, n_contacts: int = 4) -> np.ndarray:
    """Friction vectors to test, shape (m, n_contacts): every vertex of the friction set, then ``n_random`` seeded draws.

    Box (independent coefficients): the ``2^n_contacts`` corners of ``[lo, hi]^n_contacts``; shared: ``lo`` and ``hi``.
    """
    lo, hi = task.mu_range
    n = int(n_contacts)
    if task.shared_mu:
        vertices = np.array([[lo] * n, [hi] * n], dtype=float)
        draws = np.repeat(rng.uniform(lo, hi, (n_random, 1)), n, axis=1)
    else:
        vertices = np.array(np.meshgrid(*[[lo, hi]] * n, indexing="ij")).reshape(n, -1).T.astype(float)
        draws = rng.uniform(lo, hi, (n_random, n))
    return np.unique(np.vstack([vertices, draws]), axis=0) if lo == hi else np.vstack([vertices, draws])


def control_checks(cols, k, names) -> list:
    """The row's ``control_<joint>`` cells (plans written before them have none) against its commands: ``torque`` for
    its effort joint, ``hold`` for a velocity-controlled joint commanded at rest, ``velocity`` otherwise
    (:func:`qsplan.planner.plan.table.row_control`)."""
    from qsplan.planner.plan.table import row_control

    out = []
    effort = str(cols["effort_joint"][k]) if cols["mode"][k] != "free" else None
    for v in names:
        key = f"control_{v}"
        if key not in cols:
            continue
        want = row_control(v == effort, float(cols[f"qd_{v}"][k]))
        if str(cols[key][k]) != want:
            out.append(("control", f"{key} says {str(cols[key][k])!r}; the row's commands make it {want!r}"))
    return out
