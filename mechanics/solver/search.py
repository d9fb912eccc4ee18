"""Every feasible contact mode without testing every mode (Section 4.7's future work), exactly.

The paper lists as future work finding all solutions without testing all
``count_modes(n_c, 3 + |tau_I|)`` modes (eq. 49).  :func:`search_solve` does it
in three steps, each exact:

1. Breaking sets that admit no equilibrium are pruned with all their modes
   (:mod:`qsplan.mechanics.solver.breaking_sets`: one linear programme per Apriori candidate).
   On random planted scenes all but a few percent of the modes go here, while
   kinematic relaxations (one per rolling set) rarely fail, which is why the
   search runs over breaking sets.
2. Within a surviving breaking set, ``v_n = 0`` at every other contact leaves
   a ``p``-dimensional motion (``p = n_R``); the rolling contacts fix it by a
   ``p x p`` solve, and modes whose breaking contacts clearly penetrate go
   (:func:`penetrates`), without the ``dof x dof`` solve of eq. (24).
3. The rest are tested by the plain batch stages
   (:func:`qsplan.mechanics.solver.batch.solve_batch`), so every reported solution is exactly
   the reference's.

Modes of steps 1 and 2 are counted under :data:`PRUNED` and
:data:`PRUNED_KINEMATIC`; the counts still sum to eq. (49).  Both the
programmes and the tests of step 3 run in chunks on local processes or a Dask
cluster (:func:`qsplan.mechanics.parallel.map_chunks`).
"""

from __future__ import annotations

from functools import lru_cache
from math import comb

import numpy as np

from qsplan.mechanics.solver.breaking_sets import feasible_breaking_sets
from qsplan.mechanics.modes.contact_mode import Letter, combinations_array, count_modes, mode_order_key
from qsplan.mechanics.modes.kinematics import ScenePool, velocity_scale
from qsplan.mechanics.numerics import DEFAULT_TOLERANCES, Status, Tolerances, hadamard_ratio
from qsplan.mechanics.parallel import chunk_count, map_chunks
from qsplan.mechanics.model.scene import Scene
from qsplan.mechanics.solver.batch import solve_batch
from qsplan.mechanics.solver.result import SolveResult

__all__ = [
    "PRUNED",
    "PRUNED_KINEMATIC",
    "penetrates",
    "MIN_TEST_CHUNK",
    "codes_with_breaking_sets",
    "modes_with_breaking_sets",
    "search_solve",
]

#: Status of the modes never tested because their breaking set admits no equilibrium.
PRUNED = "pruned_equilibrium_infeasible"


#: Status of the untested modes whose breaking contacts penetrate in the reduced system (:func:`penetrates`).
PRUNED_KINEMATIC = "pruned_breaking_violated"

#: A reduced kinematic system (``v_n = 0`` rows, or the ``p x p`` rolling rows) with a smaller
#: Hadamard ratio / singular-value ratio is not trusted to reject a mode: 1e-8 keeps its
#: rounding (1e-16 / 1e-8) far below :data:`PENETRATION_MARGIN`.
REDUCED_SINGULAR = 1e-8

#: Relative to the scene's driving speed: a breaking contact of the reduced solve must penetrate
#: by more than this to reject the mode without the reference test (1e3 times ``tol.velocity``'s
#: default, and 1e2 above the reduced solve's rounding).
PENETRATION_MARGIN = 1e-6

#: Rolling sets per reduced solve (memory: ``REDUCED_CHUNK * p * p * 8`` bytes, p <= 10 here).
REDUCED_CHUNK = 32768

#: Fewest modes worth a chunk of the testing stage in another process (~0.1 s of work).
MIN_TEST_CHUNK = 16384


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


@lru_cache(maxsize=64)
def _positions(n: int, k: int) -> np.ndarray:
    """:func:`qsplan.mechanics.modes.contact_mode.combinations_array`, cached: every breaking set of one size reuses it."""
    out = combinations_array(n, k)
    out.setflags(write=False)
    return out


def _rolling_sets(n_c: int, dof: int, B) -> tuple[np.ndarray, np.ndarray]:
    """The contacts ``A`` outside ``B`` and every rolling set of a mode with breaking set ``B``, shape (m, r)."""
    A = np.setdiff1d(np.arange(n_c), np.asarray(B, dtype=np.intp))
    return A, A[_positions(A.size, len(B) + dof - n_c)]


def penetrates(pool, B, A, R, margin: float) -> np.ndarray:
    """Modes (breaking set ``B``, rolling sets ``R``) whose breaking contacts surely penetrate (eq. 15).

    With ``B`` fixed, ``v_n = 0`` at every other contact (eq. 13) leaves
    ``x = [qdot; thetadot_I] = x0 + Z u`` with ``u`` of dimension ``p = |R|``; the rolling
    contacts' ``v_t = 0`` fix ``u`` by a ``p x p`` solve instead of the ``dof x dof`` one of
    eq. (24).  A mode is flagged only when that reduced system is well conditioned
    (:data:`REDUCED_SINGULAR`) and some breaking contact has ``v_n < -margin``; the
    reference then finds ``v_n < -tol.velocity`` there too (or ``P_AI`` singular).

    Parameters
    ----------
    pool : ScenePool
    B, A : ndarray of int
        Breaking contacts and the others.
    R : ndarray of int, shape (m, p)
    margin : float
        m/s, well above the rounding of the reduced solve.

    Returns
    -------
    ndarray of bool, shape (m,)
    """
    n_c = pool.Wrows.shape[0] // 2
    N, T = pool.M[:n_c], pool.M[n_c:]
    dn, dt = pool.drive[:n_c], pool.drive[n_c:]
    m = R.shape[0]
    out = np.zeros(m, dtype=bool)
    if len(B) == 0 or m == 0:
        return out
    NA = N[A]
    U, sv, Vt = np.linalg.svd(NA)
    if sv.size and sv[-1] < REDUCED_SINGULAR * sv[0]:
        return out  # v_n = 0 at A is (nearly) dependent: leave these modes to the reference
    x0 = Vt[: A.size].T @ ((U.T @ dn[A]) / sv)
    Z = Vt[A.size :].T  # (dof, p)
    TZ, tx = T @ Z, dt - T @ x0  # v_t = T x0 + TZ u - dt
    NBZ, nbx = N[B] @ Z, N[B] @ x0 - dn[B]
    for lo in range(0, m, REDUCED_CHUNK):
        Rs = R[lo : lo + REDUCED_CHUNK]
        G = TZ[Rs]  # (k, p, p)
        good = hadamard_ratio(G) >= REDUCED_SINGULAR
        G[~good] = np.eye(G.shape[1])
        u = np.linalg.solve(G, tx[Rs][..., None])[..., 0]
        vB = u @ NBZ.T + nbx  # (k, b)
        out[lo : lo + REDUCED_CHUNK] = good & np.any(vB < -margin, axis=1)
    return out


def _test_chunk(job):
    """Test the modes of some breaking sets: the reduced penetration test, then the batch stages.

    Returns (counts, solutions)."""
    scene, tol, batch, residuals, sets = job
    n_c, dof = scene.n_contacts, scene.dof
    pool = ScenePool(scene)
    vscale = velocity_scale(scene)
    vtol, margin = tol.velocity * vscale, PENETRATION_MARGIN * vscale
    counts = dict.fromkeys((*Status.ORDER, PRUNED_KINEMATIC), 0)
    sols, buf, held = [], [], 0

    def flush():
        nonlocal buf, held
        codes = np.concatenate(buf)
        buf, held = [], 0
        status, found = solve_batch(scene, codes, tol, residuals, pool=pool, vtol=vtol)
        sols.extend(found)
        for code, cnt in enumerate(np.bincount(status, minlength=len(Status.ORDER))):
            counts[Status.ORDER[code]] += int(cnt)

    for B in sets:
        if not 0 <= len(B) + dof - n_c <= n_c - len(B):
            continue
        A, R = _rolling_sets(n_c, dof, B)
        keep = ~penetrates(pool, np.asarray(B, dtype=np.intp), A, R, margin)
        counts[PRUNED_KINEMATIC] += int(R.shape[0] - keep.sum())
        R = R[keep]
        for lo in range(0, R.shape[0], batch):
            buf.append(_codes(n_c, A, R[lo : lo + batch]))
            held += buf[-1].shape[0]
            if held >= batch:
                flush()
    if held:
        flush()
    return counts, sols


def modes_with_breaking_sets(n_c: int, dof: int, sets) -> int:
    """Number of modes with ``2 n_R + n_S = dof`` whose breaking set is in ``sets`` (the modes the search tests)."""
    return sum(_n_modes(n_c, dof, B) for B in sets)


def search_solve(scene: Scene, tol: Tolerances = DEFAULT_TOLERANCES, batch: int = 8192, residuals: bool = True, *,
                 workers=1, scheduler=None, sets=None, progress=None):  # fmt: skip
    """Every feasible mode of ``scene``, testing only modes whose breaking set admits equilibrium.

    Same arguments and result as :func:`qsplan.mechanics.solve`; the counts carry
    :data:`PRUNED` for the modes never tested, and still sum to eq. (49).  ``sets``: the
    breaking sets of :func:`feasible_breaking_sets`, when already found; ``progress``: see
    :func:`qsplan.mechanics.parallel.map_chunks`.
    """
    n_c, dof = scene.n_contacts, scene.dof
    total = count_modes(n_c, dof)
    if sets is None:
        sets, _ = feasible_breaking_sets(scene, tol, workers=workers, scheduler=scheduler)
    n_modes = [_n_modes(n_c, dof, B) for B in sets]
    tested = sum(n_modes)
    n_chunks = chunk_count(tested, MIN_TEST_CHUNK, workers=workers, scheduler=scheduler)
    if n_chunks == 1 and scheduler is None:
        parts = [_test_chunk((scene, tol, batch, residuals, sets))]
    else:  # split the sets into chunks of about equal numbers of modes
        edges = np.searchsorted(np.cumsum(n_modes), [tested * k / n_chunks for k in range(1, n_chunks)], side="left")
        bounds = [0, *(int(e) + 1 for e in edges), len(sets)]
        jobs = [(scene, tol, batch, residuals, sets[a:b]) for a, b in zip(bounds[:-1], bounds[1:]) if b > a]
        parts = map_chunks(_test_chunk, jobs, workers=workers, scheduler=scheduler, progress=progress)
    counts = dict.fromkeys((*Status.ORDER, PRUNED_KINEMATIC), 0)
    sols = []
    for c, s in parts:
        for k, v in c.items():
            counts[k] += v
        sols.extend(s)
    counts[PRUNED] = total - tested
    sols.sort(key=lambda s: mode_order_key(s.mode.letters))
    return SolveResult(scene=scene, modes_tested=total, solutions=tuple(sols), counts=counts, tolerances=tol)
