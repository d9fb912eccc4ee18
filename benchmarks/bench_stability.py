"""Stability study: where the float methods fail, against exact rational ground truth (issue 7).

Five families of three-contact scenes (two velocity-controlled joints, ``3 + |tau_I| = 3``) are
driven toward a degeneracy by a distance ``eps = 2^-k`` (``k = 0, 4, ..., 52``, and ``eps = 0``
itself).  All data are dyadic rationals with few bits, so the floats the methods see are the
exact data and :mod:`qsplan.mechanics.crosscheck.exact` gives the exact feasible set (strict inequalities strict,
singular meaning exactly singular):

``concurrent``
    the three normal lines of action meet in one point at ``eps = 0`` (contact 3 moved by
    ``eps`` along its tangent): ``P_AI`` and ``W_Amu`` of the all-normal modes singular;
``parallel``
    normals ``(0, 1)``, ``(eps, 1)``, ``(0, -1)``: nearly parallel, concurrent at infinity;
``slip``
    a planted mode whose sliding contact slips at speed ``eps`` (eq. 16's sign undefined at 0);
``cone``
    a planted mode whose rolling contact's force is ``eps`` (relative) off its friction-cone
    edge, inside or outside (eq. 28 active);
``mu``
    the same force, and ``mu`` moved by ``eps`` to either side of the value where the rolling
    mode's region ends.

Methods: ``enumerate`` (:func:`qsplan.mechanics.solve`, default :class:`~qsplan.mechanics.numerics.Tolerances`)
and ``lcp`` (:func:`qsplan.mechanics.crosscheck.lcp.solve_lcp`).  Counted per method: false modes (reported
feasible, exactly infeasible), missed modes (exactly feasible, rejected by an ordinary check),
declined modes (exactly feasible, reported degenerate or ill-conditioned: an honest "cannot
tell", not a guess), exceptions; for ``lcp``: a returned mode not exactly feasible (false), or
no mode though the exact set is not empty (missed).

Condition measure: each mode's Hadamard ratio ``h = min(h(P_AI), h(Q_AI))``
(:func:`qsplan.mechanics.numerics.hadamard_ratio`; ``Q_AI`` when the kinematics pass).  The chart
``benchmarks/charts/stability.png`` shows the enumerate method's wrong-answer and decline rates
per mode against ``h`` and each family's errors against ``eps``; a threshold sweep over
``Tolerances.singular`` gives the wrong answers left above each threshold and the exactly
feasible modes declined below it, which is how the default threshold was chosen.

Usage, from the repository root::

    PYTHONPATH=. python3 benchmarks/bench_stability.py [--seeds 4] [--no-chart]
"""

import argparse
from collections import Counter, defaultdict
from dataclasses import replace
from pathlib import Path

import numpy as np

from qsplan.mechanics import make_scene, solve
from qsplan.mechanics.crosscheck.exact import exact_feasible_modes
from qsplan.mechanics.modes.kinematics import velocity_scale
from qsplan.mechanics.crosscheck.lcp import solve_lcp
from qsplan.mechanics.modes.contact_mode import mode_index_array
from qsplan.mechanics.numerics import DEFAULT_TOLERANCES, Status, hadamard_ratio
from qsplan.mechanics.modes.equilibrium import equilibrium_matrix
from qsplan.mechanics.modes.kinematics import ScenePool, kinematics_stage

CHARTS = Path(__file__).resolve().parent / "charts"
FAMILIES = ("concurrent", "parallel", "slip", "cone", "mu")
EXPONENTS = tuple(range(0, 53, 4)) + (None,)  # eps = 2^-k; None: eps = 0
THRESHOLDS = (0.0, 1e-16, 1e-14, 1e-12, 1e-10, 1e-8, 1e-6)


def _dy(rng, size, bits=3, lo=-4, hi=4):
    """Random dyadic rationals ``m / 2^bits`` with ``m`` in ``[lo 2^bits, hi 2^bits]`` (exact floats)."""
    return rng.integers(lo * 2**bits, hi * 2**bits + 1, size=size) / 2.0**bits


def _wrenches(r, n):
    """``W_n, W_t`` (3, n_c) of un-normalised normals: exact for dyadic ``r, n`` (eq. 1)."""
    t = np.column_stack([-n[:, 1], n[:, 0]])
    cross = lambda a, b: a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]  # noqa: E731
    return np.vstack([n.T, cross(r, n)]), np.vstack([t.T, cross(r, t)])


def _scene(r, n, rng, mu=None, Jn=None, Jt=None, thetadot=(1.0, 0.5), g_obj=None):
    Wn, Wt = _wrenches(r, n)
    n_c = r.shape[0]
    return make_scene(
        Wn, Wt, _dy(rng, (n_c, 2)) if Jn is None else Jn, _dy(rng, (n_c, 2)) if Jt is None else Jt,
        rng.integers(1, 8, size=n_c) / 8.0 if mu is None else mu,
        _dy(rng, 3) if g_obj is None else g_obj, joint_velocity=list(thetadot),
    )  # fmt: skip


def _geometry(rng, n_c=3):
    n = _dy(rng, (n_c, 2), bits=1, lo=-2, hi=2)
    n[np.all(n == 0, axis=1)] = (0.0, 1.0)
    return _dy(rng, (n_c, 2), bits=2, lo=-1, hi=1), n


def _planted(rng, r, n, letters, sgn, mu, slip=0.5, cone=0.5, mu_shift=0.0):
    """A scene in which the mode ``letters`` is feasible up to the perturbations (cf. qsplan.mechanics.modes.planted).

    Sliding contacts slip at ``sgn * slip``; rolling ones carry ``c_n = 1``, ``c_t = sgn cone mu``,
    and their ``mu`` is then moved by ``mu_shift`` (the force lies ``-mu_shift`` outside the cone);
    breaking ones separate at 1/2.  Velocities are exact: the Jacobian column of the joint with
    unit speed is adjusted, all in dyadic rationals with few bits.
    """
    Wn, Wt = _wrenches(r, n)
    qdot = _dy(rng, 3, bits=2, lo=-1, hi=1)
    th = np.array([1.0, 0.5])
    Jn, Jt = _dy(rng, (3, 2)), _dy(rng, (3, 2))

    def set_row(J, W, i, target):  # w . qdot - J[i] . th == target, exactly (th[0] = 1)
        J[i, 0] = W[:, i] @ qdot - J[i, 1] * th[1] - target

    c_n, c_t = np.zeros(3), np.zeros(3)
    mu = np.array(mu, dtype=float)
    for i, letter in enumerate(letters):
        set_row(Jn, Wn, i, 0.5 if letter == "B" else 0.0)
        if letter == "R":
            set_row(Jt, Wt, i, 0.0)
            c_n[i], c_t[i] = 1.0, sgn[i] * cone * mu[i]
        elif letter == "S":
            set_row(Jt, Wt, i, sgn[i] * slip)
            c_n[i], c_t[i] = 1.0, -sgn[i] * mu[i]
    g_obj = -(Wn @ c_n + Wt @ c_t)
    mu[[i for i, c in enumerate(letters) if c == "R"]] += mu_shift
    return _scene(r, n, rng, mu=mu, Jn=Jn, Jt=Jt, thetadot=th, g_obj=g_obj)


def _rsb(rng, **kw):
    r, n = _geometry(rng)
    letters = "".join(np.array(list("RSB"))[rng.permutation(3)])
    return _planted(rng, r, n, letters, rng.choice([-1.0, 1.0], 3), rng.integers(1, 8, size=3) / 8.0, **kw)


def concurrent(eps, rng):
    """Planted 3S whose friction-cone edges (the columns of W_Amu, eqs. 18-20) meet in one point at eps = 0."""
    _, n = _geometry(rng)
    sgn = rng.choice([-1.0, 1.0], 3)
    mu = rng.integers(1, 8, size=3) / 8.0
    t = np.column_stack([-n[:, 1], n[:, 0]])
    e = n - (mu * sgn)[:, None] * t  # line of action of the sliding force, eq. (17)
    r = _dy(rng, 2, bits=2, lo=-1, hi=1) + _dy(rng, (3, 1), bits=2, lo=-1, hi=1) * e
    r[2] += eps * np.array([-e[2, 1], e[2, 0]])
    return _planted(rng, r, n, "SSS", sgn, mu)


def parallel(eps, rng):
    """Planted 3S with normals ``(0, 1), (eps, 1), (0, -1)``: P_AI (eq. 23) singular at eps = 0."""
    r, _ = _geometry(rng)
    n = np.array([[0.0, 1.0], [eps, 1.0], [0.0, -1.0]])
    return _planted(rng, r, n, "SSS", rng.choice([-1.0, 1.0], 3), rng.integers(1, 8, size=3) / 8.0)


def slip(eps, rng):
    return _rsb(rng, slip=eps)


def cone(eps, rng):
    return _rsb(rng, cone=1.0 - float(rng.choice([-1.0, 1.0])) * eps)


def mu(eps, rng):
    return _rsb(rng, cone=1.0, mu_shift=float(rng.choice([-1.0, 1.0])) * eps)


BUILDERS = {"concurrent": concurrent, "parallel": parallel, "slip": slip, "cone": cone, "mu": mu}


def mode_conditioning(scene):
    """``min(h(P_AI), h(Q_AI))`` of every mode in enumeration order, shape (n_modes,)."""
    codes = mode_index_array(scene.n_contacts, scene.dof)
    pool = ScenePool(scene)
    tol0 = replace(DEFAULT_TOLERANCES, singular=0.0)
    mask = np.concatenate([codes != 0, codes == 1], axis=1)  # applicable rows [n-rows; t-rows] (eq. 14)
    idx = np.argsort(~mask, axis=1, kind="stable")[:, : scene.dof]
    h = hadamard_ratio(pool.M[idx])  # P_AI (eq. 23)
    _, live, kin = kinematics_stage(scene, pool, codes, tol0, DEFAULT_TOLERANCES.velocity * velocity_scale(scene))
    if live.size:
        Q = equilibrium_matrix(pool, kin, np.broadcast_to(scene.mu, (live.size, scene.n_contacts)))
        h[live] = np.minimum(h[live], hadamard_ratio(Q))
    return h


def study(seeds: int):
    mode_rows = []  # (family, k, h, exact feasible, float status)
    scene_rows = []
    sweep = defaultdict(Counter)  # threshold -> counts
    for fam in FAMILIES:
        for k in EXPONENTS:
            eps = 0.0 if k is None else 2.0**-k
            for s in range(seeds):
                rng = np.random.default_rng([7, FAMILIES.index(fam), s])  # same geometry for every eps
                scene = BUILDERS[fam](eps, rng)
                exact = exact_feasible_modes(scene)
                X = {m for m, c in exact.items() if c.feasible}
                h = mode_conditioning(scene)
                row = dict(family=fam, k=k, seed=s, exact=X)
                try:
                    res = solve(scene, keep_statuses=True)
                    F = set(res.feasible_modes)
                    row["enum_false"] = sum(not res.solution(m).on_boundary for m in F - X)
                    row["enum_flagged"] = sum(res.solution(m).on_boundary for m in F - X)
                    miss = [m for m in X - F]
                    st = dict(zip(exact, res.statuses))
                    row["enum_declined"] = sum(st[m] in Status.DEGENERATE for m in miss)
                    row["enum_missed"] = len(miss) - row["enum_declined"]
                    row["enum_exc"] = 0
                    for (m, ex), hm in zip(exact.items(), h):
                        sol = res.solution(m)
                        mode_rows.append((fam, k, float(hm), ex.feasible, st[m], bool(sol and sol.on_boundary)))
                except Exception as exc:  # noqa: BLE001 - counted, that is the point
                    row.update(enum_false=0, enum_flagged=0, enum_missed=0, enum_declined=0, enum_exc=1, exc=repr(exc))
                try:
                    lr = solve_lcp(scene)
                    bad = lr.solved and lr.mode.letters not in X
                    row["lcp_false"] = int(bad and not lr.solution.on_boundary)
                    row["lcp_flagged"] = int(bad and lr.solution.on_boundary)
                    row["lcp_missed"] = int(not lr.solved and bool(X) and lr.status not in ("ill-conditioned", "degenerate"))
                    row["lcp_declined"] = int(not lr.solved and bool(X) and lr.status in ("ill-conditioned", "degenerate"))
                    row["lcp_exc"] = 0
                    row["lcp_status"] = lr.status
                except Exception as exc:  # noqa: BLE001
                    row.update(lcp_false=0, lcp_flagged=0, lcp_missed=0, lcp_declined=0, lcp_exc=1, exc=repr(exc))
                scene_rows.append(row)
                for T in THRESHOLDS:
                    c = sweep[T]
                    c["modes"] += len(exact)
                    try:
                        r2 = solve(scene, tol=replace(DEFAULT_TOLERANCES, singular=T), keep_statuses=True)
                    except Exception:  # noqa: BLE001 - e.g. LinAlgError on an exactly singular matrix
                        c["exceptions"] += 1
                        continue
                    F2 = set(r2.feasible_modes)
                    st2 = dict(zip(exact, r2.statuses))
                    c["false"] += len(F2 - X)
                    c["missed"] += sum(st2[m] not in Status.DEGENERATE for m in X - F2)
                    c["declined"] += sum(st2[m] in (Status.KINEMATICS_SINGULAR, Status.EQUILIBRIUM_SINGULAR) for m in X - F2)
    return mode_rows, scene_rows, sweep


def print_tables(mode_rows, scene_rows, sweep):
    print("Per family and eps = 2^-k: exact feasible modes, and enumerate / lcp errors summed over seeds:\n"
          "F false (silent), Fb false but flagged on_boundary (eq. 28 met within Tolerances.force), M missed,\n"
          "D declined (reported degenerate / ill-conditioned), X exceptions")  # fmt: skip
    print(f"{'family':>10} {'k':>4} {'exact':>6} | {'enum F':>6} {'Fb':>3} {'M':>3} {'D':>3} {'X':>3} | "
          f"{'lcp F':>5} {'Fb':>3} {'M':>3} {'D':>3} {'X':>3}")  # fmt: skip
    by = defaultdict(Counter)
    for r in scene_rows:
        c = by[(r["family"], r["k"])]
        c["exact"] += len(r["exact"])
        for key in KEYS:
            c[key] += r[key]
    tot = Counter()
    for (fam, k), c in by.items():
        tot.update(c)
        kk = "inf" if k is None else str(k)
        print(f"{fam:>10} {kk:>4} {c['exact']:>6} | {c['enum_false']:>6} {c['enum_flagged']:>3} {c['enum_missed']:>3} "
              f"{c['enum_declined']:>3} {c['enum_exc']:>3} | {c['lcp_false']:>5} {c['lcp_flagged']:>3} {c['lcp_missed']:>3} "
              f"{c['lcp_declined']:>3} {c['lcp_exc']:>3}")  # fmt: skip
    n = len(scene_rows)
    print(f"\nall {n} scenes, {tot['exact']} exactly feasible modes: enumerate false {tot['enum_false']} "
          f"(+{tot['enum_flagged']} flagged on_boundary), missed "
          f"{tot['enum_missed']}, declined {tot['enum_declined']}, exceptions {tot['enum_exc']}; lcp false "
          f"{tot['lcp_false']} (+{tot['lcp_flagged']} flagged), missed {tot['lcp_missed']} (no mode though modes exist), declined {tot['lcp_declined']}, "
          f"exceptions {tot['lcp_exc']}")  # fmt: skip
    print("\nError rate per mode (enumerate) against its Hadamard ratio h = min(h(P_AI), h(Q_AI))")
    print(f"{'h in':>20} {'modes':>6} {'wrong':>6} {'flagged':>8} {'declined':>9}")
    for lo, hi, w, f, d, m in _bins(mode_rows):
        print(f"[{lo:8.0e}, {hi:8.0e}) {m:>6} {w:>6} {f:>8} {d:>9}")
    print("\nThreshold sweep over Tolerances.singular (all modes of all scenes): false modes (incl. flagged on_boundary), "
          "exactly feasible modes declined as singular")  # fmt: skip
    print(f"{'threshold':>10} {'false':>6} {'missed':>7} {'declined':>9} {'exceptions':>11} {'modes':>6}")
    for T in THRESHOLDS:
        c = sweep[T]
        print(f"{T:>10.0e} {c['false']:>6} {c['missed']:>7} {c['declined']:>9} {c['exceptions']:>11} {c['modes']:>6}")


KEYS = tuple(f"{m}_{k}" for m in ("enum", "lcp") for k in ("false", "flagged", "missed", "declined", "exc"))
BIN_EDGES = 10.0 ** np.arange(-20, 1, 2)


def _bins(mode_rows):
    h = np.array([r[2] for r in mode_rows])
    feas = np.array([r[3] for r in mode_rows])
    st = [r[4] for r in mode_rows]
    fl = np.array([s == Status.FEASIBLE for s in st])
    dec = np.array([s in Status.DEGENERATE for s in st])
    flag = np.array([r[5] for r in mode_rows])
    wrong = (fl != feas) & ~dec & ~flag
    flagged = (fl != feas) & flag
    declined = dec & feas
    edges = np.concatenate([[0.0], BIN_EDGES])
    out = []
    for lo, hi in zip(edges[:-1], edges[1:]):
        sel = (h >= lo) & (h < hi) if hi < 1 else (h >= lo)
        if sel.any():
            out.append((lo, hi, int(wrong[sel].sum()), int(flagged[sel].sum()), int(declined[sel].sum()), int(sel.sum())))
    return out


def chart(mode_rows, scene_rows, path: Path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax, bx) = plt.subplots(1, 2, figsize=(11, 4.2))
    b = _bins(mode_rows)
    x = [np.sqrt(max(lo, 1e-22) * hi) for lo, hi, *_ in b]
    ax.semilogx(x, [100 * w / m for *_, w, f, d, m in b], "o-", color="C3", label="wrong, silent (false or missed)")
    ax.semilogx(x, [100 * f / m for *_, w, f, d, m in b], "^-", color="C1", label="false, flagged on_boundary")
    ax.semilogx(x, [100 * d / m for *_, w, f, d, m in b], "s--", color="C0", label="exactly feasible, declined")
    ax.axvline(DEFAULT_TOLERANCES.singular, color="k", lw=0.8, ls=":", label=f"Tolerances.singular = {DEFAULT_TOLERANCES.singular:g}")
    ax.set_xlabel("Hadamard ratio h = min(h(P_AI), h(Q_AI)) of the mode (leftmost bin: h < 1e-20)")
    ax.set_ylabel("% of modes in the bin")
    ax.set_title("enumerate, default tolerances: error rate per mode")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    for j, fam in enumerate(FAMILIES):
        for meth, mk in (("enum", "o-"), ("lcp", "x:")):
            ks = sorted({r["k"] for r in scene_rows if r["k"] is not None})
            err = []
            for k in ks:
                rs = [r for r in scene_rows if r["family"] == fam and r["k"] == k]
                bad = (r[f"{meth}_false"] or r[f"{meth}_flagged"] or r[f"{meth}_missed"] or r[f"{meth}_exc"] for r in rs)
                err.append(100 * sum(bool(x) for x in bad) / len(rs))
            bx.plot([2.0**-k for k in ks], err, mk, color=f"C{j}", label=f"{fam} ({meth})", alpha=0.8)
    bx.set_xscale("log")
    bx.set_xlabel("distance to degeneracy eps")
    bx.set_ylabel("% of scenes: false (incl. flagged), missed or exception")
    bx.set_title("per family (o enumerate, x lcp)")
    bx.grid(True, which="both", alpha=0.3)
    bx.legend(fontsize=7, ncol=2)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    print(f"\nchart: {path}")


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--seeds", type=int, default=4)
    p.add_argument("--no-chart", action="store_true")
    a = p.parse_args(argv)
    mode_rows, scene_rows, sweep = study(a.seeds)
    print_tables(mode_rows, scene_rows, sweep)
    if not a.no_chart:
        chart(mode_rows, scene_rows, CHARTS / "stability.png")


if __name__ == "__main__":
    main()
