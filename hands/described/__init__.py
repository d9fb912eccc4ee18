"""The one hand, :class:`DescribedHand`: any hand description holding a workpiece (issues 22, 32).

* :mod:`.hand` - :class:`DescribedHand`, the :class:`~qsplan.hands.protocol.Hand` every task's hand becomes
* :mod:`.build` - building one: from a description, from the hand records, from a plan's metadata; the door
  (``as_hand``, ``record_of``), the one place that asks which record type a value is
* :mod:`.states` - a grasp at many workpiece positions by the generic path (closing, joint angles, reasons)
* :mod:`.scenes` - those states' scenes, the contacts the closing knows, checked
* :mod:`.candidates` - the grasps worth considering: the contact pairs the closing gives along the palm
* :mod:`.records` - the hand records' answers as functions (tests, users): thin wrappers asking the answering record

``DescribedHand`` is re-exported here, imported on first use.
"""

from qsplan import lazy_attributes

_LAZY = {
    "DescribedHand": "qsplan.hands.described.hand",
}

__all__ = list(_LAZY)


__getattr__ = lazy_attributes(__name__, _LAZY, globals())


def __dir__():
    return sorted(set(globals()) | set(_LAZY))
