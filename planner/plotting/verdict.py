"""The plan card's verdict line: the certificate and the re-simulations in one line (:func:`verdict`).

Light on purpose (no matplotlib, no numpy): a run computes the verdict's facts here (:func:`verdict_facts`, plain
numbers) and hands them to the process drawing its card, which writes the line (:func:`verdict_text`) without loading
the certifier.
"""

from __future__ import annotations

from qsplan.planner.certify.scope import SCOPE_SHORT

__all__ = ["expected_verdict", "verdict", "verdict_facts", "verdict_text"]


def verdict(certificate=None, replays=()) -> tuple:
    """``(line, ok)``: the certificate and the re-simulations in one line, and whether both passed.

    Parameters
    ----------
    certificate : qsplan.planner.certify.certify.Certificate, optional
    replays : sequence of qsplan.planner.replay.replay.Replay
    """
    return verdict_text(verdict_facts(certificate), [r.followed for r in replays])


def verdict_facts(certificate=None) -> tuple | None:
    """What the verdict says of ``certificate``: ``(rows, friction vectors per contact row, certified, violations)``,
    plain numbers (None: no certificate)."""
    if certificate is None:
        return None
    pts = max((r.friction_points for r in certificate.rows), default=0)
    return (len(certificate.rows), int(pts), bool(certificate.ok), len(certificate.violations))


def expected_verdict(plan, replays: int) -> tuple:
    """``(line, ok)`` of :func:`verdict` for ``plan`` certified without a violation and re-simulated ``replays`` times
    without leaving its modes, before either is known: what :func:`qsplan.planner.plotting.card.draft_card` draws the
    card with.

    Only the number of lines it wraps to matters (:func:`qsplan.planner.plotting.card.finish_card` writes the actual
    verdict in their place); the friction vectors per row are a guess (the vertices of the friction box and the
    certificate's 8 random points).
    """
    rows = sum(int(p.t.size) for p in plan.phases)
    return verdict_text((rows, 2 ** plan.task.formation.n_contacts + 8, True, 0), [True] * int(replays))


def verdict_text(facts, followed) -> tuple:
    """:func:`verdict` from ``facts`` (:func:`verdict_facts`; None: no certificate) and each re-simulation's
    ``followed``."""
    parts, ok = [], True
    if facts is None:
        parts.append("not certified (no certificate)")
        ok = False
    else:
        rows, pts, certified, violations = facts
        what = f"{rows} rows checked from the task alone, {pts} friction vectors per contact row"
        if certified:
            parts.append(f"CERTIFIED ({what}, no violation): {SCOPE_SHORT}")
        else:
            parts.append(f"NOT CERTIFIED ({violations} violations; {what})")
            ok = False
    if followed:
        left = sum(not f for f in followed)
        n = len(followed)
        parts.append(f"re-simulated at {n} friction vector{'s' if n != 1 else ''}: "
                     + ("every run followed the planned modes" if not left else f"{left} LEFT the planned modes"))
        ok &= not left
    else:
        parts.append("not re-simulated")
        ok = False
    return "; ".join(parts), ok
