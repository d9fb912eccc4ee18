"""All feasible contact modes of a scene (Sections 3.1-3.2): the public :func:`solve`.

:func:`solve` tests every mode that meets the utility condition (29) for the
scene's control-mode partition (their number is eq. (49)), in batches
(:func:`qsplan.mechanics.solver.batch.solve_batches`), on local processes or a Dask
cluster when there are enough of them (:mod:`qsplan.mechanics.solver.chunks`).  From
:data:`SEARCH_MIN_MODES` modes on it tests only the modes that survive the exact
pruning of :mod:`qsplan.mechanics.solver.search` (same solutions; ``search="all"``
tests every mode).
"""

from __future__ import annotations

from qsplan.mechanics.errors import QsplanError
from qsplan.mechanics.model.scene import Scene
from qsplan.mechanics.modes.contact_mode import count_modes
from qsplan.mechanics.numerics import DEFAULT_TOLERANCES, Tolerances
from qsplan.mechanics.solver.batch import DEFAULT_BATCH, solve_batches
from qsplan.mechanics.solver.chunks import solve_in_chunks
from qsplan.mechanics.solver.result import SolveResult
from qsplan.mechanics.solver.search import search_solve

__all__ = ["SEARCH_MIN_MODES", "solve"]

#: Fewest modes (eq. 49) for which ``search="auto"`` prunes breaking sets
#: (:mod:`qsplan.mechanics.solver.search`).  Measured on planted scenes with dof = n_c, one core:
#: even at ~5,000 modes (n_c = 9-10), 3x faster at 25,653 (n_c = 11: 0.04 s vs 0.13 s),
#: 7x at 212,941 (n_c = 13).  Small scenes, solved in loops by mu-space maps and bands,
#: keep the plain path and its full per-status counts.
SEARCH_MIN_MODES = 20_000


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
        solutions, the untested modes counted under ``PRUNED``); ``"auto"`` prunes
        from :data:`SEARCH_MIN_MODES` modes on.  ``keep_statuses`` and ``batches``
        always test every mode.

    Returns
    -------
    SolveResult
        The same (bit for bit) however it was split.
    """
    if search not in ("auto", "prune", "all"):
        raise QsplanError(f"search: expected 'auto', 'prune' or 'all'; got {search!r}")
    if search == "auto":
        search = "prune" if count_modes(scene.n_contacts, scene.dof) >= SEARCH_MIN_MODES else "all"
    if search == "prune" and batches is None and not keep_statuses:
        return search_solve(scene, tol, batch, residuals, workers=workers, scheduler=scheduler)
    if batches is None and (workers != 1 or scheduler is not None):
        chunked = solve_in_chunks(scene, tol, batch, residuals, keep_statuses, workers=workers, scheduler=scheduler)
        if chunked is not None:
            return chunked
    return solve_batches(scene, tol, batch, residuals, keep_statuses, batches)
