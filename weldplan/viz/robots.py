"""Figures of multi-robot runs on grids: a PNG of the paths and a GIF animation (Agg, files)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from weldplan.viz.planar import _plt

COLOURS = ("tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple", "tab:brown")


def _base(ax, scenario: Any) -> None:
    g = scenario.grid
    nx, ny = g.shape
    x0, y0 = g.origin
    ext = (x0, x0 + nx * g.cell, y0, y0 + ny * g.cell)
    ax.imshow(g.occupied.T, origin="lower", cmap="Greys", alpha=0.6, extent=ext)
    ax.set_aspect("equal")


def plot_robots(scenario: Any, run: Any, path: str | Path) -> Path:
    """PNG: global paths dashed, driven paths solid, starts (squares) and goals (stars)."""
    plt = _plt()
    g = scenario.grid
    fig, ax = plt.subplots(figsize=(6, 6))
    _base(ax, scenario)
    for k, (drv, glob) in enumerate(zip(run.paths, run.global_paths, strict=True)):
        c = COLOURS[k % len(COLOURS)]
        G = g.centre(np.array(glob))
        D = g.centre(np.array(drv))
        ax.plot(G[:, 0], G[:, 1], "--", color=c, lw=1.0, alpha=0.7)
        lab = f"robot {k}: arrives at step {run.arrival[k]}, {run.replans[k]} replans"
        ax.plot(D[:, 0], D[:, 1], "-", color=c, lw=2.0, label=lab)
        ax.plot(*D[0], "s", color=c, mec="k", ms=8)
        ax.plot(*D[-1], "*", color=c, mec="k", ms=12)
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    ax.set_title(f"{scenario.name}: min distance {min(run.min_distance):.2f} > {run.safety:g}")
    out = Path(path)
    fig.savefig(out, dpi=110, bbox_inches="tight")
    plt.close(fig)
    return out


def animate_robots(scenario: Any, run: Any, path: str | Path, fps: int = 4) -> Path:
    """GIF: the robots step by step with their safety circles and trails."""
    plt = _plt()
    from matplotlib.animation import FuncAnimation, PillowWriter
    from matplotlib.patches import Circle

    g = scenario.grid
    fig, ax = plt.subplots(figsize=(5, 5))
    _base(ax, scenario)
    P = [g.centre(np.array(p)) for p in run.paths]
    dots, trails, rings = [], [], []
    for k in range(len(P)):
        c = COLOURS[k % len(COLOURS)]
        (t,) = ax.plot([], [], "-", color=c, lw=1.5)
        (d,) = ax.plot([], [], "o", color=c, mec="k", ms=8)
        r = Circle(tuple(P[k][0]), run.safety / 2, fill=False, color=c, lw=0.8)
        ax.add_patch(r)
        trails.append(t)
        dots.append(d)
        rings.append(r)
    n = max(len(p) for p in P)

    def frame(i: int):
        for k, p in enumerate(P):
            j = min(i, len(p) - 1)
            trails[k].set_data(p[: j + 1, 0], p[: j + 1, 1])
            dots[k].set_data([p[j, 0]], [p[j, 1]])
            rings[k].center = tuple(p[j])
        ax.set_title(
            f"step {i}, min distance {run.min_distance[min(i, len(run.min_distance) - 1)]:.2f}"
        )
        return [*trails, *dots, *rings]

    anim = FuncAnimation(fig, frame, frames=n, blit=False)
    out = Path(path)
    anim.save(out, writer=PillowWriter(fps=fps))
    plt.close(fig)
    return out
