"""Matplotlib figures of planar scenarios, paths and convergence (Agg backend, files only).

Consumes results; no algorithm imports this module.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike


def _plt():  # imported where used: plotting is optional at runtime
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def draw_scenario(ax, scenario) -> None:
    """Obstacles, bounds, start and goal of a scenario on a matplotlib axis."""
    from matplotlib.patches import Circle, Polygon, Rectangle

    o = scenario.obstacles
    style = {"facecolor": "#9db4d6", "edgecolor": "#3a5a8c", "linewidth": 0.6}
    if scenario.grid is not None:
        g = scenario.grid
        nx, ny = g.shape
        ax.imshow(
            g.occupied.T,
            origin="lower",
            cmap="Greys",
            alpha=0.6,
            extent=(g.origin[0], g.origin[0] + nx * g.cell, g.origin[1], g.origin[1] + ny * g.cell),
        )
    else:
        for x0, y0, x1, y1 in o.rectangles:
            ax.add_patch(Rectangle((x0, y0), x1 - x0, y1 - y0, **style))
    for x, y, r in o.circles:
        ax.add_patch(Circle((x, y), r, **style))
    for p in o.polygons:
        ax.add_patch(Polygon(p, closed=True, **style))
    b = scenario.bounds
    ax.plot([b[0], b[2], b[2], b[0], b[0]], [b[1], b[1], b[3], b[3], b[1]], "k-", lw=0.8)
    ax.plot(*scenario.start, marker="D", color="gold", mec="k", ms=7, zorder=5)
    ax.plot(*scenario.goal, marker="D", color="gold", mec="k", ms=7, zorder=5)
    ax.set_aspect("equal")
    ax.set_xlim(b[0] - 0.5, b[2] + 0.5)
    ax.set_ylim(b[1] - 0.5, b[3] + 0.5)


def plot_paths(
    scenario,
    paths: Mapping[str, ArrayLike],
    path: str | Path,
    *,
    exact: ArrayLike | None = None,
    title: str | None = None,
) -> Path:
    """Save a figure of the scenario with named paths ``(n, 2)`` (and the exact one dashed)."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(6, 6))
    draw_scenario(ax, scenario)
    if exact is not None:
        e = np.asarray(exact)
        ax.plot(e[:, 0], e[:, 1], "k--", lw=1.2, label="exact optimum")
    for name, pts in paths.items():
        p = np.asarray(pts)
        ax.plot(p[:, 0], p[:, 1], lw=1.4, label=name)
    ax.legend(fontsize=7, loc="upper left")
    ax.set_title(title or scenario.name)
    out = Path(path)
    fig.savefig(out, dpi=110, bbox_inches="tight")
    plt.close(fig)
    return out


def plot_convergence(
    histories: Mapping[str, Sequence[float]],
    path: str | Path,
    *,
    title: str = "",
    optimum: float | None = None,
    ylabel: str = "best fitness",
) -> Path:
    """Save convergence curves (mean over runs per name) as a PNG."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(6, 4))
    for name, h in histories.items():
        h = np.asarray(h, dtype=float)
        ax.plot(np.arange(len(h)), h, lw=1.3, label=name)
    if optimum is not None:
        ax.axhline(optimum, color="k", ls="--", lw=1, label="exact optimum")
    ax.set_xlabel("iteration")
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.legend(fontsize=7)
    out = Path(path)
    fig.savefig(out, dpi=110, bbox_inches="tight")
    plt.close(fig)
    return out
