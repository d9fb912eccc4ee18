"""The graphical test of Corollary 1 (Section 4.1, Fig. 4), done with lines of action.

Three unisense contact wrenches ``w_1, w_2, w_3`` (intensities ``c_k >= 0``) can
balance an external wrench ``g`` when

1. *negative span*: the force of ``-g`` lies in the cone spanned by the three
   contact forces, and
2. *moment sense*: for each pair ``(i, j)``, about the intersection ``p_ij`` of
   their lines of action, ``g`` and the third wrench ``w_k`` have moments of
   opposite sense.

Here both are evaluated geometrically, from points, directions and planar cross
products, without the determinants of Appendix A, so that the tests can compare
the two.  For a 3S mode the wrenches are the active friction-cone edges
``w_in - xi_i mu_i w_it`` (eq. 17); for an RS mode (Section 4.2) they are the
two edges ``w_rn +/- mu_r w_rt`` of the rolling contact's cone and the active
edge of the sliding one.

Notes
-----
Taking moments about ``p_ij`` removes ``w_i`` and ``w_j`` from equilibrium, so
``c_k m_k(p_ij) = -m_g(p_ij)``: condition 2 says exactly ``c_k >= 0`` for all
three, and therefore implies condition 1 (``-g = sum c_k w_k``); condition 1 is
reported separately because it is the quick visual check.  A pair of parallel
lines meets at a point at infinity; the moment about it is taken in the limit,
``m(s d) / s -> f x d``.  Boundaries are included (a moment of zero, ``g``
through a vertex, means ``c_k = 0``), as in the non-strict inequalities (35)-(36).
The test needs ``W_Amu`` nonsingular: the three lines not concurrent (nor all
parallel); otherwise :attr:`GraphicalTest.degenerate` is set and it is not feasible.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qsplan.mechanics.model.contact import cross2
from qsplan.mechanics.errors import ModeError, QsplanError
from qsplan.mechanics.modes.contact_mode import mode_from_letters
from qsplan.mechanics.numerics import DEFAULT_TOLERANCES, Tolerances
from qsplan.mechanics.muspace.regions import mode_kinematics
from qsplan.mechanics.model.scene import Scene

__all__ = [
    "LineOfAction",
    "GraphicalTest",
    "line_of_action",
    "graphical_test",
    "active_wrenches",
    "graphical_test_mode",
    "contact_points",
]

#: Two lines count as parallel when the sine of their angle is below this.
PARALLEL_SINE = 1e-12


@dataclass(frozen=True, slots=True, eq=False)
class LineOfAction:
    """The line of action of a planar wrench with nonzero force.

    Attributes
    ----------
    wrench : ndarray, shape (3,)
        ``[f_x, f_y, m]``, moment about the world origin.
    point : ndarray, shape (2,)
        The point of the line nearest the origin (m).
    direction : ndarray, shape (2,)
        Unit vector along the force.
    """

    wrench: np.ndarray
    point: np.ndarray
    direction: np.ndarray

    def moment_about(self, p) -> np.ndarray:
        """Moment of the wrench about points ``p`` (shape (..., 2)): ``m - p x f``."""
        return self.wrench[2] - cross2(p, self.wrench[:2])


def line_of_action(wrench) -> LineOfAction:
    """The line of action of ``wrench`` (shape (3,)): points ``p`` with ``p x f = m``.

    Raises
    ------
    QsplanError
        If the force is zero (a pure moment has no line of action).
    """
    w = np.asarray(wrench, dtype=float)
    f = w[:2]
    norm = float(np.hypot(f[0], f[1]))  # hypot: no underflow for tiny forces
    if not (norm > 0 and np.isfinite(norm)):
        raise QsplanError(f"wrench: a pure moment has no line of action; got {w.tolist()}")
    d = f / norm
    return LineOfAction(w, (w[2] / norm) * np.array([d[1], -d[0]]), d)


@dataclass(frozen=True, slots=True, eq=False)
class GraphicalTest:
    """Outcome of Corollary 1 for three contact wrenches and an external wrench.

    Attributes
    ----------
    lines : tuple of LineOfAction
        The three contact wrenches' lines.
    g_line : LineOfAction or None
        The external wrench's line; None for a pure moment.
    vertices : ndarray, shape (3, 2)
        ``p_12, p_23, p_31``; a row of NaN where the two lines are parallel.
    negative_span : bool
        Condition 1.
    moment_sense : ndarray of bool, shape (3,)
        Condition 2 for the pairs (1, 2), (2, 3), (3, 1) (third wrench 3, 1, 2).
    positively_spanning : bool
        The three contact forces positively span the plane (Fig. 4(b)) rather than a wedge (Fig. 4(a)).
    degenerate : bool
        The three lines are concurrent or all parallel (``W_Amu`` singular).
    """

    lines: tuple
    g_line: LineOfAction | None
    vertices: np.ndarray
    negative_span: bool
    moment_sense: np.ndarray
    positively_spanning: bool
    degenerate: bool

    @property
    def feasible(self) -> bool:
        """Both conditions hold and the configuration is not degenerate."""
        return (not self.degenerate) and self.negative_span and bool(np.all(self.moment_sense))


def _in_cone(v, dirs) -> tuple[bool, bool]:
    """Is ``v`` in the cone of the 2-D directions ``dirs``; do they positively span the plane."""
    ang = np.sort(np.arctan2(dirs[:, 1], dirs[:, 0]))
    gaps = np.diff(np.concatenate([ang, ang[:1] + 2 * np.pi]))
    g = int(np.argmax(gaps))
    spanning = gaps[g] < np.pi
    if not np.any(v):
        return True, spanning
    if spanning:
        return True, True
    start = ang[(g + 1) % ang.size]  # the cone runs counterclockwise from just after the largest gap...
    width = 2 * np.pi - gaps[g]  # ...to just before it
    a = (np.arctan2(v[1], v[0]) - start) % (2 * np.pi)
    eps = 1e-12
    return bool(a <= width + eps or a >= 2 * np.pi - eps), False


def graphical_test(wrenches, g) -> GraphicalTest:
    """Corollary 1 for three unisense contact wrenches, geometrically.

    Parameters
    ----------
    wrenches : array-like, shape (3, 3)
        Columns are the contact wrenches per unit intensity ``[f_x; f_y; m]``.
    g : array-like, shape (3,)
        The external wrench ``g_obj``.

    Returns
    -------
    GraphicalTest

    Raises
    ------
    QsplanError
        If a contact wrench is a pure moment (no line of action).
    """
    W = np.asarray(wrenches, dtype=float)
    g = np.asarray(g, dtype=float)
    lines = tuple(line_of_action(W[:, k]) for k in range(3))
    g_line = line_of_action(g) if np.any(g[:2]) else None
    pairs = ((0, 1, 2), (1, 2, 0), (2, 0, 1))
    vertices = np.full((3, 2), np.nan)
    sense = np.zeros(3, dtype=bool)
    m_k = np.zeros(3)
    m_scale = np.zeros(3)
    for v, (i, j, k) in enumerate(pairs):
        a, b = lines[i], lines[j]
        s = cross2(a.direction, b.direction)
        if abs(s) > PARALLEL_SINE:  # p = a.point + u a.dir on line b: (p - b.point) x b.dir = 0
            u = cross2(b.point - a.point, b.direction) / s
            p = a.point + u * a.direction
            vertices[v] = p
            m_k[v] = lines[k].moment_about(p)
            m_scale[v] = abs(lines[k].wrench[2]) + float(np.hypot(*p)) * float(np.hypot(*lines[k].wrench[:2]))
            m_g = g[2] - cross2(p, g[:2])
        else:  # parallel lines meet at infinity along d: moments scale as f x d
            d = a.direction
            m_k[v] = cross2(lines[k].wrench[:2], d)
            m_scale[v] = float(np.hypot(*lines[k].wrench[:2]))
            m_g = cross2(g[:2], d)
        sense[v] = m_k[v] * m_g <= 0
    # concurrent lines: the third line passes through the vertex of the other two
    degenerate = bool(np.any(np.abs(m_k) <= 1e-12 * m_scale))
    negative_span, spanning = _in_cone(-g[:2], W[:2].T)
    return GraphicalTest(lines, g_line, vertices, negative_span, sense, spanning, degenerate)


def active_wrenches(scene: Scene, mode, mu=None, tol: Tolerances = DEFAULT_TOLERANCES) -> np.ndarray:
    """The three unisense contact wrenches of a 3S or RS mode (eq. 17, Section 4.2), shape (3, 3).

    3S: ``w_in - xi_i mu_i w_it`` of the sliding contacts in order.  RS: ``w_rn + mu_r w_rt``,
    ``w_rn - mu_r w_rt`` and the sliding contact's ``w_sn - xi_s mu_s w_st``.

    Raises
    ------
    ModeError
        For other modes, or when the mode's kinematic stage fails (no sliding directions).
    """
    status, kin = mode_kinematics(scene, mode, tol)
    mode = mode_from_letters(mode)
    if mode.kind not in ("3S", "RS"):
        raise ModeError(f"mode {mode.letters}: the graphical test covers 3S and RS modes; got a {mode.kind} mode")
    if kin is None:
        raise ModeError(f"mode {mode.letters}: kinematic stage fails ({status}); no sliding directions (eq. 16)")
    mu = scene.mu if mu is None else np.broadcast_to(np.asarray(mu, float), (scene.n_contacts,))
    xi = kin.xi[0]
    edge = lambda i: scene.Wn[:, i] - xi[i] * mu[i] * scene.Wt[:, i]  # noqa: E731
    if mode.kind == "3S":
        return np.column_stack([edge(i) for i in mode.sliding])
    (r,), (s,) = mode.rolling, mode.sliding
    return np.column_stack([scene.Wn[:, r] + mu[r] * scene.Wt[:, r], scene.Wn[:, r] - mu[r] * scene.Wt[:, r], edge(s)])


def graphical_test_mode(scene: Scene, mode, mu=None, tol: Tolerances = DEFAULT_TOLERANCES) -> GraphicalTest:
    """Corollary 1 for a 3S or RS mode of a scene at friction ``mu`` (default the scene's)."""
    return graphical_test(active_wrenches(scene, mode, mu, tol), scene.g_obj)


def contact_points(scene: Scene) -> np.ndarray:
    """Contact points recovered from the wrench columns (``r x n = m_n``, ``r x t = m_t``), shape (n_c, 2).

    Exact for wrenches built by eq. (1) (``n`` and ``t`` orthonormal); for raw wrench
    columns it is the least-squares point.
    """
    out = np.zeros((scene.n_contacts, 2))
    for i in range(scene.n_contacts):
        n, t = scene.Wn[:2, i], scene.Wt[:2, i]
        A = np.array([[n[1], -n[0]], [t[1], -t[0]]])
        out[i] = np.linalg.lstsq(A, np.array([scene.Wn[2, i], scene.Wt[2, i]]), rcond=None)[0]
    return out

