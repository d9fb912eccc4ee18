"""The plan's animation (issue 25): frames checked against the plan's rows, sliding directions against a closed form,
the GIF and the self-contained HTML page read back, and one ``pytest.raises`` per validation branch."""

import base64
import re

import numpy as np
import pytest
from PIL import Image

from qsplan.mechanics import QsplanError
from qsplan.planner.plan.results import ContactSegmentPlan
from qsplan.planner.plotting.animation import MAX_FRAMES, plan_animation
from qsplan.planner.plotting.plan import animation_frames, sliding_directions

def planned(name):
    """``plan_task`` of a bundled task, once per test run (tests/planner/bundled.py)."""
    from tests.planner.bundled import planned as shared

    return shared(name)


@pytest.mark.ompl
@pytest.mark.parametrize("name", ["demo_task", "scripted_regrasp_task", "two_link_regrasp_task"])
def test_frames_follow_the_rows(name):
    plan = planned(name)
    frames = animation_frames(plan, MAX_FRAMES)
    assert 2 <= len(frames) <= MAX_FRAMES and np.all(np.diff([f.t for f in frames]) > 0)
    assert frames[0].t == plan.phases[0].t[0] and frames[-1].t == plan.duration
    for f in frames:
        ph = plan.phases[f.phase]
        assert ph.t[f.row] <= f.t and (f.row == ph.t.size - 1 or f.t < ph.t[f.row + 1])
        if isinstance(ph, ContactSegmentPlan) and ph.kind == "hold":  # a release hold: drawn still, held
            assert f.t == ph.t[f.row] and f.state == "holding" and not any(np.any(d) for _, d in f.contacts)
        elif isinstance(ph, ContactSegmentPlan):  # drawn at its rows, the workpiece sliding along x on the palm
            assert f.t == ph.t[f.row] and np.array_equal(f.q, ph.q[f.row]) and f.state == "sliding"
            dx = np.sign(ph.x[-1] - ph.x[0])
            for _, d in f.contacts[:2]:  # the palm's contacts (the scene's first two)
                assert d == pytest.approx([dx, 0.0], abs=1e-9)
            assert len(f.contacts) == 4 and all(np.any(d) for _, d in f.contacts)  # 4S: every contact slides
        assert (f.state in ("open", "closing")) == (not f.contacts)


@pytest.mark.ompl
def test_a_regrasp_is_animated_open_and_closing():
    plan = planned("two_link_regrasp_task")
    regrasp = next(i for i, p in enumerate(plan.phases) if not p.in_contact)  # after the slide and its release hold
    states = [f.state for f in animation_frames(plan, MAX_FRAMES) if f.phase == regrasp]
    assert states[0] == "holding" and states[-1] == "holding"  # released from, and closed onto, a grasp
    assert "open" in states and "closing" in states and states.index("open") < states.index("closing")


@pytest.mark.ompl
def test_max_frames_keeps_the_plan_ends():
    plan = planned("scripted_regrasp_task")
    frames = animation_frames(plan, 7)
    assert len(frames) <= 7 and frames[0].t == 0.0 and frames[-1].t == plan.duration


@pytest.mark.parametrize("dx", [-0.002, 0.003])
def test_sliding_directions_of_a_translated_workpiece(dx):
    """Fingers held, the workpiece moved by ``dx``: it slips by ``dx`` against every body, so each contact slides along
    its tangent the way ``dx`` projects on it (closed form)."""
    from qsplan.hands import default_hand
    from qsplan.hands.described.records import contacts_at
    from qsplan.hands.paper_hand.two_finger import finger_angles

    hand = default_hand()
    pose = np.array([0.0, hand.rest_height, 0.0])
    q, _ = finger_angles(hand, pose)
    out = sliding_directions(hand, pose, q, pose + [dx, 0.0, 0.0], q)
    for c, (p, d) in zip(contacts_at(hand, pose, q), out):
        tangent = np.array([-c.normal[1], c.normal[0]])
        assert np.array_equal(p, c.point)
        assert d == pytest.approx(np.sign(dx * tangent[0]) * tangent, abs=1e-12)


@pytest.mark.ompl
def test_gif_and_page(tmp_path, capsys):
    plan = planned("two_link_regrasp_task")
    frames = plan_animation(plan, tmp_path / "plan_animation.gif", tmp_path / "plan_animation.html", fps=5,
                            max_frames=24)  # fmt: skip
    assert capsys.readouterr().out == ""  # no library writes to stdout
    assert len(frames) <= 24
    with Image.open(tmp_path / "plan_animation.gif") as gif:
        assert gif.format == "GIF" and gif.n_frames == len(frames) and gif.info["loop"] == 0
        assert gif.info["duration"] == 200
        gif.seek(0)
        first = np.asarray(gif.convert("RGB"))
        gif.seek(gif.n_frames - 1)
        assert not np.array_equal(first, np.asarray(gif.convert("RGB")))  # it moves
    page = (tmp_path / "plan_animation.html").read_text()
    assert "http" not in page and "<link" not in page  # self-contained: works offline
    assert f'type="range" min="0" max="{len(frames) - 1}"' in page
    pngs = re.findall(r'"(iVBOR[A-Za-z0-9+/=]+)"', page)
    assert len(pngs) == len(frames)
    png = tmp_path / "frame.png"
    png.write_bytes(base64.b64decode(pngs[-1]))
    with Image.open(png) as im:
        assert im.size == Image.open(tmp_path / "plan_animation.gif").size
    assert f"phase {len(plan.phases) - 1}, t = {plan.duration:.2f} s, holding" in page


@pytest.mark.parametrize("kwargs, match", [
    ({"fps": 0}, "fps: expected a positive number"),
    ({"max_frames": 1}, "max_frames: expected an integer of at least 2"),
    ({"gif_path": "plan.png"}, "gif_path: expected a file name ending in .gif"),
    ({"html_path": "plan.txt"}, "html_path: expected a file name ending in .html or .htm"),
])  # fmt: skip
def test_bad_arguments_are_refused_before_drawing(tmp_path, kwargs, match):
    kwargs = {k: tmp_path / v if k.endswith("_path") else v for k, v in kwargs.items()}
    with pytest.raises(QsplanError, match=match):
        plan_animation(None, **kwargs)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.ompl
def test_a_turning_plan_is_animated_holding_and_pivoting(tmp_path):
    """Issue 31: the pivot was animated as "sliding".  Each frame's state is its phase's kind; the page says on which
    vertex the workpiece pivots; the pivot's frames show the workpiece turning."""
    plan = planned("reorient_task")
    frames = plan_animation(plan, html_path=tmp_path / "a.html")
    kinds = [plan.phases[f.phase].kind for f in frames]
    assert set(kinds) == {"slide", "hold", "pivot"}
    for f, kind in zip(frames, kinds):
        assert f.state == {"slide": "sliding", "hold": "holding", "pivot": "pivoting"}[kind]
        assert f.contacts  # every finger touches: the contacts are drawn
    turned = [f.pose[2] for f in frames if f.state == "pivoting"]
    assert turned[-1] == pytest.approx(-0.5) and np.all(np.diff(turned) <= 0)
    page = (tmp_path / "a.html").read_text()
    assert "pivoting on vertex 1" in page and "sliding\"" not in page.split("pivoting")[0][-40:]
