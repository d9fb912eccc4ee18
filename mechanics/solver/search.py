"""Every feasible contact mode without testing every mode (Section 4.7's future work), exactly.

The paper lists as future work finding all solutions without testing all
``count_modes(n_c, 3 + |tau_I|)`` modes (eq. 49).  :func:`search_solve` does it
in three steps, each exact:

1. Breaking sets that admit no equilibrium are pruned with all their modes
   (:mod:`qsplan.mechanics.solver.breaking_sets`: one linear programme per Apriori candidate).
   On random planted scenes all but a few percent of the modes go here, while
   kinematic relaxations (one per rolling set) rarely fail, which is why the
   search runs over breaking sets.  A candidate on which a force found at an earlier
   level (nearly) vanishes is kept without its programme (``witnesses``): the kept sets
   are a superset of those that admit equilibrium, for a sixth of the programmes.
2. Within a kept breaking set, the reduced screen (:mod:`qsplan.mechanics.solver.screen`)
   rejects, without the ``dof x dof`` solves of eqs. (24) and (26), the modes whose
   breaking contacts clearly penetrate (eq. 15: a ``p x p`` system, ``p = n_R``) and those
   whose forces clearly leave a friction cone (eq. 28: an ``n_S x n_S`` system); compiled
   when ``pip install .`` had a C compiler, else its numpy reference (same decisions).
   Where programmes would cost more than screening every mode, :func:`all_breaking_sets`
   replaces step 1 (``solve(search="auto")`` decides).
3. The rest, a few modes, are tested by the plain batch stages
   (:func:`qsplan.mechanics.solver.batch.solve_batch`), so every reported solution and status
   is the plain path's (forces and velocities bit for bit, :data:`TWICE_BELOW`).

Modes of steps 1 and 2 are counted under :data:`PRUNED`, :data:`PRUNED_KINEMATIC`
and :data:`PRUNED_COULOMB`; the counts still sum to eq. (49).  On local cores the compiled
screen runs on threads while this one solves the programmes; on a Dask cluster (or without
the kernel) programmes, then screening and tests run in chunks
(:func:`qsplan.mechanics.parallel.map_chunks`).
"""

from __future__ import annotations

from itertools import combinations
from math import comb

import numpy as np

from qsplan.mechanics.solver.breaking_sets import breaking_set_sizes, feasible_breaking_sets
from qsplan.mechanics.modes.contact_mode import Letter, count_modes, mode_order_key
from qsplan.mechanics.modes.kinematics import ScenePool, velocity_scale
from qsplan.mechanics.numerics import DEFAULT_TOLERANCES, Status, Tolerances
from qsplan.mechanics.parallel import chunk_count, map_chunks, resolve_workers
from qsplan.mechanics.model.scene import Scene
from qsplan.mechanics.solver.batch import solve_batch
from qsplan.mechanics.solver.result import SolveResult
from qsplan.mechanics.solver.screen import (
    KERNEL, PENETRATION_MARGIN, REDUCED_SINGULAR, ReducedScene, rolling_positions, rolling_vertices, screen_sets,
)  # fmt: skip

__all__ = [
    "PRUNED",
    "PRUNED_KINEMATIC",
    "PRUNED_COULOMB",
    "PENETRATION_MARGIN",
    "REDUCED_SINGULAR",
    "SCREEN_MODE_SECONDS",
    "SET_SECONDS",
    "SCREEN_PIECE_MODES",
    "KEPT_SHARE",
    "TWICE_BELOW",
    "THREAD_MIN_SECONDS",
    "all_breaking_sets",
    "screen_all_seconds",
    "penetrates",
    "MIN_TEST_CHUNK",
    "codes_with_breaking_sets",
    "modes_with_breaking_sets",
    "search_solve",
]

#: Status of the modes never tested because their breaking set admits no equilibrium.
PRUNED = "pruned_equilibrium_infeasible"

#: Status of the untested modes whose breaking contacts penetrate in the reduced system (eq. 15).
PRUNED_KINEMATIC = "pruned_breaking_violated"

#: Status of the untested modes whose forces leave a friction cone in the reduced system (eq. 28).
PRUNED_COULOMB = "pruned_coulomb_violated"

#: Seconds of the reduced screen per mode of a kept breaking set, one core: compiled, ~32 ns a mode
#: (eq. 15) plus ~1 us per mode that reaches eq. (28) (~3 % of them): 0.065 us a mode measured at
#: n_c = 20 (9.1 M modes, 0.58 s), 0.1 us at n_c = 16; the numpy reference ~7 us (n_c = 16).
SCREEN_MODE_SECONDS = 1e-7 if KERNEL else 7e-6

#: Seconds of the screen per breaking set besides its modes (the reductions of
#: :mod:`qsplan.mechanics.solver.screen`: a QR factorisation or two): 2-4 us compiled (n_c = 12..20),
#: ~0.3 ms in numpy.
SET_SECONDS = 3e-6 if KERNEL else 3e-4

#: Fewest modes worth a chunk of the screening stage in another process (~0.1 s of work).
MIN_TEST_CHUNK = int(0.1 / SCREEN_MODE_SECONDS)

#: Share of the modes that the breaking-set programmes keep, roughly: 2.4 % at n_c = 20, 3.7 % at
#: n_c = 16 (planted scenes, dof = n_c); with :data:`THREAD_MIN_SECONDS`, whether threads pay.
KEPT_SHARE = 0.03

#: Seconds of expected screening under which it stays on this thread: starting a helper thread and
#: importing :mod:`queue` and :mod:`threading` is not worth less (n_c <= 16 on planted scenes).
THREAD_MIN_SECONDS = 0.05

#: Kept modes in a batch under which each is tested twice, side by side.  Forces and velocities come
#: from one LAPACK solve per mode (eqs. 24, 26) and are bit for bit the plain path's however the
#: modes are batched; ``tau`` (eq. 27) and the contact velocities (eq. 5) are matrix products whose
#: last bit can depend on how many rows numpy multiplies at once, most often for a single row, which
#: the plain path's batches never are.  Twice, the few kept modes give the plain path's ``tau`` in
#: the cases measured (every feasible mode at n_c = 12..22; before this, the pruned path's ``tau``
#: differed from it by up to 7e-15 at n_c = 20); the cost is nil.
TWICE_BELOW = 64

#: Modes per call of the compiled screen on a thread (~5 ms of work): small enough to balance two
#: threads, large enough that the call (a mask per set, the result's codes) costs nothing.
SCREEN_PIECE_MODES = 50_000


def _codes(n_c: int, A: np.ndarray, R: np.ndarray) -> np.ndarray:
    """Letter codes (0 B, 1 R, 2 S) of the modes with contacts ``A`` not breaking and rolling sets ``R`` (m, r)."""
    codes = np.full((R.shape[0], n_c), Letter.B, dtype=np.uint8)
    codes[:, A] = Letter.S
    codes[np.arange(R.shape[0])[:, None], R] = Letter.R
    return codes


def codes_with_breaking_sets(n_c: int, dof: int, sets) -> np.ndarray:
    """Letter codes (0 B, 1 R, 2 S) of every mode with ``2 n_R + n_S = dof`` whose breaking set is in ``sets``.

    Returns
    -------
    ndarray of uint8, shape (m, n_c)
        ``m = sum C(n_c - |B|, |B| + dof - n_c)`` over the sets.
    """
    parts = []
    for B in sets:
        if 0 <= len(B) + dof - n_c <= n_c - len(B):
            parts.append(_codes(n_c, *_rolling_sets(n_c, dof, B)))
    return np.concatenate(parts) if parts else np.zeros((0, n_c), dtype=np.uint8)


def _n_modes(n_c, dof, B) -> int:
    b = len(B)
    return comb(n_c - b, b + dof - n_c) if 0 <= b + dof - n_c <= n_c - b else 0


def _rolling_sets(n_c: int, dof: int, B) -> tuple[np.ndarray, np.ndarray]:
    """The contacts ``A`` outside ``B`` and every rolling set of a mode with breaking set ``B``, shape (m, r)."""
    A = np.setdiff1d(np.arange(n_c), np.asarray(B, dtype=np.intp))
    return A, A[rolling_positions(A.size, len(B) + dof - n_c)]


def penetrates(pool, B, A, R, margin: float) -> np.ndarray:
    """Modes (breaking set ``B``, rolling sets ``R``) whose breaking contacts surely penetrate (eq. 15).

    The kinematic half of the reduced screen (:func:`qsplan.mechanics.solver.screen.rolling_vertices`):
    flagged only when the reduced systems are well conditioned (:data:`REDUCED_SINGULAR`) and some
    breaking contact has ``v_n < -margin``; the reference then finds ``v_n < -tol.velocity``
    there too (or ``P_AI`` singular).

    Parameters
    ----------
    pool : ScenePool
    B, A : ndarray of int
        Breaking contacts and the others (sorted).
    R : ndarray of int, shape (m, p)
    margin : float
        m/s, well above the rounding of the reduced solve.

    Returns
    -------
    ndarray of bool, shape (m,)
    """
    out = np.zeros(R.shape[0], dtype=bool)
    if len(B) == 0 or R.shape[0] == 0:
        return out
    kin = rolling_vertices(pool.M, pool.drive, B, A, np.searchsorted(A, R), margin)
    return out if kin is None else kin[0]


def _masks(sets, n_c: int) -> np.ndarray:
    """Breaking sets (tuples of contacts) as rows of a uint8 mask, shape (len(sets), n_c), 1 = breaking."""
    masks = np.zeros((len(sets), n_c), dtype=np.uint8)
    masks[np.repeat(np.arange(len(sets)), [len(B) for B in sets]), [i for B in sets for i in B]] = 1
    return masks


def _pieces(sets, n_c: int, dof: int, modes: int):
    """``sets`` (any iterable) as consecutive lists of about ``modes`` modes each."""
    part, held = [], 0
    for B in sets:
        part.append(B)
        held += _n_modes(n_c, dof, B)
        if held >= modes:
            yield part
            part, held = [], 0
    if part:
        yield part


def _new_counts() -> dict:
    return dict.fromkeys((*Status.ORDER, PRUNED_KINEMATIC, PRUNED_COULOMB), 0)


def _test_kept(scene, tol, batch, residuals, pool, screened, counts, sols):
    """Add the screens' counts, then test the kept modes by the batch stages (eqs. 24-28)."""
    kept = [codes for codes, *_ in screened]
    codes = np.concatenate(kept) if kept else np.zeros((0, scene.n_contacts), dtype=np.uint8)
    for _, n_kin, n_coul, _ in screened:
        counts[PRUNED_KINEMATIC] += n_kin
        counts[PRUNED_COULOMB] += n_coul
    vtol = tol.velocity * velocity_scale(scene)
    for lo in range(0, codes.shape[0], batch):
        part = codes[lo : lo + batch]
        twice = part.shape[0] < TWICE_BELOW  # see TWICE_BELOW: the plain path's bits
        status, found = solve_batch(scene, np.repeat(part, 2, axis=0) if twice else part, tol, residuals, pool=pool,
                                    vtol=vtol)  # fmt: skip
        if twice:
            status, found = status[::2], found[::2]
        sols.extend(found)
        for code, cnt in enumerate(np.bincount(status, minlength=len(Status.ORDER))):
            counts[Status.ORDER[code]] += int(cnt)
    return sum(n for *_, n in screened)


def _test_chunk(job):
    """Screen the modes of some breaking sets (:func:`~qsplan.mechanics.solver.screen.screen_sets`),
    then test the kept ones by the batch stages, in the process that runs the chunk.

    Returns (counts, solutions, modes of the sets)."""
    scene, tol, batch, residuals, sets = job
    pool = ScenePool(scene)
    screened = [screen_sets(ReducedScene(scene, tol, pool), _masks(sets, scene.n_contacts))]
    counts, sols = _new_counts(), []
    return counts, sols, _test_kept(scene, tol, batch, residuals, pool, screened, counts, sols)


def _in_threads(scene, tol, batch, residuals, threads, sets, max_programmes, progress):
    """The compiled screen on ``threads`` threads while this one solves the breaking-set programmes
    level by level; None when ``max_programmes`` is exceeded.

    The kernel releases the GIL.  While the programmes run, ``threads - 1`` helpers screen the
    sets found so far (a third thread would slow the programmes down 2-3x on two cores); then this
    thread joins them.  Pieces are screened in any order but kept in submission order, so the
    result does not depend on ``threads``.
    """
    n_c, dof = scene.n_contacts, scene.dof
    pool = ScenePool(scene)
    rs = ReducedScene(scene, tol, pool)
    screened, errors, helpers, total = [], [], [], count_modes(n_c, dof)

    def report():
        if progress:  # this thread only: a command's callback need not be thread-safe
            progress(sum(part[3] for part in screened if part is not None), total, "modes")

    def work(block: bool):
        while True:
            try:
                item = todo.get() if block else todo.get_nowait()
            except queue.Empty:
                return
            if item is None:
                return
            try:
                screened[item[0]] = screen_sets(rs, item[1])
            except BaseException as exc:  # noqa: BLE001 - re-raised in this thread below
                errors.append(exc)
            if not block:
                report()

    def submit(level):
        for part in _pieces(level, n_c, dof, SCREEN_PIECE_MODES):
            if not helpers:
                screened.append(screen_sets(rs, _masks(part, n_c)))
                report()
                continue
            screened.append(None)
            todo.put((len(screened) - 1, _masks(part, n_c)))

    if threads > 1:  # imported only here: ~5 ms that a small search does not need
        import queue
        import threading

        todo = queue.Queue()
        helpers = [threading.Thread(target=work, args=(True,), daemon=True) for _ in range(threads - 1)]
        for t in helpers:
            t.start()
    try:
        if sets is None:
            sets, _ = feasible_breaking_sets(scene, tol, max_programmes=max_programmes, witnesses=True, on_level=submit)
        else:
            submit(sets)
        if sets is not None and helpers:
            work(False)  # this thread helps with what is left
    except BaseException:  # Ctrl-C, a refused level: the helpers stop after their current piece
        while helpers and not todo.empty():
            todo.get_nowait()
        raise
    finally:
        for _ in helpers:
            todo.put(None)
        for t in helpers:
            t.join()
    if errors:
        raise errors[0]
    if sets is None:
        return None
    if progress:
        progress(total, total, "modes")
    counts, sols = _new_counts(), []
    return counts, sols, _test_kept(scene, tol, batch, residuals, pool, screened, counts, sols)


def modes_with_breaking_sets(n_c: int, dof: int, sets) -> int:
    """Number of modes with ``2 n_R + n_S = dof`` whose breaking set is in ``sets`` (the modes the search tests)."""
    return sum(_n_modes(n_c, dof, B) for B in sets)


def all_breaking_sets(n_c: int, dof: int):
    """Every breaking set of a mode with ``2 n_R + n_S = dof`` (eq. 29), by size then lexicographically (a generator)."""
    lo, hi = breaking_set_sizes(n_c, dof)
    for b in range(lo, hi + 1):
        yield from combinations(range(n_c), b)


def screen_all_seconds(n_c: int, dof: int) -> float:
    """Seconds, roughly, to screen every mode of eq. (49) (:func:`all_breaking_sets`, no programme), one core."""
    lo, hi = breaking_set_sizes(n_c, dof)
    return count_modes(n_c, dof) * SCREEN_MODE_SECONDS + sum(comb(n_c, b) for b in range(lo, hi + 1)) * SET_SECONDS


def search_solve(scene: Scene, tol: Tolerances = DEFAULT_TOLERANCES, batch: int = 8192, residuals: bool = True, *,
                 workers=1, scheduler=None, sets=None, progress=None, max_programmes=None, max_seconds=None):  # fmt: skip
    """Every feasible mode of ``scene``, testing only modes whose breaking set admits equilibrium.

    Same arguments and result as :func:`qsplan.mechanics.solve`; the counts carry
    :data:`PRUNED`, :data:`PRUNED_KINEMATIC` and :data:`PRUNED_COULOMB` for the modes never
    tested, and still sum to eq. (49).

    Parameters
    ----------
    sets : iterable of tuple, optional
        The breaking sets to screen, when already chosen (:func:`all_breaking_sets`: no programme);
        else those of :func:`~qsplan.mechanics.solver.breaking_sets.feasible_breaking_sets`.
    progress : callable, optional
        See :func:`qsplan.mechanics.parallel.map_chunks`.
    max_programmes : int, optional
        Return None rather than solve more breaking-set programmes.
    max_seconds : float, optional
        Return None when screening the kept sets' modes would take longer (:data:`SCREEN_MODE_SECONDS`):
        without the compiled screen, pruning can cost more than testing every mode.  (With it,
        screening a mode always costs less than testing it, and the sets are screened as found.)

    Returns
    -------
    SolveResult or None
    """
    n_c, dof = scene.n_contacts, scene.dof
    total = count_modes(n_c, dof)
    if KERNEL and scheduler is None:  # screen while the programmes run; test the few kept modes here
        threads = resolve_workers(workers) if screen_all_seconds(n_c, dof) * KEPT_SHARE >= THREAD_MIN_SECONDS else 1
        done = _in_threads(scene, tol, batch, residuals, threads, sets, max_programmes, progress)
        if done is None:
            return None
        parts = [done]
    else:
        if sets is None:
            sets, _ = feasible_breaking_sets(scene, tol, workers=workers, scheduler=scheduler,
                                             max_programmes=max_programmes, witnesses=True)  # fmt: skip
            if sets is None:
                return None
        sets = list(sets)
        n_modes = [_n_modes(n_c, dof, B) for B in sets]
        if max_seconds is not None and sum(n_modes) * SCREEN_MODE_SECONDS + len(sets) * SET_SECONDS > max_seconds:
            return None
        n_chunks = chunk_count(sum(n_modes), MIN_TEST_CHUNK, workers=workers, scheduler=scheduler)
        bounds = [0, len(sets)]
        if n_chunks > 1 or scheduler is not None:  # chunks of about equal numbers of modes
            edges = np.searchsorted(np.cumsum(n_modes), [sum(n_modes) * k / n_chunks for k in range(1, n_chunks)])
            bounds = [0, *(int(e) + 1 for e in edges), len(sets)]
        jobs = [(scene, tol, batch, residuals, sets[a:b]) for a, b in zip(bounds[:-1], bounds[1:]) if b > a]
        parts = map_chunks(_test_chunk, jobs, workers=workers, scheduler=scheduler, progress=progress)
    counts, sols, tested = _new_counts(), [], 0
    for c, s, n in parts:
        for k, v in c.items():
            counts[k] += v
        sols.extend(s)
        tested += n
    counts[PRUNED] = total - tested
    sols.sort(key=lambda s: mode_order_key(s.mode.letters))
    return SolveResult(scene=scene, modes_tested=total, solutions=tuple(sols), counts=counts, tolerances=tol)
