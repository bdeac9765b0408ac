"""The runs of ``weldplan bench robot``: a :func:`weldplan.plan` per seed and per base, a row each.

Issue 27's targets are per seed (the base searched) and per perturbed base (the seed-0 searched
base given, turned by a few degrees of yaw). :func:`run_all` plans the station once per seed, then,
for each yaw offset, once more with seed 0 and the base given at the seed-0 run's base turned by
that offset. Each run gives a :class:`RunRow`:

- **in program**: the welds the robot serves (status ``ok`` in the robot route, so in the one
  program);
- **reachable**: the welds whose chosen tool pose the robot reaches at that base on a usable IK
  branch with its links clear of the part (the reach stage's test,
  :class:`weldplan.robot.placement.ReachTest`, run again on the poses the plan chose);
- **total**: the station's welds; **flips**: IK branch changes on the path;
- **verified**: the robot route re-checked by :func:`weldplan.robot.program.verify_robot_route`
  (FK, joint limits, robot + tool collision on the whole path, the code ``weldplan verify --robot``
  runs): ``ok``, ``partial`` (checked, but welds are left out) or ``FAIL``;
- the robot walk's work (detours, transfers, OMPL runs, traps: what a slow robot stage spent)
  and the legs its transfer trial left split (:mod:`weldplan.robot.route.legtrial`), with
  **said at**: the CPU and wall seconds from the robot stage's start to the trial's line (the
  run says which legs are in doubt that soon, whatever the OMPL runs after it take; issue 27's
  "within 60 s");
- wall and CPU seconds per stage (CPU: this process and its finished children, so that a shared
  machine's load shows apart), and a **digest** of the route (order, base, joint path): two runs
  with the same digest gave the same program.

A run whose plan fails (no weld served, say) is a row too, with the error in ``note``.
"""

from __future__ import annotations

import dataclasses
import hashlib
import logging
import os
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from weldplan.errors import WeldplanError

log = logging.getLogger(__name__)

#: the stages whose seconds the table shows, in pipeline order (others are summed in "other")
TABLE_STAGES = ("route", "reach", "poses", "transitions", "robot", "program")


@dataclass(frozen=True)
class RunRow:
    """One run of the bench (module docstring); seconds are wall unless named CPU."""

    label: str
    seed: int
    base: tuple[float, float, float, float] | None
    searched: bool
    in_program: int
    reachable: int
    total: int
    flips: int
    verified: str
    wall_s: Mapping[str, float] = field(default_factory=dict)
    cpu_s: Mapping[str, float] = field(default_factory=dict)
    wall_total: float = 0.0
    cpu_total: float = 0.0
    digest: str = ""
    note: str = ""
    load: tuple[float, float, float] = (0.0, 0.0, 0.0)
    walk: Mapping[str, Any] = field(default_factory=dict)
    #: ``(CPU s, wall s)`` from the robot stage's start to the walk's transfer trial (``None``:
    #: no trial ran, no leg was blocked)
    said_at: tuple[float, float] | None = None

    def to_dict(self) -> dict[str, Any]:
        d = dataclasses.asdict(self)
        d["wall_s"], d["cpu_s"], d["walk"] = dict(self.wall_s), dict(self.cpu_s), dict(self.walk)
        return d


def _cpu() -> float:
    """CPU seconds of this process and its finished children."""
    t = os.times()
    return t.user + t.system + t.children_user + t.children_system


class _StageClock:
    """A ``progress`` callback for :func:`weldplan.plan` that takes the CPU seconds of each
    stage (a stage reports ``(name, 0, 1)`` on entry and ``(name, 1, 1)`` on exit)."""

    def __init__(self) -> None:
        self.start: dict[str, float] = {}
        self.wall: dict[str, float] = {}
        self.cpu: dict[str, float] = {}

    def __call__(self, name: str, done: int, total: int) -> None:
        if done == 0 and name not in self.start:
            self.start[name], self.wall[name] = _cpu(), time.perf_counter()
        elif done >= total and name in self.start and name not in self.cpu:
            self.cpu[name] = round(_cpu() - self.start[name], 2)


class _TrialClock(logging.Handler):
    """Takes the CPU and wall seconds, from the robot stage's start (``clock``), at which the
    walk's transfer trial says which legs are split (its first record of
    :func:`weldplan.robot.route.legtrial.leg_trial`'s outcome)."""

    def __init__(self, clock: _StageClock) -> None:
        super().__init__(logging.DEBUG)
        self.clock = clock
        self.at: tuple[float, float] | None = None

    def emit(self, record: logging.LogRecord) -> None:
        if self.at is None and "transfer trial" in record.getMessage():
            c, w = self.clock.start.get("robot"), self.clock.wall.get("robot")
            if c is not None and w is not None:
                self.at = (round(_cpu() - c, 2), round(time.perf_counter() - w, 2))


def reachable_welds(p: Any) -> int:
    """Welds whose chosen tool pose the robot reaches at the plan's base (module docstring)."""
    from weldplan.robot.collision.checker import RobotCollision
    from weldplan.robot.placement.posechoice import ReachTest

    rr = p.robot.robot_route
    ok = [w for w in p.poses.poses.poses if w.ok]
    if not ok:
        return 0
    T = np.repeat(np.eye(4)[None], len(ok), axis=0)
    for k, w in enumerate(ok):
        T[k, :3, :3] = w.rotation()
        T[k, :3, 3] = w.position
    robot = p.robot.robot.with_base(rr.base)
    floor = (rr.stats or {}).get("floor_z")
    checker = RobotCollision(robot, p.cell.part, None, rr.flange_tcp, floor_z=floor)
    test = ReachTest(robot, rr.flange_tcp, checker)
    return sum(v is None for v in test.verdicts(T))


def _verified(p: Any) -> str:
    """``ok``, ``partial (k left out)`` or ``FAIL: why`` of the robot route's re-check."""
    from weldplan.robot.program.routejson import verify_robot_route

    rr = p.robot.robot_route
    check = verify_robot_route(p.route, rr, p.robot.robot, p.cell.part, p.tool.tool)
    if not check.ok:
        return f"FAIL: {check.describe()}"
    return f"partial ({len(check.left_out)} left out)" if check.left_out else "ok"


def _digest(p: Any) -> str:
    """12 hex digits of the route's order, the robot's base and its joint path."""
    h = hashlib.sha256("-".join(p.route.order).encode())
    if p.robot is not None:
        rr = p.robot.robot_route
        for a in (rr.base, rr.q, rr.row, rr.exact):
            h.update(np.ascontiguousarray(a).tobytes())
        h.update(",".join(rr.status).encode())
    return h.hexdigest()[:12]


def run_one(station: Any, seed: int, label: str) -> RunRow:
    """Plan ``station`` with ``seed`` and measure it (module docstring)."""
    import weldplan

    clock = _StageClock()
    said = _TrialClock(clock)
    walk_log = logging.getLogger("weldplan.robot.route.walk")
    t0, c0 = time.perf_counter(), _cpu()
    spec = station.robots[0] if station.robots else None
    given = None if spec is None or spec.base is None else tuple(spec.base)
    walk_log.addHandler(said)
    try:
        p = weldplan.plan(station, rng=seed, progress=clock)
    except WeldplanError as exc:
        return RunRow(
            label, seed, given, given is None, 0, 0, _n_welds(station), 0, "-",
            wall_total=round(time.perf_counter() - t0, 2), cpu_total=round(_cpu() - c0, 2),
            note=f"error: {exc}", load=os.getloadavg(), said_at=said.at,
        )  # fmt: skip
    finally:
        walk_log.removeHandler(said)
    wall, cpu = round(time.perf_counter() - t0, 2), round(_cpu() - c0, 2)
    total = len(p.cell.joints.ids)
    walk: dict[str, Any] = {}
    if p.robot is None:
        served = reach = flips = 0
        base, verified = given, "-"
    else:
        rr = p.robot.robot_route
        served, flips = rr.n_ok, len(rr.flips)
        reach = reachable_welds(p)
        xyz_yaw = rr.stats["placement"]["base_xyz_yaw"]
        base = tuple(round(float(v), 3) for v in xyz_yaw)
        verified = _verified(p)
        walk = dict(rr.stats.get("walk", {}))
        walk["detours"] = len(rr.replanned)
    return RunRow(
        label, seed, base, given is None, served, reach, total, flips, verified,
        wall_s={s.name: round(s.seconds, 2) for s in p.stages}, cpu_s=dict(clock.cpu),
        wall_total=wall, cpu_total=cpu, digest=_digest(p), note="; ".join(p.partial())[:300],
        load=os.getloadavg(), walk=walk, said_at=said.at,
    )  # fmt: skip


def _walk_cell(w: Mapping[str, Any], said_at: tuple[float, float] | None = None) -> str:
    """``detours; transfers found/tried; OMPL solved/runs CPU s; traps; split legs (said at CPU
    s)`` of the robot's walk."""
    if not w:
        return "-"
    split = len(w.get("split_legs", ()))
    at = "" if said_at is None else f" at {said_at[0]:.0f} s"
    return (
        f"{w.get('detours', 0)}; {w.get('transfers_found', 0)}/{w.get('transfers', 0)}; "
        f"{w.get('ompl_solved', 0)}/{w.get('ompl_runs', 0)} {w.get('ompl_cpu_s', 0.0):.0f} s; "
        f"{w.get('traps', 0)}; {split} split{at}"
    )


def _n_welds(station: Any) -> int:
    from weldplan.io.joints import read_joints

    if station.part.welds is None:
        return 0
    return len(read_joints(station.part.welds).ids)


def turned(station: Any, base: tuple[float, ...], offset: float) -> Any:
    """``station`` with its (first) robot's base given at ``base`` (x, y, z mm, yaw deg) turned
    by ``offset`` degrees about +z."""
    spec = station.robots[0]
    x, y, z, yaw = (float(v) for v in base)
    b = (x, y, z, (yaw + offset + 180.0) % 360.0 - 180.0)
    robot = dataclasses.replace(spec, base=b, search={})
    return dataclasses.replace(station, robots=(robot, *station.robots[1:]))


def run_all(
    station: Any,
    seeds: tuple[int, ...],
    yaw_offsets: tuple[float, ...] = (),
    on_row: Callable[[RunRow], None] | None = None,
) -> list[RunRow]:
    """A row per seed, then per yaw offset (module docstring), each given to ``on_row`` as soon
    as it is made. The offsets need a robot; the seed-0 run is made first when ``seeds`` lacks
    it."""
    if yaw_offsets and not station.robots:
        raise WeldplanError("--yaw-offsets needs a station with a robot")
    rows: list[RunRow] = []
    order = tuple(seeds)
    if yaw_offsets and 0 not in order:
        order = (0, *order)
    for s in order:
        where = "base searched" if station.robots and station.robots[0].base is None else "base"
        rows.append(run_one(station, s, f"seed {s}, {where}"))
        if on_row is not None:
            on_row(rows[-1])
    if yaw_offsets:
        ref = next(r for r in rows if r.seed == 0)
        if ref.base is None:
            raise WeldplanError(f"the seed-0 run has no base to turn ({ref.note})")
        for off in yaw_offsets:
            rows.append(run_one(turned(station, ref.base, off), 0, f"seed-0 base {off:+g} deg"))
            if on_row is not None:
                on_row(rows[-1])
    return rows


def table_head(title: str = "") -> list[str]:
    """The lines of the table above its rows (:func:`format_table`)."""
    head = (
        "| run | base x, y, z mm, yaw deg | in program / reachable / total | flips | verified | "
        + " | ".join(f"{s} s" for s in TABLE_STAGES)
        + " | walk | wall s | CPU s | load | digest | note |"
    )
    sep = "|" + "---|" * (head.count("|") - 1)
    return ([f"### {title}", ""] if title else []) + [head, sep]


def format_row(r: RunRow) -> str:
    """One run as a table row; a stage cell is ``wall s (CPU s)``; walk: the robot walk's
    detours; transfers found / tried; OMPL runs solved / run and their CPU s; welds set aside
    as traps (:class:`~weldplan.robot.route.WalkStats`); the legs the trial left split and the
    robot stage's CPU s when it said so; load the 1-min average at the run's end."""
    base = "-" if r.base is None else ", ".join(f"{v:.1f}" for v in r.base[:3])
    if r.base is not None:
        base += f", {r.base[3]:.1f}"
    stages = " | ".join(
        f"{r.wall_s[s]:.1f} ({r.cpu_s.get(s, float('nan')):.1f})" if s in r.wall_s else "-"
        for s in TABLE_STAGES
    )
    return (
        f"| {r.label} | {base} | {r.in_program} / {r.reachable} / {r.total} | {r.flips} | "
        f"{r.verified} | {stages} | {_walk_cell(r.walk, r.said_at)} | {r.wall_total:.1f} | "
        f"{r.cpu_total:.1f} | {r.load[0]:.1f} | {r.digest} | {r.note} |"
    )


def format_table(rows: list[RunRow], title: str = "") -> str:
    """A markdown table: one row per run (module docstring)."""
    return "\n".join([*table_head(title), *(format_row(r) for r in rows)])
