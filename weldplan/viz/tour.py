"""Figures of multi-goal tours on triangular-mesh maps (Agg backend, files only)."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from weldplan.viz.planar import _plt, draw_scenario


def plot_tour(
    task: Any,
    paths: Mapping[str, ArrayLike],
    path: str | Path,
    *,
    mesh: Any = None,
    title: str | None = None,
) -> Path:
    """Save the map (with its triangular mesh when given), the targets numbered, and named tour
    paths ``(n, 2)``."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(7, 7))
    if mesh is not None:
        ax.triplot(
            mesh.nodes[:, 0], mesh.nodes[:, 1], mesh.cells, color="#cccccc", lw=0.3, zorder=0
        )
    if task.scenario is not None:
        draw_scenario(ax, task.scenario)
    else:
        sp = task.space
        for a, b in zip(sp.edge_a, sp.edge_b, strict=True):
            ax.plot([a[0], b[0]], [a[1], b[1]], "k-", lw=0.8)
        ax.plot(*task.start, marker="D", color="gold", mec="k", ms=7, zorder=5)
        ax.set_aspect("equal")
    for k, (x, y) in enumerate(task.goals, start=1):
        ax.plot(x, y, "o", color="crimson", ms=5, zorder=6)
        ax.annotate(str(k), (x, y), textcoords="offset points", xytext=(4, 4), fontsize=7)
    for name, pts in paths.items():
        p = np.asarray(pts)
        ax.plot(p[:, 0], p[:, 1], lw=1.3, label=name, zorder=4)
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    ax.set_title(title or task.name)
    out = Path(path)
    fig.savefig(out, dpi=110, bbox_inches="tight")
    plt.close(fig)
    return out
