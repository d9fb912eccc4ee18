"""Contact modes and their enumeration under the utility conditions (Sections 3.1, 3.2, 4.7).

A contact mode assigns one interaction to every contact: ``R`` (rolling),
``S`` (sliding) or ``B`` (breaking).  It is written as one letter per contact
in order (``"RBS"``) and named as in the paper (``"R1S3"``, ``"3S"``).

With a given control-mode partition of ``n_e`` effort-controlled joints, the
utility conditions (29)-(32) require ``2 n_R + n_S = 3 + n_e`` applicable
kinematic constraints; :func:`enumerate_modes` lists exactly those modes, in
the paper's order (``n_R`` ascending, then the rolling set, then the sliding
set, lexicographically), so that for three contacts 3S=1, R1S2=2, R1S3=3,
R2S1=4, R2S3=5, R3S1=6, R3S2=7 (Fig. 6's numbering).  Their number is eq. (49).
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import IntEnum
from itertools import combinations
from math import comb

import numpy as np

from qsplan.mechanics.errors import ModeError
from qsplan.mechanics.modes.counting import count_modes  # eq. (49), numpy-free for `qsplan count`

__all__ = [
    "Letter",
    "LETTERS",
    "letters_to_codes",
    "combinations_array",
    "random_mode",
    "ContactMode",
    "mode_from_letters",
    "enumerate_modes",
    "count_modes",
    "mode_index_array",
    "iter_mode_batches",
    "codes_to_letters",
    "mode_order_key",
]


class Letter(IntEnum):
    """The code of each interaction in letter-code arrays (``uint8``, one per contact)."""

    B = 0  #: breaking
    R = 1  #: rolling
    S = 2  #: sliding


#: ``LETTERS[code]`` is the letter of a code (the names of :class:`Letter` in code order).
LETTERS = "".join(c.name for c in Letter)


@dataclass(frozen=True, slots=True)
class ContactMode:
    """One contact mode.

    Attributes
    ----------
    letters : str
        One of ``R``, ``S``, ``B`` per contact, in contact order (0-based index i
        is contact ``i + 1`` of the paper).
    """

    letters: str

    def __post_init__(self):
        if not self.letters or set(self.letters) - set(LETTERS):
            raise ModeError(f"mode: expected letters R, S or B (one per contact); got {self.letters!r}")

    @property
    def n_contacts(self) -> int:
        return len(self.letters)

    @property
    def rolling(self) -> tuple[int, ...]:
        """0-based indices of rolling contacts."""
        return tuple(i for i, c in enumerate(self.letters) if c == "R")

    @property
    def sliding(self) -> tuple[int, ...]:
        """0-based indices of sliding contacts."""
        return tuple(i for i, c in enumerate(self.letters) if c == "S")

    @property
    def breaking(self) -> tuple[int, ...]:
        """0-based indices of breaking contacts."""
        return tuple(i for i, c in enumerate(self.letters) if c == "B")

    @property
    def n_constraints(self) -> int:
        """Number of applicable kinematic constraints ``2 n_R + n_S`` (eq. 13)."""
        return 2 * len(self.rolling) + len(self.sliding)

    @property
    def kind(self) -> str:
        """Type of the mode by counts, as in Section 4: ``3S``, ``RS``, ``2R``, ``R2S``, ``4S``."""
        nr, ns = len(self.rolling), len(self.sliding)
        part = lambda k, c: "" if k == 0 else (c if k == 1 else f"{k}{c}")  # noqa: E731
        return (part(nr, "R") + part(ns, "S")) or "0"

    @property
    def name(self) -> str:
        """The paper's name: ``3S``/``4S`` when no contact rolls, else ``R<i>S<j>`` with
        1-based contact numbers (several joined by commas, e.g. ``R1S2,3``)."""
        if not self.rolling:
            return f"{len(self.sliding)}S" if self.sliding else "B"
        idx = lambda ix: ",".join(str(i + 1) for i in ix)  # noqa: E731
        s = f"R{idx(self.rolling)}"
        if self.sliding:
            s += f"S{idx(self.sliding)}"
        return s

    def __str__(self) -> str:
        return self.letters


def mode_from_letters(letters, n_contacts: int | None = None, dof: int | None = None) -> ContactMode:
    """Parse ``"RBS"`` (or pass a :class:`ContactMode` through), checking that it fits a scene.

    The one "mode fits the scene" check: one letter per contact when ``n_contacts``
    is given, and ``2 n_R + n_S = dof`` (eq. 29, ``dof = 3 + |tau_I|``) when ``dof`` is.

    Raises
    ------
    ModeError
        Naming the mode, what was expected and what it has.
    """
    mode = letters if isinstance(letters, ContactMode) else ContactMode(str(letters).upper())
    if n_contacts is not None and mode.n_contacts != n_contacts:
        raise ModeError(f"mode: expected {n_contacts} letters (one per contact); got {mode.letters!r}")
    if dof is not None and mode.n_constraints != dof:
        raise ModeError(
            f"mode {mode.letters}: has {mode.n_constraints} applicable constraints but the scene's partition "
            f"needs {dof} (eq. 29 with |tau_I| = {dof - 3})"
        )
    return mode


def _iter_sets(n_contacts: int, dof: int):
    contacts = range(n_contacts)
    for nr in range(dof // 2 + 1):
        ns = dof - 2 * nr
        if nr + ns > n_contacts:
            continue
        for R in combinations(contacts, nr):
            rest = [i for i in contacts if i not in R]
            for S in combinations(rest, ns):
                yield R, S


def enumerate_modes(n_contacts: int, dof: int) -> list[ContactMode]:
    """All modes with ``2 n_R + n_S = dof``, in the paper's order (eqs. 29, 49).

    For large problems use :func:`mode_index_array`, which builds the same list
    as integer arrays without Python objects per mode.
    """
    modes = []
    for R, S in _iter_sets(n_contacts, dof):
        letters = ["B"] * n_contacts
        for i in R:
            letters[i] = "R"
        for i in S:
            letters[i] = "S"
        modes.append(ContactMode("".join(letters)))
    return modes


def combinations_array(n: int, k: int) -> np.ndarray:
    """All k-subsets of range(n) in lexicographic order, shape (C(n, k), k)."""
    if k == 0:
        return np.zeros((1, 0), dtype=np.intp)
    flat = np.fromiter((i for c in combinations(range(n), k) for i in c), dtype=np.intp, count=comb(n, k) * k)
    return flat.reshape(-1, k)


def iter_mode_batches(n_contacts: int, dof: int, batch: int = 8192):
    """Yield the modes of :func:`enumerate_modes`, in the same order, as letter-code arrays.

    Memory stays bounded by ``batch`` rows whatever the total (eq. 49).

    Yields
    ------
    codes : ndarray of uint8, shape (m, n_contacts), m <= batch
        0 = breaking, 1 = rolling, 2 = sliding.
    """
    if batch < 1:
        raise ModeError(f"batch: expected a positive number of modes; got {batch}")
    everything = np.arange(n_contacts)
    for nr in range(dof // 2 + 1):
        ns = dof - 2 * nr
        if nr + ns > n_contacts:
            continue
        Rs = combinations_array(n_contacts, nr)
        Sc = combinations_array(n_contacts - nr, ns)  # positions within the complement of R
        per_r = Sc.shape[0]
        if per_r <= batch:  # several rolling sets per batch
            pieces = ((slice(lo, lo + batch // per_r), slice(None)) for lo in range(0, Rs.shape[0], batch // per_r))
        else:  # one rolling set, its sliding sets split
            pieces = ((slice(i, i + 1), slice(lo, lo + batch)) for i in range(Rs.shape[0]) for lo in range(0, per_r, batch))
        for r_sl, s_sl in pieces:
            R, Sc_part = Rs[r_sl], Sc[s_sl]  # (a, nr), (b, ns)
            a, b = R.shape[0], Sc_part.shape[0]
            keep = np.ones((a, n_contacts), dtype=bool)
            keep[np.arange(a)[:, None], R] = False
            comp = np.broadcast_to(everything, (a, n_contacts))[keep].reshape(a, n_contacts - nr)
            codes = np.zeros((a, b, n_contacts), dtype=np.uint8)
            if nr:
                codes[np.arange(a)[:, None, None], np.arange(b)[None, :, None], R[:, None, :]] = 1
            if ns:
                S = comp[:, Sc_part]  # (a, b, ns)
                codes[np.arange(a)[:, None, None], np.arange(b)[None, :, None], S] = 2
            yield codes.reshape(a * b, n_contacts)


def mode_index_array(n_contacts: int, dof: int) -> np.ndarray:
    """All modes of :func:`enumerate_modes` as one letter-code array, shape (n_modes, n_contacts).

    0 = breaking, 1 = rolling, 2 = sliding.  For large problems iterate
    :func:`iter_mode_batches` instead.
    """
    parts = list(iter_mode_batches(n_contacts, dof, batch=1 << 16))
    return np.concatenate(parts) if parts else np.zeros((0, n_contacts), dtype=np.uint8)


def codes_to_letters(codes) -> str:
    """One row of a letter-code array (:class:`Letter`: 0/1/2) as mode letters (``B``/``R``/``S``)."""
    return "".join(LETTERS[int(c)] for c in codes)


def letters_to_codes(letters: str) -> np.ndarray:
    """Mode letters (``B``/``R``/``S``) as a letter-code row (:class:`Letter`), shape (n_c,), uint8."""
    return np.array([LETTERS.index(c) for c in letters], dtype=np.uint8)


def mode_order_key(letters: str) -> tuple:
    """Sort key giving the order of :func:`enumerate_modes`: ``n_R``, then the rolling set, then
    the sliding set, lexicographically (0-based indices)."""
    R = tuple(i for i, c in enumerate(letters) if c == "R")
    return len(R), R, tuple(i for i, c in enumerate(letters) if c == "S")


def random_mode(rng: np.random.Generator, n_contacts: int, dof: int) -> ContactMode:
    """A mode drawn uniformly from the eq. (49) set without listing it (377,379,369 members at n_c = dof = 20).

    Draws the number of rolling contacts ``r`` with weight ``C(n_c, r) C(n_c - r, dof - 2r)``
    (the eq. (49) terms), then which contacts roll and slide by a random permutation.

    Raises
    ------
    ModeError
        When no mode has ``dof`` constraints with ``n_contacts`` contacts.
    """
    weights = np.array([comb(n_contacts, r) * comb(n_contacts - r, dof - 2 * r) if dof - 2 * r <= n_contacts - r
                        else 0 for r in range(dof // 2 + 1)], dtype=float)  # fmt: skip
    if dof < 0 or weights.sum() == 0:
        raise ModeError(f"no mode has {dof} constraints with {n_contacts} contacts (eq. 49)")
    r = int(rng.choice(weights.size, p=weights / weights.sum()))
    perm = rng.permutation(n_contacts)
    letters = np.full(n_contacts, "B")
    letters[perm[:r]] = "R"
    letters[perm[r : dof - r]] = "S"
    return ContactMode("".join(letters))
