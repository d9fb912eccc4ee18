"""One feasible contact mode from a linear complementarity problem (after Pang, Trinkle & Lo [26]).

The enumerative solver (:mod:`qsplan.mechanics.solver`) tests every mode; this module
finds *one* solution of the quasistatic model (eqs. 2-11) directly, as an LCP
solved by Lemke's method (:mod:`qsplan.mechanics.crosscheck.lemke`), and maps it back to a contact
mode that :func:`~qsplan.mechanics.modes.reference.check_mode` then verifies.

Derivation
----------
Unknowns: the workpiece twist ``qdot`` (3), the velocities ``thetadot_I`` of the
effort-controlled joints (``n_e``), and the contact forces.  The velocity-controlled
joints' velocities ``thetadot_II`` and the efforts ``tau_I`` are inputs; the efforts
``tau_II`` are outputs given afterwards by eq. (3) (eq. 27).  Collect the free
variables in ``u = [qdot; thetadot_I]`` (``d = 3 + n_e``) and write, with
``J_nI, J_nII`` the columns of ``J_n`` of the two joint sets (likewise ``J_t``)::

    N = [W_n; -J_nI^T]   (d, n_c)      T = [W_t; -J_tI^T]   (d, n_c)
    a_n = -J_nII thetadot_II           a_t = -J_tII thetadot_II

so that the relative velocities of eq. (5) are ``v_n = N^T u + a_n`` and
``v_t = T^T u + a_t``, and the equilibrium equations (2) and the effort-joint rows
of (3) read, by the principle of virtual work, with the same matrices transposed::

    N c_n + T c_t + b = 0,      b = [g_obj; tau_I - g_manI].

The 2-D friction cone (eq. 7) has exactly two edges, so write
``c_t = f_1 - f_2`` with ``f_1, f_2 >= 0`` and add the slip magnitude ``lambda``.
Coulomb's law with maximal dissipation (eqs. 7-11: a contact that slips has its
force on the cone edge opposing the slip, eq. 10, 17) is then the complementarity
system::

    0 <= v_n                      _|_ c_n >= 0        (eqs. 4, 11: c_n > 0 only if v_n = 0)
    0 <= v_t + lambda             _|_ f_1 >= 0        (f_1 > 0 only if v_t = -lambda <= 0)
    0 <= -v_t + lambda            _|_ f_2 >= 0        (f_2 > 0 only if v_t = lambda >= 0)
    0 <= mu c_n - f_1 - f_2       _|_ lambda >= 0     (eq. 7; lambda = |v_t| > 0 only on the edge)

(a breaking contact has no force and any ``lambda >= |v_t|``).

A rolling contact (eq. 9) has ``v_n = v_t = lambda = 0`` and its force anywhere in
the cone; a sliding one (eq. 10) ``v_n = 0``, ``lambda = |v_t| > 0`` and
``c_t = -mu sgn(v_t) c_n``; a breaking one (eq. 11) ``v_n > 0`` and no force.

The equality block makes this a mixed LCP with the free ``u``; its ``u``-``u``
block is zero, so ``u`` cannot be eliminated by a Schur complement.  Instead
split ``u = u_+ - u_-`` (both ``>= 0``) and pair each with one side of the
equality, ``w_+ = -(G x + b) >= 0`` and ``w_- = G x + b >= 0`` (which together
force ``G x + b = 0``, so their complementarity with ``u_+, u_-`` holds
trivially).  With ``x = [c_n; f_1; f_2; lambda]`` and ``G = [N, T, -T, 0]``
the standard LCP ``w = M z + q`` has ``z = [u_+; u_-; x]`` (``2 d + 4 n_c``) and::

        [  0     0    -G  ]        [ -b ]                  [ 0  0  0  0 ]
    M = [  0     0     G  ]    q = [  b ]        M_xx =    [ 0  0  0  I ]
        [ G^T  -G^T  M_xx ]        [  a ]                  [ 0  0  0  I ]
                                                           [ U -I -I  0 ]

with ``a = [a_n; a_t; -a_t; 0]`` and ``U = diag(mu)``.  Its off-diagonal blocks
are skew and the ``I`` blocks of ``M_xx`` too; only ``U`` is not, so ``M`` is
not copositive-plus when ``mu > 0``: ray termination then does not prove that no
mode is feasible (the benchmark counts how often that happens).  The problem is
homogeneous separately in the velocities and in the forces, so ``a`` and ``b``
are scaled to unit size before pivoting and the solution scaled back.

From a solution, each contact's letter follows from its velocities (``v_n > 0``:
B; else ``v_t != 0``: S; else R) with the tolerances of
:class:`~qsplan.mechanics.numerics.Tolerances`.  A solution whose mode does not have
``2 n_R + n_S = 3 + |tau_I|`` constraints (eq. 29) is degenerate in the paper's
sense (a contact with zero speed and zero force); otherwise the mode is
re-solved and verified by :func:`~qsplan.mechanics.modes.reference.check_mode`, which also
gives the full-model residuals (eqs. 2-11).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qsplan.mechanics.modes.kinematics import velocity_scale
from qsplan.mechanics.modes.reference import check_mode
from qsplan.mechanics.crosscheck.lemke import DEFAULT_MAX_PIVOTS, LemkeStatus, lemke
from qsplan.mechanics.modes.contact_mode import ContactMode
from qsplan.mechanics.numerics import DEFAULT_TOLERANCES, Status, Tolerances
from qsplan.mechanics.model.scene import Scene
from qsplan.mechanics.modes.solution import ModeSolution, relative_velocity

__all__ = ["LcpResult", "LcpStatus", "quasistatic_lcp", "solve_lcp"]


class LcpStatus:
    """How :func:`solve_lcp` ended."""

    SOLVED = "solved"  #: a mode was found and verified by check_mode
    RAY = LemkeStatus.RAY  #: Lemke's method stopped on a ray (not a proof of "no mode": M is not copositive-plus)
    ITERATION_LIMIT = LemkeStatus.ITERATION_LIMIT
    ILL_CONDITIONED = "ill-conditioned"  #: the mode's P_AI or Q_AI is singular by the Hadamard-ratio test
    DEGENERATE = "degenerate"  #: zero separation/slip speed, or the wrong number of constraints (eq. 29)
    NOT_VERIFIED = "not verified"  #: check_mode rejects the mode read off the LCP solution


@dataclass(frozen=True, slots=True, eq=False)
class LcpResult:
    """Outcome of :func:`solve_lcp`.

    Attributes
    ----------
    mode : ContactMode or None
        The verified feasible mode (``status == "solved"``).
    solution : ModeSolution or None
        Its solution from :func:`~qsplan.mechanics.modes.reference.check_mode`, with residuals.
    status : str
        An :class:`LcpStatus` value.
    letters : str or None
        The mode read off the LCP solution, also when it failed verification.
    check_status : str or None
        The :class:`~qsplan.mechanics.numerics.Status` that check_mode gave ``letters``.
    pivots : int
        Lemke pivots.
    """

    mode: ContactMode | None
    solution: ModeSolution | None
    status: str
    letters: str | None = None
    check_status: str | None = None
    pivots: int = 0

    @property
    def solved(self) -> bool:
        return self.status == LcpStatus.SOLVED


def quasistatic_lcp(scene: Scene):
    """The LCP ``(M, q)`` of the quasistatic problem (see the module docstring).

    Returns
    -------
    M : ndarray, shape (2 d + 4 n_c, 2 d + 4 n_c)
    q : ndarray, shape (2 d + 4 n_c,)
        Built from the scene's inputs scaled to unit size.
    v_scale, f_scale : float
        The scales: velocities of the solution are ``v_scale`` times the LCP's
        ``u`` and ``lambda``, forces ``f_scale`` times its ``c_n, f_1, f_2``.
    """
    n_c = scene.n_contacts
    E, V = scene.effort_joints, scene.velocity_joints
    N = np.vstack([scene.Wn, -scene.Jn[:, E].T])
    T = np.vstack([scene.Wt, -scene.Jt[:, E].T])
    d = N.shape[0]
    thII = scene.joint_velocity[V]
    a_n, a_t = -scene.Jn[:, V] @ thII, -scene.Jt[:, V] @ thII
    b = np.concatenate([scene.g_obj, np.nan_to_num(scene.joint_effort)[E] - scene.g_man[E]])
    v_scale = float(max(np.max(np.abs(a_n), initial=0.0), np.max(np.abs(a_t), initial=0.0))) or 1.0
    f_scale = float(np.max(np.abs(b), initial=0.0)) or 1.0
    Z, I = np.zeros((n_c, n_c)), np.eye(n_c)
    G = np.hstack([N, T, -T, np.zeros((d, n_c))])
    Mxx = np.block([[Z, Z, Z, Z], [Z, Z, Z, I], [Z, Z, Z, I], [np.diag(scene.mu), -I, -I, Z]])
    zd = np.zeros((d, d))
    M = np.block([[zd, zd, -G], [zd, zd, G], [G.T, -G.T, Mxx]])
    a = np.concatenate([a_n, a_t, -a_t, np.zeros(n_c)]) / v_scale
    q = np.concatenate([-b / f_scale, b / f_scale, a])
    return M, q, v_scale, f_scale


def _letters(scene: Scene, qdot, thetadot, tol: Tolerances) -> str:
    vtol = tol.velocity * velocity_scale(scene)
    v_n, v_t = relative_velocity(scene, qdot, thetadot)
    return "".join("B" if vn > vtol else ("S" if abs(vt) > vtol else "R") for vn, vt in zip(v_n, v_t))


def solve_lcp(scene: Scene, tol: Tolerances = DEFAULT_TOLERANCES, max_pivots: int | None = DEFAULT_MAX_PIVOTS) -> LcpResult:
    """One feasible contact mode of ``scene`` by Lemke's method, verified (see the module docstring).

    Parameters
    ----------
    scene : Scene
    tol : Tolerances
        Velocity tolerance for reading the mode off the solution, and the
        tolerances of the verifying :func:`~qsplan.mechanics.modes.reference.check_mode`.
    max_pivots : int, optional
        Lemke's pivot cap (default ``50 n + 100`` for ``n = 2 (3 + |tau_I|) + 4 n_c``).

    Returns
    -------
    LcpResult
        ``mode`` is None unless ``status == "solved"``.  ``"ray termination"`` does
        not prove that the scene jams (the LCP's matrix is not copositive-plus).
    """
    M, q, v_scale, _ = quasistatic_lcp(scene)
    res = lemke(M, q, max_pivots=max_pivots)
    if not res.solved:
        return LcpResult(None, None, res.status, pivots=res.pivots)
    d = scene.dof
    u = (res.z[:d] - res.z[d : 2 * d]) * v_scale
    thetadot = np.where(scene.effort_controlled, 0.0, np.nan_to_num(scene.joint_velocity))
    thetadot[scene.effort_joints] = u[3:]
    letters = _letters(scene, u[:3], thetadot, tol)
    mode = ContactMode(letters)
    if mode.n_constraints != scene.dof:
        return LcpResult(None, None, LcpStatus.DEGENERATE, letters, None, res.pivots)
    chk = check_mode(scene, mode, tol)
    if chk.feasible:
        return LcpResult(mode, chk.solution, LcpStatus.SOLVED, letters, chk.status, res.pivots)
    if chk.status in (Status.KINEMATICS_SINGULAR, Status.EQUILIBRIUM_SINGULAR):
        status = LcpStatus.ILL_CONDITIONED
    elif chk.status in Status.DEGENERATE:
        status = LcpStatus.DEGENERATE
    else:
        status = LcpStatus.NOT_VERIFIED
    return LcpResult(None, None, status, letters, chk.status, res.pivots)
