"""A plan as an animation: ``plan_animation.gif`` and the same frames in a self-contained HTML page with a slider.

Each frame shows the hand and the workpiece (:meth:`qsplan.hands.protocol.Hand.body_polygons`), the contacts
where every finger touches, with the way the workpiece slides against the body at each (the frames:
:func:`qsplan.planner.plotting.plan.animation_frames`),
the torque-controlled link with the way its command pushes it, a gauge of each commanded joint's command inside
its guaranteed band (band edges beyond the gauge marked as in Fig. 13: filled triangles unbounded, hollow finite),
and the phase (numbered as ``plan.csv``), its kind and what the hand does
(:func:`qsplan.planner.plotting.hands.row_state`).  Each gauge keeps the plan card's scale of the phase shown (a run
of phases on one scale, linear or log: :func:`qsplan.planner.plotting.plan_panels.scale_groups`).  In-contact frames
are rows of the plan; a regrasp's frames
are its rows and the straight joint motions between them (the rows hold each velocity until the next row).

Kept light for ``qsplan plan`` and ``demo``: at most ``max_frames`` frames on a small figure, drawn with
matplotlib once each over a background drawn once (axes, ticks, legend) and per-phase texts drawn once per phase;
the GIF is those images in one palette (Pillow), the page embeds them as PNGs with a slider, play and step buttons
and a few lines of JavaScript, and needs no network.  (matplotlib's ``PillowWriter`` and ``to_jshtml`` redraw every
frame through ``savefig``: about four times the time, and ``to_jshtml``'s player loads its icons from a CDN.)
matplotlib is imported inside the functions.
"""

from __future__ import annotations

import base64
import io
import json
from pathlib import Path

import numpy as np

from qsplan.mechanics.errors import QsplanError

from qsplan.planner.plotting.hands import effort_direction, hand_limits, state_words
from qsplan.planner.plotting.plan import animation_frames
from qsplan.planner.plotting.plan_panels import (
    SLACK,
    edge_marker,
    effort_words,
    is_contact,
    joint_title,
    log_ticks,
    phase_colour,
    phase_label,
    scale_groups,
    slack,
    torque_scale,
)
from qsplan.planner.plotting.style import COMMAND, FONT, body_style, joint_colour, torque_text

__all__ = ["ANIMATION_DPI", "ANIMATION_SIZE", "DEFAULT_FPS", "MAX_FRAMES", "plan_animation"]

#: Frames at most (a plan's rows are subsampled): 60 keep the GIF near 1 MB and the drawing near a second.
MAX_FRAMES = 60

#: Frames per second of the GIF and the page's player.
DEFAULT_FPS = 8

#: Figure size (inches) and resolution (dots per inch): 576 x 288 pixels, the hand and the gauges readable.
ANIMATION_SIZE = (7.2, 3.6)
ANIMATION_DPI = 80

#: Colours of the GIF's one palette: the figure's flat fills and their antialiased edges fit in 64.
_GIF_COLOURS = 64

#: zlib level of the page's PNG frames: 3 is 40 % faster than Pillow's 6 and as small (flat colours) on these frames.
_PNG_LEVEL = 3

#: The gauges' column (fraction of the figure's height, from 0.80 down) and the gap between two gauges: a gauge's
#: tick labels and label below it and the next one's note above it (three 7-pt lines, ~0.13 of the 288-pixel height).
_GAUGE_SPAN, _GAUGE_GAP = 0.6, 0.15

#: Length of the drawn sliding and effort arrows, relative to the hand's drawing width.
_ARROW = 0.07



class _Scene:
    """The animation's artists: a background drawn once, texts drawn once per phase, the rest set per frame."""

    def __init__(self, fig, plan, frames):
        from matplotlib.patches import Polygon as Patch

        self.plan, self.frames, self.hand = plan, frames, plan.task.hand
        hand = self.hand
        self.joints = [j for j in hand.joint_names if any(is_contact(p) and p.effort_joint == j for p in plan.phases)]
        lim = hand_limits(hand, [(f.pose, f.q) for f in frames])
        self.size = _ARROW * float(lim[0][1] - lim[0][0])
        ax = self.ax = fig.add_axes((0.01, 0.16, 0.50, 0.68))
        ax.set_xlim(*lim[0])
        ax.set_ylim(*lim[1])
        ax.set_aspect("equal")
        ax.set_xticks([])
        ax.set_yticks([])
        polys = hand.body_polygons(frames[0].pose, frames[0].q)
        finger = hand.finger_of_joint
        self.patches = {}
        for name in ["palm"] + [n for n in polys if n not in ("palm", "workpiece")] + ["workpiece"]:
            face, edge = body_style(finger.get(name, name))
            self.patches[name] = ax.add_patch(Patch(polys[name], closed=True, fc=face, ec=edge, lw=1.0))
        (self.dots,) = ax.plot([], [], "o", ms=4, color="k", zorder=5)
        self.title = fig.text(0.01, 0.97, "", fontsize=FONT["label"], va="top", weight="bold")
        self.doing = fig.text(0.01, 0.895, "", fontsize=FONT["note"] + 0.5, va="top")
        self.status = fig.text(0.30, 0.895, "", fontsize=FONT["note"] + 0.5, va="top")
        self.gauges = [self._gauge(fig, j, n) for n, j in enumerate(self.joints)]
        self._timeline(fig)
        self._legend(fig)
        self.arrows = []
        self.per_phase = [self.title, self.doing] + [g["note"] for g in self.gauges]
        self.per_frame = [*self.patches.values(), self.dots, self.status, self.cursor]
        for g in self.gauges:
            self.per_frame += [g["band"], g["command"], *g["ends"].values()]
        for a in self.per_phase + self.per_frame:  # left out of the background (drawn by _render)
            a.set_animated(True)

    def _gauge(self, fig, joint, n) -> dict:
        from matplotlib.patches import Rectangle

        k = max(1, len(self.joints))
        h = min(0.16, (_GAUGE_SPAN - (k - 1) * _GAUGE_GAP) / k)
        ax = fig.add_axes((0.58, 0.80 - (n + 1) * h - n * _GAUGE_GAP, 0.39, h))
        segs = [p for p in self.plan.phases if is_contact(p) and p.effort_joint == joint]
        res = self.plan.task.torque_resolution
        scales = {}  # phase -> (limits, log): each run of phases on one scale (the plan card's panels)
        for group in scale_groups(segs, res):
            scale = torque_scale(group, res)
            scales |= {i: scale for i, p in enumerate(self.plan.phases) if any(p is m for m in group)}
        lim = scales[min(scales)][0]
        word, unit = effort_words(self.hand, joint)
        colour = joint_colour(self.hand, joint)
        ax.set_xlim(*lim)
        ax.set_ylim(0.0, 1.0)
        ax.set_yticks([])
        ax.tick_params(labelsize=FONT["tick"] - 1, pad=1)
        ax.set_xlabel(f"{joint_title(joint)} {word} ({unit})", fontsize=FONT["note"], labelpad=1)
        zero = ax.axvline(0.0, color="0.6", lw=0.5)
        band = ax.add_patch(Rectangle((0.0, 0.2), 0.0, 0.6, fc=colour, alpha=0.3, lw=0))
        (command,) = ax.plot([], [], color=COMMAND, lw=2.2)
        ends = {(side, inf): edge_marker(ax, [], 0.5, side, inf, colour, ms=6)[0] for side in ("upper", "lower")
                for inf in (True, False)}  # fmt: skip
        for (side, _), mark in ends.items():  # the gauge lies on its side: an edge beyond it points out
            mark.set_marker(">" if side == "upper" else "<")
        note = ax.text(0.5, 1.05, "", transform=ax.transAxes, ha="center", va="bottom", fontsize=FONT["note"])
        gauge = {"joint": joint, "lim": lim, "unit": unit, "band": band, "command": command, "ends": ends, "note": note,
                 "ax": ax, "zero": zero, "scales": scales, "label": f"{joint_title(joint)} {word} ({unit}"}  # fmt: skip
        self._set_scale(gauge, scales[min(scales)])
        return gauge

    @staticmethod
    def _set_scale(g, scale):
        """Put gauge ``g`` on ``scale`` (``(limits, log)``, its phases' run's: :func:`torque_scale`)."""
        from matplotlib.ticker import MaxNLocator

        (lo, hi), log = scale
        ax = g["ax"]
        ax.set_xscale("log" if log else "linear")
        ax.set_xlim(lo, hi)
        if log:
            log_ticks(ax.xaxis, lo, hi, most=6)
        else:
            ax.xaxis.set_major_locator(MaxNLocator(5))  # tick labels of small efforts (-0.035) stay apart
        g["zero"].set_visible(not log)
        ax.set_xlabel(g["label"] + (", log scale)" if log else ")"), fontsize=FONT["note"], labelpad=1)
        g["lim"] = (lo, hi)

    def scale_key(self, i) -> tuple:
        """The gauges' scales in phase ``i`` (a gauge whose joint is not torque-controlled there keeps the scale of
        its last phase before ``i`` that is, else its first)."""
        out = []
        for g in self.gauges:
            known = [j for j in g["scales"] if j <= i]
            out.append(max(known) if known else min(g["scales"]))
        return tuple(out)

    def set_scales(self, key):
        """Put every gauge on the scale of its phase in ``key`` (:meth:`scale_key`)."""
        for g, j in zip(self.gauges, key):
            self._set_scale(g, g["scales"][j])

    def _timeline(self, fig):
        ax = fig.add_axes((0.58, 0.08, 0.39, 0.05))
        for ph in self.plan.phases:
            ax.barh(0, float(ph.t[-1] - ph.t[0]), left=float(ph.t[0]), height=1.0, color=phase_colour(ph, self.hand),
                    alpha=0.75, ec="k", lw=0.4)  # fmt: skip
        ax.set_xlim(float(self.plan.phases[0].t[0]), self.plan.duration)
        ax.set_ylim(-0.5, 0.5)
        ax.set_yticks([])
        ax.tick_params(labelsize=FONT["tick"] - 1, pad=1)
        ax.set_xlabel("t (s); phases coloured as on the plan card", fontsize=FONT["note"], labelpad=1)
        (self.cursor,) = ax.plot([0.0, 0.0], [-0.8, 0.8], color="k", lw=1.8, clip_on=False)

    def _legend(self, fig):
        from matplotlib.lines import Line2D

        handles = [Line2D([], [], ls="none", marker="o", ms=4, color="k", label="contact"),
                   Line2D([], [], color="k", lw=1.0, marker=">", ms=4, markevery=[1], label="workpiece slides this way"),
                   Line2D([], [], color="0.3", lw=1.8, marker=">", ms=4, markevery=[1], label="commanded effort pushes")]  # fmt: skip
        if self.joints:
            handles.append(Line2D([], [], color=COMMAND, lw=2.2, label="command inside its band (shaded)"))
        fig.legend(handles=handles, loc="lower left", bbox_to_anchor=(0.0, 0.0), ncol=2, fontsize=FONT["note"] - 0.5,
                   frameon=False, handlelength=1.6, columnspacing=1.0)  # fmt: skip

    def set_phase(self, i, state):
        """Set the texts that hold while phase ``i`` keeps the hand's ``state``."""
        ph = self.plan.phases[i]
        self.doing.set_text(f"the hand is {state_words(self.plan, i, state)}")
        mode, control = phase_label(ph, self.hand)
        what = f"{mode}, {control}-controlled" if is_contact(ph) else ph.title()
        n = len(self.plan.phases)
        self.title.set_text(f"phase {i}" + (f" (phases 0 to {n - 1})" if n > 1 else "") + f": {what}")
        for g in self.gauges:
            if is_contact(ph) and ph.effort_joint == g["joint"]:
                value, edge, _ = slack(ph)
                g["note"].set_text(f"phase {i}: slack at least {torque_text(value, g['unit'])} (to the {edge} edge)")
                g["note"].set_color(SLACK)
            else:
                g["note"].set_text(f"phase {i}: velocity-controlled")
                g["note"].set_color("0.4")

    def set_frame(self, n) -> list:
        """Set the artists of frame ``n``; returns those to draw over its phase's background."""
        from matplotlib.patches import FancyArrowPatch

        f = self.frames[n]
        ph = self.plan.phases[f.phase]
        effort = ph.effort_joint if is_contact(ph) else None
        for name, poly in self.hand.body_polygons(f.pose, f.q).items():
            self.patches[name].set_xy(poly)
            self.patches[name].set_linewidth(2.4 if name == effort else 1.0)
        arrows = [(p, p + self.size * d, "k", 1.0) for p, d in f.contacts if np.any(d)]
        words = f"t = {f.t:.2f} s"  # short: a frame's text is drawn every frame
        if effort is not None:
            c = float(ph.command[f.row])
            p, d = effort_direction(self.hand, f.pose, f.q, effort, c) if c else (None, None)
            arrows += [(p, p + 1.6 * self.size * d, joint_colour(self.hand, effort), 1.8)] if c else []
            words += f", command {torque_text(c, effort_words(self.hand, effort)[1])}"
        while len(self.arrows) < len(arrows):  # a pool, grown when a frame needs more (no limits to update)
            self.arrows.append(self.ax.add_artist(FancyArrowPatch((0, 0), (0, 0), arrowstyle="-|>", mutation_scale=9,
                                                                  shrinkA=0, shrinkB=0, zorder=6, animated=True)))  # fmt: skip
        for arrow, (a, b, colour, lw) in zip(self.arrows, arrows):
            arrow.set_positions(a, b)
            arrow.set_color(colour)
            arrow.set_linewidth(lw)

        pts = np.array([p for p, _ in f.contacts]).reshape(-1, 2)
        self.dots.set_data(pts[:, 0], pts[:, 1])
        self.status.set_text(words)
        self.cursor.set_xdata([f.t, f.t])
        for g in self.gauges:
            self._set_gauge(ph, f.row, g)
        return self.per_frame + self.arrows[: len(arrows)]

    @staticmethod
    def _set_gauge(ph, k, g):
        for mark in g["ends"].values():
            mark.set_data([], [])
        if not (is_contact(ph) and ph.effort_joint == g["joint"]):
            g["band"].set_width(0.0)
            g["command"].set_data([], [])
            return
        (y0, y1), lo, up, c = g["lim"], float(ph.lower[k]), float(ph.upper[k]), float(ph.command[k])
        g["band"].set_x(max(lo, y0))
        g["band"].set_width(max(0.0, min(up, y1) - max(lo, y0)))
        g["command"].set_data([c, c], [0.1, 0.9])
        for side, value, at in (("upper", up, y1), ("lower", lo, y0)):
            if not (y0 <= value <= y1):
                g["ends"][(side, bool(np.isinf(value)))].set_data([at], [0.5])


def _render(plan, frames) -> list:
    """Each frame as an RGB image, shape (h, w, 3) uint8: the background drawn once, the texts of a phase and the
    hand's state once each, each frame's moving artists over them."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=ANIMATION_SIZE, dpi=ANIMATION_DPI)
    canvas = FigureCanvasAgg(fig)
    scene = _Scene(fig, plan, frames)
    bases, cached, out = {}, {}, []  # a background per set of gauge scales (drawn once each)
    for n, f in enumerate(frames):
        scales = scene.scale_key(f.phase)
        if scales not in bases:
            scene.set_scales(scales)
            canvas.draw()
            bases[scales] = canvas.copy_from_bbox(fig.bbox)
        key = (f.phase, f.state)
        if key not in cached:
            canvas.restore_region(bases[scales])
            scene.set_phase(*key)
            for a in scene.per_phase:
                fig.draw_artist(a)
            cached[key] = canvas.copy_from_bbox(fig.bbox)
        moving = scene.set_frame(n)
        canvas.restore_region(cached[key])
        for a in moving:
            fig.draw_artist(a)
        out.append(np.asarray(canvas.buffer_rgba())[..., :3].copy())
    return out


def _check(fps, max_frames) -> tuple:
    try:
        fps_value = float(fps)
    except (TypeError, ValueError):
        fps_value = float("nan")
    if not (np.isfinite(fps_value) and fps_value > 0):
        raise QsplanError(f"fps: expected a positive number of frames per second; got {fps!r}")
    if isinstance(max_frames, bool) or not isinstance(max_frames, (int, np.integer)) or max_frames < 2:
        raise QsplanError(f"max_frames: expected an integer of at least 2 (the plan's first and last rows); "
                          f"got {max_frames!r}")  # fmt: skip
    return fps_value, int(max_frames)


def _gif(images, fps) -> bytes:
    """An endlessly looping GIF of ``images`` (RGB) in one palette (no colour flicker between frames)."""
    from PIL import Image

    pics = [Image.fromarray(a) for a in images]
    sample = np.concatenate([images[j] for j in sorted({0, len(images) // 2, len(images) - 1})], axis=0)
    palette = Image.fromarray(sample).quantize(colors=_GIF_COLOURS)
    frames = [p.quantize(palette=palette, dither=Image.Dither.NONE) for p in pics]
    buf = io.BytesIO()
    frames[0].save(buf, format="GIF", save_all=True, append_images=frames[1:], duration=int(round(1000.0 / fps)),
                   loop=0)  # fmt: skip
    return buf.getvalue()


def _page(plan, frames, images, fps) -> str:
    """A self-contained HTML page: the frames as embedded PNGs, a slider, play and step buttons (no network)."""
    from html import escape

    from PIL import Image

    pngs = []
    for a in images:
        buf = io.BytesIO()
        Image.fromarray(a).save(buf, format="PNG", compress_level=_PNG_LEVEL)
        pngs.append(base64.b64encode(buf.getvalue()).decode("ascii"))
    h, w = images[0].shape[:2]
    labels = [f"frame {n + 1} of {len(frames)}: phase {f.phase}, t = {f.t:.2f} s, {state_words(plan, f.phase, f.state)}"
              for n, f in enumerate(frames)]
    title = escape(f"{plan.task.name}: the plan, phase by phase")
    return _PAGE.format(title=title, n=len(frames), last=len(frames) - 1, w=w, h=h, duration=f"{plan.duration:.3g}",
                        frames=json.dumps(pngs), labels=json.dumps(labels), interval=int(round(1000.0 / fps)))  # fmt: skip


_PAGE = """<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<title>{title}</title>
<style>
body {{font-family: sans-serif; margin: 1em;}}
#controls {{display: flex; align-items: center; gap: 0.5em; width: {w}px;}}
#slider {{flex: 1;}}
</style>
</head>
<body>
<h1>{title}</h1>
<p>{n} frames over {duration} s; phases numbered as in plan.csv.  Drag the slider, use the buttons or the arrow keys.</p>
<img id="frame" width="{w}" height="{h}" alt="the hand, the workpiece and the commands at one instant of the plan">
<div id="controls">
<button id="back" title="previous frame">&#9664;</button>
<button id="play" title="play or pause">play</button>
<button id="next" title="next frame">&#9654;</button>
<input id="slider" type="range" min="0" max="{last}" value="0" step="1" aria-label="frame">
</div>
<p id="label"></p>
<script>
const frames = {frames};
const labels = {labels};
const img = document.getElementById("frame"), slider = document.getElementById("slider");
const play = document.getElementById("play"), label = document.getElementById("label");
let timer = null;
function show(n) {{
  n = (n + frames.length) % frames.length;
  img.src = "data:image/png;base64," + frames[n];
  slider.value = n;
  label.textContent = labels[n];
}}
function toggle() {{
  if (timer) {{ clearInterval(timer); timer = null; play.textContent = "play"; }}
  else {{ timer = setInterval(() => show(Number(slider.value) + 1), {interval}); play.textContent = "pause"; }}
}}
slider.addEventListener("input", () => show(Number(slider.value)));
play.addEventListener("click", toggle);
document.getElementById("back").addEventListener("click", () => show(Number(slider.value) - 1));
document.getElementById("next").addEventListener("click", () => show(Number(slider.value) + 1));
document.addEventListener("keydown", (e) => {{
  if (e.key === "ArrowLeft") show(Number(slider.value) - 1);
  if (e.key === "ArrowRight") show(Number(slider.value) + 1);
}});
show(0);
</script>
</body>
</html>
"""


def plan_animation(plan, gif_path=None, html_path=None, fps: float = DEFAULT_FPS, max_frames: int = MAX_FRAMES) -> list:
    """Animate ``plan``: write a GIF and a self-contained HTML page with a slider (either may be None: not written).

    Parameters
    ----------
    plan : qsplan.planner.plan.results.Plan
    gif_path : str or Path, optional
        The GIF (a ``.gif`` name), looping.
    html_path : str or Path, optional
        The page (a ``.html`` name): the same frames as embedded PNGs, a slider, play and step buttons; it needs no
        network.
    fps : float
        Frames per second.
    max_frames : int
        Frames at most (at least 2).

    Returns
    -------
    list of Frame
        The frames drawn.

    Raises
    ------
    QsplanError
        ``fps``, ``max_frames`` or a path's suffix invalid (before anything is drawn).
    """
    from qsplan.planner.export.files import atomic_write

    fps, max_frames = _check(fps, max_frames)
    for field, path, suffixes in (("gif_path", gif_path, (".gif",)), ("html_path", html_path, (".html", ".htm"))):
        if path is not None and Path(path).suffix.lower() not in suffixes:
            raise QsplanError(f"{field}: expected a file name ending in {' or '.join(suffixes)}; got {str(path)!r}")
    frames = animation_frames(plan, max_frames)
    images = _render(plan, frames)
    if gif_path is not None:
        atomic_write(gif_path, _gif(images, fps), binary=True, field="gif_path")
    if html_path is not None:
        atomic_write(html_path, _page(plan, frames, images, fps), field="html_path")
    return frames
