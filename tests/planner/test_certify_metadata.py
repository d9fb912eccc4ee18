"""Every fact ``plan.json``'s metadata states is checked, or the schema labels it informational (issue 31, item 4).

The tamperings are generated from the metadata tree itself: every leaf the schema does not label informational
(``description`` beginning ``"Informational:"``, :func:`qsplan.planner.export.schema.informational_paths`) is
changed, one at a time, and the metadata check must refuse the plan naming ``metadata``; every informational leaf
changed must leave it certified (the label is true: nothing checks it).  The metadata check runs on what one
certification of the genuine plan found from the task (its rows' contacts and recomputed bands), captured once per
plan, so the hundreds of tamperings take seconds.  The issue's escapes (a turning plan's pivot contact sets merged
into one SSSS set, a contact dropped from them, the hold's proved interval claimed from -100 N m) also go through
``qsplan verify`` with and without ``--task``: exit 1 naming the row and the field.
"""

import copy
import json
import re

import pytest

from qsplan.planner import ompl_available, task_paths
from qsplan.planner.export.schema import INFORMATIONAL, informational_paths, validate

from tests.planner.test_certify_tampering import _read, _run, _write
from tests.reference.paper_pivot import RETIRED_NAMES

pytestmark = pytest.mark.ompl

#: Turning plans (a slide, a certified hold, a pivot) and regrasp plans (slides and regrasps; a chain hand's).
TURNING = ("reorient_task", "reorient_edge_task")
REGRASP = ("two_link_regrasp_task", "scripted_regrasp_task")


@pytest.fixture(scope="module")
def captured(bundled_plan):
    """``captured(name)``: ``(plan dir, doc, task, cols, evidence)`` of the bundled task ``name``, planned once per
    session; ``evidence`` is what one certification of the genuine plan found (the arguments its metadata check got),
    and that certification passed."""
    if not ompl_available():
        pytest.skip("OMPL bindings not installed")
    import qsplan.planner.certify.certify as certify_module
    from qsplan.planner.task.task import load_task

    done = {}

    def get(name):
        if name not in done:
            src = bundled_plan(name)
            task = load_task(task_paths()[name])
            seen = []
            real = certify_module.metadata_checks

            def spy(meta, task_, cols, evidence=None):
                seen.append((task_, cols, evidence))
                return real(meta, task_, cols, evidence)

            with pytest.MonkeyPatch.context() as mp:
                mp.setattr(certify_module, "metadata_checks", spy)
                cert = certify_module.certify_plan(src, task, n_random=0)
            assert cert.ok, [str(v) for v in cert.violations[:4]]
            assert len(seen) == 1
            doc = json.loads((src / "plan.json").read_text())
            done[name] = (src, doc, *seen[0])
        return done[name]

    return get


def _leaves(value, path):
    """``(path, kind)`` of every leaf (number, string, bool, null, empty list or object) and every non-empty list
    (kind ``"list"``: its last entry dropped) under ``value``, in document order."""
    if isinstance(value, dict) and value:
        for key, item in value.items():
            yield from _leaves(item, f"{path}.{key}")
    elif isinstance(value, list) and value:
        yield path, "list"
        for i, item in enumerate(value):
            yield from _leaves(item, f"{path}[{i}]")
    else:
        yield path, "leaf"


_STEP = re.compile(r"\.([^.\[\]]+)|\[(\d+)\]")


def _parent(doc, path):
    """``(container, key)`` of ``path`` (``$.metadata.phases[2].contacts``) in ``doc``."""
    parts = [(m.group(1), m.group(2)) for m in _STEP.finditer(path[1:])]
    node = doc
    for name, index in parts[:-1]:
        node = node[name] if name is not None else node[int(index)]
    name, index = parts[-1]
    return node, (name if name is not None else int(index))


def _tampered(value):
    """A different value of the same kind: a number moved by half itself (at least 0.5; an integer by 1), a string
    extended, a bool flipped, null a number, an empty list or object given an entry."""
    if isinstance(value, bool):
        return not value
    if isinstance(value, int):
        return value + 1
    if isinstance(value, float):
        return value + max(0.5, 0.5 * abs(value))
    if isinstance(value, str):
        return value + "X"
    if value is None:
        return 1.0
    if isinstance(value, list):
        return ["X"]
    return {"X": 1}


def _tamperings(doc):
    """``(path, tampered doc, informational, still informational)`` for every leaf and list of ``doc["metadata"]``:
    whether the schema labels what is changed informational in ``doc``, and in the tampered document (a step whose
    kind is changed is another step, no longer the search's figures)."""
    info = informational_paths(doc)
    for path, kind in _leaves(doc["metadata"], "$.metadata"):
        if kind == "list" and path.endswith(".competitors_precluded"):
            continue  # a shorter list of precluded modes is still true: the promise is per listed mode
        bad = dict(doc, metadata=copy.deepcopy(doc["metadata"]))  # the rows shared: only the metadata is changed
        node, key = _parent(bad, path)
        where = path
        if kind == "list":
            where = f"{path}[{len(node[key]) - 1}]"  # what the tampering removes
            node[key] = node[key][:-1]
        else:
            node[key] = _tampered(node[key])
        under = lambda labels: any(where == p or where.startswith((p + ".", p + "[")) for p in labels)  # noqa: E731
        labelled = under(info)
        yield path, bad, labelled, labelled and (kind == "list" or under(informational_paths(bad)))


def _metadata_violations(captured_plan, doc):
    from qsplan.planner.certify.files import metadata_checks

    _, _, task, cols, evidence = captured_plan
    return metadata_checks(doc["metadata"], task, cols, evidence)


def _every_fact_checked(captured, name):
    """Each non-informational leaf of ``name``'s metadata changed (or a list shortened): refused, naming ``metadata``;
    each informational leaf changed: still certified."""
    plan = captured(name)
    doc = plan[1]
    assert not _metadata_violations(plan, doc)
    escaped, flagged, checked = [], [], 0
    for path, bad, informational, still in _tamperings(doc):
        found = _metadata_violations(plan, bad)
        checked += 1
        if informational and still and found:
            flagged.append((path, found[0][2]))
        elif not informational and not found:
            escaped.append(path)
        assert all(kind == "metadata" and message and "np." not in message for _, kind, message in found), found
    assert checked > 100, checked  # the whole tree, not a handful
    assert not escaped, f"{len(escaped)} tamperings of facts not labelled informational escaped: {escaped[:10]}"
    assert not flagged, f"keys labelled informational are checked: {flagged[:5]}"


@pytest.mark.slow
@pytest.mark.parametrize("name", TURNING + REGRASP)
def test_every_stated_fact_is_checked(captured, name):
    _every_fact_checked(captured, name)


def test_every_stated_fact_of_a_jaw_plan_is_checked(captured):
    """The same on the parallel jaw's plan (prismatic joints, efforts in N; planned in ~2 s), in the default suite."""
    _every_fact_checked(captured, "parallel_jaw_task")


@pytest.mark.parametrize("stated", [*RETIRED_NAMES, "palm_edge"])
def test_a_pivot_phase_stating_another_formation_is_refused(captured, stated):
    """The pivot phase of ``reorient_task`` claiming a formation other than its generated pivot's: the retired names of
    the hand-built route (issue 32: no longer registered) and the palm edge's (registered, other contacts) are
    refused, naming the field, the claim and what the phase's contacts are."""
    plan = captured("reorient_task")
    doc = plan[1]
    bad = dict(doc, metadata=copy.deepcopy(doc["metadata"]))
    k, phase = next((k, p) for k, p in enumerate(bad["metadata"]["phases"]) if p.get("phase_kind") == "pivot")
    assert phase["formation"].startswith("pivot:v1:left:")
    phase["formation"] = stated
    found = _metadata_violations(plan, bad)
    messages = [message for _, kind, message in found if kind == "metadata"]
    assert any(f"phases[{k}].formation states \"{stated}\"" in m for m in messages), found
    assert all("np." not in m for m in messages)
    if stated != "palm_edge":
        assert any("neither a registered formation (palm_edge) nor a pivot formation" in m for m in messages), found


def test_informational_labels_follow_the_schema():
    """:func:`informational_paths` finds the labelled keys through ``$ref`` and ``oneOf``, not a key of the same name
    elsewhere; every label begins with the one prefix."""
    schema = {"type": "object", "properties": {
        "a": {"type": "string", "description": INFORMATIONAL + " a label"},
        "b": {"$ref": "#/$defs/b"},
        "steps": {"type": "array", "items": {"oneOf": [
            {"type": "object", "required": ["kind"], "properties": {"kind": {"const": "x"},
                                                                     "a": {"description": INFORMATIONAL + " x's"}}},
            {"type": "object", "required": ["kind"], "properties": {"kind": {"const": "y"}},
             "description": INFORMATIONAL + " y, whole"}]}}},
        "$defs": {"b": {"type": "object", "properties": {"a": {"type": "number"},
                                                         "c": {"description": INFORMATIONAL + " c"}}}}}  # fmt: skip
    doc = {"a": "name", "b": {"a": 1, "c": 2}, "steps": [{"kind": "x", "a": 1}, {"kind": "y", "a": 1}, {"kind": "x"}]}
    assert not validate(doc, schema)
    assert informational_paths(doc, schema) == ["$.a", "$.b.c", "$.steps[0].a", "$.steps[1]"]


def test_the_shipped_schema_labels_only_bookkeeping():
    """The plan schema's informational labels: names, labels, the run's bookkeeping, the search's figures and a finger
    replacement's formation (the next phases name it) and proof margin (the row checks prove the hold again)."""
    from qsplan.planner.export.schema import schedule_schema

    labelled = []

    def walk(node, key):
        if isinstance(node, dict):
            if str(node.get("description", "")).startswith(INFORMATIONAL):
                labelled.append(key if key != "oneOf" else node["properties"]["kind"]["const"])
            for k, item in node.items():
                walk(item, k)
        elif isinstance(node, list):
            for item in node:
                walk(item, key)

    walk(schedule_schema(), "$")
    assert sorted(labelled) == sorted(["description_source", "task", "source", "planner", "name", "ompl_states",
                                       "binding", "grasp", "grasp_from", "grasp_to", "from", "to", "search",
                                       "name", "phase", "formation", "hold_margin_N"]), labelled  # fmt: skip


# --- the escapes, through the command line ----------------------------------------------------------------


def merge_pivot_contact_sets(doc):
    """The pivot's contact sets merged into one SSSS set: the BSSSS transition row hidden."""
    phase = next(p for p in doc["metadata"]["phases"] if p.get("phase_kind") == "pivot")
    sets = phase["contact_sets"]
    phase["contact_sets"] = [{"rows": [0, sets[-1]["rows"][1]], "contacts": sets[-1]["contacts"], "mode": "SSSS"}]
    return "contact_sets"


def drop_a_contact(doc):
    """A contact dropped from the pivot's contact sets."""
    phase = next(p for p in doc["metadata"]["phases"] if p.get("phase_kind") == "pivot")
    phase["contact_sets"][-1]["contacts"].pop(1)
    return "contact_sets"


def hold_from_minus_100(doc):
    """The hold's proved interval claimed from -100 N m."""
    step = next(s for s in doc["metadata"]["sequence"] if s["kind"] == "hold")
    step["proved_interval"][0] = -100.0
    return "proved_interval"


ESCAPES = [merge_pivot_contact_sets, drop_a_contact, hold_from_minus_100]


@pytest.mark.slow
@pytest.mark.parametrize("with_task", [False, True], ids=["recorded-task", "with-task"])
@pytest.mark.parametrize("edit", ESCAPES, ids=[e.__name__ for e in ESCAPES])
@pytest.mark.parametrize("name", TURNING)
def test_turning_plan_metadata_escapes_are_refused(bundled_plan, tmp_path, name, edit, with_task):
    """``qsplan verify DIR`` and ``qsplan verify DIR --task FILE``: exit 1, the row and the field named."""
    rows, doc = _read(bundled_plan(name))
    field = edit(doc)
    bad = _write(tmp_path / "bad", rows, doc)
    argv = ["verify", str(bad), "--random", "0"] + (["--task", str(task_paths()[name])] if with_task else [])
    code, out, err = _run(argv)
    assert code == 1, (code, out, err)
    lines = [line for line in out.splitlines() if ": metadata: " in line]
    assert lines and all(re.match(r"row \d+ \(t = ", line) for line in lines), out
    assert any(field in line for line in lines), out
    assert "Traceback" not in err and "np." not in out
