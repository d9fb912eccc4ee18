"""Certify an exported two-finger plan from the task alone (issue 12, "a plan certifier").

A plan that exits 0 promises that it is physically possible.  :func:`certify_plan`
checks the promise on the exported file (``plan.csv`` or ``plan.json``, written by
:func:`qsplan.planner.export.plan_files.export_plan`), independently of the
planner's bookkeeping: every row is rebuilt from the task (the hand's polygons,
the row's joint angles and workpiece pose) and checked
(:mod:`qsplan.planner.planning.certify_rows`):

1. ``overlap``: no two of left finger, right finger, palm and workpiece overlap
   deeper than the contact tolerance (the fingers' roots turn inside the palm);
2. ``joint limit``, ``speed``, ``continuity``, ``time``: the task's joint limits, its
   joint and workpiece speed limits over every step between rows, and no jump where
   two rows share a time; the exported velocity commands within the speed limit;
3. ``contact``: on in-contact rows, every contact of the planned mode is present;
4. ``mode``, ``undecided``, ``torque``, ``force margin``, ``motion``: with the row's commands
   (the velocity-controlled finger's ``qd``, the torque-controlled finger's ``tau``)
   the all-modes solver (:func:`qsplan.mechanics.solve`, eqs. 13-28) finds the planned
   mode and no other feasible at every vertex of the friction set and at seeded random
   points in it (the kinematics once per row, the friction vectors in one batch:
   :mod:`qsplan.planner.planning.certify_modes`); no mode's feasibility is left undecided (a mode degenerate only to
   machine precision is outside the model and is counted, not failed); the torque
   lies inside its exported band; the planned mode's normal forces are at least
   ``force_margin``; it moves the workpiece as the rows do.

Units SI (m, rad, s, N, N m).  Rows are numbered from 0 (the first data row).
"""

from __future__ import annotations

import json
import math
import time
from dataclasses import dataclass, field
from pathlib import Path

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
from qsplan.planner.planning.certify_modes import mode_checks

__all__ = ["Violation", "RowVerdict", "Certificate", "certify_plan", "read_plan", "task_from_metadata", "KINDS"]

#: Every kind of violation, in the order of the checks.
KINDS = ("input", "overlap", "joint limit", "speed", "continuity", "time", "contact", "torque", "mode", "undecided",
         "force margin", "motion")  # fmt: skip

_COLUMNS = ("t", "q_left", "q_right", "qd_left", "qd_right", "tau_left", "tau_left_min", "tau_left_max", "tau_right",
            "tau_right_min", "tau_right_max", "mode", "x_workpiece", "y_workpiece", "theta_workpiece", "effort_joint")  # fmt: skip


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


def _plan_file(path) -> Path:
    p = Path(path)
    if p.is_dir():
        for name in ("plan.csv", "plan.json"):
            if (p / name).is_file():
                return p / name
        raise QsplanError(f"plan: {str(p)!r} holds neither plan.csv nor plan.json")
    if not p.is_file():
        raise QsplanError(f"plan: no such file or directory: {str(p)!r}")
    if p.suffix not in (".csv", ".json"):
        raise QsplanError(f"plan: expected a plan directory, a .csv or a .json file; got {str(p)!r}")
    return p


def _read_json(p: Path) -> tuple:
    try:
        doc = json.loads(p.read_text(encoding="utf-8"))
        data = doc["data"]
        n = len(data["t"])
    except (OSError, UnicodeDecodeError, ValueError, KeyError, TypeError, RecursionError) as exc:
        raise QsplanError(f"plan: {str(p)!r} is not a plan JSON file ({type(exc).__name__}: {exc})") from None
    cols = {}
    for name, vals in data.items():
        if name in ("mode", "effort_joint"):
            cols[name] = np.array([str(v) for v in vals])
            continue
        fill = -math.inf if name.endswith("_min") else (math.inf if name.endswith("_max") else math.nan)
        try:
            cols[name] = np.array([fill if v is None else float(v) for v in vals], dtype=float)
        except (TypeError, ValueError):
            raise QsplanError(f"plan: column {name!r} of {str(p)!r} holds a value that is not a number") from None
        if cols[name].size != n:
            raise QsplanError(f"plan: column {name!r} has {cols[name].size} rows; expected {n}")
    return cols, doc.get("metadata") if isinstance(doc, dict) else None


def read_plan(path) -> tuple:
    """Columns ``{name: ndarray}`` and the metadata (dict or None) of a plan directory, ``.csv`` or ``.json``.

    A directory is read from its ``plan.csv`` (else ``plan.json``); the metadata comes from
    ``plan.json`` beside it when there is one.

    Raises
    ------
    QsplanError
        Missing or unreadable file, a missing column, columns of different lengths.
    """
    p = _plan_file(path)
    if p.suffix == ".json":
        cols, meta = _read_json(p)
    else:
        from qsplan.planner.export.plan_files import read_plan_csv

        try:
            cols = read_plan_csv(p)
        except (OSError, UnicodeDecodeError, ValueError, IndexError) as exc:
            raise QsplanError(f"plan: {str(p)!r} is not a plan CSV file ({type(exc).__name__}: {exc})") from None
        side = p.with_suffix(".json")
        meta = _read_json(side)[1] if side.is_file() else None
    missing = [c for c in _COLUMNS if c not in cols]
    if missing:
        raise QsplanError(f"plan: {str(p)!r} lacks the column(s) {', '.join(missing)}")
    if cols["t"].size == 0:
        raise QsplanError(f"plan: {str(p)!r} has no rows")
    return cols, meta


def task_from_metadata(meta, cols=None):
    """The :class:`~qsplan.planner.planning.task.Task` a plan's ``plan.json`` metadata records.

    The metadata records the hand (but not its palm thickness: the default is used), the
    friction set, the limits and the torque resolution; the start and the waypoints are
    read from the rows (``cols``) when given.

    Raises
    ------
    QsplanError
        Naming ``task`` when the metadata does not record the task.
    """
    from qsplan.planner.planning.task import make_task

    try:
        h, lim = meta["hand"], meta["limits"]
        hand = {"workpiece": h["workpiece_vertices_m"], "workpiece_mass": h["workpiece_mass_kg"],
                "finger_base": h["finger_base_m"], "finger_length": h["finger_length_m"],
                "finger_width": h["finger_width_m"], "finger_mass": h["finger_mass_kg"],
                "palm_halfwidth": h["palm_halfwidth_m"], "gravity": h["gravity_m_s2"]}  # fmt: skip
        friction = meta["friction"]
        shared = "shared" in friction["model"]
        start, waypoints = 0.0, [1.0]
        if cols is not None:
            x, contact = cols["x_workpiece"], cols["mode"] != "free"
            ends = [i for i in range(x.size) if contact[i] and (i + 1 == x.size or not contact[i + 1])]
            start, waypoints = float(x[0]), [float(x[i]) for i in ends]
        fm = meta.get("force_margin")  # recorded since force margins exist; older plans: the default
        margin = None if fm is None else (fm["min_normal_force_N"], fm["min_coulomb_slack_N"])
        return make_task(hand, start, waypoints, friction["range"], meta["torque_resolution_N_m"], shared,
                         lim["joints_rad"], lim["joint_speed_rad_s"], lim["workpiece_speed_m_s"],
                         name=meta.get("task", "task"), force_margin=margin)  # fmt: skip
    except (KeyError, TypeError) as exc:
        raise QsplanError(f"task: the plan's metadata does not record the task ({exc}); name the task file") from None


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
    source = _plan_file(plan)
    cols, _ = read_plan(source)
    rng = np.random.default_rng(seed)
    n = cols["t"].size
    roots = joint_housings(task.hand)
    verdicts, every = [], []
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
                more, excluded = mode_checks(task, cols, k, mus, force_margin, _xdot_rows(cols, k), batched)
                found += more
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
