"""Text and JSON renderings of solver results (the CLI's output formats)."""

from __future__ import annotations

import numpy as np

from qsplan.mechanics import SolveResult

__all__ = ["solve_result_to_dict", "format_solve_result"]


def _list(a):
    return [float(x) for x in np.asarray(a).ravel()]


def solve_result_to_dict(result: SolveResult) -> dict:
    """The ``qsplan modes --json`` document.

    Contract keys: ``modes_tested`` and ``feasible`` (each with ``mode``, ``name``,
    ``qdot``, ``normal_forces``, ``tangential_forces``, ``sliding_directions``,
    ``joint_velocities``, ``joint_efforts``).  Extensions: ``kind``, ``on_boundary``,
    ``max_residual`` per mode; ``counts``, ``ambiguous``, ``jammed``, ``units`` at the top.
    Joint lists are empty for scenes that give contact velocities instead of joints.
    """
    scene = result.scene
    feas = []
    for s in result.solutions:
        feas.append(
            {
                "mode": s.mode.letters,
                "name": s.mode.name,
                "kind": s.mode.kind,
                "qdot": _list(s.qdot),
                "normal_forces": _list(s.c_n),
                "tangential_forces": _list(s.c_t),
                "sliding_directions": [int(x) for x in s.xi],
                "joint_velocities": [] if scene.virtual_joints else _list(s.thetadot),
                "joint_efforts": [] if scene.virtual_joints else _list(s.tau),
                "on_boundary": s.on_boundary,
                "max_residual": s.max_residual,
            }
        )
    return {
        "modes_tested": result.modes_tested,
        "feasible": feas,
        "counts": result.counts,
        "ambiguous": result.ambiguous,
        "jammed": result.jammed,
        "no_feasible_mode": result.no_feasible_mode,
        "undecided": result.degenerate,
        "units": {"qdot": "m/s, m/s, rad/s (workpiece point at the world origin)", "forces": "N",
                  "joint_velocities": "rad/s or m/s", "joint_efforts": "N m or N"},
    }  # fmt: skip


def format_solve_result(result: SolveResult, source: str = "") -> str:
    """A readable table of the feasible modes, the rejection counts and a verdict."""
    scene = result.scene
    lines = []
    joints = "contact velocities given" if scene.virtual_joints else f"{scene.n_joints} joint{'s' if scene.n_joints != 1 else ''} ({len(scene.effort_joints)} effort-controlled)"
    lines.append(f"scene {source}: {scene.n_contacts} contacts, {joints}; modes tested: {result.modes_tested} (eq. 49)")
    undecided = result.degenerate
    if result.no_feasible_mode and not result.jammed:
        lines.append(f"no feasible mode found, but {undecided} mode(s) were not decided (degenerate or ill-conditioned, "
                     "see below): not a proven jam")  # fmt: skip
    elif result.jammed:
        lines.append("no feasible mode: the scene jams (or the model has no quasistatic solution)")
    else:
        verdict = "AMBIGUOUS: several modes are feasible" if result.ambiguous else "unique"
        lines.append(f"{len(result.solutions)} feasible mode(s): {verdict}")
        lines.append("")
        head = f"{'mode':<{max(4, scene.n_contacts)}}  {'name':<8} {'qdot x':>9} {'qdot y':>9} {'omega':>9}   contact forces c_n / c_t [N]"
        lines.append(head)
        for s in result.solutions:
            forces = "  ".join(
                f"{i + 1}:{s.c_n[i]:.4g}/{s.c_t[i]:.4g}" for i in range(scene.n_contacts) if s.mode.letters[i] != "B"
            )
            flag = "  (on a region boundary)" if s.on_boundary else ""
            lines.append(
                f"{s.mode.letters:<{max(4, scene.n_contacts)}}  {s.mode.name:<8} "
                f"{s.qdot[0] + 0.0:>9.4g} {s.qdot[1] + 0.0:>9.4g} {s.qdot[2] + 0.0:>9.4g}   {forces}{flag}"
            )
            if not scene.virtual_joints:
                lines.append(
                    f"{'':<{max(4, scene.n_contacts)}}  joints: "
                    + "  ".join(f"{n}: v={v:.4g} tau={t:.4g}" for n, v, t in zip(scene.joint_names, s.thetadot, s.tau))
                )
    rejected = ", ".join(f"{k.replace('_', ' ')} {v}" for k, v in result.counts.items() if v and k != "feasible")
    if rejected:
        lines.append("")
        lines.append(f"rejected: {rejected}")
    return "\n".join(lines) + "\n"
