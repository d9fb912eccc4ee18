"""The batched test of contact modes (eqs. 24-28): one batch, and consecutive batches of the enumeration.

:func:`solve_batch` runs the kinematic stage (:mod:`qsplan.mechanics.modes.kinematics`,
eqs. 23-25 and 16) on a whole batch of modes at once, and the equilibrium and Coulomb
stage (:mod:`qsplan.mechanics.modes.equilibrium`, eqs. 26-28) on the survivors only.
Each mode gets exactly the status the one-mode reference
:func:`qsplan.mechanics.modes.reference.check_mode` gives it, which the tests verify.
:func:`solve_batches` streams the modes of eq. (49) through it, in-process; the public
:func:`qsplan.mechanics.solver.all_modes.solve` chooses between it, chunks of it on
other processes and the exact pruned search.
"""

from __future__ import annotations

from dataclasses import replace
from itertools import islice

import numpy as np

from qsplan.mechanics.model.scene import Scene
from qsplan.mechanics.modes.contact_mode import ContactMode, codes_to_letters, count_modes, iter_mode_batches
from qsplan.mechanics.modes.equilibrium import equilibrium_stage
from qsplan.mechanics.modes.kinematics import ScenePool, kinematics_stage, velocity_scale
from qsplan.mechanics.modes.solution import ModeSolution, model_residuals
from qsplan.mechanics.numerics import DEFAULT_TOLERANCES, Status, StatusCode, Tolerances
from qsplan.mechanics.solver.result import SolveResult

__all__ = ["DEFAULT_BATCH", "solve_batch", "solve_batches"]

#: Modes per batch.  Memory per batch is about ``batch * k * (k + n_j) * 8`` bytes
#: several times over; 8192 keeps it to a few MB for k <= 20 and amortises numpy's
#: per-call overhead.
DEFAULT_BATCH = 8192


def solve_batch(scene: Scene, codes: np.ndarray, tol: Tolerances = DEFAULT_TOLERANCES, residuals: bool = True,
               *, pool: "ScenePool | None" = None, vtol: float | None = None):  # fmt: skip
    """Test a batch of modes: kinematics (24-25, 16), then equilibrium and Coulomb (26-28) for the survivors.

    Parameters
    ----------
    codes : ndarray of uint8, shape (m, n_c)
        Letter codes (0 B, 1 R, 2 S), each mode with ``2 n_R + n_S = 3 + |tau_I|``.
    pool, vtol : optional
        The scene's :class:`ScenePool` and absolute velocity tolerance, if already computed.

    Returns
    -------
    status : ndarray of int8, shape (m,)
        Codes into ``Status.ORDER``.
    solutions : list of ModeSolution
        The feasible modes, in the order of ``codes``.
    """
    n_c = scene.n_contacts
    pool = ScenePool(scene) if pool is None else pool
    vtol = tol.velocity * velocity_scale(scene) if vtol is None else vtol
    tau_e = np.nan_to_num(scene.joint_effort)[pool.E]
    sols = []
    status, live, kin = kinematics_stage(scene, pool, codes, tol, vtol)
    if live.size:
        m = live.size
        st, c_n, c_t, tau, boundary = equilibrium_stage(
            scene, pool, kin, np.broadcast_to(scene.mu, (m, n_c)), np.broadcast_to(tau_e, (m, tau_e.size)), tol
        )
        status[live] = st
        for j in np.flatnonzero(st == StatusCode.FEASIBLE):
            sol = ModeSolution(
                mode=ContactMode(codes_to_letters(kin.codes[j])), qdot=kin.qdot[j], thetadot=kin.thetadot[j],
                c_n=c_n[j], c_t=c_t[j], tau=tau[j], xi=kin.xi[j].astype(int), on_boundary=bool(boundary[j]),
            )  # fmt: skip
            if residuals:
                sol = replace(sol, residuals=model_residuals(scene, sol))
            sols.append(sol)
    return status, sols


def solve_batches(scene: Scene, tol: Tolerances = DEFAULT_TOLERANCES, batch: int = DEFAULT_BATCH,
                  residuals: bool = True, keep_statuses: bool = False, batches: tuple[int, int] | None = None,
                  progress=None) -> SolveResult:  # fmt: skip
    """Test every mode of eq. (49) in this process, batch after batch (or batches ``lo <= i < hi``).

    Same arguments and result as :func:`qsplan.mechanics.solver.all_modes.solve` with
    ``workers=1, search="all"``; a chunk of a parallel solve is one call with ``batches``.
    ``progress(done, total, "modes")`` is called after every batch.
    """
    n_c, dof = scene.n_contacts, scene.dof
    total = count_modes(n_c, dof)
    counts = dict.fromkeys(Status.ORDER, 0)
    sols = []
    vtol = tol.velocity * velocity_scale(scene)
    kept: list = []
    pool = ScenePool(scene)
    for codes in islice(iter_mode_batches(n_c, dof, batch), *(batches or (None,))):
        status, found = solve_batch(scene, codes, tol, residuals, pool=pool, vtol=vtol)
        sols.extend(found)
        for code, cnt in enumerate(np.bincount(status, minlength=len(Status.ORDER))):
            counts[Status.ORDER[code]] += int(cnt)
        if keep_statuses:
            kept.extend(Status.ORDER[c] for c in status)
        if progress:
            progress(sum(counts.values()), total, "modes")
    return SolveResult(
        scene=scene, modes_tested=total, solutions=tuple(sols), counts=counts, tolerances=tol,
        statuses=tuple(kept) if keep_statuses else None,
    )  # fmt: skip
