"""qsplan.planner: planning two-finger tasks through OMPL with guaranteed torque bands; torque commands, export, plots, the CLI."""

if __name__ != "qsplan.planner":  # the repository root on sys.path must not load a second copy
    raise ImportError(f"this folder installs as qsplan.planner; import qsplan.planner (after `pip install .`), not {__name__}")
