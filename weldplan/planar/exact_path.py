"""The answer of the exact planar planners (:mod:`weldplan.planar.visibility`,
:mod:`weldplan.planar.grid_astar`): a shortest path, its length and how it was found.
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass

import numpy as np
from numpy.typing import NDArray


@dataclass(frozen=True)
class ExactPath:
    """A shortest path found by an exact planner.

    Attributes
    ----------
    points
        ``((n, 2))`` waypoints from start to goal (map units; cell centres for grids).
    length
        Its length.
    method
        ``"visibility-graph"`` or ``"astar-8"``.
    expanded
        Nodes of the graph (visibility graph) or cells expanded (A*).
    """

    points: tuple[tuple[float, float], ...]
    length: float
    method: str
    expanded: int = 0

    @property
    def points_array(self) -> NDArray[np.float64]:
        return np.asarray(self.points, dtype=np.float64).reshape(-1, 2)

    def to_json(self) -> str:
        return json.dumps(asdict(self))

    @classmethod
    def from_json(cls, text: str) -> ExactPath:
        d = json.loads(text)
        d["points"] = tuple(tuple(p) for p in d["points"])
        return cls(**d)
