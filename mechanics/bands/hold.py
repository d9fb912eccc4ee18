"""Certified holds: a proof that nothing moves while the hand holds still and ramps a torque (issue 23, item 3).

The setting: a :class:`~qsplan.mechanics.Scene` in which every velocity-controlled joint is **held** (commanded
velocity 0, whatever the scene's ``joint_velocity`` says) and every effort-controlled joint applies a torque
``tau``.  The unknowns of a first-order motion are ``x = (nu, thetadot_e)``: the workpiece's twist ``nu`` (m/s, m/s,
rad/s; about the world origin, as ``W``) and the effort joints' velocities.

Proof.  A motion must keep every contact closed or opening (eq. 6; held joints contribute nothing):

    v_n,i = Wn_i^T nu - Jn_i,e thetadot_e >= 0,   i.e.  A x >= 0  with  A = [Wn^T, -Jn[:, e]]  (n_c, 3 + n_e).

Multiplying the equilibria by the motion, eq. (2) by ``nu`` and eq. (3)'s effort rows by ``thetadot_e``,

    (g_obj + w) . nu + (tau - g_man,e) . thetadot_e  =  -c^T v  =  -c_t . v_t  >= 0,

because ``c_n . v_n = 0`` (complementarity, eqs. 9-10) and friction opposes sliding (eqs. 7-8): the applied loads'
power ``P(x) = p . x``, ``p = (g_obj + w, tau - g_man,e)``, equals the dissipation of sliding friction.  (Note the
sign of ``g_man``: eq. (3) reads ``J^T c = tau - g_man``, so ``tau - g_man`` is what the joint transmits.)  Hence if
``P(x) < 0`` for every admissible ``x != 0``, no motion satisfies the model, **for every friction coefficient**:
friction is not used (conservative: a hold that friction alone would secure is refused).  By Farkas' lemma that
holds iff ``A`` has full column rank (otherwise ``A x = 0`` for some ``x != 0``, and ``x`` or ``-x`` has
``P >= 0``) and ``-p`` is in the interior of the cone of ``A``'s rows: ``-p = A^T lambda`` with every
``lambda_i > 0``.  Then ``lambda`` is a frictionless equilibrium (eqs. 2-3 with ``c_t = 0``, ``c_n = lambda``),
and ``P(x) = -lambda . A x < 0`` unless ``A x = 0``, i.e. ``x = 0``.  :func:`prove_hold` finds the largest ``t``
with ``lambda >= t`` (a linear programme), certifies it against the programme's rounding
(``t - |A^T lambda + p| / sigma_min(A)``: the exact solution nearest ``lambda`` differs by at most that) and proves
the hold iff the rank is full and the certified ``t`` exceeds :data:`MARGIN_TOL`.  Otherwise the dual programme
gives a witness: an admissible ``x`` (``A x >= 0``, ``sum(A x) = 1``) along which the loads do work ``p . x >= 0``.

Ramps and boxes.  ``p`` is affine in ``(tau, w)``, and the interior of a convex cone is convex, so if the hold is
proved at finitely many ``(tau_k, w_k)`` it is proved on their convex hull (with the convex combination of the
certificates, whose every entry is at least the smallest margin): a torque ramp ``[tau_a, tau_b]`` and a wrench
box are proved by their vertices (:func:`prove_hold` takes the ramp's ends and the box's vertices), and the set of
torques a hold is proved at is an interval (:func:`hold_torque_interval`).  Units SI (N, N m, m/s, rad/s).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qsplan.mechanics.bands.disturbance import check_wrench_box
from qsplan.mechanics.errors import QsplanError
from qsplan.mechanics.model.scene import Scene

__all__ = ["INTERVAL_MARGIN", "MARGIN_CAP", "MARGIN_TOL", "RANK_TOL", "HoldProof", "hold_load", "hold_matrix",
           "hold_torque_interval", "prove_hold"]  # fmt: skip

#: The certified margin (N, the smallest normal force of the frictionless equilibrium after the rounding
#: correction) a proof needs.  Strictly positive: ``t = 0`` is a boundary case (a motion with ``P = 0``, e.g. a
#: weightless block lifting off its floor), and the correction already covers the programme's own tolerances,
#: so what is left is the rounding of the check itself (~1e-16 of loads of 0.01-100 N); 1 nN stays far above it
#: and far below any force a hand's torque resolution gives (0.02 N m on 0.1 m: 0.2 N).
MARGIN_TOL = 1e-9

#: A matrix ``A`` whose smallest singular value is below this fraction of its largest is rank deficient (a motion
#: no contact resists).  Its columns mix unit normals (1) and moment arms or Jacobian entries (~0.1 m on these
#: hands); 1e-9 is seven orders above double rounding (~1e-16) times the sizes, and a nearer-singular ``A`` would
#: need normal forces some 1e9 times the load for a certificate.
RANK_TOL = 1e-9

#: The margin is capped here (N): an internal squeeze (``A^T lambda = 0`` with ``lambda > 0``: the contacts
#: pressing on each other, e.g. a block between two walls) adds to every normal force without limit.  1 kN is far
#: above any force the bundled hands exert (a few N m on ~0.1 m fingers: tens of N).
MARGIN_CAP = 1e3

#: The smallest normal force (N) the ends of :func:`hold_torque_interval` keep by default: a thousand times
#: :data:`MARGIN_TOL`, so that its ends (where the programme puts a normal force exactly at the margin, up to
#: rounding) are proved by :func:`prove_hold`; as the margin tends to 0 the interval tends to the closure of the
#: set of torques at which a hold is proved.
INTERVAL_MARGIN = 1e-6


@dataclass(frozen=True, slots=True, eq=False)
class HoldProof:
    """The answer of :func:`prove_hold`: proved or refused, with what checks it.

    Attributes
    ----------
    proved : bool
        Nothing moves at every vertex ``(torques[k], wrenches[k])``, hence on their convex hull, for every friction.
    margin : float
        The smallest certified normal force (N) over the vertices: the frictionless equilibrium's smallest
        ``lambda_i`` minus the rounding correction; ``-inf`` when ``A`` is rank deficient.  Capped at
        :data:`MARGIN_CAP`.
    reason : str
        ``"proved"``, or why not: ``"rank deficient: ..."`` or ``"the load does work along x = ..."``.
    torques : ndarray, shape (k, n_e)
        The effort joints' torques (N m or N) at each vertex.
    wrenches : ndarray, shape (k, 3)
        The disturbance wrench (N, N, N m) at each vertex (zeros without a box).
    certificates : ndarray, shape (k, n_c)
        ``lambda`` at each vertex (N): ``-p = A^T lambda``; NaN where ``A`` is rank deficient.
    margins : ndarray, shape (k,)
        The certified margin (N) at each vertex.
    residuals : ndarray, shape (k,)
        ``max |A^T lambda + p|`` at each vertex (N, N, N m and the joints' units).
    rank : int
        The rank of ``A`` (full: ``3 + n_e``).
    witness : ndarray, shape (3 + n_e,) or None
        When refused: an admissible motion ``x = (nu, thetadot_e)`` (``A x >= 0``) along which the loads do work
        (``p . x >= 0``, up to the margin); None when proved.
    witness_vertex : int or None
        The vertex whose load the witness is for.
    witness_power : float
        ``p . x`` along the witness (W per unit of the witness's normal velocities: N); NaN when proved.
    contact_names, effort_joints : tuple of str
        The scene's contacts (``certificates``' columns) and effort joints (``torques``' columns).
    capped : bool
        The smallest margin reached :data:`MARGIN_CAP` (a large load, an internal squeeze, or no admissible motion at
        all: immobilised at first order); ``margin`` is then a floor.
    """

    proved: bool
    margin: float
    reason: str
    torques: np.ndarray
    wrenches: np.ndarray
    certificates: np.ndarray
    margins: np.ndarray
    residuals: np.ndarray
    rank: int
    witness: np.ndarray | None
    witness_vertex: int | None
    witness_power: float
    contact_names: tuple
    effort_joints: tuple
    capped: bool


def _check_scene(scene) -> None:
    if not isinstance(scene, Scene):
        raise QsplanError(f"scene: expected a qsplan.mechanics.Scene; got {type(scene).__name__}")
    if scene.n_joints and scene.effort_controlled.all():
        raise QsplanError(f"scene.effort_controlled: a hold needs at least one held (velocity-controlled) joint; "
                          f"every joint {list(scene.joint_names)} is effort-controlled")  # fmt: skip


def _check_torques(scene, torques) -> np.ndarray:
    """The torque vertices, shape (k, n_e): ``torques`` as (k, n_e), (n_e,), or (k,) for one effort joint."""
    n_e = len(scene.effort_joints)
    if torques is None:
        return scene.joint_effort[scene.effort_joints][None]
    try:
        tau = np.array(torques, dtype=float)
    except (TypeError, ValueError):
        raise QsplanError(f"torques: expected numbers (N m or N), shape (k, {n_e}); got {torques!r}") from None
    if tau.ndim == 0 or (tau.ndim == 1 and n_e == 1):
        tau = tau.reshape(-1, 1)
    elif tau.ndim == 1:
        tau = tau[None]
    if tau.ndim != 2 or tau.shape[1] != n_e or tau.shape[0] == 0:
        raise QsplanError(f"torques: expected shape (k, {n_e}) (k >= 1 vertices, one column per effort joint "
                          f"{[scene.joint_names[j] for j in scene.effort_joints]}); got shape {tau.shape}")  # fmt: skip
    if not np.all(np.isfinite(tau)):
        raise QsplanError(f"torques: expected finite numbers; got {tau.tolist()}")
    return tau


def hold_matrix(scene: Scene) -> np.ndarray:
    """``A = [Wn^T, -Jn[:, e]]``, shape (n_c, 3 + n_e): row ``i`` times ``x = (nu, thetadot_e)`` is contact ``i``'s
    normal velocity with the velocity-controlled joints held (eqs. 5-6)."""
    return np.hstack([scene.Wn.T, -scene.Jn[:, scene.effort_joints]])


def hold_load(scene: Scene, torques, wrench=None) -> np.ndarray:
    """``p = (g_obj + w, tau - g_man,e)``, shape (3 + n_e,): the applied loads' power is ``p . x`` (eqs. 2-3).

    Parameters
    ----------
    torques : array-like, shape (n_e,)
        The effort joints' torques (N m or N).
    wrench : array-like, shape (3,), optional
        A disturbance wrench on the workpiece (N, N, N m), about the world origin.
    """
    w = np.zeros(3) if wrench is None else np.asarray(wrench, dtype=float)
    e = scene.effort_joints
    return np.concatenate([scene.g_obj + w, np.asarray(torques, dtype=float).reshape(-1) - scene.g_man[e]])


def _lp(*args, **kwargs):
    """``scipy.optimize.linprog(..., method="highs")``'s answer from HiGHS directly (:func:`qsplan.mechanics.solver.lp.
    solve_lp`: the same solver and settings, without ~0.5 s of importing ``scipy.optimize``)."""
    from qsplan.mechanics.solver.lp import solve_lp

    return solve_lp(*args, **kwargs)


def _certificate(A, p, sigma_min):
    """``(lambda, certified t, residual, capped)``: the largest ``t`` with ``A^T lambda = -p``, ``lambda >= t``, ``t``
    capped at :data:`MARGIN_CAP` (``capped``: the programme reached it)."""
    n_c, m = A.shape
    cost = np.zeros(n_c + 1)
    cost[-1] = -1.0  # maximise t
    ub = np.hstack([-np.eye(n_c), np.ones((n_c, 1))])  # t - lambda_i <= 0
    eq = np.hstack([A.T, np.zeros((m, 1))])
    bounds = [(None, None)] * n_c + [(None, MARGIN_CAP)]
    res = _lp(cost, A_ub=ub, b_ub=np.zeros(n_c), A_eq=eq, b_eq=-p, bounds=bounds)
    if res.status != 0:  # full rank: A^T lambda = -p always has solutions, so the programme is feasible and bounded
        raise QsplanError(f"prove_hold: HiGHS gave no answer for the hold's certificate ({res.message})")
    lam = res.x[:n_c]
    r = A.T @ lam + p
    t = float(lam.min()) - float(np.linalg.norm(r)) / sigma_min
    return lam, min(t, MARGIN_CAP), float(np.abs(r).max()), bool(res.x[-1] >= MARGIN_CAP)


def _witness(A, p):
    """``(x, p . x)``: the admissible motion (``A x >= 0``, ``sum(A x) = 1``) along which the loads do most work.

    The dual of :func:`_certificate` (uncapped): its optimum is ``-t``."""
    n_c, m = A.shape
    res = _lp(-p, A_ub=-A, b_ub=np.zeros(n_c), A_eq=A.sum(axis=0)[None], b_eq=[1.0], bounds=[(None, None)] * m)
    if res.status != 0:  # called when refused: the cone holds a ray, and (pointed at full rank) its slice is compact
        raise QsplanError(f"prove_hold: HiGHS gave no answer for the hold's witness ({res.message})")
    return res.x, float(p @ res.x)


def _names(scene, n_e):
    e = scene.effort_joints
    return ("nu_x", "nu_y", "omega") + tuple(f"thetadot_{scene.joint_names[j]}" for j in e[:n_e])


def _describe(scene, x) -> str:
    x = x / np.abs(x).max() + 0.0  # + 0.0: no "-0" in the message
    return "(" + ", ".join(f"{n}={v:.4g}" for n, v in zip(_names(scene, len(x) - 3), x)) + ")"


def prove_hold(scene: Scene, torques=None, disturbance=None) -> HoldProof:
    """Prove that nothing moves while the velocity-controlled joints are held and the effort joints apply ``torques``.

    Parameters
    ----------
    scene : Scene
        The contacts and loads; its velocity-controlled joints are held (their commanded velocities are not used),
        its friction coefficients are not used (the proof holds for every friction).
    torques : array-like, shape (k, n_e), optional
        Torque vertices (N m or N): a ramp ``[tau_a, tau_b]`` is its two ends, and every torque between is proved
        with them.  Shape (k,) for one effort joint.  Default the scene's ``joint_effort``.
    disturbance : WrenchBox, optional
        A box of wrenches added to ``g_obj`` (N, N, N m); every torque vertex is combined with every box vertex.

    Returns
    -------
    HoldProof
        Proved iff ``A`` has full column rank and every vertex's certified margin exceeds :data:`MARGIN_TOL`.

    Raises
    ------
    QsplanError
        ``scene`` not a Scene or with every joint effort-controlled; ``torques`` of the wrong shape or not finite;
        ``disturbance`` not a WrenchBox.

    References
    ----------
    Eqs. (2), (3), (5)-(10); the module docstring gives the proof.
    """
    _check_scene(scene)
    tau = _check_torques(scene, torques)
    box = check_wrench_box(disturbance)
    W = np.zeros((1, 3)) if box is None else box.vertices()
    taus, wrenches = np.repeat(tau, len(W), axis=0), np.tile(W, (len(tau), 1))
    A = hold_matrix(scene)
    n_c, m = A.shape
    loads = np.array([hold_load(scene, t, w) for t, w in zip(taus, wrenches)])
    sv = np.linalg.svd(A, compute_uv=False)
    rank = int(np.sum(sv > RANK_TOL * sv[0])) if sv.size and sv[0] > 0 else 0
    names = (scene.contact_names, tuple(scene.joint_names[j] for j in scene.effort_joints))
    k = len(loads)
    if rank < m:
        _, _, vt = np.linalg.svd(A)
        x = vt[-1]  # A x = 0: x and -x are both admissible; the sign with P >= 0 where |P| is largest
        i = int(np.argmax(np.abs(loads @ x)))
        x = x if loads[i] @ x >= 0 else -x
        reason = (f"rank deficient ({rank} < {m}): a motion no contact resists, x = {_describe(scene, x)}, "
                  f"both ways admissible, the load's power along it {loads[i] @ x:.4g}")  # fmt: skip
        nan = np.full(k, np.nan)
        return HoldProof(False, -np.inf, reason, taus, wrenches, np.full((k, n_c), np.nan), np.full(k, -np.inf), nan,
                         rank, x, i, float(loads[i] @ x), *names, False)  # fmt: skip
    lam, margins, residuals, capped = np.empty((k, n_c)), np.empty(k), np.empty(k), np.empty(k, dtype=bool)
    for i, p in enumerate(loads):
        lam[i], margins[i], residuals[i], capped[i] = _certificate(A, p, float(sv[-1]))
    worst = int(np.argmin(margins))
    margin = float(margins[worst])
    if margin > MARGIN_TOL:
        return HoldProof(True, margin, "proved", taus, wrenches, lam, margins, residuals, rank, None, None, np.nan,
                         *names, bool(capped[worst]))  # fmt: skip
    x, power = _witness(A, loads[worst])
    at = f"torques {taus[worst].tolist()}" + ("" if box is None else f", wrench {wrenches[worst].tolist()}")
    reason = (f"the load does work along x = {_describe(scene, x)} at {at}: its power {power + 0.0:.4g} N per "
              f"unit of normal velocity (>= -{MARGIN_TOL:g}: the margin {margin + 0.0:.4g} N is not above "
              "MARGIN_TOL)")  # fmt: skip
    return HoldProof(False, margin, reason, taus, wrenches, lam, margins, residuals, rank, x, worst, power, *names,
                     False)  # fmt: skip


def hold_torque_interval(scene: Scene, disturbance=None, margin: float = INTERVAL_MARGIN) -> tuple:
    """The torques of the scene's one effort joint at which a hold is proved with every normal force >= ``margin``.

    Parameters
    ----------
    scene : Scene
        Exactly one effort-controlled joint; the others held.
    disturbance : WrenchBox, optional
        Every wrench of the box at once (one torque, a certificate per box vertex).
    margin : float
        The smallest normal force (N) of every vertex's frictionless equilibrium; above :data:`MARGIN_TOL`.

    Returns
    -------
    (lo, hi) : tuple of float
        The closed interval (N m or N; ``-inf``/``inf`` when unbounded), ``(nan, nan)`` when empty (``A`` rank
        deficient, or no torque has such an equilibrium).  An interval because the proved set is convex (module
        docstring); :func:`prove_hold` on its finite ends proves it.

    Raises
    ------
    QsplanError
        As :func:`prove_hold`; not exactly one effort joint; ``margin`` not a number in (MARGIN_TOL, MARGIN_CAP).
    """
    _check_scene(scene)
    if len(scene.effort_joints) != 1:
        raise QsplanError(f"scene.effort_controlled: the torque interval needs exactly one effort-controlled joint; "
                          f"got {len(scene.effort_joints)}")  # fmt: skip
    if not (isinstance(margin, (int, float, np.floating)) and MARGIN_TOL < margin < MARGIN_CAP):
        raise QsplanError(f"margin: expected a force in ({MARGIN_TOL:g}, {MARGIN_CAP:g}) N; got {margin!r}")
    box = check_wrench_box(disturbance)
    W = np.zeros((1, 3)) if box is None else box.vertices()
    A = hold_matrix(scene)
    n_c, m = A.shape
    sv = np.linalg.svd(A, compute_uv=False)
    if sv[-1] <= RANK_TOL * sv[0]:
        return (np.nan, np.nan)
    K = len(W)
    # variables (tau, lambda_1, ..., lambda_K): A^T lambda_k + e tau = -(p0 + w_k), lambda_k >= margin
    eq = np.zeros((K * m, 1 + K * n_c))
    rhs = np.empty(K * m)
    for k, w in enumerate(W):
        rows = slice(k * m, (k + 1) * m)
        eq[rows, 0] = np.eye(m)[-1]
        eq[rows, 1 + k * n_c:1 + (k + 1) * n_c] = A.T
        rhs[rows] = -hold_load(scene, [0.0], w)
    bounds = [(None, None)] + [(float(margin), None)] * (K * n_c)
    ends = []
    for sign in (1.0, -1.0):
        res = _lp(np.eye(1 + K * n_c)[0] * sign, A_eq=eq, b_eq=rhs, bounds=bounds)
        if res.status == 2:
            return (np.nan, np.nan)
        if res.status == 3:
            ends.append(-sign * np.inf)
        elif res.status == 0:
            ends.append(float(res.x[0]))
        else:
            raise QsplanError(f"hold_torque_interval: HiGHS gave no answer ({res.message})")
    return (ends[0], ends[1])
