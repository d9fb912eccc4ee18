"""qsplan.hands: concrete hands and scenes.

* :mod:`hands.paper` - the paper's example scenes (eqs. 37, 42, the rod of Fig. 7) in the raw form.
* :mod:`hands.rod` - the rod on two moving supports as a finite-motion system, with its closed form (Section 5.1).
* :mod:`hands.pushing` - a polygon pushed across a surface by a finger (contacts appearing).

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
}

__all__ = list(_LAZY)


def __getattr__(name):
    if name in _LAZY:
        import importlib

        value = getattr(importlib.import_module(f".{_LAZY[name]}", __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
