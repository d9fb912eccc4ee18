"""``qsplan check TASK [--out DIR] [--force] [--json]``: a task's feasibility preview, in seconds, before planning.

::

    qsplan check TASK.toml|BUNDLED_TASK [--out DIR] [--force] [--json]

Reads the task as ``qsplan plan`` does (a file, or a bundled task's name) and prints
(:func:`qsplan.planner.reports.preview.preview_task`): the start and the goal closed (the grasp, or what is
wrong: the overlapping bodies and by how much, the joints beyond their limits and by how much, the fingers
that do not close onto the features); for each grasp the hand offers, the workpiece x ranges where it is a
valid configuration and where a guaranteed band at least the torque resolution wide exists, sliding each way;
and a verdict line: a banded route from the start to the goal (the planner's own search), or what blocks it.
A goal that turns the workpiece (``[goal] theta`` or ``palm``) is not previewed: the goal's line says so, and
the route's first step, the slide to the flush instant, is previewed in its place (its end drawn and judged as
a goal), or the route's refusal is named.
``--json``: one JSON document instead.  With ``--out DIR``: ``check.png`` (the start and the goal, collisions
in red, and one bar per grasp over x) and ``check.json``; an existing file is replaced only with ``--force``.

Exit 0 whether or not a route exists (the preview is the answer); 2 for bad input (one line on stderr).
Nothing heavy is imported until :func:`run`.
"""

from __future__ import annotations

__all__ = ["OUTPUTS", "add_parser", "run"]

#: The files ``--out DIR`` writes.
OUTPUTS = ("check.png", "check.json")


def add_parser(subparsers):
    c = subparsers.add_parser("check", help="a task's feasibility preview: start and goal, where each grasp is valid "
                                            "and banded, whether a route exists (seconds, no planning)")  # fmt: skip
    c.add_argument("task", help="task file (.toml), or a bundled task's name (demo_task, two_link_task, ...)")
    c.add_argument("--out", metavar="DIR", help="write check.png and check.json into DIR")
    c.add_argument("--force", action="store_true", help="replace existing check.png / check.json in DIR")
    c.add_argument("--json", action="store_true", help="print one JSON document instead of the table")
    return c


def _ranges(ranges) -> str:
    return ", ".join(f"[{a:.4g}, {b:.4g}]" for a, b in ranges) or "nowhere"


def _table(preview) -> str:
    """The preview as text: the task, start and goal, one block per grasp, the verdict."""
    d = preview.as_dict()
    grid = d["grid"]
    n = len(preview.grasps)
    lines = [f"task {preview.task!r} ({preview.hand}): {n} grasp{'s' if n > 1 else ''} judged at {grid['points']} "
             f"workpiece x from {grid['x_from_m']:.4g} to {grid['x_to_m']:.4g} m (step {grid['step_m'] * 1e3:.3g} mm) "
             f"in {preview.seconds:.2f} s",
             f"banded: {d['banded_means']}", preview.start.message, preview.goal.message]
    if preview.slide_end is not None:  # a turning goal: its route's first step, previewed
        lines.append(preview.slide_end.message)
    lines.append("grasps (x ranges in m):")
    width = max(len(b.name) for b in preview.grasps)
    for b, g in zip(preview.grasps, d["grasps"]):
        pad = " " * (width + 4)
        lines += [f"  {b.name.ljust(width)}  {b.label}",
                  f"{pad}valid:                 {_ranges(g['valid_x_m'])}",
                  f"{pad}banded, sliding left:  {_ranges(g['banded_x_m']['sliding_left'])}",
                  f"{pad}banded, sliding right: {_ranges(g['banded_x_m']['sliding_right'])}"]  # fmt: skip
    lines.append(f"verdict: {preview.verdict}")
    return "\n".join(lines) + "\n"


def run(args, out) -> int:
    import json
    from pathlib import Path

    from qsplan.planner.task.task import load_task, task_path

    path = task_path(args.task)
    files = []
    if args.out is not None:  # the outputs checked before any work
        from qsplan.planner.export.files import check_out_dir, check_outputs

        files = [check_out_dir(args.out) / name for name in OUTPUTS]
        check_outputs(files, force=args.force, inputs=(path,))
    task = load_task(path)
    from qsplan.planner.reports.preview import preview_task

    preview = preview_task(task)
    document = json.dumps(preview.as_dict(), indent=1)
    out.write(document + "\n" if args.json else _table(preview))
    if files:
        from qsplan.planner.export.files import atomic_write
        from qsplan.planner.plotting.preview import preview_figure
        from qsplan.planner.plotting.style import save_figure

        # constrained layout sizes the page itself: no tight crop (it would draw the figure twice)
        save_figure(preview_figure(task, preview), files[0], option="out_dir", inputs=(path,), tight=False)
        atomic_write(files[1], document + "\n", inputs=(path,))
        if not args.json:
            out.write("".join(f"wrote {Path(f)}\n" for f in files))
    return 0
