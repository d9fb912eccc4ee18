"""qsplan.hands: concrete hands and scenes.

* :mod:`hands.paper` - the paper's example scenes (eqs. 37, 42, the rod of Fig. 7) in the raw form.
* :mod:`hands.rod` - the rod on two moving supports as a finite-motion system, with its closed form (Section 5.1).
* :mod:`hands.pushing` - a polygon pushed across a surface by a finger (contacts appearing).
* :mod:`hands.two_finger` - the palm and two single-link fingers of Fig. 9 holding a polygon.
* :mod:`hands.segments` - manipulation segments of that hand (segment 1: translate left in 4S).

Submodules are imported on first use so that ``import hands`` stays light.
"""

_LAZY = {
    "eq37_scene": "paper",
    "eq42_scene": "paper",
    "rod_scene": "paper",
    "PAPER_SCENES": "paper",
    "RodOnSupports": "rod",
    "make_rod_system": "rod",
    "rod_initial_state": "rod",
    "rod_distances": "rod",
    "simulate_rod": "rod",
    "RodSegment": "rod",
    "RodClosedForm": "rod",
    "rod_closed_form": "rod",
    "check_rod_inputs": "rod",
    "PushedPolygon": "pushing",
    "make_pushed_polygon": "pushing",
    "tilted_box_example": "pushing",
    "polygon_world": "pushing",
    "TwoFingerHand": "two_finger",
    "make_two_finger_hand": "two_finger",
    "default_hand": "two_finger",
    "DEFAULT_WORKPIECE": "two_finger",
    "finger_angles": "two_finger",
    "finger_angle_rates": "two_finger",
    "hand_scene": "two_finger",
    "hand_geometric_scene": "two_finger",
    "hand_contacts": "two_finger",
    "hand_polygons": "two_finger",
    "workpiece_world": "two_finger",
    "ManipulationSegment": "segments",
    "SegmentSamples": "segments",
    "first_segment": "segments",
    "sample_segment": "segments",
    "flush_angle": "segments",
    "FLUSH_CLEARANCE": "segments",
}

__all__ = list(_LAZY)


def __getattr__(name):
    if name in _LAZY:
        import importlib

        value = getattr(importlib.import_module(f".{_LAZY[name]}", __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
