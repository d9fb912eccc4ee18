"""Contact formations: how the hand holds the workpiece, and where each formation can go (issues 22, 32).

* :mod:`.registry` - formations as values in one registry (which feature touches which body, the desired mode)
* :mod:`.pivots` - pivot formations generated per workpiece and hand, and their flush instants
* :mod:`.manifold` - a formation's configuration manifold, solved for any hand
* :mod:`.motion` - a grasp held while the workpiece slides along the palm: configurations, joint rates, scenes

The registry's public names are re-exported here, imported on first use.
"""

from qsplan import lazy_attributes

_LAZY = {
    "BODIES": "qsplan.hands.formations.registry",
    "ContactSlot": "qsplan.hands.formations.registry",
    "Formation": "qsplan.hands.formations.registry",
    "FORMATIONS": "qsplan.hands.formations.registry",
    "DEFAULT_FORMATION": "qsplan.hands.formations.registry",
    "formation": "qsplan.hands.formations.registry",
}

__all__ = list(_LAZY)


__getattr__ = lazy_attributes(__name__, _LAZY, globals())


def __dir__():
    return sorted(set(globals()) | set(_LAZY))
