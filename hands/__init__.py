"""qsplan.hands: concrete hands and scenes, grouped by concept.

* :mod:`qsplan.hands.protocol` - the :class:`Hand` protocol the planner sees, its grasp states and scene arrays.
* :mod:`qsplan.hands.description` - hands described by data: the description model, hand files (TOML), the paper form.
* :mod:`qsplan.hands.described` - :class:`DescribedHand`, the one hand (any description, the batched generic path),
  built at the door by ``as_hand``; it hands its record's questions to the record it picked at construction (each
  record answers for itself: :class:`~qsplan.hands.protocol.HandRecord`).
* :mod:`qsplan.hands.chains` - serial-chain hands: the chain hand record, closing a finger (one state and batched),
  the chain's matrices at many states, closing again between segments.
* :mod:`qsplan.hands.paper_hand` - the paper hand of Fig. 9 in closed form (the accelerator): the hand, its scenes,
  grasps and grasp geometry, batched scenes, slides, manipulation segments.
* :mod:`qsplan.hands.contacts` - contacts: every contact the polygons show, named contact sets, scenes from points.
* :mod:`qsplan.hands.geometry` - geometry: the workpiece polygon, overlaps, collisions between the bodies.
* :mod:`qsplan.hands.formations` - contact formations: the registry, generated pivots, their manifolds, slides.
* :mod:`qsplan.hands.examples` - the paper's example scenes (eqs. 37, 42), the rod of Figs. 7-8, a pushed polygon.

The public names below are imported on first use so that ``import qsplan.hands`` stays light.
"""

if __name__ != "qsplan.hands":  # the repository root on sys.path must not load a second copy
    raise ImportError(f"this folder installs as qsplan.hands; import qsplan.hands (after `pip install .`), not {__name__}")

from qsplan import lazy_attributes

_LAZY = {
    "ContactSpec": "qsplan.hands.contacts.sets",
    "contact_set_scene": "qsplan.hands.contacts.sets",
    "flush_contacts": "qsplan.hands.contacts.sets",
    "locate_contacts": "qsplan.hands.contacts.sets",
    "eq37_scene": "qsplan.hands.examples.paper",
    "eq42_scene": "qsplan.hands.examples.paper",
    "rod_scene": "qsplan.hands.examples.paper",
    "PAPER_SCENES": "qsplan.hands.examples.paper",
    "RodOnSupports": "qsplan.hands.examples.rod",
    "make_rod_system": "qsplan.hands.examples.rod",
    "rod_initial_state": "qsplan.hands.examples.rod",
    "rod_distances": "qsplan.hands.examples.rod",
    "simulate_rod": "qsplan.hands.examples.rod",
    "RodSegment": "qsplan.hands.examples.rod",
    "RodClosedForm": "qsplan.hands.examples.rod",
    "rod_closed_form": "qsplan.hands.examples.rod",
    "check_rod_inputs": "qsplan.hands.examples.rod",
    "PushedPolygon": "qsplan.hands.examples.pushing",
    "make_pushed_polygon": "qsplan.hands.examples.pushing",
    "tilted_box_example": "qsplan.hands.examples.pushing",
    "polygon_world": "qsplan.hands.examples.pushing",
    "TwoFingerHand": "qsplan.hands.paper_hand.two_finger",
    "make_two_finger_hand": "qsplan.hands.paper_hand.two_finger",
    "default_hand": "qsplan.hands.paper_hand.two_finger",
    "DEFAULT_WORKPIECE": "qsplan.hands.paper_hand.two_finger",
    "finger_angles": "qsplan.hands.paper_hand.two_finger",
    "finger_angle_rates": "qsplan.hands.paper_hand.two_finger",
    "hand_scene": "qsplan.hands.paper_hand.scene",
    "hand_geometric_scene": "qsplan.hands.paper_hand.scene",
    "hand_contacts": "qsplan.hands.paper_hand.scene",
    "hand_polygons": "qsplan.hands.paper_hand.scene",
    "analytic_hand_scene": "qsplan.hands.paper_hand.analytic",
    "grasp_contacts": "qsplan.hands.paper_hand.analytic",
    "workpiece_world": "qsplan.hands.paper_hand.two_finger",
    "tangency_angles": "qsplan.hands.paper_hand.two_finger",
    "tangency_rates": "qsplan.hands.paper_hand.two_finger",
    "scene_from_contacts": "qsplan.hands.paper_hand.analytic",
    "finger_jacobians": "qsplan.hands.paper_hand.analytic",
    "Grasp": "qsplan.hands.paper_hand.grasps",
    "OnVertex": "qsplan.hands.paper_hand.grasps",
    "TipOnEdge": "qsplan.hands.paper_hand.grasps",
    "parse_placement": "qsplan.hands.paper_hand.grasps",
    "parse_grasp": "qsplan.hands.paper_hand.grasps",
    "parse_goal": "qsplan.hands.paper_hand.grasps",
    "placement_matches": "qsplan.hands.paper_hand.grasps",
    "internal_vertex": "qsplan.hands.paper_hand.grasps",
    "internal_edge": "qsplan.hands.paper_hand.grasps",
    "user_vertex": "qsplan.hands.paper_hand.grasps",
    "user_edge": "qsplan.hands.paper_hand.grasps",
    "GraspConfigurations": "qsplan.hands.paper_hand.grasp_geometry",
    "grasp_configurations": "qsplan.hands.paper_hand.grasp_geometry",
    "candidate_grasps": "qsplan.hands.paper_hand.grasp_geometry",
    "tip_angles": "qsplan.hands.paper_hand.grasp_geometry",
    "palm_range": "qsplan.hands.paper_hand.grasp_geometry",
    "TIP_MARGIN": "qsplan.hands.paper_hand.grasp_geometry",
    "SceneArrays": "qsplan.hands.paper_hand.batch_scenes",
    "scene_arrays": "qsplan.hands.paper_hand.batch_scenes",
    "grasp_scenes": "qsplan.hands.paper_hand.batch_scenes",
    "ManipulationSegment": "qsplan.hands.paper_hand.segments",
    "SegmentSamples": "qsplan.hands.paper_hand.segments",
    "first_segment": "qsplan.hands.paper_hand.segments",
    "sample_segment": "qsplan.hands.paper_hand.segments",
    "flush_angle": "qsplan.hands.paper_hand.segments",
    "FLUSH_CLEARANCE": "qsplan.hands.paper_hand.segments",
    "BODIES": "qsplan.hands.formations.registry",
    "ContactSlot": "qsplan.hands.formations.registry",
    "DEFAULT_FORMATION": "qsplan.hands.formations.registry",
    "FORMATIONS": "qsplan.hands.formations.registry",
    "Formation": "qsplan.hands.formations.registry",
    "formation": "qsplan.hands.formations.registry",
    "Hand": "qsplan.hands.protocol",
    "HandRecord": "qsplan.hands.protocol",
    "GraspStates": "qsplan.hands.protocol",
    "GraspSceneArrays": "qsplan.hands.protocol",
    "ChainGrasp": "qsplan.hands.protocol",
    "FingerContact": "qsplan.hands.protocol",
    "STATE_REASONS": "qsplan.hands.protocol",
    "JOINT_UNITS": "qsplan.hands.protocol",
    "DescribedHand": "qsplan.hands.described.hand",
    "make_described_hand": "qsplan.hands.described.build",
    "as_hand": "qsplan.hands.described.build",
    "described_from_two_finger": "qsplan.hands.described.build",
    "described_from_chain": "qsplan.hands.described.build",
    "hand_from_metadata": "qsplan.hands.described.build",
}

__all__ = list(_LAZY)


__getattr__ = lazy_attributes(__name__, _LAZY, globals())


def __dir__():
    return sorted(set(globals()) | set(_LAZY))
