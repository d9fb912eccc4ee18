"""The batch solve of every contact mode (eqs. 24-28, 49) split into chunks of consecutive batches.

:func:`qsplan.mechanics.solve` streams the modes in batches
(:func:`qsplan.mechanics.modes.contact_mode.iter_mode_batches`).  Here the batches are numbered, split
into contiguous ranges, and each range is solved by ``solve_batches(..., batches=(lo, hi))``
in its own process (:func:`qsplan.mechanics.parallel.map_chunks`).  Every batch is the
same one the single-process solve would form, so every mode gets bit-identical
numbers, and merging in range order keeps the enumeration order of the solutions
and statuses.
"""

from __future__ import annotations

from qsplan.mechanics.modes.contact_mode import count_modes, iter_mode_batches
from qsplan.mechanics.parallel import chunk_count, map_chunks, split_range
from qsplan.mechanics.solver.batch import solve_batches
from qsplan.mechanics.solver.result import merge_results

__all__ = ["MIN_CHUNK_MODES", "solve_in_chunks"]

#: Fewest modes worth a chunk of their own: one core tests ~2.5e5 modes/s (n_c = 12..14),
#: so 65536 modes are ~0.25 s.  Two workers gained nothing on n_c = 12 (73789 modes,
#: ~0.3 s, which now stays in-process) and 1.5x from n_c = 13 on (bench_parallel.py).
MIN_CHUNK_MODES = 65536


def _solve_chunk(job):
    """One range of batches, in the process that runs it."""
    scene, tol, batch, residuals, keep_statuses, lo, hi = job
    return solve_batches(scene, tol, batch, residuals, keep_statuses, (lo, hi))


def solve_in_chunks(scene, tol, batch, residuals, keep_statuses, *, workers=None, scheduler=None, progress=None):
    """``solve(scene, ...)`` over chunks of batches, or None when it should run in-process.

    None means the rule of :func:`qsplan.mechanics.parallel.chunk_count` gave one chunk
    (fewer than ``2 * MIN_CHUNK_MODES`` modes) and no scheduler was given.
    """
    n_modes = count_modes(scene.n_contacts, scene.dof)
    if scheduler is None and chunk_count(n_modes, MIN_CHUNK_MODES, workers=workers) == 1:
        return None  # decided before enumerating the batches: solve() is called in loops on small scenes
    n_batches = sum(1 for _ in iter_mode_batches(scene.n_contacts, scene.dof, batch))
    modes_per_batch = max(1, n_modes // max(1, n_batches))
    n_chunks = chunk_count(n_batches, -(-MIN_CHUNK_MODES // modes_per_batch), workers=workers, scheduler=scheduler)
    if n_batches == 0 or (n_chunks == 1 and scheduler is None):
        return None
    jobs = [(scene, tol, batch, residuals, keep_statuses, lo, hi) for lo, hi in split_range(n_batches, n_chunks)]
    return merge_results(map_chunks(_solve_chunk, jobs, workers=workers, scheduler=scheduler, progress=progress))

