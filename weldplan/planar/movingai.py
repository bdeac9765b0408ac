"""Readers for the Moving AI grid benchmarks: ``.map`` occupancy grids and ``.scen`` query files."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from weldplan.errors import InputError

MOVINGAI_PASSABLE = frozenset(".GS")


def read_movingai_map(path: str | Path) -> NDArray[np.bool_]:
    """Traversable cells of a Moving AI ``.map`` file: ``(width, height) bool`` indexed
    ``[x, y]`` with y the row as written (``.``, ``G`` and ``S`` are traversable)."""
    path = Path(path)
    lines = path.read_text().splitlines()
    try:
        h = int(lines[1].split()[1])
        w = int(lines[2].split()[1])
    except (IndexError, ValueError):
        raise InputError(
            "expected 'height H' and 'width W' header lines", path=path, line=2
        ) from None
    rows = lines[4 : 4 + h]
    if len(rows) != h or any(len(r) < w for r in rows):
        raise InputError(f"expected {h} rows of {w} cells", path=path, line=5)
    grid = np.array([[c in MOVINGAI_PASSABLE for c in r[:w]] for r in rows], dtype=bool)
    return grid.T


@dataclass(frozen=True)
class ScenarioSet:
    """Queries of a Moving AI ``.scen`` file: ``start, goal (n, 2) int`` as ``(x, y)``,
    ``length (n,)`` optimal octile lengths, ``bucket (n,)``."""

    start: NDArray[np.int64]
    goal: NDArray[np.int64]
    length: NDArray[np.float64]
    bucket: NDArray[np.int64]


def read_scen(path: str | Path) -> ScenarioSet:
    """Read a Moving AI ``.scen`` file (version 1)."""
    path = Path(path)
    rows = []
    for k, line in enumerate(path.read_text().splitlines(), 1):
        if not line.strip() or line.startswith("version"):
            continue
        f = line.split("\t") if "\t" in line else line.split()
        if len(f) < 9:
            raise InputError("expected 9 fields", path=path, line=k)
        try:
            rows.append((int(f[0]), int(f[4]), int(f[5]), int(f[6]), int(f[7]), float(f[8])))
        except ValueError:
            raise InputError("bad number", path=path, line=k) from None
    a = np.array(rows, dtype=np.float64).reshape(-1, 6)
    return ScenarioSet(
        start=a[:, 1:3].astype(np.int64),
        goal=a[:, 3:5].astype(np.int64),
        length=a[:, 5],
        bucket=a[:, 0].astype(np.int64),
    )
