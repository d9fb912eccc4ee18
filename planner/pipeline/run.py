"""The planning pipeline in one call: plan a task, export it, draw it, re-simulate the exported file.

:func:`run_plan` is what ``qsplan plan`` and ``qsplan demo`` run, and what a planning
script calls.  It holds its directory for the whole run
(:func:`qsplan.planner.export.files.locked_out_dir`: a second run into it fails at once), checks
its outputs before planning (nothing is overwritten without ``force``, never an input), plans
(:func:`qsplan.planner.plan.scripted.plan_task`, which first refuses a task whose start or goal puts the
workpiece beyond the palm: :func:`qsplan.planner.plan.failure.palm_report`), and writes into a private staging directory
inside DIR (:func:`qsplan.planner.export.files.staging_dir`) ``plan.csv`` and ``plan.json``
(:func:`qsplan.planner.export.plan_files.export_plan`), ``certificate.json``: the exported file
certified row by row from the task alone (:func:`qsplan.planner.certify.certify.certify_plan`),
``replay.json``: the exported file re-simulated (:func:`qsplan.planner.replay.replay.replay_plan`)
at ``verify`` friction vectors of the interval, ``scene.xml`` (the task's scene for MuJoCo), and the plots: by
default the plan card (:func:`qsplan.planner.plotting.card.plan_card`), with ``plots="all"`` the other plots and the
animation too (``plan_animation.gif`` and ``.html``), drawn meanwhile in a second process that also re-simulates
the plan when it is free first (:class:`qsplan.planner.pipeline.worker.Worker`: a figure it could not draw is said, in
:attr:`PlanRun.undrawn`, and the certified plan published without it; a failure: ``failure.png``, drawn here).
Only then are the files published into DIR,
by renames, the plan files last (:func:`qsplan.planner.export.manifest.publish_outputs`): a plan
file never appears in DIR before it is certified, and a run interrupted at any point (Ctrl-C
while certifying included) leaves no plan of its own there.  Outputs are recorded in
``.qsplan-outputs.json``, so a second run into the same directory replaces them (and only them)
without ``force``.  A plan that fails its certificate is not published: ``certificate.json`` and
``failure.json`` (naming the rows and reasons) are, and
:class:`~qsplan.planner.plan.results.PlanFailure` is raised.  When no plan exists it publishes
``failure.json`` (the report of where the band closes, which mode closes it, at which friction; or
which position is beyond the palm) and raises :class:`qsplan.planner.plan.results.PlanFailure`.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from qsplan.mechanics.errors import QsplanError

from qsplan.planner.export.files import (atomic_write, check_out_dir, check_output_path, check_outputs, locked_out_dir,
                                         staging_dir)  # fmt: skip
from qsplan.planner.export.manifest import MANIFEST, own_outputs, publish_outputs
from qsplan.planner.pipeline.worker import ANIMATION_FILES, PLAN_PLOTS, Worker, plot_choice, plot_files
from qsplan.planner.plan.failure import GoalReport
from qsplan.planner.plan.results import Plan, PlanFailure
from qsplan.planner.plan.scripted import DEFAULT_OPTIONS, plan_task
from qsplan.planner.task.goal import GoalNotServedError

__all__ = ["ANIMATION_FILES", "FAILURE_FILES", "PLAN_FILES", "PLAN_PLOTS", "CertificationReport", "PlanRun", "plan_outputs",
           "run_plan"]

#: Files :func:`run_plan` writes into its directory (``replay.json`` only when ``verify`` > 0; ``scene.xml``: the
#: task's scene for MuJoCo).
PLAN_FILES = ("plan.csv", "plan.json", "certificate.json", "replay.json", "scene.xml")

#: What a run that finds no plan writes (``failure.png``, the failed configuration drawn, only with the plots).
FAILURE_FILES = ("failure.json", "failure.png")

#: The plan itself: published last, so that where it is, its certificate and every other output of its run are.
PLAN_DATA = ("plan.csv", "plan.json")


#: ``planner_status`` of a plan refused by its certificate: planned and exported, then refused.
CERTIFICATE_REFUSED = "ran: planned and exported; the independent certificate refused the plan"


@dataclass(frozen=True, slots=True, eq=False)
class CertificationReport:
    """Why a plan the planner produced is not presented: its independent certificate failed.

    Attributes
    ----------
    certificate : qsplan.planner.certify.certify.Certificate
    """

    certificate: object

    @property
    def message(self) -> str:
        first = self.certificate.violations[0] if self.certificate.violations else None
        return (f"no plan: the planned motion failed its independent certification ({self.certificate.summary()})"
                + (f"; first: {first}" if first else ""))  # fmt: skip

    def as_dict(self) -> dict:
        return {"kind": "certification", "planner_status": CERTIFICATE_REFUSED, "message": self.message,
                "certificate": self.certificate.to_dict()}  # fmt: skip


@dataclass(frozen=True, slots=True, eq=False)
class PlanRun:
    """What :func:`run_plan` did.

    Attributes
    ----------
    plan : Plan
    out_dir : pathlib.Path
    files : tuple of str
        Files written, in order.
    replays : tuple of qsplan.planner.replay.replay.Replay
        The exported plan re-simulated, one per friction vector.
    certificate : qsplan.planner.certify.certify.Certificate
        The exported plan checked row by row from the task alone (always certified: a plan
        that is not is never returned).
    undrawn : tuple of (str, str)
        Each plot asked for but not drawn (an error while drawing it), with the reason; the plan and every other
        output published all the same.
    """

    plan: Plan
    out_dir: Path
    files: tuple
    replays: tuple
    certificate: object = None
    undrawn: tuple = ()

    @property
    def followed(self) -> bool:
        """Every re-simulation followed the planned modes (True when none was run)."""
        return all(r.followed for r in self.replays)


def plan_outputs(out_dir, plots=True) -> list:
    """The paths :func:`run_plan` may write into ``out_dir`` (checked before planning) with ``plots`` (as there;
    True: every plot)."""
    out = Path(out_dir)
    return [out / f for f in PLAN_FILES] + [out / f for f in plot_files(plots)]


def run_plan(task, out_dir, *, seed: int = 1, planner: str = "RRTConnect", time_limit: float | None = None,
             verify: int = 3, force: bool = False, plots="card", progress=None,
             sequence_planner: str = "widest", inputs=()) -> PlanRun:  # fmt: skip
    """Plan ``task``, export it into ``out_dir``, draw it and re-simulate the exported file.

    Parameters
    ----------
    task : qsplan.planner.task.task.Task
    out_dir : str or pathlib.Path
        Created if missing; held by this run alone while it runs.
    seed : int
        OMPL's random seed.
    planner : str
        OMPL planner of the regrasps, one of :data:`qsplan.planner.search.ompl_bridge.PLANNERS`.
    sequence_planner : str
        A task with a ``goal``: the sequence search (:data:`qsplan.planner.search.ompl_search.SEQUENCE_PLANNERS`).
    time_limit : float, optional
        Seconds per OMPL query; default that of :data:`qsplan.planner.plan.scripted.DEFAULT_OPTIONS`.
    verify : int
        Friction vectors to re-simulate the exported plan at (the two uniform extremes, then seeded
        random ones: :func:`qsplan.planner.replay.replay.friction_samples`); 0 skips.
    force : bool
        Replace existing outputs; an earlier run's outputs (``failure.json`` included) are removed when this
        run publishes, so the directory never mixes two runs.  Without it, outputs an earlier run wrote and
        nobody changed since (recorded in ``.qsplan-outputs.json``: :mod:`qsplan.planner.export.manifest`)
        are replaced all the same, and any other existing output is refused.
    plots : {"card", "all", "none"} or bool
        ``"card"`` (default): draw ``plan_card.png`` (:func:`qsplan.planner.plotting.card.plan_card`); ``"all"`` (or
        True): also ``plan_bands.png``, ``mode_timeline.png``, ``hand_snapshots.png`` and the animation
        (:data:`ANIMATION_FILES`); ``"none"`` (or False): no plot.  Drawn in a second process while the plan is
        certified (:class:`qsplan.planner.pipeline.worker.Worker`).
    progress : callable, optional
        ``progress(line)`` for progress messages.
    inputs : sequence of paths
        Files this run reads (the task file): never replaced or removed, ``force`` or not.

    Returns
    -------
    PlanRun
        Check :attr:`PlanRun.followed`: False when a re-simulation left the planned modes; and
        :attr:`PlanRun.undrawn`: the plots that could not be drawn.

    Raises
    ------
    QsplanError
        Bad arguments, or an output exists and ``force`` is False (before anything is planned or written).
    qsplan.planner.export.files.OutDirLockedError
        Another run is writing into ``out_dir`` (nothing done).
    PlanFailure
        No plan exists; ``failure.json`` in ``out_dir`` holds the report (``report_path``).
    """
    if isinstance(verify, bool) or int(verify) != verify or verify < 0:
        raise QsplanError(f"verify: expected a nonnegative number of friction vectors; got {verify}")
    limit = DEFAULT_OPTIONS.time_limit if time_limit is None else time_limit
    if not (limit > 0 and limit < float("inf")):
        raise QsplanError(f"time_limit: expected a positive number of seconds; got {time_limit}")
    progress = progress or (lambda line: None)
    options = replace(DEFAULT_OPTIONS, seed=seed, planner=planner, time_limit=limit)
    which = plot_choice(plots)
    draws = which != "none"
    out = check_out_dir(out_dir)
    # the second process first: it imports matplotlib while the plan is searched, and holds no descriptor of the lock
    with Worker(which) as worker, locked_out_dir(out, inputs) as out, staging_dir(out) as stage:
        try:
            _check_outputs(out, which, force, inputs)  # before planning: nothing is planned that cannot be written

            def publish(names):  # checked again: the directory is ours, but a user may have written into it since
                return publish_outputs(out, stage, names, _check_outputs(out, which, force, inputs), last=PLAN_DATA)

            what = f"goal {task.goal.describe()}" if task.goal is not None else f"{len(task.waypoints)} in-contact segments"
            progress(f"task {task.name!r}: {what}, mu in {list(task.mu_range)}, "
                     f"torque resolution {task.torque_resolution:g} N m")  # fmt: skip
            try:
                plan = plan_task(task, options, progress, sequence_planner=sequence_planner)
            except (PlanFailure, GoalNotServedError) as exc:  # every failure writes its report (and draws it)
                worker.stop()
                report = exc.report if isinstance(exc, PlanFailure) else GoalReport.from_error(exc)
                raise PlanFailure(report, report_path=publish(_failure_files(task, report, stage, draws))[0]) from None
            from qsplan.planner.export.plan_files import export_plan

            staged = [p.name for p in export_plan(plan, stage, force=True)]
            worker.start(plan, stage, int(verify), seed)  # meanwhile: everything but the card's verdict line
            if draws:
                progress(f"drawing {'the plan card' if which == 'card' else 'the plots and the animation'} "
                         f"{'in a second process, meanwhile' if worker.in_parallel else 'once certified'}")
            certificate = _certify(plan, out, stage, progress)
            staged.append("certificate.json")
            if not certificate.ok:  # never published where it looks like a plan
                worker.stop()
                report = CertificationReport(certificate)
                names = ["certificate.json", *_failure_files(task, report, stage, draws)]
                raise PlanFailure(report, report_path=publish(names)[1])
            replays = worker.replays(progress)
            if replays:
                atomic_write(stage / "replay.json", json.dumps([r.as_dict() for r in replays], indent=1))
                staged.append("replay.json")
            staged.append(_scene(plan, stage))
            undrawn = []
            if draws:  # the plan card states the verdict
                drawn, undrawn = _draw(worker, certificate, replays, progress)
                staged += drawn
            files = publish(staged)
        finally:
            worker.stop()  # before the staging directory is removed: nothing writes into it any more
    return PlanRun(plan, out, tuple(str(p) for p in files), tuple(replays), certificate, tuple(undrawn))


def _failure_files(task, report, stage, plots: bool) -> list:
    """Write ``failure.json`` (the report) and, with the plots, ``failure.png`` (the failed configuration drawn:
    :func:`qsplan.planner.plotting.failure.failure_figure`) into ``stage``; their names, the report first."""
    atomic_write(stage / "failure.json", json.dumps(report.as_dict(), indent=1))
    if not plots:
        return ["failure.json"]
    from qsplan.planner.plotting.failure import failure_figure

    failure_figure(task, report, stage / "failure.png")
    return ["failure.json", "failure.png"]


def _scene(plan, stage) -> str:
    """``scene.xml``: the task's scene for MuJoCo (:func:`qsplan.planner.replay.mujoco_scene.scene_xml`), its keyframe
    the plan's first row; needs no MuJoCo to write (``qsplan replay DIR --engine mujoco`` runs it)."""
    from qsplan.planner.replay.mujoco_scene import write_scene

    first = plan.phases[0]  # the plan's first row: the keyframe
    start = (first.poses(plan.task.hand.rest_height)[0], np.asarray(first.q[0], dtype=float))
    write_scene(plan.task, stage / "scene.xml", start=start, force=True)
    return "scene.xml"


def _check_outputs(out, plots, force, inputs) -> list:
    """Check this run's outputs in ``out``; returns the names of the earlier run's outputs to remove on publishing.

    Never an input, force or not (nor a file this run would remove); never through a link; an existing output is
    replaced only with ``force`` or when an earlier run wrote it and nobody changed it since (the manifest).
    """
    names = [p.name for p in plan_outputs(out, True)] + list(FAILURE_FILES)
    check_output_path(out / MANIFEST, inputs)  # the record of what qsplan wrote: never through a link
    for p in (out / n for n in names):  # a file this run may remove (an earlier run's plot, with --no-plots)
        if p.is_file() and not p.is_symlink():
            check_output_path(p, inputs)
    own = own_outputs(out)  # written by an earlier run and unchanged since: replaced without force
    check_outputs([p for p in plan_outputs(out, plots) if p.name not in own], force, inputs)
    for name in FAILURE_FILES:
        if name not in own:
            check_outputs([out / name], force, inputs)  # an earlier run's report is an output too
    # no output of an earlier run stays beside this run's (a failure, --no-plots)
    return names if force else [n for n in names if n in own]


def _draw(worker, certificate, replays, progress) -> tuple:
    """The plots drawn (:meth:`qsplan.planner.pipeline.worker.Worker.finish`), the plan card with the verdict of
    ``certificate`` and ``replays``: ``(file names, undrawn)``, each plot not drawn said in a progress line."""
    progress("finishing the plots")
    drawn, undrawn = worker.finish(certificate, [r.followed for r in replays])
    for name, why in undrawn:
        progress(f"{name} not drawn ({why}); the certified plan is published without it")
    return drawn, undrawn


def _certify(plan, out, stage, progress):
    """Certify the staged ``plan.csv``; write ``certificate.json`` beside it, naming the file as published in ``out``."""
    from qsplan.planner.certify.certify import certify_plan

    progress("certifying the exported plan row by row from the task alone")
    certificate = certify_plan(stage / "plan.csv", plan.task, force_margin=plan.task.force_margin.normal)
    source = Path(certificate.source)
    if source == stage or stage in source.parents:  # what is certified is what is published: renamed, not rewritten
        certificate = replace(certificate, source=str(out / source.relative_to(stage)))
    atomic_write(stage / "certificate.json", json.dumps(certificate.to_dict(), indent=1))
    progress(certificate.summary())
    return certificate
