"""States on the contact manifold of a described hand: a grasp held while the workpiece slides (Section 3, eqs. 1-6).

A state of a slide is the workpiece's ``x`` and the fingers' *free* joints (every joint but each
finger's last, :meth:`qsplan.hands.chain_hand.ChainHand.free_joints`); each finger's last joint closes
onto the workpiece (:func:`qsplan.hands.chain_hand.close_grasp`), so every state keeps four contacts.
A slide keeps its grasp: each finger touches the same feature with the same link (its *contact key*).

Along a motion the closing joints move so that the finger contacts stay closed: eq. 6 with equality,
``v_n = W_n^T nu - J_n thetadot = 0`` at each finger contact, solved for the closing joint's rate
(:func:`closing_rates`).  The mode a motion gives (:func:`motion_mode`) follows from the same
kinematics: a contact slides where its tangential velocity ``W_t^T nu - J_t thetadot`` is not zero, and a
slide keeps each contact's sliding direction (a reversal passes through rolling).

:func:`judge_states` judges a batch of states of one slide (grasp, collisions, limits, the mode, a
guaranteed band of the effort-controlled joint at least the torque resolution wide, every competitor
precluded, :func:`qsplan.mechanics.bands.batched_robust.robust_bands`).  Units SI (m, rad, m/s, rad/s, N m).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qsplan.mechanics.errors import QsplanError

__all__ = ["SLIP_TOL", "JudgedStates", "check_state", "closed_state", "closing_rates", "free_problem", "judge_states",
           "motion_mode", "slip_signs", "state_problem"]

#: Tangential speed (m/s), relative to the workpiece's speed, below which a contact rolls rather than
#: slides: the rates of a rolling contact compute as ~1e-16 of the speed; a sliding finger contact of the
#: bundled hands slips at 1e-3 of it or more.
SLIP_TOL = 1e-9


@dataclass(frozen=True, slots=True, eq=False)
class JudgedStates:
    """States of one slide, judged.

    Attributes
    ----------
    x : ndarray, shape (n,)
        Workpiece x (m).
    q, qd : ndarray, shape (n, n_j)
        Closed joint positions and rates (rad or m, per second), nan where the state has no grasp.
    ok : ndarray of bool, shape (n,)
    reasons : tuple of (str or None)
        Why each state is not ok.
    lower, upper : ndarray, shape (n,)
        Guaranteed band of the effort-controlled joint (N m or N), nan without one.
    scenes : tuple
        The scenes (None where the state has no grasp).
    """

    x: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    ok: np.ndarray
    reasons: tuple
    lower: np.ndarray
    upper: np.ndarray
    scenes: tuple

    @property
    def width(self) -> np.ndarray:
        return self.upper - self.lower


def closed_state(hand, x: float, q) -> tuple:
    """``(q closed (n_j,), keys ((link, kind, feature) per finger), flush, problem)`` at ``x`` from the free joints of
    ``q``; ``problem`` says why there is no grasp (then the rest is None)."""
    from qsplan.hands.chain_hand import close_grasp

    out = close_grasp(hand, x, q)
    if out is None:
        return None, None, None, "a finger closes onto nothing within its range (or overlaps the workpiece open)"
    qc, closed = out
    return qc, tuple(c.key for c in closed), any(c.flush for c in closed), None


def free_problem(task, x: float, q) -> str | None:
    """Why the configuration ``q`` (n_j,) with the workpiece at ``x`` is invalid, or None: inside the limits and no
    two bodies overlapping (the fingers may touch the workpiece, :func:`qsplan.hands.collision.find_collisions`)."""
    from qsplan.hands.collision import find_collisions

    lim = task.joint_limits
    out = (q < lim[:, 0]) | (q > lim[:, 1])
    if out.any():
        j = int(np.flatnonzero(out)[0])
        return f"joint {task.hand.joint_names[j]} at {q[j]:.6g} outside its limits {lim[j].tolist()}"
    hits = find_collisions(task.hand, task.pose(x), q, first=True)
    return f"collision: {hits[0]}" if hits else None


def check_state(task, x: float, q, keys=None) -> tuple:
    """The closed state at ``x`` (free joints of ``q``) judged as a state of a slide with contact ``keys`` (None: any):
    ``(q closed, keys, problem)``, ``problem`` None for a grasp with one contact per finger, not flush, the same
    features, inside the limits and free of collisions (:func:`free_problem`), else why not (in words)."""
    qc, got, flush, problem = closed_state(task.hand, x, q)
    if problem:
        return None, None, problem
    if keys is not None and got != tuple(keys):
        return qc, got, f"the fingers touch {got}, not the grasp's {tuple(keys)} (a contact change)"
    if flush:
        return qc, got, "a link lies flush with a workpiece edge (two contacts on one finger)"
    return qc, got, free_problem(task, x, qc)


def state_problem(task, x: float, q, keys=None) -> str | None:
    """Why the closed state at ``x`` is no state of a slide with contact ``keys``, or None (:func:`check_state`)."""
    return check_state(task, x, q, keys)[2]


def closing_rates(hand, scene, qd, xdot: float) -> np.ndarray:
    """``qd`` (n_j,) with each finger's closing joint's rate set so that its contact stays closed (eq. 6 with
    equality) while the workpiece moves at ``xdot`` (m/s) along x and the other joints at ``qd``.

    Raises
    ------
    QsplanError
        Where a closing joint cannot move its contact along the normal (``J_n`` zero: a singular grasp).
    """
    qd = np.array(qd, dtype=float)
    nu = np.array([xdot, 0.0, 0.0])
    for f in range(2):
        i, k = 2 + f, hand.finger_joints(f)[-1]
        qd[k] = 0.0
        jn = scene.Jn[i]
        if abs(jn[k]) < 1e-12:
            raise QsplanError(f"q: the {('left', 'right')[f]} finger's last joint cannot move its contact along the normal")
        qd[k] = (scene.Wn[:, i] @ nu - jn @ qd) / jn[k]
    return qd


def slip_signs(scene, qd, xdot: float) -> np.ndarray:
    """The sign of each contact's tangential velocity ``W_t^T nu - J_t thetadot`` (eq. 6), 0 where it is below
    :data:`SLIP_TOL` of ``|xdot|`` (rolling), shape (n_c,)."""
    nu = np.array([xdot, 0.0, 0.0])
    vt = scene.Wt.T @ nu - scene.Jt @ np.asarray(qd, dtype=float)
    return np.where(np.abs(vt) > SLIP_TOL * abs(xdot), np.sign(vt), 0.0)


def motion_mode(scene, qd, xdot: float) -> str:
    """The mode letters of a motion in contact: ``S`` where the contact's tangential velocity (eq. 6) is not zero
    (:func:`slip_signs`), else ``R``."""
    return "".join("S" if s else "R" for s in slip_signs(scene, qd, xdot))


def _scene(task, x, q, qd, effort: int):
    from qsplan.hands.chain_hand import chain_scene

    e = np.arange(len(q)) == effort
    return chain_scene(task.hand, task.pose(x), q, e, np.where(e, 0.0, qd))


def judge_states(task, x, q_free, rates_free, xdot: float, effort: int, keys, mode: str | None = None,
                 signs=None) -> JudgedStates:
    """Judge the states ``(x[k], q_free[k])`` of a slide moving at ``xdot`` (m/s) with the free joints at
    ``rates_free[k]`` (their rates; the closing joints' follow from eq. 6), joint ``effort`` effort-controlled.

    Parameters
    ----------
    x : ndarray, shape (n,)
    q_free, rates_free : ndarray, shape (n, n_j)
        Joint positions and rates; the closing joints' entries are ignored.
    keys : tuple
        The grasp's contact keys (:func:`closed_state`).
    mode : str, optional
        The mode the slide must have (default: the first state's :func:`motion_mode`).
    signs : array-like, shape (n_c,), optional
        The sliding direction of each contact (:func:`slip_signs`) the slide must keep (default: the first state's).
        A sliding contact whose direction reverses passes through rolling between two states (eq. 16: a slide
        keeps its direction), so the mode is not the same all along.

    Returns
    -------
    JudgedStates
    """
    from qsplan.mechanics.bands.batched_robust import robust_bands

    n, n_j = len(x), task.hand.manipulator.n_joints
    q, qd = np.full((n, n_j), np.nan), np.full((n, n_j), np.nan)
    reasons, scenes = [None] * n, [None] * n
    for k in range(n):
        qk, _, why = check_state(task, x[k], q_free[k], keys)
        if why:
            reasons[k] = why
            continue
        try:
            s0 = _scene(task, x[k], qk, np.zeros(n_j), effort)
            qdk = closing_rates(task.hand, s0, rates_free[k], xdot)
            scene = _scene(task, x[k], qk, qdk, effort)
        except QsplanError as exc:
            reasons[k] = f"no four-contact scene: {exc}"
            continue
        sk = slip_signs(scene, qdk, xdot)
        got = "".join("S" if v else "R" for v in sk)
        mode = got if mode is None else mode
        signs = sk if signs is None else np.asarray(signs, dtype=float)
        if got != mode:
            reasons[k] = f"the motion gives mode {got}, not {mode}"
            continue
        if np.any(sk != signs):
            i = int(np.flatnonzero(sk != signs)[0])
            reasons[k] = (f"contact {scene.contact_names[i]} slides the other way (its sliding direction reverses: "
                          f"it rolls in between)")  # fmt: skip
            continue
        q[k], qd[k], scenes[k] = qk, qdk, scene
    lower, upper = np.full(n, np.nan), np.full(n, np.nan)
    idx = [k for k in range(n) if scenes[k] is not None]
    if idx and mode is not None:
        bands = robust_bands([scenes[k] for k in idx], mode, task.mu_range, shared=task.shared_mu,
                             force_margin=task.force_margin)  # fmt: skip
        for k, b in zip(idx, bands):
            if b.feasible:
                lower[k], upper[k] = b.lower, b.upper
            else:
                reasons[k] = f"no guaranteed {mode} band: {b.reason}"
    width = upper - lower
    for k in idx:
        if reasons[k] is None and not width[k] >= task.torque_resolution:
            reasons[k] = f"guaranteed band {width[k]:.4g} narrower than the torque resolution {task.torque_resolution:g}"
    ok = np.array([r is None for r in reasons])
    return JudgedStates(np.asarray(x, float), q, qd, ok, tuple(reasons), lower, upper, tuple(scenes))
