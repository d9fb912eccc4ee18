"""The one hand: a :class:`~qsplan.hands.description.HandDescription` holding a workpiece (issue 22).

:class:`DescribedHand` implements :class:`qsplan.hands.protocol.Hand` for any palm and two serial fingers
of revolute and prismatic joints.  Its *generic path* answers every question from the description,
batched over states: the closing (:mod:`qsplan.hands.described.states`), the contacts checked against the
polygon search and the scenes' arrays (:mod:`qsplan.hands.described.scenes`), collisions.  Where the
description is of the paper's form (two single-link revolute fingers, Fig. 9;
:func:`~qsplan.hands.description.two_finger_form.two_finger_parameters`), the paper's closed forms answer
instead (:mod:`qsplan.hands.paper_hand.accelerator`): decided once at construction, ``accelerated=False``
forces the generic path (the tests compare the two).

Build one with :func:`qsplan.hands.described.build.make_described_hand` (a description and a workpiece), or convert
today's hands: :func:`~qsplan.hands.described.build.described_from_two_finger` (the paper's
:class:`~qsplan.hands.paper_hand.two_finger.TwoFingerHand`, given by its parameters),
:func:`~qsplan.hands.described.build.described_from_chain` (a :class:`~qsplan.hands.chains.hand.ChainHand`).
:meth:`DescribedHand.metadata` and :func:`~qsplan.hands.described.build.hand_from_metadata` round-trip (the paper hand
by today's keys).  Units SI (m, kg, rad, N, N m).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from qsplan.hands.chains.record import ChainRecord
from qsplan.hands.description.files import description_table
from qsplan.hands.formations.registry import FORMATIONS, Formation, formation as registered_formation
from qsplan.hands.paper_hand.record import PaperRecord, paper_metadata
from qsplan.hands.protocol import JOINT_UNITS
from qsplan.mechanics.errors import QsplanError

__all__ = ["DescribedHand"]


#: The parameters of the paper hand's form (:class:`qsplan.hands.paper_hand.two_finger.TwoFingerHand`) a described hand
#: of that form answers (:meth:`DescribedHand.__getattr__`).
_PAPER_PARAMETERS = frozenset({"finger_base", "finger_length", "finger_width", "finger_mass", "palm_halfwidth",
                               "pivots"})  # palm_thickness: every hand's (DescribedHand.palm_thickness)


@dataclass(frozen=True, slots=True, eq=False)
class DescribedHand:
    """A described hand and its workpiece (:class:`qsplan.hands.protocol.Hand`); build it with :func:`make_described_hand`.

    Attributes
    ----------
    description : qsplan.hands.description.HandDescription
    workpiece : ndarray, shape (k, 2)
        Counter-clockwise about the centroid (m); vertex 0 the left end of the bottom edge.
    workpiece_mass, mu : float
        kg; friction coefficient of every contact.
    vertex_order, vertex_of_user : tuple of int
        Internal and user vertex numbering.
    own_limits : (ndarray (n_j, 2), ndarray (n_j,)) or None
        The description's joint ranges and speeds; None for the paper hand given by its parameters.
    accelerated : bool
        The paper's closed forms answer (its form, and not switched off).
    chain : qsplan.hands.chains.hand.ChainHand
        The same hand as today's chain record (the polygon search's reference path).
    paper : qsplan.hands.paper_hand.two_finger.TwoFingerHand or None
        The accelerator's parameter record, where the description is of the paper's form.
    contact_view : qsplan.hands.described.scenes.ContactView or None
    user_vertices, user_edges : ndarray of int, shape (k,)
        The user's number of each internal vertex and edge.
    closings : dict
        The last closings (:func:`qsplan.hands.described.states.close_states`), shared by the grasps closed at the same
        states; a cache, not part of the hand.
    record : qsplan.hands.protocol.HandRecord
        The record that answers the questions it is handed (body polygons, one scene, joint axes, scales, range
        fields), picked once at construction: the paper's (:class:`~qsplan.hands.paper_hand.record.PaperRecord`)
        where its closed forms answer (accelerated), else the chain record's
        (:class:`~qsplan.hands.chains.record.ChainRecord`, the polygon search's reference).
    """

    description: object
    workpiece: np.ndarray
    workpiece_mass: float
    mu: float
    vertex_order: tuple
    vertex_of_user: tuple
    own_limits: tuple | None
    accelerated: bool
    chain: object
    paper: object
    contact_view: object
    user_vertices: np.ndarray
    user_edges: np.ndarray
    closings: dict = field(default_factory=dict, repr=False)
    record: object = field(init=False, repr=False)

    def __post_init__(self):
        object.__setattr__(self, "record", PaperRecord(self.paper) if self.accelerated else ChainRecord(self.chain))

    def __getattr__(self, name):
        """The paper form's parameters (``finger_length``, ``finger_base``, ``pivots``, ...), read from its record: a
        described hand of the paper's form answers them as the hand of Fig. 9 always did."""
        if name in _PAPER_PARAMETERS:
            paper = object.__getattribute__(self, "paper")
            if paper is not None:
                return getattr(paper, name)
        raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")

    @property
    def name(self) -> str:
        return self.description.name

    @property
    def manipulator(self):
        return self.description.manipulator

    @property
    def joint_names(self) -> tuple:
        return tuple(self.description.joint_names)

    @property
    def joint_kinds(self) -> tuple:
        return tuple(self.description.joint_kinds)

    @property
    def finger_joints(self) -> tuple:
        """``((left joints...), (right joints...))``: joint indices, base to tip."""
        return tuple(tuple(int(j) for j in f.joints) for f in self.description.fingers)

    @property
    def closing_joints(self) -> tuple:
        """Each finger's last joint (left, right)."""
        return tuple(f[-1] for f in self.finger_joints)

    @property
    def free_joints(self) -> tuple:
        """Every joint but the closing ones, in joint order."""
        return tuple(j for j in range(len(self.joint_names)) if j not in self.closing_joints)

    @property
    def rest_height(self) -> float:
        """Height (m) of the centre of mass when the bottom edge lies on the palm (its top is ``y = 0``)."""
        return float(-self.workpiece[:, 1].min())

    @property
    def gravity(self) -> float:
        return float(self.manipulator.gravity)

    @property
    def palm(self) -> np.ndarray:
        return self.description.palm

    @property
    def paper_form(self) -> bool:
        """Whether the description is of the paper's form (the accelerator may answer)."""
        return self.paper is not None

    @property
    def palm_range(self) -> tuple:
        """The workpiece x (m) over which its bottom edge lies on the palm's top: ``(lo, hi)``."""
        lo, hi = self.description.palm_top
        return float(lo - self.workpiece[0, 0]), float(hi - self.workpiece[1, 0])

    @property
    def finger_joint_names(self) -> tuple:
        """``(left finger's joints, right finger's joints)``, each a tuple of names from the palm to the tip."""
        names = self.joint_names
        return tuple(tuple(names[j] for j in f) for f in self.finger_joints)

    @property
    def finger_of_joint(self) -> dict:
        """``{joint name: "left" or "right"}``: the finger each joint belongs to."""
        return {name: side for side, names in zip(("left", "right"), self.finger_joint_names) for name in names}

    def joint_units(self, quantity: str = "q") -> tuple:
        """The unit of each joint's ``quantity`` (``"q"``: position, ``"qd"``: velocity, ``"tau"``: effort), in joint
        order: ``("rad", "m")`` for a revolute and a prismatic joint's positions (:data:`JOINT_UNITS`).

        Raises
        ------
        QsplanError
            Naming ``quantity`` when it is none of those.
        """
        if quantity not in JOINT_UNITS["revolute"]:
            raise QsplanError(f"quantity: expected one of {', '.join(JOINT_UNITS['revolute'])}; got {quantity!r}")
        return tuple(JOINT_UNITS[k][quantity] for k in self.joint_kinds)

    def joint_unit(self, joint: str, quantity: str = "q") -> str:
        """The unit of joint ``joint``'s ``quantity`` (:meth:`joint_units`): a jaw's effort in N, a finger's in N m."""
        return self.joint_units(quantity)[self.joint_names.index(joint)]

    @property
    def palm_thickness(self) -> float:
        """How far (m) the palm reaches below its top ``y = 0``: the paper's parameter, else ``-min y`` of the palm."""
        return self.record.palm_thickness

    @property
    def finger_reach(self) -> float:
        """A characteristic finger length (m): the paper's finger length; else the longer finger's sum, over its links,
        of the farthest link vertex from the link's frame origin (the scale of drawn normals, a sweep's joint step)."""
        return self.record.finger_reach

    def joint_axes(self, q) -> np.ndarray:
        """World position (m) of each joint's frame origin at ``q`` (n_j,), shape (n_j, 2): a revolute joint's axis,
        where a prismatic joint's link frame sits at ``q_i = 0``.  The paper's fingers turn about fixed pivots."""
        return self.record.joint_axes(q)

    def range_fields(self) -> list:
        """``[(field, value, kind)]``: the numbers a task checks against its plausible ranges: the paper's parameters
        where its closed forms answer (:meth:`qsplan.hands.paper_hand.two_finger.TwoFingerHand.range_fields`), and every
        hand's workpiece span and mass, gravity and friction
        (:meth:`qsplan.hands.chains.hand.ChainHand.range_fields`)."""
        return self.record.range_fields()

    def description_table(self) -> dict:
        """The description as a plain table in the hand-file format (:mod:`qsplan.hands.description.files`): ``name``,
        ``gravity``, ``palm``, ``fingers`` (:func:`qsplan.hands.description.files.hand_from_table` reads it back)."""
        return description_table(self.description)

    def _closed_forms(self, formation) -> bool:
        return self.accelerated and formation == FORMATIONS["palm_edge"]

    def pose(self, x) -> np.ndarray:
        """Workpiece pose ``(x, rest_height, 0)`` (m, m, rad), shape (3,)."""
        return np.array([float(x), self.rest_height, 0.0])

    def body_polygons(self, pose, q) -> dict:
        """World polygons (m): ``{"palm", "workpiece", <joint name>...}`` -> (k, 2), at ``pose`` (3,) and ``q`` (n_j,)."""
        return self.record.body_polygons(pose, q)

    def grasp_candidates(self, formation="palm_edge", free=None, xs=None) -> tuple:
        """The grasps the planner's tables consider.

        The paper's closed forms: :func:`qsplan.hands.paper_hand.grasp_geometry.candidate_grasps`.  The generic path
        (:func:`qsplan.hands.described.candidates.chain_candidates`): along the palm, from each row of ``free``
        (m, n_free; default the free joints mid-range), the distinct contact pairs the closing gives (both fingers
        touching, neither flush) at ``xs`` (default along the palm), as :class:`~qsplan.hands.protocol.ChainGrasp`, by
        ``free``'s rows then contact keys.
        """
        from qsplan.hands.described.candidates import chain_candidates

        formation = _formation(formation)
        if self._closed_forms(formation) and (free is None or not self.free_joints):
            from qsplan.hands.paper_hand.grasp_geometry import candidate_grasps

            return candidate_grasps(self.paper)
        return chain_candidates(self, formation, free, xs)

    def grasp_states(self, formation, grasp, xs, free=None):
        """The grasp at workpiece ``xs`` (n,) (m): :class:`qsplan.hands.protocol.GraspStates`.

        ``free`` (n, n_free): each state's free joints (rad or m), default the grasp's.  A paper
        :class:`~qsplan.hands.paper_hand.grasps.Grasp` goes to the closed forms when accelerated, else to the generic
        closing (:func:`qsplan.hands.described.states.requirement` reads its placements as contact keys).
        """
        from qsplan.hands.described.states import generic_states
        from qsplan.hands.paper_hand.grasps import Grasp

        formation = _formation(formation)
        xs = _positions(xs)
        if free is not None and not self.free_joints and np.shape(free) in ((len(xs), 0), (0,)):
            free = None  # no free joints to give
        if self._closed_forms(formation) and isinstance(grasp, Grasp) and free is None:
            from qsplan.hands.paper_hand.accelerator import paper_states

            return paper_states(self.paper, formation, grasp, xs)
        return generic_states(self, formation, grasp, xs, free)

    def scene_arrays(self, formation, states, idx=None):
        """The scene arrays (eqs. 1-5) of ``states`` at ``idx`` (default: where ok), batched:
        :class:`qsplan.hands.protocol.GraspSceneArrays`."""
        from qsplan.hands.paper_hand.grasps import Grasp

        formation = _formation(formation)
        if self._closed_forms(formation) and isinstance(states.grasp, Grasp):
            from qsplan.hands.paper_hand.accelerator import paper_scene_arrays

            return paper_scene_arrays(self.paper, states, idx)
        from qsplan.hands.described.scenes import generic_scene_arrays

        return generic_scene_arrays(self, formation, states, idx)

    def state_scene(self, arrays, s: int, effort_controlled, velocity, effort=None, mu=None):
        """The :class:`qsplan.mechanics.Scene` of state ``s`` of ``arrays`` (:meth:`scene_arrays`) under the joint
        inputs: ``effort_controlled`` (n_j,) bool, ``velocity`` and ``effort`` (n_j,) (rad/s or m/s; N m or N)."""
        if arrays.closed_form:
            from qsplan.hands.paper_hand.accelerator import paper_state_scene

            return paper_state_scene(self.paper, arrays, s, effort_controlled, velocity, effort, mu)
        from qsplan.hands.described.scenes import state_scene_of

        return state_scene_of(self, arrays, s, effort_controlled, velocity, effort, mu)

    @property
    def simulation_travel(self) -> float | None:
        """Largest workpiece travel (m) per step of a finite-motion simulation of this hand, or None (no bound): the
        polygon search finds a described hand's contacts at every stage of a step and refuses a penetration beyond
        the contact tolerance (1e-6 m), which a stage's Euler-like prediction reaches at about travel^2 / (2 R); at
        0.1 mm it stays within it for contact paths of radius down to 5 mm.  The paper's closed forms need none."""
        return None if self.accelerated else 1e-4

    def reclose(self, pose, q_planned, planned_pose) -> np.ndarray:
        """The plan's grasp (joints ``q_planned`` at ``planned_pose``) closed on the workpiece at ``pose`` (n_j,):
        :func:`qsplan.hands.chains.reclose.reclose`."""
        from qsplan.hands.chains.reclose import reclose

        return reclose(self, pose, q_planned, planned_pose)

    def closed_configuration(self, formation, grasp, x, free=None) -> np.ndarray:
        """The joints (n_j,) of ``grasp`` closed at ``x`` (m):
        :func:`qsplan.hands.formations.motion.closed_configuration`."""
        from qsplan.hands.formations.motion import closed_configuration

        return closed_configuration(self, _formation(formation), grasp, x, free)

    def slide_motion(self, formation, grasp, xs, xdot, effort_joint: int, free=None, free_rates=None):
        """The grasp held while the workpiece slides at ``xdot`` (m/s):
        :func:`qsplan.hands.formations.motion.slide_motion`."""
        from qsplan.hands.formations.motion import slide_motion

        return slide_motion(self, _formation(formation), grasp, _positions(xs), xdot, effort_joint, free, free_rates)

    def scene(self, pose, q, effort_controlled, velocity, effort=None, mu=None, method: str = "auto"):
        """One :class:`qsplan.mechanics.Scene` (contacts palm, palm, left, right) at ``pose`` (3,) and ``q`` (n_j,).

        ``method``: ``"generic"`` finds the contacts in the polygons (the reference, the certifier's); ``"auto"`` lets
        the paper's closed form find them where it can.  Parameters as :meth:`qsplan.hands.protocol.HandRecord.scene`.
        """
        if method not in ("auto", "generic"):
            raise QsplanError(f"method: expected 'auto' or 'generic'; got {method!r}")
        return self.record.scene(pose, q, effort_controlled, velocity, effort, mu, method)

    def collide(self, poses, q) -> np.ndarray:
        """Whether any two bodies overlap beyond their tolerance at each state (housings respected): ``poses`` (n, 3),
        ``q`` (n, n_j) -> bool (n,) (:func:`qsplan.hands.geometry.collision.find_collisions_batch`)."""
        from qsplan.hands.geometry.collision import find_collisions_batch

        return find_collisions_batch(self.record, poses, q)

    def collisions(self, pose, q, first: bool = False) -> list:
        """The overlapping body pairs at ``pose`` (3,), ``q`` (n_j,), named
        (:func:`qsplan.hands.geometry.collision.find_collisions`)."""
        from qsplan.hands.geometry.collision import find_collisions

        return find_collisions(self.record, pose, q, first)

    def opening(self, grasp, x, q) -> np.ndarray:
        """Each joint's opening direction (-1, 0, +1), shape (n_j,), releasing ``grasp`` with the workpiece at ``x`` (m)
        and the joints at ``q`` (n_j,): the closing joints against their closing direction, the free joints 0.

        The paper's closed forms: the sign that moves the contact point out of the workpiece (eq. 5).
        """
        from qsplan.hands.paper_hand.grasps import Grasp

        if self.accelerated and grasp is None:  # the default grasp, both inner edges: the left finger opens
            return np.array([1.0, -1.0])  # counter-clockwise, the right one clockwise
        if self.accelerated and isinstance(grasp, Grasp):
            from qsplan.hands.paper_hand.accelerator import paper_opening

            return paper_opening(self.paper, grasp, float(x))
        from qsplan.hands.chains.closing import closing_direction

        lim = self.description.joint_limits
        out = np.zeros(len(self.joint_names))
        for side, k in zip((1.0, -1.0), self.closing_joints):
            qm = np.array(q, dtype=float)
            qm[k] = 0.5 * (lim[k, 0] + lim[k, 1])
            out[k] = -closing_direction(self.manipulator, qm, k, side)
        return out

    def metadata(self) -> dict:
        """The hand as an exported plan's metadata records it: the paper's form by its parameters (today's keys,
        :func:`qsplan.hands.paper_hand.record.paper_metadata`, accelerated or not), any other hand by its description and
        workpiece (:meth:`qsplan.hands.chains.record.ChainRecord.metadata`: not of the paper's form, its record is the
        chain's)."""
        return paper_metadata(self.paper) if self.paper is not None else self.record.metadata()


def _formation(value) -> Formation:
    """A :class:`Formation`, or the registered one named ``value``."""
    return value if isinstance(value, Formation) else registered_formation(value)


def _positions(xs) -> np.ndarray:
    xs = np.atleast_1d(np.asarray(xs, dtype=float))
    if xs.ndim != 1 or not np.all(np.isfinite(xs)):
        raise QsplanError(f"xs: expected a finite 1-D array of workpiece x (m); got shape {xs.shape}")
    return xs
