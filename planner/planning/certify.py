"""Certify an exported plan of any two-finger hand from the task alone (issue 12, "a plan certifier").

A plan that exits 0 promises that it is physically possible.  :func:`certify_plan`
checks the promise on the exported file (``plan.csv`` or ``plan.json``, written by
:func:`qsplan.planner.export.plan_files.export_plan`), independently of the
planner's bookkeeping: every row is rebuilt from the task (the hand's polygons,
the row's joint positions and workpiece pose; the paper's hand or a described chain
hand, :mod:`qsplan.hands.interface`) and checked (:mod:`qsplan.planner.planning.certify_rows`):

1. ``overlap``: no two of the links, the palm and the workpiece overlap deeper than
   the contact tolerance (a revolute joint's link turns inside its carrier at its root);
2. ``joint limit``, ``speed``, ``continuity``, ``time``: the task's joint limits, its
   joint and workpiece speed limits over every step between rows, and no jump where
   two rows share a time; the exported velocity commands within the speed limit;
3. ``contact``: on in-contact rows, every contact of the planned mode is present;
4. ``mode``, ``undecided``, ``torque``, ``force margin``, ``motion``: with the row's commands
   (the velocity-controlled joints' ``qd``, the torque-controlled joint's ``tau``)
   the all-modes solver (:func:`qsplan.mechanics.solve`, eqs. 13-28) finds the planned
   mode and no other feasible at every vertex of the friction set and at seeded random
   points in it (the kinematics once per row, the friction vectors in one batch:
   :mod:`qsplan.planner.planning.certify_modes`); no mode's feasibility is left undecided (a mode degenerate only to
   machine precision is outside the model and is counted, not failed); the torque
   lies inside its exported band; the planned mode's normal forces are at least
   ``force_margin``; it moves the workpiece as the rows do; no sliding contact's direction
   reverses between two rows of a segment (it would stop sliding in between: a mode change,
   eq. 16, that the rows' letters do not show).

Units SI (m, rad, s, N, N m).  Rows are numbered from 0 (the first data row).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from qsplan.mechanics import QsplanError

from qsplan.planner.planning.certify_rows import (
    CONTACT_GAP_TOL,
    JUMP_TOL,
    LIMIT_TOL,
    OVERLAP_DEPTH_TOL,
    SPEED_RTOL,
    contact_checks,
    friction_points,
    joint_housings,
    limit_checks,
    overlap_checks,
    row_bodies,
    step_checks,
)
from qsplan.planner.planning.certify_inputs import plan_columns_required, plan_file, read_plan, task_from_metadata
from qsplan.planner.planning.certify_modes import mode_checks, row_scene, slip_reversals, slip_velocities

__all__ = ["Violation", "RowVerdict", "Certificate", "certify_plan", "plan_columns_required", "read_plan",
           "task_from_metadata", "KINDS"]

#: Every kind of violation, in the order of the checks.
KINDS = ("input", "overlap", "joint limit", "speed", "continuity", "time", "contact", "torque", "mode", "undecided",
         "force margin", "motion")  # fmt: skip


@dataclass(frozen=True, slots=True)
class Violation:
    """One failed check.

    Attributes
    ----------
    row : int
        Data row (0-based); a step check names its first row.
    t : float
        The row's time (s).
    kind : str
        One of :data:`KINDS`.
    message : str
        What failed, with the numbers, for a person.
    """

    row: int
    t: float
    kind: str
    message: str

    def __str__(self) -> str:
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
        Every row passed every check.
    source : str
        The file certified.
    task : str
        The task's name.
    rows : tuple of RowVerdict
    violations : tuple of Violation
        All of them, in row order.
    counts : dict[str, int]
        Violations per kind (every kind of :data:`KINDS`, zeros included).
    settings : dict
        Friction set, random points and seed, force margin and the tolerances used.
    seconds : float
        Wall time of the certification.
    """

    ok: bool
    source: str
    task: str
    rows: tuple
    violations: tuple
    counts: dict = field(default_factory=dict)
    settings: dict = field(default_factory=dict)
    seconds: float = 0.0

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
        bad = sorted({v.row for v in self.violations})
        kinds = ", ".join(f"{k} {m}" for k, m in self.counts.items() if m)
        return f"NOT certified: {len(self.violations)} violations in {len(bad)} of {head} ({kinds})"

    def to_dict(self) -> dict:
        """JSON-ready (no NaN or inf: ``null``)."""
        excluded = sorted({m for r in self.rows for m in r.excluded})
        return {"certified": self.ok, "summary": self.summary(), "source": self.source, "task": self.task,
                "rows": len(self.rows), "contact_rows": self.contact_rows, "counts": dict(self.counts),
                "violations": [v.to_dict() for v in self.violations], "excluded_degenerate_modes": excluded,
                "settings": self.settings, "seconds": self.seconds}  # fmt: skip


def _num(v):
    return float(v) if v is not None and math.isfinite(v) else None


def _xdot_rows(cols, k) -> float:
    """The workpiece's x velocity (m/s) at in-contact row ``k`` by a finite difference inside its phase."""
    t, x, ph = cols["t"], cols["x_workpiece"], cols.get("phase")
    same = (lambda i: ph[i] == ph[k]) if ph is not None else (lambda i: cols["mode"][i] != "free")
    for a, b in ((k, k + 1), (k - 1, k)):
        if 0 <= a and b < t.size and same(a) and same(b) and t[b] > t[a]:
            return float((x[b] - x[a]) / (t[b] - t[a]))
    return math.nan


def certify_plan(plan, task, *, n_random: int = 8, seed: int = 0, force_margin: float = 0.0,
                 progress=None, batched: bool = True) -> Certificate:  # fmt: skip
    """Check an exported plan row by row against ``task`` (see the module docstring for the checks).

    Parameters
    ----------
    plan : str or Path
        A plan directory (``plan.csv``, else ``plan.json``), or one of the two files.
    task : Task
        The task the plan claims to achieve (:func:`qsplan.planner.planning.task.load_task`).
    n_random : int
        Seeded random friction vectors tested per in-contact row, besides the friction set's vertices.
    seed : int
        Seed of the random friction vectors (one numpy Generator for the whole plan).
    force_margin : float
        N, nonnegative: the planned mode's normal forces must be at least this.
    progress : callable, optional
        Called with a line of text now and then.
    batched : bool
        Solve all friction vectors of a row in one batch (the kinematic stage once); False:
        the reference, :func:`qsplan.mechanics.solve` once per friction vector.  Same certificate.

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
    from qsplan.hands.interface import joint_names

    source = plan_file(plan)
    cols, _ = read_plan(source, joint_names(task.hand))
    rng = np.random.default_rng(seed)
    n = cols["t"].size
    roots = joint_housings(task.hand)
    phase = cols.get("phase", np.full(n, np.nan))  # without phases (nan != nan) no two rows are compared
    verdicts, every, slip = [], [], None  # slip: (row, phase, sliding velocities) of the last in-contact row
    for k in range(n):
        t, mode = float(cols["t"][k]), str(cols["mode"][k])
        found = limit_checks(task, cols, k)
        bodies = None
        if not any(kind == "input" for kind, _ in found):
            bodies = row_bodies(task, cols, k, roots)
            found += overlap_checks(task, cols, k, bodies)
        if k + 1 < n:
            found += step_checks(task, cols, k)
        pts, excluded = 0, ()
        if mode != "free" and not any(kind == "input" for kind, _ in found):
            contact = contact_checks(task, cols, k, bodies)
            found += contact
            if not contact:
                mus = friction_points(task, int(n_random), rng)
                try:
                    scene = row_scene(task, cols, k)
                except QsplanError as exc:
                    found.append(("contact", f"the row's scene cannot be built: {exc}"))
                else:
                    more, excluded = mode_checks(task, cols, k, mus, force_margin, _xdot_rows(cols, k), batched, scene)
                    found += more
                    slips = slip_velocities(task, cols, k, scene)
                    if slips is not None and slip is not None and slip[:2] == (k - 1, phase[k]):
                        found += slip_reversals(mode, scene.contact_names, slip[2], slips)
                    slip = None if slips is None else (k, phase[k], slips)
                pts = len(mus)
        vs = tuple(Violation(k, t, kind, msg) for kind, msg in found)
        every += vs
        verdicts.append(RowVerdict(k, t, mode, pts, vs, excluded))
        if progress is not None and (k + 1) % 50 == 0:
            progress(f"certified {k + 1} of {n} rows, {len(every)} violations so far")
    counts = dict.fromkeys(KINDS, 0)
    for v in every:
        counts[v.kind] = counts.get(v.kind, 0) + 1
    settings = {"friction": {"range": list(task.mu_range), "shared": task.shared_mu}, "n_random": int(n_random),
                "seed": seed, "force_margin_N": float(force_margin),
                "tolerances": {"overlap_depth_m": OVERLAP_DEPTH_TOL, "contact_gap_m": CONTACT_GAP_TOL,
                               "joint_limit_rad": LIMIT_TOL, "speed_rel": SPEED_RTOL, "jump": JUMP_TOL}}  # fmt: skip
    return Certificate(not every, str(source), task.name, tuple(verdicts), tuple(every), counts, settings,
                       time.perf_counter() - start)  # fmt: skip
