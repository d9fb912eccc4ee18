"""All feasible contact modes of a scene, vectorized over modes (eqs. 24-28).

:func:`solve` tests every mode that meets the utility condition (29) for the
scene's control-mode partition (their number is eq. (49)), in batches of equal
size: the kinematic partitions ``P_AI`` of a whole batch are factorised and
solved at once, the kinematic checks (breaking contacts, sliding directions)
reject most modes, and only the survivors get their ``Q_AI`` built and solved.
Each mode gets exactly the status the one-mode reference
:func:`mechanics.feasibility.check_mode` gives it, which the tests verify.
From :data:`SEARCH_MIN_MODES` modes on, :func:`solve` by default tests only the
modes that survive the exact pruning of :mod:`mechanics.mode_search` (same
solutions; ``search="all"`` tests every mode).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from itertools import islice

import numpy as np

from qsplan.mechanics.modes.contact_mode import ContactMode, codes_to_letters, count_modes, iter_mode_batches
from qsplan.mechanics.numerics import DEFAULT_TOLERANCES, Status, Tolerances, hadamard_ratio
from qsplan.mechanics.model.scene import Scene
from qsplan.mechanics.modes.reference import velocity_scale
from qsplan.mechanics.modes.solution import ModeSolution, model_residuals

__all__ = [
    "SolveResult",
    "solve",
    "DEFAULT_BATCH",
    "Kinematics",
    "kinematics_stage",
    "equilibrium_matrix",
    "single_mode_kinematics",
    "check_mode_fits",
    "equilibrium_stage",
    "ScenePool",
    "solve_batch",
    "SEARCH_MIN_MODES",
]

#: Fewest modes (eq. 49) for which ``search="auto"`` prunes breaking sets
#: (:mod:`mechanics.mode_search`).  Measured on planted scenes with dof = n_c, one core:
#: even at ~5,000 modes (n_c = 9-10), 3x faster at 25,653 (n_c = 11: 0.04 s vs 0.13 s),
#: 7x at 212,941 (n_c = 13).  Small scenes, solved in loops by mu-space maps and bands,
#: keep the plain path and its full per-status counts.
SEARCH_MIN_MODES = 20_000

#: Modes per batch.  Memory per batch is about ``batch * k * (k + n_j) * 8`` bytes
#: several times over; 8192 keeps it to a few MB for k <= 20 and amortises numpy's
#: per-call overhead.
DEFAULT_BATCH = 8192

_B, _R, _S = 0, 1, 2


@dataclass(frozen=True, slots=True, eq=False)
class SolveResult:
    """Every feasible mode of a scene, and why the others were rejected.

    Attributes
    ----------
    scene : Scene
    modes_tested : int
        Number of modes tested: eq. (49) for ``n_c`` and ``3 + |tau_I|``.
    solutions : tuple of ModeSolution
        Feasible modes in enumeration order.
    counts : dict[str, int]
        Number of modes per :class:`~mechanics.numerics.Status`; degenerate cases
        (singular matrices, zero speeds) are counted here and never reported feasible.
        A pruned search (``solve(search="prune")``) adds the untested modes under
        ``mode_search.PRUNED`` and ``mode_search.PRUNED_KINEMATIC``; the sum is still eq. (49).
    tolerances : Tolerances
    statuses : tuple of str or None
        Status of every tested mode in enumeration order, when ``solve(..., keep_statuses=True)``.
    """

    scene: Scene
    modes_tested: int
    solutions: tuple
    counts: dict
    tolerances: Tolerances = field(default=DEFAULT_TOLERANCES)
    statuses: tuple | None = None

    @property
    def feasible_modes(self) -> list[str]:
        """Letters of the feasible modes, in enumeration order."""
        return [s.mode.letters for s in self.solutions]

    @property
    def ambiguous(self) -> bool:
        """More than one mode is feasible (Section 4.3)."""
        return len(self.solutions) > 1

    @property
    def jammed(self) -> bool:
        """No mode is feasible (the paper's "Jam")."""
        return not self.solutions

    @property
    def degenerate(self) -> int:
        """Number of modes rejected as degenerate."""
        return sum(v for k, v in self.counts.items() if k in Status.DEGENERATE)

    def solution(self, letters: str) -> ModeSolution | None:
        """The solution of mode ``letters`` if it is feasible, else None."""
        for s in self.solutions:
            if s.mode.letters == letters:
                return s
        return None


def _assemble(scene: Scene, codes: np.ndarray):
    """Row indices of the applicable constraints of each mode (eq. 14) and their roles.

    Returns ``idx`` (m, k) into the stacked rows ``[n-rows; t-rows]`` (length 2 n_c),
    and ``slide`` (m, k), True where the row is the normal row of a sliding contact.
    """
    n_c = scene.n_contacts
    mask = np.concatenate([codes != _B, codes == _R], axis=1)
    k = int(mask[0].sum())
    idx = np.argsort(~mask, axis=1, kind="stable")[:, :k]
    contact = idx % n_c
    slide = (idx < n_c) & (np.take_along_axis(codes, contact, axis=1) == _S)
    return idx, contact, slide


_STATUS = Status.ORDER  # integer status codes index this tuple
_FEAS, _KSING, _BVIOL, _BZERO, _SZERO, _QSING, _COUL = range(7)


class ScenePool:
    """Per-scene arrays every batch gathers rows from (computed once per solve)."""

    def __init__(self, scene: Scene):
        self.E, self.V = scene.effort_joints, scene.velocity_joints
        self.Wrows = np.vstack([scene.Wn.T, scene.Wt.T])  # (2 n_c, 3): w_n, w_t as rows
        self.Jrows = np.vstack([scene.Jn, scene.Jt])  # (2 n_c, n_j)
        self.M = np.hstack([self.Wrows, -self.Jrows[:, self.E]])  # rows of P_AI (eq. 23)
        with np.errstate(divide="ignore"):
            self.log_row_norm = np.log(np.linalg.norm(self.M, axis=1))
        self.drive = self.Jrows[:, self.V] @ scene.joint_velocity[self.V]  # right-hand side of eq. (24)


@dataclass(frozen=True, slots=True, eq=False)
class Kinematics:
    """Kinematic stage (eqs. 24-25, 16) for modes that passed it; rows are modes.

    Attributes
    ----------
    codes : ndarray of uint8, shape (m, n_c)
    idx : ndarray of int, shape (m, k)
        Applicable rows of each mode in ``[n-rows; t-rows]`` order (eq. 14).
    contact : ndarray of int, shape (m, k)
        Contact of each applicable row.
    slide : ndarray of bool, shape (m, k)
        Row is the normal row of a sliding contact.
    qdot : ndarray, shape (m, 3)
    thetadot : ndarray, shape (m, n_j)
    xi : ndarray, shape (m, n_c)
        Sliding directions (eq. 16), 0 at rolling and breaking contacts.
    """

    codes: np.ndarray
    idx: np.ndarray
    contact: np.ndarray
    slide: np.ndarray
    qdot: np.ndarray
    thetadot: np.ndarray
    xi: np.ndarray

    def take(self, rows) -> "Kinematics":
        """The same stage restricted (or repeated) to ``rows``."""
        return Kinematics(*(getattr(self, f)[rows] for f in self.__slots__))


def kinematics_stage(scene: Scene, pool: "ScenePool", codes: np.ndarray, tol: Tolerances, vtol: float):
    """Kinematic tests of a batch of modes: P_AI (23-24), breaking (25), sliding directions (16).

    Returns
    -------
    status : ndarray of int8, shape (m,)
        Codes into ``Status.ORDER``; 0 (feasible so far) for modes that passed.
    live : ndarray of int, shape (m',)
        Rows that passed.
    kin : Kinematics
        Their kinematic solution (independent of mu and of the effort inputs).
    """
    n_c = scene.n_contacts
    E, V = pool.E, pool.V
    m = codes.shape[0]
    status = np.zeros(m, dtype=np.int8)

    idx, contact, slide = _assemble(scene, codes)
    P = pool.M[idx]  # P_AI of every mode, (m, k, k)
    sign, logdet = np.linalg.slogdet(P)
    with np.errstate(over="ignore", invalid="ignore"):
        h = np.exp(logdet - pool.log_row_norm[idx].sum(axis=1))  # == hadamard_ratio(P)
    sing = (sign == 0) | ~(h >= tol.singular)
    status[sing] = _KSING
    P[sing] = np.eye(P.shape[1])
    z = np.linalg.solve(P, pool.drive[idx][..., None])[..., 0]  # eq. (24)
    thetadot = np.empty((m, scene.n_joints))
    thetadot[:, V] = scene.joint_velocity[V]
    thetadot[:, E] = z[:, 3:]
    qdot = z[:, :3]
    v = qdot @ pool.Wrows.T - thetadot @ pool.Jrows.T  # eq. (5), (m, 2 n_c)
    v_n, v_t = v[:, :n_c], v[:, n_c:]

    alive = ~sing
    brk = codes == _B
    b_viol = alive & np.any(brk & (v_n < -vtol), axis=1)  # eq. (15)
    status[b_viol] = _BVIOL
    alive &= ~b_viol
    b_zero = alive & np.any(brk & (v_n <= vtol), axis=1)
    status[b_zero] = _BZERO
    alive &= ~b_zero
    sld = codes == _S
    s_zero = alive & np.any(sld & (np.abs(v_t) <= vtol), axis=1)  # eq. (16) undefined
    status[s_zero] = _SZERO
    alive &= ~s_zero

    live = np.flatnonzero(alive)
    xi = np.where(sld[live], np.sign(v_t[live]), 0.0)
    kin = Kinematics(codes[live], idx[live], contact[live], slide[live], qdot[live], thetadot[live], xi)
    return status, live, kin


def check_mode_fits(scene: Scene, mode) -> ContactMode:
    """``mode`` (letters or ContactMode) checked against the scene: one letter per contact
    and ``2 n_R + n_S = 3 + |tau_I|`` (eq. 29 with the scene's partition)."""
    from qsplan.mechanics.errors import ModeError

    mode = mode if isinstance(mode, ContactMode) else ContactMode(str(mode).upper())
    if mode.n_contacts != scene.n_contacts:
        raise ModeError(f"mode: expected {scene.n_contacts} letters (one per contact); got {mode.letters!r}")
    if mode.n_constraints != scene.dof:
        raise ModeError(
            f"mode {mode.letters}: has {mode.n_constraints} applicable constraints but the scene's partition "
            f"needs {scene.dof} (eq. 29 with |tau_I| = {scene.dof - 3})"
        )
    return mode


def single_mode_kinematics(scene: Scene, mode, tol: Tolerances = DEFAULT_TOLERANCES):
    """The mu- and effort-independent kinematic stage (eqs. 24-25, 16) of one mode.

    Returns
    -------
    mode : ContactMode
    status : str
        ``Status.FEASIBLE`` when the mode passed.
    pool : ScenePool
    kin : Kinematics or None
        One row with the sliding directions ``xi``; None when the mode failed.
    """
    mode = check_mode_fits(scene, mode)
    pool = ScenePool(scene)
    codes = np.array([["BRS".index(c) for c in mode.letters]], dtype=np.uint8)
    status, live, kin = kinematics_stage(scene, pool, codes, tol, tol.velocity * velocity_scale(scene))
    return mode, Status.ORDER[int(status[0])], pool, (kin if live.size else None)


def equilibrium_matrix(pool: "ScenePool", kin: Kinematics, mu: np.ndarray) -> np.ndarray:
    """``Q_AI`` of eq. (26) for every row: ``[W_Amu; J_AmuI^T]``, shape (m, k, k).

    Column ``j`` belongs to the applicable constraint ``kin.idx[:, j]``; sliding
    normal columns pick up ``-mu xi`` times the tangential column (eqs. 18-20).

    Parameters
    ----------
    mu : ndarray, shape (m, n_c)
    """
    n_c = pool.Wrows.shape[0] // 2
    idx, contact, E = kin.idx, kin.contact, pool.E
    f = np.where(kin.slide, -np.take_along_axis(mu * kin.xi, contact, axis=1), 0.0)
    partner = contact + n_c
    WAmu = pool.Wrows[idx] + f[..., None] * pool.Wrows[partner]  # (m, k, 3): columns of W_Amu
    JAmu = pool.Jrows[idx][:, :, E] + f[..., None] * pool.Jrows[partner][:, :, E]  # columns of J_AmuI^T
    return np.concatenate([WAmu, JAmu], axis=2).transpose(0, 2, 1)


def equilibrium_stage(scene: Scene, pool: "ScenePool", kin: Kinematics, mu: np.ndarray, tau_e: np.ndarray, tol: Tolerances):
    """Equilibrium (26)-(27) and Coulomb (28) for kinematically admissible modes.

    Parameters
    ----------
    mu : ndarray, shape (m, n_c)
        Friction coefficients per row (rows may repeat a mode with other mu).
    tau_e : ndarray, shape (m, n_e)
        Efforts of the effort-controlled joints per row.

    Returns
    -------
    status : ndarray of int8, shape (m,)
    c_n, c_t : ndarray, shape (m, n_c)
    tau : ndarray, shape (m, n_j)
    boundary : ndarray of bool, shape (m,)
        An inequality of (28) holds only within the force tolerance.
    """
    n_c = scene.n_contacts
    E, V = pool.E, pool.V
    m = kin.codes.shape[0]
    status = np.zeros(m, dtype=np.int8)
    idx, contact, xi = kin.idx, kin.contact, kin.xi
    Q = equilibrium_matrix(pool, kin, mu)
    q_sing = hadamard_ratio(Q) < tol.singular
    status[q_sing] = _QSING
    Q[q_sing] = np.eye(Q.shape[1])
    rhs = np.concatenate([np.broadcast_to(-scene.g_obj, (m, 3)), tau_e - scene.g_man[E]], axis=1)
    cA = np.linalg.solve(Q, rhs[..., None])[..., 0]

    rows = np.broadcast_to(np.arange(m)[:, None], idx.shape)
    c_n = np.zeros((m, n_c))
    c_t = np.zeros((m, n_c))
    is_n = idx < n_c
    c_n[rows[is_n], contact[is_n]] = cA[is_n]
    c_t[rows[~is_n], contact[~is_n]] = cA[~is_n]
    sliding = kin.codes == _S
    c_t = np.where(sliding, -mu * xi * c_n, c_t)  # eq. (17)

    rolling = kin.codes == _R
    # (28), plus c_n >= 0 at rolling contacts: eq. (9) states it, and the cone rows imply it only when mu > 0
    cone = np.minimum(np.minimum(mu * c_n + c_t, mu * c_n - c_t), c_n)
    slack = np.where(rolling, cone, np.where(sliding, c_n, np.inf))
    ftol = tol.force * np.maximum(np.max(np.abs(cA), axis=1), np.max(np.abs(rhs), axis=1))
    worst = slack.min(axis=1)
    coul = ~q_sing & (worst < -ftol)
    status[coul] = _COUL

    tau = np.empty((m, scene.n_joints))
    tau[:, E] = tau_e
    tau[:, V] = (c_n @ scene.Jn + c_t @ scene.Jt)[:, V] + scene.g_man[V]  # eq. (27), from eq. (3)
    return status, c_n, c_t, tau, worst <= ftol


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
        for j in np.flatnonzero(st == _FEAS):
            sol = ModeSolution(
                mode=ContactMode(codes_to_letters(kin.codes[j])), qdot=kin.qdot[j], thetadot=kin.thetadot[j],
                c_n=c_n[j], c_t=c_t[j], tau=tau[j], xi=kin.xi[j].astype(int), on_boundary=bool(boundary[j]),
            )  # fmt: skip
            if residuals:
                sol = replace(sol, residuals=model_residuals(scene, sol))
            sols.append(sol)
    return status, sols


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
        fewer than ``2 * MIN_CHUNK_MODES`` modes stay in-process (:mod:`mechanics.mode_chunks`).
    scheduler : str or dask.distributed.Client, optional
        Send the chunks to a Dask cluster instead (:func:`mechanics.parallel.map_chunks`).
    batches : (int, int), optional
        Test only batches ``lo <= i < hi`` of the enumeration (one chunk's share).
    search : {"auto", "prune", "all"}
        ``"all"`` tests every mode; ``"prune"`` tests only the modes whose breaking
        set admits equilibrium (:func:`mechanics.mode_search.search_solve`, the same
        solutions, the untested modes counted under ``PRUNED``); ``"auto"`` prunes
        from :data:`SEARCH_MIN_MODES` modes on.  ``keep_statuses`` and ``batches``
        always test every mode.

    Returns
    -------
    SolveResult
        The same (bit for bit) however it was split.
    """
    if search not in ("auto", "prune", "all"):
        from qsplan.mechanics.errors import QsplanError

        raise QsplanError(f"search: expected 'auto', 'prune' or 'all'; got {search!r}")
    if search == "auto":
        search = "prune" if count_modes(scene.n_contacts, scene.dof) >= SEARCH_MIN_MODES else "all"
    if search == "prune" and batches is None and not keep_statuses:
        from qsplan.mechanics.solver.search import search_solve

        return search_solve(scene, tol, batch, residuals, workers=workers, scheduler=scheduler)
    if batches is None and (workers != 1 or scheduler is not None):
        from qsplan.mechanics.solver.chunks import solve_in_chunks

        chunked = solve_in_chunks(scene, tol, batch, residuals, keep_statuses, workers=workers, scheduler=scheduler)
        if chunked is not None:
            return chunked
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
        for code, cnt in enumerate(np.bincount(status, minlength=len(_STATUS))):
            counts[_STATUS[code]] += int(cnt)
        if keep_statuses:
            kept.extend(_STATUS[c] for c in status)
    return SolveResult(
        scene=scene, modes_tested=total, solutions=tuple(sols), counts=counts, tolerances=tol,
        statuses=tuple(kept) if keep_statuses else None,
    )  # fmt: skip
