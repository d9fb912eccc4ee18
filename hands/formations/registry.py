"""Contact formations: which workpiece feature touches which body, as values in one registry (issue 22).

A *formation* says how a hand holds the workpiece: its contacts (:class:`ContactSlot`: the body, ``"palm"``,
``"left"`` or ``"right"``, and the workpiece feature), their names and order (the order of every scene's
contacts, band, friction vector, export column and plot), the desired contact mode (one letter per contact,
Section 3's ``R``/``S``/``B``) and which joints close onto the workpiece.  Every layer reads these from the
formation (:func:`formation`), never from literals, so a new formation is one entry of :data:`FORMATIONS`.

The one registered formation (Section 5.2, Fig. 9) is ``"palm_edge"``: the workpiece rests on the palm on its
bottom edge (its internal vertices 0 and 1, :mod:`qsplan.hands.geometry.workpiece`), each finger touches it at one point
(its last joint closes onto it), and the desired mode is 4S: the workpiece slides on the palm and under both
fingers.  The formations that turn the workpiece are not entries here: they are generated per hand and workpiece
(:func:`qsplan.hands.formations.pivots.pivot_formations`) and named by
:attr:`qsplan.hands.formations.pivots.Pivot.name`.  Units: none (names and letters).
"""

from __future__ import annotations

from dataclasses import dataclass

from qsplan.mechanics.errors import QsplanError

__all__ = ["BODIES", "ContactSlot", "DEFAULT_FORMATION", "FORMATIONS", "Formation", "formation"]

#: The bodies a contact can be on: the fixed palm, and each finger (any of its links).
BODIES = ("palm", "left", "right")

#: The workpiece features a contact can touch.
_FEATURES = ("vertex", "edge", "any")


@dataclass(frozen=True, slots=True)
class ContactSlot:
    """One contact of a formation.

    Attributes
    ----------
    name : str
        Its name in scenes, reports and plots (``"palm:0"``, ``"left"``).
    body : str
        One of :data:`BODIES`.
    feature : str
        What of the workpiece touches: ``"vertex"`` (a workpiece vertex on the body), ``"edge"`` (a body corner
        on a workpiece edge) or ``"any"`` (whichever the closing finds).
    index : int or None
        For a palm contact, the workpiece's internal vertex that rests on the palm (0: the left end of the bottom
        edge, 1: its right end); None for a finger contact (the closing decides).
    description : str
        In words, for reports.
    """

    name: str
    body: str
    feature: str
    index: int | None
    description: str

    def __post_init__(self):
        if self.body not in BODIES:
            raise QsplanError(f"formation contact {self.name!r}: body must be one of {', '.join(BODIES)}; got {self.body!r}")
        if self.feature not in _FEATURES:
            raise QsplanError(f"formation contact {self.name!r}: feature must be one of {', '.join(_FEATURES)}; "
                              f"got {self.feature!r}")  # fmt: skip


@dataclass(frozen=True, slots=True)
class Formation:
    """A contact formation (see the module docstring).

    Attributes
    ----------
    name : str
        Its key in :data:`FORMATIONS`.
    contacts : tuple of ContactSlot
        In scene order.
    mode : str
        The desired contact mode, one letter of ``R``, ``S``, ``B`` per contact.
    closing : str
        Which joints close onto the workpiece: ``"last"`` (each finger's last joint; the others are free).
    description : str
    """

    name: str
    contacts: tuple
    mode: str
    closing: str
    description: str

    def __post_init__(self):
        if len(self.mode) != len(self.contacts) or set(self.mode) - set("RSB"):
            raise QsplanError(f"formation {self.name!r}: mode {self.mode!r} must give one letter of R, S, B per contact "
                              f"({len(self.contacts)})")  # fmt: skip
        names = [c.name for c in self.contacts]
        if len(set(names)) != len(names):
            raise QsplanError(f"formation {self.name!r}: contact names must be unique; got {names}")
        if self.closing != "last":
            raise QsplanError(f"formation {self.name!r}: closing must be 'last'; got {self.closing!r}")

    @property
    def n_contacts(self) -> int:
        return len(self.contacts)

    @property
    def contact_names(self) -> tuple:
        return tuple(c.name for c in self.contacts)

    def as_dict(self) -> dict:
        """The formation as ``plan.json`` metadata records it: ``name``, ``mode`` and each contact's ``name``,
        ``body``, ``feature`` (and ``workpiece_vertex`` for a palm contact), in scene order."""
        contacts = [{"name": c.name, "body": c.body, "feature": c.feature,
                     **({} if c.index is None else {"workpiece_vertex": c.index})} for c in self.contacts]  # fmt: skip
        return {"name": self.name, "mode": self.mode, "contacts": contacts}

    def bodies(self, body: str) -> tuple:
        """Indices of the contacts on ``body`` (``"palm"``, ``"left"``, ``"right"``), in scene order."""
        return tuple(i for i, c in enumerate(self.contacts) if c.body == body)

    @property
    def palm_contacts(self) -> tuple:
        return self.bodies("palm")

    @property
    def finger_contacts(self) -> tuple:
        """``(left contacts, right contacts)``: indices into :attr:`contacts`."""
        return self.bodies("left"), self.bodies("right")


#: Every registered formation, by name (the pivots that turn the workpiece are generated:
#: :mod:`qsplan.hands.formations.pivots`).
FORMATIONS = {
    "palm_edge": Formation(
        name="palm_edge",
        contacts=(
            ContactSlot("palm:0", "palm", "vertex", 0, "the workpiece's bottom-left vertex on the palm"),
            ContactSlot("palm:1", "palm", "vertex", 1, "the workpiece's bottom-right vertex on the palm"),
            ContactSlot("left", "left", "any", None, "the left finger on the workpiece"),
            ContactSlot("right", "right", "any", None, "the right finger on the workpiece"),
        ),
        mode="SSSS",
        closing="last",
        description="the bottom edge on the palm, one point of each finger; 4S: sliding on the palm and under both "
                    "fingers (Section 5.2, Fig. 9)",
    ),
}

#: The formation of every task today.
DEFAULT_FORMATION = "palm_edge"


def formation(name: str = DEFAULT_FORMATION) -> Formation:
    """The registered formation ``name``.

    Raises
    ------
    QsplanError
        Naming ``formation`` and the registered names.
    """
    try:
        return FORMATIONS[name]
    except (KeyError, TypeError):
        raise QsplanError(f"formation: expected one of {', '.join(sorted(FORMATIONS))}; got {name!r}") from None
