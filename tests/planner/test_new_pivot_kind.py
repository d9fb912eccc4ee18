"""A new kind of pivot formation is one registry entry, a new hand is one file, and both turn the workpiece
(issue 32's acceptance).

The hand (``tests/data/hands/short_right_finger.toml``) is the paper hand with a right finger of 110 mm: at the demo
workpiece's flush instant it cannot reach vertex 2, so the clockwise turn needs the right fingertip's corner on
edge 1.  The kind (:class:`TipOnEdge`, written here and nowhere else) says that in one gap constraint, and one
:data:`qsplan.hands.formations.pivots.FINGER_FEATURES` entry (this test's monkeypatch) puts it in front of the formation
search, the plan's names, the certifier's formation check and the replay.  With the library's own corner kind taken away
and none added, the turn is refused; with the test's kind added, it is planned, exported and certified, and the
plan's pivot is named by the test's kind.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

from qsplan.hands.formations import pivots
from qsplan.hands.formations.manifold import VertexOnLine, gaps
from qsplan.planner.certify.certify import certify_plan
from qsplan.planner.export.plan_files import export_plan, read_plan_csv
from qsplan.planner.plan.results import PlanFailure
from qsplan.planner.plan.scripted import plan_task
from qsplan.planner.replay.replay import replay_plan
from qsplan.planner.task.task import load_task

pytestmark = pytest.mark.ompl

HANDS = Path(__file__).resolve().parent.parent / "data" / "hands"

#: The demo's workpiece turned 0.04 rad (2.3 deg) clockwise, starting near the flush instant with the right
#: fingertip on edge 1 (its band stays above the resolution to about -2.49 deg at friction [0, 0.2]).
TASK = """
name = "a fingertip pivot of a hand with a short right finger"

[hand]
file = "short_right_finger.toml"
workpiece = [[0.0, 0.0], [0.080, 0.0], [0.085, 0.080], [0.008, 0.100]]
workpiece_mass = 0.2

[motion]
start_x = -0.036

[start]
right = "edge:1"

[goal]
theta = -0.04

[friction]
range = [0.0, 0.2]
shared = false

[controller]
torque_resolution = 0.02
"""


@dataclass(frozen=True, slots=True)
class TipOnEdge:
    """A corner at the tip of the finger's last link on a workpiece edge (internal numbering): the test's kind."""

    corner: int
    edge: int
    kind = "tip"

    @property
    def key(self) -> str:
        return f"tip{self.corner}on{self.edge}"

    def constraint(self, hand, finger: str) -> VertexOnLine:
        return VertexOnLine(finger, self.corner, "workpiece", self.edge)

    def words(self, hand) -> str:
        return f"its tip corner {self.corner} on edge {int(hand.user_edges[self.edge])}"


def tip_candidates(hand, finger: str) -> tuple:
    """Both tip corners of a rectangular link (ring indices 1 and 2: ``[[0, -w], [L, -w], [L, w], [0, w]]``) on
    every workpiece edge."""
    return tuple(TipOnEdge(c, e) for c in (1, 2) for e in range(len(hand.workpiece)))


@pytest.fixture
def task(tmp_path):
    (tmp_path / "short_right_finger.toml").write_text((HANDS / "short_right_finger.toml").read_text())
    (tmp_path / "task.toml").write_text(TASK)
    return load_task(tmp_path / "task.toml")


def test_without_a_fingertip_kind_the_short_finger_cannot_turn(task, monkeypatch):
    monkeypatch.delitem(pivots.FINGER_FEATURES, "corner")
    assert [p.direction for p, _ in pivots.pivot_formations(task.hand)] == [1.0]  # counter-clockwise only
    with pytest.raises(PlanFailure, match="no route of formations reaches it") as info:
        plan_task(task)
    report = info.value.report.as_dict()
    assert [(f["formation"], f["status"]) for f in report["formations"]] == [("pivot:v0:right:e1:vertex3", "not this goal")]


def test_a_new_pivot_kind_is_one_registry_entry(task, monkeypatch, tmp_path):
    monkeypatch.delitem(pivots.FINGER_FEATURES, "corner")
    monkeypatch.setitem(pivots.FINGER_FEATURES, "tip", tip_candidates)
    found = [p for p, _ in pivots.pivot_formations(task.hand) if p.direction < 0]
    assert [p.name for p in found] == ["pivot:v1:left:e3:tip2on1"]
    assert pivots.pivot_from_name(found[0].name, task.hand) == found[0]

    plan = plan_task(task)
    assert [p.kind for p in plan.phases] == ["slide", "hold", "pivot"]
    pivot = plan.phases[-1]
    end = np.concatenate([pivot.poses(0.0)[-1], pivot.q[-1]])
    assert end[2] == pytest.approx(-0.04, abs=1e-12)
    assert np.max(np.abs(gaps(task.hand, found[0].constraints(task.hand), end))) < 1e-9  # on the test's manifold

    out = tmp_path / "out"
    export_plan(plan, out)
    cert = certify_plan(out, task)
    assert cert.ok, cert.summary()
    phases = json.loads((out / "plan.json").read_text())["metadata"]["phases"]
    assert [ph["formation"] for ph in phases] == ["palm_edge", found[0].name, found[0].name]
    cols = read_plan_csv(out / "plan.csv")
    for mu in (0.0, 0.2):  # the friction box's corners: the rigid-body replay keeps every planned mode
        replay = replay_plan(cols, task.hand, mu)
        assert replay.followed, [s.stop for s in replay.segments]
