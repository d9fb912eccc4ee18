"""The replay of phases in any formation: holds, the contact a slide makes at its end, pivots (issue 23).

:func:`qsplan.planner.replay.replay.replay_plan` re-simulates each in-contact phase with the finite-motion simulator.
A plan that turns the workpiece (:mod:`qsplan.planner.plan.turning`) has phases the palm edge's closed form does not
describe; this module says how each is replayed, from the rows and the task alone:

* a **hold** (every letter ``R``): nothing moves and nothing is simulated: the certificate proves it
  (:mod:`qsplan.mechanics.bands.hold`); the replay records it as followed, with that note;
* a phase whose **last row makes a contact** (the slide's end at the flush instant: the polygons show one more
  contact there than at the row before): simulated to the row before, where the formation still holds;
* a phase whose **first row has more contacts** than the rest (the pivot's transition row: vertex 0 lifts): the all-modes
  solver at that row with all its contacts must find the planned mode alone (the replay's start check), then the
  phase is simulated from its second row with the contacts of the rest;
* every phase's scenes come from the contacts the polygons show (:func:`qsplan.hands.contacts.found.
  row_contact_scene`), their count checked against the phase's: one path for every hand and formation.

Friction: the replay's vector gives one coefficient per body of the palm-edge formation (``palm:0``, ``palm:1``,
``left``, ``right``); a contact of another formation takes its body's (:func:`body_friction`).  Units SI.
"""

from __future__ import annotations

import numpy as np

from qsplan.mechanics.errors import QsplanError

__all__ = ["HOLD_NOTE", "body_friction", "formation_of", "found_scene", "phase_rows", "replay_segments",
           "rows_pose", "transition_modes", "turns"]

#: What a hold's replay records: it is not simulated; the certificate proves it.
HOLD_NOTE = "a hold: nothing moves; proved by the certificate (frictionless equilibrium, every contact loaded)"


def turns(columns, rows) -> bool:
    """Whether the phase's rows leave the palm edge: the workpiece turns (theta not 0), or a row's mode has other than
    four letters.  Such a phase starts where its rows say (the hold before it moves nothing); a slide on the palm
    edge starts where the simulation left the workpiece (its fingers closed on it again)."""
    theta = np.asarray(columns["theta_workpiece"], float)[rows]
    return bool(np.any(theta != 0.0) or any(len(str(columns["mode"][k])) != 4 for k in rows))


def _configuration(hand, columns, k) -> tuple:
    """``(pose, q)`` of row ``k`` (m, m, rad; rad or m)."""
    return rows_pose(columns, k), np.array([columns[f"q_{n}"][k] for n in hand.joint_names], float)


def _makes_contact(hand, columns, a, b) -> bool:
    """Whether the motion from row ``a`` to row ``b`` makes a contact only at ``b``
    (:func:`qsplan.hands.contacts.found.made_contacts`)."""
    from qsplan.hands.contacts.found import made_contacts, ordered_contacts

    after = _configuration(hand, columns, b)
    return bool(made_contacts(hand, _configuration(hand, columns, a), after, ordered_contacts(hand, *after)).any())


def phase_rows(hand, columns, rows) -> tuple:
    """``(rows to simulate, first row's mode to check with all its contacts or None, the simulated mode, note)``."""
    modes = [str(columns["mode"][k]) for k in rows]
    first = None
    if len(rows) > 1 and len(modes[0]) != len(modes[1]):  # the transition row: judged with all its contacts
        first, rows, modes = modes[0], rows[1:], modes[1:]
    note = None
    if len(rows) > 2 and _makes_contact(hand, columns, rows[-2], rows[-1]):
        rows = rows[:-1]  # the contact made at the last row: open along the motion, not simulated
        note = "simulated to the row before its last, where it makes a contact"
    return rows, first, modes[0], note


def body_friction(names, mu) -> np.ndarray:
    """The friction of contacts ``names`` from the replay's vector ``mu`` (the palm edge's palm:0, palm:1, left,
    right): each contact its slot's (:func:`qsplan.hands.contacts.found.slot_of`: a finger's contacts that finger's),
    a palm contact under another vertex palm:0's (the MuJoCo scene's feet too,
    :func:`qsplan.planner.replay.mujoco_scene.pair_friction`)."""
    from qsplan.hands.formations.registry import formation
    from qsplan.hands.contacts.found import slot_of

    slots = formation("palm_edge").contact_names
    return np.asarray([mu[j] if (j := slot_of(n, slots)) is not None else mu[0] for n in names], float)


def found_scene(hand, x, effort_controlled, velocity, effort, tracked):
    """The scene at replay state ``x`` (pose, joints, clock) of the contacts the polygons showed at the phase's
    start, followed by their features (``tracked``: :func:`qsplan.hands.contacts.found.track_contacts`).

    Raises
    ------
    QsplanError
        A contact's feature no longer touches (the geometry left its formation).
    """
    return tracked.scene(hand, x[:3], x[3:-1], effort_controlled, velocity, effort)


def formation_of(hand, columns, k, mode):
    """``(formation, tracked contacts)``: a formation of the contacts the polygons show at row ``k`` (their canonical
    names), ``mode`` its letters, the simulator's contacts of the phase; and those contacts as features to follow
    (:func:`qsplan.hands.contacts.found.track_contacts`)."""
    from qsplan.hands.formations.registry import ContactSlot, Formation
    from qsplan.hands.contacts.found import track_contacts

    pose, q = _configuration(hand, columns, k)
    tracked = track_contacts(hand, pose, q)
    if len(tracked.names) != len(mode):
        raise QsplanError(f"plan: row {k}'s mode {mode} has {len(mode)} letters, and the polygons show "
                          f"{len(tracked.names)} contacts there ({', '.join(tracked.names) or 'none'}): the rows do not "
                          "touch the workpiece as their mode says")  # fmt: skip
    slots = tuple(ContactSlot(n, n.partition(":")[0], "any", None, f"{n}, found in the polygons") for n in tracked.names)
    return Formation("found", slots, mode, "last", "the contacts the polygons show"), tracked


def transition_modes(hand, columns, k, effort_controlled, mu) -> tuple:
    """Every mode the all-modes solver finds feasible at row ``k`` with all the contacts the polygons show (its
    velocity-controlled joints along the straight line to the next row; its efforts at their commands), friction
    :func:`body_friction`."""
    from dataclasses import replace

    from qsplan.hands.contacts.found import row_contact_scene
    from qsplan.mechanics.solver.all_modes import solve

    (pose, q0), (_, q1) = _configuration(hand, columns, k), _configuration(hand, columns, k + 1)
    tau = np.nan_to_num(np.array([columns[f"tau_{n}"][k] for n in hand.joint_names], float))
    scene = row_contact_scene(hand, pose, q0, effort_controlled, q1 - q0, tau)
    scene = replace(scene, mu=body_friction(scene.contact_names, mu))
    return tuple(solve(scene, residuals=False).feasible_modes)


def replay_segments(columns) -> list:
    """Split plan columns (:func:`qsplan.planner.export.plan_files.read_plan_csv`) into in-contact segments.

    ``phase`` is the phase's integer index (``0``, ``1``, ...; files before issue 16 wrote ``0.0``,
    ``1.0``, ...: both read alike).

    Returns
    -------
    list of dict
        Per segment: ``phase``, ``rows`` (indices), ``mode``, ``effort_joint``.
    """
    for key in ("t", "phase", "mode", "effort_joint", "x_workpiece"):
        if key not in columns:
            raise QsplanError(f"plan: column {key!r} missing; expected the columns of qsplan.planner.export.plan_files")
    if not any(str(key).startswith("q_") for key in columns):
        raise QsplanError("plan: no column 'q_<joint>'; expected the columns of qsplan.planner.export.plan_files")
    try:
        values = np.asarray(columns["phase"], float)
    except (TypeError, ValueError):
        values = np.array([np.nan])
    if not (np.all(np.isfinite(values)) and np.all(values == np.round(values)) and np.all(values >= 0)):
        raise QsplanError("plan: column 'phase' holds a value that is not a phase index (0, 1, 2, ...)")
    phases = values.astype(int)
    out = []
    for p in np.unique(phases):
        rows = np.flatnonzero(phases == p)
        mode = str(columns["mode"][rows[0]])
        if mode == "free":
            continue
        out.append(dict(phase=int(p), rows=rows, mode=mode, effort_joint=str(columns["effort_joint"][rows[0]])))
    return out


def rows_pose(columns, k) -> np.ndarray:
    """The planned workpiece pose at row ``k`` (m, m, rad), shape (3,)."""
    return np.array([columns["x_workpiece"][k], columns["y_workpiece"][k], columns["theta_workpiece"][k]], float)
