"""qsplan.mechanics: the quasistatic contact model of Trinkle & Zeng (1995), Sections 3-4.

Public API (everything else is private):

* contact frames and wrenches (eq. 1): :func:`cross2`, :func:`tangent_from_normal`,
  :func:`wrench_matrix`, :func:`wrench_matrices`, :func:`shift_wrenches`, :func:`point_wrench`
* scenes: :class:`Scene`, :func:`make_scene`, :func:`load_scene`, :func:`scene_from_dict`
* contact modes (eqs. 12, 29, 49): :class:`ContactMode`, :func:`enumerate_modes`,
  :func:`count_modes`, :func:`iter_mode_batches`
* per-mode feasibility, one mode at a time (eqs. 13-28): :func:`check_mode`
* all feasible modes, vectorized: :func:`solve`, :class:`SolveResult`, :class:`ModeSolution`
* residuals of the full model (eqs. 2-11): :func:`model_residuals`
* tolerances and statuses: :class:`Tolerances`, :class:`Status`
* errors: :class:`QsplanError`, :class:`SceneError`, :class:`ModeError`
"""

from .contact import cross2, point_wrench, shift_wrenches, tangent_from_normal, wrench_matrices, wrench_matrix
from .errors import ModeError, QsplanError, SceneError
from .feasibility import ModeCheck, check_mode
from .modes import ContactMode, count_modes, enumerate_modes, iter_mode_batches, mode_from_letters
from .numerics import DEFAULT_TOLERANCES, Status, Tolerances
from .planted import planted_scene
from .scene import Scene, make_scene
from .scene_io import load_scene, scene_from_dict
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
    "ModeSolution",
    "model_residuals",
    "relative_velocity",
    "SolveResult",
    "solve",
]
