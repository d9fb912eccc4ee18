"""The plan certifier, the re-simulation and the plots of ``qsplan demo`` (issues 13 and 33), timed apart; and the
whole ``qsplan verify`` command before and after a change, side by side.

Plans the demo task once (seeded, deterministic), exports it, then times, best of ``--repeat``
(the machine is shared: the best run is the least disturbed one):

* the certification (:func:`qsplan.planner.certify.certify.certify_plan`) with every row x wrench vertex x friction
  vector of the plan in one batch (:func:`qsplan.planner.certify.modes.plan_mode_checks`), and the reference
  (``batched=False``: row by row, wrench by wrench, one :func:`qsplan.mechanics.solve` per friction vector), and
  whether their certificates are the same;
* the re-simulation at the demo's three friction vectors (:func:`qsplan.planner.replay.replay.replay_plan`)
  with the scenes shared between the three replays, and without;
* the plots (:func:`qsplan.planner.plotting.plan.plan_figures` and saving them), the first time
  in the process (imports included, as in the command) and again.

With ``--compare REV`` (a git revision of this repository: its tree is extracted to a temporary folder and imported
in place of the installed one, with this interpreter and its packages) or ``--baseline PYTHON`` (another
installation's interpreter), the whole commands of the table below are timed as subprocesses, before and after
interleaved run by run (the machine's speed drifts between minutes), best of ``--repeat`` each, and printed as a
table: command, before s, after s, ratio.  By default the processes run with the environment as it is (here
``PYTHONDONTWRITEBYTECODE=1``: every module compiled at every start); ``--bytecode`` lets both sides cache their
compiled modules (in temporary folders, one warm-up run each), as an ordinary installation does.

``--after REV`` puts a revision on the after side too (default: this tree, with its uncommitted changes).

Run: ``python3 benchmarks/bench_certify.py [--repeat N] [--compare REV | --baseline PYTHON] [--after REV]
[--bytecode] [--no-inprocess]`` (default 3 runs).
"""

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from revisions import export_revision


#: Before issue 13's certifier and replay work (2-core machine shared with other jobs, one ``qsplan
#: demo`` run timed in-process, the code at the commit before it): certification 16.7 s, the three
#: replays 25.9 s, plots 2.2 s (their code is unchanged: the difference is the machine's load), the whole
#: command 51.9 s wall.
PREVIOUS = {"certify_s": 16.7, "replay_s": 25.9, "plots_s": 2.2}

#: The whole commands compared (``{plan}``: the demo's plan, exported once by this tree).
COMMANDS = (("qsplan verify DEMO", ["verify", "{plan}"]),
            ("qsplan verify DEMO --json", ["verify", "{plan}", "--json"]),
            ("qsplan verify DEMO --random 32", ["verify", "{plan}", "--random", "32"]))  # fmt: skip


def best(fn, repeat):
    """Smallest wall time (s) of ``fn()`` over ``repeat`` runs, and its last result."""
    times, out = [], None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return min(times), out


def inprocess(repeat):
    """The in-process table (certification batched and reference, replays, plots)."""
    from qsplan.planner import export_plan, load_task, plan_task
    from qsplan.planner.certify.certify import certify_plan
    from qsplan.planner.export.plan_files import read_plan_csv
    from qsplan.planner.replay.replay import friction_samples, replay_plan
    from qsplan.planner.task.task import demo_task_path

    task = load_task(demo_task_path())
    plan = plan_task(task)
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp)
        export_plan(plan, out)
        margin = task.force_margin.normal
        t_plots_first, figs = best(lambda: _plots(plan, out), 1)
        t_plots, _ = best(lambda: _plots(plan, out), repeat)
        t_fast, fast = best(lambda: certify_plan(out, task, force_margin=margin), repeat)
        t_ref, ref = best(lambda: certify_plan(out, task, force_margin=margin, batched=False), max(1, repeat // 2))
        same = fast.rows == ref.rows and fast.violations == ref.violations and fast.counts == ref.counts
        columns = read_plan_csv(out / "plan.csv")
        mus = friction_samples(task.mu_range, 3, 1, shared=task.shared_mu)

        def replays(shared):
            scenes = {}
            return [replay_plan(columns, task.hand, mu, scenes=scenes if shared else None) for mu in mus]

        t_shared, a = best(lambda: replays(True), repeat)
        t_alone, b = best(lambda: replays(False), repeat)
        same_replay = [r.as_dict() for r in a] == [r.as_dict() for r in b]
    print(f"demo plan: {len(fast.rows)} rows, {fast.contact_rows} in contact; {fast.summary()}")
    print(f"{'measure (best of ' + str(repeat) + ', s)':<46} {'now':>8} {'issue 13':>8}")
    print(f"{'certification, the plan in one batch':<46} {t_fast:8.3f} {PREVIOUS['certify_s']:8.1f}")
    print(f"{'certification, reference (row by row, per mu)':<46} {t_ref:8.3f} {'':>8}  same certificate: {same}")
    print(f"{'re-simulation x3, scenes shared':<46} {t_shared:8.2f} {PREVIOUS['replay_s']:8.1f}")
    print(f"{'re-simulation x3, scenes per replay':<46} {t_alone:8.2f} {'':>8}  same replays: {same_replay}")
    print(f"{'plots, first in the process (imports)':<46} {t_plots_first:8.2f} {PREVIOUS['plots_s']:8.1f}")
    print(f"{'plots, again':<46} {t_plots:8.2f} {'':>8}  ({len(figs)} figures)")


def _plots(plan, out):
    from qsplan.planner.plotting.plan import plan_figures
    from qsplan.planner.plotting.style import save_figure

    figs = plan_figures(plan)
    for name, fig in figs.items():
        save_figure(fig, out / f"{name}.png")
    return figs


def whole_commands(repeat, before, after, bytecode, work: Path):
    """``[(label, before s, after s)]``: each command's best of ``repeat`` runs, before and after interleaved.
    ``before``, ``after``: ``(python, extra environment)``."""
    plan = work / "demo"
    sides = []
    for i, (python, env) in enumerate((before, after)):
        e = dict(os.environ, **env)
        if bytecode:
            e.pop("PYTHONDONTWRITEBYTECODE", None)
            e["PYTHONPYCACHEPREFIX"] = str(work / f"pycache{i}")
        sides.append((python, e))
    run = lambda side, args: subprocess.run([side[0], "-m", "qsplan.planner.cli", *args], env=side[1],  # noqa: E731
                                           capture_output=True, text=True, cwd=work)  # fmt: skip
    made = run(sides[1], ["demo", "--out", str(plan), "--no-plots"])
    if made.returncode != 0:
        raise SystemExit(f"qsplan demo failed (after):\n{made.stderr}")
    rows = []
    for label, args in COMMANDS:
        args = [a.format(plan=plan) for a in args]
        codes = []
        for side in sides:  # one warm-up each: compiled modules cached (--bytecode), files in the page cache
            codes.append(run(side, args).returncode)
        times = ([], [])
        for _ in range(repeat):
            for s, side in enumerate(sides):
                t0 = time.perf_counter()
                run(side, args)
                times[s].append(time.perf_counter() - t0)
        rows.append((label, min(times[0]), min(times[1]), codes))
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3, help="runs of each measure (best taken)")
    which = ap.add_mutually_exclusive_group()
    which.add_argument("--compare", metavar="REV", help="time the whole commands at this git revision too (before)")
    which.add_argument("--baseline", metavar="PYTHON", help="another installation's interpreter (before)")
    ap.add_argument("--after", metavar="REV", help="the after side at this git revision too (default: this tree, "
                                                   "uncommitted changes included)")
    ap.add_argument("--bytecode", action="store_true", help="let both sides cache their compiled modules")
    ap.add_argument("--no-inprocess", action="store_true", help="only the whole commands")
    args = ap.parse_args(argv)
    if not args.no_inprocess:
        inprocess(args.repeat)
    if args.compare is None and args.baseline is None:
        return
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        if args.compare is not None:
            (work / "before").mkdir()
            before = (sys.executable, {"PYTHONPATH": str(export_revision(args.compare, work / "before"))})
            said = f"git {args.compare}"
        else:
            before, said = (args.baseline, {}), args.baseline
        after, now = (sys.executable, {}), "this tree"
        if args.after is not None:
            (work / "after").mkdir()
            after, now = (sys.executable, {"PYTHONPATH": str(export_revision(args.after, work / "after"))}), f"git {args.after}"
        rows = whole_commands(args.repeat, before, after, args.bytecode, work)
    print(f"\nwhole commands, best of {args.repeat} (interleaved), before = {said}, after = {now}"
          f"{', bytecode cached' if args.bytecode else ', as the environment runs them'}")  # fmt: skip
    print(f"{'command':<36} {'before s':>9} {'after s':>9} {'ratio':>7}  exit codes")
    for label, a, b, codes in rows:
        print(f"{label:<36} {a:9.3f} {b:9.3f} {a / b:7.2f}  {codes[0]} / {codes[1]}")


if __name__ == "__main__":
    main()
