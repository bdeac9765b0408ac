"""The robot stages' inputs that used to travel as loose arguments: the tool on the flange and the
settings of the base search, the joint route and the program.

A stage takes its data and one frozen settings object, validated once when it is built (a bad
value raises :class:`~weldplan.errors.ConfigError` naming the field), instead of a dozen keyword
arguments declared again at every caller (../shared/STYLE.md, "Settings objects, not long
signatures"). As roboticstoolbox keeps ``robot.tool`` with the robot (``BaseRobot.tool``), the
flange -> TCP transform and the tool's load travel together in :class:`ToolOnRobot`.

::

    tool = ToolOnRobot(tool_flange_tcp(robot, gun_urdf), gun, mass=48.0, cog=(0, 0, 180))
    rr = plan_robot_route(route, poses, robot, tool=tool, cell=RobotCell(part=cell.part))
    build = robot_program(route, rr.q, robot, tool, part=cell, row=rr.row, exact=rr.exact,
                          settings=ProgramSettings(weld_time=0.5))

The defaults are the stages' own, each documented where it is defined: :data:`REPLAN_PLANNER`,
:data:`SEARCH_TOP`, :data:`LINE_TOLERANCE_MM` here;
:data:`~weldplan.robot.placement.DEFAULT_SINGULAR_DEG`,
:data:`~weldplan.robot.route.FLIP_PENALTY_S`, :data:`~weldplan.robot.program.DEFAULT_TOLERANCE_RAD`,
:data:`~weldplan.robot.program.DEFAULT_TCP_SPEED`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from weldplan.errors import ConfigError
from weldplan.motion.roadmap import RoadmapSettings
from weldplan.robot.placement.reach import DEFAULT_SINGULAR_DEG, BaseSearch
from weldplan.robot.program.timing import DEFAULT_TCP_SPEED, DEFAULT_TOLERANCE_RAD
from weldplan.robot.route.configs import FLIP_PENALTY_S

#: default OMPL planner for a blocked leg, and the wall-clock safety net of its first run in s
#: (:meth:`weldplan.robot.route.Detour._ompl`: WALL_FACTOR times this, a retry's in proportion
#: to its checks). The budget is the run's checks; the net must lie well above what they take:
#: on car2_200 a joint-space motion check of the KR 150 with the torch took ~0.1 s, and at 5 s
#: (50 s a first run) the net stopped 2 of 5 runs before their checks were spent, which made
#: the run not reproducible
REPLAN_PLANNER = "rrtconnect"
REPLAN_TIME_S = 30.0
#: base-search candidates re-scored along the whole route
SEARCH_TOP = 5
#: the joint-space roadmaps' work when asked for (``JointRouteSettings(roadmap=ROADMAP)``,
#: :mod:`weldplan.motion.roadmap`): few milestones, since each edge is an FCL-proven motion of
#: the whole arm and tool (tens of ms)
ROADMAP = RoadmapSettings(milestones=40, neighbours=6, query_neighbours=16)
#: mm: a linear move only where the joint path's TCP stays this close to the Cartesian line
LINE_TOLERANCE_MM = 1.0
#: the program moves between route rows (:func:`weldplan.robot.program.robot_program`)
MOVES = ("linear", "joint")
#: tolerance of a transform's rotation block against a rotation (``R^T R = I``, ``det R = 1``)
ROTATION_TOL = 1e-6


def _number(
    name: str,
    v: Any,
    lo: float,
    hi: float = math.inf,
    *,
    lo_open: bool = False,
    hi_open: bool = False,
) -> float:
    """``v`` as a finite float in ``[lo, hi]`` (an end left out where it is open), else
    ConfigError naming ``name``."""
    if isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating)):
        raise ConfigError(f"{name} must be a number, got {v!r}", field=name)
    x = float(v)
    if not math.isfinite(x) or x < lo or x > hi or (lo_open and x == lo) or (hi_open and x == hi):
        span = f"{'(' if lo_open else '['}{lo:g}, {hi:g}{')' if hi_open else ']'}"
        raise ConfigError(f"{name} must be in {span}, got {v!r}", field=name)
    return x


def _flag(name: str, v: Any) -> None:
    if not isinstance(v, bool):
        raise ConfigError(f"{name} must be true or false, got {v!r}", field=name)


def _count(name: str, v: Any, lo: int = 1) -> None:
    if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < lo:
        raise ConfigError(f"{name} must be an integer >= {lo}, got {v!r}", field=name)


def _roadmap(name: str, v: Any) -> None:
    if v is not None and not isinstance(v, RoadmapSettings):
        raise ConfigError(f"{name} must be RoadmapSettings or None, got {v!r}", field=name)


def _frame(name: str, v: ArrayLike) -> NDArray[np.float64]:
    """``v`` as a read-only ``(4, 4)`` rigid transform, else ConfigError."""
    try:
        T = np.array(v, dtype=np.float64)
    except (TypeError, ValueError):
        raise ConfigError(f"{name} must be a (4, 4) transform, got {v!r}", field=name) from None
    if T.shape != (4, 4) or not np.all(np.isfinite(T)):
        raise ConfigError(f"{name} must be a finite (4, 4) transform", field=name)
    R = T[:3, :3]
    if (
        not np.array_equal(T[3], [0.0, 0.0, 0.0, 1.0])
        or np.abs(R.T @ R - np.eye(3)).max() > ROTATION_TOL
        or np.linalg.det(R) < 0.0
    ):
        raise ConfigError(f"{name} must be a rigid transform (rotation, translation)", field=name)
    T.setflags(write=False)
    return T


@dataclass(frozen=True, eq=False)
class ToolOnRobot:
    """The tool as the robot's flange carries it.

    Attributes
    ----------
    flange_tcp
        ``(4, 4)`` mm: the TCP in the flange frame (a rigid transform; stored read-only).
    tool
        The :class:`~weldplan.tool.model.Tool` (mm, TCP frame) for the collision checks; ``None``:
        the links alone are checked.
    mass
        kg: the load the program declares; ``None`` where no program is built.
    cog
        ``(3,)`` mm: its centre of gravity in the flange frame; ``None`` with ``mass``.
    """

    flange_tcp: NDArray[np.float64]
    tool: Any = None
    mass: float | None = None
    cog: NDArray[np.float64] | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "flange_tcp", _frame("flange_tcp", self.flange_tcp))
        if (self.mass is None) != (self.cog is None):
            raise ConfigError("a tool's mass and centre of gravity go together", field="mass")
        if self.mass is not None:
            object.__setattr__(self, "mass", _number("mass", self.mass, 0.0))
            c = np.array(self.cog, dtype=np.float64).reshape(-1)
            if c.shape != (3,) or not np.all(np.isfinite(c)):
                raise ConfigError(
                    f"cog must be 3 finite numbers (mm), got {self.cog!r}", field="cog"
                )
            c.setflags(write=False)
            object.__setattr__(self, "cog", c)


@dataclass(frozen=True, eq=False)
class RobotCell:
    """Where the robot works: the part it must not touch, its base and the floor.

    Attributes
    ----------
    part
        The part mesh (mm, part frame); required for the collision check and the base search's
        part filter.
    base
        ``(4, 4)`` mm: the robot base in the part frame. ``None``: searched (``search``), or the
        robot's own base when ``search`` is ``None`` too.
    search
        Where to search for the base (:class:`~weldplan.robot.placement.BaseSearch`).
    floor_z
        mm: the floor (part frame) no link nor the tool may reach
        (:mod:`weldplan.robot.collision.selfcollision`); ``None``: ``search.floor_z`` for a searched
        base, else none (not checked).
    """

    part: Any = None
    base: NDArray[np.float64] | None = None
    search: BaseSearch | None = None
    floor_z: float | None = None

    def __post_init__(self) -> None:
        if self.base is not None:
            object.__setattr__(self, "base", _frame("base", self.base))
        if self.search is not None and not isinstance(self.search, BaseSearch):
            raise ConfigError(f"search must be a BaseSearch, got {self.search!r}", field="search")
        if self.floor_z is not None:
            object.__setattr__(self, "floor_z", _number("floor_z", self.floor_z, -math.inf))


@dataclass(frozen=True)
class PlacementSettings:
    """The base search's settings (:func:`weldplan.robot.placement.place`).

    Attributes
    ----------
    singular_deg
        deg: A5 within this of 0 is near-singular and avoided.
    flip_penalty
        s of joint motion a branch change costs (:mod:`weldplan.robot.route.configs`).
    top
        The best candidates of the search re-scored along the whole route.
    joins
        The joint-space roadmaps' work (:mod:`weldplan.motion.roadmap`): the candidates re-ranked
        by the welds the transfer trial and one roadmap join; ``None``: no roadmap.
    trial
        Re-rank the candidates by the welds the transfer trial joins in one group (consecutive
        welds joined by their own free leg or by a straight or tucked-arm joint motion between
        their retracts: no planner; :func:`weldplan.robot.placement.join_welds`), then by the
        welds served; ``False``: by the welds served alone (unless ``joins`` is given).
    """

    singular_deg: float = DEFAULT_SINGULAR_DEG
    flip_penalty: float = FLIP_PENALTY_S
    top: int = SEARCH_TOP
    joins: RoadmapSettings | None = None
    trial: bool = True

    def __post_init__(self) -> None:
        _number("singular_deg", self.singular_deg, 0.0, 90.0, hi_open=True)
        _number("flip_penalty", self.flip_penalty, 0.0)
        _count("top", self.top)
        _roadmap("joins", self.joins)
        _flag("trial", self.trial)


@dataclass(frozen=True)
class JointRouteSettings:
    """The joint route's settings (:func:`weldplan.robot.route.plan_robot_route`).

    Attributes
    ----------
    singular_deg, flip_penalty
        As :class:`PlacementSettings`.
    contact_radius
        mm: the tool's contact zone exempt at the welds; ``None``: the poses' own setting.
    check_collision, replan
        Check robot and tool against the part; re-plan blocked legs in joint space.
    planner, replan_time_s
        OMPL planner (:data:`weldplan.motion.sampling.PLANNERS`) and its budget per leg (CPU s
        of this process; :data:`REPLAN_TIME_S`).
    search_top
        The best candidates of a base search re-scored along the whole route.
    roadmap
        The joint-space roadmaps' work (:mod:`weldplan.motion.roadmap`): a searched base is
        chosen by the welds one roadmap joins and a detour asks the roadmap of its base before
        OMPL. ``None`` (the default, docs/robot-placement.md says why): neither; :data:`ROADMAP` is
        the suggested setting.
    home
        ``(6,)`` rad: the robot's home configuration; the route starts and ends there, joined
        to the first and last weld like a detour (:mod:`weldplan.robot.route.home`). ``None``
        (the default): the route starts at its first weld and ends at its last.
    """

    singular_deg: float = DEFAULT_SINGULAR_DEG
    flip_penalty: float = FLIP_PENALTY_S
    contact_radius: float | None = None
    check_collision: bool = True
    replan: bool = True
    planner: str = REPLAN_PLANNER
    replan_time_s: float = REPLAN_TIME_S
    search_top: int = SEARCH_TOP
    roadmap: RoadmapSettings | None = None
    home: tuple[float, ...] | None = None

    def __post_init__(self) -> None:
        from weldplan.motion.sampling import PLANNERS

        if self.home is not None:
            h = tuple(_number("home", v, -1e3, 1e3) for v in self.home)
            object.__setattr__(self, "home", h)

        # the fields it shares with the base search, checked there
        PlacementSettings(self.singular_deg, self.flip_penalty, self.search_top, self.roadmap)
        if self.contact_radius is not None:
            _number("contact_radius", self.contact_radius, 0.0)
        _flag("check_collision", self.check_collision)
        _flag("replan", self.replan)
        if self.planner not in PLANNERS:
            raise ConfigError(
                f"unknown planner {self.planner!r}; choose one of {', '.join(PLANNERS)}",
                field="planner",
            )
        _number("replan_time_s", self.replan_time_s, 0.0, lo_open=True)

    @property
    def placement(self) -> PlacementSettings:
        """The base search's settings: the roadmap joins only where detours join the welds
        (``replan``)."""
        return PlacementSettings(
            self.singular_deg,
            self.flip_penalty,
            self.search_top,
            self.roadmap if self.replan else None,
        )


@dataclass(frozen=True)
class ProgramSettings:
    """The program's settings (:func:`weldplan.robot.program.robot_program`).

    Attributes
    ----------
    moves
        ``"linear"`` or ``"joint"`` between exact rows (:mod:`weldplan.robot.program.build`).
    line_tolerance
        mm: with ``"linear"``, a move is linear only where the checked joint path's TCP stays
        this close to the Cartesian segment; ``None``: the Cartesian check alone (the timing may
        then be of a path far from the line: on the demo up to 149 mm).
    weld_time
        s a spot takes in the cycle time.
    clearance
        mm: the blend radii's clearance; ``None``: the route's own.
    tolerance
        rad: the timed spline's largest deviation from the joint polyline
        (:func:`weldplan.robot.program.time_route`).
    tcp_speed
        mm/s: the constant TCP speed the cycle time is compared with.
    name
        The program's name.
    home
        The joint route starts and ends at the robot's home (its first and last joint rows,
        :attr:`JointRouteSettings.home`): the program's first and last targets are ``home``
        (a joint move), the timing runs from home to home. ``False``: the route starts at its
        first weld, framed by an approach and a retreat.
    """

    moves: str = "linear"
    line_tolerance: float | None = LINE_TOLERANCE_MM
    weld_time: float = 0.0
    clearance: float | None = None
    tolerance: float = DEFAULT_TOLERANCE_RAD
    tcp_speed: float = DEFAULT_TCP_SPEED
    name: str = "weldplan_route"
    home: bool = False

    def __post_init__(self) -> None:
        _flag("home", self.home)
        if self.moves not in MOVES:
            raise ConfigError(
                f"moves must be 'linear' or 'joint', got {self.moves!r}", field="moves"
            )
        if self.line_tolerance is not None:
            _number("line_tolerance", self.line_tolerance, 0.0)
        _number("weld_time", self.weld_time, 0.0)
        if self.clearance is not None:
            _number("clearance", self.clearance, 0.0)
        _number("tolerance", self.tolerance, 0.0, lo_open=True)
        _number("tcp_speed", self.tcp_speed, 0.0, lo_open=True)
        if not isinstance(self.name, str) or not self.name:
            raise ConfigError(f"name must be a non-empty string, got {self.name!r}", field="name")
