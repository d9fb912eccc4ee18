"""An independent overlap check of exported plan rows (test helper, not the planner's own check).

Rebuilds every body of a row of ``plan.csv`` from the hand's dimensions alone (finger
rectangles from the joint axes, lengths and widths; the palm slab; the workpiece from
:func:`qsplan.hands.paper_hand.two_finger.workpiece_world` at the row's pose) and measures each
pair's overlap with shapely, so that a bug in
:mod:`qsplan.hands.geometry.collision` cannot hide itself.  A described hand's bodies
(:class:`qsplan.hands.chains.hand.ChainHand`) come from its description: the palm polygon and
each link's polygon placed by :func:`qsplan.mechanics.model.manipulator.link_polygons`.
"""

from __future__ import annotations

import json
from itertools import combinations

import numpy as np
from shapely.geometry import Point, Polygon, box

from qsplan.hands.paper_hand.two_finger import workpiece_world

#: Depth (m) of overlap accepted: a micron (touching bodies compute as overlapping by ~1e-15 m).
DEPTH = 1e-6


def _finger(hand, k, q):
    w = 0.5 * hand.finger_width
    u = np.array([np.cos(q), np.sin(q)])
    n = np.array([-u[1], u[0]])
    p = hand.pivots[k]
    return Polygon([p - w * n, p + hand.finger_length * u - w * n, p + hand.finger_length * u + w * n, p + w * n])


def _depth(region) -> float:
    """Largest over parts of the narrowest width of each part's convex hull."""
    best = 0.0
    for part in getattr(region, "geoms", (region,)):
        if part.area <= 0:
            continue
        hull = np.asarray(part.convex_hull.exterior.coords)[:-1]
        # brute force over directions every 0.25 degree (independent of the planner's rotating calipers), and across
        # each hull edge: a sliver along a flush contact (a finger edge on a workpiece edge) is ~1e-17 m thin across
        # its own edge but reads 0.1 m x sin(0.125 deg) = 2e-4 m across the nearest sampled direction
        edges = np.roll(hull, -1, axis=0) - hull
        angles = np.concatenate([np.radians(np.arange(0.0, 180.0, 0.25)), np.arctan2(edges[:, 0], -edges[:, 1])])
        proj = hull @ np.stack([np.cos(angles), np.sin(angles)])
        best = max(best, float((proj.max(axis=0) - proj.min(axis=0)).min()))
    return best


def row_bodies(hand, pose, q) -> dict:
    """``{name: shapely Polygon}`` of the palm, both fingers and the workpiece."""
    return {"palm": box(-hand.palm_halfwidth, -hand.palm_thickness, hand.palm_halfwidth, 0.0),
            "left finger": _finger(hand, 0, q[0]), "right finger": _finger(hand, 1, q[1]),
            "workpiece": Polygon(workpiece_world(hand, pose))}  # fmt: skip


def _chain_overlaps(hand, pose, q) -> list:
    """:func:`row_overlaps` of a described hand: every pair of palm, links and workpiece; a revolute joint's link and
    its carrier (the palm or the parent link) outside a disk of 1.2 link widths about the joint's axis."""
    from qsplan.mechanics.model.manipulator import link_polygons, link_poses

    man = hand.manipulator
    links = link_polygons(man, q)
    bodies = {"palm": Polygon(man.base_shape), "workpiece": Polygon(workpiece_world(hand, pose))}
    bodies.update((j.name, p) for j, p in zip(man.joints, links))
    axes = link_poses(man, q)[:, :2]
    carrier = {j.name: ("palm" if j.parent < 0 else man.joints[j.parent].name, i) for i, j in enumerate(man.joints)
               if j.kind == "revolute"}  # fmt: skip
    out = []
    for a, b in combinations(bodies, 2):
        region = bodies[a].intersection(bodies[b])
        for link, other in ((a, b), (b, a)):
            if link in carrier and carrier[link][0] == other:
                i = carrier[link][1]
                y = np.asarray(man.joints[i].link_shape)[:, 1]
                region = region.difference(Point(axes[i]).buffer(1.2 * float(y.max() - y.min())))
        if region.is_empty or region.area <= 0:
            continue
        d = _depth(region)
        if d > DEPTH:
            out.append((a, b, region.area, d))
    return out


def row_overlaps(hand, pose, q) -> list:
    """``[(body, body, area m^2, depth m)]`` of every pair overlapping deeper than :data:`DEPTH`; a finger
    and the palm are compared outside a disk of 1.2 finger widths about the joint (the joint housing)."""
    if hasattr(hand, "description") and getattr(hand, "paper", None) is None:  # a described hand not of the paper's form
        return _chain_overlaps(hand, pose, q)
    bodies = row_bodies(hand, pose, q)
    out = []
    for a, b in combinations(bodies, 2):
        region = bodies[a].intersection(bodies[b])
        if "palm" in (a, b) and "finger" in a + b:
            k = 0 if "left" in a + b else 1
            region = region.difference(Point(hand.pivots[k]).buffer(1.2 * hand.finger_width))
        if region.is_empty or region.area <= 0:
            continue
        d = _depth(region)
        if d > DEPTH:
            out.append((a, b, region.area, d))
    return out


def plan_overlaps(hand, cols) -> list:
    """``[(row, body, body, area, depth)]`` over every row of a plan read by ``read_plan_csv``."""
    out = []
    for k in range(len(cols["t"])):
        pose = np.array([cols["x_workpiece"][k], cols["y_workpiece"][k], cols["theta_workpiece"][k]])
        names = hand.joint_names if hasattr(hand, "description") else ("left", "right")
        q = np.array([cols[f"q_{n}"][k] for n in names])
        out += [(k, *o) for o in row_overlaps(hand, pose, q)]
    return out


def plan_or_refuse(task, out, **kw):
    """Run the pipeline: ``("plan", plan.csv columns)`` or ``("refused", failure.json)``."""
    from qsplan.planner.export.plan_files import read_plan_csv
    from qsplan.planner.pipeline.run import run_plan
    from qsplan.planner.plan.scripted import PlanFailure

    try:
        run_plan(task, out, verify=0, plots=False, time_limit=10.0, **kw)
    except PlanFailure as exc:
        assert exc.report_path == out / "failure.json" and not (out / "plan.csv").exists()
        report = json.loads((out / "failure.json").read_text())
        assert report["message"] == str(exc) and report["message"].startswith("no plan: ")
        return "refused", report
    return "plan", read_plan_csv(out / "plan.csv")
