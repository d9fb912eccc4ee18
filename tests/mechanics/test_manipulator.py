"""The planar joint tree: poses, Jacobians (eq. 5), gravity efforts (eq. 3), validation."""

import numpy as np
import pytest

from qsplan.mechanics import SceneError
from qsplan.mechanics.model.manipulator import (
    Joint,
    base_polygon,
    contact_jacobian,
    gravity_efforts,
    link_polygons,
    link_poses,
    make_joint,
    make_manipulator,
    point_jacobian,
)

STEP = 1e-6  # central-difference step (rad or m); truncation error ~ STEP^2, rounding ~ 1e-16 / STEP


def random_tree(rng, n, serial=False):
    """A random tree of ``n`` joints mixing revolute and prismatic joints, with masses and shapes."""
    joints = []
    for i in range(n):
        parent = i - 1 if serial else int(rng.integers(-1, i))
        joints.append(
            make_joint(
                f"j{i}",
                str(rng.choice(["revolute", "prismatic"])),
                parent,
                np.r_[rng.uniform(-1, 1, 2), rng.uniform(-np.pi, np.pi)],
                link_mass=float(rng.uniform(0, 2)),
                link_com=rng.uniform(-0.5, 0.5, 2),
                link_shape=[(0, -0.1), (0.5, -0.1), (0.5, 0.1), (0, 0.1)],
            )
        )
    return make_manipulator(joints, gravity=9.81)


def to_local(pose, p):
    c, s = np.cos(pose[2]), np.sin(pose[2])
    return np.array([[c, s], [-s, c]]) @ (np.asarray(p) - pose[:2])


def to_world(pose, local):
    c, s = np.cos(pose[2]), np.sin(pose[2])
    return pose[:2] + np.array([[c, -s], [s, c]]) @ local


def fd_point_jacobian(man, q, link, local):
    cols = []
    for i in range(len(q)):
        dq = np.zeros_like(q)
        dq[i] = STEP
        hi = to_world(link_poses(man, q + dq)[link], local)
        lo = to_world(link_poses(man, q - dq)[link], local)
        cols.append((hi - lo) / (2 * STEP))
    return np.column_stack(cols)


def ancestors(man, link):
    path = set()
    while link >= 0:
        path.add(link)
        link = man.joints[link].parent
    return path


def test_two_link_arm_poses_hand_computed():
    man = make_manipulator(
        [
            make_joint("shoulder", "revolute", -1, [0, 0, 0]),
            make_joint("elbow", "revolute", 0, [1.0, 0, 0]),
            make_joint("slide", "prismatic", 1, [0.5, 0, np.pi / 2]),
        ]
    )
    q1, q2, d = 0.3, -0.7, 0.2
    poses = link_poses(man, [q1, q2, d])
    elbow = np.array([np.cos(q1), np.sin(q1)])
    slide_origin = elbow + 0.5 * np.array([np.cos(q1 + q2), np.sin(q1 + q2)])
    a3 = q1 + q2 + np.pi / 2
    np.testing.assert_allclose(poses[0], [0, 0, q1], atol=1e-15)
    np.testing.assert_allclose(poses[1], [*elbow, q1 + q2], atol=1e-15)
    np.testing.assert_allclose(poses[2], [*(slide_origin + d * np.array([np.cos(a3), np.sin(a3)])), a3], atol=1e-15)
    # Jacobian of the shoulder link point at (1, 0) rotated: z x p; the other columns are zero.
    J = point_jacobian(man, [q1, q2, d], 0, elbow)
    np.testing.assert_allclose(J, [[-elbow[1], 0, 0], [elbow[0], 0, 0]], atol=1e-15)


@pytest.mark.parametrize("serial", [True, False], ids=["serial", "branching"])
def test_point_jacobian_matches_finite_differences(serial):
    rng = np.random.default_rng(10 + serial)
    for _ in range(40):
        man = random_tree(rng, int(rng.integers(1, 9)), serial=serial)
        q = rng.uniform(-1.5, 1.5, man.n_joints)
        link = int(rng.integers(man.n_joints))
        local = rng.uniform(-1, 1, 2)
        point = to_world(link_poses(man, q)[link], local)
        J = point_jacobian(man, q, link, point)
        assert J.shape == (2, man.n_joints)
        np.testing.assert_allclose(J, fd_point_jacobian(man, q, link, local), atol=1e-7)
        off_path = [i for i in range(man.n_joints) if i not in ancestors(man, link)]
        assert np.all(J[:, off_path] == 0.0)


def test_branching_trees_are_generated():
    rng = np.random.default_rng(12)
    man = random_tree(rng, 8)
    parents = [j.parent for j in man.joints]
    assert len(set(parents)) < len(parents)  # some link carries two children: a branch


def test_contact_jacobian_rows_are_normal_and_tangent_projections():
    rng = np.random.default_rng(13)
    for _ in range(20):
        man = random_tree(rng, 5)
        q = rng.normal(size=5)
        point, normal = rng.normal(size=2), rng.normal(size=2)
        Jp = point_jacobian(man, q, 4, point)
        n = normal / np.linalg.norm(normal)
        t = np.array([-n[1], n[0]])
        np.testing.assert_allclose(contact_jacobian(man, q, 4, point, normal), [n @ Jp, t @ Jp], atol=1e-14)


def potential_energy(man, q):
    poses = link_poses(man, q)
    return sum(man.gravity * j.link_mass * to_world(p, j.link_com)[1] for j, p in zip(man.joints, poses))


@pytest.mark.parametrize("serial", [True, False], ids=["serial", "branching"])
def test_gravity_efforts_are_gradient_of_potential_energy(serial):
    # g_man = -sum_k Jp(com_k)^T (0, -m_k g) = dV/dq with V = sum_k m_k g y_com,k.
    rng = np.random.default_rng(20 + serial)
    for _ in range(30):
        man = random_tree(rng, int(rng.integers(1, 9)), serial=serial)
        q = rng.uniform(-1.5, 1.5, man.n_joints)
        grad = np.array(
            [
                (potential_energy(man, q + STEP * e) - potential_energy(man, q - STEP * e)) / (2 * STEP)
                for e in np.eye(man.n_joints)
            ]
        )
        np.testing.assert_allclose(gravity_efforts(man, q), grad, atol=1e-6)


def test_gravity_efforts_sign_holds_a_horizontal_arm():
    # A horizontal link of mass m with its com at distance L: gravity pulls it clockwise
    # (moment -m g L about the joint); with no contact force eq. 3 gives tau = g_man, so the
    # motor must push counterclockwise with +m g L.
    man = make_manipulator([make_joint("arm", "revolute", -1, [0, 0, 0], link_mass=2.0, link_com=[0.5, 0])])
    np.testing.assert_allclose(gravity_efforts(man, [0.0]), [2.0 * 9.81 * 0.5])
    # A vertical prismatic lift carrying mass m needs +m g along its axis (up).
    lift = make_manipulator([make_joint("lift", "prismatic", -1, [0, 0, np.pi / 2], link_mass=3.0)], gravity=10.0)
    np.testing.assert_allclose(gravity_efforts(lift, [0.4]), [30.0], atol=1e-12)


def test_gravity_efforts_equal_virtual_work_of_link_weights():
    rng = np.random.default_rng(22)
    man = random_tree(rng, 6)
    q = rng.normal(size=6)
    poses = link_poses(man, q)
    expected = np.zeros(6)
    for k, j in enumerate(man.joints):
        com = to_world(poses[k], j.link_com)
        expected -= point_jacobian(man, q, k, com).T @ np.array([0.0, -j.link_mass * man.gravity])
    np.testing.assert_allclose(gravity_efforts(man, q), expected, atol=1e-12)


def test_link_polygons_follow_the_link_frames():
    rng = np.random.default_rng(30)
    man = random_tree(rng, 4)
    man = make_manipulator(
        [*man.joints[:3], make_joint("bare", "revolute", 2, [0.1, 0, 0])],
        base_shape=[(-1, -1), (1, -1), (1, 0), (-1, 0)],
    )
    q = rng.normal(size=4)
    polys = link_polygons(man, q)
    assert polys[3] is None
    poses = link_poses(man, q)
    for k in range(3):
        expected = [to_world(poses[k], v) for v in man.joints[k].link_shape]
        np.testing.assert_allclose(np.asarray(polys[k].exterior.coords)[:-1], expected, atol=1e-12)
    assert base_polygon(man).area == pytest.approx(2.0)


def test_values_are_frozen():
    man = random_tree(np.random.default_rng(31), 2)
    with pytest.raises(ValueError):
        man.joints[0].origin[0] = 1.0
    with pytest.raises(AttributeError):
        man.gravity = 1.0


J0 = dict(name="a", kind="revolute", parent=-1, origin=[0, 0, 0])


@pytest.mark.parametrize(
    "joints, kwargs, match",
    [
        ([J0, {**J0, "name": "b", "parent": 5}], {}, r"joints\[1\]\.parent: expected -1 or an index below 1; got 5"),
        ([J0, {**J0, "name": "b", "parent": 1}], {}, r"joints\[1\]\.parent: expected -1 or an index below 1; got 1"),
        ([J0, {**J0, "name": "b", "parent": -2}], {}, r"joints\[1\]\.parent"),
        ([J0, {**J0, "name": "b", "parent": 0.5}], {}, r"joints\[1\]\.parent: expected an integer"),
        ([{**J0, "kind": "ball"}], {}, r"joints\[0\]\.kind: expected 'revolute' or 'prismatic'; got 'ball'"),
        ([J0, J0], {}, r"joints\[1\]\.name: expected a unique name; 'a' is also joints\[0\]\.name"),
        ([{**J0, "name": ""}], {}, r"joints\[0\]\.name"),
        ([{**J0, "origin": [0, np.nan, 0]}], {}, r"joints\[0\]\.origin: expected finite"),
        ([{**J0, "origin": [0, 0]}], {}, r"joints\[0\]\.origin: expected shape \(3\)"),
        ([{**J0, "link_mass": -1.0}], {}, r"joints\[0\]\.link_mass: expected a nonnegative mass"),
        ([{**J0, "link_mass": np.inf}], {}, r"joints\[0\]\.link_mass: expected a finite"),
        ([{**J0, "link_com": [0, 0, 0]}], {}, r"joints\[0\]\.link_com"),
        ([{**J0, "link_shape": [(0, 0), (1, 0)]}], {}, r"joints\[0\]\.link_shape: expected at least 3"),
        ([{**J0, "link_shape": [(0, 0), (1, 1), (1, 0), (0, 1)]}], {}, r"joints\[0\]\.link_shape: expected a simple"),
        ([J0], {"gravity": -9.81}, r"gravity: expected a nonnegative"),
        ([J0], {"gravity": np.nan}, r"gravity: expected a finite"),
        ([J0], {"base_shape": [(0, 0), (1, 0), (2, 0)]}, r"base_shape: expected a polygon with positive area"),
    ],
)
def test_make_manipulator_validation(joints, kwargs, match):
    with pytest.raises(SceneError, match=match):
        make_manipulator([Joint(**j) for j in joints], **kwargs)


def test_make_manipulator_rejects_non_joints():
    with pytest.raises(SceneError, match=r"joints\[0\]: expected a Joint"):
        make_manipulator([{"name": "a"}])


def test_public_functions_validate_arguments():
    man = make_manipulator([Joint(**J0)])
    with pytest.raises(SceneError, match=r"q: expected shape \(1\)"):
        link_poses(man, [0.0, 1.0])
    with pytest.raises(SceneError, match=r"q: expected finite"):
        gravity_efforts(man, [np.nan])
    with pytest.raises(SceneError, match=r"link: expected a link index in \[0, 1\); got 1"):
        point_jacobian(man, [0.0], 1, [0, 0])
    with pytest.raises(SceneError, match=r"point: expected shape"):
        point_jacobian(man, [0.0], 0, [0, 0, 0])
    with pytest.raises(SceneError, match=r"normal: expected a nonzero direction"):
        contact_jacobian(man, [0.0], 0, [1, 0], [0, 0])
