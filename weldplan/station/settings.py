"""The settings of each stage, one frozen object a stage (../shared/DESIGN.md: "a stage takes
its inputs and one frozen, validated settings object"): :class:`CellSettings`,
:class:`RouteSettings`, :class:`ToolSettings`, :class:`RobotSettings`. Each field is declared with
:func:`~weldplan.station.fields.setting`, so its command-line option, default and help come from
one place; a :class:`~weldplan.station.model.Station` holds them."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from weldplan.errors import ConfigError
from weldplan.station.fields import _choice, _flag, _number, _optional, setting
from weldplan.weld.validate import PLANNERS, SEQUENCERS

#: the tool stage's weld orders, the robot program's moves, what the robot's sequencer minimises
TOOL_ORDERS = ("tool", "route")
ROBOT_MOVES = ("linear", "joint")
ROBOT_COSTS = ("length", "time")


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
    (:func:`weldplan.tool.transitions.plan_ordered_transitions`); docs/tool.md.

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
        OMPL for a blocked leg (:mod:`weldplan.robot.placement.roadmaps`; off by default: on car2_50
        it found the same base at twice the CPU time).
    home
        Degrees, one per axis (A1..A6): the robot's home; its route and program start and end
        there (:mod:`weldplan.robot.route.home`). ``None``: one robot alone starts at its first
        weld; a robot of several gets the conventional home
        (:data:`weldplan.robot.route.home.CONVENTIONAL_HOME_DEG`) when it is free at its base
        (docs/station.md).
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
    home: tuple[float, ...] | None = setting(
        None, "--home", "the robot's home, degrees per axis separated by commas (e.g. "
        "0,-90,90,0,0,0): its route and program start and end there, the legs to and from it "
        "planned and checked like any other (default: start at the first weld; a station of "
        "several robots gives each the conventional home)",
        metavar="A1,...,A6",
    )  # fmt: skip

    def __post_init__(self) -> None:
        _flag("roadmap", self.roadmap)
        if self.home is not None:
            if isinstance(self.home, (str, bytes)) or not hasattr(self.home, "__len__"):
                raise ConfigError(
                    f"home must be a list of degrees, got {self.home!r}", field="home"
                )
            h = tuple(_number("home", v, -1e3, 1e3) for v in self.home)
            object.__setattr__(self, "home", h)
        _number("weld_time", self.weld_time, 0.0, 3600.0)
        _number("acc_scale", self.acc_scale, 0.0, 1.0, lo_open=True)
        _number("vel_scale", self.vel_scale, 0.0, 1.0, lo_open=True)
        _number("tcp_speed", self.tcp_speed, 0.0, 1e5, lo_open=True)
        _choice("moves", self.moves, ROBOT_MOVES)
        _choice("cost", self.cost, ROBOT_COSTS)
