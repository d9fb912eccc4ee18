"""Named numerical tolerances and the singularity measure shared by every solver path.

No tolerance in qsplan is a bare number: each lives in :class:`Tolerances`
with the reason for its default, and a solver reports which check a mode
failed (``Status``) so that degenerate cases are counted, never passed.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import IntEnum

import numpy as np

__all__ = ["Tolerances", "DEFAULT_TOLERANCES", "hadamard_ratio", "rcond", "singular_matrices", "Status", "StatusCode",
           "conditioning_verdict"]


@dataclass(frozen=True, slots=True)
class Tolerances:
    """Tolerances of the per-mode feasibility test (eqs. 24-28).

    Attributes
    ----------
    singular : float
        A square matrix ``P_AI`` or ``Q_AI`` (eqs. 23, 26) counts as singular when
        its Hadamard ratio (:func:`hadamard_ratio`) is below this.  The ratio is
        zero exactly at singularity and bounds the reciprocal condition number of
        the row-equilibrated matrix from both sides (``h / k^(k/2) <= rcond <= ...``);
        1e-12 rejects matrices whose inverse would amplify rounding errors (1e-16)
        beyond the 1e-9 residuals we promise, while well-posed contact
        configurations of up to 20 constraints sit many orders above it.
        Such modes are reported ill-conditioned (:data:`Status.ILL_CONDITIONED`,
        :func:`conditioning_verdict`): their feasibility is not decided, never guessed.
        The stability study (``benchmarks/bench_stability.py``: 300 three-contact scenes
        near five degeneracies, exact rational ground truth) supports it: with the
        threshold at 0 the LU fails on exactly singular matrices (33 exceptions); from
        1e-16 up no answer was wrong or raised, and a higher threshold only declines more
        exactly feasible modes (2 at 1e-16, 30 at 1e-12, 54 at 1e-8, of 391).  1e-12
        keeps four decades between the threshold and the first failures for systems
        larger than the study's 3 x 3, whose rounding grows with k.
    velocity : float
        Relative: a breaking contact's separation speed or a sliding contact's
        slip speed below ``velocity * v_scale`` counts as zero (degenerate: the
        paper's strict inequalities (11), (15) and the sign in (16) are undefined
        there).  ``v_scale`` is the largest driving speed ``|J thetadot|`` of the
        scene.  1e-9 is far above rounding (1e-15) yet far below any physical slip.
    force : float
        Relative: Coulomb inequalities (28) may be violated by ``force * f_scale``
        (``f_scale`` the largest load or wrench intensity of the mode) and still
        hold, so that points on a region's boundary count as feasible, as the
        paper's non-strict inequalities say; such solutions are flagged
        ``on_boundary``.
    """

    singular: float = 1e-12
    velocity: float = 1e-9
    force: float = 1e-9


DEFAULT_TOLERANCES = Tolerances()


class Status:
    """Why a contact mode was accepted or rejected (counted per scene by the solver)."""

    FEASIBLE = "feasible"
    KINEMATICS_SINGULAR = "kinematics_singular"  #: P_AI singular (eqs. 23, 30, 32): degenerate
    BREAKING_VIOLATED = "breaking_violated"  #: a breaking contact penetrates (eq. 15)
    BREAKING_ZERO_SPEED = "breaking_zero_speed"  #: a breaking contact neither separates nor penetrates: degenerate
    ZERO_SLIDING_SPEED = "zero_sliding_speed"  #: a sliding contact does not slip, xi undefined (eq. 16): degenerate
    EQUILIBRIUM_SINGULAR = "equilibrium_singular"  #: Q_AI singular (eqs. 26, 31, 32): degenerate
    COULOMB_VIOLATED = "coulomb_violated"  #: eq. (28) fails
    ORDER = (
        "feasible",
        "kinematics_singular",
        "breaking_violated",
        "breaking_zero_speed",
        "zero_sliding_speed",
        "equilibrium_singular",
        "coulomb_violated",
    )
    DEGENERATE = frozenset({"kinematics_singular", "breaking_zero_speed", "zero_sliding_speed", "equilibrium_singular"})
    #: The statuses that mean "ill-conditioned": P_AI or Q_AI (eqs. 23, 26) has a Hadamard
    #: ratio below ``Tolerances.singular``, so the mode's feasibility is not decided.
    ILL_CONDITIONED = frozenset({"kinematics_singular", "equilibrium_singular"})


class StatusCode(IntEnum):
    """The integer code of each :class:`Status`, its index in ``Status.ORDER``.

    The vectorized stages keep one int8 code per mode; ``Status.ORDER[code]`` is its name.
    """

    FEASIBLE = 0
    KINEMATICS_SINGULAR = 1
    BREAKING_VIOLATED = 2
    BREAKING_ZERO_SPEED = 3
    ZERO_SLIDING_SPEED = 4
    EQUILIBRIUM_SINGULAR = 5
    COULOMB_VIOLATED = 6


assert tuple(getattr(Status, c.name) for c in StatusCode) == Status.ORDER


def conditioning_verdict(counts: dict, tol: Tolerances = DEFAULT_TOLERANCES) -> str | None:
    """One line saying the result is ill-conditioned, or None when every mode was decided.

    Parameters
    ----------
    counts : dict[str, int]
        Modes per :class:`Status` (``SolveResult.counts``).
    tol : Tolerances
        The tolerances the counts were made with (the threshold is named in the line).

    Returns
    -------
    str or None
        ``"ill-conditioned: ..."`` naming the measure, the threshold and the number of
        undecided modes: the feasible set reported may lack them.
    """
    k = counts.get(Status.KINEMATICS_SINGULAR, 0)
    q = counts.get(Status.EQUILIBRIUM_SINGULAR, 0)
    if not (k or q):
        return None
    return (
        f"ill-conditioned: {k + q} mode(s) undecided, Hadamard ratio of P_AI (eq. 23: {k}) or Q_AI "
        f"(eq. 26: {q}) below Tolerances.singular = {tol.singular:g}; exactly singular ones are outside the "
        "model (eq. 32), nearly singular ones may be feasible and are missing from the set"
    )


def hadamard_ratio(A, *, signed: bool = False, log_row_norms=None):
    """``|det A| / prod_i ||a_i||`` over the rows ``a_i`` of square matrices.

    A scale-invariant (per row) singularity measure in [0, 1]: 0 exactly when A
    is singular, 1 when its rows are orthogonal.  For a row-equilibrated k x k
    matrix, ``h / k^(k/2) <= s_min / s_max <= ...`` and ``h <= (s_min / s_max) k^(k/2)``,
    so it vanishes with the reciprocal condition number.  It costs one batched LU
    (``slogdet``), far less than an SVD.  This is the one singularity test of
    ``P_AI`` and ``Q_AI`` (eqs. 23, 26) every solver path calls.

    Parameters
    ----------
    A : array-like, shape (..., k, k)
    signed : bool
        Return ``det A / prod_i ||a_i||`` (sign of the determinant kept), in [-1, 1]:
        the finite-motion events watch it cross zero.
    log_row_norms : array-like, shape (...), optional
        ``sum_i log ||a_i||`` when the caller already has it (the batched solver gathers
        it from per-scene row norms); computed from ``A`` otherwise.

    Returns
    -------
    ndarray, shape (...)
        0 where ``A`` is singular or has a zero row; 1 for ``k = 0``.
    """
    A = np.asarray(A, dtype=float)
    if log_row_norms is None:
        norms = np.linalg.norm(A, axis=-1)
        with np.errstate(divide="ignore"):
            lognorm = np.log(norms).sum(axis=-1)
    else:
        lognorm = np.asarray(log_row_norms, dtype=float)
    sign, logdet = np.linalg.slogdet(A)
    with np.errstate(invalid="ignore", over="ignore"):
        h = np.exp(logdet - lognorm)
        if signed:
            h = sign * h
        h = np.where((sign == 0) | ~np.isfinite(lognorm), 0.0, h)
    return h


def singular_matrices(A, det, tol: Tolerances = DEFAULT_TOLERANCES):
    """Which square matrices count as singular (:attr:`Tolerances.singular`), from their determinants already
    computed: :func:`hadamard_ratio`'s test, ``|det A| < singular * prod_i ||a_i||``, or ``det`` not finite.

    A determinant within rounding of zero has no sign: the band paths (:func:`qsplan.mechanics.bands.effort.band_rows`)
    treat such a ``Q_AI`` as the solver does, singular and undecided, never by the sign its rounding happens to take.

    Parameters
    ----------
    A : array-like, shape (..., k, k)
    det : array-like, shape (...)
        ``det A``.
    tol : Tolerances

    Returns
    -------
    ndarray of bool, shape (...)
    """
    A, det = np.asarray(A, dtype=float), np.asarray(det, dtype=float)
    with np.errstate(over="ignore", invalid="ignore"):
        scale = np.prod(np.linalg.norm(A, axis=-1), axis=-1)
        return ~np.isfinite(det) | (det == 0) | (np.abs(det) < tol.singular * scale)


def rcond(A):
    """Reciprocal 2-norm condition number ``s_min / s_max`` (0 for singular), shape (...)."""
    s = np.linalg.svd(np.asarray(A, dtype=float), compute_uv=False)
    with np.errstate(invalid="ignore", divide="ignore"):
        r = np.where(s[..., 0] > 0, s[..., -1] / s[..., 0], 0.0)
    return r
