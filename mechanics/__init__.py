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

from .contact import cross2, point_wrench, shift_wrenches, tangent_from_normal, wrench_matrices, wrench_matrix
from .errors import ModeError, QsplanError, SceneError
from .feasibility import ModeCheck, check_mode
from .bands import Band, effort_band, effort_bands, guaranteed_band_box, guaranteed_band_shared, possible_band_box, sampled_band
from .graphical import GraphicalTest, graphical_test, graphical_test_mode
from .modes import ContactMode, count_modes, enumerate_modes, iter_mode_batches, mode_from_letters
from .multilinear import Multilinear
from .muspace import MuMap, MuSlice, boundary_agreement, feasibility_map, grid_points, mu_slice, polynomial_map
from .parallel import map_chunks
from .partition import Partition, effort_partitions, partition_table
from .regions import MuRegion, appendix_a, appendix_b, mode_kinematics, mode_region, region_3s, region_rs
from .numerics import DEFAULT_TOLERANCES, Status, Tolerances
from .planted import planted_scene
from .scene import Scene, make_scene
from .scene_io import load_scene, scene_from_dict
from .scene_io_write import scene_to_dict
from .solution import ModeSolution, model_residuals, relative_velocity
from .solver import SolveResult, solve

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
    "LPCheck": "lp_check",
    "lp_mode_feasible": "lp_check",
    "simulate": "motion",
    "Motion": "motion",
    "MotionOptions": "motion",
    "MotionSystem": "motion",
    "Segment": "motion",
    "Stop": "motion",
    "Event": "motion",
    "Friction": "motion",
    "make_friction": "motion",
    "pose_rate": "motion",
    "rigid_body_rates": "motion",
    "FrozenScene": "motion",
    "frozen_scene_system": "motion",
    "STOP_KINDS": "motion",
    "GeometricScene": "geometric_scene",
    "geometric_scene_from_dict": "geometric_scene",
    "scene_from_geometric_scene": "geometric_scene",
    "scene_from_geometry": "geometric_scene",
    "CONTACT_TOL": "geometry",
    "FoundContact": "geometry",
    "find_contacts": "geometry",
    "Joint": "manipulator",
    "Manipulator": "manipulator",
    "contact_jacobian": "manipulator",
    "gravity_efforts": "manipulator",
    "link_polygons": "manipulator",
    "link_poses": "manipulator",
    "make_joint": "manipulator",
    "make_manipulator": "manipulator",
    "point_jacobian": "manipulator",
}


__all__ += list(_LAZY)


def __getattr__(name):
    if name in _LAZY:
        import importlib

        value = getattr(importlib.import_module(f".{_LAZY[name]}", __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
