"""Certify an exported plan of any two-finger hand from the task alone (issues 12 and 21).

A plan that exits 0 promises that it is physically possible, and a controller may read either of its files.
:func:`certify_plan` checks every fact the export states (``plan.csv`` and ``plan.json``, written by
:func:`qsplan.planner.export.plan_files.export_plan`) independently of the planner's bookkeeping: every row is
rebuilt from the task (the hand's polygons, the row's joint positions and workpiece pose; the paper's hand or a
described chain hand, asked through :class:`qsplan.hands.protocol.Hand`).  :data:`CHECKS` says what each kind of check covers:

* the files (:mod:`~qsplan.planner.certify.files`): both present files hold the same cells, the JSON
  follows its schema, and its metadata (friction, resolution, force margin, limits, hand, phases, narrowest band)
  states the task and the rows;
* the motion (:mod:`~qsplan.planner.certify.route`): time and phase order, the task's start and goal
  (or waypoints) reached, the workpiece resting on the palm where it was left on every regrasp row, no overlap
  along the free motions between regrasp rows;
* every row (:mod:`~qsplan.planner.certify.rows`): no overlap, the limits of the task (which narrows
  the hand's: :mod:`qsplan.planner.task.limits`), speeds over every step, the velocity commands reaching
  the next row, one command per joint, the planned contacts present;
* every in-contact row's mechanics (:mod:`~qsplan.planner.certify.bands`,
  :mod:`~qsplan.planner.certify.modes`): the exported band recomputed for the whole friction set with
  every competitor precluded, the command inside it at least half a torque resolution from its edges, the margin
  cell true; and with the row's commands the all-modes solver (eqs. 13-28) finding the planned mode and no other
  at every vertex of the friction set and at seeded random points, its normal forces at least the force margin,
  moving the workpiece as the rows do, no sliding direction reversing within a segment.

Units SI (m, rad, s, N, N m).  Rows are numbered from 0 (the first data row); a violation of the plan as a
whole has no row.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from qsplan.mechanics import QsplanError

from qsplan.planner.certify.bands import BAND_RTOL, band_checks, free_row_cells, recomputed_bands
from qsplan.planner.certify.claims import RowEvidence
from qsplan.planner.certify.contacts import hold_row, judged_contact_checks, judged_contacts, row_contact_names
from qsplan.planner.certify.files import META_TOL, agreement_checks, metadata_checks, schema_checks
from qsplan.planner.certify.inputs import (plan_columns_required, plan_sources, read_plan,
                                           read_plan_file, task_from_metadata)  # fmt: skip
from qsplan.planner.certify.modes import (ModeJob, disturbance_checks, mode_checks, mode_misfit, plan_mode_checks,
                                          row_scene, slip_reversals, slip_velocities)  # fmt: skip
from qsplan.planner.certify.timing import hold_checks, row_com_velocity, timing_checks
from qsplan.planner.certify.route import (ENDPOINT_TOL, FREE_PATH_STEP, endpoint_checks, free_path_checks,
                                          rest_checks, structure_checks)  # fmt: skip
from qsplan.planner.certify.rows import (
    CONTACT_GAP_TOL,
    COMMAND_RTOL,
    JUMP_TOL,
    LIMIT_TOL,
    OVERLAP_DEPTH_TOL,
    SPEED_RTOL,
    friction_points,
    joint_housings,
    limit_checks,
    overlap_checks,
    row_bodies,
    step_checks,
)

__all__ = ["Violation", "RowVerdict", "Certificate", "certify_plan", "plan_columns_required", "read_plan",
           "task_from_metadata", "KINDS", "CHECKS"]

#: What each kind of check covers, in the order of the checks (a certificate lists them).
CHECKS = {
    "input": "every cell readable and where the export puts it: one command per joint, no effort on regrasp rows",
    "files": "plan.csv and plan.json hold the same cells; plan.json follows its schema",
    "metadata": "plan.json's metadata states the task's friction, resolution, force margin, limits and hand, and "
                "each phase's rows, times, mode, effort joint, narrowest band, contacts and contact sets, competitors, "
                "commands and time scaling, and each step of the sequence (a hold's proved interval, a pivot's "
                "vertex), as the rows and the row checks find them; the rest is labelled informational",
    "time": "time starts at 0 and grows inside every phase",
    "phase": "phases numbered 0, 1, ... in row order, one mode and effort joint per phase",
    "start": "the first row is the task's start: workpiece x, the fingers' start features or free joints",
    "goal": "the last row is the task's goal (x and features), or each in-contact stretch ends at its waypoint",
    "rest": "on regrasp rows the workpiece rests on the palm where the previous row left it",
    "overlap": "no two bodies (links, palm, workpiece) overlap, at every row and along free motions",
    "joint limit": "every joint inside the task's range (the hand's, narrowed by the task)",
    "speed": "joint and workpiece speeds within the task's limits over every step, and every velocity command",
    "continuity": "no jump where two rows share a time",
    "timing": "every phase starts and ends at rest (speed_scale 0, every velocity command 0); the velocity commands "
              "follow the time scaling's rule between rows",
    "acceleration": "every velocity command changes within its joint's acceleration limit; the workpiece's inertial "
                    "wrench between rows lies in the disturbance box every band was recomputed with",
    "hold": "at every in-contact row at rest nothing moves, the velocity-controlled joints held and the effort joint at "
            "its command, for every friction and disturbance wrench (a frictionless equilibrium with every contact "
            "loaded; the certificate's holds record each proof)",
    "motion": "velocity commands reach the next row; the solver moves the workpiece as the rows do",
    "contact": "every contact of the planned mode present on in-contact rows",
    "band": "the exported band recomputed from the task (every friction in the set, every competitor precluded), "
            "at least the torque resolution wide",
    "margin": "the margin cell is the command's distance to the nearer band edge, at least half the resolution",
    "torque": "the torque command inside its exported band",
    "control": "each control_<joint> cell names the row's command: torque for its effort joint, hold for a "
               "velocity-controlled joint at rest, velocity otherwise",
    "mode": "with the row's commands the planned mode is the only feasible one at the friction set's vertices and "
            "random points; no sliding direction reverses within a segment",
    "undecided": "no mode's feasibility left undecided by near-degeneracy",
    "force margin": "the planned mode's normal forces at least the force margin",
}  # fmt: skip

#: Every kind of violation, in the order of the checks.
KINDS = tuple(CHECKS)

@dataclass(frozen=True, slots=True)
class Violation:
    """One failed check.

    Attributes
    ----------
    row : int or None
        Data row (0-based); a step check names its first row; None: the plan as a whole (its files, metadata).
    t : float
        The row's time (s); NaN without a row.
    kind : str
        One of :data:`KINDS`.
    message : str
        What failed, with the numbers, for a person.
    """

    row: int | None
    t: float
    kind: str
    message: str

    def __str__(self) -> str:
        if self.row is None:
            return f"plan: {self.kind}: {self.message}"
        return f"row {self.row} (t = {self.t:.4g} s): {self.kind}: {self.message}"

    def to_dict(self) -> dict:
        return {"row": self.row, "t_s": _num(self.t), "kind": self.kind, "message": self.message}


@dataclass(frozen=True, slots=True)
class RowVerdict:
    """The checks of one row.

    Attributes
    ----------
    row : int
    t : float
        s.
    mode : str
        Planned mode (``"free"`` on a regrasp row).
    friction_points : int
        Friction vectors the solver was run at (0 on free rows).
    violations : tuple of Violation
    excluded : tuple of str
        Modes set aside as degenerate to machine precision (outside the model, eq. 32).
    """

    row: int
    t: float
    mode: str
    friction_points: int
    violations: tuple
    excluded: tuple = ()

    @property
    def ok(self) -> bool:
        return not self.violations


@dataclass(frozen=True, slots=True)
class Certificate:
    """The verdict on a whole plan.

    Attributes
    ----------
    ok : bool
        Every row passed every check, and so did the plan as a whole.
    source : str
        The file whose rows were checked (``plan.csv`` when present).
    task : str
        The task's name.
    rows : tuple of RowVerdict
    violations : tuple of Violation
        All of them: the plan's as a whole first, then in row order.
    counts : dict[str, int]
        Violations per kind (every kind of :data:`KINDS`, zeros included).
    settings : dict
        Friction set, random points and seed, force margin and the tolerances used.
    seconds : float
        Wall time of the certification.
    files : tuple of str
        Every file checked (the other file's cells compared with ``source``'s).
    holds : tuple of dict
        Each in-contact row at rest: ``{row, t_s, proved, margin_N, proof}`` (:func:`qsplan.planner.certify.timing.
        hold_checks`).
    """

    ok: bool
    source: str
    task: str
    rows: tuple
    violations: tuple
    counts: dict = field(default_factory=dict)
    settings: dict = field(default_factory=dict)
    seconds: float = 0.0
    files: tuple = ()
    holds: tuple = ()

    @property
    def contact_rows(self) -> int:
        return sum(r.mode != "free" for r in self.rows)

    def summary(self) -> str:
        """One line: certified or not, rows, violations by kind."""
        n, c = len(self.rows), self.contact_rows
        pts = max((r.friction_points for r in self.rows), default=0)
        head = f"{n} rows ({c} in contact, {pts} friction points each), {self.seconds:.3g} s"
        if self.ok:
            return f"certified: {head}, no violation"
        bad = sorted({v.row for v in self.violations if v.row is not None})
        kinds = ", ".join(f"{k} {m}" for k, m in self.counts.items() if m)
        return f"NOT certified: {len(self.violations)} violations in {len(bad)} of {head} ({kinds})"

    def to_dict(self) -> dict:
        """JSON-ready (no NaN or inf: ``null``)."""
        excluded = sorted({m for r in self.rows for m in r.excluded})
        checks = [{"kind": k, "what": what, "violations": self.counts.get(k, 0)} for k, what in CHECKS.items()]
        return {"certified": self.ok, "summary": self.summary(), "source": self.source, "files": list(self.files),
                "task": self.task, "rows": len(self.rows), "contact_rows": self.contact_rows, "checks": checks,
                "counts": dict(self.counts), "violations": [v.to_dict() for v in self.violations],
                "excluded_degenerate_modes": excluded, "holds": list(self.holds), "settings": self.settings,
                "seconds": self.seconds}  # fmt: skip


def _num(v):
    return float(v) if v is not None and math.isfinite(v) else None


def _v_rows(cols, k, names) -> np.ndarray:
    """The workpiece's centre-of-mass velocity ``(vx, vy)`` (m/s) the rows give at in-contact row ``k``
    (:func:`qsplan.planner.certify.timing.row_com_velocity`); nan for a phase of one row, or at rest."""
    if "phase" not in cols or ("speed_scale" in cols and cols["speed_scale"][k] == 0.0):
        return np.full(2, math.nan)  # no phase; or at rest: no speed to compare (its direction is the band's and modes')
    moving = row_com_velocity(cols, k, names)
    return np.full(2, math.nan) if moving is None else moving


def certify_plan(plan, task, *, n_random: int = 8, seed: int = 0, force_margin: float = 0.0,
                 progress=None, batched: bool = True) -> Certificate:  # fmt: skip
    """Check an exported plan row by row against ``task`` (see the module docstring for the checks).

    Parameters
    ----------
    plan : str or Path
        A plan directory, or one of its files: every plan file there (``plan.csv``, ``plan.json``) is checked, the
        rows of the CSV when present, the other file cell by cell against them.
    task : Task
        The task the plan claims to achieve (:func:`qsplan.planner.task.task.load_task`).
    n_random : int
        Seeded random friction vectors tested per in-contact row, besides the friction set's vertices.
    seed : int
        Seed of the random friction vectors (one numpy Generator for the whole plan).
    force_margin : float
        N, nonnegative: the planned mode's normal forces must be at least this.
    progress : callable, optional
        Called with a line of text now and then.
    batched : bool
        Solve every in-contact row x wrench vertex x friction vector of the plan in one batch
        (:func:`qsplan.planner.certify.modes.plan_mode_checks`); False: the reference, row by row, wrench by wrench,
        :func:`qsplan.mechanics.solve` once per friction vector.  Same certificate.

    Returns
    -------
    Certificate

    Raises
    ------
    QsplanError
        Unreadable plan, or a bad parameter (named).
    """
    if isinstance(n_random, bool) or not isinstance(n_random, (int, np.integer)) or n_random < 0:
        raise QsplanError(f"n_random: expected a nonnegative integer; got {n_random!r}")
    if not (isinstance(force_margin, (int, float)) and math.isfinite(force_margin) and force_margin >= 0):
        raise QsplanError(f"force_margin: expected a nonnegative finite number (N); got {force_margin!r}")
    start = time.perf_counter()
    names = task.hand.joint_names
    sources = plan_sources(plan)
    read = [read_plan_file(p) for p in sources]
    for p, (cols_p, _) in zip(sources, read):
        missing = [c for c in plan_columns_required(names) if c not in cols_p]
        if missing:
            raise QsplanError(f"plan: {str(p)!r} lacks the column(s) {', '.join(missing)} of the task's hand")
        if cols_p["t"].size == 0:
            raise QsplanError(f"plan: {str(p)!r} has no rows")
    source, cols = sources[0], read[0][0]
    whole = []  # (row or None, kind, message) of the plan as a whole
    if len(sources) == 2:
        whole += agreement_checks(sources[0].name, cols, sources[1].name, read[1][0])
    doc = next((d for _, d in read if d is not None), None)
    if doc is not None:
        whole += schema_checks(doc)
        meta_at = len(whole)  # the metadata's claims, checked once the rows have been (they use what those found)
    whole += structure_checks(cols)
    if "phase" in cols:
        whole += timing_checks(task, cols)
    rng = np.random.default_rng(seed)
    n = cols["t"].size
    roots = joint_housings(task.hand)
    phase = cols.get("phase", np.full(n, np.nan))  # without phases (nan != nan) no two rows are compared
    found_at = [[] for _ in range(n)]
    verdict_info, slip, ends = [], None, {}  # slip: (row, phase, sliding velocities) of the last in-contact row
    scenes = {}  # in-contact rows' scenes: their bands recomputed in one batch per mode
    named = {}  # in-contact rows' contacts, as their mode letters follow them (the metadata's contact sets)
    jobs, mode_at = [], {}  # batched: the rows' mode checks, solved together after the loop; where their answers go
    lifted = {}  # the holds proved with a finger lifted (a finger replaced mid-turn), one per run of free rows
    for k in range(n):
        mode = str(cols["mode"][k])
        found = limit_checks(task, cols, k)
        bodies = None
        if not any(kind == "input" for kind, _ in found):
            bodies = row_bodies(task, cols, k, roots)
            found += overlap_checks(task, cols, k, bodies)
            if k in (0, n - 1):
                ends[k] = bodies
        if k + 1 < n:
            found += step_checks(task, cols, k)
        pts, excluded = 0, ()
        if mode == "free":
            found += free_row_cells(cols, k, names)
            if bodies is not None:
                found += rest_checks(task, cols, k, bodies, lifted)
                if k + 1 < n and str(cols["mode"][k + 1]) == "free" and phase[k + 1] == phase[k]:
                    found += free_path_checks(task, cols, k, roots)
        elif not any(kind == "input" for kind, _ in found):
            judged = None  # any formation: the contacts the polygons show, in the canonical order
            try:
                judged = judged_contacts(task, cols, k)
            except QsplanError as exc:
                contact = [("contact", f"the row's contacts cannot be found: {exc}")]
            else:
                contact = judged_contact_checks(task, cols, k, judged)
            found += contact
            if not contact:
                named[k] = row_contact_names(task, cols, k, judged)
                try:
                    scene = row_scene(task, cols, k, judged)
                except QsplanError as exc:
                    found.append(("contact", f"the row's scene cannot be built: {exc}"))
                    scene = None
                misfit = None if scene is None or hold_row(cols, k) else mode_misfit(scene, mode)
                if misfit:  # not a mode of this row's scene: nothing judges it or its band
                    found.append(("mode", misfit))
                elif scene is not None:
                    scenes[k] = scene
                    mus = friction_points(task, int(n_random), rng, len(scene.contact_names))
                    pts = len(mus)
                    if not hold_row(cols, k) and batched:  # a hold: nothing moves, the hold proof decides
                        jobs.append(ModeJob(k, scene, mus, _v_rows(cols, k, names)))
                        mode_at[k] = len(found)
                    elif not hold_row(cols, k):  # the reference, row by row
                        more, excluded = mode_checks(task, cols, k, mus, force_margin, _v_rows(cols, k, names),
                                                     False, scene)  # fmt: skip
                        found += more
                        if task.disturbance is not None:
                            found += disturbance_checks(task, cols, k, mus, force_margin, False, scene)
                    slips = slip_velocities(task, cols, k, scene)
                    if (slips is not None and slip is not None and slip[:2] == (k - 1, phase[k])
                            and len(slip[2]) == len(slips)):  # fmt: skip
                        found += slip_reversals(mode, scene.contact_names, slip[2], slips)
                    slip = None if slips is None else (k, phase[k], slips)
        found_at[k] += found
        verdict_info.append((mode, pts, excluded))
        if progress is not None and (k + 1) % 50 == 0:
            progress(f"certified {k + 1} of {n} rows")
    for k, (more, excluded) in plan_mode_checks(task, cols, jobs, force_margin).items():
        found_at[k][mode_at[k]:mode_at[k]] = more
        verdict_info[k] = (verdict_info[k][0], verdict_info[k][1], excluded)
    bands = recomputed_bands(task, cols, scenes)
    for k, rb in bands.items():
        found_at[k] += band_checks(task, cols, k, rb)
    held, holds = hold_checks(task, cols, scenes)
    for k, kind, msg in held:
        found_at[k].append((kind, msg))
    if doc is not None:
        whole[meta_at:meta_at] = metadata_checks(doc.get("metadata"), task, cols, RowEvidence(named, bands))
    if 0 in ends and n - 1 in ends:
        whole += endpoint_checks(task, cols, ends[0], ends[n - 1])
    plan_level = []
    for row, kind, msg in whole:
        if row is None:
            plan_level.append(Violation(None, math.nan, kind, msg))
        else:
            found_at[row].append((kind, msg))
    verdicts, every = [], list(plan_level)
    for k, (mode, pts, excluded) in enumerate(verdict_info):
        t = float(cols["t"][k])
        vs = tuple(Violation(k, t, kind, msg) for kind, msg in found_at[k])
        every += vs
        verdicts.append(RowVerdict(k, t, mode, pts, vs, excluded))
    counts = dict.fromkeys(KINDS, 0)
    for v in every:
        counts[v.kind] = counts.get(v.kind, 0) + 1
    settings = {"friction": {"range": list(task.mu_range), "shared": task.shared_mu}, "n_random": int(n_random),
                "seed": seed, "force_margin_N": float(force_margin), "torque_resolution": task.torque_resolution,
                "tolerances": {"overlap_depth_m": OVERLAP_DEPTH_TOL, "contact_gap_m": CONTACT_GAP_TOL,
                               "joint_limit_rad": LIMIT_TOL, "speed_rel": SPEED_RTOL, "jump": JUMP_TOL,
                               "command_rel": COMMAND_RTOL, "band_rel": BAND_RTOL, "metadata_rel": META_TOL,
                               "endpoint_m": ENDPOINT_TOL, "free_path_step_m": FREE_PATH_STEP}}  # fmt: skip
    return Certificate(not every, str(source), task.name, tuple(verdicts), tuple(every), counts, settings,
                       time.perf_counter() - start, tuple(str(p) for p in sources), tuple(holds))  # fmt: skip
