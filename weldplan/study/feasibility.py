"""The weld feasibility study: which spots each gun closes on and which robot reaches them.

What a welding engineer asks first of a new spot list (issue 29, item 4; the weld-point
projection and gun search of Siemens Process Simulate): per spot,

1. **the surface**: the spot's distance to the part (exact point-triangle distance, open3d); a
   spot farther than ``max_spot_distance`` has nothing to weld (``no_surface``) and goes no
   further;
2. **the stack** it joins: a hook (``stacks``), ``"not analysed"`` until a flange detector fills
   it (:data:`StackFinder`);
3. **each gun**: the tool stage's pose search over its candidates (spins, tilts in the cone,
   both sides of the sheet for a gun that straddles it; :func:`weldplan.tool.plan_weld_poses`):
   the number of free candidates, the verified pose, or the closest miss and which part of the
   gun hits;
4. **each robot** carrying each gun, at a given base or at one searched for the study: whether
   it reaches one of the spot's free gun poses on a usable IK branch with its links and the tool
   clear of the part, itself and the floor, and else why not (:mod:`weldplan.study.robot_reach`).

A searched base (:func:`_search_base`): :func:`weldplan.robot.placement.search_base` ranks the
candidates of the robot's region (:attr:`StudyRobot.search`, default the floor about the
spots) by the spots whose verified pose or one of its alternatives is usable, with the arm's
chord clear of the part, then by manipulability; the best ``base_pool`` are judged by the study
itself (the spots served, links and tool checked) and the one serving most wins (ties: the
search's order). The study is deterministic: no random draw, every search budgeted by work.

Frames: the study is in the frame of the part and spots it is given, and the robots' bases
and the floor are in that frame too: the part frame, or the cell frame when the part was placed
in a cell (:mod:`weldplan.cellframe`; a station of several robots gives it the cell's part and
welds, :mod:`weldplan.multi.station`). The result
(:class:`~weldplan.study.result.FeasibilityStudy`) is in that frame; its
:meth:`~weldplan.study.result.FeasibilityStudy.reach_matrix` (spots x robots) is the input of
a multi-robot allocation (issue 30).
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
import trimesh
from numpy.typing import NDArray

from weldplan.errors import ConfigError, PlanningError
from weldplan.io.joints import Joints
from weldplan.robot.model.arm import Robot
from weldplan.station.model import ToolSpec, setting
from weldplan.study.result import (
    FRAME,
    NO_GUN_POSE,
    NO_SURFACE,
    NOT_ANALYSED,
    OK,
    FeasibilityStudy,
    GunVerdict,
    RobotVerdict,
    SpotVerdict,
    StudyRobotInfo,
)
from weldplan.study.robot_reach import (
    ReachBudget,
    SpotPoses,
    robot_verdicts,
    tcp_matrices,
    tool_recheck,
)
from weldplan.tool.model.tool import Tool
from weldplan.tool.settings import (
    DEFAULT_AZIMUTHS,
    DEFAULT_CLEARANCE,
    DEFAULT_CONE,
    DEFAULT_CONTACT_RADIUS,
    DEFAULT_SPIN_STEP,
    DEFAULT_TILT_STEP,
)

log = logging.getLogger(__name__)

#: mm: a spot farther than this from the part's surface has nothing to weld (a spot on a sheet
#: lies on it; 5 mm allows for a CSV rounded to the mm and a spot given on the far skin of a
#: 2 x 2 mm stack)
DEFAULT_MAX_SPOT_DISTANCE = 5.0
#: searched bases judged by the study itself (the best of weldplan.robot.placement.search_base)
DEFAULT_BASE_POOL = 6
#: the search ranks this many times ``base_pool`` candidates, of which the study judges the best
#: at distinct floor positions first (the kinematic ranking puts several yaws of one position
#: first; a link through the part at one usually blocks them all)
POOL_SPREAD = 4
#: free poses per spot the base search scores where the verified one fails (spread in rotation)
SEARCH_ALTS = 8

#: The per-spot stack hook: ``stacks(part, xyz (n, 3) mm) -> n words`` (the sheets a spot joins,
#: or why none). A flange detector (weldplan.geometry.flanges, issue 29 item 3) plugs in here;
#: without one every spot's stack is :data:`~weldplan.study.result.NOT_ANALYSED`.
StackFinder = Callable[[trimesh.Trimesh, NDArray[np.float64]], Sequence[str]]


@dataclass(frozen=True)
class StudySettings:
    """The study's settings (validated once).

    Attributes
    ----------
    cone, tilt_step, spin_step, azimuths
        The gun's candidate poses (degrees; :func:`weldplan.tool.plan_weld_poses`).
    contact_radius
        mm: the zone about the spot where the gun may touch the part.
    clearance
        mm: least distance between the gun outside that zone and the part.
    max_spot_distance
        mm: a spot farther from the part's surface is ``no_surface``.
    floor_z
        mm: the floor's height in the study's frame (module docstring): searched bases stand on
        it and no link may reach below it (``None``: bases on the part's lowest point, the floor
        not checked).
    singular_deg
        A5 within this many degrees of 0 is near-singular.
    robot_poses, robot_branches
        Work per spot for the robot: free gun poses judged, usable branches collision-checked
        (:class:`~weldplan.study.robot_reach.ReachBudget`).
    base_pool
        Searched bases judged by the study itself (module docstring).
    """

    cone: float = setting(
        DEFAULT_CONE, "--tool-cone", "largest tilt of the gun off the spot's approach axis, "
        "degrees in (0, 90]",
        metavar="DEG",
    )  # fmt: skip
    tilt_step: float = DEFAULT_TILT_STEP
    spin_step: float = DEFAULT_SPIN_STEP
    azimuths: int = DEFAULT_AZIMUTHS
    contact_radius: float = setting(
        DEFAULT_CONTACT_RADIUS, "--contact-radius", "the gun may touch the part inside this "
        "sphere about the spot, mm",
        metavar="MM",
    )  # fmt: skip
    clearance: float = setting(
        DEFAULT_CLEARANCE, "--clearance", "least distance of the gun outside that sphere to the "
        "part, mm",
        metavar="MM",
    )  # fmt: skip
    max_spot_distance: float = setting(
        DEFAULT_MAX_SPOT_DISTANCE, "--max-spot-distance", "a spot farther from the part's "
        "surface (mm) is 'no surface'",
        metavar="MM",
    )  # fmt: skip
    floor_z: float | None = None
    singular_deg: float = 5.0
    robot_poses: int = 64
    robot_branches: int = 24
    base_pool: int = DEFAULT_BASE_POOL

    def __post_init__(self) -> None:
        for name in ("contact_radius", "clearance", "max_spot_distance", "singular_deg"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v >= 0):
                raise ConfigError(f"must be a finite number >= 0, got {v!r}", field=name)
        if not 0 < self.cone <= 90 or not 0 < self.tilt_step or not 0 < self.spin_step <= 360:
            raise ConfigError(
                "cone in (0, 90], tilt_step > 0, spin_step in (0, 360] deg", field="cone"
            )
        for name in ("azimuths", "robot_poses", "robot_branches", "base_pool"):
            v = getattr(self, name)
            if not (isinstance(v, int) and v >= 1):
                raise ConfigError(f"must be an integer >= 1, got {v!r}", field=name)
        if self.floor_z is not None and not math.isfinite(self.floor_z):
            raise ConfigError(f"must be finite, got {self.floor_z!r}", field="floor_z")

    def budget(self) -> ReachBudget:
        return ReachBudget(self.robot_poses, self.robot_branches, self.singular_deg)


@dataclass(frozen=True, eq=False)
class StudyTool:
    """A tool of the study.

    Attributes
    ----------
    name
        Its name in the tables.
    tool
        The tool (mm, TCP frame).
    spec
        The tool as a station names it (:class:`~weldplan.station.model.ToolSpec`): how a robot's
        flange carries it, as in the robot stage (:meth:`flange_tcp`).
    """

    name: str
    tool: Tool
    spec: ToolSpec

    def flange_tcp(self, robot: Robot) -> NDArray[np.float64]:
        """``(4, 4)`` mm: the TCP in ``robot``'s flange frame
        (:func:`weldplan.station.mount.flange_tcp`, the robot stage's mounting)."""
        from weldplan.station.mount import flange_tcp

        return flange_tcp(self.spec, robot)


def load_study_tool(
    path: str,
    *,
    tcp: str | None = None,
    units: str | None = None,
    mesh: str | None = None,
    name: str | None = None,
) -> StudyTool:
    """A :class:`StudyTool` from a file, read and mounted as ``weldplan plan --tool`` reads and
    mounts it (:func:`weldplan.station.mount.load_tool_spec`): a URDF (``tcp`` its TCP joint or
    link, default the last fixed joint; the root link is the mounting frame) or a mesh (``tcp``
    ``"x,y,z,rx,ry,rz"`` in ``units`` and degrees; the mesh frame is the mounting frame).
    ``name``: default the file's stem."""
    from pathlib import Path

    from weldplan.station.mount import load_tool_spec

    mesh_path = None if mesh is None else Path(mesh)
    spec = ToolSpec(file=Path(path), tcp=tcp, units=units, mesh=mesh_path)
    tool, _ = load_tool_spec(spec)
    return StudyTool(name or Path(path).stem, tool, spec)


@dataclass(frozen=True, eq=False)
class StudyRobot:
    """A robot of the study.

    Attributes
    ----------
    name
        Its name in the tables.
    robot
        The robot (its ``base`` is used when ``searched`` is False).
    searched
        Search its base on the floor (module docstring) instead of using ``robot.base``.
    source
        Where it was read from (for the result).
    search
        With ``searched``: where (:class:`~weldplan.robot.placement.BaseSearch`: the floor grid or
        a line, and the discs kept out); ``None``: the floor about the spots, on
        :attr:`StudySettings.floor_z`.
    """

    name: str
    robot: Robot
    searched: bool = False
    source: str = ""
    search: Any = None


def check_spots(
    part: trimesh.Trimesh,
    spots: Joints,
    tools: Sequence[StudyTool],
    robots: Sequence[StudyRobot] = (),
    settings: StudySettings | None = None,
    *,
    stacks: StackFinder | None = None,
    frame: str = FRAME,
) -> FeasibilityStudy:
    """The feasibility study of ``spots`` on ``part`` (module docstring).

    Parameters
    ----------
    part
        The part (mm).
    spots
        The spots (mm, part frame; approach directions optional: the surface normal otherwise).
    tools
        At least one tool.
    robots
        Robots, each carrying every tool in turn.
    settings
        :class:`StudySettings` (defaults when ``None``).
    stacks
        The per-spot stack hook (:data:`StackFinder`).
    frame
        The frame ``part`` and ``spots`` are in, as the result records it: ``"part"``, or
        ``"cell"`` for a part placed in a cell (module docstring).

    Returns
    -------
    FeasibilityStudy
        A :class:`~weldplan.study.result.SpotVerdict` per spot, in ``spots`` order.

    Raises
    ------
    ConfigError
        No tool, or two tools or robots with one name.
    PlanningError
        A searched base: no floor candidate reaches any spot.
    """
    settings = settings or StudySettings()
    _check_names(tools, robots)
    t0, c0 = time.perf_counter(), time.process_time()
    stats: dict[str, Any] = {
        "spots": len(spots),
        "gun_s": [],
        "gun_cpu_s": [],
        "robot_s": [],
        "robot_cpu_s": [],
    }
    from weldplan.geometry.distance import SurfaceDistance

    dist = SurfaceDistance(part)(np.asarray(spots.xyz))
    near = dist <= settings.max_spot_distance
    stats["no_surface"] = int((~near).sum())
    stack = _stacks(stacks, part, spots, near)
    guns, poses, infos, verdicts = [], [], [], []
    for st in tools:
        with _timed(stats, "gun"):
            g, p = _gun_stage(part, spots, near, st, settings)
        guns.append(g)
        poses.append(p)
    for sr in robots:
        with _timed(stats, "robot"):
            info, per_tool = _robot_stage(part, sr, tools, guns, poses, settings)
        infos.append(info)
        verdicts.append(per_tool)
    out = [
        SpotVerdict(
            id=wid,
            position=tuple(float(v) for v in spots.xyz[i]),  # type: ignore[arg-type]
            surface_distance=float(dist[i]),
            stack=stack[i],
            guns=tuple(g[i] for g in guns),
            robots=tuple(v[k][i] for k in range(len(tools)) for v in verdicts),
        )
        for i, wid in enumerate(spots.ids)
    ]
    stats["total_s"] = round(time.perf_counter() - t0, 3)
    stats["total_cpu_s"] = round(time.process_time() - c0, 3)
    study = FeasibilityStudy(
        spots=tuple(out),
        tools=tuple(t.name for t in tools),
        robots=tuple(infos),
        settings=asdict(settings),
        stats=stats,
        frame=frame,
    )
    log.info("feasibility study: %d / %d spots feasible", int(study.feasible.sum()), len(out))
    return study


@contextmanager
def _timed(stats: dict[str, Any], stage: str) -> Iterator[None]:
    """Append the wall and CPU seconds (this process) of the block to ``stats[stage + "_s"]``
    and ``stats[stage + "_cpu_s"]`` (on a loaded machine the CPU figure is the quiet one)."""
    t, c = time.perf_counter(), time.process_time()
    yield
    stats[f"{stage}_s"].append(round(time.perf_counter() - t, 3))
    stats[f"{stage}_cpu_s"].append(round(time.process_time() - c, 3))


def _check_names(tools: Sequence[StudyTool], robots: Sequence[StudyRobot]) -> None:
    if not tools:
        raise ConfigError("the study needs at least one tool", field="tools")
    for what, names in (("tool", [t.name for t in tools]), ("robot", [r.name for r in robots])):
        if len(set(names)) != len(names):
            raise ConfigError(f"two {what}s share a name: {names}", field=f"{what}s")


def _stacks(
    stacks: StackFinder | None, part: trimesh.Trimesh, spots: Joints, near: NDArray[np.bool_]
) -> list[str]:
    """The stack column: the hook's words, ``"not analysed"`` without a hook, ``"none (no
    surface)"`` for a spot off the part."""
    words = [NOT_ANALYSED] * len(spots)
    if stacks is not None:
        words = [str(w) for w in stacks(part, np.asarray(spots.xyz))]
        if len(words) != len(spots):
            raise ConfigError(
                f"the stack hook gave {len(words)} words for {len(spots)} spots", field="stacks"
            )
    return [w if near[i] else "none (no surface)" for i, w in enumerate(words)]


def _subset(spots: Joints, keep: NDArray[np.bool_]) -> Joints:
    d = None if spots.directions is None else np.asarray(spots.directions)[keep]
    ids = tuple(i for i, k in zip(spots.ids, keep, strict=True) if k)
    return Joints(ids=ids, xyz=np.asarray(spots.xyz)[keep], directions=d)


def _gun_stage(
    part: trimesh.Trimesh,
    spots: Joints,
    near: NDArray[np.bool_],
    st: StudyTool,
    s: StudySettings,
) -> tuple[list[GunVerdict], list[SpotPoses]]:
    """Per spot the tool's :class:`GunVerdict` and its free poses (verified one first)."""
    from weldplan.tool.poses.plan import plan_weld_poses
    from weldplan.tool.settings import PoseSearchSettings

    n = len(spots)
    gun: list[GunVerdict] = []
    free: list[SpotPoses] = [SpotPoses(np.asarray(p), np.zeros((0, 4))) for p in spots.xyz]
    wp = None
    if near.any():
        search = PoseSearchSettings(
            cone=s.cone,
            tilt_step=s.tilt_step,
            spin_step=s.spin_step,
            azimuths=s.azimuths,
            contact_radius=s.contact_radius,
            clearance=s.clearance,
        )
        wp = plan_weld_poses(part, _subset(spots, near), st.tool, search)
    rows = iter(range(int(near.sum())))
    limit = f"no surface within {s.max_spot_distance:g} mm"
    for i in range(n):
        if not near[i]:
            gun.append(GunVerdict(st.name, NO_SURFACE, reason=limit))
            continue
        k = next(rows)
        p = wp.poses[k]  # type: ignore[union-attr]
        c = int(wp.stats["candidates_per_weld"])  # type: ignore[union-attr]
        if p.ok:
            gun.append(GunVerdict(st.name, OK, p.n_collision_free, c, p.quaternion, p.flipped))
            free[i] = SpotPoses(np.asarray(p.position), np.asarray(wp.alternatives[k]))  # type: ignore[union-attr]
        else:
            why = p.miss.describe() if p.miss is not None else "no free pose"
            gun.append(
                GunVerdict(
                    st.name,
                    NO_GUN_POSE,
                    p.n_collision_free,
                    c,
                    miss=p.miss,
                    reason=f"no free pose; {why}",
                )
            )
    return gun, free


def _robot_stage(
    part: trimesh.Trimesh,
    sr: StudyRobot,
    tools: Sequence[StudyTool],
    guns: list[list[GunVerdict]],
    poses: list[list[SpotPoses]],
    s: StudySettings,
) -> tuple[StudyRobotInfo, list[list[RobotVerdict]]]:
    """One robot: its base (given or :func:`_search_base` on the first tool with free poses)
    and its verdicts per tool and spot."""
    robot, on = sr.robot, ""
    kits = [_Kit.build(part, sr.robot, st, s) for st in tools]
    judged: dict[int, list[RobotVerdict | None]] = {}
    if sr.searched:
        k = next((k for k, p in enumerate(poses) if any(len(x.quaternions) for x in p)), None)
        if k is not None:
            robot, judged[k] = _search_base(part, sr, kits[k], poses[k], s)
            on = tools[k].name
    out = []
    for k, kit in enumerate(kits):
        got = judged.get(k)
        if got is None:
            got = kit.judge(robot, sr.name, poses[k], s)
        out.append(
            [
                v if v is not None else _gun_word(g, sr.name)
                for v, g in zip(got, guns[k], strict=True)
            ]
        )
    info = StudyRobotInfo(
        name=sr.name,
        source=sr.source,
        base=tuple(tuple(float(v) for v in r) for r in robot.base),
        searched=bool(on),
        tool=on,
        note="" if on or not sr.searched else "not searched: no spot has a free gun pose",
    )
    return info, out


def _gun_word(g: GunVerdict, robot: str) -> RobotVerdict:
    """A robot's verdict at a spot the gun does not close on: the gun's."""
    return RobotVerdict(g.tool, robot, g.status, g.reason)


@dataclass(frozen=True, eq=False)
class _Kit:
    """One tool on one robot: the tool, its TCP in the flange frame, the robot's collision
    checker with the tool (re-based per candidate, sharing the part's structures) and the
    tool's independent re-check of a pose (its verdicts remembered across bases); built once."""

    tool: StudyTool
    flange_tcp: NDArray[np.float64]
    checker: Any
    tool_clear: Callable[[NDArray[np.float64]], bool]

    @classmethod
    def build(cls, part: trimesh.Trimesh, robot: Robot, st: StudyTool, s: StudySettings) -> _Kit:
        from weldplan.robot.collision.checker import RobotCollision
        from weldplan.tool.verify.poses import PoseChecker

        F = st.flange_tcp(robot)
        checker = RobotCollision(
            robot, part, st.tool, F, contact_radius=s.contact_radius, floor_z=s.floor_z
        )
        pc = PoseChecker(part, st.tool, s.contact_radius, s.clearance)
        return cls(st, F, checker, tool_recheck(pc))

    def judge(
        self, robot: Robot, name: str, free: list[SpotPoses], s: StudySettings
    ) -> list[RobotVerdict | None]:
        """:func:`weldplan.study.robot_reach.robot_verdicts` of ``robot`` at its base."""
        return robot_verdicts(
            robot,
            self.checker.with_robot(robot),
            self.flange_tcp,
            free,
            self.tool_clear,
            s.budget(),
            (self.tool.name, name),
        )


def _search_base(
    part: trimesh.Trimesh,
    sr: StudyRobot,
    kit: _Kit,
    free: list[SpotPoses],
    s: StudySettings,
) -> tuple[Robot, list[RobotVerdict | None]]:
    """The searched base of ``sr`` for the kit's tool (module docstring) and its verdicts there.

    Raises
    ------
    PlanningError
        No floor candidate reaches any spot.
    """
    from weldplan.robot.placement.altreach import spread
    from weldplan.robot.placement.reach import BaseSearch, search_base

    inv = np.linalg.inv(kit.flange_tcp)
    has = [k for k, p in enumerate(free) if len(p.quaternions)]
    T = np.stack([tcp_matrices(free[k].position, free[k].quaternions[:1])[0] @ inv for k in has])
    alts = [
        tcp_matrices(
            free[k].position, free[k].quaternions[spread(free[k].quaternions, SEARCH_ALTS)]
        )
        @ inv
        for k in has
    ]
    try:
        ranked = search_base(
            sr.robot,
            T,
            part,
            sr.search if sr.search is not None else BaseSearch(floor_z=s.floor_z),
            singular_deg=s.singular_deg,
            top=POOL_SPREAD * s.base_pool,
            alternatives=alts,
        )
    except PlanningError as exc:
        raise PlanningError(f"robot {sr.name}: {exc}") from None
    best: tuple[int, Robot, list[RobotVerdict | None]] | None = None
    for pl in _distinct(ranked, s.base_pool):
        rb = sr.robot.with_base(pl.base)
        got = kit.judge(rb, sr.name, free, s)
        n_ok = sum(v is not None and v.status == OK for v in got)
        log.info(
            "study base %s: %d / %d spots served (reach %d)",
            np.round(pl.xyz_yaw(), 1).tolist(),
            n_ok,
            len(has),
            pl.n_usable,
        )
        if best is None or n_ok > best[0]:
            best = (n_ok, rb, got)
    assert best is not None  # search_base returns at least one candidate or raises
    return best[1], best[2]


def _distinct(ranked: list[Any], k: int) -> list[Any]:
    """The best ``k`` placements of ``ranked`` (best first), one per floor position first, then
    the rest in rank order."""
    seen: set[tuple[float, ...]] = set()
    first, rest = [], []
    for pl in ranked:
        key = tuple(np.round(pl.base[:3, 3], 1))
        (rest if key in seen else first).append(pl)
        seen.add(key)
    return (first + rest)[:k]
