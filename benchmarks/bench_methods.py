"""Benchmark: speed against accuracy of the two methods, n_c = 3..20 (issue 7; Table 1, Section 4.7).

Methods: ``enumerate`` (:func:`qsplan.mechanics.solve`, every feasible mode, eq. (49) modes tested)
and ``lcp`` (:func:`qsplan.mechanics.crosscheck.lcp.solve_lcp`, one mode by Lemke's method, verified by
``check_mode``).  For each ``n_c`` the scenes are seeded planted scenes
(:func:`qsplan.mechanics.planted_scene`) with ``|tau_I| = n_c - 3`` effort-controlled joints of
``n_c - 1``, so at least one mode (the planted one) is feasible in every scene.

Printed tables:

1. time against n_c: best-of-``--repeat`` wall clock per scene for each method, on the
   first seed; ``enumerate`` (the pruned exact search above 20,000 modes) is not run where
   the time extrapolated from the previous n_c (last time times its last growth factor)
   exceeds ``--cap`` seconds (marked ``not run``, with the estimate);
2. LCP accuracy over ``--seeds`` scenes per n_c: how often it returns a verified mode, how
   often that mode is in the enumerated full set (where the first seed's enumeration took
   at most ``--stats-cap`` seconds), how often it is the planted mode, how often the full
   set has several modes and the LCP's is the first in the paper's order, and how often it
   reports none though modes exist (every failure here: planted scenes always have one), by
   status;
3. the paper's Table 1 (RS6000/320 cpu seconds, n_c = 3 + |tau_I| = 3..8, 12; and the
   bilinear-programming "several cpu seconds" at 20) extended with our times.

Charts (``benchmarks/charts/``): ``speed_accuracy.png`` (time against n_c for both methods
and the paper's, and the LCP's success rate against n_c).

Usage, from the repository root::

    PYTHONPATH=. python3 benchmarks/bench_methods.py [--max-contacts 20] [--seeds 20] [--repeat 3] [--cap 30]
"""

import argparse
import time
from collections import Counter
from pathlib import Path

import numpy as np

from qsplan.mechanics.modes.contact_mode import random_mode
from qsplan.mechanics import count_modes, planted_scene, solve
from qsplan.mechanics.crosscheck.lcp import solve_lcp

SEED = 1995
CHARTS = Path(__file__).resolve().parent / "charts"

#: Table 1 (cpu seconds, RS6000/320) for n_c = 3 + |tau_I|, the text's 20 cpu minutes at 12,
#: and Section 4.7's "several cpu seconds" of the bilinear program at 20 (plotted as 5 s).
PAPER_ENUM_SECONDS = {3: 0.3, 4: 0.4, 5: 0.75, 6: 2.0, 7: 5.4, 8: 15.0, 12: 1200.0}
PAPER_BILINEAR_SECONDS = {20: 5.0}


def bench_scene(n_c: int, seed: int):
    """Seeded planted scene with ``3 + |tau_I| = n_c``."""
    rng = np.random.default_rng([SEED, seed, n_c])
    return planted_scene(rng, n_c, n_effort=n_c - 3, n_joints=n_c - 1, mode=random_mode(rng, n_c, n_c))


def best_time(fn, repeat: int):
    best, out = float("inf"), None
    for _ in range(repeat):
        t = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t)
    return best, out


def run(max_contacts: int, seeds: int, repeat: int, cap: float, stats_cap: float):
    rows = []
    times = []  # enumeration times of the previous n_c (s)
    for n_c in range(3, max_contacts + 1):
        total = count_modes(n_c, n_c)
        scene, planted = bench_scene(n_c, 0)
        # the pruned search does not scale with eq. (49): extrapolate by the last growth factor (at least 1)
        est = times[-1] * max(times[-1] / times[-2], 1.0) if len(times) >= 2 else 0.0
        if est <= cap:
            t_enum, res = best_time(lambda: solve(scene), repeat if est < 1.0 else 1)
            times.append(t_enum)
            assert planted.letters in res.feasible_modes
        else:
            t_enum = None
        t_lcp, _ = best_time(lambda: solve_lcp(scene), repeat)
        stats = Counter()
        for s in range(seeds):
            sc, pl = bench_scene(n_c, s)
            r = solve_lcp(sc)
            stats["scenes"] += 1
            stats[f"status: {r.status}"] += 1
            if not r.solved:
                stats["none though modes exist"] += 1
                continue
            stats["solved"] += 1
            stats["planted"] += r.mode.letters == pl.letters
            if t_enum is not None and t_enum <= stats_cap:
                full = solve(sc).feasible_modes
                stats["checked"] += 1
                stats["in full set"] += r.mode.letters in full
                if len(full) > 1:
                    stats["several"] += 1
                    stats["first of several"] += r.mode.letters == full[0]
        rows.append(dict(n_c=n_c, modes=total, t_enum=t_enum, est=est, t_lcp=t_lcp, stats=stats))
        enum_txt = f"{t_enum:10.4f}" if t_enum is not None else f"not run (est. {est:.3g} s)"
        print(f"n_c={n_c:2d} modes={total:>11d} enumerate {enum_txt}  lcp {t_lcp:.4f} s  "
              f"lcp solved {stats['solved']}/{stats['scenes']}", flush=True)  # fmt: skip
    return rows


def print_tables(rows):
    print("\nTime against n_c (s, best of repeats, seed 0; dof = n_c)")
    print(f"{'n_c':>4} {'modes (49)':>12} {'enumerate':>22} {'lcp':>9} {'speed-up':>9}")
    for r in rows:
        e = f"{r['t_enum']:.4f}" if r["t_enum"] is not None else f"not run (~{r['est']:.2g})"
        sp = f"{r['t_enum'] / r['t_lcp']:.1f}" if r["t_enum"] is not None else "-"
        print(f"{r['n_c']:>4} {r['modes']:>12} {e:>22} {r['t_lcp']:>9.4f} {sp:>9}")

    print("\nLCP accuracy over seeded planted scenes (every scene has at least one feasible mode)")
    print(f"{'n_c':>4} {'scenes':>6} {'solved':>7} {'in full set':>12} {'planted':>8} {'first of several':>17} "
          f"{'none though modes exist (by status)'}")  # fmt: skip
    for r in rows:
        s = r["stats"]
        chk = f"{s['in full set']}/{s['checked']}" if s["checked"] else "not checked"
        sev = f"{s['first of several']}/{s['several']}" if s["several"] else "-"
        why = ", ".join(f"{k[8:]} {v}" for k, v in sorted(s.items()) if k.startswith("status: ") and "solved" not in k)
        print(f"{r['n_c']:>4} {s['scenes']:>6} {s['solved']:>7} {chk:>12} {s['planted']:>8} {sev:>17} "
              f"{s['none though modes exist']} {('(' + why + ')') if why else ''}")  # fmt: skip
    tot = Counter()
    for r in rows:
        tot.update(r["stats"])
    print(f"all: {tot['solved']}/{tot['scenes']} solved ({100 * tot['solved'] / tot['scenes']:.1f} %), "
          f"{tot['in full set']}/{tot['checked']} in the full set, none-though-modes-exist "
          f"{tot['none though modes exist']} ({100 * tot['none though modes exist'] / tot['scenes']:.1f} %)")

    print("\nThe paper's Table 1 extended (cpu s on an RS6000/320 against our wall clock s)")
    print(f"{'n_c = 3+|tau_I|':>16} {'modes':>11} {'paper enum':>11} {'ours enum':>12} {'paper 1-sol':>12} {'ours lcp':>9}")
    for r in rows:
        n = r["n_c"]
        if n not in PAPER_ENUM_SECONDS and n not in PAPER_BILINEAR_SECONDS and n not in (10, 14, 16):
            continue
        pe = PAPER_ENUM_SECONDS.get(n)
        pb = PAPER_BILINEAR_SECONDS.get(n)
        oe = f"{r['t_enum']:.4f}" if r["t_enum"] is not None else "not run"
        print(f"{n:>16} {r['modes']:>11} {('%.2f' % pe) if pe else '-':>11} {oe:>12} "
              f"{('several' if pb else '-'):>12} {r['t_lcp']:>9.4f}")  # fmt: skip


def chart(rows, path: Path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax, bx) = plt.subplots(1, 2, figsize=(11, 4.2))
    n = [r["n_c"] for r in rows]
    te = [(r["n_c"], r["t_enum"]) for r in rows if r["t_enum"] is not None]
    ax.semilogy(*zip(*te), "o-", label="enumerate (all modes), ours")
    ne = [(r["n_c"], r["est"]) for r in rows if r["t_enum"] is None]
    if ne:
        ax.semilogy(*zip(*ne), "o--", mfc="none", color="C0", alpha=0.6, label="enumerate, extrapolated (not run)")
    ax.semilogy(n, [r["t_lcp"] for r in rows], "s-", color="C1", label="lcp (one mode, Lemke), ours")
    ax.semilogy(*zip(*sorted(PAPER_ENUM_SECONDS.items())), "^:", color="C2", label="paper, enumerate (RS6000)")
    ax.semilogy(*zip(*PAPER_BILINEAR_SECONDS.items()), "v", color="C3", label="paper, bilinear ('several s')")
    ax.set_xlabel("n_c = 3 + |tau_I|")
    ax.set_ylabel("time per scene (s)")
    ax.set_title("Speed")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    sol = [r["stats"]["solved"] / r["stats"]["scenes"] for r in rows]
    bx.plot(n, [100 * x for x in sol], "s-", color="C1", label="lcp returns a verified mode")
    chk = [(r["n_c"], 100 * r["stats"]["in full set"] / r["stats"]["checked"]) for r in rows if r["stats"]["checked"]]
    if chk:
        bx.plot(*zip(*chk), "o", mfc="none", color="C0", label="of the modes returned: % in the enumerated set")
    bx.plot(n, [100 * r["stats"]["planted"] / r["stats"]["scenes"] for r in rows], "d:", color="C4",
            label="... and it is the planted mode")  # fmt: skip
    bx.set_ylim(0, 105)
    bx.set_xlabel("n_c = 3 + |tau_I|")
    bx.set_ylabel("% of seeded scenes (each has a feasible mode)")
    bx.set_title("Accuracy of the one-solution method")
    bx.grid(True, alpha=0.3)
    bx.legend(fontsize=8, loc="lower left")
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    print(f"\nchart: {path}")


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--max-contacts", type=int, default=20)
    p.add_argument("--seeds", type=int, default=20, help="scenes per n_c for the LCP statistics")
    p.add_argument("--repeat", type=int, default=3)
    p.add_argument("--cap", type=float, default=30.0, help="skip enumeration runs estimated above this (s)")
    p.add_argument("--stats-cap", type=float, default=1.0,
                   help="enumerate each statistics scene only when estimated below this (s)")  # fmt: skip
    p.add_argument("--no-chart", action="store_true")
    a = p.parse_args(argv)
    rows = run(a.max_contacts, a.seeds, a.repeat, a.cap, a.stats_cap)
    print_tables(rows)
    if not a.no_chart:
        chart(rows, CHARTS / "speed_accuracy.png")


if __name__ == "__main__":
    main()
