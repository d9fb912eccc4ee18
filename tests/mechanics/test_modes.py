"""Contact modes: enumeration under the utility conditions, eq. (49) and Table 1."""

import pytest

from qsplan.mechanics import ContactMode, ModeError, count_modes, enumerate_modes, iter_mode_batches, mode_from_letters
from qsplan.mechanics.modes.contact_mode import codes_to_letters, mode_index_array

TABLE1 = {  # the paper's Table 1, n_c = 3..8
    -1: [6, 16, 45, 126, 357, 1016],
    0: [7, 19, 51, 141, 393, 1107],
    1: [6, 16, 45, 126, 357, 1016],
}


@pytest.mark.parametrize("offset", [-1, 0, 1])
def test_table1_counts_by_formula_and_by_enumeration(offset):
    formula = [count_modes(nc, nc + offset) for nc in range(3, 9)]
    enumerated = [len(enumerate_modes(nc, nc + offset)) for nc in range(3, 9)]
    batched = [sum(len(b) for b in iter_mode_batches(nc, nc + offset, 97)) for nc in range(3, 9)]
    assert formula == TABLE1[offset]
    assert enumerated == TABLE1[offset]
    assert batched == TABLE1[offset]


def test_paper_large_counts():
    assert count_modes(20, 20) == 377_379_369
    assert count_modes(12, 12) == 73_789  # "over 73,000 contact modes" (Section 4.7)
    assert count_modes(16, 16) == 5_196_627


def test_every_enumerated_mode_satisfies_eq29_and_is_unique():
    for nc, dof in [(4, 3), (5, 6), (6, 7), (7, 4)]:
        modes = enumerate_modes(nc, dof)
        assert len({m.letters for m in modes}) == len(modes)
        assert all(m.n_constraints == dof for m in modes)
        # and nothing is missed: brute force over 3**n_c
        brute = sum(
            1 for k in range(3**nc) if sum({0: 0, 1: 2, 2: 1}[(k // 3**i) % 3] for i in range(nc)) == dof
        )
        assert brute == len(modes)


def test_three_contact_order_is_the_papers_numbering():
    # Fig. 6 numbering: 3S=1, R1S2=2, R1S3=3, R2S1=4, R2S3=5, R3S1=6, R3S2=7
    assert [m.name for m in enumerate_modes(3, 3)] == ["3S", "R1S2", "R1S3", "R2S1", "R2S3", "R3S1", "R3S2"]


def test_no_modes_below_half_dof():
    assert count_modes(2, 5) == 0 and enumerate_modes(2, 5) == []


@pytest.mark.parametrize("batch", [1, 2, 7, 64, 10_000])
def test_batches_reproduce_enumeration_order(batch):
    ref = [m.letters for m in enumerate_modes(7, 7)]
    got = [codes_to_letters(c) for b in iter_mode_batches(7, 7, batch) for c in b]
    assert got == ref
    assert all(len(b) <= batch for b in iter_mode_batches(7, 7, batch))
    assert [codes_to_letters(c) for c in mode_index_array(7, 7)] == ref


def test_mode_names_and_kinds():
    assert ContactMode("RBS").name == "R1S3" and ContactMode("RBS").kind == "RS"
    assert ContactMode("SSSS").name == "4S" and ContactMode("SSSS").kind == "4S"
    assert ContactMode("RSSB").kind == "R2S" and ContactMode("RSSB").name == "R1S2,3"
    assert ContactMode("RR").kind == "2R" and ContactMode("RR").name == "R1,2"
    m = ContactMode("SRB")
    assert (m.rolling, m.sliding, m.breaking, m.n_constraints) == ((1,), (0,), (2,), 3)


@pytest.mark.parametrize("bad", ["", "RXS", "r s"])
def test_bad_mode_letters(bad):
    with pytest.raises(ModeError, match="letters"):
        ContactMode(bad)


def test_mode_length_checked():
    with pytest.raises(ModeError, match="expected 3 letters"):
        mode_from_letters("RS", 3)
    assert mode_from_letters("rbs", 3).letters == "RBS"


def test_negative_counts_rejected():
    with pytest.raises(ModeError):
        count_modes(-1, 3)
    with pytest.raises(ModeError):
        list(iter_mode_batches(3, 3, 0))
