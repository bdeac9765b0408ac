"""The station's Gantt chart: one row per robot, its moves, welds and waits on the station clock.

Drawn from a :class:`~weldplan.multi.schedule.StationSchedule` (issue 30, item 5), the chart a
station engineer reads beside the cycle time: per robot (top row: the first robot) its
``move`` / ``weld`` / ``wait`` activities as bars in :data:`KIND_COLORS`, each weld's id on its
bar and each wait's interlock name on its bar where the text fits (a wait's name too long for
its bar stands over it), each robot's own end at the end of its row, the station's cycle time
as a solid line and, when given, the allocation's lower bound as a dashed one; the axis in s.

Two outputs of one figure (:func:`gantt_figure`, matplotlib with the Agg backend, imported
where used):

- :func:`gantt_png`: a PNG file, written whole or not at all; byte-for-byte the same for the
  same schedule (fixed size and dpi, no bounding-box trimming, no ``Software`` stamp);
- :func:`gantt_svg`: an inline SVG for HTML pages (the station page lays it under the 3D view,
  :mod:`weldplan.viz.station_page`) with where its time axis lies on the picture
  (:class:`GanttSvg`), so a page can put a cursor at any station time.

The margins are fixed in inches (:data:`MARGINS_IN`), not fitted to the text, so the time axis
lies at the same place on every chart of the same number of robots.
"""

from __future__ import annotations

import io
from dataclasses import dataclass
from os import PathLike
from pathlib import Path
from typing import Any

#: bar colours by activity kind (:data:`weldplan.multi.schedule.ACTIVITY_KINDS`)
KIND_COLORS = {"move": "#4C78A8", "weld": "#E45756", "wait": "#F2B701"}
#: the station's cycle time line and the lower bound's
CYCLE_COLOR = "#111111"
BOUND_COLOR = "#2CA02C"
#: figure width (in), height of one robot's row (in), pixels per inch of the PNG
WIDTH_IN = 10.0
ROW_IN = 0.55
DPI = 100
#: fixed margins (in): left (robot names), right, top (title, line labels), bottom (axis, legend)
MARGINS_IN = (1.0, 0.35, 0.6, 0.85)
#: a bar's height as a share of its row
BAR_SHARE = 0.6
#: the time axis runs this much past the latest of the cycle and the bound (room for labels)
X_PAD = 1.1
#: font size (pt) of the labels on bars; a label is put on a bar when its estimated width
#: (CHAR_EM * size per character) fits inside the bar
LABEL_PT = 7.0
CHAR_EM = 0.62


@dataclass(frozen=True)
class GanttSvg:
    """An SVG chart and where its time axis lies on it.

    Attributes
    ----------
    svg
        The ``<svg>`` element (no XML prologue), to inline in a page.
    t_max
        s at the axis's right end (it starts at 0).
    x0, x1
        The axis's left and right ends as shares of the picture's width (0: its left edge).
    y0, y1
        The axis box's top and bottom as shares of the picture's height (0: its top edge).
    """

    svg: str
    t_max: float
    x0: float
    x1: float
    y0: float
    y1: float

    def x_of(self, t: float) -> float:
        """Share of the picture's width at station time ``t`` s."""
        return self.x0 + (self.x1 - self.x0) * float(t) / self.t_max


def _plt() -> Any:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def gantt_figure(schedule: Any, *, bound: float | None = None, title: str | None = None) -> Any:
    """The matplotlib figure of the chart (module docstring); the caller closes it.

    Parameters
    ----------
    schedule
        The :class:`~weldplan.multi.schedule.StationSchedule`.
    bound
        s: the allocation's lower bound on the cycle time (a dashed line), or None.
    title
        Above the chart; default: the robots' count and the cycle time.
    """
    plt = _plt()
    n = max(len(schedule.robots), 1)
    left, right, top, bottom = MARGINS_IN
    height = top + bottom + ROW_IN * n
    fig = plt.figure(figsize=(WIDTH_IN, height), dpi=DPI)
    ax = fig.add_axes(
        (left / WIDTH_IN, bottom / height, 1 - (left + right) / WIDTH_IN, ROW_IN * n / height)
    )
    cycle = float(schedule.cycle_time)
    t_max = X_PAD * max(cycle, bound or 0.0) or 1.0
    ax.set_xlim(0.0, t_max)
    ax.set_ylim(-0.5, n - 0.5)
    pt_per_s = (WIDTH_IN - left - right) * 72.0 / t_max
    for r in range(len(schedule.robots)):
        _draw_row(ax, schedule, r, n - 1 - r, pt_per_s)
    ax.set_yticks([n - 1 - r for r in range(len(schedule.robots))], list(schedule.robots))
    ax.set_xlabel("station time (s)")
    ax.grid(axis="x", color="#DDDDDD", linewidth=0.6)
    ax.set_axisbelow(True)
    _draw_lines(ax, cycle, bound)
    _legend(fig, bound is not None)
    if title is None:
        title = f"station schedule: {len(schedule.robots)} robots, cycle {cycle:.2f} s"
    fig.suptitle(title, y=1 - 0.12 / height, va="top", fontsize=11)
    return fig


def _draw_row(ax: Any, schedule: Any, r: int, y: float, pt_per_s: float) -> None:
    """Robot ``r``'s bars at row ``y``, their labels, and its end."""
    acts = schedule.of(r)
    h = BAR_SHARE
    for kind, color in KIND_COLORS.items():
        spans = _merged([(a.start, a.end) for a in acts if a.kind == kind and a.duration > 0])
        if spans:
            ax.broken_barh(spans, (y - h / 2, h), facecolors=color, linewidth=0)
    for a in acts:
        if a.kind == "move" or not a.label or a.duration <= 0:
            continue
        fits = len(a.label) * CHAR_EM * LABEL_PT <= a.duration * pt_per_s
        mid = (a.start + a.end) / 2
        if fits:
            ax.text(mid, y, a.label, ha="center", va="center", fontsize=LABEL_PT, clip_on=True)
        elif a.kind == "wait":  # an interlock's name is always shown: over its bar
            ax.text(mid, y + h / 2, a.label, ha="center", va="bottom", fontsize=LABEL_PT - 1)
    end = schedule.cycle_times[r]
    text = "idle" if not acts else f"{end:.2f} s"
    ax.text(end, y, " " + text, ha="left", va="center", fontsize=LABEL_PT + 1)


def _merged(spans: list[tuple[float, float]]) -> list[tuple[float, float]]:
    """``(start, width)`` of ``spans`` ``(start, end)`` (s, in time order) with the ones that
    touch joined: a robot's moves through its via stops are one bar (no seams between them)."""
    out: list[list[float]] = []
    for a, b in spans:
        if out and a <= out[-1][1] + 1e-9:
            out[-1][1] = max(out[-1][1], b)
        else:
            out.append([a, b])
    return [(a, b - a) for a, b in out]


def _draw_lines(ax: Any, cycle: float, bound: float | None) -> None:
    """The cycle time (solid) and the lower bound (dashed), labelled over the axis box."""
    ax.axvline(cycle, color=CYCLE_COLOR, linewidth=1.4)
    ax.text(cycle, 1.01, f"cycle {cycle:.2f} s", transform=ax.get_xaxis_transform(),
            ha="left", va="bottom", fontsize=8, color=CYCLE_COLOR)  # fmt: skip
    if bound is not None:
        ax.axvline(bound, color=BOUND_COLOR, linewidth=1.4, linestyle=(0, (4, 3)))
        ax.text(bound, 1.01, f"bound {bound:.2f} s ", transform=ax.get_xaxis_transform(),
                ha="right", va="bottom", fontsize=8, color=BOUND_COLOR)  # fmt: skip


def _legend(fig: Any, with_bound: bool) -> None:
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    handles = [Patch(facecolor=c, label=k) for k, c in KIND_COLORS.items()]
    handles.append(Line2D([], [], color=CYCLE_COLOR, linewidth=1.4, label="station cycle"))
    if with_bound:
        handles.append(
            Line2D(
                [], [], color=BOUND_COLOR, linewidth=1.4, linestyle=(0, (4, 3)), label="lower bound"
            )  # fmt: skip
        )
    fig.legend(handles=handles, loc="lower center", ncol=len(handles), frameon=False,
               fontsize=8, bbox_to_anchor=(0.5, 0.0))  # fmt: skip


def gantt_png_bytes(
    schedule: Any, *, bound: float | None = None, title: str | None = None
) -> bytes:
    """The chart as PNG bytes (:func:`gantt_figure`), the same bytes for the same schedule."""
    plt = _plt()
    fig = gantt_figure(schedule, bound=bound, title=title)
    out = io.BytesIO()
    try:
        fig.savefig(out, format="png", dpi=DPI, metadata={"Software": None})
    finally:
        plt.close(fig)
    return out.getvalue()


def gantt_png(
    schedule: Any,
    path: str | PathLike[str],
    *,
    bound: float | None = None,
    title: str | None = None,
) -> Path:
    """Write the chart to PNG ``path``, whole or not at all; returns the path.

    ``(WIDTH_IN * DPI)`` pixels wide, ``ROW_IN * DPI`` pixels a robot plus the margins high."""
    from weldplan.io.outputset import write_outputs

    path = Path(path)
    write_outputs({path: gantt_png_bytes(schedule, bound=bound, title=title)})
    return path


def gantt_svg(schedule: Any, *, bound: float | None = None, title: str | None = None) -> GanttSvg:
    """The chart as an inline SVG and its time axis's place on it (:class:`GanttSvg`); the same
    text for the same schedule (fixed ids, no date; the text as SVG text, in the page's font)."""
    import matplotlib

    plt = _plt()
    with matplotlib.rc_context({"svg.hashsalt": "weldplan-gantt", "svg.fonttype": "none"}):
        fig = gantt_figure(schedule, bound=bound, title=title)
        ax = fig.axes[0]
        box = ax.get_position()
        t_max = float(ax.get_xlim()[1])
        out = io.StringIO()
        try:
            fig.savefig(out, format="svg", metadata={"Date": None, "Creator": None})
        finally:
            plt.close(fig)
    text = out.getvalue()
    svg = text[text.index("<svg") :]
    return GanttSvg(svg, t_max, float(box.x0), float(box.x1), 1 - float(box.y1), 1 - float(box.y0))


def bar_rows(schedule: Any) -> list[tuple[int, float, float]]:
    """``(robot, top share, bottom share)`` of each robot's bars on the picture's height (0:
    the top edge), for tests and pages that look for a robot's row."""
    n = max(len(schedule.robots), 1)
    left, right, top, bottom = MARGINS_IN
    height = top + bottom + ROW_IN * n
    out = []
    for r in range(len(schedule.robots)):
        y = n - 1 - r  # data units, row centre; the axis spans -0.5 .. n - 0.5
        centre = top + ROW_IN * (n - 0.5 - y)
        half = ROW_IN * BAR_SHARE / 2
        out.append((r, (centre - half) / height, (centre + half) / height))
    return out
