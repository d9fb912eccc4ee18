"""The certifier's mode checks of a whole plan at once (:func:`qsplan.planner.certify.modes.plan_mode_checks`)
against the row-by-row reference (:func:`~qsplan.planner.certify.modes.mode_checks`, then
:func:`~qsplan.planner.certify.modes.disturbance_checks` at every vertex of the task's wrench box): the same failures,
in the same order, with the same messages, and the same modes set aside, on the demo's reference plan and on
variants made to fail in every way the check names (a wrench box that breaks the planned mode, a force margin, no
driving speed, torques beyond the bands, the velocity reversed).

The whole-plan certificates (batched against ``batched=False``) are compared in ``test_certify.py`` and, on a turning
plan with holds and five-contact rows, below (slow)."""

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from qsplan.mechanics.bands.disturbance import WrenchBox
from qsplan.planner.certify.contacts import judged_contacts
from qsplan.planner.certify.modes import ModeJob, disturbance_checks, mode_checks, plan_mode_checks, row_scene
from qsplan.planner.certify.rows import friction_points
from qsplan.planner.export.plan_files import read_plan_csv
from qsplan.planner.task.task import demo_task_path, load_task

REFERENCE = Path(__file__).resolve().parent.parent / "data" / "reference_plans" / "demo_task.csv"


def _cols(edit=None):
    cols = {k: np.array(v, copy=True) for k, v in read_plan_csv(REFERENCE).items()}
    if edit is not None:
        edit(cols)
    return cols


def _stop(cols):  # no driving speed on rows 10-13: every mode degenerate
    for k in range(10, 14):
        v = "right" if cols["effort_joint"][k] == "left" else "left"
        cols[f"qd_{v}"][k] = 0.0


def _far(cols):  # torques far beyond their bands on rows 20-23: competitors win, the planned mode fails
    for k in range(20, 24):
        e = str(cols["effort_joint"][k])
        cols[f"tau_{e}"][k] = cols[f"tau_{e}"][k] * 4.0 + 10.0


def _reverse(cols):  # the velocity-controlled finger driven backwards on rows 30-33: the workpiece moves the other way
    for k in range(30, 34):
        v = "right" if cols["effort_joint"][k] == "left" else "left"
        cols[f"qd_{v}"][k] = -cols[f"qd_{v}"][k]


def _jobs(task, cols, rows, n_random, seed=0):
    """Each row's ModeJob as certify_plan builds it (moving rows; the rows' own x speed, as the motion check uses)."""
    from qsplan.planner.certify.certify import _v_rows

    rng = np.random.default_rng(seed)
    jobs = []
    for k in rows:
        scene = row_scene(task, cols, k, judged_contacts(task, cols, k))
        mus = friction_points(task, n_random, rng, scene.n_contacts)
        jobs.append(ModeJob(k, scene, mus, _v_rows(cols, k, ["left", "right"])))
    return jobs


def _reference(task, cols, jobs, margin):
    out = {}
    for job in jobs:
        found, excluded = mode_checks(task, cols, job.row, job.mus, margin, job.v_rows, True, job.scene)
        if task.disturbance is not None:
            found += disturbance_checks(task, cols, job.row, job.mus, margin, True, job.scene)
        out[job.row] = (found, excluded)
    return out


BIG_BOX = WrenchBox((-6.0, -6.0, -0.05), (6.0, 6.0, 0.05))  # N, N, N m: far beyond the demo's inertial box


@pytest.mark.parametrize("edit, box, margin, kinds", [
    (None, "task", 0.0, set()),
    (None, None, 0.0, set()),
    (None, BIG_BOX, 0.0, {"mode"}),
    (None, BIG_BOX, 0.5, {"mode", "force margin"}),
    (None, "task", 5.0, {"force margin"}),
    (_stop, "task", 0.0, {"mode"}),
    (_far, BIG_BOX, 0.0, {"mode"}),
    (_reverse, "task", 0.0, {"motion"}),
], ids=["demo", "no box", "big box", "big box and margin", "margin", "stopped", "far", "reversed"])  # fmt: skip
def test_plan_at_once_is_row_by_row(edit, box, margin, kinds):
    task = load_task(demo_task_path())
    if box != "task":
        task = replace(task, disturbance=box)
    cols = _cols(edit)
    rows = sorted({0, 1, 2, *range(9, 15), *range(19, 25), *range(29, 35), 50, 79, 80})
    jobs = _jobs(task, cols, rows, n_random=3)
    fast = plan_mode_checks(task, cols, jobs, margin)
    assert fast == _reference(task, cols, jobs, margin)
    found = {kind for more, _ in fast.values() for kind, _ in more}
    assert kinds <= found
    if box is BIG_BOX:  # a failure only some wrench vertex shows, named with it
        assert any("under the disturbance wrench" in msg for more, _ in fast.values() for _, msg in more)
    if edit is _stop:  # degenerate modes looked at again at machine precision and set aside
        assert any(excluded for _, excluded in fast.values())


def test_nearly_degenerate_modes_are_undecided_alike(monkeypatch):
    """Coarse tolerances in place of the default ones: many modes degenerate (nearly singular ``P_AI``), decided at
    machine precision: undecided, looked at again at the block's first such vector, as the reference caches it."""
    import qsplan.planner.certify.modes as modes
    from qsplan.mechanics import Tolerances

    monkeypatch.setattr(modes, "DEFAULT_TOLERANCES", Tolerances(singular=1e-3, velocity=1e-3))
    task = replace(load_task(demo_task_path()), disturbance=BIG_BOX)
    cols = _cols()
    jobs = _jobs(task, cols, [0, 5, 40, 80], n_random=4)
    fast = plan_mode_checks(task, cols, jobs, 0.0)
    assert fast == _reference(task, cols, jobs, 0.0)
    assert any("is nearly degenerate" in msg for more, _ in fast.values() for _, msg in more)


def test_singular_equilibria_are_looked_at_per_vector_alike(monkeypatch):
    """Planted scenes whose ``Q_AI`` is nearly singular at some friction vectors (coarse tolerances): the second look
    at each such vector (the reference's cache key is the vector itself), with and without a wrench box.  The second
    look made coarse too (singular 0.02, not machine precision), so that it still sees some of them singular at some
    vectors only: the answer depends on which vector each is looked at."""
    from types import SimpleNamespace

    import qsplan.planner.certify.modes as modes
    from qsplan.mechanics import Status, Tolerances, planted_scene, solve_many

    coarse = Tolerances(singular=0.05)
    monkeypatch.setattr(modes, "DEFAULT_TOLERANCES", coarse)
    monkeypatch.setattr(modes, "EXACT_TOLERANCES", Tolerances(singular=0.02))
    rng = np.random.default_rng(5)
    jobs, planned, singular = [], [], 0
    for k in range(10):
        scene, mode = planted_scene(rng, int(rng.integers(3, 6)), int(rng.integers(0, 2)))
        mus = rng.uniform(0.0, 1.2, (6, scene.n_contacts))
        jobs.append(ModeJob(k, scene, mus, np.nan))
        planned.append(getattr(mode, "letters", mode))
        singular += int((solve_many(scene, mus, coarse).codes == Status.ORDER.index(Status.EQUILIBRIUM_SINGULAR)).sum())
    assert singular > 0
    cols = {"mode": np.array(planned), "y_workpiece": np.zeros(len(jobs))}
    for box in (None, WrenchBox((-0.5, -0.5, -0.02), (0.5, 0.5, 0.02))):
        task = SimpleNamespace(disturbance=box)
        for margin in (0.0, 0.1):
            assert plan_mode_checks(task, cols, jobs, margin) == _reference(task, cols, jobs, margin)


def test_rows_in_several_calls_give_the_same_answers(monkeypatch):
    """A long plan's rows solved in several calls (FORCES_PER_CALL: memory), down to one row per call: same answers."""
    import qsplan.planner.certify.modes as modes

    task = replace(load_task(demo_task_path()), disturbance=BIG_BOX)
    cols = _cols(_far)
    jobs = _jobs(task, cols, range(15, 30), n_random=2)
    whole = plan_mode_checks(task, cols, jobs, 0.5)
    for limit in (60_000, 1):
        monkeypatch.setattr(modes, "FORCES_PER_CALL", limit)
        assert plan_mode_checks(task, cols, jobs, 0.5) == whole


def test_no_rows_no_checks():
    task = load_task(demo_task_path())
    assert plan_mode_checks(task, _cols(), [], 0.0) == {}


@pytest.mark.slow
@pytest.mark.ompl
def test_turning_plan_certificate_is_the_reference_one(bundled_plan):
    """A turning plan (slides of four contacts, the flush instant and the pivot of five and four, holds at rest): the
    plan at once gives the reference's certificate (every row, verdict, violation and set-aside mode)."""
    from qsplan.planner.certify.certify import certify_plan, read_plan, task_from_metadata

    out = bundled_plan("reorient_task")
    cols, meta = read_plan(out)
    task = task_from_metadata(meta, cols)
    kw = {"force_margin": task.force_margin.normal, "n_random": 2}
    fast, reference = certify_plan(out, task, **kw), certify_plan(out, task, batched=False, **kw)
    assert fast.rows == reference.rows and fast.violations == reference.violations and fast.counts == reference.counts
    assert fast.to_dict()["excluded_degenerate_modes"] == reference.to_dict()["excluded_degenerate_modes"]
    assert len({r.friction_points for r in fast.rows if r.mode != "free"}) >= 2  # four- and five-contact rows
