"""Hands described by data (issue 15): a palm and two serial fingers of revolute and prismatic joints.

* :mod:`.model` - :class:`HandDescription`, :class:`FingerChain`, the one validator :func:`make_hand_description`
* :mod:`.files` - hand files (TOML): :func:`load_hand`, :func:`hand_from_table`, :func:`bundled_hands`
* :mod:`.two_finger_form` - the paper's two-finger hand (Fig. 9) as a description and back

Submodules are imported on first use so that ``import qsplan.hands.description`` stays light.
"""

from qsplan import lazy_attributes

_LAZY = {
    "FINGER_NAMES": "qsplan.hands.description.model",
    "HAND_RANGES": "qsplan.hands.description.model",
    "FingerChain": "qsplan.hands.description.model",
    "HandDescription": "qsplan.hands.description.model",
    "make_hand_description": "qsplan.hands.description.model",
    "joint_frames": "qsplan.hands.description.model",
    "bundled_hands": "qsplan.hands.description.files",
    "load_hand": "qsplan.hands.description.files",
    "hand_from_table": "qsplan.hands.description.files",
    "two_finger_parameters": "qsplan.hands.description.two_finger_form",
    "describe_two_finger_hand": "qsplan.hands.description.two_finger_form",
}

__all__ = list(_LAZY)


__getattr__ = lazy_attributes(__name__, _LAZY, globals())


def __dir__():
    return sorted(set(globals()) | set(_LAZY))
