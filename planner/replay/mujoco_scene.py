"""A task's scene as MuJoCo's MJCF: palm, fingers with their joints and actuators, workpiece, per-contact friction.

:func:`scene_xml` writes the plane of the paper (Section 5.2, Fig. 9) into MuJoCo's 3-D world as it is: x to the
right, y up, gravity along -y, every joint turning about z (a prismatic one sliding in the plane); every body
is its polygon extruded :data:`DEPTH` along z, centred on z = 0.  Names (what
:mod:`qsplan.planner.replay.mujoco_replay` reads):

* ``palm``: the palm, fixed (a box when its polygon is an axis-aligned rectangle, else a prism);
* ``workpiece``: a planar free body, joints ``workpiece_x``, ``workpiece_y`` (m) and ``workpiece_theta`` (rad),
  so ``qpos`` is the plan's pose ``(x, y, theta)`` of its centre of mass; its polygon (the hand's internal
  vertices) and a foot ``foot:K`` under every vertex ``K``: a sphere of :data:`FOOT_RADIUS` inside the corner,
  touching both its edges (:func:`foot_centres`), which carries the palm contact ``palm:K`` (the certifier's name of
  a palm contact at internal vertex ``K``, :func:`qsplan.hands.contacts.found.contact_names`): the workpiece rests
  on any of its edges, or pivots on any vertex, on two feet or one;
* one body per joint of the hand (its name), at the joint's origin in its parent link and turned by the
  origin's angle: a ``hinge`` about z (``q`` rad, the link's angle from the joint frame) or a ``slide`` along
  the frame's x (``q`` m), with its link polygon as geom ``link:<joint>``;
* per joint two actuators: ``servo:<joint>``, a velocity drive: its ``ctrl`` is the velocity command, its
  activation integrates it into a position reference ``a`` that a PD tracks, ``kp (a - q) - kv qd``
  (:func:`servo_gains`; a controller sets ``a = q_ref + qd_ref kv / kp`` at each tick and ``ctrl = qd_ref``); and
  ``motor:<joint>``, a torque (N m, or N) motor.  A replay zeroes the servo's gains while the joint is
  torque-controlled;
* contact pairs, each with its own friction: ``palm:K`` (palm, ``foot:K``) per workpiece vertex, and per link of
  the left finger ``left:<joint>`` (link, workpiece), of the right finger ``right:<joint>``.  The friction vector
  keeps the palm edge's four coefficients (``palm:0``, ``palm:1``, ``left``, ``right``); a palm contact under
  another vertex takes ``palm:0``'s, the rule of every replay (:func:`qsplan.planner.replay.phases.body_friction`).
  No other pair collides (the certifier checks links, palm and workpiece apart along the plan).  A ``contact``
  sensor ``force:<pair>`` per pair reports its points' forces.

The quasistatic model has massless links where the hand file gives none: MuJoCo needs a moving body's
mass, so such a link weighs :data:`NOMINAL_LINK_MASS` with its gravity compensated (``gravcomp``); each joint
carries a motor's :data:`ARMATURE`.  Units SI.
"""

from __future__ import annotations

import numpy as np

from qsplan.hands.geometry.workpiece import polygon_inertia  # noqa: F401 (in __all__: its home is the hands layer)

from qsplan.mechanics.errors import QsplanError

__all__ = ["ARMATURE", "CONTACT_SOLIMP", "CONTACT_TIMECONST", "DEPTH", "FOOT_RADIUS", "MIN_MU", "NOMINAL_LINK_MASS",
           "PHYSICS_STEP", "SENSOR_SLOTS", "SERVO_OMEGA", "contact_pairs", "foot_centres", "pair_friction",
           "polygon_inertia", "scene_xml", "servo_gains", "start_of", "write_scene"]

#: Extrusion of every body along z (m).  The motion is planar (every joint turns about z or slides in the plane),
#: so the depth changes no force in the plane; 2 cm is a finger's thickness.
DEPTH = 0.02

#: Radius (m) of the workpiece's feet: a palm contact of the model is a workpiece vertex on the palm; a sphere in
#: that corner, touching both its edges (:func:`foot_centres`), carries it (with its own friction).  Its lowest
#: point lies on an edge's line when that edge rests flat on the palm, and at most ``r (1 / sin(a / 2) - 1)`` short
#: of the corner in any other orientation (``a`` the interior angle: 41 um at a right angle, 15 um at 120 deg).
FOOT_RADIUS = 1e-4

#: MuJoCo's time step (s): ten steps per 1 kHz control tick, so that the servos (:data:`SERVO_OMEGA`) and the
#: contacts (:data:`CONTACT_TIMECONST`) are resolved (omega * step = 0.4).
PHYSICS_STEP = 1e-4

#: Contact stiffness as MuJoCo's time constant (s, ``solref``): two steps, the stiffest MuJoCo resolves; a 0.2 kg
#: workpiece then sinks a few micrometres into the palm under its weight.
CONTACT_TIMECONST = 2 * PHYSICS_STEP

#: MuJoCo's contact impedance (``solimp``: dmin, dmax, width m): near 1 for a hard contact from the first
#: 0.1 mm of penetration.
CONTACT_SOLIMP = (0.99, 0.999, 1e-4)

#: Reflected inertia of each joint's motor (``armature``): kg m^2 for a revolute joint (a small geared servo),
#: kg for a prismatic one (a ball-screw jaw).  It sets the servos' gains (:func:`servo_gains`) and is what a
#: torque-controlled joint accelerates besides its link.
ARMATURE = {"revolute": 2e-4, "prismatic": 0.05}

#: Natural frequency (rad/s) of the joint servos: critically damped PD on :data:`ARMATURE`, stiff enough that a
#: 0.5 N m load deflects a revolute joint 0.16 mrad (16 um at a 0.1 m finger), stable at :data:`PHYSICS_STEP`.
SERVO_OMEGA = 4000.0

#: Mass (kg) of a link the hand file leaves massless (MuJoCo needs a moving body's mass): 1 g, its gravity
#: compensated, its inertia that of the uniform polygon.
NOMINAL_LINK_MASS = 1e-3

#: Contact points each pair's force sensor reports (``force:<pair>``, MuJoCo's ``contact`` sensor: per point the
#: count found and the force in the contact frame, normal first).  A prism on a prism touches at up to 4 points.
SENSOR_SLOTS = 8

#: MuJoCo's smallest friction coefficient (``mjMINMU``): a coefficient of 0 is written as this.
MIN_MU = 1e-5


def servo_gains(kind: str) -> tuple:
    """``(kp, kv)`` of a joint's servo: critically damped at :data:`SERVO_OMEGA` on the joint's :data:`ARMATURE`
    (N m/rad and N m s/rad for a revolute joint; N/m and N s/m for a prismatic one)."""
    inertia = ARMATURE[kind]
    return inertia * SERVO_OMEGA**2, 2.0 * inertia * SERVO_OMEGA


def contact_pairs(hand) -> dict:
    """``{contact: (pair names)}``, the contacts a replay judges and the MJCF pairs carrying each: the palm edge's
    four first (``palm:0``, ``palm:1``, ``left``, ``right``: the friction vector's order and every earlier replay's
    letters), then ``palm:K`` for the workpiece's other vertices ``K = 2, 3, ...`` (extended, never renamed)."""
    left, right = hand.finger_joint_names
    more = {f"palm:{k}": (f"palm:{k}",) for k in range(2, len(hand.workpiece))}
    return {"palm:0": ("palm:0",), "palm:1": ("palm:1",), "left": tuple(f"left:{n}" for n in left),
            "right": tuple(f"right:{n}" for n in right), **more}  # fmt: skip


def pair_friction(mu, names) -> np.ndarray:
    """The friction of contacts ``names`` (:func:`contact_pairs`' keys) from a friction vector ``mu`` (palm:0, palm:1,
    left, right): :func:`qsplan.planner.replay.phases.body_friction`, the rule of every replay (a palm contact under
    another vertex takes palm:0's)."""
    from qsplan.planner.replay.phases import body_friction

    return body_friction(names, _mu(mu))


def foot_centres(polygon, radius: float = FOOT_RADIUS) -> np.ndarray:
    """Centres (k, 2) of the feet of ``polygon`` (k, 2), in its frame: each on its vertex's inward bisector at
    ``radius / sin(a / 2)`` (``a`` the interior angle), so that the sphere touches both edges of the corner.

    Whichever way the workpiece turns, the foot's lowest point stands at most ``radius (1 / sin(a / 2) - 1)`` above
    the corner's (along the bisector) and exactly on an edge's line when that edge rests flat on the palm.
    """
    p = np.asarray(polygon, dtype=float)
    x, y = p[:, 0], p[:, 1]
    ccw = float(x @ np.roll(y, -1) - np.roll(x, -1) @ y) > 0.0
    out = np.empty_like(p)
    for k in range(len(p)):
        a, b = p[k - 1] - p[k], p[(k + 1) % len(p)] - p[k]
        a, b = a / np.hypot(*a), b / np.hypot(*b)
        turn = float(a[0] * b[1] - a[1] * b[0])  # from the next edge's direction to the previous one's
        half = 0.5 * np.arctan2(-turn if ccw else turn, float(a @ b)) % np.pi  # half the interior angle, (0, pi)
        # the inward bisector: the next edge's direction turned inward by half the interior angle
        c, s = np.cos(half), np.sin(half) * (1.0 if ccw else -1.0)
        u = np.array([c * b[0] - s * b[1], s * b[0] + c * b[1]])
        out[k] = p[k] + radius / np.sin(half) * u
    return out


def _convex(polygon) -> tuple:
    """``(convex hull vertices (k, 2) counter-clockwise, whether the polygon was convex)``."""
    from shapely.geometry import MultiPoint, Polygon

    p = np.asarray(polygon, dtype=float)
    hull = MultiPoint(p).convex_hull
    return np.asarray(hull.exterior.coords)[:-1], abs(hull.area - Polygon(p).area) <= 1e-12 * max(hull.area, 1e-30)


def _nums(values) -> str:
    return " ".join(repr(float(v)) for v in np.ravel(values))


def _prism(name, polygon) -> str:
    """A mesh asset: ``polygon`` (k, 2) extruded over z in [-DEPTH/2, DEPTH/2]."""
    p = np.asarray(polygon, dtype=float)
    z = np.full((len(p), 1), DEPTH / 2)
    return f'    <mesh name="{name}" vertex="{_nums(np.vstack([np.hstack([p, -z]), np.hstack([p, z])]))}"/>'


def _mu(mu) -> np.ndarray:
    m = np.broadcast_to(np.asarray(mu, dtype=float), (4,)).copy()
    if np.any(~np.isfinite(m)) or np.any(m < 0):
        raise QsplanError(f"mu: expected four nonnegative friction coefficients (palm:0, palm:1, left, right); "
                          f"got {m.tolist()}")  # fmt: skip
    return m


def scene_xml(task, mu=None, start=None) -> str:
    """The MJCF (MuJoCo XML) of ``task``'s scene (the layout: :mod:`qsplan.planner.replay.mujoco_scene`).

    Parameters
    ----------
    task : qsplan.planner.task.task.Task
    mu : float or array-like, shape (4,), optional
        Friction of the contacts palm:0, palm:1, left, right (a foot under another vertex takes palm:0's,
        :func:`pair_friction`); default the middle of the task's friction set (a replay sets each run's own).
    start : (array-like (3,), array-like (n_j,)), optional
        The workpiece pose (m, m, rad) and joints (rad or m) of a keyframe ``start`` (a plan's first row).

    Returns
    -------
    str
    """
    hand = task.hand
    man = hand.description.manipulator
    mu = _mu(np.mean(task.mu_range) if mu is None else mu)
    notes, assets, pairs = [], [], []
    palm, palm_convex = _convex(hand.palm)
    lo, hi = palm.min(axis=0), palm.max(axis=0)
    if len(palm) == 4 and np.all((palm == lo) | (palm == hi)):  # an axis-aligned rectangle
        palm_geom = (f'<geom name="palm" type="box" pos="{_nums([*(lo + hi) / 2, 0.0])}" '
                     f'size="{_nums([*(hi - lo) / 2, DEPTH / 2])}" rgba="0.6 0.6 0.6 1"/>')  # fmt: skip
    else:
        assets.append(_prism("palm", palm))
        palm_geom = '<geom name="palm" type="mesh" mesh="palm" rgba="0.6 0.6 0.6 1"/>'
    if not palm_convex:
        notes.append("the palm polygon is not convex: its convex hull collides")
    body = [f"    {palm_geom}"]
    # the workpiece: a planar free body at its centre of mass (the hand's internal vertices are about it)
    wp = np.asarray(hand.workpiece, dtype=float)
    _, izz = polygon_inertia(wp, hand.workpiece_mass)
    assets.append(_prism("workpiece", wp))
    body += ['    <body name="workpiece">',
             f'      <inertial pos="0 0 0" mass="{float(hand.workpiece_mass)!r}" diaginertia="{_nums([izz] * 3)}"/>',
             '      <joint name="workpiece_x" type="slide" axis="1 0 0"/>',
             '      <joint name="workpiece_y" type="slide" axis="0 1 0"/>',
             '      <joint name="workpiece_theta" type="hinge" axis="0 0 1"/>',
             '      <geom name="workpiece" type="mesh" mesh="workpiece" rgba="0.85 0.55 0.2 1"/>']  # fmt: skip
    feet = foot_centres(wp)
    palm_mu = pair_friction(mu, [f"palm:{k}" for k in range(len(wp))])
    for k, centre in enumerate(feet):
        body.append(f'      <geom name="foot:{k}" type="sphere" size="{FOOT_RADIUS!r}" '
                    f'pos="{_nums([*centre, 0.0])}" rgba="0.85 0.55 0.2 1"/>')  # fmt: skip
        pairs.append((f"palm:{k}", "palm", f"foot:{k}", palm_mu[k]))
    body.append("    </body>")
    # the hand: one body per joint, nested along each finger
    finger = dict(zip(hand.joint_names, hand.description.finger_of_joint))
    children = {i: [c for c, j in enumerate(man.joints) if j.parent == i] for i in range(-1, len(man.joints))}
    actuators = []

    def link(i, indent):
        j = man.joints[i]
        pad = " " * indent
        hull, convex = _convex(j.link_shape)
        if not convex:
            notes.append(f"link {j.name!r} is not convex: its convex hull collides")
        massless = float(j.link_mass) <= 0.0
        mass = NOMINAL_LINK_MASS if massless else float(j.link_mass)
        c, izz = polygon_inertia(hull, mass)
        com = c if massless else np.asarray(j.link_com, dtype=float)
        if not massless:  # the parallel axis: the hand file's centre of mass, the polygon's spread about it
            izz += mass * float(np.sum((c - com) ** 2))
        x, y, angle = (float(v) for v in j.origin)
        kind = "hinge" if j.kind == "revolute" else "slide"
        axis = "0 0 1" if kind == "hinge" else "1 0 0"
        lo, hi = (float(v) for v in hand.description.joint_limits[i])
        name = _attr(j.name)  # names in XML attributes
        assets.append(_prism(f"link:{name}", hull))
        out = [f'{pad}<body name="{name}" pos="{_nums([x, y, 0.0])}" euler="0 0 {angle!r}"'
               + (' gravcomp="1">' if massless else ">"),
               f'{pad}  <inertial pos="{_nums([*com, 0.0])}" mass="{mass!r}" diaginertia="{_nums([izz] * 3)}"/>',
               f'{pad}  <joint name="{name}" type="{kind}" axis="{axis}" range="{lo!r} {hi!r}" '
               f'armature="{ARMATURE[j.kind]!r}"/>',
               f'{pad}  <geom name="link:{name}" type="mesh" mesh="link:{name}" rgba="0.3 0.4 0.8 1"/>']
        kp, kv = servo_gains(j.kind)
        actuators.append(f'    <general name="servo:{name}" joint="{name}" dyntype="integrator" gainprm="{kp!r}" '
                         f'biastype="affine" biasprm="0 {-kp!r} {-kv!r}"/>')  # fmt: skip
        actuators.append(f'    <motor name="motor:{name}" joint="{name}" gear="1"/>')
        side = finger[j.name]
        pairs.append((f"{side}:{name}", f"link:{name}", "workpiece", mu[2 if side == "left" else 3]))
        for c in children[i]:
            out += link(c, indent + 2)
        return out + [f"{pad}</body>"]

    for i in children[-1]:
        body += link(i, 4)
    g = float(hand.gravity)
    lines = [f'<mujoco model="{_attr(task.name)}">',
             f"  <!-- qsplan: the scene of task {_comment(task.name)!r}, hand {_comment(hand.description.name)!r}; "
             "plane x-y, gravity -y, joints about z (qsplan.planner.replay.mujoco_scene) -->"]  # fmt: skip
    lines += [f"  <!-- note: {n} -->" for n in notes]
    lines += ['  <compiler angle="radian" inertiafromgeom="false" autolimits="true"/>',
              f'  <option timestep="{PHYSICS_STEP!r}" gravity="0 {-g!r} 0" integrator="implicitfast" cone="elliptic"/>',
              "  <default>",
              f'    <geom contype="0" conaffinity="0" condim="3" solref="{CONTACT_TIMECONST!r} 1" '
              f'solimp="{_nums(CONTACT_SOLIMP)}"/>',
              "  </default>", "  <asset>", *assets, "  </asset>", "  <worldbody>", *body, "  </worldbody>",
              "  <contact>"]  # fmt: skip
    for name, g1, g2, m in pairs:
        f = max(float(m), MIN_MU)
        lines.append(f'    <pair name="{name}" geom1="{g1}" geom2="{g2}" condim="3" '
                     f'friction="{_nums([f, f, 0, 0, 0])}" '
                     f'solref="{CONTACT_TIMECONST!r} 1" solimp="{_nums(CONTACT_SOLIMP)}"/>')  # fmt: skip
    lines += ["  </contact>", "  <actuator>", *actuators, "  </actuator>", "  <sensor>"]
    lines += [f'    <contact name="force:{name}" geom1="{g1}" geom2="{g2}" data="found force" num="{SENSOR_SLOTS}"/>'
              for name, g1, g2, _ in pairs]
    lines += ["  </sensor>"]
    if start is not None:
        pose, q = start
        qpos = _nums(np.concatenate([np.ravel(pose), np.ravel(q)]))
        lines += ["  <keyframe>", f'    <key name="start" qpos="{qpos}"/>', "  </keyframe>"]
    return "\n".join(lines + ["</mujoco>"]) + "\n"


def start_of(columns) -> tuple:
    """``(pose (3,), q (n_j,))`` of a plan's first row (columns as :func:`qsplan.planner.export.plan_files.plan_columns`
    or :func:`~qsplan.planner.export.plan_files.read_plan_csv` give them): the ``start`` of :func:`scene_xml`."""
    pose = np.array([float(np.ravel(columns[k])[0]) for k in ("x_workpiece", "y_workpiece", "theta_workpiece")])
    q = np.array([float(np.ravel(columns[k])[0]) for k in columns if k.startswith("q_")])
    return pose, q


def write_scene(task, path, start=None, force: bool = False):
    """Write :func:`scene_xml` of ``task`` (keyframe ``start``, e.g. :func:`start_of` a plan's columns) to ``path``,
    atomically, never over an existing file without ``force``; returns the path."""
    from qsplan.planner.export.files import atomic_write

    return atomic_write(path, scene_xml(task, start=start), force=force)


def _attr(text) -> str:
    """``text`` safe inside an XML attribute."""
    from xml.sax.saxutils import quoteattr

    return quoteattr(str(text))[1:-1]


def _comment(text) -> str:
    """``text`` safe inside an XML comment (no ``--``)."""
    return str(text).replace("--", "- -")
