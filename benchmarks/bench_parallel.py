"""Benchmark: chunked work in-process, on a local process pool and on a Dask LocalCluster.

For each task (every mode of a seeded n_c = 13 scene by the plain batch solve; a
400 x 400 mu-space map of eq. (42) by ``feasibility_map``; a 2000 x 2000 slice by the
polynomial path; the torque bands along 200 samples of segment 1) prints one row
per way of running it: 1 worker (in-process), 2 local workers, and a local Dask
cluster of 2 single-threaded worker processes started here.  Times are the best of
``REPEAT`` wall-clock runs (the cluster's start-up is not included: it is started
once, as a user's cluster would be); "identical" compares the whole result, every
array bit for bit, with the in-process run (:func:`qsplan.mechanics.parallel.first_difference`).

Usage, with qsplan installed with its cluster extra (``pip install .[cluster]``)
or ``PYTHONPATH=.``: ``python benchmarks/bench_parallel.py [--repeat 3]``.
"""

import argparse
import inspect

import numpy as np
from bench_muspace import best_of  # the script's own folder is on sys.path

from qsplan.hands.examples.paper import eq42_scene
from qsplan.hands.paper_hand.segments import first_segment, sample_segment
from qsplan.hands.paper_hand.two_finger import default_hand
from qsplan.mechanics import scene_from_dict, solve
from qsplan.mechanics.muspace.maps import feasibility_map, grid_points
from qsplan.mechanics.muspace.slices import mu_slice
from qsplan.mechanics.parallel import first_difference
from qsplan.mechanics.modes.planted import planted_scene
from qsplan.planner import segment_bands

SEED = 1995


def tasks():
    """``(name, f(**parallel_kwargs))`` for each task."""
    scene13, _ = planted_scene(np.random.default_rng(SEED), 13, 10, 12)
    plain = {"search": "all"} if "search" in inspect.signature(solve).parameters else {}
    eq42 = scene_from_dict(eq42_scene(0.5))
    xs400 = np.linspace(0.0, 1.5, 400)
    pts400 = grid_points(eq42.mu, 0, 1, xs400, xs400)
    xs2000 = np.linspace(0.0, 1.5, 2000)
    samples = sample_segment(first_segment(default_hand()), 200)
    return [
        ("modes, n_c = 13 (212941 modes)", lambda **kw: solve(scene13, **plain, **kw)),
        ("feasibility_map 400 x 400", lambda **kw: feasibility_map(eq42, pts400, **kw)),
        ("mu_slice polynomial 2000 x 2000", lambda **kw: mu_slice(eq42, 0, 1, xs2000, xs2000, **kw)),
        ("segment_bands, 200 samples", lambda **kw: segment_bands(samples, **kw)),
    ]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args(argv)
    rows, refs = [], {}
    for name, f in tasks():  # local runs first: a live Dask client's threads rule out fork (see qsplan.mechanics.parallel)
        for label, kw in (("1", {"workers": 1}), ("2", {"workers": 2})):
            t, out = best_of(lambda: f(**kw), args.repeat)
            refs.setdefault(name, (t, out))
            rows.append((name, label, t, first_difference(out, refs[name][1])))
    from distributed import Client, LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, \
            Client(cluster, set_as_default=False) as client:  # fmt: skip
        for name, f in tasks():
            t, out = best_of(lambda: f(scheduler=client, workers=2), args.repeat)
            rows.append((name, "local cluster (2)", t, first_difference(out, refs[name][1])))
    print(f"{'task':<34} {'workers':<18} {'time (s)':>9} {'speed-up':>9}  identical")
    for name, label, t, d in sorted(rows, key=lambda r: list(refs).index(r[0])):
        print(f"{name:<34} {label:<18} {t:9.3f} {refs[name][0] / t:8.2f}x  {'yes' if d is None else 'no: ' + d}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
