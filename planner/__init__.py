"""qsplan.planner: planning two-finger tasks through OMPL with guaranteed torque bands; torque commands, export, plots, the CLI.

Subpackages, in layers (lowest first; a module imports only its own layer and lower ones, above
:mod:`qsplan.mechanics` and :mod:`qsplan.hands`; ``tests/test_architecture.py`` asserts it):

* :mod:`.task` - the task: what a plan must achieve, its fields and ranges, goals, joint limits
* :mod:`.torque` - band sweeps along a segment and the torque command rule (Figs. 10-13)
* :mod:`.states` - judging configurations: in contact (with a guaranteed band) and in free space, collisions
* :mod:`.search` - band tables, the widest route, the OMPL adapter (the only package importing ``ompl``)
* :mod:`.plan` - typed plans, :func:`plan_task`, slides and regrasps realised, failure reports
* :mod:`.export` - plan files (CSV and JSON), their schema, safe writing
* :mod:`.certify` - the certifier of exported plans; :mod:`.replay` - their re-simulation
* :mod:`.plotting`, :mod:`.reports` - figures and renderings
* :mod:`.pipeline` - :func:`run_plan`, the whole run; :mod:`.cli` - the ``qsplan`` command

Public API (loaded on first use, so ``import qsplan.planner`` stays light):

* tasks: :class:`Task`, :func:`load_task`, :func:`make_task`, :func:`demo_task_path`, :func:`task_paths`
* planning (Section 5.2, Figs. 9-13): :func:`plan_task`, :class:`Plan`; its typed phases :class:`SlidePhase`,
  :class:`HoldPhase`, :class:`PivotPhase` (in contact: :class:`ContactSegmentPlan`) and :class:`RegraspPhase`
  (:class:`RegraspPlan`); :class:`PlannerOptions`, :data:`DEFAULT_OPTIONS`; judged states
  :func:`check_contact_state`, :func:`check_free_state`, :class:`StateCheck`
* the whole pipeline (plan, export, plots, re-simulation): :func:`run_plan`, :class:`PlanRun`
* automatic planning (a start and a :class:`Goal`, no waypoints; :func:`plan_task` dispatches to it):
  :func:`plan_automatic`, :func:`band_tables`, :class:`BandTables`, :func:`widest_route`,
  :func:`search_route`, :data:`SEQUENCE_PLANNERS`
* no plan: :class:`PlanFailure` (a :class:`NoAnswerError`) with its :class:`FailureReport`
* export: :func:`export_plan`, :func:`read_plan_csv`, :func:`export_schedule`, :func:`check_outputs`
* replay and verification: :func:`replay_plan`, :func:`friction_samples`, :class:`Replay`; in MuJoCo
  (``pip install '.[sim]'``): :func:`replay_mujoco`, :func:`scene_xml`
* controller-rate samples of a plan: ``plan.sample(times)``, or of a plan directory or file :func:`sample_plan`;
  :class:`PlanSamples`
* independent certification of an exported plan: :func:`certify_plan`, :class:`Certificate`
* torque bands along a segment and commands: :func:`segment_bands`, :func:`guaranteed_sweep`,
  :func:`point_band_sweep`, :func:`sampled_guaranteed_sweep`, :func:`choose_command`, :func:`sweep_segment`;
  for one scene, the guaranteed band with every competitor precluded: :func:`robust_band`
* plots: :func:`plan_figures`, :func:`plan_animation`, :func:`segment_band_figures`, :func:`plot_hand`, :func:`plot_mu_map`,
  :func:`rod_motion_figure`, :func:`push_motion_figure`, :func:`save_figure`, ...
* errors: :class:`QsplanError` (bad input, a ``ValueError``), :class:`NoAnswerError` (no answer exists)
"""

if __name__ != "qsplan.planner":  # the repository root on sys.path must not load a second copy
    raise ImportError(f"this folder installs as qsplan.planner; import qsplan.planner (after `pip install .`), not {__name__}")

from qsplan import lazy_attributes

#: Public name -> the module that defines it (imported on first attribute access).
_LAZY = {
    # errors
    "QsplanError": "qsplan.mechanics.errors",
    "NoAnswerError": "qsplan.mechanics.errors",
    # tasks
    "Task": "qsplan.planner.task.task",
    "load_task": "qsplan.planner.task.task",
    "make_task": "qsplan.planner.task.task",
    "demo_task_path": "qsplan.planner.task.task",
    "task_paths": "qsplan.planner.task.task",
    "task_path": "qsplan.planner.task.task",
    # planning
    "plan_task": "qsplan.planner.plan.scripted",
    "DEFAULT_OPTIONS": "qsplan.planner.plan.scripted",
    "REGRASP_OPENING": "qsplan.planner.plan.scripted",
    "SWEEP_STEP": "qsplan.planner.plan.scripted",
    "Plan": "qsplan.planner.plan.results",
    "ContactSegmentPlan": "qsplan.planner.plan.results",
    "RegraspPlan": "qsplan.planner.plan.results",
    "SlidePhase": "qsplan.planner.plan.results",
    "HoldPhase": "qsplan.planner.plan.results",
    "PivotPhase": "qsplan.planner.plan.results",
    "RegraspPhase": "qsplan.planner.plan.results",
    "PlanFailure": "qsplan.planner.plan.results",
    "StateCheck": "qsplan.planner.states.contact",
    "check_contact_state": "qsplan.planner.states.contact",
    "check_free_state": "qsplan.planner.states.contact",
    "contact_samples": "qsplan.planner.states.contact",
    "FailureReport": "qsplan.planner.plan.failure",
    "ClosedPoint": "qsplan.planner.plan.failure",
    "failure_report": "qsplan.planner.plan.failure",
    "PlannerOptions": "qsplan.planner.search.ompl_bridge",
    "PlanResult": "qsplan.planner.search.ompl_bridge",
    "PLANNERS": "qsplan.planner.search.ompl_bridge",
    "plan_path": "qsplan.planner.search.ompl_bridge",
    "ompl_available": "qsplan.planner.search.ompl_bridge",
    "Goal": "qsplan.planner.task.goal",
    # automatic planning: the sequence search (issue 14)
    "plan_automatic": "qsplan.planner.plan.autoplan",
    "SEQUENCE_PLANNERS": "qsplan.planner.search.ompl_search",
    "search_route": "qsplan.planner.search.ompl_search",
    "band_tables": "qsplan.planner.search.tables",
    "BandTables": "qsplan.planner.search.tables",
    "widest_route": "qsplan.planner.search.widest",
    "run_plan": "qsplan.planner.pipeline.run",
    "segment_command": "qsplan.planner.torque.command",
    "with_segment_command": "qsplan.planner.torque.command",
    "command_rule": "qsplan.planner.torque.command",
    "check_schedule_files": "qsplan.planner.export.schema",
    "PlanRun": "qsplan.planner.pipeline.run",
    "certify_plan": "qsplan.planner.certify.certify",
    "Certificate": "qsplan.planner.certify.certify",
    "Violation": "qsplan.planner.certify.certify",
    "plan_outputs": "qsplan.planner.pipeline.run",
    # replay and verification
    "replay_plan": "qsplan.planner.replay.replay",
    "replay_mujoco": "qsplan.planner.replay.mujoco_replay",
    "scene_xml": "qsplan.planner.replay.mujoco_scene",
    "sample_plan": "qsplan.planner.export.sample",
    "PlanSamples": "qsplan.planner.export.sample",
    "friction_samples": "qsplan.planner.replay.replay",
    "Replay": "qsplan.planner.replay.replay",
    "SegmentReplay": "qsplan.planner.replay.replay",
    # export
    "export_plan": "qsplan.planner.export.plan_files",
    "read_plan_csv": "qsplan.planner.export.plan_files",
    "plan_columns": "qsplan.planner.export.plan_files",
    "plan_metadata": "qsplan.planner.export.plan_files",
    "export_schedule": "qsplan.planner.export.schedule",
    "schedule_columns": "qsplan.planner.export.schedule",
    "schedule_metadata": "qsplan.planner.export.schedule",
    "check_outputs": "qsplan.planner.export.files",
    "OutputExistsError": "qsplan.planner.export.files",
    # torque bands and commands
    "robust_band": "qsplan.mechanics.bands.robust",
    "RobustBand": "qsplan.mechanics.bands.robust",
    "segment_bands": "qsplan.planner.torque.sweep",
    "SegmentBands": "qsplan.planner.torque.sweep",
    "paper_method_wider": "qsplan.planner.torque.sweep",
    "BandSweep": "qsplan.planner.torque.pointwise",
    "GuaranteedSweep": "qsplan.planner.torque.pointwise",
    "guaranteed_sweep": "qsplan.planner.torque.pointwise",
    "point_band_sweep": "qsplan.planner.torque.pointwise",
    "sampled_guaranteed_sweep": "qsplan.planner.torque.pointwise",
    "competing_modes": "qsplan.planner.torque.sweep",
    "narrowest": "qsplan.planner.torque.pointwise",
    "choose_command": "qsplan.planner.torque.command",
    "default_safety_margin": "qsplan.planner.torque.command",
    "sweep_segment": "qsplan.planner.reports.segment",
    "SweepRun": "qsplan.planner.reports.segment",
    "segment_document": "qsplan.planner.reports.segment",
    # reports
    "reproduce_paper": "qsplan.planner.reports.paper",
    "format_solve_result": "qsplan.planner.reports.solve_report",
    "solve_result_to_dict": "qsplan.planner.reports.solve_report",
    # plots (matplotlib is imported inside the functions)
    "plan_figures": "qsplan.planner.plotting.plan",
    "plan_animation": "qsplan.planner.plotting.animation",
    "plan_card": "qsplan.planner.plotting.card",
    "plot_plan_bands": "qsplan.planner.plotting.plan",
    "plot_mode_timeline": "qsplan.planner.plotting.plan",
    "plan_snapshots_figure": "qsplan.planner.plotting.plan",
    "segment_band_figures": "qsplan.planner.plotting.bands",
    "plot_band_sweep": "qsplan.planner.plotting.bands",
    "plot_guaranteed": "qsplan.planner.plotting.bands",
    "plot_speed_accuracy": "qsplan.planner.plotting.bands",
    "auto_display_limit": "qsplan.planner.plotting.bands",
    "plot_hand": "qsplan.planner.plotting.hands",
    "plot_hand_description": "qsplan.planner.plotting.hand_files",
    "hand_strip_figure": "qsplan.planner.plotting.hands",
    "plot_mu_map": "qsplan.planner.plotting.muspace",
    "mu_slices_figure": "qsplan.planner.plotting.muspace",
    "rod_mu_figure": "qsplan.planner.plotting.muspace",
    "plot_friction_rectangle": "qsplan.planner.plotting.muspace",
    "plot_contact_scene": "qsplan.planner.plotting.muspace",
    "rod_motion_figure": "qsplan.planner.plotting.motion",
    "push_motion_figure": "qsplan.planner.plotting.motion",
    "plot_rod_distances": "qsplan.planner.plotting.motion",
    "plot_rod_mu_space": "qsplan.planner.plotting.motion",
    "plot_push_snapshots": "qsplan.planner.plotting.motion",
    "new_axes": "qsplan.planner.plotting.style",
    "save_figure": "qsplan.planner.plotting.style",
}

__all__ = list(_LAZY)


__getattr__ = lazy_attributes(__name__, _LAZY, globals())


def __dir__():
    return sorted(set(globals()) | set(_LAZY))
