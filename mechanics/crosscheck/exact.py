"""Exact ground truth: the one-mode test of eqs. (13)-(28) in rational arithmetic.

Every float is a binary rational, so :class:`fractions.Fraction` holds a scene's
data exactly; Gaussian elimination over the rationals then decides singularity
(a pivot is zero or it is not), the signs of separation and slip speeds and the
Coulomb inequalities without rounding.  The strict inequalities of the paper
(eq. 15 for breaking contacts, the sign in eq. 16 for sliding ones) are tested
strictly and the non-strict ones (eq. 28) non-strictly, so
:func:`exact_feasible_modes` is the exact feasible set of the scene as stated.
It follows :func:`qsplan.mechanics.modes.reference.check_mode` step by step and
returns the same :class:`~qsplan.mechanics.numerics.Status` values, with no tolerance
at all.  It re-derives eqs. (13)-(28) on purpose, sharing no arithmetic with
:mod:`qsplan.mechanics.modes.kinematics` and :mod:`qsplan.mechanics.modes.equilibrium`,
so that it is an independent reference (only the scene check is shared).

It is slow (denominators grow to hundreds of digits) and meant for small scenes
(``n_c <= 6``): tests and the stability study (``benchmarks/bench_stability.py``).
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction

from qsplan.mechanics.modes.contact_mode import ContactMode, enumerate_modes
from qsplan.mechanics.numerics import Status
from qsplan.mechanics.model.scene import Scene

__all__ = ["ExactCheck", "exact_check_mode", "exact_feasible_modes", "solve_exact", "rational"]


def rational(a):
    """Nested lists of :class:`Fraction` equal to the float array ``a`` (exact)."""
    if hasattr(a, "tolist"):
        a = a.tolist()
    if isinstance(a, list):
        return [rational(x) for x in a]
    return Fraction(a)


def solve_exact(A, b):
    """Solve ``A x = b`` over the rationals; None when ``A`` is singular.

    Parameters
    ----------
    A : list of k lists of k Fraction
    b : list of k Fraction

    Returns
    -------
    list of k Fraction, or None
    """
    k = len(A)
    T = [list(A[i]) + [b[i]] for i in range(k)]
    for c in range(k):
        p = next((r for r in range(c, k) if T[r][c] != 0), None)
        if p is None:
            return None
        T[c], T[p] = T[p], T[c]
        piv = T[c][c]
        for r in range(k):
            if r != c and T[r][c] != 0:
                f = T[r][c] / piv
                T[r] = [x - f * y for x, y in zip(T[r], T[c])]
    return [T[i][k] / T[i][i] for i in range(k)]


@dataclass(frozen=True, slots=True, eq=False)
class ExactCheck:
    """Exact outcome of one mode: status and, when the kinematics were solved, the motion.

    Attributes
    ----------
    mode : ContactMode
    status : str
        A :class:`~qsplan.mechanics.numerics.Status` value.
    qdot : tuple of Fraction or None
    c_n, c_t : tuple of Fraction or None
        Forces when the equilibrium stage was reached.
    on_boundary : bool
        An inequality of eq. (28) holds with equality.
    """

    mode: ContactMode
    status: str
    qdot: tuple | None = None
    c_n: tuple | None = None
    c_t: tuple | None = None
    on_boundary: bool = False

    @property
    def feasible(self) -> bool:
        return self.status == Status.FEASIBLE


def _dot(a, b):
    return sum((x * y for x, y in zip(a, b)), Fraction(0))


class _Exact:
    """The scene's data as Fractions (computed once per scene)."""

    def __init__(self, scene: Scene):
        self.Wn, self.Wt = rational(scene.Wn.T), rational(scene.Wt.T)  # rows: contact wrenches
        self.Jn, self.Jt = rational(scene.Jn), rational(scene.Jt)
        self.mu = rational(scene.mu)
        self.g_obj = rational(scene.g_obj)
        self.g_man = rational(scene.g_man)
        self.E = [int(i) for i in scene.effort_joints]
        self.V = [int(i) for i in scene.velocity_joints]
        self.th_V = [Fraction(float(scene.joint_velocity[j])) for j in self.V]
        self.tau_E = [Fraction(float(scene.joint_effort[j])) for j in self.E]
        self.n_j = scene.n_joints


def _check(X: _Exact, mode: ContactMode) -> ExactCheck:
    R, S, B = mode.rolling, mode.sliding, mode.breaking
    E, V = X.E, X.V
    # Applicable constraints in check_mode's order (eq. 14): n-rows of R, t-rows of R, n-rows of S.
    rows = [(i, X.Wn, X.Jn) for i in R] + [(i, X.Wt, X.Jt) for i in R] + [(i, X.Wn, X.Jn) for i in S]
    # Kinematics (23)-(24): [W_A^T, -J_AI] z_I = J_AII thetadot_II.
    P = [W[i] + [-J[i][j] for j in E] for i, W, J in rows]
    rhs = [_dot([J[i][j] for j in V], X.th_V) for i, W, J in rows]
    z = solve_exact(P, rhs)
    if z is None:
        return ExactCheck(mode, Status.KINEMATICS_SINGULAR)
    qdot = z[:3]
    th = [Fraction(0)] * X.n_j
    for j, v in zip(V, X.th_V):
        th[j] = v
    for j, v in zip(E, z[3:]):
        th[j] = v

    def vel(W, J, i):
        return _dot(W[i], qdot) - _dot(J[i], th)  # eq. (5)

    v_nB = [vel(X.Wn, X.Jn, i) for i in B]
    if any(v < 0 for v in v_nB):
        return ExactCheck(mode, Status.BREAKING_VIOLATED, tuple(qdot))
    if any(v == 0 for v in v_nB):
        return ExactCheck(mode, Status.BREAKING_ZERO_SPEED, tuple(qdot))
    v_tS = [vel(X.Wt, X.Jt, i) for i in S]
    if any(v == 0 for v in v_tS):
        return ExactCheck(mode, Status.ZERO_SLIDING_SPEED, tuple(qdot))
    xi = {i: (1 if v > 0 else -1) for i, v in zip(S, v_tS)}

    # Equilibrium (26): columns [w; j_E] of W_Amu and J_AmuI^T (eqs. 18-20).
    cols = [X.Wn[i] + [X.Jn[i][j] for j in E] for i in R] + [X.Wt[i] + [X.Jt[i][j] for j in E] for i in R]
    for i in S:
        f = -X.mu[i] * xi[i]
        cols.append([a + f * b for a, b in zip(X.Wn[i] + [X.Jn[i][j] for j in E], X.Wt[i] + [X.Jt[i][j] for j in E])])
    k = len(cols)
    Q = [[cols[c][r] for c in range(k)] for r in range(k)]
    b = [-g for g in X.g_obj] + [t - X.g_man[j] for j, t in zip(E, X.tau_E)]
    cA = solve_exact(Q, b)
    if cA is None:
        return ExactCheck(mode, Status.EQUILIBRIUM_SINGULAR, tuple(qdot))
    n_c = len(mode.letters)
    c_n, c_t = [Fraction(0)] * n_c, [Fraction(0)] * n_c
    nR = len(R)
    for a, i in enumerate(R):
        c_n[i], c_t[i] = cA[a], cA[nR + a]
    for a, i in enumerate(S):
        c_n[i] = cA[2 * nR + a]
        c_t[i] = -X.mu[i] * xi[i] * c_n[i]  # eq. (17)
    # Coulomb (28), and c_n >= 0 at rolling contacts (eq. 9).
    slack = [X.mu[i] * c_n[i] + c_t[i] for i in R] + [X.mu[i] * c_n[i] - c_t[i] for i in R]
    slack += [c_n[i] for i in R] + [c_n[i] for i in S]
    status = Status.COULOMB_VIOLATED if any(s < 0 for s in slack) else Status.FEASIBLE
    return ExactCheck(mode, status, tuple(qdot), tuple(c_n), tuple(c_t), any(s == 0 for s in slack))


def exact_check_mode(scene: Scene, mode: ContactMode) -> ExactCheck:
    """Exact counterpart of :func:`~qsplan.mechanics.modes.reference.check_mode` (eqs. 13-28), no tolerances.

    Parameters
    ----------
    scene : Scene
        Its float data are taken as the exact rationals they are.
    mode : ContactMode
        With ``2 n_R + n_S = 3 + |tau_I|``.

    Returns
    -------
    ExactCheck
    """
    from qsplan.mechanics.modes.kinematics import check_mode_fits

    return _check(_Exact(scene), check_mode_fits(scene, mode))


def exact_feasible_modes(scene: Scene) -> dict:
    """Exact status of every mode tested for the scene (eq. 49), in enumeration order.

    Returns
    -------
    dict[str, ExactCheck]
        Keyed by mode letters; the feasible set is ``[m for m, c in d.items() if c.feasible]``.
    """
    X = _Exact(scene)
    return {m.letters: _check(X, m) for m in enumerate_modes(scene.n_contacts, scene.dof)}
