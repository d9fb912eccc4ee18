"""The control-mode partitioner (eqs. 23, 26, 29-32)."""

import numpy as np
import pytest

from qsplan.mechanics import ContactMode, ModeError, check_mode, planted_scene, solve
from qsplan.mechanics.modes.partition import effort_partitions, partition_table


def test_scene_partition_admits_its_planted_mode_and_is_ranked():
    rng = np.random.default_rng(8)
    for _ in range(25):
        nc = int(rng.integers(3, 6))
        ne = int(rng.integers(0, 3))
        scene, planted = planted_scene(rng, nc, ne, ne + 2)
        sol = solve(scene).solution(planted.letters)
        xi = sol.xi[list(planted.sliding)]
        parts = effort_partitions(scene, planted, xi=xi)
        assert tuple(scene.effort_joints) in [p.effort_joints for p in parts]
        conds = [p.conditioning for p in parts]
        assert conds == sorted(conds, reverse=True)
        assert all(len(p.effort_joints) == planted.n_constraints - 3 for p in parts)


def test_every_admitted_partition_gives_a_unique_solution():
    # Switch the scene to each admitted partition: the planted motion stays a solution of eq. (24).
    rng = np.random.default_rng(12)
    scene, planted = planted_scene(rng, 4, 1, 3)
    ref = solve(scene).solution(planted.letters)
    for p in effort_partitions(scene, planted, xi=ref.xi[list(planted.sliding)]):
        effort = np.zeros(scene.n_joints, dtype=bool)
        effort[list(p.effort_joints)] = True
        alt = scene.with_control(effort, ref.thetadot, ref.tau)
        got = check_mode(alt, planted)
        assert got.feasible
        np.testing.assert_allclose(got.solution.qdot, ref.qdot, atol=1e-9)
        np.testing.assert_allclose(got.solution.c_n, ref.c_n, atol=1e-9)


def test_all_rolling_P_and_Q_share_conditioning():
    # with no sliding contact Q_AI is P_AI transposed up to column signs
    scene, _ = planted_scene(np.random.default_rng(1), 4, 1, 3)
    for p in effort_partitions(scene, ContactMode("RRBB")):
        assert p.rcond_P == pytest.approx(p.rcond_Q, rel=1e-9)


def test_modes_outside_eq29_have_no_partition():
    scene, _ = planted_scene(np.random.default_rng(2), 4, 0, 2)
    assert effort_partitions(scene, ContactMode("SBBB")) == []  # 1 < 3 constraints
    assert effort_partitions(scene, ContactMode("RRRB")) == []  # 6 > 3 + 2 joints


def test_partition_table_lists_only_admitting_partitions():
    scene, planted = planted_scene(np.random.default_rng(3), 3, 1, 2)
    table = partition_table(scene)
    assert () in table and all(len(ContactMode(m).letters) == 3 for v in table.values() for m in v)
    for joints, modes in table.items():
        for m in modes:
            assert ContactMode(m).n_constraints == 3 + len(joints)


def test_bad_xi_rejected():
    scene, _ = planted_scene(np.random.default_rng(2), 3, 0, 2)
    with pytest.raises(ModeError, match="xi"):
        effort_partitions(scene, ContactMode("SSS"), xi=[1, 0, 1])


def test_partition_table_refuses_large_scenes_with_an_estimate(tmp_path, capsys, monkeypatch):
    """Refused from the estimate, before any matrix test (the table's tests would fail this one)."""
    import json

    from qsplan.mechanics import QsplanError
    from qsplan.mechanics.modes import partition
    from qsplan.mechanics.model.scene_io_write import scene_to_dict
    from qsplan.mechanics.modes.partition import MAX_TABLE_TESTS, partition_table_work
    from qsplan.planner.cli.main import main

    scene, _ = planted_scene(np.random.default_rng(5), 16, 3, 5)
    assert partition_table_work(16, 5) > MAX_TABLE_TESTS
    with pytest.raises(QsplanError, match=r"partition: the table for 16 contacts and 5 joints needs about .* matrix tests"):
        partition_table(scene)
    path = tmp_path / "n16.json"
    path.write_text(json.dumps(scene_to_dict(scene)))

    def tested(*args, **kwargs):
        raise AssertionError("a partition was tested")

    # the CLI reads the package's name (``from qsplan.mechanics import ...``), which the package loads and keeps on
    # first use: patch the package first (its real function loaded before the module's is replaced, and restored
    # after), or a package first used here would keep the fake for the rest of the process (test_cli's partition)
    import qsplan.mechanics as mechanics

    for where in (mechanics, partition):
        monkeypatch.setattr(where, "effort_partitions", tested)
    assert main(["partition", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "(--mode LETTERS)" in err


def test_partition_table_work_counts_the_small_table():
    # 3 contacts, 2 joints: eq. 49's modes for 3, 4, 5 constraints, times joint sets, times (1 + 2^n_S)
    from qsplan.mechanics.modes.partition import partition_table_work

    assert partition_table_work(3, 2) == 78
