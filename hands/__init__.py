"""qsplan.hands: concrete hands and scenes.

* :mod:`qsplan.hands.paper` - the paper's example scenes (eqs. 37, 42, the rod of Fig. 7) in the raw form.
* :mod:`qsplan.hands.rod` - the rod on two moving supports as a finite-motion system, with its closed form (Section 5.1).
* :mod:`qsplan.hands.pushing` - a polygon pushed across a surface by a finger (contacts appearing).
* :mod:`qsplan.hands.two_finger` - the palm and two single-link fingers of Fig. 9 holding a polygon.
* :mod:`qsplan.hands.two_finger_scene` - that hand's scene (geometric and raw) at a configuration.
* :mod:`qsplan.hands.two_finger_analytic` - that scene at a grasp from the contacts the hand knows (the fast path).
* :mod:`qsplan.hands.grasps` - where each finger touches (inner edge on a vertex, tip on an edge), in the user's numbering.
* :mod:`qsplan.hands.grasp_geometry` - a grasp's joint angles, contacts and rates along the palm (vectorized).
* :mod:`qsplan.hands.batch_scenes` - a grasp's scenes at many positions at once.
* :mod:`qsplan.hands.segments` - manipulation segments of that hand (segment 1: translate left in 4S).
* :mod:`qsplan.hands.formations` - contact formations (which feature touches which body, the desired mode) as values.
* :mod:`qsplan.hands.protocol` - the :class:`Hand` protocol the planner sees, its grasp states and scene arrays.
* :mod:`qsplan.hands.described` - :class:`DescribedHand`, the one hand: any description, batched generic path
  (:mod:`~qsplan.hands.described_states`, :mod:`~qsplan.hands.described_scenes`,
  :mod:`~qsplan.hands.described_candidates`, :mod:`~qsplan.hands.closing_batch`, :mod:`~qsplan.hands.chain_arrays`),
  the paper's closed forms as an accelerator (:mod:`~qsplan.hands.paper_accelerator`); built at the door by
  :mod:`~qsplan.hands.described_build` (``as_hand``: every hand a task names becomes one).
* :mod:`qsplan.hands.motion` - a grasp's slide motion (joint rates, eq. 6 with equality at the closing joints) and
  closed configurations, for any hand; :mod:`qsplan.hands.reclose` - the fingers closed again between segments.
* :mod:`qsplan.hands.collision` - overlaps between every pair of bodies, batched.
* :mod:`qsplan.hands.contact_sets` - a scene from an explicit, named contact set at any pose (issue 23).
* :mod:`qsplan.hands.pivots` - the pivot formations of a hand and workpiece, generated, and their flush instants;
  :mod:`qsplan.hands.manifold` - a formation's configuration manifold solved for any hand (issue 32).

Submodules are imported on first use so that ``import qsplan.hands`` stays light.
"""

if __name__ != "qsplan.hands":  # the repository root on sys.path must not load a second copy
    raise ImportError(f"this folder installs as qsplan.hands; import qsplan.hands (after `pip install .`), not {__name__}")

from qsplan import lazy_attributes

_LAZY = {
    "ContactSpec": "qsplan.hands.contact_sets",
    "contact_set_scene": "qsplan.hands.contact_sets",
    "flush_contacts": "qsplan.hands.contact_sets",
    "locate_contacts": "qsplan.hands.contact_sets",
    "eq37_scene": "qsplan.hands.paper",
    "eq42_scene": "qsplan.hands.paper",
    "rod_scene": "qsplan.hands.paper",
    "PAPER_SCENES": "qsplan.hands.paper",
    "RodOnSupports": "qsplan.hands.rod",
    "make_rod_system": "qsplan.hands.rod",
    "rod_initial_state": "qsplan.hands.rod",
    "rod_distances": "qsplan.hands.rod",
    "simulate_rod": "qsplan.hands.rod",
    "RodSegment": "qsplan.hands.rod",
    "RodClosedForm": "qsplan.hands.rod",
    "rod_closed_form": "qsplan.hands.rod",
    "check_rod_inputs": "qsplan.hands.rod",
    "PushedPolygon": "qsplan.hands.pushing",
    "make_pushed_polygon": "qsplan.hands.pushing",
    "tilted_box_example": "qsplan.hands.pushing",
    "polygon_world": "qsplan.hands.pushing",
    "TwoFingerHand": "qsplan.hands.two_finger",
    "make_two_finger_hand": "qsplan.hands.two_finger",
    "default_hand": "qsplan.hands.two_finger",
    "DEFAULT_WORKPIECE": "qsplan.hands.two_finger",
    "finger_angles": "qsplan.hands.two_finger",
    "finger_angle_rates": "qsplan.hands.two_finger",
    "hand_scene": "qsplan.hands.two_finger_scene",
    "hand_geometric_scene": "qsplan.hands.two_finger_scene",
    "hand_contacts": "qsplan.hands.two_finger_scene",
    "hand_polygons": "qsplan.hands.two_finger_scene",
    "analytic_hand_scene": "qsplan.hands.two_finger_analytic",
    "grasp_contacts": "qsplan.hands.two_finger_analytic",
    "workpiece_world": "qsplan.hands.two_finger",
    "tangency_angles": "qsplan.hands.two_finger",
    "tangency_rates": "qsplan.hands.two_finger",
    "scene_from_contacts": "qsplan.hands.two_finger_analytic",
    "finger_jacobians": "qsplan.hands.two_finger_analytic",
    "Grasp": "qsplan.hands.grasps",
    "OnVertex": "qsplan.hands.grasps",
    "TipOnEdge": "qsplan.hands.grasps",
    "parse_placement": "qsplan.hands.grasps",
    "parse_grasp": "qsplan.hands.grasps",
    "parse_goal": "qsplan.hands.grasps",
    "placement_matches": "qsplan.hands.grasps",
    "internal_vertex": "qsplan.hands.grasps",
    "internal_edge": "qsplan.hands.grasps",
    "user_vertex": "qsplan.hands.grasps",
    "user_edge": "qsplan.hands.grasps",
    "GraspConfigurations": "qsplan.hands.grasp_geometry",
    "grasp_configurations": "qsplan.hands.grasp_geometry",
    "candidate_grasps": "qsplan.hands.grasp_geometry",
    "tip_angles": "qsplan.hands.grasp_geometry",
    "palm_range": "qsplan.hands.grasp_geometry",
    "TIP_MARGIN": "qsplan.hands.grasp_geometry",
    "SceneArrays": "qsplan.hands.batch_scenes",
    "scene_arrays": "qsplan.hands.batch_scenes",
    "grasp_scenes": "qsplan.hands.batch_scenes",
    "ManipulationSegment": "qsplan.hands.segments",
    "SegmentSamples": "qsplan.hands.segments",
    "first_segment": "qsplan.hands.segments",
    "sample_segment": "qsplan.hands.segments",
    "flush_angle": "qsplan.hands.segments",
    "FLUSH_CLEARANCE": "qsplan.hands.segments",
    "BODIES": "qsplan.hands.formations",
    "ContactSlot": "qsplan.hands.formations",
    "DEFAULT_FORMATION": "qsplan.hands.formations",
    "FORMATIONS": "qsplan.hands.formations",
    "Formation": "qsplan.hands.formations",
    "formation": "qsplan.hands.formations",
    "Hand": "qsplan.hands.protocol",
    "GraspStates": "qsplan.hands.protocol",
    "GraspSceneArrays": "qsplan.hands.protocol",
    "ChainGrasp": "qsplan.hands.protocol",
    "FingerContact": "qsplan.hands.protocol",
    "STATE_REASONS": "qsplan.hands.protocol",
    "DescribedHand": "qsplan.hands.described",
    "make_described_hand": "qsplan.hands.described_build",
    "as_hand": "qsplan.hands.described_build",
    "described_from_two_finger": "qsplan.hands.described_build",
    "described_from_chain": "qsplan.hands.described_build",
    "hand_from_metadata": "qsplan.hands.described_build",
}

__all__ = list(_LAZY)


__getattr__ = lazy_attributes(__name__, _LAZY, globals())
