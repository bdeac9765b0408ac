"""The planned torch route: ordered legs from weld joint to weld joint, in mm.

A :class:`Route` is what ``weldplan plan`` produces and everything downstream consumes: the
verifier (:mod:`weldplan.weld.verify`), the exports (:mod:`weldplan.io.export`), the viewer
(:mod:`weldplan.viz.viewer`). It is a frozen dataclass with a JSON round trip, so a route can be
saved, re-verified and exported later without the cell that produced it.

Data flows one way (model -> planning -> route -> export/view): this module imports neither the
exports nor the viewer. Write and show a route with their functions::

    from weldplan.io.export import read_route, write_csv, write_json, write_post
    write_csv(route, "route.csv"); write_json(route, "route.json")
    write_post(route, "route.mod", "rapid", part=cell)
    weldplan.viz.show(route, cell)          # inline 3D view in Jupyter

Leg convention
--------------
Each :class:`Leg` runs from real joint ``from_id`` to real joint ``to_id`` through waypoints::

    points[0]   the weld spot of ``from_id`` (on the part's surface)
    points[1]   its virtual joint (nearest free voxel centre)      <- approach segment 0 -> 1
    ...         via points of the local path (all free at clearance)
    points[-2]  the virtual joint of ``to_id``
    points[-1]  the weld spot of ``to_id``                           <- approach segment -2 -> -1

The first and the last segment are the *approach segments*: the only segments that may touch
the part (see :func:`weldplan.weld.verify.verify_route` for exactly how they are checked).
"""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, TypeVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from weldplan.geometry.pathcore import polyline_length as _polyline_length

_View = TypeVar("_View")

#: format tag written into the JSON, bumped when the layout changes
ROUTE_FORMAT = "weldplan.route/1"


def _points(a: ArrayLike) -> NDArray[np.float64]:
    P = np.array(a, dtype=np.float64).reshape(-1, 3)
    P.setflags(write=False)
    return P


def polyline_length(points: ArrayLike) -> float:
    """Length (mm) of the polyline ``points (k, 3)``: the sum of its segment lengths."""
    return _polyline_length(np.asarray(points, dtype=np.float64).reshape(-1, 3))


@dataclass(frozen=True, eq=False)
class Leg:
    """One leg of a route: from a weld joint to the next, through free waypoints.

    Attributes
    ----------
    from_id, to_id
        Joint ids (as in the joints CSV).
    points
        ``(k, 3) float`` mm, ``k >= 2``: weld spot, virtual joint, vias, virtual joint, weld spot
        (module docstring). Read-only.
    method
        How the middle of the leg was found: ``"straight"`` (the segment between the two
        virtual joints was free), ``"so-aco"``, ``"aco"`` or ``"exact"``.
    length
        Polyline length in mm (computed from ``points`` when not given).
    smooth
        ``(m, 3) float`` mm or ``None``: the smooth path of the leg (``weldplan plan --smooth``,
        :func:`weldplan.weld.smoothing.smooth_route`): the same weld spots and approach segments
        as ``points``, and between the virtual joints dense waypoints on a C2 curve, every chord
        checked at the clearance. ``None`` when the leg was not smoothed (its polyline is the
        path). Read-only.
    """

    from_id: str
    to_id: str
    points: NDArray[np.float64]
    method: str = "straight"
    length: float = float("nan")
    smooth: NDArray[np.float64] | None = None

    def __post_init__(self) -> None:
        P = _points(self.points)
        if len(P) < 2:
            raise ValueError(f"leg {self.from_id}->{self.to_id}: needs at least 2 points")
        object.__setattr__(self, "points", P)
        if self.smooth is not None:
            S = _points(self.smooth)
            if len(S) < 2:
                raise ValueError(f"leg {self.from_id}->{self.to_id}: a smooth path needs 2 points")
            object.__setattr__(self, "smooth", S)
        object.__setattr__(self, "from_id", str(self.from_id))
        object.__setattr__(self, "to_id", str(self.to_id))
        if not np.isfinite(self.length):
            object.__setattr__(self, "length", polyline_length(P))
        else:
            object.__setattr__(self, "length", float(self.length))

    @property
    def n_segments(self) -> int:
        return len(self.points) - 1

    @property
    def vias(self) -> NDArray[np.float64]:
        """``(k - 2, 3)`` the waypoints strictly between the two weld spots."""
        return self.points[1:-1]

    @property
    def path(self) -> NDArray[np.float64]:
        """``(m, 3)`` the points the torch travels: :attr:`smooth` when the leg has one, else
        :attr:`points`."""
        return self.points if self.smooth is None else self.smooth

    @property
    def smooth_length(self) -> float:
        """mm along :attr:`path` (the polyline length when the leg is not smoothed)."""
        return self.length if self.smooth is None else polyline_length(self.smooth)

    def reversed(self) -> Leg:
        """The same leg travelled the other way."""
        smooth = None if self.smooth is None else self.smooth[::-1]
        return Leg(self.to_id, self.from_id, self.points[::-1], self.method, self.length, smooth)

    def to_dict(self) -> dict[str, Any]:
        d: dict[str, Any] = {
            "from": self.from_id,
            "to": self.to_id,
            "method": self.method,
            "length": self.length,
            "points": self.points.tolist(),
        }
        if self.smooth is not None:
            d["smooth"] = self.smooth.tolist()
        return d

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> Leg:
        length = d.get("length")
        smooth = d.get("smooth")
        return cls(
            d["from"],
            d["to"],
            np.asarray(d["points"], dtype=float),
            d.get("method", "straight"),
            float("nan") if length is None else float(length),
            None if smooth is None else np.asarray(smooth, dtype=float),
        )


@dataclass(frozen=True)
class Route:
    """An ordered, collision-free torch route through every weld joint of a cell.

    Attributes
    ----------
    order
        Joint ids in visiting order (each joint exactly once).
    legs
        ``len(order) - 1`` legs, leg ``k`` from ``order[k]`` to ``order[k + 1]``.
    joint_ids
        Every joint id of the cell, in the order of its joints CSV.
    joint_xyz
        ``(n, 3) float`` mm, the weld spots, rows matching ``joint_ids``.
    directions
        ``(n, 3) float`` unit tool directions from the joints CSV, or ``None``.
    virtual_xyz
        ``(n, 3) float`` mm, the virtual joints (nearest free voxel centres), or ``None``.
    lower_bound
        mm, a lower bound on the open path over straight-line distances between the weld spots
        (no obstacles, no approach): no route through these joints can be shorter.
    lower_bound_method
        ``"held-karp"`` (that path's exact optimum, up to 16 joints), ``"1-tree"`` (Held and
        Karp's 1-tree bound with subgradient ascent, for larger cells: typically 1-2 % below the
        optimum) or ``"mst"`` (minimum spanning tree, the weakest; old routes).
    settings
        The :class:`~weldplan.weld.pipeline.PlanConfig` that produced the route, as a dict.
    seed
        The integer seed when one was given, else ``None``.
    stats
        Figures of the run (pairs planned, pairs blocked, seconds per stage, sequencer history ...).
    provenance
        What the route was planned against (:attr:`weldplan.weld.cell.Cell.provenance`):
        ``mesh`` (``geometry_sha256`` of the part in mm, ``file``, ``file_sha256``, ``units``,
        ``scale``, ``repairs``), ``joints``, ``clearance`` and ``pitch``.
        :func:`~weldplan.weld.verify.verify_route` refuses to check the route against another
        mesh, scale or clearance. Empty in routes written before it existed.
    tool
        Empty for the point-tip route; with a tool (``weldplan plan --tool``): ``provenance``
        (:func:`weldplan.tool.model.load_tool`: files, sha256, TCP, units) and ``poses``
        (:meth:`weldplan.tool.poses.WeldPoses.to_dict`: a pose or the closest miss per weld, in
        route order), ``transitions`` and, with a robot, ``robot``: the route JSON's section as
        written. The stages above read it typed, never as a dict:
        :class:`weldplan.tool.section.ToolSection` (the tool stage's keys) and
        :class:`weldplan.robot.program.ToolRoute` (the whole section), each read once per
        route (:meth:`tool_view`). Written to the JSON only when not empty.
    """

    order: tuple[str, ...]
    legs: tuple[Leg, ...]
    joint_ids: tuple[str, ...]
    joint_xyz: NDArray[np.float64]
    directions: NDArray[np.float64] | None = None
    virtual_xyz: NDArray[np.float64] | None = None
    lower_bound: float = float("nan")
    lower_bound_method: str = ""
    settings: dict[str, Any] = field(default_factory=dict)
    seed: int | None = None
    stats: dict[str, Any] = field(default_factory=dict)
    provenance: dict[str, Any] = field(default_factory=dict)
    tool: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        object.__setattr__(self, "provenance", dict(self.provenance or {}))
        object.__setattr__(self, "tool", dict(self.tool or {}))
        object.__setattr__(self, "order", tuple(str(i) for i in self.order))
        object.__setattr__(self, "legs", tuple(self.legs))
        object.__setattr__(self, "joint_ids", tuple(str(i) for i in self.joint_ids))
        object.__setattr__(self, "joint_xyz", _points(self.joint_xyz))
        if self.directions is not None:
            object.__setattr__(self, "directions", _points(self.directions))
        if self.virtual_xyz is not None:
            object.__setattr__(self, "virtual_xyz", _points(self.virtual_xyz))
        if len(self.joint_xyz) != len(self.joint_ids):
            raise ValueError("joint_xyz must have one row per joint id")
        if len(self.legs) != max(len(self.order) - 1, 0):
            raise ValueError("a route over k joints has k - 1 legs")
        for k, leg in enumerate(self.legs):
            if (leg.from_id, leg.to_id) != (self.order[k], self.order[k + 1]):
                raise ValueError(
                    f"leg {k} runs {leg.from_id}->{leg.to_id}, "
                    f"the order says {self.order[k]}->{self.order[k + 1]}"
                )

    def tool_view(self, read: Callable[[Route], _View]) -> _View:
        """``read(self)``, computed once per route: the typed view of the ``tool`` section that
        ``read`` builds (:meth:`weldplan.tool.section.ToolSection.of`,
        :meth:`weldplan.robot.program.ToolRoute.of`; the typed views live in the layers above
        this one, which cannot import them).

        Kept beside the route's fields as :func:`functools.cached_property` keeps its values
        (the instance's ``__dict__``): not a field, so not compared, not serialised and not
        carried by :func:`dataclasses.replace`, whose new route reads its own section again.
        The route is frozen and its section is never changed in place, so the view stays the
        section's. A ``read`` that raises caches nothing.
        """
        views: dict[Callable[[Route], Any], Any] = self.__dict__.setdefault("_tool_views", {})
        if read not in views:
            views[read] = read(self)
        return views[read]

    # ------------------------------------------------------------------ figures
    @property
    def length(self) -> float:
        """Total length in mm (the sum of the leg lengths)."""
        return float(sum(leg.length for leg in self.legs))

    @property
    def leg_lengths(self) -> NDArray[np.float64]:
        """``(len(legs),) float`` mm."""
        return np.array([leg.length for leg in self.legs], dtype=float)

    def is_virtual(self, joint_id: str, p: ArrayLike, tol: float = 1e-3) -> bool:
        """Whether point ``p`` (3,) is the virtual joint of ``joint_id`` (within ``tol`` mm)."""
        if self.virtual_xyz is None or joint_id not in self.joint_ids:
            return False
        v = self.virtual_xyz[self.index_of(joint_id)]
        return bool(np.linalg.norm(v - np.asarray(p, dtype=float)) <= tol)

    def approach_flags(self, k: int) -> tuple[bool, bool]:
        """Whether leg ``k`` starts and ends with an approach segment (spot <-> virtual joint).

        A spot that is its own virtual joint (a joint in free space) has no approach.
        """
        leg = self.legs[k]
        return (
            not self.is_virtual(leg.from_id, leg.points[0]),
            not self.is_virtual(leg.to_id, leg.points[-1]),
        )

    @property
    def approach_length(self) -> float:
        """mm of the route spent on approach segments (weld spot <-> its virtual joint)."""
        total = 0.0
        for k, leg in enumerate(self.legs):
            start, end = self.approach_flags(k)
            seg = np.linalg.norm(np.diff(leg.points, axis=0), axis=1)
            total += (seg[0] if start else 0.0) + (seg[-1] if end and len(seg) > 1 else 0.0)
        return float(total)

    @property
    def inner_length(self) -> float:
        """mm between virtual joints: :attr:`length` less the approaches (the paper's measure)."""
        return self.length - self.approach_length

    @property
    def gap(self) -> float:
        """Relative excess over the lower bound, ``length / lower_bound - 1`` (nan if unknown)."""
        if not np.isfinite(self.lower_bound) or self.lower_bound <= 0:
            return float("nan")
        return self.length / self.lower_bound - 1.0

    def index_of(self, joint_id: str) -> int:
        """Row of ``joint_id`` in :attr:`joint_xyz`."""
        return self.joint_ids.index(str(joint_id))

    def waypoints(self, smooth: bool = False) -> NDArray[np.float64]:
        """``(m, 3)`` the whole route as one polyline (shared weld spots not repeated).

        ``smooth=True``: each leg's :attr:`Leg.path` (its smooth waypoints where it has them)
        instead of its polyline.
        """
        if not self.legs:
            if self.order:
                return self.joint_xyz[[self.index_of(self.order[0])]]
            return np.zeros((0, 3))
        pts = [leg.path if smooth else leg.points for leg in self.legs]
        return np.concatenate([pts[0]] + [p[1:] for p in pts[1:]], axis=0)

    @property
    def has_smooth(self) -> bool:
        """Whether any leg carries a smooth path (``weldplan plan --smooth``)."""
        return any(leg.smooth is not None for leg in self.legs)

    @property
    def smooth_length(self) -> float:
        """mm along the legs' :attr:`Leg.path` (smooth where smoothed, else the polyline)."""
        return float(sum(leg.smooth_length for leg in self.legs))

    def table(self) -> list[dict[str, Any]]:
        """One dict per leg (step, from, to, method, via points, length mm) for display."""
        return [
            {
                "leg": k,
                "from": leg.from_id,
                "to": leg.to_id,
                "method": leg.method,
                "vias": len(leg.points) - 2,
                "length_mm": round(leg.length, 3),
            }
            for k, leg in enumerate(self.legs)
        ]

    def summary(self) -> dict[str, Any]:
        """The headline figures: joints, legs, length, lower bound, gap."""
        return {
            "joints": len(self.joint_ids),
            "legs": len(self.legs),
            "length_mm": round(self.length, 3),
            "inner_length_mm": round(self.inner_length, 3),
            "lower_bound_mm": round(self.lower_bound, 3),
            "lower_bound_method": self.lower_bound_method,
            "gap_percent": round(100 * self.gap, 3) if np.isfinite(self.gap) else None,
            "order": "-".join(self.order),
        }

    # ------------------------------------------------------------------ JSON
    def to_dict(self) -> dict[str, Any]:
        d: dict[str, Any] = {
            "format": ROUTE_FORMAT,
            "units": "mm",
            "order": list(self.order),
            "length": self.length,
            "lower_bound": self.lower_bound,
            "lower_bound_method": self.lower_bound_method,
            "joints": {
                "ids": list(self.joint_ids),
                "xyz": self.joint_xyz.tolist(),
                "directions": None if self.directions is None else self.directions.tolist(),
                "virtual_xyz": None if self.virtual_xyz is None else self.virtual_xyz.tolist(),
            },
            "legs": [leg.to_dict() for leg in self.legs],
            "settings": self.settings,
            "seed": self.seed,
            "stats": self.stats,
            "provenance": self.provenance,
        }
        if self.tool:
            d["tool"] = self.tool
        return d

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> Route:
        fmt = d.get("format")
        if fmt != ROUTE_FORMAT:
            raise ValueError(f"not a weldplan route (format {fmt!r}, expected {ROUTE_FORMAT!r})")
        j = d["joints"]
        lb = d.get("lower_bound")
        return cls(
            order=tuple(d["order"]),
            legs=tuple(Leg.from_dict(leg) for leg in d["legs"]),
            joint_ids=tuple(j["ids"]),
            joint_xyz=np.asarray(j["xyz"], dtype=float).reshape(-1, 3),
            directions=None if j.get("directions") is None else np.asarray(j["directions"]),
            virtual_xyz=None if j.get("virtual_xyz") is None else np.asarray(j["virtual_xyz"]),
            lower_bound=float("nan") if lb is None else float(lb),
            lower_bound_method=d.get("lower_bound_method", ""),
            settings=dict(d.get("settings") or {}),
            seed=d.get("seed"),
            stats=dict(d.get("stats") or {}),
            provenance=dict(d.get("provenance") or {}),
            tool=dict(d.get("tool") or {}),
        )

    def to_json(self, indent: int | None = 1) -> str:
        """JSON text; non-finite floats are written as ``null``."""
        return json.dumps(_jsonable(self.to_dict()), indent=indent, allow_nan=False)

    @classmethod
    def from_json(cls, text: str) -> Route:
        return cls.from_dict(json.loads(text))

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Route):
            return NotImplemented
        return self.to_json() == other.to_json()

    __hash__ = None  # type: ignore[assignment]


def _jsonable(x: Any) -> Any:
    """Replace non-finite floats and numpy scalars so ``json.dumps(allow_nan=False)`` works."""
    if isinstance(x, dict):
        return {str(k): _jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_jsonable(v) for v in x]
    if isinstance(x, np.ndarray):
        return _jsonable(x.tolist())
    if isinstance(x, (np.floating, float)):
        v = float(x)
        return v if np.isfinite(v) else None
    if isinstance(x, np.integer):
        return int(x)
    if isinstance(x, np.bool_):
        return bool(x)
    return x
