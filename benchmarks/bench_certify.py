"""The plan certifier, the re-simulation and the plots of ``qsplan demo`` (issue 13), timed apart.

Plans the demo task once (seeded, deterministic), exports it, then times, best of ``--repeat``
(the machine is shared: the best run is the least disturbed one):

* the certification (:func:`qsplan.planner.certify.certify.certify_plan`) with every friction
  vector of a row in one batch, and the per-vector reference (``batched=False``, one
  :func:`qsplan.mechanics.solve` per friction vector: the algorithm before issue 13), and
  whether their certificates are the same;
* the re-simulation at the demo's three friction vectors (:func:`qsplan.planner.replay.replay.replay_plan`)
  with the scenes shared between the three replays, and without;
* the plots (:func:`qsplan.planner.plotting.plan.plan_figures` and saving them), the first time
  in the process (imports included, as in the command) and again.

Run: ``python3 benchmarks/bench_certify.py [--repeat N]`` (default 3).
"""

import argparse
import tempfile
import time
from pathlib import Path

from qsplan.planner import export_plan, load_task, plan_task
from qsplan.planner.certify.certify import certify_plan
from qsplan.planner.export.plan_files import read_plan_csv
from qsplan.planner.replay.replay import friction_samples, replay_plan
from qsplan.planner.task.task import demo_task_path

#: Before issue 13's certifier and replay work (2-core machine shared with other jobs, one ``qsplan
#: demo`` run timed in-process, the code at the commit before it): certification 16.7 s, the three
#: replays 25.9 s, plots 2.2 s (their code is unchanged: the difference is the machine's load), the whole
#: command 51.9 s wall.
PREVIOUS = {"certify_s": 16.7, "replay_s": 25.9, "plots_s": 2.2}


def best(fn, repeat):
    """Smallest wall time (s) of ``fn()`` over ``repeat`` runs, and its last result."""
    times, out = [], None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return min(times), out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3, help="runs of each measure (best taken)")
    args = ap.parse_args(argv)
    task = load_task(demo_task_path())
    plan = plan_task(task)
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp)
        export_plan(plan, out)
        margin = task.force_margin.normal
        t_plots_first, figs = best(lambda: _plots(plan, out), 1)
        t_plots, _ = best(lambda: _plots(plan, out), args.repeat)
        t_fast, fast = best(lambda: certify_plan(out, task, force_margin=margin), args.repeat)
        t_ref, ref = best(lambda: certify_plan(out, task, force_margin=margin, batched=False), max(1, args.repeat // 2))
        same = fast.rows == ref.rows and fast.violations == ref.violations
        columns = read_plan_csv(out / "plan.csv")
        mus = friction_samples(task.mu_range, 3, 1, shared=task.shared_mu)

        def replays(shared):
            scenes = {}
            return [replay_plan(columns, task.hand, mu, scenes=scenes if shared else None) for mu in mus]

        t_shared, a = best(lambda: replays(True), args.repeat)
        t_alone, b = best(lambda: replays(False), args.repeat)
        same_replay = [r.as_dict() for r in a] == [r.as_dict() for r in b]
    print(f"demo plan: {len(fast.rows)} rows, {fast.contact_rows} in contact; {fast.summary()}")
    print(f"{'measure (best of ' + str(args.repeat) + ', s)':<44} {'now':>8} {'before':>8}")
    print(f"{'certification, friction vectors batched':<44} {t_fast:8.2f} {PREVIOUS['certify_s']:8.1f}")
    print(f"{'certification, one solve per vector (ref.)':<44} {t_ref:8.2f} {'':>8}  same certificate: {same}")
    print(f"{'re-simulation x3, scenes shared':<44} {t_shared:8.2f} {PREVIOUS['replay_s']:8.1f}")
    print(f"{'re-simulation x3, scenes per replay':<44} {t_alone:8.2f} {'':>8}  same replays: {same_replay}")
    print(f"{'plots, first in the process (imports)':<44} {t_plots_first:8.2f} {PREVIOUS['plots_s']:8.1f}")
    print(f"{'plots, again':<44} {t_plots:8.2f} {'':>8}  ({len(figs)} figures)")


def _plots(plan, out):
    from qsplan.planner.plotting.plan import plan_figures
    from qsplan.planner.plotting.style import save_figure

    figs = plan_figures(plan)
    for name, fig in figs.items():
        save_figure(fig, out / f"{name}.png")
    return figs


if __name__ == "__main__":
    main()
