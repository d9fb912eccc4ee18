"""The one validator of friction coefficients (eq. 8: ``mu_i >= 0``) and of friction ranges.

Every public function that takes friction values or an uncertainty interval checks
it here, so that the rule and the message are the same everywhere; ``field`` names
the argument (or document field) in the message.
"""

from __future__ import annotations

import numpy as np

from qsplan.mechanics.errors import SceneError

__all__ = ["MAX_FRICTION", "check_friction", "check_mu_range"]

#: Largest friction coefficient accepted anywhere.  No dry material pair exceeds about 2 (rubber on
#: rough surfaces); at 100 a friction cone is within 0.6 degrees of a half-plane, and beyond it the
#: coefficients dominate the mode matrices (eqs. 23-26) until the solver's answers change with
#: rounding alone (a mu-space slice to 1e308 reported other modes than one to 1e6).
MAX_FRICTION = 100.0


def _shown(values: np.ndarray):
    return values.tolist() if values.size <= 8 else f"{values.size} values, e.g. {values[~(np.isfinite(values) & (values >= 0))][:3].tolist()}"


def check_friction(mu, field: str = "mu", element: str | None = None):
    """Friction coefficients ``mu`` checked finite and nonnegative (eq. 8); a float for a scalar.

    Parameters
    ----------
    mu : float or array-like
    field : str
        Named in the error.
    element : str, optional
        A format with ``{i}`` naming one coefficient of an array (e.g. ``"contacts[{i}].mu"``):
        the error then names the first bad one.

    Returns
    -------
    float, or ndarray of the shape of ``mu``

    Raises
    ------
    SceneError
        ``"<field>: expected a nonnegative friction coefficient; got -0.1"`` for one value,
        ``"<field>: expected nonnegative finite friction coefficients; got [...]"`` for several.
    """
    try:
        vals = np.asarray(mu, dtype=float)
    except (TypeError, ValueError):
        raise SceneError(f"{field}: expected nonnegative finite friction coefficients; got {mu!r}") from None
    if np.any(np.isfinite(vals) & (vals > MAX_FRICTION)):
        raise SceneError(f"{field}: expected friction coefficients of at most {MAX_FRICTION:g} "
                         f"(qsplan.mechanics.model.friction.MAX_FRICTION); got {float(np.max(vals[np.isfinite(vals)])):g}")  # fmt: skip
    bad = ~(np.isfinite(vals) & (vals >= 0))
    if vals.ndim == 0:
        if bad:
            raise SceneError(f"{field}: expected a nonnegative friction coefficient; got {float(vals)}")
        return float(vals)
    if bad.any():
        if element is not None:
            i = int(np.flatnonzero(bad.reshape(-1))[0])
            raise SceneError(f"{element.format(i=i)}: expected a nonnegative friction coefficient; got {vals.reshape(-1)[i]}")
        raise SceneError(f"{field}: expected nonnegative finite friction coefficients; got {_shown(vals.reshape(-1))}")
    return vals


def check_mu_range(lo, hi, field: str = "mu range", n: int | None = None):
    """A friction interval ``0 <= lo <= hi`` (finite), per contact when ``n`` is given.

    Parameters
    ----------
    lo, hi : float, or array-like of shape (n,) with ``n``
    field : str
        Named in the error.
    n : int, optional
        Broadcast both ends to shape (n,) (independent intervals per contact).

    Returns
    -------
    lo, hi : float, or ndarray of shape (n,) with ``n``

    Raises
    ------
    SceneError
        ``"<field>: expected 0 <= LO <= HI (finite); got <lo> <hi>"``.
    """
    try:
        a, b = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
        if n is not None:
            a, b = np.broadcast_to(a, (n,)), np.broadcast_to(b, (n,))
    except (TypeError, ValueError):
        raise SceneError(f"{field}: expected 0 <= LO <= HI (finite); got {lo!r} {hi!r}") from None
    if not (np.all(np.isfinite(a)) and np.all(np.isfinite(b))) or np.any(a < 0) or np.any(a > b):
        raise SceneError(f"{field}: expected 0 <= LO <= HI (finite); got {a.tolist()} {b.tolist()}")
    if np.any(b > MAX_FRICTION):
        raise SceneError(f"{field}: expected HI <= {MAX_FRICTION:g} (qsplan.mechanics.model.friction.MAX_FRICTION); "
                         f"got {float(np.max(b)):g}")  # fmt: skip
    if n is None:
        return float(a), float(b)
    return a, b
