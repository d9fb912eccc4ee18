"""The bridge to OMPL (PyPI ``ompl`` 2.x, nanobind bindings): plan over a box of real variables.

Everything OMPL-specific lives here, behind plain numpy in and out:
:func:`plan_path` takes the bounds, start, goal, a state validity predicate on
numpy vectors and optional per-state costs, and returns a :class:`PlanResult`
with the path as an array.  It follows the verified recipes of
``shared/notes/ompl2_python_cookbook.md``:

* the RNG is seeded before any space or planner is created, and planners are
  stopped by an iteration budget when ``deterministic`` is asked for (a time
  budget makes anytime planners differ from run to run), except the PRM family
  (:data:`TIMED_PLANNERS`): PRM checks for solutions in a second thread that
  would wait forever for Python's global lock to evaluate a Python termination
  condition or objective, so it is stopped by OMPL's own timer (C++, no Python)
  and takes no ``state_cost``;
* OMPL's console output is silenced unless ``verbose``;
* the validity checker returns a real Python ``bool``;
* paths are copied to numpy at once and no OMPL object outlives the call
  (nanobind keeps some of them alive through cycles otherwise);
* ``ss.solve`` gets a termination condition object, not a float (a float >= 1
  starts a watchdog thread per call).

A motion (edge) is valid when every state along it at the stated resolution is
valid: OMPL's discrete motion validator with ``validity_resolution`` as the
fraction of the space's extent between checks.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Callable

from qsplan.mechanics.errors import QsplanError

if TYPE_CHECKING:  # numpy loads in plan_path, so that the CLI's parser (PLANNERS) stays light
    import numpy as np

__all__ = ["PlannerOptions", "PlanResult", "plan_path", "PLANNERS", "TIMED_PLANNERS", "ompl_available"]

#: Geometric planners offered (all bound in ompl 2.0.1).
PLANNERS = ("RRTConnect", "RRT", "RRTstar", "BITstar", "PRM", "KPIECE1")

#: Planners that search in a second thread (the PRM family): stopped by OMPL's timer, never by a Python
#: callable, and never given a Python objective (either hangs the process: the thread waits for the GIL
#: that ``solve`` holds).  Not deterministic: the thread's timing changes the roadmap.
TIMED_PLANNERS = ("PRM",)


def ompl_available() -> bool:
    """Whether the OMPL Python bindings import."""
    try:
        import ompl  # noqa: F401
    except ImportError:
        return False
    return True


@dataclass(frozen=True, slots=True)
class PlannerOptions:
    """Options of :func:`plan_path`.

    Attributes
    ----------
    planner : str
        One of :data:`PLANNERS`.
    time_limit : float
        Seconds for the whole query, solve and simplification; the planner stops when it runs
        out (with ``deterministic`` it stops at the iteration budget or the time limit, whichever
        comes first).
    iterations : int
        Iteration budget (calls of the termination check) when ``deterministic``.
    deterministic : bool
        Seeded and stopped by iterations, so that the same inputs give the same path (not for
        :data:`TIMED_PLANNERS`, always stopped by the time limit alone).
    seed : int
        OMPL's global RNG seed.
    validity_resolution : float
        Fraction of the space's maximum extent between validity checks along a motion.
    simplify : bool
        Shortcut and smooth the path (OMPL's simplifier, to completion within what is left of
        ``time_limit``: deterministic unless it runs out).  Skipped when a ``state_cost`` is
        given: the shortcuts minimise length and would undo the cost.
    interpolate : int
        Number of states of the returned path (0: as planned); states are added
        along the path, each checked again.
    verbose : bool
        Let OMPL print its log (warnings and above).
    """

    planner: str = "RRTConnect"
    time_limit: float = 5.0
    iterations: int = 20_000
    deterministic: bool = True
    seed: int = 1
    validity_resolution: float = 0.005
    simplify: bool = True
    interpolate: int = 0
    verbose: bool = False

    def __post_init__(self):
        if self.planner not in PLANNERS:
            raise QsplanError(f"planner: expected one of {', '.join(PLANNERS)}; got {self.planner!r}")
        if not (self.time_limit > 0):
            raise QsplanError(f"time_limit: expected a positive number of seconds; got {self.time_limit}")
        if self.iterations < 1:
            raise QsplanError(f"iterations: expected a positive integer; got {self.iterations}")
        if not (0 < self.validity_resolution < 1):
            raise QsplanError(f"validity_resolution: expected a fraction in (0, 1); got {self.validity_resolution}")


@dataclass(frozen=True, slots=True, eq=False)
class PlanResult:
    """Outcome of :func:`plan_path`.

    Attributes
    ----------
    path : ndarray, shape (N, d) or (0, d)
        The states, start first; empty when nothing was found.
    exact : bool
        The path reaches the goal (OMPL's EXACT_SOLUTION).
    status : str
        OMPL's status text (``"dense sweep: ..."`` for an in-contact segment, naming the first invalid state).
    validity_checks : int
        Calls of the validity predicate (for an in-contact segment's dense sweep, which makes this record
        without OMPL: the samples judged).
    seconds : float
        Wall-clock planning time (the dense sweep's time).
    """

    path: np.ndarray
    exact: bool
    status: str
    validity_checks: int
    seconds: float
    options: PlannerOptions = field(default_factory=PlannerOptions)

    @property
    def checks_per_second(self) -> float:
        return self.validity_checks / self.seconds if self.seconds > 0 else float("nan")


#: BIT*'s samples per batch. It looks at the clock only between batches, and each sample costs
#: Python validity checks, so OMPL's default (100) let a 0.5 s limit run to ~1.4 s here; 20
#: keeps it near the limit with no measurable loss of path quality on one-variable segments.
BITSTAR_SAMPLES_PER_BATCH = 20


def _planner(og, si, name):
    planner = getattr(og, name)(si)
    if name == "BITstar":
        planner.setSamplesPerBatch(BITSTAR_SAMPLES_PER_BATCH)
    return planner


def plan_path(
    low,
    high,
    start,
    goal,
    is_valid: Callable[[np.ndarray], bool],
    options: PlannerOptions = PlannerOptions(),
    state_cost: Callable[[np.ndarray], float] | None = None,
) -> PlanResult:
    """Plan a path from ``start`` to ``goal`` in the box ``[low, high]`` of R^d.

    Parameters
    ----------
    low, high : array-like, shape (d,)
        Bounds of the configuration variables (SI units of each variable).
    start, goal : array-like, shape (d,)
    is_valid : callable
        ``is_valid(x) -> bool`` for a state ``x`` of shape (d,).
    options : PlannerOptions
    state_cost : callable, optional
        ``state_cost(x) -> float >= 0``: an optimization objective integrating this cost
        along the path (trapezoid rule) is set, so optimizing planners prefer
        low-cost states (e.g. ``1 / margin`` to prefer wide effort bands).  Use an
        optimizing planner (``BITstar`` is fastest here, ``RRTstar``); Python cost calls
        make ``RRTstar`` slow.

    Returns
    -------
    PlanResult

    Raises
    ------
    QsplanError
        On malformed bounds or a start/goal outside them or invalid, or a ``state_cost`` with a planner
        of :data:`TIMED_PLANNERS`.
    """
    import numpy as np

    try:
        from ompl import base as ob
        from ompl import geometric as og
        from ompl import util as ou
    except ImportError as exc:  # pragma: no cover - ompl is a dependency
        raise QsplanError(f"ompl: the OMPL Python bindings are not installed ({exc})") from None

    timed = options.planner in TIMED_PLANNERS
    if timed and state_cost is not None:
        raise QsplanError(f"state_cost: {options.planner} cannot take a Python objective (its second thread would "
                          f"wait forever for Python's global lock); use RRTstar or BITstar")  # fmt: skip
    low, high = np.asarray(low, float), np.asarray(high, float)
    start, goal = np.asarray(start, float), np.asarray(goal, float)
    d = low.size
    if high.shape != (d,) or start.shape != (d,) or goal.shape != (d,) or not np.all(high > low):
        raise QsplanError(f"bounds: expected low < high, and start and goal of {d} values")
    for name, x in (("start", start), ("goal", goal)):
        if np.any(x < low) or np.any(x > high):
            raise QsplanError(f"{name}: outside the planning bounds: {x.tolist()}")
        if not is_valid(x):
            raise QsplanError(f"{name}: the state is not valid: {x.tolist()}")

    ou.setLogLevel(ou.LOG_WARN if options.verbose else ou.LOG_NONE)
    ou.RNG.setSeed(int(options.seed))
    calls = [0]

    def to_np(s):
        return np.array([s[i] for i in range(d)])

    def checker(s):
        calls[0] += 1
        return bool(is_valid(to_np(s)))

    space = ob.RealVectorStateSpace(d)
    bounds = ob.RealVectorBounds(d)
    for i in range(d):
        bounds.setLow(i, float(low[i]))
        bounds.setHigh(i, float(high[i]))
    space.setBounds(bounds)
    ss = og.SimpleSetup(space)
    si = ss.getSpaceInformation()
    ss.setStateValidityChecker(checker)
    si.setStateValidityCheckingResolution(options.validity_resolution)
    s0, s1 = si.allocState(), si.allocState()
    for i in range(d):
        s0[i] = float(start[i])
        s1[i] = float(goal[i])
    ss.setStartAndGoalStates(s0, s1)
    if state_cost is not None:

        class _Cost(ob.OptimizationObjective):
            def __init__(self, info):
                super().__init__(info)
                self.info = info

            def stateCost(self, s):
                return ob.Cost(float(state_cost(to_np(s))))

            def motionCost(self, a, b):
                c = 0.5 * (self.stateCost(a).value() + self.stateCost(b).value())
                return ob.Cost(c * self.info.distance(a, b))

        ss.setOptimizationObjective(_Cost(si))
    ss.setPlanner(_planner(og, si, options.planner))

    t0 = time.perf_counter()
    if options.deterministic and not timed:
        count = [0]
        deadline = t0 + options.time_limit

        def done():
            count[0] += 1
            return count[0] > options.iterations or time.perf_counter() > deadline

        ptc = ob.PlannerTerminationCondition(done)
    else:
        ptc = ob.timedPlannerTerminationCondition(options.time_limit)
    status = ss.solve(ptc)
    exact = status.getStatus() == ob.PlannerStatus.EXACT_SOLUTION
    path = np.zeros((0, d))
    straight = False
    if exact:
        left = options.time_limit - (time.perf_counter() - t0)
        if options.simplify and state_cost is None and left > 0:
            # the straight line is what the simplifier ends with whenever it is valid (always in one
            # dimension), and costs one motion check; else the simplifier, with what is left of the time
            # limit by OMPL's timer (the same as simplifyMax when that suffices; its final B-spline
            # smoothing does not look at the timer)
            straight = si.checkMotion(s0, s1)
            if not straight:
                ss.simplifySolution(ob.timedPlannerTerminationCondition(left))
        if straight:  # the line itself, with the states interpolate asks for (OMPL's interpolate spaces them evenly)
            path = start + np.linspace(0.0, 1.0, max(2, int(options.interpolate)))[:, None] * (goal - start)
        else:
            geo = og.PathGeometric(ss.getSolutionPath())  # a copy: nothing dangles after ss goes
            if options.interpolate:
                geo.interpolate(int(options.interpolate))
            path = np.array([to_np(s) for s in geo.getStates()])
            del geo
    seconds = time.perf_counter() - t0
    text = str(status)
    del ss, si, space
    return PlanResult(path, exact, text, calls[0], seconds, options)
