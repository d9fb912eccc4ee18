"""Rows at rest in the planner tests: every phase starts and ends at rest (issue 24), where the quasistatic model
decides nothing; a test judges such a row for the motion that leaves or reaches it, as the certifier does."""

import numpy as np


def moving_velocity(d, k, joint) -> float:
    """Joint ``joint``'s velocity command at row ``k`` of plan columns ``d``; at a row at rest (``qd`` 0) the rate of
    the straight line to the adjacent row of its phase (the motion's direction; its size does not matter to the
    quasistatic model)."""
    qd = float(d[f"qd_{joint}"][k])
    if qd != 0.0 or not np.all(np.nan_to_num([d[c][k] for c in d if c.startswith("qd_")]) == 0.0):
        return qd
    n, ph = len(d["t"]), d["phase"]
    a, b = (k, k + 1) if k + 1 < n and ph[k + 1] == ph[k] else (k - 1, k)
    return float((d[f"q_{joint}"][b] - d[f"q_{joint}"][a]) / (d["t"][b] - d["t"][a]))
