"""The number of contact modes tested under the utility conditions (eq. 49, Table 1).

A binomial sum, kept apart from :mod:`qsplan.mechanics.modes.contact_mode` (which re-exports it) so
that ``qsplan count`` answers without importing numpy.
"""

from __future__ import annotations

from math import comb

from qsplan.mechanics.errors import ModeError

__all__ = ["count_modes"]


def count_modes(n_contacts: int, dof: int) -> int:
    """Number of contact modes with ``2 n_R + n_S = dof`` (eq. 49).

    Parameters
    ----------
    n_contacts : int
        ``n_c``.
    dof : int
        ``3 + |tau_I|``, the number of applicable constraints.

    Returns
    -------
    int
        0 when ``n_c < dof / 2`` (no mode satisfies the utility conditions).
    """
    if n_contacts < 0 or dof < 0:
        raise ModeError(f"count: contacts and dof must be nonnegative; got {n_contacts}, {dof}")
    return sum(
        comb(n_contacts, nr) * comb(n_contacts - nr, dof - 2 * nr)
        for nr in range(dof // 2 + 1)
        if dof - 2 * nr <= n_contacts - nr
    )
