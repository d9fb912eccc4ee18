"""The band checks' fast paths (issue 33) against their reference paths, bit for bit.

* :func:`qsplan.mechanics.bands.effort.intersect_rows` folds large row sets column by column
  (:data:`~qsplan.mechanics.bands.effort.COLUMNS_FROM`): the same bits as its reductions, and the same bands as a
  plain loop over the rows (an independent reference), on rows with flat, NaN, infinite and zero entries; rows that
  share ``s1`` broadcast (the wrench vertices') give the bits of the same rows repeated;
* :func:`qsplan.mechanics.bands.preclusion.cell_lower_bounds` with ``wrenches`` (each row's extremes over the wrench
  vertices) gives the bounds of every control point (``wrenches=1``) on the cells of real competitor searches under a
  wrench box, box and shared friction, the root cell and its bisections: cells where ``det`` keeps its sign and
  cells where it changes sign, bounds finite and infinite.

The batched root cells' grouping and the tables are compared with the per-state searches in
``test_disturbance_bands.py`` (``bits``, bit for bit) and ``test_bands_batched*.py``.
"""

import numpy as np
import pytest

from qsplan.mechanics import enumerate_modes, planted_scene
from qsplan.mechanics.bands import effort
from qsplan.mechanics.bands.cells import FrictionCells
from qsplan.mechanics.bands.disturbance import WrenchBox
from qsplan.mechanics.bands.effort import band_kinematics, intersect_rows
from qsplan.mechanics.bands.preclusion import cell_lower_bounds, friction_set
from qsplan.mechanics.numerics import DEFAULT_TOLERANCES

MU = (0.1, 0.4)
SEED = 33


def _rows(rng, n, r):
    """Rows ``s0 + tau s1`` with the entries a band meets: flat slopes, zeros (and negative zeros), NaN, infinities."""
    s0, s1 = rng.standard_normal((n, r)), rng.standard_normal((n, r))
    pick = lambda p: rng.random((n, r)) < p  # noqa: E731
    s1[pick(0.05)] = 1e-13  # flat against the largest slope
    s1[pick(0.02)] = 0.0
    s0[pick(0.02)] = 0.0
    s0[pick(0.02)] = -0.0
    s0[pick(0.01)] = np.nan
    s1[pick(0.01)] = np.nan
    s0[pick(0.005)] = np.inf
    s1[pick(0.005)] = -np.inf
    scale = np.abs(rng.standard_normal(n)) + 0.1
    return s0, s1, scale


def _loop(s0, s1, scale, tol):
    """The band of each row set by a loop over its rows: the definition (effort.intersect_rows' docstring)."""
    out = []
    for a, b, sc in zip(s0, s1, scale):
        big = np.max(np.abs(b))  # NaN if a slope is NaN: then no row is flat
        lo, hi, ok = -np.inf, np.inf, True
        for x, y in zip(a, b):
            flat = abs(y) <= tol.force * big
            if not flat and y > 0:
                lo = max(lo, -x / y) if not np.isnan(lo) else lo
            elif not flat and y < 0:
                hi = min(hi, -x / y) if not np.isnan(hi) else hi
            if flat and not x >= -tol.force * sc:
                ok = False
            if not np.isfinite(x):
                ok = False
        out.append((lo, hi, ok and lo <= hi))
    return out


@pytest.mark.parametrize("r", [1, 4, 6, 9])
def test_intersect_rows_columns_are_its_reductions(r, monkeypatch):
    rng = np.random.default_rng([SEED, r])
    tol = DEFAULT_TOLERANCES
    s0, s1, scale = _rows(rng, 4 * effort.COLUMNS_FROM // r + 7, r)
    assert s0.size >= 4 * effort.COLUMNS_FROM  # the column path
    with np.errstate(all="ignore"):
        fast = intersect_rows(s0, s1, scale, tol)
        monkeypatch.setattr(effort, "COLUMNS_FROM", 10**12)
        slow = intersect_rows(s0, s1, scale, tol)
    for x, y in zip(fast, slow):
        assert x.tobytes() == y.tobytes()
    assert not np.any(np.signbit(fast[0]) & (fast[0] == 0)) and not np.any(np.signbit(fast[1]) & (fast[1] == 0))
    ok = fast[2]
    assert 0 < ok.sum() < ok.size  # bands and failures both met
    with np.errstate(all="ignore"):
        ref = _loop(s0[:400], s1[:400], scale[:400], tol)
    for k, (lo, hi, good) in enumerate(ref):
        assert good == ok[k]
        if good:  # the edges where there is a band (elsewhere NaN may propagate differently through a loop)
            assert (lo, hi) == (fast[0][k], fast[1][k])


def _cases():
    """Competitor searches' cells under a wrench box: ``(det, N0, N1, g_lo, g_hi, W)`` of the root cell and of three
    rounds of bisection of every cell, random scenes, each scene's modes as competitors, box and shared friction."""
    tol = DEFAULT_TOLERANCES
    for k in range(10):
        rng = np.random.default_rng([SEED, k])
        n_c = int(rng.integers(3, 5))
        scene, _ = planted_scene(rng, n_c, 1, n_joints=2)
        half = rng.uniform(0.5, 1.0, 3) * 0.05 * max(float(np.max(np.abs(scene.g_obj))), 1.0)
        half[int(rng.integers(3))] = 0.0  # one component fixed: 4 wrench vertices, as the tables' inertial box
        box = WrenchBox(-half, half)
        for shared in (False, True):
            lo, hi = friction_set(*MU, n_c, shared)
            for mode in list(enumerate_modes(n_c, scene.dof))[:: max(1, 3 ** n_c // 12)]:
                mk = band_kinematics(scene, mode, tol)
                if not mk.ok:
                    continue
                cells = FrictionCells(scene, mk, lo, hi, shared, tol, box)
                clo, chi = cells.root
                for _ in range(4):
                    det, N0, N1, *_, spread = cells.evaluate(clo, chi)
                    g = rng.uniform(-5.0, 5.0, (2, det.shape[0]))
                    yield det, N0, N1, g.min(axis=0), g.max(axis=0), cells.wrench_blocks
                    yield det, N0, N1, -np.inf, np.inf, cells.wrench_blocks
                    clo, chi = cells.split(clo, chi, spread)


def test_cell_bounds_over_wrench_extremes_are_those_over_every_control_point():
    tol = DEFAULT_TOLERANCES
    met = {"steady finite": 0, "straddle finite": 0, "inf": 0, "-inf": 0}
    for det, N0, N1, g_lo, g_hi, W in _cases():
        assert W == 4 and N0.shape[1] % W == 0
        for sign in (1.0, -1.0):  # both searches' slopes (the largest effort's search negates N1)
            lb, steady = cell_lower_bounds(det, N0, sign * N1, g_lo, g_hi, tol, W)
            ref, ref_steady = cell_lower_bounds(det, N0, sign * N1, g_lo, g_hi, tol)
            assert lb.tobytes() == ref.tobytes() and steady.tobytes() == ref_steady.tobytes()
            met["steady finite"] += int(np.sum(steady & np.isfinite(lb)))
            met["straddle finite"] += int(np.sum(~steady & np.isfinite(lb)))
            met["inf"] += int(np.sum(lb == np.inf))
            met["-inf"] += int(np.sum(lb == -np.inf))
    assert all(v > 0 for v in met.values()), met


@pytest.mark.parametrize("n", [7, 300])  # the reductions, then the column fold
def test_intersect_rows_broadcast_is_the_materialised_rows(n):
    """The rows under each wrench vertex share ``s1``: broadcast (wrench_vertex_parts) or repeated, the same bits."""
    rng = np.random.default_rng([SEED, n])
    tol = DEFAULT_TOLERANCES
    W, F, r = 4, 8, 5
    s0, s1, scale = _rows(rng, n * W * F, r)
    s0, scale = s0.reshape(n, W, F, r), scale.reshape(n, W, F)
    s1 = s1[: n * F].reshape(n, 1, F, r)
    with np.errstate(all="ignore"):
        got = intersect_rows(s0, s1, scale, tol)
        flat = intersect_rows(s0.reshape(-1, r), np.broadcast_to(s1, s0.shape).reshape(-1, r), scale.reshape(-1), tol)
    assert (s0.size >= effort.COLUMNS_FROM) == (n > 10)
    for x, y in zip(got, flat):
        assert x.shape == (n, W, F) and x.tobytes() == y.reshape(n, W, F).tobytes()
