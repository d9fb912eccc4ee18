"""qsplan.mechanics: the quasistatic contact model of Trinkle & Zeng (1995), Sections 3-5.

Subpackages, by the paper's concepts (each ``__init__`` lists its modules and equations):

* :mod:`.model` - contact frames and wrenches (eq. 1), manipulators (eqs. 3, 5), scenes, geometry, scene I/O
* :mod:`.modes` - contact modes (eqs. 12, 29, 49), kinematics (eqs. 23-25), equilibrium and Coulomb
  friction (eqs. 26-28), solutions with residuals (eqs. 2-11), partitions (eq. 32), the one-mode reference
* :mod:`.solver` - every feasible mode of a scene, batched, chunked or pruned (Sections 3.1-3.2, 4.7)
* :mod:`.muspace` - mu-space: multilinear forms, regions, Appendices A and B, maps, slices, Corollary 1
* :mod:`.bands` - effort bands (eq. 28, Section 5.2) at one friction and over uncertain friction
* :mod:`.motion` - finite motions through mode switches (Section 5.1)
* :mod:`.crosscheck` - independent checks: exact rational arithmetic, an LP, the LCP and Lemke

Public API (this module's ``__all__``): the names below.  Each loads its module on first use
(``_LAZY``), so that ``import qsplan.mechanics`` imports neither numpy nor the solver, shapely or scipy.

* contact frames and wrenches (eq. 1): :func:`cross2`, :func:`tangent_from_normal`,
  :func:`wrench_matrix`, :func:`wrench_matrices`, :func:`shift_wrenches`, :func:`point_wrench`
* scenes: :class:`Scene`, :func:`make_scene`, :func:`load_scene`, :func:`scene_from_dict`,
  :func:`scene_to_dict`, :func:`planted_scene` (random scenes with a known feasible mode)
* manipulators (planar kinematic trees, eq. 5): :func:`make_manipulator`, :func:`link_poses`,
  :func:`point_jacobian`, :func:`contact_jacobian`, :func:`gravity_efforts`
* the geometric scene form: :func:`scene_from_geometry`, :func:`find_contacts`
* contact modes (eqs. 12, 29, 49): :class:`ContactMode`, :func:`enumerate_modes`,
  :func:`count_modes`, :func:`iter_mode_batches`
* per-mode feasibility, one mode at a time (eqs. 13-28): :func:`check_mode`
* control-mode partitions (eq. 32): :func:`effort_partitions`, :func:`partition_table`
* mu-space (Section 4, Appendices A-B): :func:`feasibility_map`, :func:`polynomial_map`,
  :func:`mu_slice`, :func:`mode_region`, :func:`region_3s`, :func:`region_rs`, :func:`graphical_test`
* effort bands (eq. 28, Section 5.2): :func:`effort_band`, :func:`guaranteed_band_box`,
  :func:`guaranteed_band_shared`, :func:`sampled_band`
* all feasible modes, vectorized: :func:`solve`, :class:`SolveResult`, :class:`ModeSolution`
* every mode's status at many friction vectors (the kinematic stage once): :func:`solve_many`, its
  per-vector reference :func:`solve_many_reference`, :class:`VectorStatuses`
* residuals of the full model (eqs. 2-11): :func:`model_residuals`
* finite motion (Section 5.1): :func:`simulate`, :class:`MotionOptions`, :func:`make_friction`
* independent checks: :func:`lp_mode_feasible`
* tolerances and statuses: :class:`Tolerances`, :class:`Status`
* the guaranteed band of one scene with every competitor precluded (Fig. 13): :func:`robust_band`
* errors: :class:`QsplanError`, :class:`SceneError`, :class:`ModeError` (bad input);
  :class:`NoAnswerError` (no answer exists; not a ``ValueError``)

Parallel infrastructure (:func:`qsplan.mechanics.parallel.map_chunks`) is not part of it.
"""

if __name__ != "qsplan.mechanics":  # the repository root on sys.path must not load a second copy
    raise ImportError(f"this folder installs as qsplan.mechanics; import qsplan.mechanics (after `pip install .`), not {__name__}")

from qsplan import lazy_attributes

# Every public name loads its module on first use (PEP 562), so that ``import qsplan.mechanics`` -- and
# ``qsplan.mechanics.errors``, which the CLI's light commands need -- imports neither numpy nor the solver.
_LAZY = {
    # bands
    "HoldProof": "qsplan.mechanics.bands.hold",
    "prove_hold": "qsplan.mechanics.bands.hold",
    "hold_torque_interval": "qsplan.mechanics.bands.hold",
    "FrictionHold": "qsplan.mechanics.bands.friction_hold",
    "prove_friction_hold": "qsplan.mechanics.bands.friction_hold",
    "Band": "qsplan.mechanics.bands.effort",
    "ForceMargin": "qsplan.mechanics.bands.effort",
    "effort_band": "qsplan.mechanics.bands.effort",
    "effort_bands": "qsplan.mechanics.bands.effort",
    "guaranteed_band_box": "qsplan.mechanics.bands.guaranteed",
    "guaranteed_band_shared": "qsplan.mechanics.bands.guaranteed",
    "possible_band_box": "qsplan.mechanics.bands.guaranteed",
    "sampled_band": "qsplan.mechanics.bands.guaranteed",
    "RobustBand": "qsplan.mechanics.bands.robust",
    "robust_band": "qsplan.mechanics.bands.robust",
    "WrenchBox": "qsplan.mechanics.bands.disturbance",
    "check_wrench_box": "qsplan.mechanics.bands.disturbance",
    # errors
    "ModeError": "qsplan.mechanics.errors",
    "NoAnswerError": "qsplan.mechanics.errors",
    "QsplanError": "qsplan.mechanics.errors",
    "SceneError": "qsplan.mechanics.errors",
    # model
    "cross2": "qsplan.mechanics.model.contact",
    "point_wrench": "qsplan.mechanics.model.contact",
    "shift_wrenches": "qsplan.mechanics.model.contact",
    "tangent_from_normal": "qsplan.mechanics.model.contact",
    "wrench_matrices": "qsplan.mechanics.model.contact",
    "wrench_matrix": "qsplan.mechanics.model.contact",
    "Scene": "qsplan.mechanics.model.scene",
    "make_scene": "qsplan.mechanics.model.scene",
    "load_scene": "qsplan.mechanics.model.scene_io",
    "scene_from_dict": "qsplan.mechanics.model.scene_io",
    "scene_to_dict": "qsplan.mechanics.model.scene_io_write",
    # modes
    "ContactMode": "qsplan.mechanics.modes.contact_mode",
    "count_modes": "qsplan.mechanics.modes.counting",
    "enumerate_modes": "qsplan.mechanics.modes.contact_mode",
    "iter_mode_batches": "qsplan.mechanics.modes.contact_mode",
    "mode_from_letters": "qsplan.mechanics.modes.contact_mode",
    "Partition": "qsplan.mechanics.modes.partition",
    "effort_partitions": "qsplan.mechanics.modes.partition",
    "partition_table": "qsplan.mechanics.modes.partition",
    "planted_scene": "qsplan.mechanics.modes.planted",
    "ModeCheck": "qsplan.mechanics.modes.reference",
    "check_mode": "qsplan.mechanics.modes.reference",
    "ModeSolution": "qsplan.mechanics.modes.solution",
    "model_residuals": "qsplan.mechanics.modes.solution",
    "relative_velocity": "qsplan.mechanics.modes.solution",
    # muspace
    "appendix_a": "qsplan.mechanics.muspace.appendices",
    "appendix_b": "qsplan.mechanics.muspace.appendices",
    "region_3s": "qsplan.mechanics.muspace.appendices",
    "region_rs": "qsplan.mechanics.muspace.appendices",
    "GraphicalTest": "qsplan.mechanics.muspace.graphical",
    "graphical_test": "qsplan.mechanics.muspace.graphical",
    "graphical_test_mode": "qsplan.mechanics.muspace.graphical",
    "MuMap": "qsplan.mechanics.muspace.maps",
    "feasibility_map": "qsplan.mechanics.muspace.maps",
    "grid_points": "qsplan.mechanics.muspace.maps",
    "polynomial_map": "qsplan.mechanics.muspace.maps",
    "Multilinear": "qsplan.mechanics.muspace.multilinear",
    "MuRegion": "qsplan.mechanics.muspace.regions",
    "mode_kinematics": "qsplan.mechanics.muspace.regions",
    "mode_region": "qsplan.mechanics.muspace.regions",
    "MuSlice": "qsplan.mechanics.muspace.slices",
    "boundary_agreement": "qsplan.mechanics.muspace.slices",
    "mu_slice": "qsplan.mechanics.muspace.slices",
    # numerics
    "DEFAULT_TOLERANCES": "qsplan.mechanics.numerics",
    "Status": "qsplan.mechanics.numerics",
    "Tolerances": "qsplan.mechanics.numerics",
    # solver
    "solve": "qsplan.mechanics.solver.all_modes",
    "SolveResult": "qsplan.mechanics.solver.result",
    "VectorStatuses": "qsplan.mechanics.solver.many",
    "solve_many": "qsplan.mechanics.solver.many",
    "solve_many_reference": "qsplan.mechanics.solver.many",
    # the modules that need shapely (geometry, manipulators) or scipy (the simulator, the LP check)
    "LPCheck": "qsplan.mechanics.crosscheck.lp_check",
    "lp_mode_feasible": "qsplan.mechanics.crosscheck.lp_check",
    "simulate": "qsplan.mechanics.motion.simulator",
    "MotionOptions": "qsplan.mechanics.motion.simulator",
    "Motion": "qsplan.mechanics.motion.trajectory",
    "Segment": "qsplan.mechanics.motion.trajectory",
    "Stop": "qsplan.mechanics.motion.trajectory",
    "STOP_KINDS": "qsplan.mechanics.motion.trajectory",
    "Event": "qsplan.mechanics.motion.events",
    "MotionSystem": "qsplan.mechanics.motion.system",
    "Friction": "qsplan.mechanics.motion.system",
    "make_friction": "qsplan.mechanics.motion.system",
    "pose_rate": "qsplan.mechanics.motion.system",
    "rigid_body_rates": "qsplan.mechanics.motion.system",
    "FrozenScene": "qsplan.mechanics.motion.system",
    "frozen_scene_system": "qsplan.mechanics.motion.system",
    "GeometricScene": "qsplan.mechanics.model.geometric_scene",
    "geometric_scene_from_dict": "qsplan.mechanics.model.geometric_scene",
    "scene_from_geometric_scene": "qsplan.mechanics.model.geometric_scene",
    "scene_from_geometry": "qsplan.mechanics.model.geometric_scene",
    "CONTACT_TOL": "qsplan.mechanics.model.geometry",
    "FoundContact": "qsplan.mechanics.model.geometry",
    "find_contacts": "qsplan.mechanics.model.geometry",
    "Joint": "qsplan.mechanics.model.manipulator",
    "Manipulator": "qsplan.mechanics.model.manipulator",
    "contact_jacobian": "qsplan.mechanics.model.manipulator",
    "gravity_efforts": "qsplan.mechanics.model.manipulator",
    "link_polygons": "qsplan.mechanics.model.manipulator",
    "link_poses": "qsplan.mechanics.model.manipulator",
    "make_joint": "qsplan.mechanics.model.manipulator",
    "make_manipulator": "qsplan.mechanics.model.manipulator",
    "point_jacobian": "qsplan.mechanics.model.manipulator",
}

#: The public names: those imported above, then the lazily loaded ones.
__all__ = [
    "cross2",
    "point_wrench",
    "shift_wrenches",
    "tangent_from_normal",
    "wrench_matrices",
    "wrench_matrix",
    "ModeError",
    "NoAnswerError",
    "QsplanError",
    "RobustBand",
    "robust_band",
    "WrenchBox",
    "check_wrench_box",
    "SceneError",
    "ModeCheck",
    "check_mode",
    "Band",
    "ForceMargin",
    "effort_band",
    "effort_bands",
    "guaranteed_band_box",
    "guaranteed_band_shared",
    "possible_band_box",
    "sampled_band",
    "GraphicalTest",
    "graphical_test",
    "graphical_test_mode",
    "Multilinear",
    "MuMap",
    "MuSlice",
    "boundary_agreement",
    "feasibility_map",
    "grid_points",
    "mu_slice",
    "polynomial_map",
    "Partition",
    "effort_partitions",
    "partition_table",
    "MuRegion",
    "appendix_a",
    "appendix_b",
    "mode_kinematics",
    "mode_region",
    "region_3s",
    "region_rs",
    "ContactMode",
    "count_modes",
    "enumerate_modes",
    "iter_mode_batches",
    "mode_from_letters",
    "DEFAULT_TOLERANCES",
    "Status",
    "Tolerances",
    "planted_scene",
    "Scene",
    "make_scene",
    "load_scene",
    "scene_from_dict",
    "scene_to_dict",
    "ModeSolution",
    "model_residuals",
    "relative_velocity",
    "SolveResult",
    "solve",
    "VectorStatuses",
    "solve_many",
    "solve_many_reference",
]
__all__ += [name for name in _LAZY if name not in __all__]


__getattr__ = lazy_attributes(__name__, _LAZY, globals())


def __dir__():
    return sorted(set(globals()) | set(_LAZY))
