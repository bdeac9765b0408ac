"""The station: what a user plans (part, welds, robots with their tools and bases, settings).

A :class:`Station` is declarative and cheap: paths and numbers, every field checked when it is
made (``__post_init__``), nothing loaded. :func:`weldplan.station.load.load_station` reads one
from a TOML file; ``weldplan plan MESH JOINTS ...`` builds the same object from its options
(:mod:`weldplan.commands._station_args`); :func:`weldplan.station.pipeline.plan` runs it.

The settings of each stage are one frozen object (:class:`CellSettings`, :class:`RouteSettings`,
:class:`ToolSettings`, :class:`RobotSettings`), as ../shared/DESIGN.md asks ("a stage takes its
inputs and one frozen, validated settings object"). A station holds a *list* of robots, each
with its tool and its base (given or searched), so that several robots (issue 30) fit the same
model; :func:`~weldplan.station.pipeline.plan` plans one robot today and says so for more.

Frames and units: millimetres and degrees; the part frame is where the mesh and the welds are
given. ``part_pose`` is the part's pose in the cell (:class:`weldplan.cellframe.PartPose`; ``None``:
the part frame is the planning frame): the cell stage moves the mesh and the welds into the cell
frame, a robot stands on the cell's floor (``floor_z``, default the pose's, 0) and is checked
against it, and the programs' work object carries the pose.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from os import PathLike
from pathlib import Path
from typing import Any

from weldplan.errors import ConfigError
from weldplan.weld.validate import PLANNERS, SEQUENCERS

#: the built-in tools a station may name instead of a file (:func:`weldplan.tool.arc_torch`)
BUILTIN_TOOLS = ("arc_torch",)
#: the tool stage's weld orders, the robot program's moves, what the robot's sequencer minimises
TOOL_ORDERS = ("tool", "route")
ROBOT_MOVES = ("linear", "joint")
ROBOT_COSTS = ("length", "time")
#: keyword parameters of the built-in arc torch (mm, degrees; :func:`weldplan.tool.arc_torch`)
ARC_TORCH_PARAMS = (
    "neck_length",
    "diameter",
    "bend_angle",
    "stickout",
    "nozzle_length",
    "body_length",
    "body_diameter",
)


def _number(name: str, v: Any, lo: float, hi: float = math.inf, *, lo_open: bool = False) -> float:
    """``v`` as a finite float in ``[lo, hi]`` (``(lo, hi]`` when ``lo_open``), else ConfigError."""
    ok = isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
    ok = ok and (v > lo if lo_open else v >= lo) and v <= hi
    if not ok:
        bounds = f"{'(' if lo_open else '['}{lo:g}, {hi:g}]"
        raise ConfigError(f"{name} must be a number in {bounds}, got {v!r}", field=name)
    return float(v)


def _optional(name: str, v: Any, lo: float, hi: float = math.inf, **kw: bool) -> float | None:
    return None if v is None else _number(name, v, lo, hi, **kw)


def _choice(name: str, v: Any, choices: tuple[str, ...]) -> str:
    if v not in choices:
        raise ConfigError(f"{name} must be one of {', '.join(choices)}; got {v!r}", field=name)
    return str(v)


def _flag(name: str, v: Any) -> bool:
    if not isinstance(v, bool):
        raise ConfigError(f"{name} must be true or false, got {v!r}", field=name)
    return v


def setting(
    default: Any, option: str, help: str, *, metavar: str | None = None,
    choices: tuple[str, ...] | None = None,
) -> Any:  # fmt: skip
    """A settings field with its command-line option: the field's default and ``help`` are the
    option's (:mod:`weldplan.commands._settings_args` builds the option groups of ``weldplan
    plan`` from this metadata), so an option and its station-file key cannot drift.

    Parameters
    ----------
    default
        The field's default (the option's).
    option
        The long option, e.g. ``"--tool-cone"``; a bool field's option is a flag that sets it
        (``"--smooth"``) or, named ``"--no-..."``, clears it (``"--no-slide"``).
    help
        What the setting does, with its unit; the default and the station-file key are added.
    metavar, choices
        The option's value placeholder and its allowed words.
    """
    meta = {"option": option, "help": help, "metavar": metavar, "choices": choices}
    return field(default=default, metadata=meta)


def _normalise(obj: Any, name: str, value: Any) -> None:
    object.__setattr__(obj, name, value)


def _path(obj: Any, name: str) -> None:
    """Field ``name`` of ``obj`` as a Path (None stays None), else a ConfigError."""
    v = getattr(obj, name)
    if v is None:
        return
    if not isinstance(v, (str, PathLike)):
        raise ConfigError(f"{name} must be a path, got {v!r}", field=name)
    _normalise(obj, name, Path(v))


@dataclass(frozen=True)
class PartSpec:
    """The part and its welds.

    Attributes
    ----------
    mesh, welds
        The part mesh (STL, OBJ, PLY, OFF, GLB/GLTF) and the welds CSV (``id, x, y, z[, dx, dy,
        dz]``); both ``None``: the embedded demo cell (:func:`weldplan.weld.cell.demo_cell`).
    units
        ``"mm"`` or ``"m"``: of the mesh and welds files.
    scale, length
        An extra scale factor of the mesh, or the length (mm) its longest side is scaled to.
    """

    mesh: Path | None = None
    welds: Path | None = None
    units: str = "mm"
    scale: float | None = None
    length: float | None = None

    def __post_init__(self) -> None:
        if (self.mesh is None) != (self.welds is None):
            raise ConfigError("part: give both mesh and welds (or neither: the demo)", field="mesh")
        for k in ("mesh", "welds"):
            _path(self, k)
        _choice("units", self.units, ("mm", "m"))
        _optional("scale", self.scale, 0.0, lo_open=True)
        _optional("length", self.length, 0.0, lo_open=True)

    @property
    def is_demo(self) -> bool:
        return self.mesh is None


@dataclass(frozen=True)
class CellSettings:
    """The cell's search grid and the welds' virtual joints (:func:`weldplan.weld.cell.build_cell`).

    Attributes
    ----------
    pitch, margin
        mm: voxel side of the search grid; margin of its region about the welds.
    approach_cone
        Degrees in (0, 90]: each virtual joint lies within this angle of its weld's approach.
    max_joint_distance
        mm: largest distance of a weld from the part's surface (None: the cell's default).
    spot_depth
        mm >= 0: how far below the surface, along its approach, each weld spot lies (a spot on
        the faying surface of a sheet stack: the gauge of the sheet on the approach side plus
        the gap); the approach cone the route is checked against starts that far out
        (:func:`weldplan.weld.verify.approach_pieces`). 0: spots on the surface.
    """

    pitch: float = setting(5.0, "--pitch", "voxel side of the search grid, mm", metavar="MM")
    margin: float = setting(
        150.0, "--margin", "margin of the search grid about the welds, mm", metavar="MM"
    )
    approach_cone: float = setting(
        45.0, "--approach-cone", "the cell stage's cone, degrees in (0, 90]: each virtual joint "
        "(the point-tip route's start at a weld) lies within this angle of its weld's approach "
        "direction (90 = anywhere on the torch side); not the tool's --tool-cone",
        metavar="DEG",
    )  # fmt: skip
    max_joint_distance: float | None = setting(
        None, "--max-joint-distance", "largest distance from a weld to the part's surface, mm; "
        "a weld farther is an error (default: the larger of 20 and 4 x (clearance + pitch), 40 "
        "at the defaults)",
        metavar="MM",
    )  # fmt: skip
    spot_depth: float = setting(
        0.0, "--spot-depth", "mm below the surface, along the approach, that the weld spots lie "
        "(a spot on the faying surface of a sheet stack: the near sheet's gauge plus the gap); "
        "the route's approach cone starts that far out (0: spots on the surface)",
        metavar="MM",
    )  # fmt: skip

    def __post_init__(self) -> None:
        _number("pitch", self.pitch, 0.0, lo_open=True)
        _number("margin", self.margin, 0.0, lo_open=True)
        _number("approach_cone", self.approach_cone, 0.0, 90.0, lo_open=True)
        _optional("max_joint_distance", self.max_joint_distance, 0.0, lo_open=True)
        _number("spot_depth", self.spot_depth, 0.0)


@dataclass(frozen=True)
class RouteSettings:
    """The point-tip route's planner and sequencer (the fields of
    :class:`~weldplan.weld.pipeline.PlanConfig` a user sets; ``aco``: SO-ACO iterations N = ants
    M)."""

    planner: str = setting(
        "exact", "--planner", "local planner for blocked pairs: exact = 26-connected A* + the "
        "secondary optimisation, then the refinement; so-aco = the paper's; ompl = OMPL's BIT*, "
        "1 s a pair, on the same FCL checks (needs the ompl extra)",
        choices=PLANNERS,
    )  # fmt: skip
    sequencer: str = setting(
        "auto", "--sequencer", "weld order: auto = exact (Held-Karp) up to 13 welds, else nn "
        "(nearest neighbour + the seeded 2-opt / Or-opt polish, reproducible); fast-tsp = a "
        "stronger engine without a seed (not reproducible); pso = the paper's TSP-PSO + polish",
        choices=SEQUENCERS,
    )  # fmt: skip
    aco: int = setting(10, "--aco", "SO-ACO iterations N = ants M (the paper also runs 50)",
                       metavar="N")  # fmt: skip
    refine: bool = setting(
        True, "--no-refine", "skip the continuous refinement after the grid planner (with "
        "--planner so-aco: the paper's pipeline as printed; default: refine, shortcuts anywhere "
        "on the path re-checked by FCL)",
    )  # fmt: skip
    smooth: bool = setting(
        False, "--smooth", "give each leg a smooth path: a C2 curve between its virtual joints, "
        "checked at the clearance and exported as dense waypoints (CSV/JSON kind 'smooth'; "
        "RAPID MoveL, KRL SPLINE); a leg whose curve fails keeps its polyline and the summary "
        "says so",
    )  # fmt: skip
    smooth_spacing: float = setting(
        5.0, "--smooth-spacing", "with --smooth: largest spacing of the smooth waypoints, mm "
        "(denser where a chord would cut into the clearance)",
        metavar="MM",
    )  # fmt: skip
    candidates: int | None = setting(
        None, "--candidates", "check and plan up front only each weld's K nearest pairs, the "
        "rest on demand (for hundreds of welds; default: every pair checked straight)",
        metavar="K",
    )  # fmt: skip
    candidate_radius: float | None = setting(
        None, "--candidate-radius", "with --candidates: neighbours farther than this (mm) are "
        "planned only on demand",
        metavar="MM",
    )  # fmt: skip
    skip_unreachable: bool = setting(
        False, "--skip-unreachable", "plan the largest group of welds that reach each other "
        "and list the others, with the reason, in the summary and the route JSON "
        "(stats.skipped); exit code 3",
    )  # fmt: skip
    memory_limit: float | None = setting(
        None, "--memory-limit", "refuse up front a run whose estimated peak memory (grid + "
        "pair tables), GB, exceeds this (default: 80 % of the memory available at start)",
        metavar="GB",
    )  # fmt: skip

    def __post_init__(self) -> None:
        if not (isinstance(self.aco, int) and not isinstance(self.aco, bool) and self.aco >= 1):
            raise ConfigError(f"aco must be >= 1, got {self.aco!r}", field="aco")
        self.config(5.0, 5.0, 150.0)  # every other field, checked by PlanConfig

    def config(self, clearance: float, pitch: float, margin: float) -> Any:
        """The :class:`~weldplan.weld.pipeline.PlanConfig` of these settings in a cell."""
        from weldplan.weld.pipeline import PlanConfig

        return PlanConfig(
            clearance=clearance,
            pitch=pitch,
            margin=margin,
            planner=self.planner,
            sequencer=self.sequencer,
            aco={"n_iterations": self.aco, "n_ants": self.aco},
            refine=self.refine,
            smooth=self.smooth,
            smooth_spacing=self.smooth_spacing,
            candidates=self.candidates,
            candidate_radius=self.candidate_radius,
            skip_unreachable=self.skip_unreachable,
            memory_limit=self.memory_limit,
        )


@dataclass(frozen=True)
class ToolSettings:
    """The tool stage: weld poses (:func:`weldplan.tool.plan_weld_poses`) and transitions
    (:func:`weldplan.tool.reorder.plan_ordered_transitions`); docs/tool.md.

    Attributes
    ----------
    cone
        Degrees in [0, 90]: largest tilt of the tool off a weld's approach axis.
    contact_radius
        mm: the tool may touch the part only inside this sphere about the weld spot.
    retract, side_exit
        mm: the axial retract before and after each weld; the sideways exit tried where the
        axial one is blocked (0: never).
    slide, exit_check
        Slide between welds; choose each pose only where the tool can leave it.
    rot_weight
        mm per rad: the tool order minimises TCP length + this x orientation change.
    order
        ``"tool"`` (order the welds on the tool's costs) or ``"route"`` (the point-tip order).
    se3_time
        CPU seconds OMPL may spend re-planning one blocked transition in SE(3) (0: none).
    """

    cone: float = setting(
        15.0, "--tool-cone", "the tool stage's cone, degrees in [0, 90]: largest tilt of the "
        "tool's axis off a weld's approach axis (not the cell's --approach-cone nor the tool's "
        "own contact --tip-cone)",
        metavar="DEG",
    )  # fmt: skip
    contact_radius: float = setting(
        20.0, "--contact-radius", "the tool may touch the part only inside this sphere about "
        "the weld spot, mm (the electrode tip's)",
        metavar="MM",
    )  # fmt: skip
    retract: float = setting(
        50.0, "--retract", "leave and approach each weld along the tool axis over this many mm "
        "(every motion of the swept tool is checked)",
        metavar="MM",
    )  # fmt: skip
    side_exit: float = setting(
        250.0, "--side-exit", "where the axial retract is blocked, try leaving sideways by this "
        "many mm first (a C-gun round a flange; 0: never)",
        metavar="MM",
    )  # fmt: skip
    slide: bool = setting(
        True, "--no-slide", "never slide between welds (lift 4-20 mm off the sheet, slide, "
        "lower: a C-gun stays straddled over the flange; tried after the axial retract by "
        "default)",
    )  # fmt: skip
    rot_weight: float = setting(
        200.0, "--rot-weight", "the weld order minimises TCP length + this x orientation "
        "change, mm per rad",
        metavar="MM/RAD",
    )  # fmt: skip
    order: str = setting(
        "tool", "--tool-order", "order the welds on the tool's costs (tool) or keep the "
        "point-tip route's order (route)",
        choices=TOOL_ORDERS,
    )  # fmt: skip
    exit_check: bool = setting(
        True, "--no-exit-check", "choose each weld's pose without asking whether the tool can "
        "leave it (a lift off the sheet, the axial retract or a side exit; on by default, "
        "docs/tool.md)",
    )  # fmt: skip
    se3_time: float = setting(
        10.0, "--se3-time", "the CPU-seconds safety net of re-planning one blocked transition "
        "in SE(3), whose budget is a number of checks; a re-plan stopped at 3x this makes the "
        "run not reproducible (0: report blocked transitions without re-planning)",
        metavar="S",
    )  # fmt: skip

    def __post_init__(self) -> None:
        _number("cone", self.cone, 0.0, 90.0)
        for k in ("contact_radius", "retract", "side_exit", "rot_weight", "se3_time"):
            _number(k, getattr(self, k), 0.0)
        _flag("slide", self.slide)
        _flag("exit_check", self.exit_check)
        _choice("order", self.order, TOOL_ORDERS)

    def transition_kw(self, seed: int | None) -> dict[str, Any]:
        """The transition planner's keywords (one place for the exit test's planner and the
        transitions stage, which must agree)."""
        return dict(
            retract=self.retract, se3=self.se3_time > 0, time_s=max(self.se3_time, 1e-3),
            seed=seed, rot_weight=max(self.rot_weight, 1.0), side_exit=self.side_exit,
            slide=self.slide,
        )  # fmt: skip


#: s a spot takes when ``weld_time`` is not given (squeeze, weld and hold of a typical
#: sheet-steel spot; an assumption, say yours)
DEFAULT_WELD_TIME = 0.5


@dataclass(frozen=True)
class RobotSettings:
    """The robot stage: joint route, timing and program (docs/robot.md).

    Attributes
    ----------
    weld_time
        s a spot takes in the cycle time.
    acc_scale, vel_scale
        Fractions in (0, 1] of the robot's joint accelerations and URDF velocity limits.
    tcp_speed
        mm/s: the constant TCP speed the cycle time is compared with.
    moves
        ``"linear"`` (blended where verified) or ``"joint"`` program moves.
    cost
        What the sequencer minimises: ``"length"`` or ``"time"`` (the robot's leg times).
    roadmap
        Judge a searched base by the welds one joint-space roadmap joins, and ask it before
        OMPL for a blocked leg (:mod:`weldplan.robot.roadmaps`; off by default: on car2_50 it
        found the same base at twice the CPU time).
    """

    weld_time: float = setting(
        DEFAULT_WELD_TIME, "--weld-time", "seconds per spot in the cycle time", metavar="S"
    )
    acc_scale: float = setting(
        1.0, "--acc-scale", "scale of the robot's joint accelerations (1: each joint reaches "
        "its URDF velocity in 0.5 s)",
        metavar="F",
    )  # fmt: skip
    vel_scale: float = setting(
        1.0, "--vel-scale", "scale of the URDF joint velocity limits", metavar="F"
    )
    tcp_speed: float = setting(
        1000.0, "--tcp-speed", "constant TCP speed the cycle time is compared with, mm/s",
        metavar="MM/S",
    )  # fmt: skip
    moves: str = setting(
        "linear", "--moves", "program moves between route rows: linear (blended where "
        "verified) or joint (exact stops, the checked joint path itself)",
        choices=ROBOT_MOVES,
    )  # fmt: skip
    cost: str = setting(
        "length", "--cost", "what the sequencer minimises: route length or the robot's cycle "
        "time (rest-to-rest bounds between the welds' IK configurations; needs --robot)",
        choices=ROBOT_COSTS,
    )  # fmt: skip
    roadmap: bool = setting(
        False, "--roadmap", "judge a searched base by the welds one joint-space roadmap (OMPL "
        "PRM) joins, and ask it before OMPL for a blocked leg (off by default: slower, same "
        "answers measured)",
    )  # fmt: skip

    def __post_init__(self) -> None:
        _flag("roadmap", self.roadmap)
        _number("weld_time", self.weld_time, 0.0, 3600.0)
        _number("acc_scale", self.acc_scale, 0.0, 1.0, lo_open=True)
        _number("vel_scale", self.vel_scale, 0.0, 1.0, lo_open=True)
        _number("tcp_speed", self.tcp_speed, 0.0, 1e5, lo_open=True)
        _choice("moves", self.moves, ROBOT_MOVES)
        _choice("cost", self.cost, ROBOT_COSTS)


@dataclass(frozen=True)
class ToolSpec:
    """A tool as the station names it: a file (URDF, or a mesh with ``tcp``) or a built-in.

    Attributes
    ----------
    file
        A URDF (its TCP: the last fixed joint, or ``tcp`` naming a joint or link) or a mesh.
    builtin, params
        ``"arc_torch"`` (:func:`weldplan.tool.arc_torch`) with its keyword parameters (mm,
        degrees; default the bent torch, 22 deg); mounted with its body's end on the flange and
        its body along the flange's z axis.
    tcp
        With a mesh: ``"x,y,z,rx,ry,rz"`` in the mesh frame; with a URDF: a joint or link name.
    units, mesh
        Unit of the mesh file; with a URDF, a mesh in its root-link frame instead of its own.
    tip_cone
        Degrees: the tool may touch the part only within this cone about its axis behind the TCP.
    mass
        kg: the tool's load for the programs (default: a URDF's ``<inertial>`` masses).
    """

    file: Path | None = None
    builtin: str | None = None
    params: Mapping[str, float] = field(default_factory=dict)
    tcp: str | None = None
    units: str | None = None
    mesh: Path | None = None
    tip_cone: float | None = None
    mass: float | None = None

    def __post_init__(self) -> None:
        if (self.file is None) == (self.builtin is None):
            raise ConfigError("a tool is a file or a builtin, exactly one of them", field="file")
        if self.builtin is not None:
            _choice("builtin", self.builtin, BUILTIN_TOOLS)
            for k in ("tcp", "units", "mesh"):
                if getattr(self, k) is not None:
                    raise ConfigError(f"{k} goes with a tool file, not a builtin", field=k)
            for k, v in self.params.items():
                _choice("arc_torch parameter", k, ARC_TORCH_PARAMS)
                _number(k, v, -90.0 if k == "bend_angle" else 0.0)
        elif self.params:
            raise ConfigError("parameters go with a builtin tool", field=next(iter(self.params)))
        for k in ("file", "mesh"):
            _path(self, k)
        _normalise(self, "params", dict(self.params))
        if self.units is not None:
            _choice("units", self.units, ("mm", "m"))
        _optional("tip_cone", self.tip_cone, 0.0, 90.0, lo_open=True)
        _optional("mass", self.mass, 0.0, 5000.0, lo_open=True)

    @property
    def is_urdf(self) -> bool:
        return self.file is not None and self.file.suffix.lower() == ".urdf"


@dataclass(frozen=True)
class RobotSpec:
    """One robot of the station: its arm (or none: the tool alone), its tool, its base.

    Attributes
    ----------
    tool
        The tool its flange carries (:class:`ToolSpec`).
    urdf, opw
        The arm's URDF (6 revolute joints with limits) and OPW parameters (default
        ``opw_parameters.yaml`` beside it); ``urdf`` None: no arm, the tool stage only.
    base
        ``(x, y, z, yaw)`` mm and degrees about +z, in the part frame; None: searched.
    search
        Where the base is searched (:class:`weldplan.robot.reach.BaseSearch` keywords but the
        floor, which is the station's): ``step``, ``half_width``, ``heights``, ``extra_yaws``,
        ``line``. Empty: the defaults.
    settings
        The robot stage's :class:`RobotSettings`.
    """

    tool: ToolSpec
    urdf: Path | None = None
    opw: Path | None = None
    base: tuple[float, float, float, float] | None = None
    search: Mapping[str, Any] = field(default_factory=dict)
    settings: RobotSettings = field(default_factory=RobotSettings)

    def __post_init__(self) -> None:
        for k in ("urdf", "opw"):
            _path(self, k)
        if self.urdf is None and (self.opw is not None or self.base is not None or self.search):
            raise ConfigError("opw, base and search need a robot urdf", field="urdf")
        if self.base is not None:
            b = tuple(self.base)
            if len(b) != 4:
                raise ConfigError(f"base must be [x, y, z, yaw], got {b!r}", field="base")
            _normalise(self, "base", tuple(_number("base", v, -1e7, 1e7) for v in b))
        if self.search:
            if self.base is not None:
                raise ConfigError("give a base or a search region, not both", field="search")
            self.base_search(None)  # checked once
        _normalise(self, "search", dict(self.search))

    def base_search(self, floor_z: float | None) -> Any:
        """The :class:`~weldplan.robot.reach.BaseSearch` on the station's floor."""
        from weldplan.robot.reach import BaseSearch

        if "floor_z" in self.search:
            raise ConfigError(
                "the floor is the station's (floor_z), not the search's", field="floor_z"
            )
        kw = {k: tuple(map(tuple, v)) if k == "line" else v for k, v in self.search.items()}
        for k in ("heights", "extra_yaws"):
            if k in kw:
                kw[k] = tuple(kw[k])
        try:
            return BaseSearch(floor_z=floor_z, **kw)
        except TypeError as exc:
            raise ConfigError(f"search: {exc}", field="search") from None
        except ValueError as exc:
            raise ConfigError(f"search: {exc}", field="search") from None


@dataclass(frozen=True)
class OutputSpec:
    """Files a run writes (paths as given: relative to the current directory). ``post``:
    ``"rapid"`` or ``"krl"``. The library's :func:`~weldplan.station.pipeline.plan` writes
    nothing; :func:`weldplan.station.outputs.write_plan` and the CLI use these."""

    csv: Path | None = None
    json: Path | None = None
    html: Path | None = None
    post: str | None = None
    post_file: Path | None = None
    trajectory: Path | None = None
    tool_csv: Path | None = None
    robot_html: Path | None = None
    png: Path | None = None

    def __post_init__(self) -> None:
        for f in fields(self):
            if f.name != "post":
                _path(self, f.name)
        if self.post is not None:
            _choice("post", self.post, ("rapid", "krl"))


@dataclass(frozen=True)
class Station:
    """A station: the part placed in the cell, its welds, its robots, every stage's settings.

    Attributes
    ----------
    part
        :class:`PartSpec`.
    robots
        The robots, each with its tool and base (:class:`RobotSpec`); empty: the point-tip
        route only.
    clearance
        mm: the torch tip's radius, the route's clearance from the part.
    part_pose
        The part's pose in the cell; None is the identity (module docstring).
    floor_z
        mm: the floor's height in the part frame (None: not known, not checked; the base search
        then stands the robot at the part's lowest point).
    cell, route, tool
        The settings of the cell, the point-tip route and the tool stage.
    jobs
        Worker processes planning local paths (1: in this process).
    seed
        The seed a run uses when :func:`~weldplan.station.pipeline.plan` is given no ``rng``.
    name
        The program's name (None: ``weldplan_route``; the CLI uses the output file's stem).
    outputs
        :class:`OutputSpec`: what the CLI writes.
    source
        The station file this came from, if any.
    """

    part: PartSpec = field(default_factory=PartSpec)
    robots: tuple[RobotSpec, ...] = ()
    clearance: float = setting(
        5.0, "--clearance", "the torch tip's radius: the point-tip route's clearance from the "
        "part, mm",
        metavar="MM",
    )  # fmt: skip
    part_pose: Any = None
    floor_z: float | None = None
    cell: CellSettings = field(default_factory=CellSettings)
    route: RouteSettings = field(default_factory=RouteSettings)
    tool: ToolSettings = field(default_factory=ToolSettings)
    jobs: int = 1
    seed: int = 0
    name: str | None = None
    outputs: OutputSpec = field(default_factory=OutputSpec)
    source: Path | None = None

    def __post_init__(self) -> None:
        _normalise(self, "robots", tuple(self.robots))
        _number("clearance", self.clearance, 0.0, lo_open=True)
        _optional("floor_z", self.floor_z, -1e6, 1e6)
        if not (isinstance(self.jobs, int) and not isinstance(self.jobs, bool) and self.jobs >= 1):
            raise ConfigError(f"jobs must be >= 1, got {self.jobs!r}", field="jobs")
        from weldplan.weld.validate import seed

        seed(self.seed)
        self.plan_config()  # the route's settings together with the cell's

    def plan_config(self) -> Any:
        """The point-tip stage's :class:`~weldplan.weld.pipeline.PlanConfig`."""
        return self.route.config(self.clearance, self.cell.pitch, self.cell.margin)

    @property
    def robot(self) -> RobotSpec | None:
        """The one robot (None without any); several: a ConfigError until issue 30 lands."""
        if len(self.robots) > 1:
            raise ConfigError(
                f"{len(self.robots)} robots: planning several robots in one station is not "
                "implemented yet (issue 30); give one",
                field="robot",
            )
        return self.robots[0] if self.robots else None
