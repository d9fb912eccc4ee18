"""The result of solving a scene for every feasible contact mode (Sections 3.1-3.2, eq. 49)."""

from __future__ import annotations

from dataclasses import dataclass, field, replace

from qsplan.mechanics.model.scene import Scene
from qsplan.mechanics.modes.solution import ModeSolution
from qsplan.mechanics.numerics import DEFAULT_TOLERANCES, Status, Tolerances

__all__ = ["SolveResult", "merge_results"]


@dataclass(frozen=True, slots=True, eq=False)
class SolveResult:
    """Every feasible mode of a scene, and why the others were rejected.

    Attributes
    ----------
    scene : Scene
    modes_tested : int
        Number of modes tested: eq. (49) for ``n_c`` and ``3 + |tau_I|``.
    solutions : tuple of ModeSolution
        Feasible modes in enumeration order.
    counts : dict[str, int]
        Number of modes per :class:`~qsplan.mechanics.numerics.Status`; degenerate cases
        (singular matrices, zero speeds) are counted here and never reported feasible.
        A pruned search (``solve(search="prune")``) adds the untested modes under
        ``solver.search.PRUNED`` and ``solver.search.PRUNED_KINEMATIC``; the sum is still eq. (49).
    tolerances : Tolerances
    statuses : tuple of str or None
        Status of every tested mode in enumeration order, when ``solve(..., keep_statuses=True)``.
    """

    scene: Scene
    modes_tested: int
    solutions: tuple
    counts: dict
    tolerances: Tolerances = field(default=DEFAULT_TOLERANCES)
    statuses: tuple | None = None

    @property
    def feasible_modes(self) -> list[str]:
        """Letters of the feasible modes, in enumeration order."""
        return [s.mode.letters for s in self.solutions]

    @property
    def ambiguous(self) -> bool:
        """More than one mode is feasible (Section 4.3)."""
        return len(self.solutions) > 1

    @property
    def no_feasible_mode(self) -> bool:
        """No mode was found feasible (a jam only if no mode was left undecided: :attr:`jammed`)."""
        return not self.solutions

    @property
    def jammed(self) -> bool:
        """A proven jam (the paper's "Jam"): no mode is feasible and none was left undecided.

        With undecided (degenerate or ill-conditioned) modes and no feasible one, the scene may
        or may not jam: :attr:`no_feasible_mode` is True and this is False.  The one definition
        used by the text and JSON outputs alike.
        """
        return not self.solutions and self.degenerate == 0

    @property
    def degenerate(self) -> int:
        """Number of modes not decided: rejected as degenerate or ill-conditioned (:data:`Status.DEGENERATE`)."""
        return sum(v for k, v in self.counts.items() if k in Status.DEGENERATE)

    def solution(self, letters: str) -> ModeSolution | None:
        """The solution of mode ``letters`` if it is feasible, else None."""
        for s in self.solutions:
            if s.mode.letters == letters:
                return s
        return None


def merge_results(parts):
    """One :class:`~qsplan.mechanics.solver.result.SolveResult` from the results of consecutive batch ranges.

    Solutions and statuses are concatenated in range order (the enumeration order),
    counts per status summed.
    """
    counts = dict.fromkeys(parts[0].counts, 0)
    for p in parts:
        for k, v in p.counts.items():
            counts[k] += v
    solutions = tuple(s for p in parts for s in p.solutions)
    statuses = None if parts[0].statuses is None else tuple(s for p in parts for s in p.statuses)
    return replace(parts[0], solutions=solutions, counts=counts, statuses=statuses)
