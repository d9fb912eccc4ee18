"""Cells of the competitor search: control values of a competing mode's rows on a cell of the uncertainty set.

The branch and bound of :mod:`qsplan.mechanics.bands.preclusion` bounds a competitor's Coulomb rows
``N_r = det Q_AI * s_r`` (eqs. 26-28) on cells of the uncertainty set by *control values*: numbers of which
``N_r`` at any point of the cell is a convex combination with weights the same for every row.

* Friction in a box: ``N_r`` is multilinear in the mu's, and the control values are its values at the cell's
  vertices.
* One shared coefficient: ``N_r`` is a polynomial in it, and the control values are its Bernstein
  coefficients on the cell's interval.
* With a box of disturbance wrenches (:mod:`qsplan.mechanics.bands.disturbance`) the cell is a friction cell
  times a wrench cell: ``N_r`` is affine in the wrench as well (eq. 26), so the control values are the ones
  above at each vertex of the wrench cell (weights: the friction weights times the wrench cell's multilinear
  weights), wrench-major.  ``det Q_AI`` does not depend on the wrench: its values repeat.

:class:`FrictionCells` also gives each cell's point bands (the model's own bands at actual points of the cell,
whose feasible efforts are the search's incumbents) and how much the control values change along each side
(where to bisect).
"""

from __future__ import annotations

import numpy as np

from qsplan.mechanics.bands.disturbance import wrench_vertex_rows
from qsplan.mechanics.bands.effort import band_rows, intersect_rows
from qsplan.mechanics.bands.guaranteed import bernstein_matrix, shared_coordinate, shared_coordinates, shared_nodes

__all__ = ["SPLIT_TIE", "FrictionCells", "point_bands", "side_spread"]

#: Weight of a cell side's relative width when choosing the side to bisect (the change of the
#: control values along it weighs 1): small, so it only breaks ties between sides the rows do not
#: tell apart, such as sides along which nothing changes.
SPLIT_TIE = 1e-3

#: The band of each friction point from its rows ``s0 + tau s1 >= 0``: the effort-band intersection itself.
point_bands = intersect_rows


def _corners(clo, chi, base, free):
    """The vertices of cells ``[clo, chi]`` (m, d) over the coordinates ``free`` of points ``base`` (n,):
    (m, 2^d, n), vertex ``k`` taking ``chi`` at coordinate ``i`` where bit ``i`` of ``k`` is set."""
    m, d = clo.shape
    bits = ((np.arange(2**d)[:, None] >> np.arange(d)[None]) & 1).astype(bool)  # (K, d)
    pts = np.broadcast_to(base, (m, 2**d, base.size)).copy()
    pts[:, :, free] = np.where(bits[None], chi[:, None, :], clo[:, None, :])
    return pts


class FrictionCells:
    """Control values of a competitor's rows on cells of the friction set (times the wrench box, if any).

    A cell is ``[clo, chi]`` over the free friction coordinates (box: the contacts that are not breaking and
    whose interval has width; shared: the one coefficient), followed by the wrench box's free components.
    """

    def __init__(self, scene, mk, lo, hi, shared, tol, box=None):
        self.scene, self.mk, self.tol, self.box = scene, mk, tol, box
        self.shared = shared
        n_c = scene.n_contacts
        self.n_c = n_c
        self.wfree = [] if box is None else list(box.free)
        self.wrench_blocks = 2 ** len(self.wfree)  # the control points' wrench vertices (wrench-major blocks)
        wlo, whi = ([], []) if box is None else (np.array(box.lo)[self.wfree], np.array(box.hi)[self.wfree])
        if shared:
            nodes = shared_nodes(mk.mode, lo, hi)
            self.deg, self.range = nodes.size - 1, (lo, hi)
            rows = band_rows(scene, mk, np.repeat(nodes[:, None], n_c, axis=1), loads=box is not None)
            s0, s1, det = rows[:3]
            V = np.vander(shared_coordinates(mk.mode), self.deg + 1, increasing=True)
            self.cdet = np.linalg.solve(V, det)  # (deg+1,) power-basis coefficients in t (shared_coordinate)
            self.cN0 = np.linalg.solve(V, s0 * det[:, None])  # (deg+1, R)
            self.cN1 = np.linalg.solve(V, s1 * det[:, None])
            if box is not None:
                self.cN2 = np.linalg.solve(V, (rows[4] * det[:, None, None]).reshape(self.deg + 1, -1))  # (deg+1, 3 R)
            self.root = (np.array([[lo, *wlo]]), np.array([[hi, *whi]]))
        else:
            self.free = [c for c in range(n_c) if mk.mode.letters[c] != "B" and hi[c] > lo[c]]
            self.base = lo.copy()
            self.root = (np.concatenate([lo[self.free], wlo])[None], np.concatenate([hi[self.free], whi])[None])

    def wrenches(self, clo, chi):
        """The vertices of the cells' wrench parts, (m, W, 3) (the last ``len(wfree)`` coordinates)."""
        d = len(self.wfree)
        return _corners(clo[:, clo.shape[1] - d :], chi[:, chi.shape[1] - d :], np.array(self.box.lo), self.wfree)

    def evaluate(self, clo, chi):
        """Control values and point bands of cells ``[clo, chi]`` (m, d).

        Returns det (m, K), N0 (m, K, R), N1 (m, K, R), the bands at actual points of the cells:
        pl, pu (m, P), pok (m, P), and the change along each side (m, d) (:func:`side_spread`).
        """
        m = clo.shape[0]
        if self.shared:
            return self._bernstein(clo, chi)
        d = len(self.free)
        mu = _corners(clo[:, :d], chi[:, :d], self.base, self.free)
        rows = band_rows(self.scene, self.mk, mu.reshape(-1, self.n_c), loads=self.box is not None)
        if self.box is None:
            s0, s1, det, scale = rows
        else:  # the friction vertices under each of the cell's wrench vertices, wrench-major
            rows = [x.reshape((m, 2**d) + x.shape[1:]) for x in rows]
            s0, s1, det, scale = wrench_vertex_rows(*rows, self.wrenches(clo, chi))
            d += len(self.wfree)
            s0, s1, det, scale = s0.reshape(-1, s0.shape[-1]), s1.reshape(-1, s1.shape[-1]), det.reshape(-1), scale.reshape(-1)
        R, K = s0.shape[1], 2**d
        N0 = (s0 * det[:, None]).reshape(m, K, R)
        N1 = (s1 * det[:, None]).reshape(m, K, R)
        pl, pu, pok = point_bands(s0, s1, scale, self.tol)
        det = det.reshape(m, K)
        spread = side_spread(det, N0, N1, [np.arange(K) ^ (1 << i) for i in range(d)])  # vertices differing in side i
        return det, N0, N1, pl.reshape(m, K), pu.reshape(m, K), pok.reshape(m, K), spread

    def _bernstein(self, clo, chi):
        a, b, m = clo[:, 0], chi[:, 0], clo.shape[0]
        M = bernstein_matrix(self.deg, shared_coordinate(a, *self.range), shared_coordinate(b, *self.range))
        det = M @ self.cdet
        N0 = M @ self.cN0
        N1 = M @ self.cN1
        # point bands from the model itself (the fitted polynomials lose their accuracy near a root of det)
        pts = np.stack([a, 0.5 * (a + b), b], axis=1)  # (m, 3)
        rows = band_rows(self.scene, self.mk, np.repeat(pts.reshape(-1, 1), self.n_c, axis=1), loads=self.box is not None)
        if self.box is None:
            pl, pu, pok = point_bands(*rows[:2], rows[3], self.tol)
            return det, N0, N1, pl.reshape(m, 3), pu.reshape(m, 3), pok.reshape(m, 3), np.ones((m, 1))
        w, K = self.wrenches(clo, chi), det.shape[1]
        N0, N1, det, _ = wrench_vertex_rows(N0, N1, det, None, (M @ self.cN2).reshape(N0.shape + (3,)), w)
        s0, s1, _, scale = wrench_vertex_rows(*(x.reshape((m, 3) + x.shape[1:]) for x in rows), w)
        R, P = s0.shape[-1], s0.shape[1]
        pl, pu, pok = point_bands(s0.reshape(-1, R), s1.reshape(-1, R), scale.reshape(-1), self.tol)
        # sides: the coefficient (consecutive Bernstein coefficients), then each free wrench component
        k, v = np.arange(det.shape[1]) % K, np.arange(det.shape[1]) // K
        partners = [v * K + np.minimum(k + 1, K - 1)] + [(v ^ (1 << i)) * K + k for i in range(len(self.wfree))]
        return det, N0, N1, pl.reshape(m, P), pu.reshape(m, P), pok.reshape(m, P), side_spread(det, N0, N1, partners)

    @staticmethod
    def split(clo, chi, spread):
        """Bisect each cell along the side where its control values vary most (``spread`` (m, d)).

        Splitting a side along which the rows hardly change does not tighten the bound; the
        widest side breaks ties (and is the choice where every side is flat).
        """
        width = chi - clo
        if not width.shape[1]:
            return clo, chi
        k = np.argmax(spread * (width > 0) + SPLIT_TIE * width / np.maximum(width.max(axis=1, keepdims=True), 1e-300), axis=1)
        rows = np.arange(clo.shape[0])
        mid = 0.5 * (clo[rows, k] + chi[rows, k])
        lo2, hi1 = clo.copy(), chi.copy()
        hi1[rows, k] = mid
        lo2[rows, k] = mid
        return np.vstack([clo, lo2]), np.vstack([hi1, chi])


def side_spread(det, N0, N1, partners):
    """How much the control values change along each side of each cell, relative to their size, (m, d).

    For side ``i``: the largest change between control points ``k`` and ``partners[i][k]`` (those that
    differ along that side only), of ``det`` and of every row's ``N0`` and ``N1``, each scaled by its
    largest magnitude on the cell.
    """
    m = N0.shape[0]
    if not partners:  # a point cell: nothing to split
        return np.zeros((m, 0))

    def unit(x, axes):
        x = np.where(np.isfinite(x), x, 0.0)
        return x / np.maximum(np.max(np.abs(x), axis=axes, keepdims=True), 1e-300)

    X = np.concatenate([unit(det, 1)[:, :, None], unit(N0, (1, 2)), unit(N1, (1, 2))], axis=2)  # (m, K, 1 + 2R)
    return np.stack([np.max(np.abs(X[:, p] - X), axis=(1, 2)) for p in partners], axis=1)
