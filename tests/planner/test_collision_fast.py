"""The fast collision test (numpy, batched) against the shapely reference, on thousands of seeded configurations.

Every state is judged three ways: :func:`find_collisions_batch` (numpy, shapely only for the
pairs it leaves undecided), :func:`find_collisions` (one state, the fast path clearing what it
can) and :func:`shapely_collisions` (the reference).  Each pair's fast decision must agree with
the reference wherever it decides, and both fast answers must equal the reference's everywhere.
"""

from dataclasses import replace

import numpy as np
import pytest
from scipy.optimize import brentq
from shapely.geometry import MultiPoint, Point, Polygon, box

from qsplan.hands.paper_hand.two_finger import default_hand, finger_angles, make_two_finger_hand
from qsplan.hands.paper_hand.scene import hand_polygons
from qsplan.mechanics.errors import QsplanError, SceneError
from qsplan.hands.geometry.collision import (CLEAR, COLLIDES, CONTACT_DEPTH_TOL, DECISION_BAND, HOUSING_QUAD_SEGS,
                                             JOINT_HOUSING, LINK_DEPTH_TOL, UNDECIDED, body_label,
                                             collision_decisions, collision_pairs, find_collisions,
                                             find_collisions_batch, overlap_depth, shapely_collisions)  # fmt: skip
from qsplan.hands.geometry.overlap import (convex_vertices, disk_pieces, intersection_width, make_polygons,
                                           separating_depth)  # fmt: skip
from qsplan.planner.task.task import load_task, task_paths

#: Workpieces of the planner's shape tests (tests/planner/test_plan_shapes.py) and finger lengths (m).
SHAPES = {
    "triangle": ([[0, 0], [0.08, 0], [0.04, 0.07]], 0.16),
    "pentagon": ([[0, 0], [0.07, 0], [0.08, 0.04], [0.035, 0.07], [-0.01, 0.04]], 0.11),
    "thin rectangle": ([[0, 0], [0.03, 0], [0.03, 0.10], [0, 0.10]], 0.16),
    "flat rectangle": ([[0, 0], [0.10, 0], [0.10, 0.025], [0, 0.025]], 0.16),
    "hexagon": ([[0.02, 0], [0.06, 0], [0.08, 0.035], [0.06, 0.07], [0.02, 0.07], [0, 0.035]], 0.11),
    "crossing pentagon": ([[0, 0], [0.07, 0], [0.07, 0.06], [0.035, 0.09], [0, 0.06]], 0.16),
}  # fmt: skip


def random_workpiece(rng):
    """A convex polygon (m) with a level bottom edge, 3 to 8 vertices."""
    width = rng.uniform(0.02, 0.10)
    pts = np.column_stack([rng.uniform(-0.01, width + 0.01, 6), rng.uniform(0.005, 0.11, 6)])
    hull = MultiPoint(np.vstack([[0.0, 0.0], [width, 0.0], pts[: rng.integers(1, 7)]])).convex_hull
    return np.asarray(hull.exterior.coords)[:-1]


def hands(rng, n_random):
    """The default hand, the demo and pentagon tasks' hands, the :data:`SHAPES` hands, ``n_random`` random hands."""
    out = [default_hand()] + [load_task(task_paths()[stem]).hand for stem in ("demo_task", "pentagon_task")]
    out += [make_two_finger_hand(w, finger_length=length) for w, length in SHAPES.values()]
    for _ in range(n_random):
        width = rng.uniform(0.004, 0.02)
        out.append(make_two_finger_hand(random_workpiece(rng), finger_base=rng.uniform(0.05, 0.12),
                                        finger_length=rng.uniform(0.06, 0.2), finger_width=width,
                                        palm_halfwidth=rng.uniform(0.1, 0.2),
                                        palm_thickness=rng.uniform(0.005, 0.03)))  # fmt: skip
    return out


def configurations(hand, rng, n):
    """``(poses (n, 3), qs (n, 2))``: grasps, grasps pushed or opened by 1e-9..0.1 rad, workpieces
    lifted, sunk or tilted, fingers anywhere, fingers near the palm's surface on either side."""
    poses, qs = [], []
    while len(poses) < n:
        kind = rng.integers(7)
        pose = np.array([rng.uniform(-0.06, 0.06), hand.rest_height, 0.0])
        if kind == 1:
            pose[1] += rng.choice([-1.0, 1.0]) * 10 ** rng.uniform(-8, -2.5)
        elif kind == 2:
            pose[2] += rng.normal() * 0.1
        try:
            q = finger_angles(hand, pose)[0]
        except QsplanError:
            q = rng.uniform(0.05, 3.09, 2)
        if kind == 3:
            q = q + rng.choice([-1.0, 1.0], 2) * 10 ** rng.uniform(-9, -1, 2)
        elif kind == 4:
            q = rng.uniform(-0.4, np.pi + 0.4, 2)
        elif kind in (5, 6):
            q = np.array([rng.uniform(-0.2, 0.6), np.pi - rng.uniform(-0.2, 0.6)])
            if kind == 6:
                pose[1] += 0.3  # the workpiece out of the way
        poses.append(pose)
        qs.append(q)
    return np.array(poses), np.array(qs)


def assert_agrees(hand, poses, qs, every=1):
    """Fast decisions never contradict the reference; the batched and single-state answers equal it."""
    decisions = collision_decisions(hand, poses, qs)
    batch = find_collisions_batch(hand, poses, qs)
    labels = [(body_label(a), body_label(b)) for a, b in collision_pairs(hand)]
    for i in range(0, len(poses), every):
        ref = shapely_collisions(hand, poses[i], qs[i])
        hit = {c.bodies for c in ref}
        for label, d in zip(labels, decisions[i]):
            assert label not in hit if d == CLEAR else label in hit if d == COLLIDES else True, (label, d, i)
        assert batch[i] == bool(ref), i
        assert find_collisions(hand, poses[i], qs[i]) == ref, i
        assert find_collisions(hand, poses[i], qs[i], first=True) == ref[:1], i
    return decisions


@pytest.mark.slow
def test_default_hand_and_bundled_tasks_agree_with_shapely():
    rng = np.random.default_rng(13)
    for hand in hands(rng, 0)[:3]:
        poses, qs = configurations(hand, rng, 1000)
        decisions = assert_agrees(hand, poses, qs)
        assert np.any(decisions == COLLIDES) and np.any(np.all(decisions == CLEAR, axis=1))


@pytest.mark.slow
def test_shapes_and_random_hands_agree_with_shapely():
    rng = np.random.default_rng(1995)
    for hand in hands(rng, 8)[3:]:
        poses, qs = configurations(hand, rng, 400)
        assert_agrees(hand, poses, qs)


def test_in_contact_sweeps_are_decided_without_shapely():
    """The planner's in-contact states (dense sweeps of the bundled tasks): the fast path decides every pair."""
    total = 0
    for path in task_paths().values():
        task = load_task(path)
        if not task.hand.accelerated:  # a described hand's states: tests/planner/test_chain_plan.py
            continue
        stops = [task.start_x, *task.waypoints]
        poses, qs = [], []
        for x in np.linspace(min(stops) - 0.01, max(stops) + 0.01, 1001):
            try:
                qs.append(finger_angles(task.hand.paper, task.pose(x))[0])
            except QsplanError:  # no grasp there: not a state of the planner
                continue
            poses.append(task.pose(x))
        poses, qs = np.array(poses).reshape(-1, 3), np.array(qs).reshape(-1, 2)
        total += len(poses)
        decisions = assert_agrees(task.hand, poses, qs, every=20)
        assert not np.any(decisions == UNDECIDED)
    assert total > 3000


def _pair_depth(hand, pose, q, pair):
    """The reference's depth of one pair (m), whatever the tolerance (shapely, independent of the module)."""
    polys = {k: Polygon(v) for k, v in hand_polygons(hand, pose, q).items()}
    region = polys[pair[0]].intersection(polys[pair[1]])
    if "palm" in pair and pair != ("palm", "workpiece"):
        axis = hand.pivots[0 if "left" in pair else 1]
        region = region.difference(Point(axis).buffer(JOINT_HOUSING * hand.finger_width, HOUSING_QUAD_SEGS))
    return overlap_depth(region)


CROSSING = make_two_finger_hand(SHAPES["crossing pentagon"][0], finger_length=0.16)
DEFAULT = default_hand()
ABOVE = (0.0, 0.5, 0.0)  # a workpiece pose out of the fingers' reach


def grasp(hand, x, sink=0.0, turn=(0.0, 0.0)):
    """``(pose, q)``: the workpiece at ``x`` (m) sunk ``sink`` (m) into the palm, the fingers at their grasp
    turned by ``turn`` (rad)."""
    pose = (x, hand.rest_height - sink, 0.0)
    return pose, finger_angles(hand, pose)[0] + turn


#: name: (hand, pair, state(s) -> (pose, q), bracket of s, tolerance).  One parameter moves one pair
#: through its tolerance: the workpiece sunk into the palm, a finger turned into the workpiece, the
#: crossing fingers of the pentagon grasp as the workpiece moves, a finger dipping into the palm just
#: outside its joint housing (its lower edge leaves the housing at atan(1/2)), on either side.  (Turning
#: about an axis on the palm's surface, a finger enters the palm at its housing first: nowhere else does
#: its depth pass through the tolerance.)
EDGES = {
    "workpiece into palm": (DEFAULT, ("palm", "workpiece"), lambda s: grasp(DEFAULT, 0.01, sink=s), (0.0, 1e-5),
                            CONTACT_DEPTH_TOL),
    "finger into workpiece": (DEFAULT, ("workpiece", "left"), lambda s: grasp(DEFAULT, -0.02, turn=(-s, 0.0)),
                              (0.0, 1e-3), CONTACT_DEPTH_TOL),
    "fingers graze": (CROSSING, ("left", "right"), lambda s: grasp(CROSSING, s), (0.0, 0.03), LINK_DEPTH_TOL),
    "left finger into palm at its housing": (DEFAULT, ("palm", "left"), lambda s: (ABOVE, (s, np.pi / 2)),
                                              (0.44, np.arctan(0.5)), LINK_DEPTH_TOL),
    "right finger into palm at its housing": (DEFAULT, ("palm", "right"), lambda s: (ABOVE, (np.pi / 2, np.pi - s)),
                                               (0.44, np.arctan(0.5)), LINK_DEPTH_TOL),
}  # fmt: skip


@pytest.mark.parametrize("offset", [-1e-7, -1e-8, -3e-9, -5e-10, 0.0, 5e-10, 3e-9, 1e-8, 1e-7])
@pytest.mark.parametrize("name", list(EDGES))
def test_depths_just_below_and_above_each_tolerance(name, offset):
    hand, pair, state, (lo, hi), tol = EDGES[name]
    s = brentq(lambda s: _pair_depth(hand, *state(s), pair) - (tol + offset), min(lo, hi), max(lo, hi),
               xtol=1e-16, rtol=1e-15)
    pose, q = (np.asarray(a, float) for a in state(s))
    depth = _pair_depth(hand, pose, q, pair)
    assert depth == pytest.approx(tol + offset, abs=2e-10)
    decisions = assert_agrees(hand, pose[None], q[None])
    column = collision_pairs(hand).index(pair)
    if abs(depth - tol) > 2 * DECISION_BAND and "housing" not in name:
        assert decisions[0, column] == (COLLIDES if depth > tol else CLEAR)
    assert find_collisions_batch(hand, pose[None], q[None])[0] == (depth > tol)


def test_fingers_deep_in_the_palm_away_from_the_housing():
    """Fingers turned below the palm's surface (tip inside the slab) and through it: collisions, decided fast."""
    hand = DEFAULT
    qs = np.array([[-0.03, np.pi / 2], [np.pi / 2, np.pi + 0.03], [-np.pi / 2, np.pi / 2], [0.3, np.pi + 0.3]])
    decisions = assert_agrees(hand, np.tile(ABOVE, (len(qs), 1)), qs)
    assert np.all(decisions[:, 1:3].max(axis=1) == COLLIDES)


def test_the_housing_band_is_narrow():
    """Where the fast path defers (a finger's edge leaving the palm just outside its housing), the band of joint
    angles is under 1e-4 rad wide, on each side, and the reference decides there."""
    phi = np.linspace(0.4634, 0.4638, 4001)
    for side, q in ((1, np.column_stack([phi, np.full_like(phi, np.pi / 2)])),
                    (2, np.column_stack([np.full_like(phi, np.pi / 2), np.pi - phi]))):  # fmt: skip
        decisions = collision_decisions(DEFAULT, np.tile(ABOVE, (len(phi), 1)), q)[:, side]
        undecided = phi[decisions == UNDECIDED]
        assert 0 < np.ptp(undecided) < 1e-4 and np.all(decisions[phi < undecided.min()] == COLLIDES)
        assert np.all(decisions[phi > undecided.max()] == CLEAR)
        assert_agrees(DEFAULT, np.tile(ABOVE, (len(phi), 1)), q, every=50)


def test_a_hand_that_is_not_convex_is_left_to_shapely():
    h = DEFAULT
    notch = np.array([[-0.04, -0.05], [0.04, -0.05], [0.04, 0.05], [0.0, 0.0], [-0.04, 0.05]])
    hand = replace(h, workpiece=notch)  # past make_two_finger_hand, which refuses it
    poses, qs = configurations(h, np.random.default_rng(3), 50)
    assert np.all(collision_decisions(hand, poses, qs) == UNDECIDED)
    assert_agrees(hand, poses, qs)


@pytest.mark.parametrize("single, args, match", [
    (False, ([0.0, 0.03], [[1.0, 2.0]]), r"poses: expected shape \(any, 3\); got \(2,\)"),
    (False, ([[0.0, 0.03, 0.0]], [[1.0, 2.0, 3.0]]), r"qs: expected shape \(1, 2\); got \(1, 3\)"),
    (False, ([[0.0, np.nan, 0.0]], [[1.0, 2.0]]), r"poses: expected finite numbers"),
    (True, ([0.0, 0.03], [1.0, 2.0]), r"pose: expected shape \(3\); got \(2,\)"),
    (True, ([0.0, 0.03, 0.0], [1.0, 2.0, 3.0]), r"q: expected shape \(2\); got \(3,\)"),
])  # fmt: skip
def test_validation_names_the_field(single, args, match):
    with pytest.raises(SceneError, match=match):
        (find_collisions if single else find_collisions_batch)(DEFAULT, *args)


def test_empty_batch():
    assert find_collisions_batch(DEFAULT, np.zeros((0, 3)), np.zeros((0, 2))).shape == (0,)


# --- overlap.py: the measures themselves --------------------------------------------------------------


def _stack(*polygons):
    return make_polygons([convex_vertices(p) for p in polygons], 8)


def test_intersection_width_is_the_reference_depth_on_random_convex_pairs():
    rng = np.random.default_rng(7)
    A, B, expected = [], [], []
    for _ in range(3000):
        a = np.asarray(MultiPoint(rng.normal(size=(rng.integers(3, 9), 2)) * 0.05).convex_hull.exterior.coords)[:-1]
        b = np.asarray(MultiPoint(rng.normal(size=(rng.integers(3, 9), 2)) * 0.05 + rng.normal(size=2) * 0.06)
                       .convex_hull.exterior.coords)[:-1]  # fmt: skip
        A.append(a), B.append(b), expected.append(overlap_depth(Polygon(a).intersection(Polygon(b))))
    PA, PB = _stack(*A), _stack(*B)
    width = intersection_width(PA, PB)
    assert np.max(np.abs(width - expected)) < 1e-13
    assert np.all(np.maximum(separating_depth(PA, PB), 0.0) >= width - 1e-13)  # the separating axis bounds it
    assert 500 < np.count_nonzero(width) < 2900


@pytest.mark.parametrize("a, b, expected", [
    (box(0, 0, 1, 1), box(1, 0, 2, 1), 0.0),  # edges touching
    (box(0, 0, 1, 1), box(1, 1, 2, 2), 0.0),  # corners touching
    (box(0, 0, 1, 1), box(2, 0, 3, 1), 0.0),  # apart
    (box(0, 0, 1, 1), box(0, 0, 1, 1), 1.0),  # the same
    (box(0, 0, 4, 4), box(1, 1, 2, 3), 1.0),  # nested
    (box(0, 0, 10, 1), box(0, 1 - 1e-7, 10, 2), 1e-7),  # flush edges, a sliver
    (Polygon([(0, 0), (4, 0), (0, 3)]), box(-1, -1, 5, 5), 12 / 5),  # a triangle inside: its least altitude
    (box(0, 0, 1, 1), Polygon([(0.5, 0.9), (1.5, 2), (-0.5, 2)]), 0.1),  # a corner pushed 0.1 through an edge
])  # fmt: skip
def test_degenerate_pairs(a, b, expected):
    A, B = (np.asarray(p.exterior.coords)[:-1] for p in (a, b))
    reference = overlap_depth(a.intersection(b))
    width = intersection_width(_stack(A), _stack(B))[0]
    assert width == pytest.approx(reference, abs=1e-15)
    if expected:
        assert width == pytest.approx(expected, rel=1e-9)


def test_disk_pieces_cover_and_fill_the_polygon_outside_the_disk():
    rng = np.random.default_rng(2)
    link = np.array([[0.0, -0.006], [0.16, -0.006], [0.16, 0.006], [0.0, 0.006]])
    r = JOINT_HOUSING * 0.012
    cover, inside = disk_pieces(link, 0.999 * r, 1.001 * r)
    assert len(cover) == 1 and len(inside) == 3
    pts = np.column_stack([rng.uniform(0, 0.16, 20000), rng.uniform(-0.006, 0.006, 20000)])
    outside = np.hypot(*pts.T) > 0.999 * r
    pieces = [Polygon(p).buffer(1e-12) for p in cover]
    assert all(any(p.contains(Point(x)) for p in pieces) for x in pts[outside][:2000])
    for piece in inside:
        assert np.all(np.hypot(*piece.T) >= 1.001 * r * (1 - 1e-12))
