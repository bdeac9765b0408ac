"""Results of the weld feasibility study: per spot, whether each gun closes and each robot reaches.

One :class:`SpotVerdict` per spot holds a :class:`GunVerdict` per tool and a
:class:`RobotVerdict` per (tool, robot); :class:`FeasibilityStudy` holds them all with the
robots' bases, the settings and the figures of the run. Every class is frozen and round-trips
through JSON (:meth:`FeasibilityStudy.to_json` / :meth:`FeasibilityStudy.from_json`).

Frames and units: the **part frame** (where the mesh and the spots are given), millimetres,
quaternions ``(qw, qx, qy, qz)`` of the TCP frame, joint values in radians, angles in words in
degrees. :meth:`FeasibilityStudy.reach_matrix` is the input a multi-robot allocation takes.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field, fields
from typing import Any

import numpy as np
from numpy.typing import NDArray

from weldplan.tool.poses.result import Miss

#: verdict words. A spot with a free gun pose (the gun closes on it)
OK = "ok"
#: no part surface within the study's ``max_spot_distance`` of the spot (nothing to weld)
NO_SURFACE = "no_surface"
#: none of the gun's candidate poses is free (:class:`GunVerdict.miss` says where it hits)
NO_GUN_POSE = "no_gun_pose"
#: robot words, in the order a spot gets closer to feasible: no free branch because...
OUT_OF_REACH = "out_of_reach"
JOINT_LIMIT = "joint_limit"
SINGULAR = "singular"
COLLISION = "collision"
#: the per-spot stack column until a flange detector fills it (:mod:`weldplan.study.stacks`)
NOT_ANALYSED = "not analysed"
#: the study's frame (every position and pose in the result)
FRAME = "part"


def _plain(obj: Any) -> dict[str, Any]:
    """The fields of the dataclass ``obj`` as JSON values, in field order: tuples as lists, a
    nested result by its ``to_dict``."""
    out = {}
    for f in fields(obj):
        v = getattr(obj, f.name)
        out[f.name] = (
            list(v) if isinstance(v, tuple) else v.to_dict() if hasattr(v, "to_dict") else v
        )
    return out


class _Verdict:
    """What a gun's and a robot's verdicts share: ``ok`` and their JSON fields."""

    status: str

    @property
    def ok(self) -> bool:
        return self.status == OK

    def to_dict(self) -> dict[str, Any]:
        return _plain(self)


@dataclass(frozen=True)
class GunVerdict(_Verdict):
    """Whether one tool closes on one spot.

    Attributes
    ----------
    tool
        The tool's name in the study.
    status
        :data:`OK`, :data:`NO_GUN_POSE` or :data:`NO_SURFACE`.
    n_free
        Candidate poses of the pose search that do not collide with the part (of
        ``n_candidates``; :attr:`weldplan.tool.poses.WeldPose.n_collision_free`).
    n_candidates
        Candidate poses per spot (spins x tilts, both sides for a tool that straddles).
    quaternion
        ``(qw, qx, qy, qz)``: the verified free pose of the TCP (part frame), ``None`` without.
    flipped
        That pose approaches from the other side of the sheet.
    miss
        The closest miss when no pose is free: where on the gun it hits and by how much.
    reason
        In words: empty when ok.
    """

    tool: str
    status: str
    n_free: int = 0
    n_candidates: int = 0
    quaternion: tuple[float, float, float, float] | None = None
    flipped: bool = False
    miss: Miss | None = None
    reason: str = ""

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> GunVerdict:
        q = d.get("quaternion")
        return cls(
            tool=str(d["tool"]),
            status=str(d["status"]),
            n_free=int(d.get("n_free", 0)),
            n_candidates=int(d.get("n_candidates", 0)),
            quaternion=None if q is None else tuple(float(v) for v in q),  # type: ignore[arg-type]
            flipped=bool(d.get("flipped", False)),
            miss=None if d.get("miss") is None else Miss.from_dict(d["miss"]),
            reason=str(d.get("reason", "")),
        )


@dataclass(frozen=True)
class RobotVerdict(_Verdict):
    """Whether one robot, carrying one tool, reaches a free pose of that tool at one spot.

    Attributes
    ----------
    tool, robot
        Names in the study.
    status
        :data:`OK`; :data:`NO_SURFACE` or :data:`NO_GUN_POSE` (the gun's verdict); else why no
        free pose has a usable branch clear of the part: :data:`COLLISION` (a usable branch
        exists, a link or the tool touches the part, the floor or the robot itself),
        :data:`SINGULAR`, :data:`JOINT_LIMIT`, :data:`OUT_OF_REACH` (the closest to feasible
        over the poses tried wins, in that order).
    reason
        In words (the body that hits, the joint out of its limits); empty when ok.
    quaternion
        ``(qw, qx, qy, qz)``: the TCP pose reached (part frame; verified free for the tool).
    q
        ``(6,)`` rad: the configuration that reaches it (usable, links clear).
    poses_tried
        Free gun poses of the spot judged for the robot.
    """

    tool: str
    robot: str
    status: str
    reason: str = ""
    quaternion: tuple[float, float, float, float] | None = None
    q: tuple[float, ...] | None = None
    poses_tried: int = 0

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> RobotVerdict:
        q, c = d.get("quaternion"), d.get("q")
        return cls(
            tool=str(d["tool"]),
            robot=str(d["robot"]),
            status=str(d["status"]),
            reason=str(d.get("reason", "")),
            quaternion=None if q is None else tuple(float(v) for v in q),  # type: ignore[arg-type]
            q=None if c is None else tuple(float(v) for v in c),
            poses_tried=int(d.get("poses_tried", 0)),
        )


@dataclass(frozen=True)
class SpotVerdict:
    """One spot: where it is, what it sits on, each gun's and each robot's verdict.

    Attributes
    ----------
    id
        The spot's id (the CSV's).
    position
        ``(3,)`` mm, part frame.
    surface_distance
        mm from the spot to the part's surface.
    stack
        The sheet stack the spot joins, or :data:`NOT_ANALYSED` (:mod:`weldplan.study.stacks`).
    guns
        One :class:`GunVerdict` per tool, in the study's tool order.
    robots
        One :class:`RobotVerdict` per (tool, robot), tools outer, robots inner.
    """

    id: str
    position: tuple[float, float, float]
    surface_distance: float
    stack: str = NOT_ANALYSED
    guns: tuple[GunVerdict, ...] = ()
    robots: tuple[RobotVerdict, ...] = ()

    @property
    def feasible(self) -> bool:
        """Some robot reaches the spot with some tool; without robots, some gun closes on it."""
        if self.robots:
            return any(r.ok for r in self.robots)
        return any(g.ok for g in self.guns)

    def to_dict(self) -> dict[str, Any]:
        return {
            "id": self.id,
            "position": list(self.position),
            "surface_distance": self.surface_distance,
            "stack": self.stack,
            "guns": [g.to_dict() for g in self.guns],
            "robots": [r.to_dict() for r in self.robots],
        }

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> SpotVerdict:
        return cls(
            id=str(d["id"]),
            position=tuple(float(v) for v in d["position"]),  # type: ignore[arg-type]
            surface_distance=float(d["surface_distance"]),
            stack=str(d.get("stack", NOT_ANALYSED)),
            guns=tuple(GunVerdict.from_dict(g) for g in d.get("guns", ())),
            robots=tuple(RobotVerdict.from_dict(r) for r in d.get("robots", ())),
        )


@dataclass(frozen=True)
class StudyRobotInfo:
    """A robot of the study and where it stands.

    Attributes
    ----------
    name
        Its name in the study.
    source
        The URDF it was read from.
    base
        ``(4, 4)`` mm: its base in the part frame (given, or the one searched).
    searched
        Whether the base was searched (:func:`weldplan.study.feasibility.check_spots`).
    tool
        The tool whose poses the search scored (searched bases only; empty when given).
    note
        Why a base asked to be searched was not (no spot has a free gun pose to search on: the
        robot's own base stands, and no verdict depends on it); empty otherwise.
    """

    name: str
    source: str
    base: tuple[tuple[float, ...], ...]
    searched: bool
    tool: str = ""
    note: str = ""

    def base_matrix(self) -> NDArray[np.float64]:
        return np.asarray(self.base, dtype=np.float64)

    def xyz_yaw(self) -> tuple[float, float, float, float]:
        """``(x, y, z, yaw_deg)`` of the base (the ``--robot-base`` form)."""
        B = self.base_matrix()
        return (*(float(v) for v in B[:3, 3]), float(np.degrees(np.arctan2(B[1, 0], B[0, 0]))))

    def to_dict(self) -> dict[str, Any]:
        return {
            "name": self.name,
            "source": self.source,
            "base": [list(r) for r in self.base],
            "searched": self.searched,
            "tool": self.tool,
            "note": self.note,
        }

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> StudyRobotInfo:
        return cls(
            name=str(d["name"]),
            source=str(d["source"]),
            base=tuple(tuple(float(v) for v in r) for r in d["base"]),
            searched=bool(d["searched"]),
            tool=str(d.get("tool", "")),
            note=str(d.get("note", "")),
        )


@dataclass(frozen=True)
class FeasibilityStudy:
    """The study of a spot list: a :class:`SpotVerdict` per spot, in the file's order.

    Attributes
    ----------
    spots
        One verdict per spot.
    tools
        The tools' names, in order.
    robots
        The robots and their bases, in order.
    settings
        The study's settings (:class:`weldplan.study.feasibility.StudySettings`, as a dict).
    stats
        Figures of the run (seconds per stage, candidate counts).
    frame
        The frame of every position and pose: :data:`FRAME` (the part's), or ``"cell"`` when
        the part was placed in a cell (:mod:`weldplan.cellframe`).
    """

    spots: tuple[SpotVerdict, ...]
    tools: tuple[str, ...]
    robots: tuple[StudyRobotInfo, ...] = ()
    settings: dict[str, Any] = field(default_factory=dict)
    stats: dict[str, Any] = field(default_factory=dict)
    frame: str = FRAME

    @property
    def ids(self) -> tuple[str, ...]:
        return tuple(s.id for s in self.spots)

    @property
    def feasible(self) -> NDArray[np.bool_]:
        """``(n,) bool``: :attr:`SpotVerdict.feasible` per spot."""
        return np.array([s.feasible for s in self.spots], dtype=bool)

    @property
    def all_feasible(self) -> bool:
        return bool(self.feasible.all())

    def _index(self, names: tuple[str, ...], key: str | int, what: str) -> int:
        if isinstance(key, int):
            if not 0 <= key < len(names):
                raise KeyError(f"no {what} number {key} (the study has {len(names)})")
            return key
        if key not in names:
            raise KeyError(f"no {what} named {key!r} (the study has {', '.join(names)})")
        return names.index(key)

    def gun_matrix(self) -> NDArray[np.bool_]:
        """``(n_spots, n_tools) bool``: the tool closes on the spot (a verified free pose)."""
        return np.array([[g.ok for g in s.guns] for s in self.spots], dtype=bool).reshape(
            len(self.spots), len(self.tools)
        )

    def reach_matrix(self, tool: str | int | None = None) -> NDArray[np.bool_]:
        """``(n_spots, n_robots) bool``: the robot reaches a free pose of ``tool`` at the spot
        on a usable branch clear of the part (``None``: of any tool). Rows in :attr:`ids`
        order, columns in :attr:`robots` order: what a multi-robot allocation assigns over."""
        nt, nr = len(self.tools), len(self.robots)
        ok = np.array([[r.ok for r in s.robots] for s in self.spots], dtype=bool)
        ok = ok.reshape(len(self.spots), nt, nr)
        if tool is None:
            return ok.any(axis=1)
        return ok[:, self._index(self.tools, tool, "tool")]

    def robot_verdict(self, spot: str, tool: str | int, robot: str | int) -> RobotVerdict:
        """The verdict of ``robot`` carrying ``tool`` at spot ``spot`` (an id)."""
        s = self.spots[self.ids.index(spot)]
        t = self._index(self.tools, tool, "tool")
        r = self._index(tuple(x.name for x in self.robots), robot, "robot")
        return s.robots[t * len(self.robots) + r]

    def unreached(self) -> dict[str, str]:
        """The spots that are not feasible, each with why: ``{id: "tool/robot: reason; ..."}``
        over every (tool, robot) pair (without robots, every tool), in spot order. What an
        allocation lists instead of dropping a spot."""
        out: dict[str, str] = {}
        for s in self.spots:
            if s.feasible:
                continue
            if s.robots:
                why = [f"{r.tool}/{r.robot}: {r.status} {r.reason}".strip() for r in s.robots]
            else:
                why = [f"{g.tool}: {g.status} {g.reason}".strip() for g in s.guns]
            out[s.id] = "; ".join(why)
        return out

    def counts(self) -> dict[str, Any]:
        """Spots per verdict: ``{"spots", "feasible", "gun": {tool: {status: n}}, "robot":
        {"tool/robot": {status: n}}}``."""
        from collections import Counter

        out: dict[str, Any] = {
            "spots": len(self.spots),
            "feasible": int(self.feasible.sum()),
            "gun": {},
            "robot": {},
        }
        for k, t in enumerate(self.tools):
            out["gun"][t] = dict(Counter(s.guns[k].status for s in self.spots))
        for k, t in enumerate(self.tools):
            for j, r in enumerate(self.robots):
                c = Counter(s.robots[k * len(self.robots) + j].status for s in self.spots)
                out["robot"][f"{t}/{r.name}"] = dict(c)
        return out

    def to_dict(self) -> dict[str, Any]:
        return {
            "frame": self.frame,
            "tools": list(self.tools),
            "robots": [r.to_dict() for r in self.robots],
            "settings": self.settings,
            "stats": self.stats,
            "spots": [s.to_dict() for s in self.spots],
        }

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> FeasibilityStudy:
        return cls(
            spots=tuple(SpotVerdict.from_dict(s) for s in d["spots"]),
            tools=tuple(str(t) for t in d["tools"]),
            robots=tuple(StudyRobotInfo.from_dict(r) for r in d.get("robots", ())),
            settings=dict(d.get("settings", {})),
            stats=dict(d.get("stats", {})),
            frame=str(d.get("frame", FRAME)),
        )

    def to_json(self, indent: int | None = 1) -> str:
        return json.dumps(self.to_dict(), indent=indent)

    @classmethod
    def from_json(cls, text: str) -> FeasibilityStudy:
        return cls.from_dict(json.loads(text))
