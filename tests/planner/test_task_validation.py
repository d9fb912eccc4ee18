"""Task files validated at every level (issue 12): unknown keys in sub-tables, physical ranges, encoding."""

import tomllib

import pytest

from qsplan.mechanics import QsplanError
from qsplan.planner.task.task import MAX_WAYPOINTS, TASK_RANGES, demo_task_path, load_task, make_task, task_paths

from tests.fuzzing import toml_text


@pytest.fixture
def demo():
    return tomllib.loads(task_paths()["scripted_regrasp_task"].read_text())


def _load(tmp_path, doc):
    path = tmp_path / "t.toml"
    path.write_text(toml_text(doc))
    return load_task(path)


def test_bundled_tasks_load():
    for path in task_paths().values():
        task = load_task(path)
        assert len(task.waypoints) >= 1 or task.goal is not None
    assert load_task(demo_task_path()).goal is not None  # qsplan demo plans automatically


@pytest.mark.parametrize(
    "table,key,value,match",
    [
        ("limits", "joint_sped", 0.05, r"limits\.joint_sped: unknown field; expected some of (\w+, )*joint_speed, left"),
        ("motion", "goal", 0.1, r"motion\.goal: unknown field"),
        ("friction", "rnage", [0, 1], r"friction\.rnage: unknown field"),
        ("controller", "torque_res", 0.1, r"controller\.torque_res: unknown field"),
        ("hand", "finger_lenght", 0.1, r"hand\.finger_lenght: unknown field"),
        ("limits", "workpiece_speed", 1e-300, r"limits\.workpiece_speed: expected 0\.0001 to 0\.5 m/s"),
        ("limits", "joint_speed", 1e3, r"limits\.joint_speed: expected 0\.001 to 10 rad/s"),
        ("controller", "torque_resolution", 1e300, r"controller\.torque_resolution: expected 1e-06 to 10 N m"),
        ("limits", "left", [-100.0, 100.0], r"limits\.left: expected -3\.14159 to 3\.14159 rad"),
        ("limits", "right", [1.0, 1.0], r"limits\.right: expected lo < hi"),
        ("friction", "range", [0.2, 0.2], r"friction\.range: expected lo < hi"),
        ("friction", "range", [0.0, 1e308], r"friction\.range: expected HI <= 100"),
        ("friction", "shared", 1, r"friction\.shared: expected true or false"),
        ("hand", "finger_length", 1e21, r"hand\.finger_length: expected 0\.001 to 1 m"),
        ("hand", "finger_width", 10**400, r"hand\.finger_width: expected a positive finite number|hand\.finger_width: "),
        ("hand", "workpiece_mass", "heavy", r"hand\.workpiece_mass: expected a number"),
        ("hand", "workpiece", [[0, 0], [1e30, 0], [0, 1]], r"hand\.workpiece\[1\]: expected -1 to 1 m"),
        ("motion", "waypoints", [0.01 * (-1) ** k for k in range(MAX_WAYPOINTS + 1)], r"motion\.waypoints: expected a list of 1 to 50"),
        ("motion", "waypoints", [1e-300], r"motion\.waypoints\[0\]: segment 1 moves the workpiece 1e-300 m"),
        ("motion", "start_x", 1e21, r"motion\.start_x: expected -1 to 1 m"),
        ("controller", "min_normal_force", 1e6,
         r"^controller\.min_normal_force: expected 0 to 100 N \(.*TASK_RANGES\['min_normal_force'\]\); got 1e\+06$"),
        ("controller", "min_coulomb_slack", 101.0,
         r"^controller\.min_coulomb_slack: expected 0 to 100 N \(.*TASK_RANGES\['min_coulomb_slack'\]\); got 101$"),
        ("controller", "min_normal_force", -0.01, r"^controller\.min_normal_force: expected a nonnegative finite force \(N\)"),
        ("controller", "min_coulomb_slack", "0.1", r"^controller\.min_coulomb_slack: expected a nonnegative finite force"),
        ("hand", "finger_length", 160, r"^hand\.finger_length: expected 0\.001 to 1 m .*; got 160: looks like millimetres; "
                                       r"expected metres$"),
    ],
)
def test_bad_task_fields_one_line(tmp_path, demo, table, key, value, match):
    demo[table][key] = value
    with pytest.raises(QsplanError, match=match) as info:
        _load(tmp_path, demo)
    assert "\n" not in str(info.value)


def test_every_range_has_a_unit():
    for lo, hi, unit in TASK_RANGES.values():
        assert lo < hi and unit


@pytest.mark.parametrize(
    "data,match",
    [(b"\xff\xfe" + "name = 'x'".encode("utf-16-le"), "UTF-16"), (b"a = " + b"[" * 3000 + b"]" * 3000, "nests"),
     (b"a = " + b"9" * 5000, "not valid TOML"), (b"name = \xc3", "not UTF-8")],  # fmt: skip
)
def test_hostile_task_files(tmp_path, data, match):
    path = tmp_path / "t.toml"
    path.write_bytes(data)
    with pytest.raises(QsplanError, match=match):
        load_task(path)


def test_make_task_checks_ranges_of_a_built_hand():
    from qsplan.hands.paper_hand.two_finger import default_hand

    with pytest.raises(QsplanError, match=r"limits\.workpiece_speed"):
        make_task(default_hand(), 0.0, [-0.04], workpiece_speed=1e-300)


@pytest.mark.parametrize("key", ["min_normal_force", "min_coulomb_slack"])
def test_controller_margins_at_their_range_edges_are_kept(tmp_path, demo, key):
    for value in TASK_RANGES[key][:2]:
        demo["controller"][key] = value
        margin = _load(tmp_path, demo).force_margin
        assert (margin.normal if key == "min_normal_force" else margin.slack) == value


def test_a_task_names_its_hand_files_out_of_range_field(tmp_path):
    from qsplan.hands.description import bundled_hands

    (tmp_path / "big.toml").write_text(bundled_hands()["two_link_hand"].read_text().replace("mass = 0.0", "mass = 1e5", 1))
    doc = tomllib.loads(task_paths()["two_link_task"].read_text())
    doc["hand"] = {k: v for k, v in doc["hand"].items() if k in ("workpiece", "workpiece_mass", "mu", "palm_edge")}
    doc["hand"]["file"] = "big.toml"
    with pytest.raises(QsplanError, match=r"^hand\.file: .*big\.toml: fingers\[0\]\.joints\[0\]\.link\.mass: expected 0 "
                                          r"to 100 kg .*; got 100000$"):  # fmt: skip
        _load(tmp_path, doc)
