"""A mode singular on the friction set's boundary: one answer whatever the rounding (issue 31, the parallel jaw).

The hexagon of ``benchmarks/mujoco_tasks/jaw_04.toml`` has sides that rise 5 cm over 2 cm: a slope of 0.4.  Held by the
parallel jaw at its side corners, the competitor ``BSSR`` (palm:0 lifts, palm:1 and the left jaw slide, the right jaw
rolls) wedges the hexagon: its ``det Q_AI`` vanishes where palm:1's friction equals that slope.  With friction
``[0.1, 0.4]`` the singular set is a face of the friction box.  There ``det Q_AI`` is 0 in exact arithmetic and, in
floating point, 0 or a residue of either sign (-6.9e-18 of 0.016) depending on the last bit of the scene; the
competitor search once read the residue's sign (precluded in one cell: the planner's scene) or an exact 0 (never
resolved: the certifier's scene at 3 of 47 rows), so the certifier refused the planner's band.

Checked here against things computed another way: the wedge's friction from the geometry alone (the slope), the
singularity test against :func:`qsplan.mechanics.numerics.hadamard_ratio`, and the band at every row of a slide, in
both the closed-form scene and the polygon search's, with friction up to the slope (no band, for a reason that
says so) and up to 0.39 (a band, the same in both scenes).
"""

from __future__ import annotations

from functools import cache

import numpy as np
import pytest
from qsplan.mechanics.bands.effort import band_kinematics, band_rows
from qsplan.mechanics.bands.preclusion import competitor_torques
from qsplan.mechanics.bands.robust import robust_band
from qsplan.mechanics.numerics import DEFAULT_TOLERANCES, hadamard_ratio, singular_matrices

#: The hexagon of jaw_04: its right side from (0.06, 0) to (0.08, 0.05), its left from (-0.02, 0.05) to (0, 0).
HEXAGON = [[0.0, 0.0], [0.06, 0.0], [0.08, 0.05], [0.05, 0.09], [0.01, 0.09], [-0.02, 0.05]]
SLOPE = (0.08 - 0.06) / 0.05  # dx/dy of its sides: the wedge's friction, 0.4

TASK = f"""
name = "parallel jaw: the hexagon of jaw_04"
[hand]
file = "parallel_jaw"
workpiece = {HEXAGON}
workpiece_mass = 0.2
[motion]
start_x = 0.0
[goal]
x = -0.02
[friction]
range = [0.1, 0.4]
shared = false
[controller]
torque_resolution = 0.02
"""


@cache
def _task(hi: float = 0.4):
    import tomllib

    from qsplan.planner.task.task import task_from_record

    doc = tomllib.loads(TASK.replace("range = [0.1, 0.4]", f"range = [0.1, {hi}]"))
    return task_from_record(doc)


def _scene(x: float, method: str):
    """The slide's scene at workpiece ``x`` (m): the left jaw force-controlled, the right one closing the grasp as
    the workpiece moves left at 1 cm/s (the grasp's closed form or the polygon search: ``method``)."""
    from qsplan.hands.described.records import scene_at
    from qsplan.planner.states.contact import contact_samples

    task = _task()
    s = contact_samples(task, [x], "left_jaw", -0.01)
    if method == "auto":
        return s.scenes[0]
    effort = np.array(task.hand.joint_names) == "left_jaw"
    return scene_at(task.hand, s.pose[0], s.q[0], effort, s.qd[0], method="generic")


def test_singular_matrices_is_the_hadamard_test():
    """The test from a determinant already computed agrees with :func:`hadamard_ratio` (an LU of its own) on random,
    nearly singular and exactly singular matrices, at and away from the threshold."""
    rng = np.random.default_rng(7)
    A = rng.normal(size=(400, 5, 5)) * rng.uniform(0.01, 100.0, size=(400, 5, 1))  # rows of any scale
    A[:100, 4] = A[:100, 3] * 2.0 + 1e-13 * rng.normal(size=(100, 5))  # nearly singular, ratio ~1e-13
    A[100:120, 4] = A[100:120, 0]  # exactly singular
    A[120:140, 4] = A[120:140, 1] * (1.0 + 1e-6 * rng.normal(size=(20, 5)))  # ratio ~1e-6: decided
    got = singular_matrices(A, np.linalg.det(A))
    want = hadamard_ratio(A) < DEFAULT_TOLERANCES.singular
    assert np.array_equal(got, want)
    assert got[100:120].all() and not got[120:140].any() and not got[140:].any()
    assert singular_matrices(np.eye(3)[None], np.array([np.nan])).all()  # a determinant that is not a number


def test_the_wedge_is_singular_where_friction_equals_the_slope():
    """``det Q_AI`` of BSSR changes sign where palm:1's coefficient crosses the sides' slope (the geometry alone says
    where a corner wedges: friction equal to the tangent of the side's angle), and nowhere else along that edge of
    the box; at the slope the band rows are the singular ones (NaN, ``det`` 0)."""
    scene = _scene(-0.004, "generic")
    mk = band_kinematics(scene, "BSSR", DEFAULT_TOLERANCES)
    assert mk.ok
    mu = np.tile([0.1, SLOPE, 0.1, 0.1], (7, 1))
    mu[:, 1] += np.array([-1e-2, -1e-4, -1e-6, 0.0, 1e-6, 1e-4, 1e-2])
    s0, _, det, _ = band_rows(scene, mk, mu)
    assert np.all(det[:3] < 0) and np.all(det[4:] > 0)
    assert det[3] == 0.0 and np.isnan(s0[3]).all()  # the singular test, not the residue's sign
    along = np.tile([0.1, 0.0, 0.1, 0.1], (50, 1))
    along[:, 1] = np.linspace(0.1, SLOPE - 1e-3, 50)
    assert np.all(band_rows(scene, mk, along)[2] < 0)  # inside the set it keeps its sign: singular on its face only


@pytest.mark.parametrize("method", ["auto", "generic"])
def test_one_answer_at_every_row_whatever_the_rounding(method):
    """Every row of the slide the planner took (0 to -9 mm), in both scenes (closed form, polygon search: they differ
    in the last bit), gets the same answer: no band up to friction 0.4 (the competitor singular at a point of the set,
    said so, at once), a band up to 0.39 (the face outside the set), equal in both scenes to 1e-9 N."""
    lo, hi = _task().mu_range
    for x in np.linspace(0.0, -0.009, 19):
        scene = _scene(float(x), method)
        kw = dict(shared=False, force_margin=_task().force_margin, disturbance=_task().disturbance)
        rb = robust_band(scene, "SSSS", (lo, hi), **kw)
        assert not rb.feasible and "singular" in rb.reason and "Tolerances.singular" in rb.reason
        ct = competitor_torques(scene, "BSSR", lo, hi, rb.desired.lower, rb.desired.upper,
                                disturbance=_task().disturbance)  # fmt: skip
        assert not ct.empty and not ct.exact and ct.cells <= 2  # the search ends at its first singular cell
        assert (ct.lower, ct.upper) == (rb.desired.lower, rb.desired.upper)  # conservative: the whole interval
        inside = robust_band(scene, "SSSS", (lo, 0.39), **kw)
        other = robust_band(_scene(float(x), "generic" if method == "auto" else "auto"), "SSSS", (lo, 0.39), **kw)
        assert inside.feasible and other.feasible
        assert inside.lower == pytest.approx(other.lower, abs=1e-9)
        assert inside.upper == pytest.approx(other.upper, abs=1e-9)


@pytest.mark.slow
@pytest.mark.ompl
def test_the_planner_proposes_only_what_its_certifier_confirms(tmp_path):
    """jaw_04 plans and certifies (it was refused: a band at 3 rows the certifier could not confirm): the slide runs
    with the right jaw force-controlled, whose bands do not meet the wedge; every row's band recomputed by the
    certifier."""
    from qsplan.planner.pipeline.run import run_plan

    run = run_plan(_task(), tmp_path / "out", verify=0, plots="none")
    cert = run.certificate
    assert cert.ok, cert.summary()
    efforts = {p.effort_joint for p in run.plan.phases if p.in_contact}
    assert efforts == {"right_jaw"}
