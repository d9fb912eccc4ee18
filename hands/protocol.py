"""What the planner may ask a hand: the :class:`Hand` protocol and the values it answers with (issue 22).

A hand holds a workpiece on its palm in a contact *formation* (:mod:`qsplan.hands.formations.registry`): the
bottom edge on the palm and one contact per finger, each finger's last joint closed onto the workpiece
(Section 5.2, Fig. 9).  :class:`Hand` is a :class:`typing.Protocol` (as
:class:`qsplan.mechanics.motion.system.MotionSystem` is for finite motions): body polygons at a
configuration, the grasps worth considering, the grasp's configurations along the palm
(:class:`GraspStates`: closed joints, contacts, joint rates), their scenes' arrays batched
(:class:`GraspSceneArrays`, eqs. 1-5), one scene, collisions, opening directions, metadata, and the joints'
units, fingers and axes, the scales a drawing takes and the numbers a task checks (issue 32: the planner asks a
hand through this protocol only).  Its one implementation is :class:`qsplan.hands.described.hand.DescribedHand`.

:class:`ChainGrasp` is a grasp of any described hand: per finger the contact key ``(link, kind, feature)``
the closing gives (:class:`FingerContact`) and the free joints' values; the paper's hand keeps its
:class:`qsplan.hands.paper_hand.grasps.Grasp` (placements).  Both have ``label`` and ``matches``.  Arrays are numpy, in
SI units (m, rad; m for a prismatic joint's position, rad/m or m/m for its rate per unit workpiece x).
"""

from __future__ import annotations

from dataclasses import dataclass, fields, replace
from typing import Protocol, runtime_checkable

import numpy as np

from qsplan.hands.paper_hand.grasps import parse_goal

__all__ = ["CONTACT_KINDS", "ChainGrasp", "FingerContact", "GraspSceneArrays", "GraspStates", "Hand", "HandRecord",
           "JOINT_UNITS",
           "SlideMotion", "STATE_REASONS",
           "NO_CONTACT", "OTHER_CONTACT", "FLUSH", "NO_PLACEMENT", "SINGULAR"]

#: A finger contact's kind: ``"vertex"``, a workpiece vertex on a link edge; ``"edge"``, a link vertex (a corner)
#: on a workpiece edge (:class:`qsplan.hands.chains.closing.ClosedFinger`).
CONTACT_KINDS = ("vertex", "edge")

#: Units of a joint's position (``q``), velocity (``qd``) and effort (``tau``), by joint kind (SI):
#: :meth:`Hand.joint_units` reads it.
JOINT_UNITS = {"revolute": {"q": "rad", "qd": "rad/s", "tau": "N m"},
               "prismatic": {"q": "m", "qd": "m/s", "tau": "N"}}  # fmt: skip

#: Why a state of :class:`GraspStates` is not a configuration of its grasp (``GraspStates.reason``; 0 where it is).
NO_CONTACT, OTHER_CONTACT, FLUSH, NO_PLACEMENT, SINGULAR = 1, 2, 3, 4, 5

#: :data:`NO_CONTACT` ... in words.
STATE_REASONS = {
    NO_CONTACT: "a finger closes onto nothing within its range (or overlaps the workpiece open)",
    OTHER_CONTACT: "the fingers touch other features than the grasp's (a contact change)",
    FLUSH: "a link lies flush with a workpiece edge (two contacts on one finger)",
    NO_PLACEMENT: "a finger's placement has no valid configuration (out of reach, at an end of an edge, or the finger "
                  "would cross the workpiece)",
    SINGULAR: "a closing joint cannot move its contact along the normal (a singular grasp)",
}


@dataclass(frozen=True, slots=True)
class FingerContact:
    """Where one finger touches the workpiece.

    Attributes
    ----------
    link : int
        The touching link (its joint's index).
    link_name : str
    kind : str
        One of :data:`CONTACT_KINDS`.
    feature : int
        The workpiece vertex (``"vertex"``) or edge (``"edge"``), internal numbering (``hand.workpiece`` rows).
    written : int
        The same feature in the user's numbering (the workpiece as written).
    """

    link: int
    link_name: str
    kind: str
    feature: int
    written: int

    @property
    def key(self) -> tuple:
        """``(link, kind, feature)``: :attr:`qsplan.hands.chains.closing.ClosedFinger.key`."""
        return (self.link, self.kind, self.feature)

    def __str__(self) -> str:
        return f"{self.link_name} {self.kind}:{self.written}"

    def matches(self, goal=None, field: str = "goal") -> bool:
        """Whether this contact meets the placement string ``goal`` (``"vertex"``, ``"vertex:K"``, ``"edge:K"``; None:
        anything).  A branch (``"edge:K:B"``) names a corner of the paper's fingertip, which a chain contact does not
        record: it matches no chain contact.

        Raises
        ------
        SceneError
            Naming ``field`` when ``goal`` is not a placement string.
        """
        if goal is None:
            return True
        kind, index, branch = parse_goal(goal, field)
        return kind == self.kind and index in (None, self.written) and branch is None


@dataclass(frozen=True, slots=True)
class ChainGrasp:
    """A grasp of a described hand: each finger's contact and the free joints' values.

    Attributes
    ----------
    left, right : FingerContact
    free : tuple of float
        The free joints' positions (rad or m), in the order of ``free_names``.
    free_names : tuple of str
        The free joints (every joint but each finger's last), in joint order.
    """

    left: FingerContact
    right: FingerContact
    free: tuple = ()
    free_names: tuple = ()

    @property
    def keys(self) -> tuple:
        """Each finger's contact key ``(link, kind, feature)``, left then right."""
        return (self.left.key, self.right.key)

    @property
    def label(self) -> str:
        """``"L left_distal vertex:2 / R right_distal edge:1 (left_proximal 1.4, right_proximal 1.74)"``."""
        free = ", ".join(f"{n} {v:.6g}" for n, v in zip(self.free_names, self.free))
        return f"L {self.left} / R {self.right}" + (f" ({free})" if free else "")

    def __str__(self) -> str:
        return self.label

    def matches(self, goal_left=None, goal_right=None) -> bool:
        """Whether the grasp meets the goal placements (strings as :meth:`qsplan.hands.paper_hand.grasps.Grasp.matches`
        takes them, user numbering; None: anything): :meth:`FingerContact.matches` of each finger."""
        return self.left.matches(goal_left, "goal_left") & self.right.matches(goal_right, "goal_right")


@dataclass(frozen=True, slots=True, eq=False)
class GraspStates:
    """A grasp at ``n`` workpiece positions on the palm (pose ``(x, rest_height, 0)``), its formation's contacts.

    A superset of :class:`qsplan.hands.paper_hand.grasp_geometry.GraspConfigurations` for any hand and formation.  Its
    arrays may be shared with the closings a hand keeps (:func:`qsplan.hands.described.states.closing_of`): read-only.

    Attributes
    ----------
    formation : qsplan.hands.formations.registry.Formation
    grasp : qsplan.hands.paper_hand.grasps.Grasp or ChainGrasp
    x : ndarray, shape (n,)
        Workpiece x (m).
    poses : ndarray, shape (n, 3)
        Workpiece poses ``(x, rest_height, 0)`` (m, m, rad).
    q : ndarray, shape (n, n_j)
        Joint positions (rad or m): the free joints as given, the closing joints closed onto the grasp's features;
        NaN where a finger closes onto nothing.
    ok : ndarray of bool, shape (n,)
        Every contact of the formation exists as the grasp says.  Joint limits (but the closing joints' ranges of a
        described closing) and collisions are not checked.
    reason : ndarray of int8, shape (n,)
        0 where ``ok``, else why not (:data:`STATE_REASONS`).
    finger_ok : ndarray of bool, shape (n, 2)
        Per finger (left, right).
    touched, touched_as_written : ndarray of int, shape (n, 2)
        The workpiece feature (vertex or edge) each finger touches, internal and user numbering.
    tip : ndarray of bool, shape (2,)
        Whether each finger's contact is a link corner on a workpiece edge (``"edge"``), not a workpiece vertex on a link
        edge.
    points : ndarray, shape (n, n_c, 2)
        Contact points (m), the formation's order.
    normals : ndarray, shape (n, n_c, 2)
        Unit normals into the workpiece (eq. 1).
    bodies : ndarray of int, shape (n, n_c)
        The body of each contact: -1 the palm, else the touching link (joint index).
    dq_dx : ndarray, shape (n, n_j)
        Joint rates per unit workpiece x (rad/m or m/m) that keep every finger contact closed, free joints held
        (eq. 6 with equality); NaN where not ok.
    """

    formation: object
    grasp: object
    x: np.ndarray
    poses: np.ndarray
    q: np.ndarray
    ok: np.ndarray
    reason: np.ndarray
    finger_ok: np.ndarray
    touched: np.ndarray
    touched_as_written: np.ndarray
    tip: np.ndarray
    points: np.ndarray
    normals: np.ndarray
    bodies: np.ndarray
    dq_dx: np.ndarray

    @property
    def n(self) -> int:
        return len(self.x)

    def take(self, rows) -> "GraspStates":
        """The states ``rows`` (array of int), as states."""
        rows = np.asarray(rows, dtype=int)
        fixed = ("formation", "grasp", "tip")
        return replace(self, **{f.name: getattr(self, f.name)[rows] for f in fields(self) if f.name not in fixed})

    def why(self, k: int) -> str | None:
        """Why state ``k`` is not ok, in words (None where it is): a paper placement without a configuration names the
        finger and how (:func:`qsplan.hands.paper_hand.grasps.no_placement_words`)."""
        if int(self.reason[k]) == NO_PLACEMENT and not isinstance(self.grasp, ChainGrasp):
            from qsplan.hands.paper_hand.grasps import no_placement_words

            return no_placement_words(self.grasp, int(np.argmin(self.finger_ok[k])))
        return STATE_REASONS.get(int(self.reason[k]))

    def touching(self) -> np.ndarray:
        """What each finger touches, as an integer per finger and state that changes when its contact changes, shape
        (n, 2): a paper placement's feature (the hand's numbering), a chain contact's ``(link, kind, feature)`` code."""
        if not isinstance(self.grasp, ChainGrasp):
            return self.touched
        left, right = self.formation.finger_contacts
        link = self.bodies[:, [left[0], right[0]]]
        kind = np.broadcast_to(np.asarray(self.tip, dtype=int), self.touched.shape)
        return (link * 2 + kind) * 1000 + self.touched

    def matches(self, goal_left=None, goal_right=None) -> np.ndarray:
        """Where the grasp meets the goal placements (strings as :meth:`qsplan.hands.paper_hand.grasps.Grasp.matches`
        takes them), shape (n,) bool: ``"vertex:K"`` where the finger touches vertex ``K`` (user numbering), the others
        wherever ok."""
        out = self.ok.copy()
        if not self.grasp.matches(goal_left, goal_right):
            return np.zeros_like(out)
        for k, (goal, field) in enumerate(((goal_left, "goal_left"), (goal_right, "goal_right"))):
            if goal is not None:
                kind, index, _ = parse_goal(goal, field)
                if index is not None:
                    out &= (self.touched_as_written[:, k] == index) & (self.tip[k] == (kind == "edge"))
        return out


@dataclass(frozen=True, slots=True, eq=False)
class GraspSceneArrays:
    """The model's matrices (eqs. 1-5) at ``m`` states of a :class:`GraspStates`, stacked, with no object per state.

    Attributes
    ----------
    idx : ndarray of int, shape (m,)
        The states (indices into the :class:`GraspStates`).
    Wn, Wt : ndarray, shape (m, 3, n_c)
        Normal and tangential wrench matrices (eq. 1), about the world origin; NaN where not ``ok``.
    Jn, Jt : ndarray, shape (m, n_c, n_j)
        Contact Jacobians (eq. 5; zero rows on the palm) (m per rad, or m/m).
    g_obj : ndarray, shape (m, 3)
        The workpiece's weight as a wrench about the origin (eq. 2) (N, N, N m).
    g_man : ndarray, shape (m, n_j)
        The links' gravity efforts (eq. 3) (N m or N).
    bodies : ndarray of int, shape (m, n_c)
        Each contact's body (-1 the palm, else the link).
    dq_dx : ndarray, shape (m, n_j)
        :attr:`GraspStates.dq_dx` of these contacts.
    ok : ndarray of bool, shape (m,)
        Where the polygons give exactly the formation's contacts (the scene the polygon search builds).
    reasons : tuple of (str or None), length m
        Why a state is not ok, in words.
    fallback : dict of int to Scene
        The states (positions in ``idx``) whose scene the polygon search built, where the closed form could not decide.
    closed_form : bool
        Built by the paper's closed forms (:mod:`qsplan.hands.paper_hand.accelerator`), whose scenes they build again.
    """

    idx: np.ndarray
    Wn: np.ndarray
    Wt: np.ndarray
    Jn: np.ndarray
    Jt: np.ndarray
    g_obj: np.ndarray
    g_man: np.ndarray
    bodies: np.ndarray
    dq_dx: np.ndarray
    ok: np.ndarray
    reasons: tuple
    fallback: dict
    closed_form: bool = False


@dataclass(frozen=True, slots=True, eq=False)
class SlideMotion:
    """A grasp at ``n`` workpiece positions of a slide.

    Attributes
    ----------
    poses : ndarray, shape (n, 3)
        Workpiece poses (m, m, rad).
    q, qd : ndarray, shape (n, n_j)
        Joint positions (rad or m) and rates (rad/s or m/s): the velocity-controlled joints' commands; the
        effort-controlled joint's rate is the one the contacts give it (its command is an effort).
    touching : ndarray of int, shape (n, 2)
        What each finger touches, as a code that changes when the contact changes (the paper's hand: the workpiece
        vertex; any hand: :func:`touch_codes`).
    scenes : tuple of Scene, length n
    """

    poses: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    touching: np.ndarray
    scenes: tuple


@runtime_checkable
class Hand(Protocol):
    """A planar hand holding a workpiece (Section 5.2): what the planner, export, certifier, replay and plots ask.

    Attributes
    ----------
    name : str
    description : qsplan.hands.description.HandDescription
    joint_names, joint_kinds : tuple of str, length n_j
        Kinds ``"revolute"`` (rad) or ``"prismatic"`` (m).
    finger_joints : (tuple of int, tuple of int)
        Each finger's joints (indices), base to tip: left, right.
    closing_joints : (int, int)
        Each finger's last joint, which closes onto the workpiece.
    free_joints : tuple of int
        The others, in joint order.
    manipulator : qsplan.mechanics.model.manipulator.Manipulator
    workpiece : ndarray, shape (k, 2)
        Internal vertices (m): counter-clockwise about the centroid, vertex 0 the left end of the bottom edge.
    workpiece_mass, mu, rest_height, gravity : float
        kg; friction of every contact; height (m) of the centre of mass on the palm; m/s^2 along -y.
    vertex_order, vertex_of_user : tuple of int
        Internal and user vertex numbering (:class:`qsplan.hands.geometry.workpiece.PreparedWorkpiece`).
    palm : ndarray, shape (p, 2)
        The palm polygon (m), top edge on ``y = 0``.
    own_limits : (ndarray (n_j, 2), ndarray (n_j,)) or None
        The hand's joint ranges (rad or m) and speeds (rad/s or m/s); None for the paper's hand given by its parameters.
    accelerated : bool
        Whether the paper's closed forms answer (decided once at construction).
    finger_joint_names : (tuple of str, tuple of str)
        Each finger's joint names, base to tip: left, right.
    finger_of_joint : dict
        ``{joint name: "left" or "right"}``.
    finger_reach : float
        A characteristic finger length (m), the scale of drawn normals and of a sweep's joint step: the paper's
        finger length; else the longer finger's sum, over its links, of the farthest link vertex from the link's frame.
    palm_thickness : float
        How far (m) the palm reaches below its top ``y = 0``.
    user_vertices, user_edges : ndarray of int, shape (k,)
        The user's number of each internal vertex and edge.
    simulation_travel : float or None
        Largest workpiece travel (m) per step of a finite-motion simulation of this hand (None: no bound).
    """

    name: str
    description: object
    joint_names: tuple
    joint_kinds: tuple
    finger_joints: tuple
    closing_joints: tuple
    free_joints: tuple
    manipulator: object
    workpiece: np.ndarray
    workpiece_mass: float
    mu: float
    vertex_order: tuple
    vertex_of_user: tuple
    rest_height: float
    gravity: float
    palm: np.ndarray
    own_limits: tuple | None
    accelerated: bool
    finger_joint_names: tuple
    finger_of_joint: dict
    finger_reach: float
    palm_thickness: float
    user_vertices: np.ndarray
    user_edges: np.ndarray
    simulation_travel: float | None

    def pose(self, x) -> np.ndarray:
        """Workpiece pose ``(x, rest_height, 0)`` (m, m, rad), shape (3,)."""

    def body_polygons(self, pose, q) -> dict:
        """World polygons (m): ``{"palm", "workpiece", <joint name>...}`` -> (k, 2), at ``pose`` (3,) and ``q`` (n_j,)."""

    def grasp_candidates(self, formation, free=None, xs=None) -> tuple:
        """The grasps the planner's tables consider; ``free`` (m, n_free): free-joint values to close from, at workpiece
        positions ``xs`` (default along the palm)."""

    def grasp_states(self, formation, grasp, xs, free=None) -> GraspStates:
        """The grasp at every workpiece x of ``xs`` (n,) (``free`` (n, n_free): per-state free joints)."""

    def scene_arrays(self, formation, states: GraspStates, idx=None) -> GraspSceneArrays:
        """The scene arrays of ``states`` at ``idx`` (default: where ok), batched (eqs. 1-5)."""

    def state_scene(self, arrays: GraspSceneArrays, s: int, effort_controlled, velocity, effort=None, mu=None):
        """The :class:`qsplan.mechanics.Scene` of state ``s`` of ``arrays`` under the given joint inputs."""

    def closed_configuration(self, formation, grasp, x, free=None) -> np.ndarray:
        """The joints (n_j,) of ``grasp`` closed onto the workpiece at ``x`` (m), geometry only (raises
        :class:`~qsplan.mechanics.errors.SceneError` where it has none)."""

    def slide_motion(self, formation, grasp, xs, xdot, effort_joint: int, free=None, free_rates=None):
        """A slide's configurations, joint rates, contacts and scenes at ``xs`` (n,) moving at ``xdot`` (m/s):
        :class:`qsplan.hands.formations.motion.SlideMotion` (raises :class:`~qsplan.mechanics.errors.SceneError` naming
        the first x without a configuration)."""

    def scene(self, pose, q, effort_controlled, velocity, effort=None, mu=None, method: str = "auto"):
        """One :class:`qsplan.mechanics.Scene` at ``pose`` (3,) and ``q`` (n_j,); ``"generic"``: the polygon search."""

    def collide(self, poses, q) -> np.ndarray:
        """Whether two bodies overlap beyond their tolerance at each state: ``poses`` (n, 3), ``q`` (n, n_j) -> (n,)."""

    def collisions(self, pose, q, first: bool = False) -> list:
        """The overlapping body pairs at one state, named (:class:`qsplan.hands.geometry.collision.Collision`)."""

    def opening(self, grasp, x, q) -> np.ndarray:
        """Each joint's opening direction (-1, 0, +1), shape (n_j,), releasing ``grasp`` at workpiece ``x``, joints ``q``
        (n_j,)."""

    def joint_units(self, quantity: str = "q") -> tuple:
        """The unit of each joint's ``quantity`` (``"q"``, ``"qd"``, ``"tau"``), in joint order (:data:`JOINT_UNITS`)."""

    def joint_unit(self, joint: str, quantity: str = "q") -> str:
        """The unit of joint ``joint``'s ``quantity`` (:meth:`joint_units`): a jaw's effort in N, a finger's in N m."""

    def joint_axes(self, q) -> np.ndarray:
        """World position (m) of each joint's frame origin at ``q`` (n_j,), shape (n_j, 2)."""

    def range_fields(self) -> list:
        """``[(field, value, kind)]``: the numbers a task checks against its plausible ranges (``kind`` a key of
        ``qsplan.planner.task.fields.TASK_RANGES``)."""

    def description_table(self) -> dict:
        """The hand's description as a plain table in the hand-file format (:mod:`qsplan.hands.description.files`)."""

    def reclose(self, pose, q_planned, planned_pose) -> np.ndarray:
        """The plan's grasp (joints ``q_planned`` (n_j,) at ``planned_pose`` (3,)) closed again on the workpiece at
        ``pose`` (3,): the joints (n_j,)."""

    def metadata(self) -> dict:
        """The hand as a plan's metadata records it (:func:`qsplan.hands.described.build.hand_from_metadata` reads
        it)."""


@runtime_checkable
class HandRecord(Protocol):
    """What a hand record answers for itself (issue 32): the questions a :class:`Hand` hands to its record.

    One answerer per record type, picked once where a record becomes a hand (the described hand's construction,
    :func:`qsplan.hands.described.build.record_of` for a bare record): the paper's
    :class:`qsplan.hands.paper_hand.record.PaperRecord` (its closed forms) and a chain hand's
    :class:`qsplan.hands.chains.record.ChainRecord` (its description, the polygon search).  Nobody asks which one it is.

    Attributes
    ----------
    hand : TwoFingerHand or ChainHand
        The record answered for.
    closed_form : bool
        Whether the paper's closed forms answer (else the polygon search).
    workpiece : ndarray, shape (k, 2)
    manipulator : qsplan.mechanics.model.manipulator.Manipulator
    joint_names, joint_kinds : tuple of str
    finger_joint_names : tuple of tuple of str
    palm_thickness, link_width, finger_reach : float
        m: the palm below ``y = 0``, a link's narrowest width, a finger's reach (drawing scales).
    """

    hand: object
    closed_form: bool
    workpiece: np.ndarray
    manipulator: object
    joint_names: tuple
    joint_kinds: tuple
    finger_joint_names: tuple
    palm_thickness: float
    link_width: float
    finger_reach: float

    def joint_axes(self, q) -> np.ndarray:
        """World position (m) of each joint's frame origin at ``q`` (n_j,), shape (n_j, 2)."""

    def body_polygons(self, pose, q) -> dict:
        """World polygons (m): ``{"palm", "workpiece", <joint name>...}`` -> (k, 2)."""

    def scene(self, pose, q, effort_controlled, velocity, effort=None, mu=None, method: str = "auto"):
        """One :class:`qsplan.mechanics.Scene` (contacts palm, palm, left, right)."""

    def contacts_at(self, pose, q) -> list:
        """The grasp's contacts found in the polygons, in the scene's order."""

    def range_fields(self) -> list:
        """``[(field, value, kind)]``: the record's numbers a task checks against its plausible ranges."""

    def metadata(self) -> dict:
        """The record as an exported plan's metadata records it."""

    def description_table(self) -> dict:
        """The description in the hand-file format (refused where the record is given by parameters)."""
