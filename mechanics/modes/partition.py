"""The control-mode partitioner (Section 3.2, eqs. 23, 26, 29-32).

For a contact mode with ``k = 2 n_R + n_S`` applicable constraints, exactly
``k - 3`` joints must be effort-controlled, and that set ``I`` must make both
``P_AI`` (eq. 23) and ``Q_AI`` (eq. 26) nonsingular with the same column/row
selection (eq. 32).  :func:`effort_partitions` lists every admissible set for
a mode, best-conditioned first; :func:`partition_table` says, for a scene's
geometry, which partitions admit which modes.

``Q_AI`` depends on the sliding directions ``xi`` (eq. 16) through
``W_Amu``; when they are not given, a partition is admitted only if ``Q_AI``
is nonsingular for **every** sign pattern of the sliding contacts (so it stays
valid whichever way they slip), and its conditioning is the worst over them.
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import combinations, product
from math import comb

import numpy as np

from qsplan.mechanics.errors import ModeError, QsplanError
from qsplan.mechanics.modes.contact_mode import ContactMode, enumerate_modes, mode_from_letters
from qsplan.mechanics.numerics import DEFAULT_TOLERANCES, Tolerances, hadamard_ratio, rcond
from qsplan.mechanics.model.scene import Scene

__all__ = ["Partition", "effort_partitions", "partition_table", "partition_table_work", "MAX_SIGN_PATTERNS_SLIDING",
           "MAX_TABLE_TESTS"]  # fmt: skip

#: Without given sliding directions, all 2**n_S sign patterns are checked; above
#: this many sliding contacts that is too many, and ``xi`` must be given.
MAX_SIGN_PATTERNS_SLIDING = 12

#: Most matrix tests (eq. 49's modes x effort-joint sets x sliding sign patterns) a
#: :func:`partition_table` may need: ~20 us each, so about a minute.  16-41 contacts need
#: 1e8 and more (the table never returned); one mode (``effort_partitions``) stays cheap.
MAX_TABLE_TESTS = 3_000_000

#: Seconds per matrix test, for the estimate in the refusal.
_TEST_SECONDS = 2e-5


@dataclass(frozen=True, slots=True)
class Partition:
    """An admissible control-mode partition for one contact mode.

    Attributes
    ----------
    effort_joints : tuple of int
        0-based joints to effort-control (``tau_I``); the others are velocity-controlled.
    rcond_P, rcond_Q : float
        Reciprocal condition numbers of ``P_AI`` and (worst over sliding directions) ``Q_AI``.
    """

    effort_joints: tuple
    rcond_P: float
    rcond_Q: float

    @property
    def conditioning(self) -> float:
        """``min(rcond_P, rcond_Q)``: larger is better."""
        return min(self.rcond_P, self.rcond_Q)


def _applicable(scene: Scene, mode: ContactMode):
    R, S = list(mode.rolling), list(mode.sliding)
    WA_T = np.vstack([scene.Wn.T[R], scene.Wt.T[R], scene.Wn.T[S]])
    JA = np.vstack([scene.Jn[R], scene.Jt[R], scene.Jn[S]])
    return WA_T, JA, R, S


def effort_partitions(scene: Scene, mode: ContactMode, xi=None, tol: Tolerances = DEFAULT_TOLERANCES) -> list[Partition]:
    """Every joint set that may be effort-controlled for ``mode`` (eq. 32), best-conditioned first.

    Parameters
    ----------
    scene : Scene
        Geometry, Jacobians and mu are used; its own control partition is ignored.
    mode : ContactMode
    xi : array-like of +-1, shape (n_S,), optional
        Sliding directions of the sliding contacts in order; default: all patterns.
    tol : Tolerances
        ``tol.singular`` decides singularity, as in the solver.

    Returns
    -------
    list of Partition
        Empty when the mode violates (29)-(31) or no joint set satisfies (32).
    """
    mode = mode_from_letters(mode, scene.n_contacts)
    k = mode.n_constraints
    m = k - 3
    if m < 0 or m > scene.n_joints:  # eq. (29)
        return []
    WA_T, JA, R, S = _applicable(scene, mode)
    if xi is None:
        if len(S) > MAX_SIGN_PATTERNS_SLIDING:
            raise ModeError(f"xi: {len(S)} sliding contacts; give the sliding directions explicitly")
        patterns = [np.array(p, dtype=float) for p in product((-1.0, 1.0), repeat=len(S))]
    else:
        xi = np.asarray(xi, dtype=float).reshape(-1)
        if xi.shape != (len(S),) or not np.all(np.abs(xi) == 1):
            raise ModeError(f"xi: expected {len(S)} values of +1 or -1 (one per sliding contact); got {xi.tolist()}")
        patterns = [xi]
    mu_S = scene.mu[S]
    out = []
    for I in combinations(range(scene.n_joints), m):
        I = list(I)
        P = np.hstack([WA_T, -JA[:, I]])  # eq. (23)
        if hadamard_ratio(P) < tol.singular:
            continue
        worst_h, worst_r = np.inf, np.inf
        for p in patterns:
            f = -mu_S * p
            WAmu = np.hstack([scene.Wn[:, R], scene.Wt[:, R], scene.Wn[:, S] + scene.Wt[:, S] * f])
            JAmuI = np.hstack([scene.Jn[R][:, I].T, scene.Jt[R][:, I].T, scene.Jn[S][:, I].T + scene.Jt[S][:, I].T * f])
            Q = np.vstack([WAmu, JAmuI])  # eq. (26)
            worst_h = min(worst_h, float(hadamard_ratio(Q)))
            worst_r = min(worst_r, float(rcond(Q)))
        if worst_h < tol.singular:
            continue
        out.append(Partition(tuple(I), float(rcond(P)), worst_r))
    out.sort(key=lambda p: -p.conditioning)
    return out


def partition_table_work(n_contacts: int, n_joints: int, max_effort: int | None = None) -> int:
    """Matrix tests :func:`partition_table` needs: modes (eq. 49) x joint sets x sign patterns of the sliding contacts."""
    top = n_joints if max_effort is None else min(max_effort, n_joints)
    total = 0
    for m in range(top + 1):
        dof = 3 + m
        for n_r in range(dof // 2 + 1):
            n_s = dof - 2 * n_r
            if n_r + n_s <= n_contacts:
                total += comb(n_contacts, n_r) * comb(n_contacts - n_r, n_s) * comb(n_joints, m) * (1 + 2**n_s)
    return total


def partition_table(scene: Scene, tol: Tolerances = DEFAULT_TOLERANCES, max_effort: int | None = None) -> dict:
    """Which control-mode partitions admit which contact modes (eqs. 29-32).

    Parameters
    ----------
    scene : Scene
    tol : Tolerances
    max_effort : int, optional
        Largest number of effort-controlled joints considered (default: all joints).

    Raises
    ------
    QsplanError
        The table would need more than :data:`MAX_TABLE_TESTS` matrix tests (:func:`partition_table_work`).

    Returns
    -------
    dict
        Maps each effort-joint tuple to the list of mode letters it admits, in
        enumeration order; partitions that admit no mode are left out.
    """
    work = partition_table_work(scene.n_contacts, scene.n_joints, max_effort)
    if work > MAX_TABLE_TESTS:
        raise QsplanError(
            f"partition: the table for {scene.n_contacts} contacts and {scene.n_joints} joints needs about "
            f"{work:.2g} matrix tests (~{work * _TEST_SECONDS:.2g} s; limit {MAX_TABLE_TESTS:.0e}); "
            f"rank the effort-joint sets of one mode instead (mode=LETTERS)"
        )
    top = scene.n_joints if max_effort is None else min(max_effort, scene.n_joints)
    table: dict = {}
    for m in range(top + 1):
        for mode in enumerate_modes(scene.n_contacts, 3 + m):
            for p in effort_partitions(scene, mode, tol=tol):
                table.setdefault(p.effort_joints, []).append(mode.letters)
    return dict(sorted(table.items(), key=lambda kv: (len(kv[0]), kv[0])))
