"""Results of the weld-pose search: one :class:`WeldPose` per weld, gathered in :class:`WeldPoses`.

Orientations are quaternions ``(qw, qx, qy, qz)`` of the TCP frame in the part frame (scalar
first); angles in degrees, lengths in mm. Both classes are frozen and round-trip through JSON.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

#: status of a weld with a verified collision-free pose
OK = "ok"
#: status of a weld none of whose candidate poses is free
NO_FREE_POSE = "no free pose"


def quat_wxyz(R: ArrayLike) -> NDArray[np.float64]:
    """``(n, 4)`` quaternions ``(qw, qx, qy, qz)``, ``qw >= 0``, of rotations ``(n, 3, 3)``."""
    q = np.roll(Rotation.from_matrix(np.asarray(R, dtype=np.float64)).as_quat(), 1, axis=-1)
    return np.where(q[..., :1] < 0, -q, q)


@dataclass(frozen=True)
class Miss:
    """The candidate pose that came closest to being free, for a weld with none free.

    Attributes
    ----------
    spin, tilt, azimuth
        The candidate's spin about the approach axis, tilt off it and the tilt's direction (deg).
    distance
        mm: FCL distance from the checked tool to the part; ``0`` when they intersect.
    penetration
        mm: the deepest triangle-pair penetration FCL reports among the contacts (0 when they do
        not intersect: then the miss is a clearance shortfall, ``distance < clearance``).
    contacts
        Number of tool triangles touching the part.
    tool_point
        ``(3,)`` mm, TCP frame: the centroid of the tool triangle that hits deepest (or, with no
        contact, the one nearest the part).
    region
        That place on the tool in words (:meth:`weldplan.tool.model.Tool.region`).
    flipped
        The candidate is the tool turned over, approaching from the other side of the sheet
        (tools that straddle the sheet, :attr:`weldplan.tool.model.Tool.straddles`).
    """

    spin: float
    tilt: float
    azimuth: float
    distance: float
    penetration: float
    contacts: int
    tool_point: tuple[float, float, float]
    region: str
    flipped: bool = False

    def to_dict(self) -> dict[str, Any]:
        return {
            "spin": self.spin,
            "tilt": self.tilt,
            "azimuth": self.azimuth,
            "distance": self.distance,
            "penetration": self.penetration,
            "contacts": self.contacts,
            "tool_point": list(self.tool_point),
            "region": self.region,
            "flipped": self.flipped,
        }

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> Miss:
        return cls(
            spin=float(d["spin"]),
            tilt=float(d["tilt"]),
            azimuth=float(d["azimuth"]),
            distance=float(d["distance"]),
            penetration=float(d["penetration"]),
            contacts=int(d["contacts"]),
            tool_point=tuple(float(v) for v in d["tool_point"]),  # type: ignore[arg-type]
            region=str(d["region"]),
            flipped=bool(d.get("flipped", False)),
        )

    def describe(self) -> str:
        if self.contacts:
            how = f"hits by up to {self.penetration:.1f} mm ({self.contacts} tool triangles)"
        else:
            how = f"clears the part by only {self.distance:.1f} mm"
        side = ", turned over" if self.flipped else ""
        return (
            f"closest miss (spin {self.spin:g}, tilt {self.tilt:g} deg{side}): {how} "
            f"at {self.region}"
        )


@dataclass(frozen=True)
class WeldPose:
    """The tool pose chosen for one weld.

    Attributes
    ----------
    id
        The joint id.
    status
        :data:`OK` (a collision-free pose that passed the independent re-check) or
        :data:`NO_FREE_POSE`.
    position
        ``(3,)`` mm: the weld spot, where the TCP is placed.
    approach
        ``(3,)`` unit vector: the nominal tool axis (TCP +z, into the part) before tilt; for a
        pose turned over (``flipped``) the joint's approach axis reversed.
    quaternion
        ``(qw, qx, qy, qz)`` of the TCP frame in the part frame, or ``None`` when no pose is free.
    spin, tilt, azimuth
        Degrees: the spin about the approach axis, the tilt off it and the tilt's direction
        (about the approach axis, from the nominal frame's x axis); NaN when no pose is free.
    n_collision_free
        How many of the sampled candidate poses do not collide (their clearance is measured
        only where the choice needed it, see :func:`weldplan.tool.poses.plan_weld_poses`).
    miss
        The closest miss when no pose is free, else ``None``.
    flipped
        The pose is the tool turned over, approaching from the other side of the sheet (a tool
        that straddles the sheet, :attr:`weldplan.tool.model.Tool.straddles`).
    note
        Why an ok pose is second best: every free candidate failed the search's acceptance test
        (no exit, out of the robot's reach; :mod:`weldplan.tool.poses.choice`); empty otherwise.
    """

    id: str
    status: str
    position: tuple[float, float, float]
    approach: tuple[float, float, float]
    quaternion: tuple[float, float, float, float] | None
    spin: float = float("nan")
    tilt: float = float("nan")
    azimuth: float = float("nan")
    n_collision_free: int = 0
    miss: Miss | None = None
    flipped: bool = False
    note: str = ""

    @property
    def ok(self) -> bool:
        return self.status == OK

    def rotation(self) -> np.ndarray:
        """``(3, 3)``: the TCP axes (columns) in the part frame."""
        if self.quaternion is None:
            raise ValueError(f"weld {self.id} has no pose")
        return Rotation.from_quat(np.roll(self.quaternion, -1)).as_matrix()

    def to_dict(self) -> dict[str, Any]:
        return {
            "id": self.id,
            "status": self.status,
            "position": list(self.position),
            "approach": list(self.approach),
            "quaternion": None if self.quaternion is None else list(self.quaternion),
            "spin": _num(self.spin),
            "tilt": _num(self.tilt),
            "azimuth": _num(self.azimuth),
            "n_collision_free": self.n_collision_free,
            "miss": None if self.miss is None else self.miss.to_dict(),
            "flipped": self.flipped,
            "note": self.note,
        }

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> WeldPose:
        q = d.get("quaternion")
        return cls(
            id=str(d["id"]),
            status=str(d["status"]),
            position=tuple(float(v) for v in d["position"]),  # type: ignore[arg-type]
            approach=tuple(float(v) for v in d["approach"]),  # type: ignore[arg-type]
            quaternion=None if q is None else tuple(float(v) for v in q),  # type: ignore[arg-type]
            spin=_float(d.get("spin")),
            tilt=_float(d.get("tilt")),
            azimuth=_float(d.get("azimuth")),
            n_collision_free=int(d.get("n_collision_free", 0)),
            miss=None if d.get("miss") is None else Miss.from_dict(d["miss"]),
            flipped=bool(d.get("flipped", False)),
            note=str(d.get("note", "")),
        )


def _num(x: float) -> float | None:
    return None if x != x else float(x)


def _float(x: Any) -> float:
    return float("nan") if x is None else float(x)


@dataclass(frozen=True)
class WeldPoses:
    """A pose (or the closest miss) for every weld, in route order.

    Attributes
    ----------
    poses
        One :class:`WeldPose` per weld, in the order the route visits them.
    tool
        The tool's name and source.
    total_rotation
        Degrees: the sum of the rotation angles between consecutive ok poses along the order
        (welds without a pose are skipped), the quantity the pose choice minimises.
    settings
        The search settings (cone, steps, contact radius, clearance).
    stats
        Figures of the run (candidates checked, seconds).
    alternatives
        Per weld (the same order), ``(k, 4)`` quaternions ``(qw, qx, qy, qz)``: the candidate
        orientations of the search not known to fail for the tool (no collision; clearance
        unmeasured or kept; not rejected by the re-check), the chosen one first, the others by
        rotation from it; ``(0, 4)`` for a weld with no pose. What the robot's base search may
        choose among (:mod:`weldplan.robot.placement.altreach`). Empty when not known (read from
        JSON: not written there).
    """

    poses: tuple[WeldPose, ...]
    tool: str
    total_rotation: float
    settings: dict[str, Any] = field(default_factory=dict)
    stats: dict[str, Any] = field(default_factory=dict)
    alternatives: tuple[NDArray[np.float64], ...] = field(default=(), compare=False, repr=False)

    @property
    def n_ok(self) -> int:
        return sum(p.ok for p in self.poses)

    @property
    def order(self) -> tuple[str, ...]:
        return tuple(p.id for p in self.poses)

    def __getitem__(self, joint_id: str) -> WeldPose:
        for p in self.poses:
            if p.id == joint_id:
                return p
        raise KeyError(joint_id)

    def summary(self) -> str:
        lines = [
            f"{self.n_ok} / {len(self.poses)} welds with a verified free pose of {self.tool}; "
            f"total orientation change {self.total_rotation:.1f} deg"
        ]
        for p in self.poses:
            if not p.ok and p.miss is not None:
                lines.append(f"  weld {p.id}: no free pose; {p.miss.describe()}")
            elif p.ok and p.note:
                lines.append(f"  weld {p.id}: {p.note}")
        return "\n".join(lines)

    def to_dict(self) -> dict[str, Any]:
        return {
            "tool": self.tool,
            "total_rotation": self.total_rotation,
            "settings": self.settings,
            "stats": self.stats,
            "poses": [p.to_dict() for p in self.poses],
        }

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> WeldPoses:
        return cls(
            poses=tuple(WeldPose.from_dict(p) for p in d["poses"]),
            tool=str(d["tool"]),
            total_rotation=float(d["total_rotation"]),
            settings=dict(d.get("settings", {})),
            stats=dict(d.get("stats", {})),
        )

    def to_json(self, indent: int | None = 1) -> str:
        return json.dumps(self.to_dict(), indent=indent)

    @classmethod
    def from_json(cls, text: str) -> WeldPoses:
        return cls.from_dict(json.loads(text))
