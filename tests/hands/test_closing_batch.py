"""The batched closing (qsplan.hands.chains.closing_batch) against the per-state reference
(qsplan.hands.chains.closing.close_finger).

Seeded random states of every bundled hand and of a hand mixing a two-link finger and a leaning jaw: the same
contact or none, the same contact key and link feature, the same flush verdict, the closing value, point and
normal to 1e-12; the batched link poses against ``link_poses``."""

import numpy as np
import pytest

from qsplan.hands.chains.hand import make_chain_hand
from qsplan.hands.chains.closing import close_finger
from qsplan.hands.chains.closing_batch import close_finger_batch, link_poses_batch
from qsplan.hands.description import load_hand
from qsplan.hands.paper_hand.two_finger import DEFAULT_WORKPIECE
from qsplan.hands.geometry.workpiece import workpiece_world
from qsplan.mechanics.model.manipulator import link_poses
from tests.hands.described_cases import HEXAGON, mixed_description

#: Agreement (m, rad) of the batched closing with the reference: both take the same closed forms of the same
#: numbers; only the order of a few floating-point operations differs.
TOL = 1e-12

CASES = {
    "two_link_hand": (lambda: load_hand("two_link_hand"), DEFAULT_WORKPIECE),
    "parallel_jaw": (lambda: load_hand("parallel_jaw"), HEXAGON),
    "paper_hand": (lambda: load_hand("paper_hand"), DEFAULT_WORKPIECE),
    "mixed": (mixed_description, HEXAGON),
    # a rectangle between parallel jaws: each jaw's face closes flush onto a side (two contacts on one finger)
    "jaws on a rectangle": (lambda: load_hand("parallel_jaw"), [[0.0, 0.0], [0.06, 0.0], [0.06, 0.05], [0.0, 0.05]]),
}


def _states(hand, n, rng):
    lim = hand.description.joint_limits
    xs = rng.uniform(-0.05, 0.05, n)
    q = rng.uniform(lim[:, 0], lim[:, 1], (n, len(lim)))
    return xs, q, np.stack([workpiece_world(hand, hand.pose(x)) for x in xs])


@pytest.mark.parametrize("case", sorted(CASES))
def test_the_batched_closing_is_the_reference_state_by_state(case):
    make, workpiece = CASES[case]
    hand = make_chain_hand(make(), workpiece)
    man, lim = hand.manipulator, hand.description.joint_limits
    xs, q, W = _states(hand, 400, np.random.default_rng(7))
    flush = 0
    for f, side in enumerate((1.0, -1.0)):
        joints = hand.finger_joints(f)
        batch = close_finger_batch(man, q, joints, lim, W, side)
        for i in range(len(xs)):
            ref = close_finger(man, q[i], joints, lim, W[i], side)
            assert batch.found[i] == (ref is not None), (f, i)
            if ref is None:
                continue
            kind = ("edge", "vertex")[batch.kind[i]]
            assert (batch.link, kind, batch.feature[i], batch.link_feature[i], batch.flush[i]) == \
                (ref.link, ref.kind, ref.feature, ref.link_feature, ref.flush), (f, i)
            assert abs(batch.value[i] - ref.value) <= TOL
            np.testing.assert_allclose(batch.point[i], ref.point, rtol=0, atol=TOL)
            np.testing.assert_allclose(batch.normal[i], ref.normal, rtol=0, atol=TOL)
            flush += int(ref.flush)
        assert batch.found.sum() > 20  # the sample reaches contacts
    if case == "jaws on a rectangle":
        assert flush > 20  # the flush rule is exercised


def test_link_poses_batch_is_link_poses_per_state():
    man = mixed_description().manipulator
    q = np.random.default_rng(3).uniform(-1.0, 1.0, (50, man.n_joints))
    batch = link_poses_batch(man, q)
    for i in range(len(q)):
        np.testing.assert_allclose(batch[i], link_poses(man, q[i]), rtol=0, atol=TOL)
