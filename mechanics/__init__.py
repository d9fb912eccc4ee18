"""qsplan.mechanics: the quasistatic contact model of Trinkle & Zeng (1995), Sections 3-4.

Public API (everything else is private):

* contact frames and wrenches (eq. 1): :func:`cross2`, :func:`tangent_from_normal`,
  :func:`wrench_matrix`, :func:`wrench_matrices`, :func:`shift_wrenches`, :func:`point_wrench`
* scenes: :class:`Scene`, :func:`make_scene`, :func:`load_scene`, :func:`scene_from_dict`
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
* residuals of the full model (eqs. 2-11): :func:`model_residuals`
* tolerances and statuses: :class:`Tolerances`, :class:`Status`
* errors: :class:`QsplanError`, :class:`SceneError`, :class:`ModeError`
"""

if __name__ != "qsplan.mechanics":  # the repository root on sys.path must not load a second copy
    raise ImportError(f"this folder installs as qsplan.mechanics; import qsplan.mechanics (after `pip install .`), not {__name__}")


from qsplan.mechanics.model.contact import cross2, point_wrench, shift_wrenches, tangent_from_normal, wrench_matrices, wrench_matrix
from qsplan.mechanics.errors import ModeError, QsplanError, SceneError
from qsplan.mechanics.modes.reference import ModeCheck, check_mode
from qsplan.mechanics.bands.effort import Band, effort_band, effort_bands, guaranteed_band_box, guaranteed_band_shared, possible_band_box, sampled_band
from qsplan.mechanics.muspace.graphical import GraphicalTest, graphical_test, graphical_test_mode
from qsplan.mechanics.modes.contact_mode import ContactMode, count_modes, enumerate_modes, iter_mode_batches, mode_from_letters
from qsplan.mechanics.muspace.multilinear import Multilinear
from qsplan.mechanics.muspace.maps import MuMap, MuSlice, boundary_agreement, feasibility_map, grid_points, mu_slice, polynomial_map
from qsplan.mechanics.parallel import map_chunks
from qsplan.mechanics.modes.partition import Partition, effort_partitions, partition_table
from qsplan.mechanics.muspace.regions import MuRegion, appendix_a, appendix_b, mode_kinematics, mode_region, region_3s, region_rs
from qsplan.mechanics.numerics import DEFAULT_TOLERANCES, Status, Tolerances
from qsplan.mechanics.modes.planted import planted_scene
from qsplan.mechanics.model.scene import Scene, make_scene
from qsplan.mechanics.model.scene_io import load_scene, scene_from_dict
from qsplan.mechanics.model.scene_io_write import scene_to_dict
from qsplan.mechanics.modes.solution import ModeSolution, model_residuals, relative_velocity
from qsplan.mechanics.solver.batch import SolveResult, solve

__all__ = [
    "cross2",
    "point_wrench",
    "shift_wrenches",
    "tangent_from_normal",
    "wrench_matrices",
    "wrench_matrix",
    "ModeError",
    "QsplanError",
    "SceneError",
    "ModeCheck",
    "check_mode",
    "GeometricScene",
    "geometric_scene_from_dict",
    "scene_from_geometric_scene",
    "scene_from_geometry",
    "CONTACT_TOL",
    "FoundContact",
    "find_contacts",
    "Joint",
    "Manipulator",
    "contact_jacobian",
    "gravity_efforts",
    "link_polygons",
    "link_poses",
    "make_joint",
    "make_manipulator",
    "point_jacobian",
    "Band",
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
    "map_chunks",
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
]

# Geometry needs shapely and the simulator scipy; load those modules on first use so that ``import mechanics``
# (and the CLI's solver path) stays light.
_LAZY = {
    "LPCheck": "qsplan.mechanics.crosscheck.lp_check",
    "lp_mode_feasible": "qsplan.mechanics.crosscheck.lp_check",
    "simulate": "qsplan.mechanics.motion.simulator",
    "Motion": "qsplan.mechanics.motion.simulator",
    "MotionOptions": "qsplan.mechanics.motion.simulator",
    "MotionSystem": "qsplan.mechanics.motion.simulator",
    "Segment": "qsplan.mechanics.motion.simulator",
    "Stop": "qsplan.mechanics.motion.simulator",
    "Event": "qsplan.mechanics.motion.simulator",
    "Friction": "qsplan.mechanics.motion.simulator",
    "make_friction": "qsplan.mechanics.motion.simulator",
    "pose_rate": "qsplan.mechanics.motion.simulator",
    "rigid_body_rates": "qsplan.mechanics.motion.simulator",
    "FrozenScene": "qsplan.mechanics.motion.simulator",
    "frozen_scene_system": "qsplan.mechanics.motion.simulator",
    "STOP_KINDS": "qsplan.mechanics.motion.simulator",
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


__all__ += list(_LAZY)


def __getattr__(name):
    if name in _LAZY:
        import importlib

        value = getattr(importlib.import_module(_LAZY[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
