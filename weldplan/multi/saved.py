"""A station of several robots as files: per robot its own files, one station JSON above them.

:func:`station_paths` names every file a station plan writes from the station's
:class:`~weldplan.station.model.OutputSpec` (each robot's files are the station's names with
``_robot1``, ``_robot2`` ... before the suffix; the route JSON and the trajectory CSV of every
robot are always written, since the station JSON points at them; the ``html`` name is the
station's page, :func:`weldplan.viz.station_page.station_page_text`, with its Gantt chart as a
PNG beside it, ``<stem>_gantt.png``, :func:`weldplan.viz.gantt.gantt_png_bytes`);
:func:`write_station` renders them in memory (each robot's program with the interlock signals
the plan gave it, :func:`robot_plans`) and
writes them as one set, whole or not at all (:func:`weldplan.io.outputset.write_outputs`).

The station JSON (``route_station.json`` beside ``route.json``) holds what no robot's file
can: the allocation report (ours, the baselines, the lower bound), the station's schedule
(:meth:`~weldplan.multi.schedule.StationSchedule.to_dict`, interlocks included), the replay's
verdict (``null``: robot-robot interference not checked), the allocate-plan rounds (``rounds``:
per round the allocation's cycle, the timed cycle, each robot's timed cycle and the robots
re-planned; a file without them reads as none), and per robot the names of its route JSON,
trajectory and program, relative to the station JSON's folder. :func:`load_station_plan`
reads it into a frozen :class:`SavedStationPlan`; :meth:`SavedStationPlan.verify` re-checks it
(:mod:`weldplan.multi.recheck`), which is what ``weldplan verify STATION_JSON`` runs::

    splan = weldplan.plan(station, rng=0)            # a StationPlan
    weldplan.save_station_plan(splan, "out/station.json")  # + out/station_robot1.json, ...
    saved = weldplan.load_station_plan("out/station.json")
    saved.verify().exit_code
"""

from __future__ import annotations

import dataclasses
import json
import os
from dataclasses import dataclass
from os import PathLike
from pathlib import Path
from typing import Any

import numpy as np

from weldplan.errors import InputError
from weldplan.multi.result import AllocationReport
from weldplan.multi.schedule import ReplayVerdict, StationSchedule

#: the station JSON's ``format`` entry, and its version
STATION_FORMAT = "weldplan station plan"
FORMAT_VERSION = 1


def robot_path(path: Path, k: int) -> Path:
    """``route.csv`` -> ``route_robot1.csv`` for robot ``k`` (0-based)."""
    return path.with_name(f"{path.stem}_robot{k + 1}{path.suffix}")


@dataclass(frozen=True)
class StationPaths:
    """Every file of a station plan.

    Attributes
    ----------
    station
        The station JSON.
    robots
        Per robot ``{kind: path}`` (the kinds of
        :func:`weldplan.station.outputs.output_paths`: ``csv``, ``json``, ``timings``,
        ``trajectory``, ``post``, ``post_dat``...).
    post
        The programs' language (``"rapid"``, ``"krl"``; ``None``: no program).
    html, gantt
        The station's page and its Gantt chart (PNG) beside it (``None``: not written).
    """

    station: Path
    robots: tuple[dict[str, Path], ...]
    post: str | None = None
    html: Path | None = None
    gantt: Path | None = None

    def all(self) -> dict[str, Path]:
        """``{"station": ..., "robot1 csv": ...}``: every file, named for messages."""
        out = {"station": self.station}
        if self.html is not None and self.gantt is not None:
            out |= {"station html": self.html, "station gantt": self.gantt}
        for k, paths in enumerate(self.robots):
            out |= {f"robot{k + 1} {kind}": p for kind, p in paths.items()}
        return out


def station_paths(out: Any, n_robots: int) -> StationPaths:
    """The files of a station of ``n_robots`` robots from ``out``
    (:class:`~weldplan.station.model.OutputSpec`), checked before any work: every folder
    writable, no file named twice. The station JSON is the ``json`` name (else the route
    CSV's, with ``.json``) with ``_station`` before the suffix."""
    from weldplan.errors import WeldplanError
    from weldplan.io.outputset import check_outputs
    from weldplan.station.outputs import output_paths

    if out.csv is None:
        raise WeldplanError("no route CSV to write: give -o (or [output] csv in the station)")
    base = out.json or out.csv.with_suffix(".json")
    station = base.with_name(f"{base.stem}_station{base.suffix}")
    robots = tuple(
        output_paths(_robot_outputs(out, k), robot=True, tool=True) for k in range(n_robots)
    )
    html = out.html
    gantt = None if html is None else html.with_name(f"{html.stem}_gantt.png")
    paths = StationPaths(station, robots, out.post, html, gantt)
    seen: dict[Path, str] = {}
    for kind, p in paths.all().items():
        if p.resolve() in seen:
            raise WeldplanError(f"{p}: given for both {seen[p.resolve()]} and {kind}")
        seen[p.resolve()] = kind
    check_outputs({k: p for k, p in paths.all().items() if k.startswith("station")})
    return paths


def _robot_outputs(out: Any, k: int) -> Any:
    """Robot ``k``'s :class:`~weldplan.station.model.OutputSpec`: every name with
    ``_robot<k+1>`` (but ``html``, the station's page); the route JSON and the trajectory
    always."""
    kw = {
        f.name: robot_path(getattr(out, f.name), k)
        for f in dataclasses.fields(out)
        if f.name not in ("post", "html") and getattr(out, f.name) is not None
    }
    kw["html"] = None
    kw.setdefault("json", robot_path(out.csv.with_suffix(".json"), k))
    kw.setdefault("trajectory", robot_path(out.csv.with_name(f"{out.csv.stem}_trajectory.csv"), k))
    return dataclasses.replace(out, **kw)


def robot_plans(splan: Any) -> tuple[Any, ...]:
    """Per robot its :class:`~weldplan.station.pipeline.Plan` as written (``None``: idle): the
    program named ``<station>_robot<k>``, its interlock signals as the plan's program carries
    them (:func:`weldplan.multi.station.with_signals`, the one mapping from the schedule's
    interlocks to signals), a note naming the station."""
    base = splan.station.name or "weldplan_route"
    return tuple(
        None if p is None else _robot_plan(splan, p, f"{base}_robot{k + 1}", k)
        for k, p in enumerate(splan.plans)
    )


def _robot_plan(splan: Any, plan: Any, name: str, k: int) -> Any:
    build = plan.program
    note = (
        f"Station '{splan.station.name or 'weldplan_route'}': robot {k + 1} of "
        f"{len(splan.plans)}; {splan.interference}."
    )
    prog = dataclasses.replace(build.program, name=name, notes=(*build.program.notes, note))
    station = dataclasses.replace(plan.station, name=name)
    return dataclasses.replace(
        plan, station=station, program=dataclasses.replace(build, program=prog)
    )


def station_dict(splan: Any, paths: StationPaths) -> dict[str, Any]:
    """The station JSON's content (module docstring); file names relative to its folder."""
    from weldplan._version import __version__

    st, folder = splan.station, paths.station.parent

    def rel(p: Path | None) -> str | None:
        return None if p is None else Path(os.path.relpath(p, folder or ".")).as_posix()

    robots = []
    for k, spec in enumerate(st.robots):
        files = paths.robots[k] if splan.plans[k] is not None else {}
        robots.append({
            "name": splan.allocation.robots[k],
            "urdf": None if spec.urdf is None else str(spec.urdf),
            "base": None if spec.base is None else list(spec.base),
            "welds": list(splan.allocation.welds_of(k)),
            "route": rel(files.get("json")),
            "trajectory": rel(files.get("trajectory")),
            "program": [rel(files[x]) for x in ("post", "post_dat") if x in files],
            "timed_cycle": splan.timed_cycles[k],
            "rows": _route_rows(splan.plans[k]),
        })  # fmt: skip
    sched = splan.schedule
    return {
        "format": STATION_FORMAT,
        "version": FORMAT_VERSION,
        "producer": {"weldplan": __version__, "station": st.name or "weldplan_route"},
        "station_file": None if st.source is None else str(st.source),
        "seed": splan.seed,
        "robots": robots,
        "allocation": splan.report.to_dict(),
        "schedule": None if sched is None else sched.to_dict(),
        "cycle_time": splan.cycle_time if sched is None else sched.cycle_time,
        "interference": splan.interference,
        "replay": None if splan.replay is None else splan.replay.to_dict(),
        "rounds": [c.to_dict() for c in getattr(splan, "rounds", ())],
    }


def _route_rows(plan: Any) -> list[int] | None:
    """The route row of each timed row of a robot's program (its
    :attr:`~weldplan.robot.program.ProgramBuild.row`; the identity when it has none), which
    names the program's target of each row the schedule's interlocks name; ``None`` for an
    idle robot."""
    if plan is None or plan.program is None:
        return None
    build = plan.program
    rows = build.row if build.row is not None else range(len(build.timing.row_times))
    return [int(r) for r in rows]


def station_texts(splan: Any, paths: StationPaths) -> dict[Path, str | bytes]:
    """Every file of ``paths`` rendered in memory: per robot its files
    (:func:`weldplan.station.outputs.render_outputs` of :func:`robot_plans`; each program
    parsed back and re-solved by FK), then the station JSON."""
    from weldplan.station.outputs import render_outputs

    texts: dict[Path, str | bytes] = {}
    for plan, files in zip(robot_plans(splan), paths.robots, strict=True):
        if plan is None:
            continue
        rendered = render_outputs(plan, set(files), paths.post)
        texts |= {p: rendered[kind] for kind, p in files.items()}
    d = station_dict(splan, paths)
    texts[paths.station] = json.dumps(d, indent=1, allow_nan=False) + "\n"
    if paths.html is not None and paths.gantt is not None:
        from weldplan.viz.gantt import gantt_png_bytes
        from weldplan.viz.station_page import station_page_text

        texts[paths.html] = station_page_text(splan)
        bound = float(splan.report.bound.value)
        title = f"{splan.station.name or 'weldplan_route'}: {len(splan.plans)} robots"
        texts[paths.gantt] = gantt_png_bytes(splan.schedule, bound=bound, title=title)
    return texts


def write_station(splan: Any, paths: StationPaths) -> None:
    """Render every file, then write them as one set, whole or not at all."""
    from weldplan.io.outputset import write_outputs

    write_outputs(station_texts(splan, paths))


def save_station_plan(splan: Any, path: str | PathLike[str]) -> Path:
    """Write the station JSON ``path`` and beside it, per robot with welds, its route JSON
    (``<stem>_robot<k>.json`` and its timings) and trajectory CSV, as one set. Returns
    ``path``. The programs are the CLI's (``--post``); their signals are the plan's programs'."""
    from weldplan.station.model import OutputSpec

    path = Path(path)
    stem = path.stem[: -len("_station")] if path.stem.endswith("_station") else path.stem
    out = OutputSpec(csv=path.with_name(f"{stem}.csv"), json=path.with_name(f"{stem}.json"))
    paths = station_paths(out, len(splan.plans))
    paths = StationPaths(
        path, tuple({k: v for k, v in r.items() if k != "csv"} for r in paths.robots)
    )
    write_station(splan, paths)
    return path


@dataclass(frozen=True)
class SavedRobot:
    """One robot of a saved station: its name, given base and URDF, its share of the welds
    (visiting order), and its files (absolute, ``None``: not written; ``program``: empty
    without ``--post``); ``rows``: the route row of each timed row of its program (``None``:
    not recorded, an idle robot or a plan saved before they were)."""

    name: str
    urdf: str | None
    base: tuple[float, ...] | None
    welds: tuple[str, ...]
    route: Path | None
    trajectory: Path | None
    program: tuple[Path, ...]
    timed_cycle: float | None
    rows: tuple[int, ...] | None = None


@dataclass(frozen=True)
class SavedStationPlan:
    """A station plan read back from its station JSON (:func:`load_station_plan`).

    Attributes
    ----------
    path
        The station JSON.
    station_file
        The station file it was planned from, as recorded (``None``: built in Python).
    robots
        :class:`SavedRobot` per robot, station order.
    report
        The :class:`~weldplan.multi.result.AllocationReport`.
    schedule
        The :class:`~weldplan.multi.schedule.StationSchedule` (``None``: none recorded).
    cycle_time
        s: the station's cycle as recorded.
    interference
        The plan's line on robot-robot interference.
    replay
        The replay's :class:`~weldplan.multi.schedule.ReplayVerdict`; ``None``: the plan says
        interference was not checked.
    rounds
        The allocate-plan rounds (:class:`~weldplan.multi.calibrate.CalibrationRound`: the
        allocation's cycle, the timed cycle, the robots re-planned), in order; empty in a file
        written before they were recorded.
    """

    path: Path
    station_file: str | None
    robots: tuple[SavedRobot, ...]
    report: AllocationReport
    schedule: StationSchedule | None
    cycle_time: float
    interference: str
    replay: ReplayVerdict | None
    rounds: tuple[Any, ...] = ()

    @property
    def kept_round(self) -> int | None:
        """The index of the round the station keeps, by the rule of
        :func:`weldplan.multi.calibrate.allocate_and_plan`: a round whose timed cycle drops
        (by more than its ``EPS_S``) is kept, and so is one that re-planned nothing at the
        kept cycle (the same plans, a newer allocation); ``None``: no round recorded."""
        from weldplan.multi.calibrate import EPS_S

        kept = None
        for k, c in enumerate(self.rounds):
            best = np.inf if kept is None else self.rounds[kept].timed_cycle
            if c.timed_cycle < best - EPS_S or (not c.planned and c.timed_cycle <= best + EPS_S):
                kept = k
        return kept

    def rounds_lines(self) -> list[str]:
        """One line a round: its allocation's cycle, its timed cycle and the robots it
        re-planned (the kept one marked); empty when none is recorded."""
        kept = self.kept_round
        names = [r.name for r in self.robots]
        out = []
        for k, c in enumerate(self.rounds):
            planned = ", ".join(names[i] if i < len(names) else str(i) for i in c.planned)
            out.append(
                f"round {k + 1}: allocation {c.model_cycle:.2f} s, timed {c.timed_cycle:.2f} s, "
                f"re-planned {planned or 'none'}{' (kept)' if k == kept else ''}"
            )
        return out

    def load_station(self) -> Any:
        """The :class:`~weldplan.station.model.Station` the plan records (its station file,
        as given or beside the station JSON), read again. Raises
        :class:`~weldplan.errors.InputError` when it records none."""
        from weldplan.station.load import load_station

        if self.station_file is None:
            raise InputError("the plan records no station file: give the station", path=self.path)
        f = Path(self.station_file)
        if not f.is_file() and (self.path.parent / f).is_file():
            f = self.path.parent / f
        return load_station(f)

    def page_text(self, *, station: Any = None) -> str:
        """The station's page (:func:`weldplan.viz.station_page.saved_station_page_text`)
        rebuilt from the saved files; ``station`` default :meth:`load_station`."""
        from weldplan.viz.station_page import saved_station_page_text

        return saved_station_page_text(
            self, station if station is not None else self.load_station()
        )

    def verify(self, *, station: Any = None) -> Any:
        """Re-check the saved plan (:func:`weldplan.multi.recheck.verify_station`; ``station``:
        the :class:`~weldplan.station.model.Station`, default the recorded station file).

        Returns
        -------
        :class:`~weldplan.station.recheck.Verdict`
        """
        from weldplan.multi.recheck import verify_station

        return verify_station(self, station=station)


def is_station_json(path: str | PathLike[str]) -> bool:
    """True when ``path`` is a JSON file whose ``format`` is :data:`STATION_FORMAT` (a route
    JSON is not; an unreadable file is left to its own reader's error)."""
    try:
        with open(path, encoding="utf-8") as f:
            d = json.load(f)
    except (OSError, ValueError):
        return False
    return isinstance(d, dict) and d.get("format") == STATION_FORMAT


def load_station_plan(path: str | PathLike[str]) -> SavedStationPlan:
    """Read the station JSON ``path`` (module docstring).

    Raises
    ------
    InputError
        Not JSON (naming the line), not a station plan, or a field missing or of the wrong
        kind (naming it).
    """
    path = Path(path)
    try:
        d = json.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise InputError(f"cannot read it: {exc.strerror}", path=path) from None
    except json.JSONDecodeError as exc:
        raise InputError(f"not valid JSON: {exc.msg}", path=path, line=exc.lineno) from None
    if not isinstance(d, dict) or d.get("format") != STATION_FORMAT:
        raise InputError(
            f'not a station plan (no "format": "{STATION_FORMAT}"; a route JSON is re-checked '
            "with its mesh)",
            path=path,
        )
    key = "robots"
    try:
        robots = tuple(_robot(path, r) for r in d[key])
        key = "allocation"
        report = AllocationReport.from_dict(d[key])
        key = "schedule"
        sched = None if d.get(key) is None else StationSchedule.from_dict(d[key])
        key = "replay"
        replay = None if d.get(key) is None else ReplayVerdict.from_dict(d[key])
        key = "cycle_time"
        cycle = float(d[key])
        key = "interference"
        note = str(d[key])
        key = "rounds"
        rounds = tuple(_round(c) for c in d.get(key) or ())
    except (KeyError, TypeError, ValueError, AttributeError) as exc:
        why = f"missing {exc}" if isinstance(exc, KeyError) else str(exc)
        raise InputError(f"not a valid entry: {why}", path=path, field=key) from None
    source = d.get("station_file")
    return SavedStationPlan(
        path, None if source is None else str(source), robots, report, sched, cycle, note, replay,
        rounds,
    )  # fmt: skip


def _round(d: dict[str, Any]) -> Any:
    """A :class:`~weldplan.multi.calibrate.CalibrationRound` from its ``to_dict()``."""
    from weldplan.multi.calibrate import CalibrationRound

    return CalibrationRound(
        float(d["model_cycle"]), float(d["timed_cycle"]), tuple(float(v) for v in d["timed"]),
        tuple(int(v) for v in d["planned"]),
    )  # fmt: skip


def _robot(path: Path, r: dict[str, Any]) -> SavedRobot:
    def file(x: Any) -> Path | None:
        return None if x is None else (path.parent / str(x))

    base = r.get("base")
    cycle = r.get("timed_cycle")
    rows = r.get("rows")
    return SavedRobot(
        str(r["name"]), None if r.get("urdf") is None else str(r["urdf"]),
        None if base is None else tuple(float(v) for v in base),
        tuple(str(w) for w in r["welds"]), file(r.get("route")), file(r.get("trajectory")),
        tuple(p for p in (file(x) for x in r.get("program", ())) if p is not None),
        None if cycle is None else float(cycle),
        None if rows is None else tuple(int(v) for v in rows),
    )  # fmt: skip
