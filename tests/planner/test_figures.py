"""Every figure function rendered and checked as a reader would (issue 16): titles, axis labels with units, no two
texts overlapping, no legend over a plot area, and what each figure must say (renderer bounding boxes, Agg)."""

import numpy as np
import pytest

from qsplan.hands import default_hand, eq37_scene, eq42_scene, first_segment, rod_scene, sample_segment
from qsplan.mechanics import mu_slice, scene_from_dict
from qsplan.planner.plotting.bands import plot_guaranteed, plot_speed_accuracy, segment_band_figures
from qsplan.planner.plotting.muspace import mu_slices_figure, plot_contact_scene, plot_mu_map, rod_mu_figure
from qsplan.planner.plotting.style import PALETTE, mode_set_colour, new_axes, torque_text
from qsplan.planner.torque.command import with_segment_command
from qsplan.planner.torque.sweep import segment_bands
from tests.planner.figure_checks import all_text, labels_without_units, legends_over_axes, overlapping_texts

PLAIN = (r"^\$\\mu_\d\$$", r"^$", r"^[xy]$")  # mu axes have no unit; the paper's example scenes neither


def check_layout(fig, allowed=PLAIN):
    """The layout assertions every figure passes."""
    assert overlapping_texts(fig) == []
    assert legends_over_axes(fig) == []
    assert labels_without_units(fig, allowed) == []


@pytest.fixture(scope="module")
def bands():
    S = sample_segment(first_segment(default_hand()), 41)
    return {shared: with_segment_command(segment_bands(S, shared=shared, workers=1), 0.02) for shared in (False, True)}


def test_band_figures(bands):
    figs = segment_band_figures(bands[False])
    assert set(figs) == {"fig10_frictionless", "fig11_mu_high", "fig12_competitors", "fig13_guaranteed", "hand_strip"}
    for name, fig in figs.items():
        check_layout(fig)
    text = {name: all_text(fig) for name, fig in figs.items()}
    assert "Fig. 10" in text["fig10_frictionless"] and "unbounded for t in [0," in text["fig10_frictionless"]
    assert "upper edge unbounded (infinite)" in text["fig10_frictionless"]
    assert "beyond the plotted range (finite)" in text["fig10_frictionless"]  # two markers, two meanings
    assert "inf N m" not in "\n".join(text.values())
    assert "zoom on the lower edge" in text["fig11_mu_high"]  # the edge that matters stays visible
    assert "R2S BSRS: the left palm vertex lifts off" in text["fig12_competitors"]
    assert "the paper's R2S (RBSS" in text["fig12_competitors"]  # which competitor, and why not the paper's
    assert "narrowest: " in text["fig13_guaranteed"] and "torque (oz in, the paper's unit)" in text["fig13_guaranteed"]
    assert "t = 0 s" in text["hand_strip"] and "torque-controlled finger" in text["hand_strip"]


def test_shared_fig13_command_stays_on_scale(bands):
    fig, ax = new_axes(1, 1, size=(8.0, 5.4))
    plot_guaranteed(bands[True], ax[0, 0])
    check_layout(fig)
    command = next(line for line in ax[0, 0].get_lines() if line.get_label() == "exported command")
    y = np.asarray(command.get_ydata(), float)
    assert np.all(y < 0.5) and np.max(np.abs(np.diff(y))) < 0.01  # it used to leap to the plot's top


@pytest.fixture(scope="module")
def slices():
    xs = np.linspace(0.0, 1.5, 41)
    s42 = [mu_slice(scene_from_dict(eq42_scene()), 0, 1, xs, xs, base_mu=[0, 0, m], workers=1) for m in (0.1, 0.6)]
    s37 = mu_slice(scene_from_dict(eq37_scene()), 0, 1, xs, xs, base_mu=[0, 0, 0.5], workers=1)
    rod = mu_slice(scene_from_dict(rod_scene(l1=1.0, l2=0.6)), 0, 1, xs[:28], xs[:28], workers=1)
    return s42, s37, rod


def test_mu_slices_one_legend_outside_same_colours(slices):
    s42, s37, _ = slices
    fig = mu_slices_figure(s42, ["$\\mu_3$ = 0.1", "$\\mu_3$ = 0.6"], "eq. (42)")
    check_layout(fig)
    assert len(fig.legends) == 1 and not any(ax.get_legend() for ax in fig.axes)
    labels = [t.get_text() for t in fig.legends[0].get_texts()]
    assert len(labels) == len(set(labels)) and "3S (1) + R1S3 (3) + R2S1 (4)  [ambiguous]" in labels
    assert mode_set_colour((0,)) == mode_set_colour([0]) != mode_set_colour((0, 2))  # by mode numbers, not order
    fig, axes = new_axes(1, 1)
    ax = plot_mu_map(s37, ax=axes[0, 0], title="eq. (37)")
    check_layout(fig)
    def fills(handles):
        return {h.get_label(): h.get_facecolor()[:3] for h in handles if hasattr(h, "get_facecolor")}

    from matplotlib.colors import to_rgb

    light = [c + 0.25 * (1 - c) for c in to_rgb(PALETTE[0])]  # mode 1's colour, lightened under the labels
    assert fills(ax.mu_legend_handles)["3S (1)"] == pytest.approx(light)  # in eq. (37)'s figure
    assert fills(fig_42_alone(s42[1]))["3S (1) + R3S1 (6)  [ambiguous]"] == pytest.approx(light)  # eq. (42)'s


def fig_42_alone(sl):
    _, axes = new_axes(1, 1)
    return plot_mu_map(sl, ax=axes[0, 0]).mu_legend_handles


def test_mu_fill_follows_the_exact_boundary(slices):
    """Painted from the exact regions, not the 41 x 41 cells: no staircase along the boundary."""
    _, _, rod = slices
    fig, axes = new_axes(1, 1)
    ax = plot_mu_map(rod, ax=axes[0, 0], numbers=False, curves=False)
    image = ax.get_images()[0].get_array()
    n = image.shape[0]
    mu = np.linspace(rod.xs[0], rod.xs[-1], n)
    above = mu[:, None] * 1.0 > 0.6 * mu[None, :]  # R2S1 above l1 mu2 = l2 mu1 (rows: mu2)
    r2s1 = np.all(np.isclose(image, image[-1, 0]), axis=-1)
    margin = np.abs(mu[:, None] - 0.6 * mu[None, :]) > 1.5 * (mu[1] - mu[0])
    assert np.array_equal(r2s1[margin], above[margin])


def test_fig8_rectangle_and_no_entry_without_area(slices):
    _, _, rod = slices
    fig = rod_mu_figure(rod, 1.0, 0.6, (0.5, 0.5), (0.4, 0.4))
    check_layout(fig)
    labels = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert "friction rectangle (sliding to rolling values)" in labels
    assert not any("ambiguous" in label for label in labels)  # both RS modes only on the line: no area


@pytest.mark.parametrize("make, mode", [(eq37_scene, "SSS"), (eq42_scene, "SSS")])
def test_scene_figures(make, mode):
    fig, axes = new_axes(1, 1, size=(6.5, 7.5))
    ax = plot_contact_scene(scene_from_dict(make()), mode=mode, mu=[0.3, 0.3, 0.3], ax=axes[0, 0])
    check_layout(fig)
    assert ax.get_xlabel() == "x" and "feasible by Corollary 1" in ax.get_title()
    x0, x1 = ax.get_xlim()
    y0, y1 = ax.get_ylim()
    for line in ax.get_lines():  # every point drawn (contacts, p12, p23, p31, centre) inside the axes
        if line.get_linestyle() == "None" or line.get_marker() not in ("None", None, ""):
            for x, y in zip(*map(np.atleast_1d, line.get_data())):
                assert x0 <= x <= x1 and y0 <= y <= y1
    assert "E+" in all_text(fig)


def test_rod_and_push_figures():
    from qsplan.hands import rod_closed_form, simulate_rod, tilted_box_example
    from qsplan.mechanics import MotionOptions, simulate
    from qsplan.planner.plotting.motion import push_motion_figure, rod_motion_figure

    params = dict(l1=1.0, l2=0.6, mu_static=(0.3, 0.3), mu_kinetic=(0.3, 0.3), speed=0.1, duration=20.0)
    fig = rod_motion_figure(simulate_rod(**params), closed_form=rod_closed_form(**params))
    check_layout(fig)
    text = all_text(fig)
    assert "no_persistent_mode" not in text and "no mode can continue" in text
    assert "switch of the closed form" not in text  # no switch: no legend entry for one
    corners = [ln for ln in fig.axes[1].get_lines() if "runs at" in ln.get_label()]
    assert corners[0].get_markersize() > corners[1].get_markersize()  # one corner drawn around the other
    system, x0 = tilted_box_example()
    fig = push_motion_figure(simulate(system, x0, 6.0, options=MotionOptions(max_step=0.05)))
    check_layout(fig)
    text = all_text(fig)
    assert "floor@" not in text and "R rolls, S slides, - not touching" in text


def test_speed_accuracy_chart():
    rows = [{"method": "exact box", "samples": None, "time": 0.008, "error": 0.0},
            {"method": "exact shared", "samples": None, "time": 0.13, "error": 0.0}]
    rows += [{"method": f"sampled {k}", "samples": n, "time": 0.005 * n ** 0.5, "error": e / n}
             for k, e in (("box", 20.0), ("shared", 2.0)) for n in (5, 20, 100, 1000)]  # fmt: skip
    fig, axes = new_axes(1, 1, size=(6.8, 4.6))
    ax = plot_speed_accuracy(rows, axes[0, 0])
    check_layout(fig)
    ymin = ax.get_ylim()[0]
    assert all(min(ln.get_ydata()) > ymin for ln in ax.get_lines() if "sampling" in ln.get_label())
    assert "no error" in all_text(fig) and "e-" not in " ".join(t.get_text() for t in ax.get_xticklabels())


@pytest.mark.ompl
def test_plan_figures_and_card(small_run):
    from qsplan.planner.plotting.plan import plan_figures, plot_plan_bands

    figs = plan_figures(small_run.plan, small_run.certificate, small_run.replays)
    assert set(figs) == {"plan_bands", "mode_timeline", "hand_snapshots", "plan_card"}
    for fig in figs.values():
        check_layout(fig)
    card = all_text(figs["plan_card"])
    assert "Plan card: small" in card and "CERTIFIED" in card and "re-simulated at 1 friction vector" in card
    assert card.count("narrowest ") >= len(small_run.plan.segments) and "finger torque" in card
    assert "$\\tau_{" in card and "(rad/s)" in card and "(N m)" in card
    assert figs["plan_card"].get_size_inches() == pytest.approx((8.27, 11.69))
    timeline = all_text(figs["mode_timeline"])
    assert "regrasp" in timeline and "4S (SSSS)" in timeline
    axes = plot_plan_bands(small_run.plan, sharey=True)
    assert len({ax.get_ylim() for ax in axes}) == 1
    assert "inf N m" not in "\n".join(all_text(f) for f in figs.values())


def test_torque_text():
    assert [torque_text(v) for v in (0.1394, np.inf, -np.inf, np.nan)] == ["0.139 N m", "unbounded above",
                                                                            "unbounded below", "none"]
