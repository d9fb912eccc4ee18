"""Every contact the polygons show, in the canonical order (issue 23: the certifier's and the replay's view of a row in
any formation): the order against the paper hand's flush instant and pivot in closed form (tests/reference), the
names, the contact a motion makes, the scene against the named contact sets, and the errors."""

from __future__ import annotations

import numpy as np
import pytest

from qsplan.hands.contacts.found import (contact_names, drawable_contacts, made_contacts, ordered_contacts,
                                         row_contact_scene)  # fmt: skip
from qsplan.mechanics.errors import QsplanError
from qsplan.planner.task.task import load_task, task_paths

from tests.reference.paper_pivot import (PIVOT, TRANSITION, flush_instant, pivot_configurations, pivot_scene,
                                         transition_scene)  # fmt: skip


@pytest.fixture(scope="module")
def hand():
    return load_task(task_paths()["demo_task"]).hand


def test_the_canonical_order_is_the_closed_form_formations(hand):
    fi = flush_instant(hand)
    at_flush = ordered_contacts(hand, fi.pose, fi.q)
    assert contact_names(hand, fi.pose, at_flush) == TRANSITION.contact_names
    c = pivot_configurations(hand, [-0.3])
    assert contact_names(hand, c.pose[0], ordered_contacts(hand, c.pose[0], c.q[0])) == \
        PIVOT.contact_names  # fmt: skip
    # palm-edge: the order of every earlier plan (palm:0, palm:1, left, right), the palm's left to right
    before = (fi.pose + [0.005, 0.0, 0.0], None)
    from qsplan.hands.paper_hand.two_finger import finger_angles

    q = finger_angles(hand.paper, before[0])[0]
    found = ordered_contacts(hand, before[0], q)
    assert contact_names(hand, before[0], found) == ("palm:0", "palm:1", "left", "right")
    assert found[0].point[0] < found[1].point[0]


def test_scenes_equal_the_named_contact_sets(hand):
    fi = flush_instant(hand)
    named = transition_scene(hand, fi)
    found = row_contact_scene(hand, fi.pose, fi.q, [False, True], named.joint_velocity)
    assert found.contact_names == named.contact_names
    for a in ("Wn", "Wt", "Jn", "Jt", "g_obj"):
        np.testing.assert_allclose(getattr(found, a), getattr(named, a), atol=1e-14)
    c = pivot_configurations(hand, np.linspace(-0.05, -0.6, 4))
    for i in range(4):
        named = pivot_scene(hand, c, i)
        found = row_contact_scene(hand, c.pose[i], c.q[i], [False, True], named.joint_velocity)
        np.testing.assert_allclose(found.Wn, named.Wn, atol=1e-14)
        np.testing.assert_allclose(found.Jt, named.Jt, atol=1e-14)


def test_the_contact_a_motion_makes_at_its_end(hand):
    from qsplan.hands.paper_hand.two_finger import finger_angles

    fi = flush_instant(hand)
    near = fi.pose + [0.0005, 0.0, 0.0]
    q_near = finger_angles(hand.paper, near)[0]
    found = ordered_contacts(hand, fi.pose, fi.q)
    made = made_contacts(hand, (near, q_near), (fi.pose, fi.q), found)
    assert contact_names(hand, fi.pose, found)[int(np.flatnonzero(made)[0])] == "left:base" and made.sum() == 1
    scene = row_contact_scene(hand, fi.pose, fi.q, [False, True], [0.1, np.nan], drop=made)
    assert scene.contact_names == ("palm:0", "palm:1", "left:tip", "right")
    with pytest.raises(QsplanError, match="touches nothing"):
        row_contact_scene(hand, fi.pose, fi.q, [False, True], [0.1, np.nan], drop=np.ones(5, bool))


def test_a_chain_hand_draws_its_grasp_contacts():
    from qsplan.hands.described.records import contacts_at
    from tests.planner.bundled import bundled_task, planned

    task = bundled_task("two_link_task")
    first = planned("two_link_task").phases[0]  # a grasp the chain hand closes (its first row)
    pose, q = first.poses(task.hand.rest_height)[0], first.q[0]
    assert [c.body for c in drawable_contacts(task.hand, pose, q)] == [c.body for c in contacts_at(task.hand, pose, q)]
