"""Every feasible contact mode without testing every mode: breaking sets pruned by equilibrium (Section 4.7).

The paper lists as future work finding all solutions without testing all
``count_modes(n_c, 3 + |tau_I|)`` modes (eq. 49).  The search here is exact.

A mode's breaking set ``B`` carries no force: ``c_n = c_t = 0`` there, and
every other contact's force lies in its friction cone (eq. 28; a sliding force
is on the edge of the cone, eq. 17).  So if no force ``c`` with ``c_B = 0`` and
every other ``c_i`` in its (slightly widened) cone satisfies the equilibrium
rows of eq. (26),

    [W_n; J_nI^T] c_n + [W_t; J_tI^T] c_t = [-g_obj; tau_I - g_I],

no mode with breaking set ``B`` can pass the Coulomb test (28), and nor can a
mode whose breaking set contains ``B`` (the constraint set only shrinks).  That
*equilibrium relaxation* is one small linear programme per breaking set.  On
random planted scenes it fails for all but a few percent of the breaking sets,
while the kinematic relaxations (one per rolling set) rarely fail, which is why
the search runs over breaking sets.

The breaking sets are visited level by level (``|B| = 0, 1, ...``), as in the
Apriori algorithm: a set is a candidate only when every subset one smaller
admits equilibrium, so most infeasible sets are discarded without a programme.
The modes of the surviving breaking sets are tested by the plain batch stages
(:func:`mechanics.solver.test_codes`), so every reported solution is exactly the
reference's; the others are counted under :data:`PRUNED`, and the counts still
sum to eq. (49).

Tolerances: the reference accepts a Coulomb slack down to ``-tol.force * F``,
``F`` the largest load or force of the mode.  The programme widens every cone
inequality by ``CONE_WIDENING * max(1, mu) * tol.force * FORCE_RATIO`` times the
largest load, which contains every force the reference accepts whose largest
component is at most ``FORCE_RATIO`` times the largest load (2 in the widening
covers a sliding contact at ``c_n = -ftol``, the rest is margin for rounding).
A mode could only be lost if the reference accepted it *because of* its
tolerance (``on_boundary``) with forces over ``FORCE_RATIO`` times the loads,
that is with ``Q_AI`` (eq. 26) within a factor ``1 / FORCE_RATIO`` of
singular.  (The tolerance relative to ``F`` is not a convex condition: a
programme with ``F`` as a variable can always make ``F`` large enough to accept
anything, so some cap is needed.)  HiGHS's own tolerances only loosen the
programme further.
"""

from __future__ import annotations

from math import comb

import numpy as np

from .modes import _combinations, count_modes, mode_order_key
from .numerics import DEFAULT_TOLERANCES, Status, Tolerances
from .parallel import chunk_count, map_chunks, split_range
from .scene import Scene

__all__ = [
    "PRUNED",
    "CONE_WIDENING",
    "FORCE_RATIO",
    "MIN_LP_CHUNK",
    "EquilibriumRelaxation",
    "equilibrium_relaxation",
    "admits_equilibrium",
    "feasible_breaking_sets",
    "codes_with_breaking_sets",
    "search_solve",
]

#: Status of the modes never tested because their breaking set admits no equilibrium.
PRUNED = "pruned_equilibrium_infeasible"

#: Factor on ``max(1, mu) * tol.force``: 2 covers a sliding contact whose ``c_n`` is
#: ``-ftol`` (both cone rows then lose ``2 mu ftol``); 4 leaves a margin for rounding.
CONE_WIDENING = 4.0

#: Largest ratio of a mode's forces to its loads up to which the widened cones contain
#: every force the reference accepts: 1e6 is far beyond well-posed grasps (forces within
#: a few orders of the loads) and keeps the widening (4e-3 of the loads at mu <= 1) small.
FORCE_RATIO = 1e6

#: Fewest candidate breaking sets (one programme of ~2-5 ms each) worth a chunk in another process.
MIN_LP_CHUNK = 48

#: Fewest modes worth a chunk of the testing stage in another process (~0.1 s of work).
MIN_TEST_CHUNK = 16384


class EquilibriumRelaxation:
    """The equilibrium relaxation of one scene (rows of eq. 26 over all contacts, cones of eq. 28).

    Variables are ``(c_n[0], c_t[0], ..., c_n[n_c-1], c_t[n_c-1])``; a breaking set
    only fixes its contacts' forces to zero through the bounds.

    Attributes
    ----------
    A_eq : ndarray, shape (dof, 2 n_c)
    b_eq : ndarray, shape (dof,)
        ``[-g_obj; tau_I - g_I]`` divided by its largest magnitude.
    A_ub : ndarray, shape (3 n_c, 2 n_c)
    b_ub : ndarray, shape (3 n_c,)
        Widened cone rows ``-mu c_n -+ c_t <= w``, ``-c_n <= w`` (eqs. 28, 9).
    trivial : bool
        The loads vanish: ``c = 0`` balances them, so no breaking set can be pruned.
    """

    def __init__(self, scene: Scene, tol: Tolerances):
        n = scene.n_contacts
        E = scene.effort_joints
        rhs = np.concatenate([-scene.g_obj, np.nan_to_num(scene.joint_effort)[E] - scene.g_man[E]])
        scale = float(np.max(np.abs(rhs))) if rhs.size else 0.0
        self.n_contacts = n
        self.trivial = not scale > 0
        self.A_eq = np.zeros((rhs.size, 2 * n))
        self.A_eq[:, 0::2] = np.vstack([scene.Wn, scene.Jn[:, E].T])  # columns of Q_AI for c_n (eq. 26)
        self.A_eq[:, 1::2] = np.vstack([scene.Wt, scene.Jt[:, E].T])
        self.b_eq = rhs / scale if scale > 0 else rhs
        rows = np.zeros((n, 3, 2 * n))
        i = np.arange(n)
        rows[i, 0, 2 * i], rows[i, 0, 2 * i + 1] = -scene.mu, 1.0
        rows[i, 1, 2 * i], rows[i, 1, 2 * i + 1] = -scene.mu, -1.0
        rows[i, 2, 2 * i] = -1.0
        self.A_ub = rows.reshape(3 * n, 2 * n)
        w = CONE_WIDENING * max(1.0, float(np.max(scene.mu, initial=0.0))) * tol.force * FORCE_RATIO
        self.b_ub = np.full(3 * n, w)


def equilibrium_relaxation(scene: Scene, tol: Tolerances = DEFAULT_TOLERANCES) -> EquilibriumRelaxation:
    """The equilibrium relaxation of ``scene`` (see :class:`EquilibriumRelaxation`)."""
    return EquilibriumRelaxation(scene, tol)


def admits_equilibrium(rel: EquilibriumRelaxation, breaking) -> bool:
    """Whether some force with ``c = 0`` on ``breaking`` and cones elsewhere balances the loads.

    False proves that no mode whose breaking set contains ``breaking`` passes eq. (28).

    Parameters
    ----------
    rel : EquilibriumRelaxation
    breaking : iterable of int
        0-based contact indices.
    """
    from scipy.optimize import linprog

    if rel.trivial:
        return True
    bounds = [(None, None)] * (2 * rel.n_contacts)
    for i in breaking:
        bounds[2 * i] = bounds[2 * i + 1] = (0.0, 0.0)
    res = linprog(
        np.zeros(rel.A_eq.shape[1]), A_ub=rel.A_ub, b_ub=rel.b_ub, A_eq=rel.A_eq, b_eq=rel.b_eq,
        bounds=bounds, method="highs",
    )  # fmt: skip
    return res.status != 2  # 2: proven infeasible; anything else (solved, iteration limit) keeps the set


def _lp_chunk(job):
    rel, sets = job
    return [admits_equilibrium(rel, s) for s in sets]


def _breaking_range(n_c: int, dof: int) -> tuple[int, int]:
    """Sizes of the breaking sets of modes with ``2 n_R + n_S = dof`` (eq. 29): ``n_R = |B| + dof - n_c``."""
    return max(0, n_c - dof), (2 * n_c - dof) // 2


def _candidates(level: list[tuple], feasible: set) -> list[tuple]:
    """Sets one larger whose every subset one smaller is in ``feasible`` (Apriori join), sorted."""
    out = []
    for a in range(len(level)):
        pa = level[a]
        for b in range(a + 1, len(level)):
            pb = level[b]
            if pa[:-1] != pb[:-1]:
                break  # level is sorted: sets sharing a prefix are consecutive
            cand = pa + (pb[-1],)
            if all(cand[:j] + cand[j + 1 :] in feasible for j in range(len(cand) - 2)):
                out.append(cand)
    return out


def _check_sets(rel, sets, workers, scheduler) -> list[bool]:
    n_chunks = chunk_count(len(sets), MIN_LP_CHUNK, workers=workers, scheduler=scheduler)
    if n_chunks == 1 and scheduler is None:
        return _lp_chunk((rel, sets))
    jobs = [(rel, sets[lo:hi]) for lo, hi in split_range(len(sets), n_chunks)]
    return [ok for part in map_chunks(_lp_chunk, jobs, workers=workers, scheduler=scheduler) for ok in part]


def feasible_breaking_sets(scene: Scene, tol: Tolerances = DEFAULT_TOLERANCES, *, workers=1, scheduler=None):
    """Breaking sets of the scene's modes that admit equilibrium, level by level (Apriori).

    Returns
    -------
    sets : list of tuple of int
        Sorted 0-based breaking sets with sizes of the scene's modes (eq. 29) that admit equilibrium.
    programmes : int
        Linear programmes solved.
    """
    n_c, dof = scene.n_contacts, scene.dof
    lo, hi = _breaking_range(n_c, dof)
    rel = equilibrium_relaxation(scene, tol)
    level, programmes, out = [()], 1, []
    if not admits_equilibrium(rel, ()):
        return out, programmes
    for size in range(0, hi + 1):
        if size >= lo:
            out.extend(level)
        if size == hi:
            break
        if size == 0:
            cands = [(i,) for i in range(n_c)]
        else:
            cands = _candidates(level, set(level))
        if not cands:
            break
        ok = _check_sets(rel, cands, workers, scheduler)
        programmes += len(cands)
        level = [c for c, good in zip(cands, ok) if good]
    return out, programmes


def codes_with_breaking_sets(n_c: int, dof: int, sets) -> np.ndarray:
    """Letter codes (0 B, 1 R, 2 S) of every mode with ``2 n_R + n_S = dof`` whose breaking set is in ``sets``.

    Returns
    -------
    ndarray of uint8, shape (m, n_c)
        ``m = sum C(n_c - |B|, |B| + dof - n_c)`` over the sets.
    """
    parts = []
    for B in sets:
        b = len(B)
        r = b + dof - n_c
        if r < 0 or n_c - b - r < 0:
            continue
        A = np.setdiff1d(np.arange(n_c), np.asarray(B, dtype=np.intp))
        R = A[_combinations(A.size, r)]  # (C(n_c - b, r), r)
        codes = np.zeros((R.shape[0], n_c), dtype=np.uint8)
        codes[:, A] = 2
        codes[np.arange(R.shape[0])[:, None], R] = 1
        parts.append(codes)
    return np.concatenate(parts) if parts else np.zeros((0, n_c), dtype=np.uint8)


def _n_modes(n_c, dof, B) -> int:
    b = len(B)
    return comb(n_c - b, b + dof - n_c) if 0 <= b + dof - n_c <= n_c - b else 0


def _test_chunk(job):
    """Test every mode of some breaking sets with the batch stages; return (counts, solutions)."""
    from .solver import test_codes

    scene, tol, batch, residuals, sets = job
    counts = dict.fromkeys(Status.ORDER, 0)
    sols = []
    start = 0
    while start < len(sets):  # group sets into batches of about ``batch`` modes
        stop, m = start, 0
        while stop < len(sets) and (m == 0 or m + _n_modes(scene.n_contacts, scene.dof, sets[stop]) <= batch):
            m += _n_modes(scene.n_contacts, scene.dof, sets[stop])
            stop += 1
        codes = codes_with_breaking_sets(scene.n_contacts, scene.dof, sets[start:stop])
        for lo in range(0, codes.shape[0], batch):
            status, found = test_codes(scene, codes[lo : lo + batch], tol, residuals)
            sols.extend(found)
            for code, cnt in enumerate(np.bincount(status, minlength=len(Status.ORDER))):
                counts[Status.ORDER[code]] += int(cnt)
        start = stop
    return counts, sols


def search_solve(scene: Scene, tol: Tolerances = DEFAULT_TOLERANCES, batch: int = 8192, residuals: bool = True, *,
                 workers=1, scheduler=None):  # fmt: skip
    """Every feasible mode of ``scene``, testing only modes whose breaking set admits equilibrium.

    Same arguments and result as :func:`mechanics.solver.solve`; the counts carry
    :data:`PRUNED` for the modes never tested, and still sum to eq. (49).
    """
    from .solver import SolveResult

    n_c, dof = scene.n_contacts, scene.dof
    total = count_modes(n_c, dof)
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
        parts = map_chunks(_test_chunk, jobs, workers=workers, scheduler=scheduler)
    counts = dict.fromkeys(Status.ORDER, 0)
    sols = []
    for c, s in parts:
        for k, v in c.items():
            counts[k] += v
        sols.extend(s)
    counts[PRUNED] = total - tested
    sols.sort(key=lambda s: mode_order_key(s.mode.letters))
    return SolveResult(scene=scene, modes_tested=total, solutions=tuple(sols), counts=counts, tolerances=tol)
