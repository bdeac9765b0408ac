"""How :func:`~weldplan.weld.cell.build_cell` models a cell: one frozen, validated settings
object (../shared/DESIGN.md: a stage takes its inputs and one settings object).

The grid (pitch, clearance, margin, region of interest), the virtual joints' search (radius,
approach cone), the input check (the largest joint-to-part distance) and the spots' depth: the
library's side of a station's :class:`weldplan.station.settings.CellSettings` (its ``[cell]``
table and options), which :func:`weldplan.station.pipeline.cell_stage` maps onto this. A
bad value is an :class:`~weldplan.errors.InputError` naming the setting, raised once, when the
settings are made: the cell's settings come from the user's input (the CLI's options, a
station file's ``[cell]`` table), and their messages are those of
:class:`weldplan.weld.pipeline.PlanConfig`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, TypedDict

import numpy as np
from numpy.typing import ArrayLike

from weldplan.errors import InputError
from weldplan.geometry.grid import DEFAULT_CLEARANCE, DEFAULT_MARGIN, DEFAULT_PITCH
from weldplan.weld.validate import _is_real
from weldplan.weld.virtual import _SEARCH_FACTOR, APPROACH_CONE_DEG

#: floor (mm) of the default largest distance from a joint to the part's surface
JOINT_DISTANCE_MIN_MM = 20.0


def default_max_joint_distance(
    clearance: float, pitch: float, search_radius: float | None = None
) -> float:
    """Default largest distance (mm) from a weld joint to the part's surface.

    A weld joint lies on the part; its approach runs to a virtual joint at most the search
    radius away (``4 * (clearance + pitch)``, 40 mm at 5/5 mm, or ``search_radius`` when
    given). A joint farther from the surface than that, and than :data:`JOINT_DISTANCE_MIN_MM`,
    belongs to another part, another unit or another scale. On the committed sets the farthest
    joint is 0.13 mm off car2's surface (1000-joint set) and 3e-5 mm off the demo part.
    """
    radius = _SEARCH_FACTOR * (clearance + pitch) if search_radius is None else search_radius
    return float(max(JOINT_DISTANCE_MIN_MM, radius))


@dataclass(frozen=True)
class CellBuildSettings:
    """The settings of :func:`~weldplan.weld.cell.build_cell`.

    Attributes
    ----------
    pitch, clearance, margin, region
        Grid settings, mm (see :func:`weldplan.geometry.grid.build_grid`).
    search_radius, approach_cone
        The virtual joints' search radius (mm; ``None``: ``4 (clearance + pitch)``) and cone
        about a joint's approach direction (deg), see :func:`weldplan.weld.virtual.virtual_joints`.
    max_joint_distance
        Largest distance (mm) from a joint to the part's surface; ``None``:
        :func:`default_max_joint_distance` (40 mm at the default clearance and pitch), see
        :attr:`joint_distance_limit`.
    spot_depth
        mm (>= 0, below the surface along the approach): :attr:`Cell.spot_depth`.
    """

    pitch: float = DEFAULT_PITCH
    clearance: float = DEFAULT_CLEARANCE
    margin: float = DEFAULT_MARGIN
    region: str | ArrayLike = "joints"
    search_radius: float | None = None
    approach_cone: float = APPROACH_CONE_DEG
    max_joint_distance: float | None = None
    spot_depth: float = 0.0

    def __post_init__(self) -> None:
        put = object.__setattr__
        put(self, "pitch", _positive_mm("pitch", self.pitch))
        put(self, "clearance", _positive_mm("clearance", self.clearance))
        margin = _finite_mm("margin", self.margin, minimum=0.0, text="margin must be >= 0 mm")
        put(self, "margin", margin)
        if self.search_radius is not None:
            put(self, "search_radius", _positive_mm("search_radius", self.search_radius))
        if self.max_joint_distance is not None:
            limit = _positive_mm("max_joint_distance", self.max_joint_distance)
            put(self, "max_joint_distance", limit)
        depth = _finite_mm(
            "spot_depth", self.spot_depth, minimum=0.0, text="spot_depth must be >= 0 mm"
        )
        put(self, "spot_depth", depth)

    @property
    def joint_distance_limit(self) -> float:
        """mm: :attr:`max_joint_distance`, or its default for this pitch, clearance and radius."""
        if self.max_joint_distance is not None:
            return float(self.max_joint_distance)
        return default_max_joint_distance(self.clearance, self.pitch, self.search_radius)


class CellBuildOptions(TypedDict, total=False):
    """The keyword conveniences of :func:`~weldplan.weld.cell.build_cell`: any
    :class:`CellBuildSettings` field by name."""

    pitch: float
    clearance: float
    margin: float
    region: str | ArrayLike
    search_radius: float | None
    approach_cone: float
    max_joint_distance: float | None
    spot_depth: float


def _finite_mm(name: str, value: Any, *, minimum: float, text: str) -> float:
    # a number, not something float() happens to accept ("5", True): the API says what it takes
    v = float(value) if _is_real(value) else float("nan")
    if not (np.isfinite(v) and v >= minimum):
        raise InputError(f"{text}, got {value}", field=name)
    return v


def _positive_mm(name: str, value: Any) -> float:
    """The messages of :class:`weldplan.weld.pipeline.PlanConfig`, as InputErrors."""
    v = _finite_mm(name, value, minimum=0.0, text=f"{name} must be a positive number of mm")
    if v == 0:
        raise InputError(f"{name} must be a positive number of mm, got {value}", field=name)
    return v
