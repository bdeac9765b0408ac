"""Convergence plots of optimiser runs (consumes histories; algorithms never import this)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

#: values plotted on the log axis are floored here, so exact zeros (SMA on Sphere) stay visible
#: and the curves above the floor keep a readable scale
LOG_FLOOR = 1e-30


def plot_convergence(
    histories: Mapping[str, Sequence[Sequence[float]]],
    path: str | Path,
    *,
    title: str = "",
    xlabel: str = "iteration",
    floor: float = LOG_FLOOR,
) -> Path:
    """Median best-so-far curve (and the 25-75 % band) per algorithm on a log scale, to a PNG.

    Parameters
    ----------
    histories
        algorithm name -> list of runs, each a best-so-far history ``(n_iter + 1,)``; runs may
        differ in length (they are cut to the shortest).
    path
        Output PNG file.
    floor
        Values below this are drawn at it (the axis label says so).
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8.5, 4.8))
    colors = plt.get_cmap("tab20").colors
    styles = ("-", "--", "-.", ":")
    for k, (name, runs) in enumerate(histories.items()):
        n = min(len(h) for h in runs)
        H = np.maximum(np.array([np.asarray(h[:n], dtype=float) for h in runs]), floor)
        H = np.where(np.isfinite(H), H, np.nan)
        med = np.nanmedian(H, axis=0)
        x = np.arange(n)
        (line,) = ax.semilogy(
            x, med, label=name, lw=1.4, color=colors[k % 20], ls=styles[(k // 10) % 4]
        )
        if H.shape[0] > 1:
            lo, hi = np.nanpercentile(H, [25, 75], axis=0)
            ax.fill_between(x, lo, hi, color=line.get_color(), alpha=0.15, lw=0)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(f"best value so far (median, 25-75 %; floor {floor:g})")
    ax.set_title(title)
    ax.grid(True, which="major", alpha=0.3)
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)
    fig.tight_layout()
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return out
