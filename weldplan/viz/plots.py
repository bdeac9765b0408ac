"""Matplotlib plots of a planning run: convergence of the local planner and of the sequencer.

They consume results (a :class:`~weldplan.weld.route.Route` and its ``stats``); algorithms never
import this module. Use the Agg backend for files (``matplotlib.use("Agg")``) in headless runs.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from weldplan.weld.route import Route


def _axes(ax: Any = None) -> Any:
    if ax is not None:
        return ax
    import matplotlib.pyplot as plt

    _, ax = plt.subplots(figsize=(5, 3.2))
    return ax


def plot_convergence(
    history: Sequence[float],
    *,
    ax: Any = None,
    label: str | None = None,
    xlabel: str = "iteration",
    ylabel: str = "best length (mm)",
    reference: float | None = None,
    reference_label: str = "reference",
) -> Any:
    """Best-so-far value per iteration (a step line), with an optional reference level."""
    ax = _axes(ax)
    h = np.asarray(history, dtype=float)
    h = np.where(np.isfinite(h), h, np.nan)
    ax.step(np.arange(len(h)), h, where="post", label=label)
    if reference is not None and np.isfinite(reference):
        ax.axhline(reference, color="k", lw=0.8, ls="--", label=reference_label)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.grid(alpha=0.3)
    return ax


def plot_route_convergence(route: Route, *, max_pairs: int = 8) -> Any:
    """A figure with the local planner's convergence (per planned pair) and the sequencer's.

    Left: best path length per SO-ACO iteration for up to ``max_pairs`` planned pairs (relative
    to each pair's final length, so pairs of different lengths share an axis). Right: the
    sequencer's best open-path cost per swarm iteration, with the straight-line lower bound.
    """
    import matplotlib.pyplot as plt

    fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 3.6))
    local = route.stats.get("local_paths", {})
    shown = 0
    for pair, d in local.items():
        h = np.asarray(d.get("history") or [], dtype=float)
        if len(h) == 0 or not np.isfinite(d.get("length", np.nan)):
            continue
        plot_convergence(
            h / d["length"], ax=a1, label=f"{pair}", ylabel="best length / final length"
        )
        shown += 1
        if shown >= max_pairs:
            break
    a1.set_title(f"local planner ({route.settings.get('planner', '?')}), {len(local)} pairs")
    if shown:
        a1.legend(fontsize=7, ncol=2)
    else:
        a1.text(
            0.5,
            0.5,
            "no pair needed the planner\n(or no history recorded)",
            ha="center",
            va="center",
            transform=a1.transAxes,
        )
    hist = route.stats.get("sequence_history") or []
    if hist:
        plot_convergence(
            hist,
            ax=a2,
            label="swarm best",
            ylabel="open-path cost (mm)",
            reference=route.lower_bound,
            reference_label=f"lower bound ({route.lower_bound_method})",
        )
        a2.axhline(route.length, color="C3", lw=0.8, label="final route")
        a2.legend(fontsize=7)
    else:
        a2.text(
            0.5,
            0.5,
            f"sequencer: {route.stats.get('sequence_method', '?')}\n(no swarm)",
            ha="center",
            va="center",
            transform=a2.transAxes,
        )
    a2.set_title("sequencer")
    fig.tight_layout()
    return fig


def plot_leg_lengths(route: Route, *, ax: Any = None) -> Any:
    """Bar chart of the leg lengths in route order, planned legs hatched."""
    ax = _axes(ax)
    L = route.leg_lengths
    colors = ["C1" if leg.method != "straight" else "C0" for leg in route.legs]
    ax.bar(np.arange(len(L)), L, color=colors)
    ax.set_xticks(np.arange(len(L)))
    ax.set_xticklabels([f"{g.from_id}-{g.to_id}" for g in route.legs], rotation=90, fontsize=7)
    ax.set_ylabel("leg length (mm)")
    ax.set_title("legs (orange: planned around an obstacle)")
    return ax
