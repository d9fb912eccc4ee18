"""The paper's second way out, its kernel measured: rank-one updates of P_AI^{-1} against batched solves.

Section 4.7 proposes ordering the modes so that consecutive ``P_AI`` (eq. 23) differ by one
row, and updating a factorization instead of refactoring.  The plain path of
:func:`qsplan.mechanics.solve` factors every mode's ``dof x dof`` matrix in numpy batches
(``np.linalg.solve`` on a ``(K, dof, dof)`` stack: LAPACK ``gesv`` per matrix, ``O(dof^3)``).
A Gray-order walk would instead replace one row per step, which is a rank-one change
``A' = A + e_i (r' - r_i)^T`` and, by Sherman-Morrison, an ``O(dof^2)`` update of
``A^{-1}``; run in lockstep over ``K`` walks it is also a numpy batch.

This script measures both kernels on the same random well-conditioned stacks, per mode
(one solve against one update plus the product ``A^{-1} b``), and the accuracy the
update loses over ``m`` consecutive row replacements (relative error of the solution
against a fresh solve), which sets how often a walk must refactor.  Whatever the kernel
ratio, a full walk also pays for the row bookkeeping and the refactorizations, so the
ratio is an upper bound on its gain over the plain path.

Usage, from the repository root::

    PYTHONPATH=. python3 benchmarks/bench_orders.py [--batch 8192] [--repeat 5]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

DOFS = (4, 8, 12, 16, 20)
STEPS = (1, 10, 100, 1000)


def best(fn, repeat):
    t = np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        t = min(t, time.perf_counter() - t0)
    return t


def stack(rng, k, d):
    """``k`` random ``d x d`` matrices with rows of unit norm (like eq. 23's rows after scaling), well conditioned."""
    A = rng.normal(size=(k, d, d)) + 2.0 * np.eye(d)
    return A / np.linalg.norm(A, axis=2, keepdims=True)


def rank_one_row_update(Ainv, i, delta):
    """``(A + e_i delta^T)^{-1}`` from ``A^{-1}`` (Sherman-Morrison), batched: Ainv (k, d, d), delta (k, d)."""
    u = Ainv[:, :, i]  # A^{-1} e_i, (k, d)
    w = np.einsum("kd,kde->ke", delta, Ainv)  # delta^T A^{-1}, (k, d)
    denom = 1.0 + w[:, i]  # 1 + delta^T A^{-1} e_i
    return Ainv - u[:, :, None] * w[:, None, :] / denom[:, None, None]


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--batch", type=int, default=8192, help="matrices per batch (K)")
    p.add_argument("--repeat", type=int, default=5)
    a = p.parse_args(argv)
    rng = np.random.default_rng(1995)
    k = a.batch
    print(f"per-mode time (ns), batch K = {k}, best of {a.repeat}; numpy {np.__version__}")
    print(f"{'dof':>4} {'solve':>10} {'update+mult':>12} {'ratio':>7}   rel. error after m row updates: "
          + "  ".join(f"m={m}" for m in STEPS))  # fmt: skip
    for d in DOFS:
        A = stack(rng, k, d)
        b = rng.normal(size=(k, d))
        Ainv = np.linalg.inv(A)
        delta = stack(rng, k, d)[:, 0, :] - A[:, 0, :]
        t_solve = best(lambda: np.linalg.solve(A, b[:, :, None]), a.repeat) / k
        t_upd = best(lambda: np.einsum("kde,ke->kd", rank_one_row_update(Ainv, 0, delta), b), a.repeat) / k
        errs = []
        Aw, Aiw = A.copy(), Ainv.copy()
        done = 0
        for m in STEPS:
            while done < m:
                i = done % d
                new = stack(rng, k, d)[:, 0, :]
                Aiw = rank_one_row_update(Aiw, i, new - Aw[:, i, :])
                Aw[:, i, :] = new
                done += 1
            x_upd = np.einsum("kde,ke->kd", Aiw, b)
            x_ref = np.linalg.solve(Aw, b[:, :, None])[:, :, 0]
            errs.append(float(np.median(np.linalg.norm(x_upd - x_ref, axis=1) / np.linalg.norm(x_ref, axis=1))))
        print(f"{d:4d} {1e9 * t_solve:10.0f} {1e9 * t_upd:12.0f} {t_solve / t_upd:7.2f}   "
              + "  ".join(f"{e:.1e}" for e in errs))  # fmt: skip


if __name__ == "__main__":
    main()
