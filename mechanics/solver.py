"""All feasible contact modes of a scene, vectorized over modes (eqs. 24-28).

:func:`solve` tests every mode that meets the utility condition (29) for the
scene's control-mode partition (their number is eq. (49)), in batches of equal
size: the kinematic partitions ``P_AI`` of a whole batch are factorised and
solved at once, the kinematic checks (breaking contacts, sliding directions)
reject most modes, and only the survivors get their ``Q_AI`` built and solved.
Each mode gets exactly the status the one-mode reference
:func:`mechanics.feasibility.check_mode` gives it, which the tests verify.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from .modes import ContactMode, count_modes, mode_index_array
from .numerics import DEFAULT_TOLERANCES, Status, Tolerances, hadamard_ratio
from .scene import Scene
from .feasibility import velocity_scale
from .solution import ModeSolution, model_residuals

__all__ = ["SolveResult", "solve", "DEFAULT_BATCH"]

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
    tolerances : Tolerances
    """

    scene: Scene
    modes_tested: int
    solutions: tuple
    counts: dict
    tolerances: Tolerances = field(default=DEFAULT_TOLERANCES)

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


def _solve_batch(scene: Scene, codes: np.ndarray, tol: Tolerances, vtol: float):
    """Statuses (m,) of a batch of modes and arrays for the feasible ones."""
    n_c = scene.n_contacts
    E, V = scene.effort_joints, scene.velocity_joints
    m = codes.shape[0]
    Wrows = np.vstack([scene.Wn.T, scene.Wt.T])  # (2 n_c, 3)
    Jrows = np.vstack([scene.Jn, scene.Jt])  # (2 n_c, n_j)
    status = np.full(m, Status.FEASIBLE, dtype=object)

    idx, contact, slide = _assemble(scene, codes)
    WA = Wrows[idx]  # (m, k, 3)
    JA = Jrows[idx]  # (m, k, n_j)
    P = np.concatenate([WA, -JA[:, :, E]], axis=2)  # P_AI, eq. (23)
    sing = hadamard_ratio(P) < tol.singular
    status[sing] = Status.KINEMATICS_SINGULAR
    P[sing] = np.eye(P.shape[1])
    thetadot_v = scene.joint_velocity[V]
    z = np.linalg.solve(P, (JA[:, :, V] @ thetadot_v)[..., None])[..., 0]  # eq. (24)
    thetadot = np.empty((m, scene.n_joints))
    thetadot[:, V] = thetadot_v
    thetadot[:, E] = z[:, 3:]
    qdot = z[:, :3]
    v = qdot @ Wrows.T - thetadot @ Jrows.T  # eq. (5), (m, 2 n_c)
    v_n, v_t = v[:, :n_c], v[:, n_c:]

    alive = ~sing
    brk = codes == _B
    b_viol = alive & np.any(brk & (v_n < -vtol), axis=1)  # eq. (15)
    status[b_viol] = Status.BREAKING_VIOLATED
    alive &= ~b_viol
    b_zero = alive & np.any(brk & (v_n <= vtol), axis=1)
    status[b_zero] = Status.BREAKING_ZERO_SPEED
    alive &= ~b_zero
    sld = codes == _S
    s_zero = alive & np.any(sld & (np.abs(v_t) <= vtol), axis=1)  # eq. (16) undefined
    status[s_zero] = Status.ZERO_SLIDING_SPEED
    alive &= ~s_zero

    live = np.flatnonzero(alive)
    if live.size == 0:
        return status, live, None
    idx, contact, slide = idx[live], contact[live], slide[live]
    codes_l, qdot, thetadot, v_t = codes[live], qdot[live], thetadot[live], v_t[live]
    xi = np.where(codes_l == _S, np.sign(v_t), 0.0)
    mu = scene.mu
    # W_Amu and J_Amu: sliding normal rows pick up -mu xi times the tangential row (eqs. 18-20).
    f = np.where(slide, -mu[contact] * np.take_along_axis(xi, contact, axis=1), 0.0)
    partner = contact + n_c
    WAmu = Wrows[idx] + f[..., None] * Wrows[partner]  # (m', k, 3): columns of W_Amu
    JAmu = Jrows[idx] + f[..., None] * Jrows[partner]  # (m', k, n_j): columns of J_Amu^T
    Q = np.concatenate([WAmu, JAmu[:, :, E]], axis=2).transpose(0, 2, 1)  # Q_AI, eq. (26)
    q_sing = hadamard_ratio(Q) < tol.singular
    status[live[q_sing]] = Status.EQUILIBRIUM_SINGULAR
    Q[q_sing] = np.eye(Q.shape[1])
    tau_in = np.nan_to_num(scene.joint_effort)
    rhs = np.concatenate([-scene.g_obj, tau_in[E] - scene.g_man[E]])
    cA = np.linalg.solve(Q, np.broadcast_to(rhs, (live.size, rhs.size))[..., None])[..., 0]

    ml = live.size
    rows = np.arange(ml)[:, None]
    c_n = np.zeros((ml, n_c))
    c_t = np.zeros((ml, n_c))
    is_n = idx < n_c
    c_n[np.broadcast_to(rows, idx.shape)[is_n], contact[is_n]] = cA[is_n]
    c_t[np.broadcast_to(rows, idx.shape)[~is_n], contact[~is_n]] = cA[~is_n]
    c_t = np.where(codes_l == _S, -mu * xi * c_n, c_t)  # eq. (17)

    rol = codes_l == _R
    slack = np.where(rol, np.minimum(mu * c_n + c_t, mu * c_n - c_t), np.where(codes_l == _S, c_n, np.inf))  # eq. (28)
    ftol = tol.force * np.maximum(np.max(np.abs(cA), axis=1), np.max(np.abs(rhs)))
    worst = slack.min(axis=1)
    coul = ~q_sing & (worst < -ftol)
    status[live[coul]] = Status.COULOMB_VIOLATED
    ok = ~q_sing & ~coul

    tau = np.empty((ml, scene.n_joints))
    tau[:, E] = tau_in[E]
    tau[:, V] = (c_n @ scene.Jn + c_t @ scene.Jt)[:, V] + scene.g_man[V]  # eq. (27)
    feas = dict(
        index=live[ok], qdot=qdot[ok], thetadot=thetadot[ok], c_n=c_n[ok], c_t=c_t[ok],
        tau=tau[ok], xi=xi[ok].astype(int), boundary=(worst[ok] <= ftol[ok]),
    )  # fmt: skip
    return status, live, feas


def solve(scene: Scene, tol: Tolerances = DEFAULT_TOLERANCES, batch: int = DEFAULT_BATCH, residuals: bool = True) -> SolveResult:
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

    Returns
    -------
    SolveResult
    """
    n_c, dof = scene.n_contacts, scene.dof
    total = count_modes(n_c, dof)
    counts = dict.fromkeys(Status.ORDER, 0)
    sols = []
    vtol = tol.velocity * velocity_scale(scene)
    for start in range(0, total, batch):
        codes = mode_index_array(n_c, dof, start, start + batch)
        status, _, feas = _solve_batch(scene, codes, tol, vtol)
        for key, cnt in zip(*np.unique(status.astype(str), return_counts=True)):
            counts[str(key)] += int(cnt)
        if feas is None:
            continue
        for j, i in enumerate(feas["index"]):
            mode = ContactMode("".join("BRS"[c] for c in codes[i]))
            sol = ModeSolution(
                mode=mode, qdot=feas["qdot"][j], thetadot=feas["thetadot"][j], c_n=feas["c_n"][j],
                c_t=feas["c_t"][j], tau=feas["tau"][j], xi=feas["xi"][j], on_boundary=bool(feas["boundary"][j]),
            )  # fmt: skip
            if residuals:
                sol = replace(sol, residuals=model_residuals(scene, sol))
            sols.append(sol)
    return SolveResult(scene=scene, modes_tested=total, solutions=tuple(sols), counts=counts, tolerances=tol)
