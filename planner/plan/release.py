"""Release holds: before the fingers let go of the workpiece, the joint that bears the grasp's load is unloaded at
rest (issue 31).

A slide ends at rest with its contacts loaded as the sliding motion left them.  The rigid model says nothing about
those loads at rest (a certified hold, :mod:`qsplan.mechanics.bands.hold`, proves only that nothing moves), but a
compliant hand keeps them: a position servo that pushed the workpiece along keeps its deflection, and when a regrasp
opens the fingers the stored force goes at once, a kick.  On ``benchmarks/mujoco_tasks/two_link_right.toml`` at
friction 0.3 the slide nears a wedge (the rigid model's contact forces grow from 5 N to 36 N over its last 5 mm at
that friction), MuJoCo's pushing finger carries 18 N, and its release kicked the workpiece 0.14 mm along the palm.

Before every release (a regrasp right after a slide) the plan therefore holds the workpiece still while the joint
that bears the largest torque at the slide's end (:func:`release_joint`: the slide's mode solved at every vertex of
the friction set, every joint's torque, eq. 3) goes to the least torque at which the hold is still proved
(:func:`release_torque`, inside :func:`qsplan.mechanics.bands.hold.hold_torque_interval` with the task's force
margin):

* the slide's effort joint: its torque ramps there from the slide's last command
  (:data:`qsplan.planner.plan.pivot.HOLD_TORQUE_RATE`);
* another joint: taken over at rest directly at that torque (its servo lets go of what it stored; nothing moves, for
  every friction, by the hold's proof), held :data:`~qsplan.planner.plan.pivot.HOLD_MIN_DURATION`.

The phase is a hold (every letter ``R``, :func:`qsplan.planner.plan.pivot.hold_phase`), its band the proved hold
interval, certified like any hold (:func:`qsplan.planner.certify.timing.hold_checks`).  Where no joint's hold is
proved there the release goes as before.  Units SI (m, s, N m or N).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

__all__ = ["release_hold", "release_holds", "release_joint", "release_torque"]


def release_torque(lo: float, hi: float, resolution: float) -> float:
    """The effort of least magnitude at least a torque resolution inside ``[lo, hi]`` (N m or N; ``-inf``/``inf``
    allowed): 0 where it fits, else the edge nearer 0 moved a resolution in; the midpoint of an interval narrower than
    two resolutions; NaN for an empty one."""
    if not lo <= hi:
        return float("nan")
    a, b = lo + resolution, hi - resolution
    if a > b:
        return 0.5 * (lo + hi)
    return float(min(max(0.0, a), b))


def release_joint(task, slide) -> list:
    """The joints in the order a release hold tries them: by the largest torque each bears at ``slide``'s last row
    (N m or N), over every vertex of the task's friction set, largest first.

    The row's scene is the one the certifier judges it with (at rest: the motion that reaches it, the effort joint at
    its last command, :func:`qsplan.planner.plan.timing.rest_scene`); the slide's mode, guaranteed there for every
    friction of the set, is solved at each vertex (:func:`qsplan.mechanics.solve`) and every joint's torque read
    (eq. 3: the servos' share of the load).  A vertex where nothing is found adds nothing.
    """
    from itertools import product

    from qsplan.mechanics import solve
    from qsplan.planner.plan.timing import rest_scene

    names = list(task.hand.joint_names)
    effort = np.array(names) == slide.effort_joint
    k = slide.t.size - 1
    chord = (slide.q[k] - slide.q[k - 1]) / (slide.t[k] - slide.t[k - 1]) if k > 0 else np.zeros(len(names))
    scene = rest_scene(task, slide, k, k - 1, effort, np.where(effort, 0.0, chord))
    scene = scene.with_control(effort, np.where(effort, np.nan, chord), np.where(effort, slide.command[k], np.nan))
    peak = np.zeros(len(names))
    lo, hi, n = *task.mu_range, scene.n_contacts  # the set's vertices: a shared coefficient's ends, or the box's
    for mu in ([[lo] * n, [hi] * n] if task.shared_mu else product((lo, hi), repeat=n)):
        for sol in solve(scene.with_mu(mu), residuals=False, workers=1).solutions:
            peak = np.maximum(peak, np.abs(np.asarray(sol.tau, dtype=float)))
    return [names[j] for j in np.argsort(-peak, kind="stable")]


def release_hold(task, name, pose, q, joint, tau_from, t0, formation: str):
    """``(hold phase, HoldStep)`` unloading ``joint`` at rest at ``pose``, ``q``: its torque ramps from ``tau_from``
    (N m or N; None: taken over there) to :func:`release_torque` of the proved hold interval, every other joint held;
    None where that interval is empty.

    Raises
    ------
    PlanFailure, QsplanError
        As :func:`qsplan.planner.plan.pivot.hold_phase` (no hold proved for the ramp, no scene).
    """
    from qsplan.planner.plan.pivot import held_interval, hold_phase
    from qsplan.planner.plan.steps import HoldStep

    held = held_interval(task, pose, q, np.array(task.hand.joint_names) == joint)
    lo, hi = held[1]
    target = release_torque(lo, hi, task.torque_resolution)
    if not np.isfinite(target):
        return None
    start = target if tau_from is None else float(tau_from)
    hold = hold_phase(task, name, pose, q, joint, start, target, t0, formation, held=held)
    return hold, HoldStep(float(pose[0]), float(pose[2]), joint, start, target, float(lo), float(hi))


def _release_hold(task, slide, t0):
    """The hold before ``slide``'s release, from ``t0`` (s): ``(phase, HoldStep)``, or None where no joint's hold is
    proved at the slide's end."""
    from qsplan.mechanics.errors import QsplanError
    from qsplan.planner.plan.results import PlanFailure

    pose = slide.poses(task.hand.rest_height)[-1]
    q = slide.q[-1]
    for joint in release_joint(task, slide):
        start = float(slide.command[-1]) if joint == slide.effort_joint else None
        try:  # no hold proved with this joint (or its scene not built): the next one
            found = release_hold(task, f"release hold at x = {pose[0]:.4g} m", pose, q, joint, start, t0,
                                 slide.formation)  # fmt: skip
        except (PlanFailure, QsplanError):
            continue
        if found is None:
            continue
        hold, step = found
        # on the palm edge: the formation's contacts, named as the slide's rows name them
        same = slide.contacts is None and len(hold.mode) == len(task.formation.contact_names)
        hold = replace(hold, pose=None if slide.pose is None else hold.pose, contacts=None if same else hold.contacts)
        return hold, step
    return None


def release_holds(plan):
    """``plan`` (time-scaled) with a release hold (the module docstring) between every slide and the regrasp that
    follows it, the later phases' times moved by its duration; its ``timing`` and, where ``sequence`` has a step per
    phase, ``sequence`` with the hold's."""
    from qsplan.planner.plan.results import SlidePhase
    from qsplan.planner.plan.steps import SearchSummary, route_steps
    from qsplan.planner.plan.timing import PhaseTiming

    task = plan.task
    stepped = len(route_steps(plan.sequence)) == len(plan.phases)
    steps = list(route_steps(plan.sequence)) if stepped else []
    phases, timing, seq, shift = [], [], [], 0.0
    for i, ph in enumerate(plan.phases):
        ph = replace(ph, t=ph.t + shift) if shift else ph
        phases.append(ph)
        if plan.timing:
            timing.append(plan.timing[i])
        if stepped:
            seq.append(steps[i])
        after = plan.phases[i + 1] if i + 1 < len(plan.phases) else None
        if not (isinstance(ph, SlidePhase) and after is not None and not after.in_contact):
            continue
        found = _release_hold(task, ph, float(ph.t[-1]))
        if found is None:
            continue
        hold, step = found
        duration = float(hold.t[-1] - hold.t[0])
        phases.append(hold)
        if plan.timing:
            timing.append(PhaseTiming(hold.name, 0, 0.0, 0.0, duration, duration, "none (a hold: nothing moves)"))
        if stepped:
            seq.append(step)
        shift += duration
    if stepped:
        seq += [s for s in plan.sequence if isinstance(s, SearchSummary)]
    return replace(plan, phases=tuple(phases), timing=tuple(timing) if plan.timing else plan.timing,
                   sequence=tuple(seq) if stepped else plan.sequence)
