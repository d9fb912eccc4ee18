"""The closed forms of Appendices A and B: regions of 3S and RS modes (eqs. 34-41, 50-60).

Transcribed line by line, with ``# (50)`` ... ``# (60)`` comments, so that a reader can
hold code and paper side by side.  The general construction of
:func:`qsplan.mechanics.muspace.regions.mode_region` gives the same regions for every
mode; these forms are its cross-check.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qsplan.mechanics.errors import ModeError
from qsplan.mechanics.model.scene import Scene
from qsplan.mechanics.modes.kinematics import check_mode_fits
from qsplan.mechanics.muspace.multilinear import Multilinear
from qsplan.mechanics.muspace.regions import MuRegion, empty_region, mode_kinematics
from qsplan.mechanics.numerics import DEFAULT_TOLERANCES, Tolerances

__all__ = ["Appendix3S", "AppendixRS", "appendix_a", "appendix_b", "region_3s", "region_rs"]


@dataclass(frozen=True, slots=True)
class Appendix3S:
    """Appendix A's coefficients (eqs. 50-57) of a 3S mode; contacts numbered 1-3 in mode order.

    ``F[i, j]`` is ``F_{i+1, j+1}`` (diagonal 0).  The denominator of (34) is
    ``A mu1 mu2 mu3 + B_1 mu2 mu3 + B_2 mu1 mu3 + B_3 mu1 mu2 + C . mu + D``.
    """

    A: float
    B: np.ndarray
    C: np.ndarray
    D: float
    E: np.ndarray
    F: np.ndarray
    G: np.ndarray


def _det3(*cols):
    return float(np.linalg.det(np.column_stack(cols)))


def appendix_a(wn, wt, g, xi) -> Appendix3S:
    """Appendix A (eqs. 50-57), transcribed as printed.

    Parameters
    ----------
    wn, wt : array-like, shape (3, 3)
        Columns ``w_in``, ``w_it`` of the three sliding contacts.
    g : array-like, shape (3,)
        ``g_obj``.
    xi : array-like, shape (3,)
        Sliding directions of the three contacts.
    """
    n = [np.asarray(wn, float)[:, i] for i in range(3)]
    t = [np.asarray(wt, float)[:, i] for i in range(3)]
    g = np.asarray(g, float)
    x1, x2, x3 = (float(v) for v in xi)
    F = np.zeros((3, 3))
    F[0, 1], F[0, 2] = x2 * _det3(g, t[1], n[2]), x3 * _det3(g, n[1], t[2])  # (54)
    F[1, 0], F[1, 2] = x1 * _det3(t[0], g, n[2]), x3 * _det3(n[0], g, t[2])  # (55)
    F[2, 0], F[2, 1] = x1 * _det3(t[0], n[1], g), x2 * _det3(n[0], t[1], g)  # (56)
    return Appendix3S(
        A=-x1 * x2 * x3 * _det3(t[0], t[1], t[2]),  # (50)
        B=np.array([x2 * x3 * _det3(n[0], t[1], t[2]),
                    x1 * x3 * _det3(t[0], n[1], t[2]),
                    x1 * x2 * _det3(t[0], t[1], n[2])]),  # (51)
        C=np.array([-x1 * _det3(t[0], n[1], n[2]), -x2 * _det3(n[0], t[1], n[2]), -x3 * _det3(n[0], n[1], t[2])]),  # (52)
        D=_det3(n[0], n[1], n[2]),  # (50)
        E=np.array([-x2 * x3 * _det3(g, t[1], t[2]),
                    -x1 * x3 * _det3(t[0], g, t[2]),
                    -x1 * x2 * _det3(t[0], t[1], g)]),  # (53)
        F=F,
        G=np.array([-_det3(g, n[1], n[2]), -_det3(n[0], g, n[2]), -_det3(n[0], n[1], g)]),  # (57)
    )  # fmt: skip


@dataclass(frozen=True, slots=True)
class AppendixRS:
    """Appendix B's coefficients (eqs. 58-60) of an RS mode.

    ``c_nR = (C1 mu_S + D1) / (A mu_S + B)``, ``c_tR = (C2 mu_S + D2) / (A mu_S + B)``,
    ``c_nS = D3 / (A mu_S + B)`` (eq. 39).
    """

    A: float
    B: float
    C1: float
    C2: float
    D1: float
    D2: float
    D3: float


def appendix_b(w_rn, w_rt, w_sn, w_st, g, xi_s: float) -> AppendixRS:
    """Appendix B (eqs. 58-60), transcribed as printed; arguments are wrench columns, shape (3,)."""
    r_n, r_t, s_n, s_t, g = (np.asarray(v, float) for v in (w_rn, w_rt, w_sn, w_st, g))
    xs = float(xi_s)
    return AppendixRS(
        A=-xs * _det3(r_n, r_t, s_t), B=_det3(r_n, r_t, s_n),  # (58)
        C1=xs * _det3(g, r_t, s_t), C2=xs * _det3(r_n, g, s_t),  # (59)
        D1=-_det3(g, r_t, s_n), D2=-_det3(r_n, g, s_n), D3=-_det3(r_n, r_t, g),  # (60)
    )  # fmt: skip


def region_3s(scene: Scene, mode, tol: Tolerances = DEFAULT_TOLERANCES) -> MuRegion:
    """The region of a 3S mode from Appendix A and inequalities (34)-(36).

    Raises
    ------
    ModeError
        If ``mode`` is not a 3S mode of the scene (three sliding contacts, the rest breaking,
        no effort-controlled joints).
    """
    source = "Appendix A, eqs. (34)-(36), (50)-(57)"
    mode = check_mode_fits(scene, mode)
    if mode.kind != "3S":
        raise ModeError(f"mode {mode.letters}: Appendix A covers 3S modes; got a {mode.kind} mode")
    status, kin = mode_kinematics(scene, mode, tol)
    if kin is None:
        return empty_region(mode, status, scene.n_contacts, source)
    S = list(mode.sliding)
    xi = kin.xi[0]
    co = appendix_a(scene.Wn[:, S], scene.Wt[:, S], scene.g_obj, xi[S])
    i1, i2, i3 = S
    den = Multilinear.from_terms(S, {
        (): co.D, (i1,): co.C[0], (i2,): co.C[1], (i3,): co.C[2],
        (i2, i3): co.B[0], (i1, i3): co.B[1], (i1, i2): co.B[2], (i1, i2, i3): co.A,
    })  # fmt: skip
    nums = []
    for a in range(3):
        others = [b for b in range(3) if b != a]
        terms = {(): co.G[a], tuple(S[b] for b in others): co.E[a]}
        for b in others:
            terms[(S[b],)] = co.F[a, b]
        nums.append(Multilinear.from_terms(S, terms))
    return MuRegion(mode, status, xi, den, tuple(nums), tuple(f"c_n{i + 1} >= 0" for i in S), source)


def region_rs(scene: Scene, mode, tol: Tolerances = DEFAULT_TOLERANCES) -> MuRegion:
    """The region of an RS mode from Appendix B and inequalities (39)-(41).

    Raises
    ------
    ModeError
        If ``mode`` is not an RS mode of the scene.
    """
    source = "Appendix B, eqs. (39)-(41), (58)-(60)"
    mode = check_mode_fits(scene, mode)
    if mode.kind != "RS":
        raise ModeError(f"mode {mode.letters}: Appendix B covers RS modes; got a {mode.kind} mode")
    status, kin = mode_kinematics(scene, mode, tol)
    if kin is None:
        return empty_region(mode, status, scene.n_contacts, source)
    (r,), (s,) = mode.rolling, mode.sliding
    xi = kin.xi[0]
    co = appendix_b(scene.Wn[:, r], scene.Wt[:, r], scene.Wn[:, s], scene.Wt[:, s], scene.g_obj, xi[s])
    rs = tuple(sorted((r, s)))
    den = Multilinear.from_terms(rs, {(s,): co.A, (): co.B})
    c_nS = Multilinear.from_terms(rs, {(): co.D3})
    rolled = {(r, s): co.C1, (r,): co.D1}
    plus = Multilinear.from_terms(rs, {**rolled, (s,): co.C2, (): co.D2})  # (40), second line with +
    minus = Multilinear.from_terms(rs, {**rolled, (s,): -co.C2, (): -co.D2})
    c_nR = Multilinear.from_terms(rs, {(s,): co.C1, (): co.D1})  # c_nR >= 0 (eq. 9); (40)-(41) imply it only for mu_R > 0
    labels = (
        f"c_n{s + 1} >= 0", f"mu{r + 1} c_n{r + 1} + c_t{r + 1} >= 0", f"mu{r + 1} c_n{r + 1} - c_t{r + 1} >= 0",
        f"c_n{r + 1} >= 0",
    )  # fmt: skip
    return MuRegion(mode, status, xi, den, (c_nS, plus, minus, c_nR), labels, source)
