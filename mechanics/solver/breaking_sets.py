"""Breaking sets that admit equilibrium: the relaxation that prunes contact modes (eqs. 17, 26, 28).

A mode's breaking set ``B`` carries no force: ``c_n = c_t = 0`` there, and
every other contact's force lies in its friction cone (eq. 28; a sliding force
is on the edge of the cone, eq. 17).  So if no force ``c`` with ``c_B = 0`` and
every other ``c_i`` in its (slightly widened) cone satisfies the equilibrium
rows of eq. (26),

    [W_n; J_nI^T] c_n + [W_t; J_tI^T] c_t = [-g_obj; tau_I - g_I],

no mode with breaking set ``B`` passes the Coulomb test (28), and nor does a
mode whose breaking set contains ``B`` (the constraint set only shrinks).  This
*equilibrium relaxation* is one small linear programme per breaking set.
:func:`feasible_breaking_sets` visits the sets level by level (``|B| = 0, 1,
...``), as in the Apriori algorithm: a set is a candidate only when every subset
one smaller admits equilibrium, so most infeasible sets go without a programme.

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

The programmes are solved by the compiled kernel (``relax`` in ``screen_kernel.c``, ~65 us a set
at n_c = 20 against ~0.4 ms with HiGHS) when it is built: Phase 1 of a small dense simplex on
the cones written with nonnegative columns (:meth:`EquilibriumRelaxation.columns`).  It decides
nothing on trust: a set is kept when the basic solution, recomputed from the data, balances the
loads within :data:`RELAX_RESIDUAL`, and pruned only when its last multipliers pass as a Farkas
certificate checked from the data: every force in the widened cones that balances the loads
would need normal forces summing to more than :data:`PROOF_RATIO` times the largest load (beyond
:data:`FORCE_RATIO`'s cap above).  Any other outcome falls back to HiGHS (``compiled=False``:
HiGHS for every set, the reference).
"""

from __future__ import annotations

import numpy as np

from qsplan.mechanics.errors import QsplanError
from qsplan.mechanics.numerics import DEFAULT_TOLERANCES, Tolerances
from qsplan.mechanics.parallel import chunk_count, map_chunks, split_range
from qsplan.mechanics.model.scene import Scene
from qsplan.mechanics.quiet import quiet_highs
from qsplan.mechanics.solver.screen import compiled_relax

__all__ = [
    "CONE_WIDENING",
    "FORCE_RATIO",
    "PROOF_RATIO",
    "RELAX_RESIDUAL",
    "RELAX_PIVOTS_PER_ROW",
    "RELAX_PRICE_TOL",
    "RELAX_PIVOT_TOL",
    "CERTIFICATE_MARGIN",
    "MIN_LP_CHUNK",
    "MIN_COMPILED_CHUNK",
    "MAX_LEVEL_SETS",
    "WITNESS_ZERO",
    "EquilibriumRelaxation",
    "equilibrium_relaxation",
    "admits_equilibrium",
    "feasible_breaking_sets",
    "breaking_set_sizes",
]

#: Factor on ``max(1, mu) * tol.force``: 2 covers a sliding contact whose ``c_n`` is
#: ``-ftol`` (both cone rows then lose ``2 mu ftol``); 4 leaves a margin for rounding.
CONE_WIDENING = 4.0

#: Largest ratio of a mode's forces to its loads up to which the widened cones contain
#: every force the reference accepts: 1e6 is far beyond well-posed grasps (forces within
#: a few orders of the loads) and keeps the widening (4e-3 of the loads at mu <= 1) small.
FORCE_RATIO = 1e6

#: Fewest candidate breaking sets (one programme of ~0.5 ms each with highspy) worth a chunk in
#: another process (~0.1 s of work, several times a local pool's start-up).
MIN_LP_CHUNK = 200

#: The same with the compiled kernel (~65 us a set at n_c = 20): ~0.3 s of work a chunk.
MIN_COMPILED_CHUNK = 5000

#: The compiled programme's proof of infeasibility: a Farkas certificate whose rounding-level
#: violations (~1e-15) would let only forces with normal components summing to more than this many
#: times the largest load balance the loads.  1e9 is ``1 / Tolerances.force``'s default: at such
#: forces the reference's own Coulomb tolerance (``tol.force * F``) is as large as the loads, so its
#: verdict there means nothing (and it is 1e3 times :data:`FORCE_RATIO`, whose argument already sets
#: aside modes with forces over 1e6 loads).  Measured at n_c = 20: the certificates of nearly feasible
#: sets (margin ~3e-4 of the loads) prove 1e10-1e11; none fell short of 1e9.
PROOF_RATIO = 1e9

#: Largest equilibrium residual (in units of the largest load, as the rows) of a basic solution the
#: compiled programme calls feasible: 1e-9, far above its rounding (~1e-14 measured at n_c = 20) and
#: far below the widening (4e-3); calling a set feasible only keeps it, which is always safe.
RELAX_RESIDUAL = 1e-9

#: The compiled programme gives up (HiGHS decides) after this many pivots per equilibrium row:
#: measured ~1-2 per row; the cap only guards against cycling that Bland's rule did not break.
RELAX_PIVOTS_PER_ROW = 50

#: A column enters the compiled programme's basis when it lowers the phase-1 objective by more than
#: this per unit of its norm: above the rounding of a dot product of O(1) terms (~1e-15), and small
#: enough that the multipliers left violate the certificate by no more (see :data:`PROOF_RATIO`).
RELAX_PRICE_TOL = 1e-11

#: Entries of a basis direction smaller than this are not pivots of the compiled programme (the
#: ratio test skips them): same order as :data:`RELAX_PRICE_TOL`, for the same reason.
RELAX_PIVOT_TOL = 1e-11

#: A Farkas certificate's margin must exceed its rounding: this times ``|y|_1 max(1, |r|_inf)``,
#: some 1e6 above the rounding of the dot products it sums.
CERTIFICATE_MARGIN = 1e-9


#: With ``witnesses``, a force "vanishes" at a contact when both its components are within this
#: many cone widenings (``b_ub``, in units of the largest load: 8e-3 of the loads by default) of
#: zero: a candidate where it vanishes balances the loads up to a residual of that order, a
#: relaxation of the same kind as the widening.  Only programmes are skipped: every set that
#: admits equilibrium is still kept.  Measured on the planted n_c = 20 scene of
#: ``benchmarks/bench_scale.py``: 1, 2, 4 widenings solve 1317, 691, 540 of the 4113 programmes and
#: keep 8.63, 9.19, 9.84 M modes (8.12 M in the exact sets); 2 costs least with the compiled
#: screen (~70 ns a mode against ~0.3 ms a programme).
WITNESS_ZERO = 2.0

#: Most candidate breaking sets one Apriori level may hold (memory: ~250 bytes a set as tuples
#: and hash entries, so ~125 MB; time: ~100 s of programmes).  With few effort joints the
#: breaking sets of the modes are large (``|B| >= n_c - dof``) and the levels below them hold
#: up to C(n_c, n_c / 2) sets: at n_c = 40 an unbounded search reached 9.5 GB.
MAX_LEVEL_SETS = 500_000


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
        self.mu = np.asarray(scene.mu, dtype=float)
        self._columns = None

    def columns(self) -> dict:
        """The widened cones with nonnegative columns, for the compiled programme (cached).

        Every widened cone ``{c_n >= -w, |c_t| <= w + mu c_n}`` is exactly ``base + z_1 (1, mu) +
        z_2 (1, -mu) + z_3 (0, 1)``, ``z >= 0``: for ``mu < 1`` with ``base = (-w, -w (1 - mu))``
        (a corner) and ``z_3 <= 2 w (1 - mu)`` (the segment ``c_n = -w``); for ``mu >= 1`` the row
        ``c_n >= -w`` is implied, ``base = (-w / mu, 0)`` (the apex) and there is no ``z_3``.

        Returns
        -------
        dict of contiguous arrays: ``G`` (N, dof) the columns' equilibrium rows, ``ub`` (N,)
        (inf: none), ``gnorm`` (N,), ``owner`` (N,) int32 contacts, ``dir`` (N, 2) the force per
        unit, ``shift`` (n_c, dof) each base's rows, ``base`` (n_c, 2), ``b`` (dof,).
        """
        if self._columns is None:
            n, w, mu = self.n_contacts, float(self.b_ub[0]) if self.b_ub.size else 0.0, self.mu
            wide = mu >= 1.0
            base = np.where(wide[:, None], np.stack([-w / np.maximum(mu, 1.0), 0.0 * mu], 1),
                            np.stack([-w + 0.0 * mu, -w * (1.0 - mu)], 1))  # fmt: skip
            owner, dirs, ub = [], [], []
            for i in range(n):
                owner += [i, i]
                dirs += [(1.0, mu[i]), (1.0, -mu[i])]
                ub += [np.inf, np.inf]
                if not wide[i]:
                    owner.append(i)
                    dirs.append((0.0, 1.0))
                    ub.append(2.0 * w * (1.0 - mu[i]))
            owner = np.array(owner, dtype=np.int32)
            dirs = np.array(dirs, dtype=float).reshape(-1, 2)
            En, Et = self.A_eq[:, 0::2], self.A_eq[:, 1::2]
            G = np.ascontiguousarray((En[:, owner] * dirs[:, 0] + Et[:, owner] * dirs[:, 1]).T)
            self._columns = dict(
                G=G, ub=np.array(ub, dtype=float), gnorm=np.linalg.norm(G, axis=1), owner=owner,
                dir=np.ascontiguousarray(dirs), shift=np.ascontiguousarray((En * base[:, 0] + Et * base[:, 1]).T),
                base=np.ascontiguousarray(base), b=np.ascontiguousarray(self.b_eq, dtype=float),
            )  # fmt: skip
        return self._columns


def equilibrium_relaxation(scene: Scene, tol: Tolerances = DEFAULT_TOLERANCES) -> EquilibriumRelaxation:
    """The equilibrium relaxation of ``scene`` (see :class:`EquilibriumRelaxation`)."""
    return EquilibriumRelaxation(scene, tol)


class _Programme:
    """The relaxation as a reusable linear programme: HiGHS through ``highspy`` when installed
    (one model, only the bounds change, warm-started: ~0.5 ms a set), else ``scipy.optimize.linprog``
    (~5 ms a set, mostly its input checks)."""

    def __init__(self, rel: EquilibriumRelaxation):
        self.rel = rel
        self.n_vars = rel.A_eq.shape[1]
        try:
            import highspy
        except ImportError:
            self.highs = None
            return
        h = quiet_highs(highspy)  # highspy prints a banner on descriptor 1 when built (see qsplan.mechanics.quiet)
        h.setOptionValue("simplex_strategy", 1)  # dual simplex: the bounds change, the last basis stays dual feasible
        inf = highspy.kHighsInf
        h.addVars(self.n_vars, np.full(self.n_vars, -inf), np.full(self.n_vars, inf))
        A = np.vstack([rel.A_eq, rel.A_ub])
        nz = A != 0  # compressed rows by hand: scipy.sparse alone costs ~0.15 s of import on the `modes` path
        starts = np.concatenate([[0], np.cumsum(nz.sum(axis=1))[:-1]]).astype(np.int32)
        lower = np.concatenate([rel.b_eq, np.full(rel.b_ub.size, -inf)])
        upper = np.concatenate([rel.b_eq, rel.b_ub])
        h.addRows(A.shape[0], lower, upper, int(nz.sum()), starts, np.nonzero(nz)[1].astype(np.int32), A[nz])
        self.highs, self.infeasible, self.inf = h, highspy.HighsModelStatus.kInfeasible, inf
        self.optimal = highspy.HighsModelStatus.kOptimal
        self.cols = np.arange(self.n_vars, dtype=np.int32)

    def __call__(self, breaking) -> bool:
        return self.solve(breaking)[0]

    def solve(self, breaking):
        """``(admits, force)``: False only with a proof of infeasibility; ``force``, shape (2 n_c,), a
        solution ``(c_n[0], c_t[0], ...)`` in units of the largest load when one was found, else None."""
        if self.rel.trivial:
            return True, np.zeros(self.n_vars)
        fixed = [j for i in breaking for j in (2 * i, 2 * i + 1)]
        if self.highs is None:
            from scipy.optimize import linprog

            bounds = [(None, None)] * self.n_vars
            for j in fixed:
                bounds[j] = (0.0, 0.0)
            res = linprog(
                np.zeros(self.n_vars), A_ub=self.rel.A_ub, b_ub=self.rel.b_ub, A_eq=self.rel.A_eq,
                b_eq=self.rel.b_eq, bounds=bounds, method="highs",
            )  # fmt: skip
            return res.status != 2, (res.x if res.status == 0 else None)  # 2: proven infeasible; else kept
        lower = np.full(self.n_vars, -self.inf)
        upper = np.full(self.n_vars, self.inf)
        lower[fixed] = upper[fixed] = 0.0
        self.highs.changeColsBounds(self.n_vars, self.cols, lower, upper)
        self.highs.run()
        status = self.highs.getModelStatus()
        if status == self.optimal:
            return True, np.array(self.highs.getSolution().col_value)
        return status != self.infeasible, None  # only a proof of infeasibility prunes


def admits_equilibrium(rel: EquilibriumRelaxation, breaking) -> bool:
    """Whether some force with ``c = 0`` on ``breaking`` and cones elsewhere balances the loads.

    False proves that no mode whose breaking set contains ``breaking`` passes eq. (28).

    Parameters
    ----------
    rel : EquilibriumRelaxation
    breaking : iterable of int
        0-based contact indices.
    """
    return _Programme(rel)(breaking)


def _decide(rel: EquilibriumRelaxation, sets, compiled: bool) -> list:
    """``(admits, force or None)`` of every set: the compiled programme first (when ``compiled``), HiGHS
    for the sets it leaves undecided (and for all of them without it)."""
    if rel.trivial:  # c = 0 balances the loads: every set admits it (no programme, no HiGHS import)
        return [(True, np.zeros(2 * rel.n_contacts)) for _ in sets]
    out = [None] * len(sets)
    if compiled and sets:
        cols, n = rel.columns(), rel.n_contacts
        masks = np.zeros((len(sets), n), dtype=np.uint8)
        masks[np.repeat(np.arange(len(sets)), [len(B) for B in sets]), [i for B in sets for i in B]] = 1
        raw, forces = compiled_relax(
            cols["G"], cols["ub"], cols["gnorm"], cols["owner"], cols["dir"], cols["shift"], cols["base"], cols["b"],
            masks, n, cols["G"].shape[1], cols["G"].shape[0], RELAX_PIVOTS_PER_ROW * cols["G"].shape[1],
            RELAX_PRICE_TOL, RELAX_PIVOT_TOL, RELAX_RESIDUAL, CERTIFICATE_MARGIN, PROOF_RATIO,
        )  # fmt: skip
        status = np.frombuffer(raw, dtype=np.int8)
        forces = np.frombuffer(forces, dtype=float).reshape(len(sets), 2 * n)
        for k, st in enumerate(status):
            if st >= 0:
                out[k] = (True, forces[k].copy()) if st == 1 else (False, None)
    if any(v is None for v in out):
        programme = _Programme(rel)
        out = [programme.solve(B) if v is None else v for B, v in zip(sets, out)]
    return out


def _lp_chunk(job):
    rel, sets, compiled = job
    return _decide(rel, sets, compiled)


def breaking_set_sizes(n_c: int, dof: int) -> tuple[int, int]:
    """Sizes of the breaking sets of modes with ``2 n_R + n_S = dof`` (eq. 29): ``n_R = |B| + dof - n_c``."""
    return max(0, n_c - dof), (2 * n_c - dof) // 2


def _candidates(level: list[tuple], feasible: set, cap: int) -> list[tuple] | None:
    """Sets one larger whose every subset one smaller is in ``feasible`` (Apriori join), sorted;
    None as soon as there are more than ``cap`` of them (or ``8 cap`` joins were tried)."""
    out, joins = [], 0
    for a in range(len(level)):
        pa = level[a]
        for b in range(a + 1, len(level)):
            pb = level[b]
            if pa[:-1] != pb[:-1]:
                break  # level is sorted: sets sharing a prefix are consecutive
            joins += 1
            cand = pa + (pb[-1],)
            if all(cand[:j] + cand[j + 1 :] in feasible for j in range(len(cand) - 2)):
                out.append(cand)
        if len(out) > cap or joins > 8 * cap:
            return None
    return out


def _check_sets(rel, sets, workers, scheduler, compiled=False) -> list:
    """``(admits, force or None)`` of every set, on local processes or a cluster when there are many."""
    least = MIN_COMPILED_CHUNK if compiled else MIN_LP_CHUNK
    n_chunks = chunk_count(len(sets), least, workers=workers, scheduler=scheduler)
    if n_chunks == 1 and scheduler is None:
        return _decide(rel, sets, compiled)
    jobs = [(rel, sets[lo:hi], compiled) for lo, hi in split_range(len(sets), n_chunks)]
    return [ok for part in map_chunks(_lp_chunk, jobs, workers=workers, scheduler=scheduler) for ok in part]


def _vanishing(force, zero: float) -> np.ndarray:
    """Contacts where ``force`` (``(c_n[0], c_t[0], ...)``) is within ``zero`` of 0, shape (n_c,) bool."""
    return (np.abs(force[0::2]) <= zero) & (np.abs(force[1::2]) <= zero)


def _witnessed(cands: list, vanish: list) -> np.ndarray:
    """Which candidates lie inside the vanishing set of some force found so far, shape (len(cands),) bool."""
    out = np.zeros(len(cands), dtype=bool)
    if not vanish or not cands:
        return out
    V, C = np.array(vanish), np.array(cands)
    step = max(1, int(2e7 // (V.shape[0] * C.shape[1] + 1)))  # bounded temporaries
    for lo in range(0, len(cands), step):
        out[lo : lo + step] = V[:, C[lo : lo + step]].all(axis=2).any(axis=0)
    return out


def feasible_breaking_sets(scene: Scene, tol: Tolerances = DEFAULT_TOLERANCES, *, workers=1, scheduler=None,
                           max_programmes: int | None = None, witnesses: bool = False, on_level=None,
                           compiled: bool | None = None):  # fmt: skip
    """Breaking sets of the scene's modes that admit equilibrium, level by level (Apriori).

    Parameters
    ----------
    max_programmes : int, optional
        Give up (``sets`` None) rather than solve more programmes than this in all: the
        budget of ``solve(search="auto")``.  Without it, a level of more than
        :data:`MAX_LEVEL_SETS` candidates is refused with a ``QsplanError``.
    witnesses : bool
        Skip the programme of a candidate when a force found at an earlier level is within
        :data:`WITNESS_ZERO` cone widenings of zero at every contact of the candidate: that force,
        with those contacts' shares dropped, balances the loads up to a residual of the widening's
        order, so the candidate is kept unproven.  The sets are then a superset of those that
        admit equilibrium (every one that does is kept), for a sixth to a third of the programmes
        at n_c = 12..20: what the pruned search needs, since it screens every kept set.
    on_level : callable, optional
        ``on_level(sets)`` with each level's sets as soon as they are known (sizes of the scene's
        modes only), so that their modes can be screened while the next level's programmes run.
    compiled : bool or None
        Solve the programmes with the compiled kernel, HiGHS only for those it leaves undecided
        (None: when it is built); False: HiGHS for every set, the reference.  Both prune only
        sets proven infeasible (module docstring); they may differ on sets HiGHS leaves undecided
        (kept).

    Returns
    -------
    sets : list of tuple of int, or None
        Sorted 0-based breaking sets with sizes of the scene's modes (eq. 29) that admit
        equilibrium (with ``witnesses``: or nearly); None when ``max_programmes`` would be exceeded.
    programmes : int
        Linear programmes solved.
    """
    n_c, dof = scene.n_contacts, scene.dof
    lo, hi = breaking_set_sizes(n_c, dof)
    rel = equilibrium_relaxation(scene, tol)
    compiled = compiled_relax is not None if compiled is None else bool(compiled and compiled_relax is not None)
    zero = WITNESS_ZERO * float(rel.b_ub[0]) if rel.b_ub.size else 0.0
    ok, force = _decide(rel, [()], compiled)[0]
    level, programmes, out = [()], 1, []
    vanish = [_vanishing(force, zero)] if witnesses and force is not None else []
    if not ok:
        return out, programmes
    for size in range(0, hi + 1):
        if size >= lo:
            out.extend(level)
            if on_level is not None and level:
                on_level(level)
        if size == hi:
            break
        room = MAX_LEVEL_SETS if max_programmes is None else max_programmes - programmes
        if size == 0:
            cands = [(i,) for i in range(n_c)] if n_c <= room else None
        else:
            cands = _candidates(level, set(level), room)
        if cands is None:
            if max_programmes is not None:
                return None, programmes
            raise QsplanError(
                f"search: the pruned search would test more than {MAX_LEVEL_SETS:,} breaking sets of "
                f"{size + 1} contacts (n_c = {n_c}, {dof} constraints per mode); use search='auto' or 'all'"
            )
        if not cands:
            break
        known = _witnessed(cands, vanish)  # only earlier levels' forces: the same sets for any workers
        todo = [c for c, k in zip(cands, known) if not k]
        if max_programmes is not None and programmes + len(todo) > max_programmes:
            return None, programmes
        verdicts = dict(zip(todo, _check_sets(rel, todo, workers, scheduler, compiled))) if todo else {}
        programmes += len(todo)
        level = [c for c, k in zip(cands, known) if k or verdicts[c][0]]
        if witnesses:
            vanish += [_vanishing(f, zero) for ok, f in verdicts.values() if ok and f is not None]
    return out, programmes
