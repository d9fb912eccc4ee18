"""Rigid pairs of contacts (a flush pair, the bottom edge on the palm) and the modes their geometry makes degenerate.

Two contacts between the workpiece and one body with parallel normals at points off one normal line keep the two
bodies from turning relative to each other while both hold, so their sliding speeds are equal (eq. 6): a mode that
rolls one and slides the other slides it at zero speed.  The certifier sets such modes aside as degenerate by
geometry (:func:`qsplan.planner.certify.modes.structural_degeneracy`) instead of leaving them undecided where
rounding makes the float and machine-precision looks disagree (issue 32: a chain of pivots at mu = 0).  Checked here
against exact rational arithmetic on dyadic scenes (:func:`qsplan.mechanics.crosscheck.exact.exact_check_mode`).
"""

from __future__ import annotations

import numpy as np
import pytest

from qsplan.mechanics import make_scene
from qsplan.mechanics.crosscheck.exact import exact_check_mode
from qsplan.mechanics.model.contact import wrench_matrices
from qsplan.mechanics.modes.contact_mode import ContactMode
from qsplan.mechanics.numerics import Status
from qsplan.planner.certify.modes import rigid_pairs, structural_degeneracy


def _scene(points, normals, names):
    """Three contacts, one effort-controlled joint: dyadic numbers, so exact arithmetic sees exactly these data."""
    Wn, Wt = wrench_matrices(np.array(points, float), np.array(normals, float))
    return make_scene(Wn, Wt, [[0.0], [0.0], [0.5]], [[0.0], [0.0], [0.25]], [0.5] * 3, [0.0, -1.0, 0.0],
                      effort_controlled=[True], joint_effort=[0.5], contact_names=names)  # fmt: skip


#: The bottom edge on the palm (two contacts, normal +y, 1 m apart) and a finger on the left side.
RESTING = ([[-0.5, 0.0], [0.5, 0.0], [-0.5, 0.5]], [[0.0, 1.0], [0.0, 1.0], [1.0, 0.0]], ("palm:0", "palm:1", "left"))


def test_a_palm_edge_is_a_rigid_pair_and_rolling_one_end_stops_the_other_exactly():
    scene = _scene(*RESTING)
    assert rigid_pairs(scene) == ((0, 1),)
    letters = ["RSS", "SRS", "SSS", "RRB", "BSS", "SBS"]
    assert structural_degeneracy(letters, rigid_pairs(scene)).tolist() == [True, True, False, False, False, False]
    for mode in ("RSS", "SRS"):  # exact arithmetic: the sliding end's speed is exactly zero
        assert exact_check_mode(scene, ContactMode(mode)).status in Status.DEGENERATE


@pytest.mark.parametrize("points, normals, names, why", [
    ([[-0.5, 0.0], [0.5, 0.0], [-0.5, 0.5]], [[0.0, 1.0], [0.0, 1.0], [1.0, 0.0]], ("palm:0", "left", "right"),
     "another body"),
    ([[0.0, 0.0], [0.0, 0.5], [-0.5, 0.5]], [[0.0, 1.0], [0.0, 1.0], [1.0, 0.0]], ("palm:0", "palm:1", "left"),
     "points on one normal line"),
    ([[-0.5, 0.0], [0.5, 0.0], [-0.5, 0.5]], [[0.0, 1.0], [0.6, 0.8], [1.0, 0.0]], ("palm:0", "palm:1", "left"),
     "normals at an angle"),
])  # fmt: skip
def test_what_is_not_a_rigid_pair(points, normals, names, why):
    assert rigid_pairs(_scene(points, normals, names)) == (), why


def test_the_chained_turn_certifies_at_zero_friction():
    """The demo turned to -0.84 rad: at mu = 0 a pivot row's competitor BRSS (the flush pair rolled at its base and
    slid at its tip) was left undecided by rounding; the rigid pair sets it aside, and every row is decided.

    Whether rounding leaves BRSS undecided without the rule depends on the BLAS kernel (it did with OpenBLAS's Haswell
    kernel, not with the one a fresh machine here picks by itself): the test does not ask for that.  It asks what
    holds on every machine: at every pivot row the flush pair is a rigid pair of the row's scene, BRSS is set aside
    by geometry, and every row is decided."""
    import tempfile
    from dataclasses import replace
    from pathlib import Path

    from qsplan.planner.certify import modes
    from qsplan.planner.certify.contacts import judged_contacts
    from qsplan.planner.export.plan_files import export_plan, read_plan_csv
    from qsplan.planner.plan.scripted import plan_task
    from qsplan.planner.task.goal import Goal
    from qsplan.planner.task.task import load_task, task_paths

    task = replace(load_task(task_paths()["reorient_task"]), goal=Goal(None, None, None, theta=-0.84))
    out = Path(tempfile.mkdtemp())
    export_plan(plan_task(task), out)
    cols = read_plan_csv(out / "plan.csv")
    rows = [k for k in range(cols["t"].size) if cols["phase"][k] == 2][1:-1]
    scenes = {k: modes.row_scene(task, cols, k, judged_contacts(task, cols, k)) for k in rows}

    def undecided():
        return [k for k in rows if any(kind == "undecided" for kind, _ in modes.mode_checks(
            task, cols, k, np.zeros((1, 4)), task.force_margin.normal, np.nan, True, scenes[k])[0])]  # fmt: skip

    for k in rows:
        names = scenes[k].contact_names
        pairs = modes.rigid_pairs(scenes[k])
        assert (names.index("left:base"), names.index("left:tip")) in pairs, (k, names, pairs)
        brss = "".join({"palm:1": "B", "left:base": "R"}.get(n, "S") for n in names)
        assert structural_degeneracy([brss], pairs).tolist() == [True], (k, brss)
    assert undecided() == []
