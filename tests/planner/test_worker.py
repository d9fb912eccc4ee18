"""The run's second process (issue 33): the plan card drawn while the plan is certified, then its verdict written
onto it (the same pixels as the card drawn at once); what a run draws by default (the card) and with ``--plots all``;
re-simulations taken by whichever process is free first, with the same results; a worker that fails or dies never
withholds a certified plan, and says so; Ctrl-C at a terminal (the whole process group) leaves no process and no
output."""

import json
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from qsplan.planner.cli.main import main
from qsplan.planner.export.files import LOCK_NAME, STAGE_PREFIX
from qsplan.planner.pipeline import worker as worker_module
from qsplan.planner.pipeline.worker import Worker, draw_plots, plot_files, replay_exported
from qsplan.planner.plan.scripted import plan_task
from qsplan.planner.task.task import demo_task_path, load_task

pytestmark = pytest.mark.ompl

#: The demo's plan without the re-simulations: planned, exported and certified in about a second.
QUICK = ["--verify", "0", "--quiet"]


@pytest.fixture(scope="module")
def demo_plan():
    return plan_task(load_task(demo_task_path()))


def png(path):
    from PIL import Image

    with Image.open(path) as im:
        return np.asarray(im.convert("RGBA")).astype(int)


#: Pixels two drawings of one card may differ in, and by how much (of 255): the antialiasing of an edge whose
#: coordinates differ in their last bits between two computations of the same geometry (seen: 3 pixels, 1 level).  A
#: verdict written wrong (a word, a colour, a line moved) changes hundreds of pixels by far more.
SAME_PICTURE = (50, 32)


def same_picture(a, b) -> bool:
    d = np.abs(a - b).max(axis=-1)
    return a.shape == b.shape and int((d > 0).sum()) <= SAME_PICTURE[0] and int(d.max()) <= SAME_PICTURE[1]


class _Row:
    def __init__(self, points):
        self.friction_points = points


class _Cert:
    """A certificate as the card reads it (rows with their friction points, ok, violations)."""

    def __init__(self, rows, points, ok=True):
        self.rows = [_Row(points) for _ in range(rows)]
        self.ok, self.violations = ok, [] if ok else ["a violation"]


def test_the_card_drafted_then_finished_is_the_card_drawn_at_once(demo_plan, tmp_path):
    from qsplan.planner.plotting.card import CARD_DPI, draft_card, finish_card, plan_card
    from qsplan.planner.plotting.style import save_figure
    from qsplan.planner.plotting.verdict import verdict_facts, verdict_text

    cert = _Cert(81, 7)  # not the draft's guess of the friction points: the line differs, its line count not
    stated = verdict_text(verdict_facts(cert), (True, True, True))
    save_figure(plan_card(demo_plan, stated=stated), tmp_path / "once.png", dpi=CARD_DPI, tight=False)
    finish_card(draft_card(demo_plan, 3), stated, tmp_path / "drafted.png")
    assert same_picture(png(tmp_path / "once.png"), png(tmp_path / "drafted.png"))
    # a verdict of another length (one re-simulation left its modes): the card is drawn again whole, the same as at once
    stated = verdict_text(verdict_facts(cert), (True, False, True))
    save_figure(plan_card(demo_plan, stated=stated), tmp_path / "once.png", dpi=CARD_DPI, tight=False)
    finish_card(draft_card(demo_plan, 3), stated, tmp_path / "drafted.png")
    assert same_picture(png(tmp_path / "once.png"), png(tmp_path / "drafted.png"))
    # and a card finished with another verdict is another picture
    finish_card(draft_card(demo_plan, 3), verdict_text(verdict_facts(cert), (True, True)), tmp_path / "other.png")
    assert not same_picture(png(tmp_path / "once.png"), png(tmp_path / "other.png"))


def test_a_figure_that_fails_is_said_and_the_others_drawn(demo_plan, tmp_path, monkeypatch):
    from qsplan.planner.plotting import plan as plan_plots

    def broken(*args, **kwargs):
        raise RuntimeError("no room\nfor the bands")

    monkeypatch.setattr(plan_plots, "plot_plan_bands", broken)
    names, undrawn = draw_plots(demo_plan, tmp_path, "all", 1, lambda: ((81, 24, True, 0), (True,)))
    assert undrawn == [("plan_bands.png", "RuntimeError: no room for the bands")]
    assert names == [n for n in plot_files("all") if n != "plan_bands.png"]
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(names)


def test_the_worker_re_simulates_as_this_process_does(demo_plan, tmp_path):
    from qsplan.planner.export.plan_files import export_plan

    export_plan(demo_plan, tmp_path, force=True)
    here = [r.as_dict() for r in replay_exported(demo_plan, tmp_path / "plan.csv", 2, 1)]
    with Worker("card") as worker:
        if not worker.in_parallel:
            pytest.skip("no second process can be started here")
        worker.start(demo_plan, tmp_path, 2, 1)
        t0 = time.perf_counter()
        while worker.replaying is None and time.perf_counter() - t0 < 120:  # the worker takes them once drafted
            time.sleep(0.05)
        assert worker.replaying == "worker"
        replays = worker.replays(lambda line: None)
        assert [r.as_dict() for r in replays] == here
        names, undrawn = worker.finish(_Cert(81, 24), [r.followed for r in replays])
    assert names == ["plan_card.png"] and undrawn == [] and (tmp_path / "plan_card.png").is_file()


def run(args, capsys):
    code = main(args)
    out, err = capsys.readouterr()
    return code, out, err


def test_the_default_draws_the_card_and_plots_all_the_rest(tmp_path, capsys):
    code, out, err = run(["demo", "--out", str(tmp_path / "card"), *QUICK], capsys)
    assert code == 0 and err == ""
    assert sorted(p.name for p in (tmp_path / "card").iterdir() if p.suffix in (".png", ".gif", ".html")) == [
        "plan_card.png"]
    code, out, err = run(["demo", "--out", str(tmp_path / "all"), "--plots", "all", *QUICK], capsys)
    assert code == 0 and err == ""
    written = {p.name for p in (tmp_path / "all").iterdir()}
    assert set(plot_files("all")) <= written and out.count("wrote ") == 4 + len(plot_files("all"))
    code, _, err = run(["demo", "--out", str(tmp_path / "x"), "--plots", "all", "--no-plots", *QUICK], capsys)
    assert code == 2 and err.count("\n") == 1 and "--no-plots" in err and not (tmp_path / "x").exists()


def test_a_worker_that_dies_never_withholds_the_certified_plan(tmp_path, capsys, monkeypatch):
    started, killed = Worker.start, []

    def start_then_die(self, *args):
        started(self, *args)
        if self.pid is not None:
            os.kill(self.pid, signal.SIGKILL)  # killed (out of memory, say) while drawing
            killed.append(self.pid)

    monkeypatch.setattr(Worker, "start", start_then_die)
    out = tmp_path / "out"
    code, _, err = run(["demo", "--out", str(out), "--verify", "1", "--quiet"], capsys)
    assert code == 0, err
    if not killed:
        pytest.skip("no second process here (this process runs other threads): nothing to kill")
    names = sorted(p.name for p in out.iterdir() if not p.name.startswith("."))
    assert names == ["certificate.json", "plan.csv", "plan.json", "replay.json", "scene.xml"]
    assert json.loads((out / "certificate.json").read_text())["certified"] is True
    assert err.count("\n") == 1 and err.startswith("qsplan: warning: plan_card.png not drawn (the drawing process ended")
    assert err.rstrip().endswith("the certified plan is published without it")


def test_ctrl_c_at_a_terminal_leaves_no_process_and_no_output(tmp_path):
    """SIGINT to the whole process group (what a terminal sends) while certifying: the worker ignores it, the run ends
    it; exit 130, one line, nothing in DIR, no process of the group left."""
    out = tmp_path / "out"
    argv = [sys.executable, "-m", "qsplan.planner.cli", "demo", "--out", str(out)]
    proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True)
    seen, t0 = "", time.perf_counter()
    while time.perf_counter() - t0 < 120 and "certifying the exported plan" not in seen:
        line = proc.stderr.readline()
        if not line:
            break
        seen += line
    os.killpg(proc.pid, signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err[-500:]
    assert err.splitlines()[-1] == "qsplan: interrupted" and "Traceback" not in err
    assert not out.exists() or [p.name for p in out.iterdir()] == []
    assert _group_ends(proc.pid), "a process of the run outlived it"


def _group_ends(pgid, seconds=10.0) -> bool:
    """Whether every process of the group ``pgid`` ends within ``seconds``."""
    t0 = time.perf_counter()
    while time.perf_counter() - t0 < seconds:
        try:
            os.killpg(pgid, 0)
        except ProcessLookupError:
            return True
        time.sleep(0.05)
    return False


def test_a_killed_run_leaves_no_worker(tmp_path):
    """SIGKILL to the run while it certifies (no cleanup at all): its worker ends with it (the kernel's signal)."""
    argv = [sys.executable, "-m", "qsplan.planner.cli", "demo", "--out", str(tmp_path / "out")]
    proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True)
    seen, t0 = "", time.perf_counter()
    while time.perf_counter() - t0 < 120 and "certifying the exported plan" not in seen:
        line = proc.stderr.readline()
        if not line:
            break
        seen += line
    proc.kill()
    proc.communicate(timeout=60)
    assert _group_ends(proc.pid), "the worker outlived its killed run"
    assert not (tmp_path / "out" / "plan.csv").exists()


def test_the_command_line_offers_what_a_run_draws():
    from qsplan.planner.cli.main import build_parser
    from qsplan.planner.cli.options import UsageError

    parser = build_parser()
    assert parser.parse_args(["demo"]).plots == "card" and not parser.parse_args(["demo"]).no_plots
    assert [parser.parse_args(["plan", "t", "--plots", p]).plots for p in worker_module.PLOTS] == list(worker_module.PLOTS)
    with pytest.raises(UsageError, match="--plots: invalid choice"):
        parser.parse_args(["demo", "--plots", "some"])


def test_staging_files_are_never_published(tmp_path, capsys):
    out = tmp_path / "out"
    assert run(["demo", "--out", str(out), "--verify", "1", "--quiet"], capsys)[0] == 0
    assert not [p.name for p in out.iterdir() if p.name.startswith(".worker") or p.name.startswith(STAGE_PREFIX)
                or p.name == LOCK_NAME]  # fmt: skip
    assert worker_module.plot_files("card") == ("plan_card.png",)
