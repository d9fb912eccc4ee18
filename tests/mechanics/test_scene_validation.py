"""Hostile and careless scene files refused in one line naming the field (issue 12): encoding, nesting,
magnitudes, friction, and raw wrench columns checked as a contact frame (eq. 1)."""

import json

import numpy as np
import pytest

from qsplan.hands.examples.paper import eq37_scene, eq42_scene, rod_scene
from qsplan.mechanics import SceneError, load_scene, scene_from_dict
from qsplan.mechanics.model.contact import FRAME_TOL, check_contact_frame, wrench_matrix
from qsplan.mechanics.model.fields import MAX_DEPTH, MAX_FILE_BYTES, nesting_depth, read_document
from qsplan.mechanics.model.friction import MAX_FRICTION, check_friction, check_mu_range

from tests.fuzzing import ROOT


def _raw(**contact):
    c = {"wn": [0.0, 1.0, -1.0], "wt": [-1.0, 0.0, 0.0], "mu": 0.3, "velocity": [0.0, 1.0]}
    c.update(contact)
    return {"g_obj": [0.0, -1.0, 0.0], "contacts": [c, {"r": [1.0, 0.0], "n": [0.0, 1.0], "mu": 0.3, "velocity": [0, 1]}]}


@pytest.mark.parametrize("name", ["eq37", "eq42", "rod"])
def test_paper_scenes_pass_the_frame_check(name):
    doc = {"eq37": eq37_scene, "eq42": eq42_scene, "rod": rod_scene}[name]()
    assert scene_from_dict(doc).n_contacts >= 2


@pytest.mark.parametrize("path", sorted((ROOT / "examples" / "scenes").glob("*.*")), ids=lambda p: p.name)
def test_example_scene_files_load(path):
    assert load_scene(path).n_contacts >= 1


@pytest.mark.parametrize(
    "contact,match",
    [
        ({"wn": [0.0, 1.1, -1.0]}, r"contacts\[0\]\.wn: the force part .* has length 1\.1; expected a unit normal"),
        ({"wn": [1e-11, 0.0, 0.0], "wt": [0.0, 1e-11, 0.0]}, r"contacts\[0\]\.wn: .*expected a unit normal"),
        ({"wt": [0.0, 1.0, -1.0]}, r"contacts\[0\]\.wt: .* not the normal turned by \+90 degrees"),
        ({"wt": [1.0, 0.0, 0.0]}, r"contacts\[0\]\.wt: .* not the normal turned"),
        ({"wn": [0.0, 1.0, 1e30]}, r"contacts\[0\]\.wn\[2\]: expected a magnitude of at most 1e\+06"),
        ({"wn": [0.0, 1e308, 0.0]}, r"contacts\[0\]\.wn\[1\]: expected a magnitude"),
        ({"wn": [0.0, 10**400, 0.0]}, r"contacts\[0\]\.wn\[1\]: expected a finite number; got 1000"),
        ({"mu": 1e3}, r"contacts\[0\]\.mu: expected friction coefficients of at most 100"),
    ],
)
def test_bad_wrench_columns_are_refused(contact, match):
    with pytest.raises(SceneError, match=match):
        scene_from_dict(_raw(**contact))


def test_rounded_frames_within_tolerance_are_accepted():
    assert scene_from_dict(_raw(wn=[0.0, 1.0 + FRAME_TOL / 2, -1.0])).n_contacts == 2


def test_frame_check_recovers_the_contact_point():
    rng = np.random.default_rng(3)
    for _ in range(20):
        r, angle = rng.normal(size=2), rng.uniform(-np.pi, np.pi)
        W = wrench_matrix(r, [np.cos(angle), np.sin(angle)])
        np.testing.assert_allclose(check_contact_frame(W[:, 0], W[:, 1]), r, atol=1e-12)


def test_huge_normal_in_point_form_is_refused():
    doc = _raw()
    doc["contacts"][1]["n"] = [0.0, 1e308]
    with pytest.raises(SceneError, match=r"contacts\[1\]\.n\[1\]: expected a magnitude"):
        scene_from_dict(doc)


@pytest.mark.parametrize(
    "data,suffix,match",
    [
        (json.dumps(eq42_scene()).encode("utf-16"), ".json", "UTF-16 encoded; expected UTF-8"),
        (b'{"g_obj": [0, -1, 0], "name": "\xff\xfe"}', ".json", r"not UTF-8 text \(byte 31 is b.\\xff."),
        (b'{"a": ' + b"[" * 100_000 + b"]" * 100_000 + b"}", ".json", f"nests lists/tables 100001 deep; expected at most {MAX_DEPTH}"),
        (b"a = " + b"[" * 5000 + b"]" * 5000, ".toml", "nests lists/tables 5000 deep"),
        (b'{"g_obj": [' + b"1" * 5000 + b"]}", ".json", "invalid JSON: Exceeds the limit"),
        (b'{"g_obj": [0, -1, 0], "x": "\x00"}', ".json", "contains NUL"),
        (b"[1, 2]", ".json", "expected an object/table at the top level; got list"),
    ],
    ids=["utf16", "bad-utf8", "deep-json", "deep-toml", "huge-int", "nul", "list"],
)
def test_hostile_files_one_line_error(tmp_path, data, suffix, match):
    path = tmp_path / f"s{suffix}"
    path.write_bytes(data)
    with pytest.raises(SceneError, match=match) as info:
        load_scene(path)
    assert "\n" not in str(info.value) and len(str(info.value)) < 400


def test_utf8_bom_is_accepted(tmp_path):
    path = tmp_path / "s.json"
    path.write_bytes(json.dumps(eq42_scene()).encode("utf-8-sig"))
    assert load_scene(path).n_contacts == 3


def test_oversized_file_is_refused_unparsed(tmp_path):
    path = tmp_path / "s.json"
    path.write_bytes(b" " * (MAX_FILE_BYTES + 1))
    with pytest.raises(SceneError, match="larger than 4 MiB"):
        read_document(path)


@pytest.mark.parametrize(
    "text,toml,depth",
    [('{"a": "[[[[", "b": [1]}', False, 2), ("a = '[[[[' # [[[[\n[b]\nc = [[1]]", True, 3), ('{"a": "\\"[["}', False, 1),
     ('a = """ [[[ """', True, 0)],  # fmt: skip
)
def test_nesting_depth_ignores_strings_and_comments(text, toml, depth):
    assert nesting_depth(text, toml=toml) == depth


def test_friction_bounded_everywhere():
    assert check_friction(MAX_FRICTION) == MAX_FRICTION
    with pytest.raises(SceneError, match="at most 100"):
        check_friction([0.1, 1e308], "mu")
    with pytest.raises(SceneError, match=r"mu range: expected HI <= 100"):
        check_mu_range(0.0, 1e3)
