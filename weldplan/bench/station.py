"""``weldplan bench station``: stations of several robots planned whole, cycle times side by side.

Issue 30's targets: per station its welds and robots, the welds no robot reaches, the cycle
times of the one-robot and nearest-robot baselines, of our allocation and of its lower bound
(:class:`weldplan.multi.result.AllocationReport`, over the allocation's leg-time model), the
station's timed cycle (:attr:`weldplan.multi.schedule.StationSchedule.cycle_time`: every
robot's timed program on one clock, waits included), the waits and the interlocks, the
robot-robot replay's minimum distance (when the plan carries a replay), and the wall and CPU
seconds of each stage.

Stations:

- **planned** ones go through :func:`weldplan.plan`, the call ``weldplan plan station.toml``
  makes: the demo two-robot station (:func:`demo_two_robots`: ``examples/demo_station.toml``
  with two KUKA KR 150 R3100-2 at :data:`DEMO_BASES`, on either side of the demo part) and any
  ``--station FILE``. With ``--pages`` each gets its station page
  (:func:`weldplan.viz.station_page.station_page`) and its Gantt chart
  (:func:`weldplan.viz.gantt.gantt_png`) in ``--out``;
- **synthetic** ones (``--synthetic W:R,...``) run the allocation only, on the synthetic
  stations of :func:`synthetic_station`: no part, no
  programs, so no timed cycle; they show how the allocation and its bound scale.

Writes ``station.md`` (the page docs/bench-station.md is a copy of) and ``station.json`` to
``--out``.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import logging
import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from weldplan.errors import WeldplanError

log = logging.getLogger(__name__)

ROOT = Path(__file__).resolve().parents[2]
#: (x, y, z mm, yaw deg), part frame: behind the demo part facing it, and in front facing back
DEMO_BASES = ((448.1, 95.3, 652.7, -7.5), (2450.0, -150.0, 652.7, 180.0))
#: deg, A1..A6: both robots' home, the arm turned a quarter away from the part (facing each other,
#: their conventional homes A1 = 0 would touch: docs/station.md#home)
DEMO_HOME = (90.0, -90.0, 90.0, 0.0, 0.0, 0.0)
#: rad/s: joint velocity limits of a heavy six-axis arm (KR 150 class) for the synthetic
#: stations; accelerations 3x
SYNTH_VEL = np.radians([105.0, 101.0, 107.0, 136.0, 129.0, 206.0])
#: mm: the synthetic robots' bases (up to four), at the corners of a 2.4 x 3.6 m rectangle
SYNTH_BASES = np.array([[-1200, -1800, 0], [1200, -1800, 0], [-1200, 1800, 0], [1200, 1800, 0.0]])
#: mm: a synthetic robot serves the welds within this distance of its base
SYNTH_REACH_MM = 2600.0
#: s a synthetic weld
SYNTH_WELD_S = 0.5
#: ``--car2``: car2 upright in a cell with the straight arc torch (examples/), 200 welds on two
#: robots and 400 on four
CAR2_STATIONS = ("car2_upright_200_2.toml", "car2_upright_400_4.toml")

HELP = (
    "stations of several robots (weldplan.plan on station files): one-robot, nearest-robot, "
    "ours and bound cycle times, the timed cycle, waits, interlocks, CPU and wall per stage"
)


@dataclass(frozen=True)
class StationRow:
    """One station's figures (module docstring); cycle times in s, distances in mm.

    ``timed``, ``waiting``, ``interlocks``, ``replay_*``, ``robots_rows`` and ``rounds`` are
    empty or None for an allocation-only (synthetic) station. ``robots_rows``: per robot
    ``(name, welds, allocated s, timed s or None, utilisation, waiting s)``; ``rounds``: per
    allocate-plan round (:mod:`weldplan.multi.calibrate`) ``(model cycle s, timed cycle s,
    robots planned)``, ``ours`` being the best round's model cycle; ``baselines`` (with
    ``--plan-baselines``, :func:`timed_baselines`): per allocation ``(name, modelled cycle s,
    planned and timed cycle s or None)``."""

    name: str
    kind: str
    welds: int
    robots: int
    unreached: int
    one_robot: float | None
    nearest: float | None
    ours: float
    bound: float
    bound_name: str
    timed: float | None = None
    waiting: float | None = None
    interlocks: int | None = None
    replay_min: float | None = None
    replay_ok: bool | None = None
    robots_rows: tuple[tuple[Any, ...], ...] = ()
    wall_s: dict[str, float] = field(default_factory=dict)
    cpu_s: dict[str, float] = field(default_factory=dict)
    wall_total: float = 0.0
    cpu_total: float = 0.0
    load: tuple[float, ...] = ()
    note: str = ""
    rounds: tuple[tuple[float, float, tuple[int, ...]], ...] = ()
    bound_study: float | None = None
    baselines: tuple[tuple[str, float | None, float | None], ...] = ()

    def to_dict(self) -> dict[str, Any]:
        return dataclasses.asdict(self)


def _cpu() -> float:
    """CPU seconds of this process and its finished children."""
    t = os.times()
    return t.user + t.system + t.children_user + t.children_system


class _StationClock:
    """A ``progress`` callback for a station's :func:`weldplan.plan` that takes the CPU seconds
    of its phases in this process, named as :attr:`weldplan.multi.station.StationPlan.stats`
    names their wall seconds: the cell (until the first study), each robot's study, the
    allocation (every round's, :mod:`weldplan.multi.calibrate`: from the last study or
    ``("allocation", round, rounds)`` to ``("plan", 0, n)``, and from ``("plan", n, n)`` to the
    next round), the robots' shares (``"shares"``, from ``("plan", 0, n)`` to ``("plan", n,
    n)``, summed over the rounds: with a process pool, its workers' CPU too) and what follows
    ``("interference", 0, R)`` (``"interference"``: the interference, the zones, the replay).
    Each share's own CPU, whole and by stage, is measured where it ran
    (:mod:`weldplan.multi.shares`) and read from the plan's ``stats["cpu"]``."""

    def __init__(self) -> None:
        self.t0 = _cpu()
        self.cpu: dict[str, float] = {}
        self.mark = self.t0
        self.phase = "cell"

    def _close_phase(self, next_phase: str) -> None:
        now = _cpu()
        self.cpu[self.phase] = round(self.cpu.get(self.phase, 0.0) + now - self.mark, 2)
        self.phase, self.mark = next_phase, now

    def __call__(self, name: str, done: int, total: int) -> None:
        if name == "study":  # (study, k, R) as robot k's study starts; (study, R, R) at the end
            self._close_phase(f"study robot{done + 1}" if done < total else "allocation")
        elif name in ("allocation", "interference"):
            self._close_phase(name)
        elif name == "plan" and done == total:
            self._close_phase("allocation")
        elif name == "plan" and done == 0:
            self._close_phase("shares")

    def finish(self) -> dict[str, float]:
        self._close_phase("done")
        self.cpu.pop("done", None)
        return self.cpu


def demo_two_robots() -> Any:
    """The demo station (``examples/demo_station.toml``: the demo part, its 15 welds, the
    shared spot gun) with two KR 150 at :data:`DEMO_BASES` instead of its one searched base, both
    at home :data:`DEMO_HOME`."""
    from weldplan.station import load_station

    st = load_station(ROOT / "examples" / "demo_station.toml")
    spec = st.robots[0]
    spec = dataclasses.replace(spec, settings=dataclasses.replace(spec.settings, home=DEMO_HOME))
    specs = tuple(dataclasses.replace(spec, base=b) for b in DEMO_BASES)
    return dataclasses.replace(st, robots=specs, name="demo-2-robots")


def plan_row(
    station: Any,
    name: str,
    seed: int,
    pages: Path | None = None,
    jobs: int | None = None,
    baselines: bool = False,
) -> StationRow:
    """Plan ``station`` with :func:`weldplan.plan` and measure it; with ``pages``, write its
    station page and Gantt chart there (``<name>.html``, ``<name>_gantt.png``) and the plan
    (``<name>_station.json``, the robots' route JSONs beside it); with ``jobs``,
    on that many processes (the robots' shares in parallel: :mod:`weldplan.multi.shares`);
    with ``baselines``, the baselines' allocations planned and timed too
    (:func:`timed_baselines`)."""
    import weldplan

    if jobs is not None:
        station = dataclasses.replace(station, jobs=jobs)
    clock = _StationClock()
    t0 = time.perf_counter()
    p = weldplan.plan(station, rng=seed, progress=clock)
    wall_total, cpu = round(time.perf_counter() - t0, 2), clock.finish()
    cpu |= {k: round(v, 2) for k, v in p.stats.get("cpu", {}).items() if k != "shares"}
    cpu_total = round(_cpu() - clock.t0, 2)
    if not hasattr(p, "schedule"):
        raise WeldplanError(f"{name}: one robot; `weldplan bench robot` measures single robots")
    rep, s = p.report, p.schedule
    replay = p.replay
    wall = {k: round(v, 2) for k, v in p.stats.get("seconds", {}).items()}
    for k, sub in enumerate(p.plans):
        for stage in () if sub is None else sub.stages:
            wall[f"robot{k + 1} {stage.name}"] = round(stage.seconds, 2)
    rows = []
    for r, rname in enumerate(s.robots):
        timed = p.timed_cycles[r]
        rows.append((rname, len(rep.ours.welds_of(r)), round(rep.ours.shares[r].cycle_time, 3),
                     None if timed is None else round(timed, 3), round(s.utilisation[r], 3),
                     round(s.waiting[r], 3)))  # fmt: skip
    if pages is not None:
        _write_pages(p, name, pages)
    planned = timed_baselines(p, seed, wall, cpu) if baselines else ()
    return StationRow(
        name, "planned", len(rep.ours.welds), len(s.robots), len(rep.ours.unreached),
        _cycle(rep.one_robot), _cycle(rep.nearest), round(rep.ours.cycle_time, 3),
        round(rep.bound.value, 3), rep.bound.name, round(s.cycle_time, 3),
        round(sum(s.waiting), 3), len(s.interlocks),
        None if replay is None else _finite(replay.min_distance),
        None if replay is None else replay.ok, tuple(rows), wall, cpu, wall_total,
        cpu_total, tuple(round(v, 2) for v in os.getloadavg()),
        f"{p.interference}; shares planned {p.stats.get('shares', 'in turn')} "
        f"(jobs {station.jobs})",
        tuple((round(c.model_cycle, 3), round(c.timed_cycle, 3), c.planned) for c in p.rounds),
        None if rep.bound.at_study_poses is None else round(rep.bound.at_study_poses, 3),
        planned,
    )  # fmt: skip


def timed_baselines(
    p: Any, seed: int, wall: dict[str, float], cpu: dict[str, float]
) -> tuple[tuple[str, float | None, float | None], ...]:
    """The baselines of ``p``'s report (:mod:`weldplan.multi.baselines`: one robot, nearest
    robot) planned as our allocation is: each robot's share through the single-robot
    pipeline at its base (:func:`weldplan.multi.shares.plan_shares`, the station's seed) and
    timed by its program; ``(name, modelled cycle s, timed cycle s)`` per allocation, ours
    (the best round's plans) last. The timed cycle is the slowest robot's program, without
    interlock waits (the rounds' measure: no interference stage runs for a baseline); None
    when the report has no such baseline. Each baseline's wall and CPU seconds go to
    ``wall`` and ``cpu`` (``"baseline nearest-robot"``...)."""
    from weldplan.multi.shares import plan_shares

    out = []
    for a in (p.report.one_robot, p.report.nearest):
        if a is None:
            continue
        t0, c0 = time.perf_counter(), _cpu()
        got = plan_shares(p.station, a, seed=seed)
        wall[f"baseline {a.method}"] = round(time.perf_counter() - t0, 2)
        cpu[f"baseline {a.method}"] = round(_cpu() - c0, 2)
        times = [pl.program.timing.total for pl in got.plans if pl is not None]
        out.append((a.method, round(a.cycle_time, 3), round(max(times, default=0.0), 3)))
    best = min((r.timed_cycle for r in p.rounds), default=None)
    out.append(("ours", round(p.report.ours.cycle_time, 3), _round3(best)))
    return tuple(out)


def _round3(v: float | None) -> float | None:
    return None if v is None else round(float(v), 3)


def _cycle(a: Any) -> float | None:
    return None if a is None else round(a.cycle_time, 3)


def _finite(v: float) -> float | None:
    return None if not np.isfinite(v) else round(float(v), 2)


def _write_pages(p: Any, name: str, folder: Path) -> None:
    from weldplan.multi.saved import save_station_plan
    from weldplan.viz.gantt import gantt_png
    from weldplan.viz.station_page import station_page

    folder.mkdir(parents=True, exist_ok=True)
    save_station_plan(p, folder / f"{name}_station.json")  # `weldplan verify` re-checks it
    gantt_png(p.schedule, folder / f"{name}_gantt.png", bound=p.report.bound.value,
              title=f"{name}: {len(p.schedule.robots)} robots")  # fmt: skip
    station_page(p, folder / f"{name}.html")


def synthetic_station(W: int, R: int, seed: int) -> tuple[Any, np.ndarray, np.ndarray]:
    """``(ReachMap, weld_time (R, W) s, travel (R, W, W) s)``: ``W`` welds spread over a
    3 x 1.6 x 0.6 m body, ``R`` robots at :data:`SYNTH_BASES`, a weld served by every robot
    within :data:`SYNTH_REACH_MM` (and always by the nearest); move times the rest-to-rest
    joint-space bounds (:func:`weldplan.robot.route.rest_to_rest_bound`) between synthetic
    configurations that vary smoothly with the weld's position."""
    from weldplan.multi import ReachMap
    from weldplan.robot.route.legtime import rest_to_rest_bound

    if not 1 <= R <= len(SYNTH_BASES):
        raise WeldplanError(f"synthetic stations have 1 to {len(SYNTH_BASES)} robots, not {R}")
    g = np.random.default_rng(seed)
    pos = g.uniform([-1500, -800, 0], [1500, 800, 600], (W, 3))
    bases = SYNTH_BASES[:R]
    d = np.linalg.norm(pos[None] - bases[:, None], axis=2)
    ok = d < SYNTH_REACH_MM
    ok[np.argmin(d, axis=0), np.arange(W)] = True
    Q = np.stack(
        [
            np.c_[
                np.arctan2(pos[:, 1] - b[1], pos[:, 0] - b[0]),
                (pos - b) @ g.normal(size=(3, 5)) / 2000,
            ]
            for b in bases
        ]
    )
    T = np.stack([rest_to_rest_bound(q[:, None] - q[None], SYNTH_VEL, 3.0 * SYNTH_VEL) for q in Q])
    return ReachMap.of(ok, bases=bases, positions=pos), np.full((R, W), SYNTH_WELD_S), T


def synthetic_row(W: int, R: int, seed: int) -> StationRow:
    """The allocation report of :func:`synthetic_station` ``(W, R, seed)``, measured."""
    from weldplan.multi import allocation_report

    reach, wt, T = synthetic_station(W, R, seed)
    t0, c0 = time.perf_counter(), _cpu()
    rep = allocation_report(reach, wt, T, rng=seed)
    wall, cpu = round(time.perf_counter() - t0, 2), round(_cpu() - c0, 2)
    unique = int((reach.ok.sum(axis=0) == 1).sum())
    return StationRow(
        f"synthetic-{W}-{R}", "allocation only", W, R, len(rep.ours.unreached),
        _cycle(rep.one_robot), _cycle(rep.nearest), round(rep.ours.cycle_time, 3),
        round(rep.bound.value, 3), rep.bound.name, wall_s={"allocation": wall},
        cpu_s={"allocation": cpu}, wall_total=wall, cpu_total=cpu,
        load=tuple(round(v, 2) for v in os.getloadavg()),
        note=f"{unique} welds served by one robot only",
    )  # fmt: skip


def _pct(a: float | None, b: float | None) -> str:
    return "-" if a is None or b is None or b <= 0 else f"{100 * (a / b - 1):+.1f} %"


def _s(v: float | None) -> str:
    return "-" if v is None else f"{v:.2f}"


def format_page(rows: list[StationRow], command: str, machine: str) -> str:
    """The markdown page (``station.md``): the cycle-time table, per robot, per stage."""
    from weldplan.bench.common import table

    out = ["# Stations of several robots (weldplan bench station)", "",
           f"Command: `{command}`  ", f"Machine: {machine}", "",
           "Cycle times in s. *one robot*, *nearest robot*, *ours* and *bound* are the "
           "allocation's (its leg-time model: the robots' move times between the welds they "
           "reach plus the weld time); *timed* is the station's cycle over the robots' timed "
           "programs on one clock, waits included. *vs bound* and *vs nearest*: ours over them. "
           "*round 1*: the first allocation's model and timed cycle (no waits), before the "
           "planned legs' timed values replace their model times; *ours* and *timed* are the "
           "best round's (weldplan.multi.calibrate).",
           ""]  # fmt: skip
    head = ["station", "kind", "welds", "robots", "unreached", "one robot", "nearest robot",
            "ours", "bound", "ours vs bound", "ours vs nearest", "timed", "waits s",
            "interlocks", "replay min mm", "round 1 ours / timed", "rounds", "wall s", "CPU s",
            "load"]  # fmt: skip
    body = [[r.name, r.kind, r.welds, r.robots, r.unreached, _s(r.one_robot), _s(r.nearest),
             _s(r.ours), _s(r.bound), _pct(r.ours, r.bound), _pct(r.ours, r.nearest),
             _s(r.timed), _s(r.waiting), "-" if r.interlocks is None else r.interlocks,
             _replay(r), _first(r), len(r.rounds) or "-", f"{r.wall_total:.1f}",
             f"{r.cpu_total:.1f}",
             " ".join(f"{v:.1f}" for v in r.load)] for r in rows]  # fmt: skip
    out += [table(head, body), ""]
    for r in rows:
        out += [f"## {r.name}", "", f"Bound: {r.bound_name}.", ""]
        if r.bound_study is not None:
            out += [f"The same bound over the study's gun poses (all IK branches): "
                    f"{r.bound_study:.2f} s; it holds only where the plans keep those poses.",
                    ""]  # fmt: skip
        if r.note:
            out += [f"Note: {r.note}.", ""]
        if r.baselines:
            ours = r.baselines[-1][2]
            bh = ["allocation", "modelled s", "planned and timed s", "ours (timed) vs it"]
            body = [[n, _s(m), _s(t), _pct(ours, t) if n != "ours" else "-"]
                    for n, m, t in r.baselines]  # fmt: skip
            out += ["Baselines planned and timed (each share through the single-robot "
                    "pipeline; the slowest program, no interlock waits):", "",
                    table(bh, body), ""]  # fmt: skip
        if r.rounds:
            rh = ["round", "ours (model) s", "timed s", "robots planned"]
            body = [[k + 1, f"{m:.2f}", f"{t:.2f}", ", ".join(f"robot{i + 1}" for i in p)]
                    for k, (m, t, p) in enumerate(r.rounds)]  # fmt: skip
            out += [table(rh, body), ""]
        if r.robots_rows:
            rh = ["robot", "welds", "allocated s", "timed s", "utilisation", "waiting s"]
            out += [table(rh, [[n, w, f"{a:.2f}", _s(t), f"{u:.0%}", f"{ws:.2f}"]
                               for n, w, a, t, u, ws in r.robots_rows]), ""]  # fmt: skip
        stages = list(dict.fromkeys([*r.wall_s, *r.cpu_s]))
        body = [[k, _s(r.wall_s.get(k)), _s(r.cpu_s.get(k))] for k in stages]
        out += [table(["stage", "wall s", "CPU s"], body), ""]
    return "\n".join(out)


def _first(r: StationRow) -> str:
    return "-" if not r.rounds else f"{r.rounds[0][0]:.2f} / {r.rounds[0][1]:.2f}"


def _replay(r: StationRow) -> str:
    if r.replay_ok is None:
        return "not checked" if r.kind == "planned" else "-"
    return f"{_s(r.replay_min)} ({'ok' if r.replay_ok else 'FAIL'})"


def parse_synthetic(text: str) -> tuple[tuple[int, int], ...]:
    """``"100:2,400:4"`` -> ``((100, 2), (400, 4))``: welds and robots per station."""
    try:
        out = tuple((int(a), int(b)) for a, b in (p.split(":") for p in text.split(",")))
    except ValueError:
        out = ()
    if not out or any(w < 1 or not 1 <= r <= len(SYNTH_BASES) for w, r in out):
        raise argparse.ArgumentTypeError(
            f"synthetic stations are W:R,... (welds >= 1, 1 to 4 robots), got {text!r}"
        )
    return out


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--station", action="append", default=[], metavar="TOML",
                   help="plan this station file too (repeatable)")  # fmt: skip
    p.add_argument("--no-demo", action="store_true", help="skip the demo two-robot station")
    p.add_argument("--synthetic", type=parse_synthetic, default=(), metavar="W:R,...",
                   help="allocation-only synthetic stations, e.g. 100:2,400:4")  # fmt: skip
    p.add_argument("--seed", type=int, default=0, help="every station's seed (default 0)")
    p.add_argument("--pages", action="store_true",
                   help="write each planned station's page and Gantt chart to --out")  # fmt: skip
    p.add_argument("--car2", action="store_true",
                   help="plan the car2 stations too: upright in a cell, the straight arc "
                   "torch, 200 welds on 2 robots and 400 on 4 (examples/car2_upright_*.toml; "
                   "slow)")  # fmt: skip
    p.add_argument("--plan-baselines", action="store_true",
                   help="also plan and time the one-robot and nearest-robot allocations of "
                   "each planned station (each a full plan of its shares; slow)")  # fmt: skip
    p.add_argument("--jobs", type=_jobs, default=None, metavar="N",
                   help="processes per planned station: the robots' shares in parallel "
                   "(default: each station's own jobs)")  # fmt: skip


def _jobs(text: str) -> int:
    try:
        n = int(text)
    except ValueError:
        n = 0
    if n < 1:
        raise argparse.ArgumentTypeError(f"--jobs must be an integer >= 1, got {text!r}")
    return n


def run(args: argparse.Namespace) -> int:
    from weldplan.bench.common import conditions
    from weldplan.station import load_station

    out = Path(args.out)
    pages = out if args.pages else None
    rows: list[StationRow] = []
    before = conditions()
    try:
        stations = [] if args.no_demo else [(demo_two_robots(), "demo-2-robots")]
        files = [Path(f) for f in args.station]
        if getattr(args, "car2", False):
            files += [ROOT / "examples" / f for f in CAR2_STATIONS]
        stations += [(load_station(f), f.stem) for f in files]
        for st, name in stations:
            rows.append(plan_row(st, name, args.seed, pages, getattr(args, "jobs", None),
                                 getattr(args, "plan_baselines", False)))  # fmt: skip
            print(f"{name}: timed cycle {rows[-1].timed:.2f} s", flush=True)
        for W, R in args.synthetic:
            rows.append(synthetic_row(W, R, args.seed))
            print(f"{rows[-1].name}: ours {rows[-1].ours:.2f} s", flush=True)
    except WeldplanError as exc:
        print(f"error: {exc}")
        return 2
    command = "weldplan bench station " + " ".join(_argv(args))
    page = format_page(rows, command.strip(), f"{before} before; {conditions()} after")
    out.mkdir(parents=True, exist_ok=True)
    (out / "station.md").write_text(page + "\n")
    (out / "station.json").write_text(json.dumps([r.to_dict() for r in rows], indent=1) + "\n")
    print(page)
    return 0


def _argv(args: argparse.Namespace) -> list[str]:
    out = [f"--station {f}" for f in args.station]
    if args.no_demo:
        out.append("--no-demo")
    if args.synthetic:
        out.append("--synthetic " + ",".join(f"{w}:{r}" for w, r in args.synthetic))
    if args.seed:
        out.append(f"--seed {args.seed}")
    if args.pages:
        out.append("--pages")
    if getattr(args, "car2", False):
        out.append("--car2")
    if getattr(args, "jobs", None) is not None:
        out.append(f"--jobs {args.jobs}")
    if getattr(args, "plan_baselines", False):
        out.append("--plan-baselines")
    return out
