"""The row checks of the plan certifier (:mod:`qsplan.planner.planning.certify`), each rebuilt from the task alone.

Every function here takes the task, the plan's columns (``{name: ndarray}`` as
:func:`qsplan.planner.export.plan_files.read_plan_csv` returns them) and a row
index, and returns ``(kind, message)`` pairs: nothing of the planner's own
validity checker or band computation is used.  The geometry comes from the
hand's polygons (:func:`qsplan.hands.hand_polygons`); the mechanics of a row (the
mode check) is in :mod:`qsplan.planner.planning.certify_modes`.  Units SI (m, rad, s, N, N m).
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
    "row_pose",
    "row_q",
    "joint_housings",
    "row_bodies",
    "overlap_checks",
    "contact_checks",
    "limit_checks",
    "step_checks",
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

#: Radius of the palm's joint housing in finger widths: a finger's root turns inside the
#: palm (its rectangle is centred on the joint axis at the palm's surface), so the finger is
#: checked against the palm only outside a disk this many widths about its joint.  1.12 is
#: the disk through the corners of one finger width of root (hypot(1, 1/2)).
JOINT_HOUSING = float(np.hypot(1.0, 0.5))

#: Joint angles (rad) beyond a limit by less than this are inside: the CSV holds full
#: double precision (repr round trip), so only the planner's own rounding is forgiven.
LIMIT_TOL = 1e-9

#: Relative excess tolerated on a speed limit (finite differences and exported commands).
#: A finite difference of a path that respects the limit never exceeds it (mean value
#: theorem), so this only absorbs rounding of ``dt`` (decimal times) and of the angles.
SPEED_RTOL = 1e-6

#: Jump (rad or m) tolerated between two rows at the same time (a phase switch): rounding.
JUMP_TOL = 1e-9

def row_pose(cols, k) -> np.ndarray:
    """Workpiece ``(x, y, theta)`` of row ``k`` (m, m, rad), shape (3,)."""
    return np.array([cols["x_workpiece"][k], cols["y_workpiece"][k], cols["theta_workpiece"][k]], dtype=float)


def row_q(cols, k) -> np.ndarray:
    """Joint angles ``(left, right)`` of row ``k`` (rad), shape (2,)."""
    return np.array([cols["q_left"][k], cols["q_right"][k]], dtype=float)


def joint_housings(hand) -> dict:
    """``{"left", "right"}`` -> the disk (shapely) about each finger's joint inside which it may overlap the palm."""
    from shapely.geometry import Point

    housing = JOINT_HOUSING * hand.finger_width
    return {side: Point(p).buffer(housing, 64) for side, p in zip(("left", "right"), hand.pivots)}


def row_bodies(task, cols, k, roots=None) -> dict:
    """The bodies of row ``k`` as shapely geometry: ``{"polys": {name: Polygon}, "roots": {side: disk}}``.

    Built once per row and passed to :func:`overlap_checks` and :func:`contact_checks`;
    ``roots``: :func:`joint_housings` of the task's hand, when already built (they do not move).
    """
    from shapely.geometry import Polygon

    from qsplan.hands import hand_polygons

    polys = {name: Polygon(v) for name, v in hand_polygons(task.hand, row_pose(cols, k), row_q(cols, k)).items()}
    return {"polys": polys, "roots": joint_housings(task.hand) if roots is None else roots}


def _depth(inter) -> float:
    """Narrowest width (m) of a convex intersection: its penetration depth for a vertex or an edge pushed in."""
    if inter.is_empty or inter.area == 0.0:
        return 0.0
    hull = np.asarray(inter.convex_hull.exterior.coords)[:-1]
    edges = np.roll(hull, -1, axis=0) - hull
    lengths = np.hypot(edges[:, 0], edges[:, 1])
    normals = np.stack([-edges[:, 1], edges[:, 0]], axis=1)[lengths > 0] / lengths[lengths > 0, None]
    widths = hull @ normals.T
    return float((widths.max(axis=0) - widths.min(axis=0)).min())


_NAMES = {"left": "left finger", "right": "right finger", "palm": "palm", "workpiece": "workpiece"}
_PAIRS = (("left", "right"), ("left", "workpiece"), ("right", "workpiece"), ("workpiece", "palm"),
          ("left", "palm"), ("right", "palm"))  # fmt: skip


def overlap_checks(task, cols, k, bodies=None) -> list:
    """Check 1: no two of left finger, right finger, palm and workpiece overlap deeper than :data:`OVERLAP_DEPTH_TOL`.

    ``bodies``: :func:`row_bodies` of the row, when already built.
    """
    b = row_bodies(task, cols, k) if bodies is None else bodies
    polys, out = b["polys"], []
    for a, c in _PAIRS:
        A = polys[a].difference(b["roots"][a]) if c == "palm" and a in b["roots"] else polys[a]
        inter = A.intersection(polys[c])
        depth = _depth(inter)
        if depth > OVERLAP_DEPTH_TOL:
            out.append(("overlap", f"{_NAMES[a]} / {_NAMES[c]} overlap {inter.area * 1e6:.3g} mm^2, "
                                   f"{depth * 1e3:.3g} mm deep"))  # fmt: skip
    return out


def contact_checks(task, cols, k, bodies=None) -> list:
    """Check 3: every contact of the row's mode is present (palm:0, palm:1, left finger, right finger).

    ``bodies``: :func:`row_bodies` of the row, when already built.
    """
    from shapely.geometry import Point

    polys = (row_bodies(task, cols, k) if bodies is None else bodies)["polys"]
    mode = str(cols["mode"][k])
    if len(mode) != 4 or set(mode) - set("RSB"):
        return [("contact", f"mode {mode!r}: expected four letters of R, S, B (palm:0, palm:1, left, right)")]
    V = np.asarray(polys["workpiece"].exterior.coords)[:-1]
    gaps = [("palm:0 (workpiece's bottom-left vertex on the palm)", Point(V[0]).distance(polys["palm"])),
            ("palm:1 (workpiece's bottom-right vertex on the palm)", Point(V[1]).distance(polys["palm"])),
            ("left finger on the workpiece", polys["left"].distance(polys["workpiece"])),
            ("right finger on the workpiece", polys["right"].distance(polys["workpiece"]))]  # fmt: skip
    return [("contact", f"contact {name} of mode {mode} is missing: gap {gap * 1e3:.3g} mm")
            for name, gap in gaps if gap > CONTACT_GAP_TOL]  # fmt: skip


def limit_checks(task, cols, k) -> list:
    """Check 2 (one row): joint limits, exported joint-speed commands, the torque inside its band."""
    out = []
    q = row_q(cols, k)
    if not np.all(np.isfinite(q)) or not np.all(np.isfinite(row_pose(cols, k))):
        return [("input", "a joint angle or the workpiece pose is not a finite number")]
    for j, side in enumerate(("left", "right")):
        lo, hi = task.joint_limits[j]
        if q[j] < lo - LIMIT_TOL or q[j] > hi + LIMIT_TOL:
            out.append(("joint limit", f"{side} joint at {q[j]:.6g} rad, outside its limits [{lo:g}, {hi:g}] rad"))
        qd = cols[f"qd_{side}"][k]
        if np.isfinite(qd) and abs(qd) > task.joint_speed * (1 + SPEED_RTOL):
            out.append(("speed", f"{side} joint speed command {qd:.6g} rad/s beyond the limit {task.joint_speed:g} rad/s"))
    if cols["mode"][k] == "free":
        return out
    e = str(cols["effort_joint"][k])
    if e not in ("left", "right"):
        return out + [("input", f"effort_joint {e!r}: expected 'left' or 'right' on an in-contact row")]
    v = "right" if e == "left" else "left"
    tau, lo, hi = (float(cols[f"tau_{e}{s}"][k]) for s in ("", "_min", "_max"))
    if not np.isfinite(tau) or np.isnan(lo) or np.isnan(hi):
        out.append(("torque", f"{e} joint: no torque command or band (tau = {tau}, band [{lo}, {hi}])"))
    elif not lo <= tau <= hi:
        edge = lo if tau < lo else hi
        out.append(("torque", f"{e} joint torque {tau:.6g} N m outside its band [{lo:.6g}, {hi:.6g}] N m "
                              f"({abs(tau - edge):.3g} N m past the edge)"))  # fmt: skip
    if not np.isfinite(cols[f"qd_{v}"][k]):
        out.append(("input", f"{v} joint (velocity-controlled): no velocity command"))
    return out


def step_checks(task, cols, k) -> list:
    """Check 2 (rows ``k`` and ``k + 1``): time order, speed limits over the step, no jump at a switch."""
    t0, t1 = cols["t"][k], cols["t"][k + 1]
    dt = t1 - t0
    if not (np.isfinite(dt) and dt >= 0):
        return [("time", f"time goes from {t0:.6g} s to {t1:.6g} s at the next row")]
    dq = row_q(cols, k + 1) - row_q(cols, k)
    p0, p1 = row_pose(cols, k), row_pose(cols, k + 1)
    dx = float(np.hypot(*(p1[:2] - p0[:2])))
    dth = abs(p1[2] - p0[2])
    if dt == 0.0:
        jumps = [f"{s} joint {abs(d):.3g} rad" for s, d in zip(("left", "right"), dq) if abs(d) > JUMP_TOL]
        jumps += [f"workpiece {dx * 1e3:.3g} mm"] if dx > JUMP_TOL else []
        jumps += [f"workpiece {dth:.3g} rad"] if dth > JUMP_TOL else []
        return [("continuity", f"jump at t = {t0:.6g} s to the next row: " + ", ".join(jumps))] if jumps else []
    out = []
    for side, d in zip(("left", "right"), dq):
        if abs(d) > task.joint_speed * dt * (1 + SPEED_RTOL) + JUMP_TOL:
            out.append(("speed", f"{side} joint moves {abs(d):.4g} rad in {dt:.4g} s to the next row: "
                                 f"{abs(d) / dt:.4g} rad/s > limit {task.joint_speed:g} rad/s"))  # fmt: skip
    if dx > task.workpiece_speed * dt * (1 + SPEED_RTOL) + JUMP_TOL:
        out.append(("speed", f"workpiece moves {dx * 1e3:.4g} mm in {dt:.4g} s to the next row: "
                             f"{dx / dt:.4g} m/s > limit {task.workpiece_speed:g} m/s"))  # fmt: skip
    return out


def friction_points(task, n_random, rng) -> np.ndarray:
    """Friction vectors (4,) to test, shape (m, 4): every vertex of the friction set, then ``n_random`` seeded draws.

    Box (independent coefficients): the 16 corners of ``[lo, hi]^4``; shared: ``lo`` and ``hi``.
    """
    lo, hi = task.mu_range
    if task.shared_mu:
        vertices = np.array([[lo] * 4, [hi] * 4], dtype=float)
        draws = np.repeat(rng.uniform(lo, hi, (n_random, 1)), 4, axis=1)
    else:
        vertices = np.array(np.meshgrid(*[[lo, hi]] * 4, indexing="ij")).reshape(4, -1).T.astype(float)
        draws = rng.uniform(lo, hi, (n_random, 4))
    return np.unique(np.vstack([vertices, draws]), axis=0) if lo == hi else np.vstack([vertices, draws])
