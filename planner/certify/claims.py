"""The certifier's checks of what ``plan.json``'s metadata states about each phase and the planned sequence (issue 31).

``metadata.phases`` describes each phase and ``metadata.sequence`` the steps the planner chose (one per phase, then
the search's figures).  Every fact they state about what the plan executes is checked here against the rows, and
against what the row checks found from the task (:class:`RowEvidence`: each in-contact row's contacts, found in the
polygons, and its band recomputed); :func:`phase_claims` and :func:`sequence_claims` return ``(row, "metadata",
message)`` triples, the row the phase's first.  What each key promises, and how it is checked:

``metadata.phases[i]``
    ``index``, ``rows``, ``t_start_s``, ``t_end_s``, ``kind``, ``mode`` (its first row's), ``effort_joint``,
    ``narrowest_band``: the rows'.  ``effort_unit``: the effort joint's unit.  ``phase_kind``: ``hold`` where nothing
    moves, ``pivot`` where the workpiece turns, ``slide`` otherwise.  ``contacts``: the contacts the first row's mode
    letters follow; ``contact_sets``: each run of rows (first and last, counted within the phase) with one list of
    contacts and one mode, as the row checks found the contacts; ``formation``: the registered formation
    (:mod:`qsplan.hands.formations.registry`) with the contacts of the last run (a pivot's first row judges the
    transition).  ``competitors_precluded``: distinct modes, each of the length of a mode the phase's rows plan and
    none of them.  The promise is what the band check proves: at every row, every mode of its contacts but the planned
    one is precluded for every friction in the set (all of them, listed or not).  ``workpiece_speed_m_s``: the largest
    speed of the workpiece's centre of mass at the quasistatic speed (``speed_scale`` 1): 0 where nothing moves; a
    translating workpiece's speed over every interval (its distance over the path covered: the rule's integral of the
    speed scale over time); a turning one's at least every interval's mean and at most the task's limit.  ``command``:
    ``margin_N_m`` the least margin cell, ``half_narrowest_band_N_m`` half the narrowest band, ``max_N_m`` the
    largest command, ``lower_edge_max_N_m`` the largest lower edge.  ``time_scaling``: ``duration_s`` the phase's,
    ``pieces`` its rest-to-rest pieces (runs of rows in motion), ``path_acceleration_1_s2`` the largest change of the
    speed scale per second between two rows, ``peak_speed_scale`` the largest speed scale at a row,
    ``quasistatic_duration_s`` the path covered (a phase at rest throughout: its duration).  A regrasp's
    ``x_workpiece_m``: its first row's.  A finger replaced mid-turn (free rows where one finger's joints move and the
    other's do not): ``phase_kind`` ``replace``, that ``finger``, ``y_workpiece_m`` and ``theta_workpiece_rad`` of its
    first row, and ``contacts_kept``: the contacts the polygons show there without that finger's.
``metadata.sequence[i]``
    A step of the kind of phase ``i`` (``slide``, ``regrasp``, ``replace``, ``hold``, ``pivot``); the search's figures
    last.  A replacement's ``theta_rad``, ``finger`` and ``contacts_kept`` as its phase's (``formation`` and
    ``hold_margin_N`` informational: the next phases name the formation, the row checks prove the hold).
    ``x_from_m``, ``x_to_m`` (``x_from``, ``x_to``, ``x``), ``theta_from_rad``, ``theta_to_rad``, ``theta_rad``,
    ``effort_joint``, ``effort_unit``, ``narrowest_band``: the phase's rows'.  A hold's ``torque_from``,
    ``torque_to``: its first and last command; its ``proved_interval``: every hold row's band, and within the band
    the row checks recomputed from the task (the torques at which nothing moves).  A pivot's ``vertex`` (as the task
    writes it): the one workpiece vertex on the palm after its first row.

Informational (the schema says so; nothing a controller relies on): a phase's ``name``, ``ompl_states`` and
``time_scaling.binding``, a grasp's label (``grasp``, ``grasp_from``, ``grasp_to``, ``from``, ``to``) and the
search's figures.  Units SI.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from qsplan.mechanics.errors import QsplanError

from qsplan.planner.certify.stated import META_TOL, close, difference, differs, finite_or_none, narrowest, show

__all__ = ["INFORMATIONAL_PHASE_KEYS", "INFORMATIONAL_STEP_KEYS", "RowEvidence", "phase_claims", "sequence_claims"]

#: Keys of ``metadata.phases[i]`` (and of its ``time_scaling``) that state nothing a controller relies on.
INFORMATIONAL_PHASE_KEYS = frozenset({"name", "ompl_states"})
INFORMATIONAL_TIMING_KEYS = frozenset({"binding"})

#: Keys of a ``metadata.sequence`` step that state nothing a controller relies on (the grasps' labels), and the
#: kinds of step that are informational as a whole (the search's figures).
INFORMATIONAL_STEP_KEYS = frozenset({"grasp", "grasp_from", "grasp_to", "from", "to"})
INFORMATIONAL_STEPS = frozenset({"search"})


@dataclass(frozen=True, slots=True)
class RowEvidence:
    """What the row checks found from the task, for the metadata's claims.

    Attributes
    ----------
    contacts : dict
        ``{row: tuple of str}``: the contacts each in-contact row's mode letters follow
        (:func:`qsplan.planner.certify.contacts.row_contact_names`), for every row whose contacts were found.
    bands : dict
        ``{row: band}``: each in-contact row's band recomputed from the task
        (:func:`qsplan.planner.certify.bands.recomputed_bands`; ``feasible``, ``lower``, ``upper``).
    """

    contacts: dict = field(default_factory=dict)
    bands: dict = field(default_factory=dict)


def _message(found) -> str:
    return differs(found, "the rows'")


def _phase_rows(cols, i) -> np.ndarray:
    return np.flatnonzero(np.asarray(cols["phase"], float) == i)


def _effort_ok(task, cols, rows) -> bool:
    """Every row names one of the hand's joints as its effort joint (else the input check names it)."""
    names = set(task.hand.joint_names)
    return all(str(cols["effort_joint"][k]) in names for k in rows)


def _moves(cols, rows, names) -> tuple:
    """``(anything moves, the workpiece turns)`` over ``rows``: a pose or joint change above the jump tolerance."""
    from qsplan.planner.certify.rows import JUMP_TOL

    pose = np.column_stack([np.asarray(cols[f"{c}_workpiece"], float)[rows] for c in ("x", "y", "theta")])
    q = np.column_stack([np.asarray(cols[f"q_{n}"], float)[rows] for n in names])
    moved = max(float(np.max(np.ptp(pose, axis=0))), float(np.max(np.ptp(q, axis=0))))
    return moved > JUMP_TOL, float(np.ptp(pose[:, 2])) > JUMP_TOL


def _path(cols, rows):
    """Per interval of ``rows``: ``(dt, path covered ds, centre-of-mass distance)``; ``ds`` by the time scaling's rule
    (the speed scale linear in time between rows: ``(u_a + u_b) dt / 2`` quasistatic seconds)."""
    t = np.asarray(cols["t"], float)[rows]
    u = np.asarray(cols["speed_scale"], float)[rows]
    x, y = (np.asarray(cols[c], float)[rows] for c in ("x_workpiece", "y_workpiece"))
    dt = np.diff(t)
    return dt, 0.5 * (u[:-1] + u[1:]) * dt, np.hypot(np.diff(x), np.diff(y))


def _time_scaling(cols, rows) -> dict:
    """``time_scaling`` as the rows give it (:mod:`qsplan.planner.plan.timing`'s rule)."""
    from qsplan.planner.plan.timing import scale_rate

    t = np.asarray(cols["t"], float)[rows]
    u = np.asarray(cols["speed_scale"], float)[rows]
    _, ds, _ = _path(cols, rows)
    alpha = scale_rate(t, u)
    moving = u > 0
    duration = float(t[-1] - t[0])
    return {"pieces": int(np.count_nonzero(np.diff(moving.astype(int)) == 1) + int(moving[0])),
            "path_acceleration_1_s2": alpha, "peak_speed_scale": float(np.max(u)), "duration_s": duration,
            "quasistatic_duration_s": float(np.sum(ds)) if moving.any() else duration}  # fmt: skip


def _contact_sets(cols, rows, evidence):
    """``(contacts, contact_sets)`` of the phase as the row checks found its contacts, or None where some row's
    contacts were not found (its contact check names it)."""
    from qsplan.planner.export.plan_files import contact_runs

    if not all(int(k) in evidence.contacts for k in rows):
        return None
    runs = contact_runs([evidence.contacts[int(k)] for k in rows], [str(cols["mode"][k]) for k in rows])
    return runs[0]["contacts"], runs


def _command(cols, rows) -> dict:
    """``command`` as the rows give it: the least margin, half the narrowest band, the largest command and lower
    edge."""
    e = [str(cols["effort_joint"][k]) for k in rows]
    tau = np.array([cols[f"tau_{ej}"][k] for ej, k in zip(e, rows)], dtype=float)
    lower = np.array([cols[f"tau_{ej}_min"][k] for ej, k in zip(e, rows)], dtype=float)
    _, w = narrowest(cols, rows)
    return {"margin_N_m": finite_or_none(float(np.min(np.asarray(cols["margin"], float)[rows]))),
            "half_narrowest_band_N_m": None if w is None else 0.5 * w, "max_N_m": finite_or_none(float(np.max(tau))),
            "lower_edge_max_N_m": finite_or_none(float(np.max(lower)))}  # fmt: skip


def _replacement(task, cols, rows) -> dict:
    """A run of free rows where one finger's joints move and the other's do not (a finger replaced mid-turn): its
    ``phase_kind``, ``finger``, the workpiece's ``y_workpiece_m`` and ``theta_workpiece_rad`` and the ``contacts_kept``
    the polygons show at its first row without the moving finger's; ``{}`` for a regrasp (both fingers move)."""
    from qsplan.hands.contacts.found import lifted_contacts
    from qsplan.mechanics.errors import SceneError

    from qsplan.planner.certify.rows import moving_fingers, row_pose, row_q

    moving = moving_fingers(task, cols, rows)
    if len(moving) != 1:
        return {}
    k = int(rows[0])
    pose = row_pose(cols, k)
    try:
        _, names, lifted = lifted_contacts(task.hand, pose, row_q(cols, k, task.hand.joint_names), moving[0])
        kept = [n for n, off in zip(names, lifted) if not off]
    except SceneError:
        kept = None  # the row checks name the overlap
    return {"phase_kind": "replace", "finger": moving[0], "y_workpiece_m": float(pose[1]),
            "theta_workpiece_rad": float(pose[2]), "contacts_kept": kept}


def _phase_kind(cols, rows, names) -> str:
    moved, turned = _moves(cols, rows, names)
    return "pivot" if turned else ("slide" if moved else "hold")


def phase_claims(phases, task, cols, evidence) -> list:
    """Each ``metadata.phases`` entry against its rows and ``evidence`` (the module docstring)."""
    names = task.hand.joint_names
    ph = np.asarray(cols["phase"], float)
    if not isinstance(phases, list) or not np.all(np.isfinite(ph)) or len(phases) != int(np.max(ph)) + 1:
        count = int(np.max(ph)) + 1 if np.all(np.isfinite(ph)) else "unnumbered"
        return [(None, "metadata", f"{len(phases) if isinstance(phases, list) else 'no'} phases described; the rows "
                                   f"have {count}")]  # fmt: skip
    out = []
    for i, d in enumerate(phases):
        rows = _phase_rows(cols, i)
        path = f"metadata.phases[{i}]"
        if not rows.size:
            out.append((None, "metadata", f"phase {i} has no rows"))
            continue
        if not isinstance(d, dict):
            out.append((int(rows[0]), "metadata", f"{path} is not an object"))
            continue
        out += [(int(rows[0]), "metadata", m) for m in _core(d, cols, rows, path)]
        out += [(int(rows[0]), "metadata", m) for m in _more(d, task, cols, rows, path, evidence, names)]
    return out


def _core(d, cols, rows, path) -> list:
    """Index, rows, times, kind, mode, effort joint and narrowest band (issue 21's claims)."""
    i = int(cols["phase"][rows[0]])
    mode, effort = str(cols["mode"][rows[0]]), str(cols["effort_joint"][rows[0]])
    kind = "regrasp" if mode == "free" else "contact"
    problems = []
    if d.get("index") != i:
        problems.append(f"index {d.get('index')}")
    if d.get("rows") != rows.size:
        problems.append(f"{d.get('rows')} rows (the file has {rows.size})")
    t = np.asarray(cols["t"], float)
    if not (close(d.get("t_start_s"), t[rows[0]]) and close(d.get("t_end_s"), t[rows[-1]])):
        problems.append(f"times {d.get('t_start_s')} to {d.get('t_end_s')} s (the rows': {t[rows[0]]:g} to "
                        f"{t[rows[-1]]:g} s)")  # fmt: skip
    if d.get("kind") != kind:
        problems.append(f"kind {d.get('kind')!r} (the rows': {kind})")
    if kind == "contact":
        if d.get("mode") != mode or d.get("effort_joint") != effort:
            problems.append(f"mode {d.get('mode')} / effort joint {d.get('effort_joint')} (the rows': {mode} / "
                            f"{effort})")  # fmt: skip
        tn, w = narrowest(cols, rows)
        nb = d.get("narrowest_band") or {}
        if not (close(nb.get("t_s"), tn) and close(nb.get("width_N_m"), w)):
            problems.append(f"narrowest band {nb.get('width_N_m')} at t = {nb.get('t_s')} s (the rows': {w} at "
                            f"{tn:g} s)")  # fmt: skip
    return [f"{path} states " + "; ".join(problems)] if problems else []


_CORE = frozenset({"index", "rows", "t_start_s", "t_end_s", "kind", "mode", "effort_joint", "narrowest_band"})


def _more(d, task, cols, rows, path, evidence, names) -> list:
    """The rest of a phase's claims (the module docstring), each against the rows or ``evidence``."""
    contact = str(cols["mode"][rows[0]]) != "free"
    truth, out = {}, []
    unknown = set(INFORMATIONAL_PHASE_KEYS)  # not checked: informational, or what broken rows leave unknown (named)
    if "speed_scale" in cols:
        truth["time_scaling"] = _time_scaling(cols, rows)
    else:
        unknown.add("time_scaling")
    if not contact:
        truth["x_workpiece_m"] = float(cols["x_workpiece"][rows[0]])
        truth.update(_replacement(task, cols, rows))
    elif _effort_ok(task, cols, rows):
        truth["effort_unit"] = task.hand.joint_unit(str(cols["effort_joint"][rows[0]]), "tau")
        truth["phase_kind"] = _phase_kind(cols, rows, names)
        truth["command"] = _command(cols, rows)
    else:
        unknown |= {"effort_unit", "phase_kind", "command"}
    claim = {k: v for k, v in d.items() if k not in _CORE | unknown | _SPECIAL}
    if isinstance(claim.get("time_scaling"), dict):
        claim["time_scaling"] = {k: v for k, v in claim["time_scaling"].items() if k not in INFORMATIONAL_TIMING_KEYS}
    found = difference(claim, truth, path)
    if found:
        out.append(_message(found))
    if not contact:
        return out + [f"{path}.{k} is stated for a regrasp" for k in _SPECIAL if k in d]
    sets = _contact_sets(cols, rows, evidence)
    if sets is not None:
        for key, value in (("contacts", sets[0]), ("contact_sets", sets[1])):
            if key in d and (found := difference(d[key], value, f"{path}.{key}")):
                out.append(_message(found) + " (the contacts found in the polygons and the mode column)")
        if "formation" in d:
            out += _formation_claim(d["formation"], task, cols, rows, tuple(sets[1][-1]["contacts"]), path)
    if "competitors_precluded" in d:
        out += _competitor_claims(d["competitors_precluded"], cols, rows, path)
    if "workpiece_speed_m_s" in d and "speed_scale" in cols:
        out += _speed_claims(d["workpiece_speed_m_s"], task, cols, rows, path, names)
    return out


def _formation_claim(name, task, cols, rows, last, path) -> list:
    """A phase's ``formation``: a registered one (the palm edge's) whose contacts are the phase's last set, or a
    generated pivot (:func:`qsplan.hands.formations.pivots.pivot_from_name`) whose constraints hold at every row of the
    phase (each gap within the contact tolerance) and whose pivot vertex is on the palm at its last row."""
    from qsplan.hands.formations.registry import FORMATIONS
    from qsplan.hands.formations.manifold import gaps
    from qsplan.hands.formations.pivots import pivot_from_name
    from qsplan.mechanics.model.geometry import CONTACT_TOL
    from qsplan.planner.certify.rows import row_pose, row_q

    pivot = pivot_from_name(name, task.hand)
    if pivot is None and name not in FORMATIONS:  # e.g. a name of the retired hand-built route (issue 32)
        return [f"{path}.formation states {show(name)}: neither a registered formation ({', '.join(sorted(FORMATIONS))}) "
                "nor a pivot formation of this hand and workpiece (pivot:vVERTEX:FINGER:eEDGE:FEATURE)"]  # fmt: skip
    if pivot is None:
        fits = sorted(n for n, f in FORMATIONS.items() if f.contact_names == last)
        if name in fits:
            return []
        whose = " or ".join(fits) or "no registered formation"
        return [f"{path}.formation states {show(name)}; the phase's last contacts ({', '.join(last)}) are those of "
                f"{whose}"]  # fmt: skip
    names = task.hand.joint_names
    try:
        worst = max(float(np.max(np.abs(gaps(task.hand, pivot.constraints(task.hand),
                                                 np.concatenate([row_pose(cols, k), row_q(cols, k, names)])))))
                    for k in rows)  # fmt: skip
    except (QsplanError, IndexError) as exc:
        return [f"{path}.formation states {show(name)}, not a formation of this hand and workpiece ({exc})"]
    if not worst <= CONTACT_TOL or f"palm:{pivot.vertex}" not in last:
        return [f"{path}.formation states {show(name)}; its contacts are {worst:.3g} m open at the phase's rows (or its "
                f"pivot vertex is off the palm: the last contacts {', '.join(last)})"]  # fmt: skip
    return []


#: Keys checked by their own rule rather than equality.
_SPECIAL = frozenset({"contacts", "contact_sets", "formation", "competitors_precluded", "workpiece_speed_m_s"})


def _competitor_claims(comps, cols, rows, path) -> list:
    """Distinct modes, each as long as a mode the phase plans and none of them (the module docstring)."""
    planned = {str(cols["mode"][k]) for k in rows}
    lengths = {len(m) for m in planned}
    if not isinstance(comps, list) or not all(isinstance(c, str) for c in comps):
        return [f"{path}.competitors_precluded states {show(comps)}; expected a list of modes"]
    bad = [c for c in comps if not c or set(c) - set("RSB") or len(c) not in lengths or c in planned]
    if len(set(comps)) != len(comps):
        bad.append("(a mode listed twice)")
    if bad:
        return [f"{path}.competitors_precluded states {show(bad[0])}: not a competitor of the phase's planned "
                f"mode(s) {', '.join(sorted(planned))} (one letter of R, S, B per contact, another mode)"]  # fmt: skip
    return []


def _speed_claims(claim, task, cols, rows, path, names) -> list:
    """The workpiece's largest speed at the quasistatic speed (the module docstring)."""
    if not (isinstance(claim, (int, float)) and not isinstance(claim, bool) and math.isfinite(claim)):
        return [f"{path}.workpiece_speed_m_s states {show(claim)}; expected a speed (m/s)"]
    _, ds, dist = _path(cols, rows)
    moving = ds > 0
    if not moving.any():
        return [] if claim == 0.0 else [f"{path}.workpiece_speed_m_s states {claim:g} m/s; nothing moves in the phase"]
    mean = float(np.max(dist[moving] / ds[moving]))  # the mean speed over each interval at the quasistatic speed
    _, turned = _moves(cols, rows, names)
    if not turned:  # a translation along a line at one quasistatic speed: every interval's mean is the speed
        return [] if close(claim, mean) else [f"{path}.workpiece_speed_m_s states {claim:g} m/s; the rows move the "
                                               f"workpiece at {mean:.10g} m/s at the quasistatic speed"]  # fmt: skip
    limit = float(task.workpiece_speed)
    if claim < mean * (1 - META_TOL) or claim > limit * (1 + META_TOL):
        return [f"{path}.workpiece_speed_m_s states {claim:g} m/s; the rows' largest mean speed over an interval at "
                f"the quasistatic speed is {mean:.10g} m/s and the task's limit {limit:g} m/s"]  # fmt: skip
    return []


def sequence_claims(sequence, phases, task, cols, evidence) -> list:
    """``metadata.sequence`` against the phases' rows (the module docstring)."""
    if not isinstance(sequence, list) or not all(isinstance(s, dict) for s in sequence):
        return [(None, "metadata", "metadata.sequence is not a list of steps")]
    names = task.hand.joint_names
    ph = np.asarray(cols["phase"], float)
    n_phases = int(np.max(ph)) + 1 if np.all(np.isfinite(ph)) else 0
    steps = [(j, s) for j, s in enumerate(sequence) if s.get("kind") not in INFORMATIONAL_STEPS]
    tail = [j for j, s in enumerate(sequence) if s.get("kind") in INFORMATIONAL_STEPS]
    if len(steps) != n_phases or (tail and tail[0] != len(steps)):
        return [(None, "metadata", f"metadata.sequence states {len(steps)} steps (then the search's figures); the rows "
                                   f"have {n_phases} phases")]  # fmt: skip
    out = []
    for i, (j, s) in enumerate(steps):
        rows = _phase_rows(cols, i)
        if not rows.size:
            continue
        path = f"metadata.sequence[{j}]"
        contact = str(cols["mode"][rows[0]]) != "free"
        replaced = {} if contact else _replacement(task, cols, rows)
        kind = _phase_kind(cols, rows, names) if contact else ("replace" if replaced else "regrasp")
        if s.get("kind") != kind:
            out.append((int(rows[0]), "metadata", f"{path}.kind states {show(s.get('kind'))}; phase {i}'s rows are a "
                                                  f"{kind}"))  # fmt: skip
            continue
        x = np.asarray(cols["x_workpiece"], float)[rows]
        th = np.asarray(cols["theta_workpiece"], float)[rows]
        truth = {"kind": kind, "x_from_m": float(x[0]), "x_to_m": float(x[-1])}
        unknown = INFORMATIONAL_STEP_KEYS | {"proved_interval", "vertex"}  # informational, or checked below
        if kind == "regrasp":
            truth["x"] = float(x[0])
        if kind == "replace":
            truth.update(theta_rad=float(th[0]), finger=replaced["finger"], contacts_kept=replaced["contacts_kept"])
            unknown = unknown | {"formation", "hold_margin_N"}  # informational: the next phases and the row checks
        if contact and not _effort_ok(task, cols, rows):  # the input check names the rows
            unknown |= {"effort_joint", "effort_unit", "narrowest_band", "torque_from", "torque_to", "proved_interval"}
        elif contact:
            e = str(cols["effort_joint"][rows[0]])
            truth.update(effort_joint=e, effort_unit=task.hand.joint_unit(e, "tau"))
            _, w = narrowest(cols, rows)
            tau = np.asarray(cols[f"tau_{e}"], float)[rows]
            ends = {"slide": ("x_from", "x_to", x), "hold": ("torque_from", "torque_to", tau),
                    "pivot": ("theta_from_rad", "theta_to_rad", th)}[kind]  # fmt: skip
            truth.update({ends[0]: float(ends[2][0]), ends[1]: float(ends[2][-1])})
            truth.update({"theta_rad": float(th[0])} if kind == "hold" else {"narrowest_band": w})
        if kind == "pivot":
            truth.pop("x_from_m"), truth.pop("x_to_m")
        claim = {k: v for k, v in s.items() if k not in unknown}
        found = difference(claim, truth, path)
        if found:
            out.append((int(rows[0]), "metadata", _message(found)))
        if kind == "hold" and "proved_interval" in s:
            out += [(int(rows[0]), "metadata", m) for m in _interval_claims(s["proved_interval"], cols, rows, path,
                                                                            evidence)]  # fmt: skip
        if kind == "pivot" and "vertex" in s:
            out += [(int(rows[0]), "metadata", m)
                    for m in _vertex_claims(s["vertex"], task, cols, rows, path, evidence)]  # fmt: skip
    return out


def _edges(interval):
    """``(lo, hi)`` of a stated interval (``null``: unbounded), or None when it is not two numbers or nulls."""
    if not (isinstance(interval, list) and len(interval) == 2):
        return None
    ends = []
    for v, inf in zip(interval, (-math.inf, math.inf)):
        if v is None:
            ends.append(inf)
        elif isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v):
            ends.append(float(v))
        else:
            return None
    return tuple(ends)


def _interval_claims(interval, cols, rows, path, evidence) -> list:
    """A hold's proved interval: every hold row's band, within the hold the row checks proved from the task."""
    from qsplan.planner.certify.bands import BAND_RTOL

    ends = _edges(interval)
    where = f"{path}.proved_interval states {show(interval)}"
    if ends is None or ends[0] > ends[1]:
        return [f"{where}; expected [lower, upper] (N m, null: unbounded)"]
    lo, hi = ends
    for k in rows:
        e = str(cols["effort_joint"][k])
        band = (float(cols[f"tau_{e}_min"][k]), float(cols[f"tau_{e}_max"][k]))
        if not (close(lo, band[0]) and close(hi, band[1])):
            return [f"{where}; the hold's rows export the band [{band[0]:.10g}, {band[1]:.10g}] (row {int(k)})"]
        rb = evidence.bands.get(int(k))
        if rb is None:
            continue
        tol = BAND_RTOL * max([abs(v) for v in (lo, hi, rb.lower, rb.upper) if math.isfinite(v)] + [1.0])
        if not rb.feasible or lo < rb.lower - tol or hi > rb.upper + tol:
            proved = f"[{rb.lower:.10g}, {rb.upper:.10g}]" if rb.feasible else "nothing"
            return [f"{where}; the hold recomputed from the task is proved on {proved} (row {int(k)})"]
    return []


def _vertex_claims(vertex, task, cols, rows, path, evidence) -> list:
    """A pivot's vertex: the one workpiece vertex on the palm after the phase's first row (as the task writes it)."""
    sets = _contact_sets(cols, rows, evidence)
    if sets is None:
        return []
    palm = sorted({c for s in sets[1] if s["rows"][1] > 0 for c in s["contacts"] if c.startswith("palm:")})
    internal = [int(c.split(":")[1]) for c in palm if c.split(":")[1].isdigit()]
    written = [int(task.hand.vertex_order[k]) for k in internal if 0 <= k < len(task.hand.vertex_order)]
    if len(palm) != 1 or len(written) != 1 or vertex != written[0] or isinstance(vertex, bool):
        return [f"{path}.vertex states {show(vertex)}; after its first row the pivot rests on the palm with "
                f"{', '.join(palm) or 'nothing'} (vertex {', '.join(map(str, written)) or 'none'} as the task writes "
                "it)"]  # fmt: skip
    return []
