"""All feasible contact modes of a scene (Sections 3.1-3.2): the public :func:`solve`.

:func:`solve` tests every mode that meets the utility condition (29) for the
scene's control-mode partition (their number is eq. (49)), in batches
(:func:`qsplan.mechanics.solver.batch.solve_batches`), on local processes or a Dask
cluster when there are enough of them (:mod:`qsplan.mechanics.solver.chunks`).  From
:data:`SEARCH_MIN_MODES` modes on, ``search="auto"`` uses the exact pruned search of
:mod:`qsplan.mechanics.solver.search` (same solutions): it screens every mode
(:func:`~qsplan.mechanics.solver.search.all_breaking_sets`) when that costs less than
:data:`SCREEN_ALL_SECONDS`, else prunes breaking sets by programmes within a budget worth the
cheaper of screening and testing every mode (:func:`estimate_seconds`,
:func:`~qsplan.mechanics.solver.search.screen_all_seconds`), and falls back to the cheaper of
those two when the budget runs out: so ``auto`` costs at most about 1.5 times the cheaper
(:data:`AUTO_PROGRAMME_SHARE`).
"""

from __future__ import annotations

from qsplan.mechanics.errors import QsplanError
from qsplan.mechanics.model.scene import Scene
from qsplan.mechanics.modes.contact_mode import count_modes
from qsplan.mechanics.numerics import DEFAULT_TOLERANCES, Tolerances
from qsplan.mechanics.solver.batch import DEFAULT_BATCH, solve_batches
from qsplan.mechanics.solver.result import SolveResult
from qsplan.mechanics.solver.screen import compiled_relax
from qsplan.mechanics.solver.search import all_breaking_sets, screen_all_seconds, search_solve

__all__ = ["SEARCH_MIN_MODES", "AUTO_PROGRAMME_SHARE", "MODE_SECONDS_PER_CONSTRAINT", "PROGRAMME_SECONDS",
           "SCREEN_ALL_SECONDS", "estimate_seconds", "solve"]  # fmt: skip

#: Fewest modes (eq. 49) for which ``search="auto"`` prunes breaking sets
#: (:mod:`qsplan.mechanics.solver.search`).  Measured on planted scenes with dof = n_c, one core:
#: even at ~5,000 modes (n_c = 9-10), 3x faster at 25,653 (n_c = 11: 0.04 s vs 0.13 s),
#: 7x at 212,941 (n_c = 13).  Small scenes, solved in loops by mu-space maps and bands,
#: keep the plain path and its full per-status counts.
SEARCH_MIN_MODES = 20_000

#: Seconds to test one mode, per applicable constraint (``dof``), one core: measured 3.3 us at
#: dof = 4 (n_c = 12), 6.3 us at dof = 6 (n_c = 16), 17 us at dof = 12 (n_c = 12).
MODE_SECONDS_PER_CONSTRAINT = 1.4e-6

#: Seconds of one breaking-set programme, with the level's joins and witness checks around it: with
#: the compiled kernel 20-35 us measured at n_c = 12, 35-55 us at n_c = 16, 65-100 us at n_c = 20
#: (planted scenes, dof = n_c); with highspy alone (warm-started) 0.19-0.95 ms at n_c = 12-16, ~0.3 ms
#: at n_c = 20.
PROGRAMME_SECONDS = 1e-4 if compiled_relax is not None else 4e-4

#: Seconds of screening every mode (no programme) under which ``search="auto"`` does so: the
#: programmes would cost about as much (importing highspy alone takes ~13 ms, the first levels'
#: programmes ~10-30 ms at n_c = 12).
SCREEN_ALL_SECONDS = 0.02

#: Share of the cheaper of testing and screening every mode that ``search="auto"`` may spend on
#: breaking-set programmes before it gives up pruning by them: then it does the cheaper, so it
#: stays within 1.5x of it.
AUTO_PROGRAMME_SHARE = 0.5


def estimate_seconds(n_contacts: int, dof: int, workers: int = 1) -> float:
    """Seconds, roughly, to test every mode of eq. (49) on ``workers`` cores (``search="all"``).

    ``search="auto"`` stays within about 1.5 times this: its breaking-set programmes are
    budgeted to :data:`AUTO_PROGRAMME_SHARE` of it.
    """
    return count_modes(n_contacts, dof) * dof * MODE_SECONDS_PER_CONSTRAINT / max(1, workers)


def _auto(scene, tol, batch, residuals, workers, scheduler, progress):
    """The pruned search's result, or None when testing every mode is cheaper (module docstring)."""
    n_c, dof = scene.n_contacts, scene.dof
    if count_modes(n_c, dof) < SEARCH_MIN_MODES:
        return None
    plain, everything = estimate_seconds(n_c, dof), screen_all_seconds(n_c, dof)
    kw = dict(workers=workers, scheduler=scheduler, progress=progress)
    if everything <= min(SCREEN_ALL_SECONDS, plain):
        return search_solve(scene, tol, batch, residuals, sets=all_breaking_sets(n_c, dof), **kw)
    budget = int(AUTO_PROGRAMME_SHARE * min(plain, everything) / PROGRAMME_SECONDS)
    if budget > n_c:
        result = search_solve(scene, tol, batch, residuals, max_programmes=budget, max_seconds=plain, **kw)
        if result is not None:
            return result
    if everything < plain:
        return search_solve(scene, tol, batch, residuals, sets=all_breaking_sets(n_c, dof), **kw)
    return None


def solve(
    scene: Scene,
    tol: Tolerances = DEFAULT_TOLERANCES,
    batch: int = DEFAULT_BATCH,
    residuals: bool = True,
    keep_statuses: bool = False,
    *,
    workers: int | None = None,
    scheduler=None,
    batches: tuple[int, int] | None = None,
    search: str = "auto",
    progress=None,
) -> SolveResult:
    """Find every feasible contact mode of ``scene`` (Sections 3.1-3.2).

    Parameters
    ----------
    scene : Scene
        Its control-mode partition fixes ``3 + |tau_I|`` applicable constraints per mode.
    tol : Tolerances
    batch : int
        Modes per vectorized batch (memory stays bounded by it).
    residuals : bool
        Evaluate the full-model residuals (eqs. 2-11) of every feasible solution.
    keep_statuses : bool
        Keep every mode's status (memory grows with eq. (49); for tests and diagnosis).
    workers : int or None
        Local processes for chunks of batches (``None``: all cores, 1: in-process);
        fewer than ``2 * MIN_CHUNK_MODES`` modes stay in-process (:mod:`qsplan.mechanics.solver.chunks`).
    scheduler : str or dask.distributed.Client, optional
        Send the chunks to a Dask cluster instead (:func:`qsplan.mechanics.parallel.map_chunks`).
    batches : (int, int), optional
        Test only batches ``lo <= i < hi`` of the enumeration (one chunk's share).
    search : {"auto", "prune", "all"}
        ``"all"`` tests every mode; ``"prune"`` tests only the modes whose breaking
        set admits equilibrium (:func:`qsplan.mechanics.solver.search.search_solve`, the same
        solutions, the untested modes counted under ``PRUNED`` and the screened-out ones under
        ``PRUNED_KINEMATIC`` and ``PRUNED_COULOMB``); ``"auto"``, from :data:`SEARCH_MIN_MODES`
        modes on, screens or prunes whichever the estimates say is cheapest (module docstring),
        testing every mode when that is cheaper still.  ``keep_statuses``
        and ``batches`` always test every mode.
    progress : callable, optional
        ``progress(done, total, unit)`` as the work advances (``unit``: ``"modes"`` or
        ``"chunks"``), for a command's progress lines.

    Returns
    -------
    SolveResult
        The same (bit for bit) however it was split.

    Raises
    ------
    QsplanError
        ``search="prune"`` on a scene whose breaking-set search would hold more than
        :data:`qsplan.mechanics.solver.breaking_sets.MAX_LEVEL_SETS` sets in one level.
    ParallelError
        The processes running chunks failed (:func:`qsplan.mechanics.parallel.map_chunks`).
    """
    if search not in ("auto", "prune", "all"):
        raise QsplanError(f"search: expected 'auto', 'prune' or 'all'; got {search!r}")
    if search == "auto" and batches is None and not keep_statuses:
        pruned = _auto(scene, tol, batch, residuals, workers, scheduler, progress)
        if pruned is not None:
            return pruned
    elif search == "prune" and batches is None and not keep_statuses:
        return search_solve(scene, tol, batch, residuals, workers=workers, scheduler=scheduler, progress=progress)
    if batches is None and (workers != 1 or scheduler is not None):
        from qsplan.mechanics.solver.chunks import solve_in_chunks  # process pools: not on the pruned path

        chunked = solve_in_chunks(scene, tol, batch, residuals, keep_statuses, workers=workers, scheduler=scheduler,
                                  progress=progress)  # fmt: skip
        if chunked is not None:
            return chunked
    return solve_batches(scene, tol, batch, residuals, keep_statuses, batches, progress=progress)
