"""Contacts from polygons: points and inward normals (eq. 1), degenerate touches, tolerance."""

import numpy as np
import pytest
from shapely.geometry import Polygon, box

from qsplan.mechanics import SceneError
from qsplan.mechanics.model.geometry import CONTACT_TOL, check_polygon, find_contacts

UNIT = Polygon([(0, 0), (1, 0), (1, 1), (0, 1)])  # ordering starts at (0, 0); shapely.box starts at (1, 0)
PALM = box(-2, -1, 3, 0)


def summary(contacts):
    return [(c.body, tuple(np.round(c.point, 9)), tuple(np.round(c.normal, 9)), c.kind) for c in contacts]


def test_square_on_palm_gives_two_edge_edge_contacts_with_normals_up():
    contacts = find_contacts(UNIT, [(-1, PALM)])
    assert summary(contacts) == [
        (-1, (0.0, 0.0), (0.0, 1.0), "edge-edge"),
        (-1, (1.0, 0.0), (0.0, 1.0), "edge-edge"),
    ]


@pytest.mark.parametrize(
    "palm, points",
    [
        (box(0, -1, 1, 0), [(0.0, 0.0), (1.0, 0.0)]),  # same width: corners meet corners, but the edges face
        (box(0.2, -1, 0.7, 0), [(0.2, 0.0), (0.7, 0.0)]),  # narrower palm: the palm's corners
        (box(0.5, -1, 3, 0), [(0.5, 0.0), (1.0, 0.0)]),  # partial overlap: one corner of each
    ],
    ids=["same-width", "narrower", "partial"],
)
def test_edge_edge_contacts_sit_at_the_ends_of_the_overlap(palm, points):
    contacts = find_contacts(UNIT, [(-1, palm)])
    assert [tuple(np.round(c.point, 12)) for c in contacts] == points
    assert all(c.kind == "edge-edge" for c in contacts)
    np.testing.assert_allclose([c.normal for c in contacts], [[0, 1], [0, 1]], atol=1e-15)


def test_finger_tip_on_workpiece_edge():
    # A pointed finger (link 1) touches the square's left face at (0, 0.5): edge-vertex,
    # normal = the face's inward normal (+x), the point = the finger's vertex.
    finger = Polygon([(-1, 0.45), (-0.1, 0.45), (0, 0.5), (-0.1, 0.55), (-1, 0.55)])
    (c,) = find_contacts(UNIT, [(1, finger)])
    assert c.body == 1 and c.kind == "edge-vertex"
    np.testing.assert_allclose(c.point, [0, 0.5])
    np.testing.assert_allclose(c.normal, [1, 0])


def test_workpiece_vertex_on_body_edge():
    # A diamond standing on its corner: vertex-edge, normal = the palm's outward normal (+y).
    diamond = Polygon([(0, 0), (1, 1), (0, 2), (-1, 1)])
    (c,) = find_contacts(diamond, [(-1, PALM)])
    assert c.kind == "vertex-edge"
    np.testing.assert_allclose(c.point, [0, 0])
    np.testing.assert_allclose(c.normal, [0, 1])


def test_tilted_edge_gives_outward_normal_of_body_edge():
    # A square on a 30-degree ramp (palm), resting on its corner at the ramp.
    a = np.deg2rad(30)
    ramp = Polygon([(0, 0), (4 * np.cos(a), 4 * np.sin(a)), (4 * np.cos(a), -1), (0, -1)])
    p = 2 * np.array([np.cos(a), np.sin(a)])
    b = a + np.deg2rad(20)  # the square is tilted 20 degrees off the ramp
    R = np.array([[np.cos(b), -np.sin(b)], [np.sin(b), np.cos(b)]])
    diamond = Polygon([p + R @ v for v in [(0, 0), (1, 0), (1, 1), (0, 1)]])
    (c,) = find_contacts(diamond, [(-1, ramp)])
    np.testing.assert_allclose(c.normal, [-np.sin(a), np.cos(a)], atol=1e-12)
    np.testing.assert_allclose(c.point, p)


def test_corner_in_body_notch_gives_one_contact_per_notch_edge():
    # The unit square in an L-shaped corner: the floor and the wall each give an edge-edge pair;
    # (0, 0) carries two contacts with different normals (not duplicates).
    corner = Polygon([(-1, -1), (2, -1), (2, 0), (0, 0), (0, 2), (-1, 2)])
    assert summary(find_contacts(UNIT, [(-1, corner)])) == [
        (-1, (0.0, 0.0), (1.0, 0.0), "edge-edge"),
        (-1, (0.0, 0.0), (0.0, 1.0), "edge-edge"),
        (-1, (1.0, 0.0), (0.0, 1.0), "edge-edge"),
        (-1, (0.0, 1.0), (1.0, 0.0), "edge-edge"),
    ]


def test_corner_in_tilted_notch_gives_vertex_edge_pair():
    # A square's corner pushed into a V notch wider than 90 degrees: two vertex-edge contacts.
    notch = Polygon([(-2, 1), (0, 0), (2, 1), (2, -1), (-2, -1)])
    diamond = Polygon([(0, 0), (0.5, 0.5), (0, 1), (-0.5, 0.5)])
    contacts = find_contacts(diamond, [(-1, notch)])
    assert [c.kind for c in contacts] == ["vertex-edge", "vertex-edge"]
    normals = sorted(tuple(np.round(c.normal * np.sqrt(5), 9)) for c in contacts)
    assert normals == [(-1.0, 2.0), (1.0, 2.0)]


def test_body_corner_in_workpiece_notch_gives_edge_vertex_pair():
    wp = Polygon([(-1, 0), (0, 0.5), (1, 0), (1, 1), (-1, 1)])
    spike = Polygon([(-0.5, -1), (0.5, -1), (0, 0.5)])
    contacts = find_contacts(wp, [(2, spike)])
    assert [c.kind for c in contacts] == ["edge-vertex", "edge-vertex"]
    for c in contacts:
        np.testing.assert_allclose(c.point, [0, 0.5])
    np.testing.assert_allclose([c.normal for c in contacts], np.array([[0.5, 1], [-0.5, 1]]) / np.hypot(0.5, 1))  # by normal angle


@pytest.mark.parametrize(
    "body",
    [
        box(1, -1, 2, 0),  # squares corner to corner, no overlap of the facing edges
        Polygon([(1, 0), (1.5, -0.5), (2, -0.2)]),  # a triangle's corner on the square's corner
    ],
    ids=["diagonal-squares", "triangle"],
)
def test_vertex_on_vertex_raises(body):
    with pytest.raises(SceneError, match=r"contact normal undefined: vertex of link 1 .* touches workpiece vertex at \(1, 0\)"):
        find_contacts(UNIT, [(1, body)])


def test_vertex_on_vertex_message_uses_body_names():
    with pytest.raises(SceneError, match=r"vertex of link 3 \('thumb'\)"):
        find_contacts(UNIT, [(3, box(1, -1, 2, 0))], body_names={3: "thumb"})


def test_penetration_raises_naming_body_and_depth():
    with pytest.raises(SceneError, match=r"palm: penetrates the workpiece by 0\.01 m"):
        find_contacts(box(0, -0.01, 1, 1), [(-1, PALM)])


def test_crossing_without_vertices_inside_is_penetration():
    # A plus sign: neither polygon has a vertex inside the other.
    with pytest.raises(SceneError, match=r"link 0: penetrates the workpiece by 0\.1"):
        find_contacts(box(-1, -0.1, 1, 0.1), [(0, box(-0.1, -1, 0.1, 1))])


@pytest.mark.parametrize("gap, found", [(0.5 * CONTACT_TOL, 2), (2 * CONTACT_TOL, 0), (-0.5 * CONTACT_TOL, 2)])
def test_default_tolerance(gap, found):
    assert len(find_contacts(box(0, gap, 1, 1 + gap), [(-1, PALM)])) == found


def test_explicit_tolerance():
    lifted = box(0, 1e-4, 1, 1)
    assert find_contacts(lifted, [(-1, PALM)]) == []
    assert len(find_contacts(lifted, [(-1, PALM)], tol=1e-3)) == 2
    with pytest.raises(SceneError, match="penetrates the workpiece by 2e-06 m"):
        find_contacts(box(0, -2e-6, 1, 1), [(-1, PALM)])


def test_ordering_by_body_then_along_workpiece_boundary():
    left = Polygon([(-1, 0.2), (0, 0.3), (-1, 0.4)])
    right = Polygon([(2, 0.6), (1, 0.5), (2, 0.4)])
    top = Polygon([(0.4, 2), (0.5, 1), (0.6, 2)])
    contacts = find_contacts(UNIT, [(2, top), (0, right), (1, left), (-1, PALM), (0, left)])
    assert [(c.body, tuple(np.round(c.point, 9))) for c in contacts] == [
        (-1, (0.0, 0.0)),
        (-1, (1.0, 0.0)),
        (0, (1.0, 0.5)),
        (0, (0.0, 0.3)),
        (1, (0.0, 0.3)),
        (2, (0.5, 1.0)),
    ]


def test_orientation_of_input_polygons_does_not_matter():
    cw = Polygon([(0, 0), (0, 1), (1, 1), (1, 0)])
    palm_cw = Polygon(list(PALM.exterior.coords)[::-1])
    assert summary(find_contacts(cw, [(-1, palm_cw)])) == summary(find_contacts(UNIT, [(-1, PALM)]))


def test_contacts_move_with_a_rigid_motion():
    rng = np.random.default_rng(40)
    finger = Polygon([(-1, 0.45), (-0.1, 0.45), (0, 0.5), (-0.1, 0.55), (-1, 0.55)])
    base = find_contacts(UNIT, [(-1, PALM), (0, finger)])
    for _ in range(20):
        a, d = rng.uniform(-np.pi, np.pi), rng.uniform(-5, 5, 2)
        R = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])

        def move(p):
            return Polygon(np.asarray(p.exterior.coords) @ R.T + d)

        moved = find_contacts(move(UNIT), [(-1, move(PALM)), (0, move(finger))])
        assert [(c.body, c.kind) for c in moved] == [(c.body, c.kind) for c in base]
        np.testing.assert_allclose([c.point for c in moved], [c.point @ R.T + d for c in base], atol=1e-9)
        np.testing.assert_allclose([c.normal for c in moved], [c.normal @ R.T for c in base], atol=1e-9)


def test_collinear_vertices_are_not_corners():
    # A vertex in the middle of the square's bottom edge lying on the palm corner is no vertex-vertex touch.
    wp = Polygon([(0, 0), (0.5, 0), (1, 0), (1, 1), (0, 1)])
    palm = box(0.5, -1, 3, 0)
    assert [tuple(np.round(c.point, 12)) for c in find_contacts(wp, [(-1, palm)])] == [(0.5, 0.0), (1.0, 0.0)]


@pytest.mark.parametrize(
    "args, kwargs, match",
    [
        ((UNIT, [(-1, PALM)]), {"tol": 0.0}, r"tol: expected a positive"),
        ((UNIT, [(-1, PALM)]), {"tol": np.nan}, r"tol: expected a positive"),
        ((UNIT.exterior, [(-1, PALM)]), {}, r"workpiece: expected a non-empty shapely Polygon"),
        ((box(0, 0, 3, 3).difference(box(1, 1, 2, 2)), [(-1, PALM)]), {}, r"workpiece: polygons with holes"),
        ((UNIT, [PALM]), {}, r"bodies\[0\]: expected a \(body_index, Polygon\) pair"),
        ((UNIT, [(-2, PALM)]), {}, r"bodies\[0\]: expected a body index >= -1"),
        ((UNIT, [(0, Polygon([(0, 0), (1, 1), (1, 0), (0, 1)]))]), {}, r"bodies\[0\] \(link 0\): expected a valid"),
    ],
)
def test_find_contacts_validation(args, kwargs, match):
    with pytest.raises(SceneError, match=match):
        find_contacts(*args, **kwargs)


@pytest.mark.parametrize(
    "value, match",
    [
        ([[0, 0], [1, 0]], r"expected at least 3 vertices"),
        ([[0, 0], [1, 0], [2, 0]], r"positive area"),
        ([[0, 0], [1, 1], [1, 0], [0, 1]], r"simple polygon"),
        ([[0, 0], [1, 0], [np.inf, 1]], r"finite"),
        ([0, 1, 2], r"shape"),
    ],
)
def test_check_polygon(value, match):
    with pytest.raises(SceneError, match="shape: .*" + match):
        check_polygon(value, "shape")


def test_check_polygon_drops_closing_vertex():
    assert check_polygon([[0, 0], [1, 0], [0, 1], [0, 0]], "p").shape == (3, 2)
