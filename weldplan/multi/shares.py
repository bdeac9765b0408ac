"""Each robot's share of a station planned by the single-robot pipeline, in turn or in parallel.

:func:`plan_shares` is step 5 of :func:`weldplan.multi.station.plan_station`: per robot with
welds, :func:`weldplan.station.pipeline.plan` on its sub-station (the station with that robot
alone at its base, the welds file restricted to its share of the allocation). Where the shares
run (issue 30, item 6: the executor/Dask path the route's pair planning already takes,
:mod:`weldplan.weld.parallel`):

* **in turn, in this process** (the default: ``station.jobs`` 1 and no executor, or a single
  share): each share's blocked pairs on the executor given, or on a pool of ``station.jobs``;
* **on an executor**, when the run has one and two or more robots have welds: the executor given
  (``--dask``: a Dask ``Client.get_executor()``, or any ``concurrent.futures.Executor``), or, with
  ``station.jobs`` > 1, a local process pool of ``min(jobs, shares)`` workers. A task carries the
  sub-station (paths and settings) and its share of the welds as CSV text, so a worker needs no
  folder of this process: it writes the share to :func:`share_file` and plans it with
  ``jobs = jobs // workers`` processes (at least 1; 1 on an executor given). A worker of a remote
  Dask cluster must see the station's own files (mesh, URDF, tools) at the same paths.

**The same files either way.** A share's plan is a function of its sub-station and the seed
alone: every stochastic stage draws from the seed (OMPL's process-wide seed is reset by each
call, :mod:`weldplan.motion.sampling`), pair planning does not depend on the executor
(:mod:`weldplan.weld.parallel`), and the share's welds file, which the routes record
(``provenance.joints.source``), is named by its content (:func:`share_file`), not by a random
temporary name. ``tests/test_multi_shares.py`` compares the files of a station planned both
ways byte for byte (but the ``.timings.json``, wall seconds by design).

**What travels back.** A :class:`~weldplan.station.pipeline.Plan` holds live models: the tool's
and the robot's caches (FCL BVHs, the IK solver), the exit test's transition planner
(``PosesResult.planner``: reused by the transitions stage, by nothing after it) and the reach
test's collision checker (``ReachTest.checker``: its counters are what the summary reads). A
worker sends its plan through :class:`_SharePickler`: the tool and robot models whole without their
caches (each rebuilt on first use, as after loading), the planner and the checker left out.

**Progress.** A share's events carry the robot's name: ``("robot2 poses", done, total)``, its
route's too (``"robot2 local"``); the station adds ``("plan", done, shares)`` as shares finish.
In turn they arrive live; from an executor, a share's events arrive when it returns.
"""

from __future__ import annotations

import contextlib
import dataclasses
import functools
import getpass
import hashlib
import io
import logging
import os
import pickle
import tempfile
import time
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import Executor, ProcessPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from weldplan.errors import PlanningError

log = logging.getLogger(__name__)

Progress = Callable[[str, int, int], None]


@dataclass(frozen=True)
class ShareTask:
    """One robot's share as a worker receives it (picklable).

    Attributes
    ----------
    k, name
        The robot's index and name (``"robot2"``) in the station.
    station
        Its sub-station (:func:`sub_station`); ``station.part.welds`` names the station's
        welds file, which the worker replaces by ``welds_csv`` written to a file of its own.
    welds_csv
        The share's welds, CSV text in the welds file's own units and frame.
    seed
        The station's integer seed.
    jobs
        Processes for the share's own blocked pairs.
    """

    k: int
    name: str
    station: Any
    welds_csv: str
    seed: int | None
    jobs: int = 1


@dataclass(frozen=True, eq=False)
class ShareResult:
    """One share planned: its plan, what it reported, what it cost where it ran.

    Attributes
    ----------
    k
        The robot's index.
    plan
        Its :class:`~weldplan.station.pipeline.Plan`.
    events
        ``(stage, done, total)`` progress events, in order, named with the robot.
    seconds, cpu
        Wall and CPU seconds of the share (CPU: the process that planned it and its finished
        children, such as a pair-planning pool).
    stage_cpu
        CPU s per stage of the plan (``"robot2 poses"``).
    """

    k: int
    plan: Any
    events: tuple[tuple[str, int, int], ...]
    seconds: float
    cpu: float
    stage_cpu: dict[str, float] = field(default_factory=dict)


class ShareFailed(PlanningError):
    """One robot's share has no plan: the single-robot pipeline's
    :class:`~weldplan.errors.PlanningError` for it (e.g. every weld of it without a leg from
    or to its home). ``k``: the robot's index; ``welds``: its share's weld ids; ``message``:
    the pipeline's words; ``events``: the share's progress events up to the failure (a share
    planned in a worker reports them in the parent as one planned in turn did live).
    Picklable, so a share planned in a worker raises it in the parent.
    :mod:`weldplan.multi.passes` re-allocates the share's welds away from that robot."""

    def __init__(
        self,
        k: int,
        welds: tuple[str, ...],
        message: str,
        events: tuple[tuple[str, int, int], ...] = (),
    ) -> None:
        super().__init__(f"robot {k + 1}: {message}")
        self.k, self.welds, self.message = int(k), tuple(welds), str(message)
        self.events = tuple(events)

    def __reduce__(self) -> tuple[Any, tuple[Any, ...]]:
        return (ShareFailed, (self.k, self.welds, self.message, self.events))


@dataclass(frozen=True, eq=False)
class Shares:
    """What :func:`plan_shares` returns: per robot its plan (``None``: no weld), the wall and
    CPU seconds (``"plan robot2"``, ``"shares"``: all of them, however they ran; CPU also per
    stage, ``"robot2 poses"``), and where they ran (``"in turn"``, ``"process pool of 2"``,
    ``"executor"``)."""

    plans: tuple[Any, ...]
    seconds: dict[str, float]
    cpu: dict[str, float]
    ran: str


def cpu_seconds() -> float:
    """CPU s of this process and its finished children."""
    t = os.times()
    return t.user + t.system + t.children_user + t.children_system


def sub_station(station: Any, spec: Any, welds: Path) -> Any:
    """The station with robot ``spec`` alone (its base fixed) and ``welds`` as its welds file;
    the part pose, the floor and the settings kept."""
    part = dataclasses.replace(station.part, welds=welds)
    return dataclasses.replace(station, part=part, robots=(spec,))


def welds_file(station: Any, ids: Sequence[str], folder: Path, name: str) -> Path:
    """The station's welds file restricted to ``ids``, in the file's own units and frame (the
    part frame: the sub-station places them with the station's part pose)."""
    from weldplan.io.joints import Joints, read_joints
    from weldplan.io.mesh import unit_scale

    p = station.part
    j = read_joints(p.welds, units=p.units)
    keep = [j.ids.index(i) for i in ids]
    f = unit_scale(p.units)
    d = None if j.directions is None else np.asarray(j.directions)[keep]
    out = folder / f"{name}_welds.csv"
    Joints(ids=tuple(ids), xyz=np.asarray(j.xyz)[keep] / f, directions=d).to_csv(out)
    return out


def share_tasks(station: Any, allocation: Any, seed: int | None, jobs: int) -> list[ShareTask]:
    """A :class:`ShareTask` per robot with welds in ``allocation``
    (:class:`~weldplan.multi.result.Allocation`), in station order."""
    tasks = []
    with tempfile.TemporaryDirectory(prefix="weldplan-station-") as tmp:
        for k, spec in enumerate(station.robots):
            ids = allocation.welds_of(k)
            if not ids:
                continue
            name = allocation.robots[k]
            text = welds_file(station, ids, Path(tmp), name).read_text(encoding="utf-8")
            sub = sub_station(station, spec, Path(station.part.welds))
            tasks.append(ShareTask(k, name, sub, text, seed, jobs))
    return tasks


class _Recorder:
    """The progress of one share: each event named with the robot, kept, passed on live (if
    ``live``), and each pipeline stage's CPU seconds (from its ``(stage, 0, 1)`` to its
    ``(stage, 1, 1)``)."""

    def __init__(self, name: str, live: Progress | None) -> None:
        self.name, self.live = name, live
        self.events: list[tuple[str, int, int]] = []
        self.cpu: dict[str, float] = {}
        self._open: dict[str, float] = {}

    def __call__(self, stage: str, done: int, total: int) -> None:
        event = (f"{self.name} {stage}", int(done), int(total))
        self.events.append(event)
        if total == 1 and done == 0:
            self._open[stage] = cpu_seconds()
        elif total == 1 and done == 1 and stage in self._open:
            self.cpu[f"{self.name} {stage}"] = round(cpu_seconds() - self._open.pop(stage), 2)
        if self.live is not None:
            self.live(*event)


def run_share(
    task: ShareTask, *, executor: Executor | None = None, progress: Progress | None = None
) -> ShareResult:
    """Plan one share in this process: its welds written to :func:`share_file`, the
    single-robot pipeline on its sub-station with ``task.jobs`` processes and ``executor`` for
    its blocked pairs, its events named with the robot (passed on live to ``progress``)."""
    from weldplan.station.pipeline import plan

    rec = _Recorder(task.name, progress)
    t, c = time.perf_counter(), cpu_seconds()
    part = dataclasses.replace(task.station.part, welds=share_file(task.welds_csv, task.name))
    sub = dataclasses.replace(task.station, part=part, jobs=task.jobs)
    log.info("station: %s plans its share", task.name)
    try:
        p = plan(sub, rng=task.seed, executor=executor, progress=rec)
    except ShareFailed:
        raise
    except PlanningError as exc:  # this robot has no plan of its share: re-allocated above
        from weldplan.io.joints import read_joints

        ids = read_joints(part.welds).ids
        raise ShareFailed(task.k, ids, str(exc), tuple(rec.events)) from None
    stages = {f"{task.name} {s.name}" for s in p.stages}
    stage_cpu = {k: v for k, v in rec.cpu.items() if k in stages}
    return ShareResult(
        task.k, p, tuple(rec.events), time.perf_counter() - t, cpu_seconds() - c, stage_cpu
    )


def share_file(text: str, name: str) -> Path:
    """The file a share's welds (CSV ``text``) are read from: ``<name>_welds.csv`` in a folder
    of the system's temporary folder named by the text's SHA-256, ``weldplan-shares-<user>/
    <digest>/``. The same share gets the same path in any process and run (the routes record
    it), and the file holds exactly what was planned. Written whole (a unique file renamed
    over it), so runs of the same share at once read the same bytes; left in place (a few kB)
    for the same reason."""
    digest = hashlib.sha256(text.encode("utf-8")).hexdigest()[:16]
    folder = Path(tempfile.gettempdir()) / f"weldplan-shares-{getpass.getuser()}" / digest
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"{name}_welds.csv"
    if not path.is_file() or path.read_text(encoding="utf-8") != text:
        with tempfile.NamedTemporaryFile(
            "w", encoding="utf-8", dir=folder, suffix=".part", delete=False
        ) as fh:
            fh.write(text)
        os.replace(fh.name, path)
    return path


def _remote(task: ShareTask) -> bytes:
    """An executor's task: :func:`run_share`, its result pickled by :class:`_SharePickler`."""
    return dumps(run_share(task))


def _rebuilt(cls: type, state: dict[str, Any]) -> Any:
    """An instance of ``cls`` with ``state`` as its attributes (frozen dataclasses included)."""
    obj = cls.__new__(cls)
    for k, v in state.items():
        object.__setattr__(obj, k, v)
    return obj


@functools.cache
def _live_types() -> tuple[type, type, type, type]:
    """``(Tool, Robot, ReachTest, PosesResult)``, imported once."""
    from weldplan.robot.model.arm import Robot
    from weldplan.robot.placement.posechoice import ReachTest
    from weldplan.station.toolstage import PosesResult
    from weldplan.tool.model.tool import Tool

    return Tool, Robot, ReachTest, PosesResult


class _SharePickler(pickle.Pickler):
    """Pickles a share's result (module docstring, *What travels back*): the tool and robot
    models without their caches, the exit test's planner and the reach test's checker as
    ``None``."""

    def reducer_override(self, obj: Any) -> Any:
        tool, robot, reach_test, poses = _live_types()
        if isinstance(obj, (tool, robot)):
            return _rebuilt, (type(obj), {**vars(obj), "_cache": {}})
        if isinstance(obj, reach_test):
            return _rebuilt, (type(obj), {**vars(obj), "checker": None})
        if isinstance(obj, poses):
            return _rebuilt, (type(obj), {**vars(obj), "planner": None})
        return NotImplemented


def dumps(result: ShareResult) -> bytes:
    """``result`` pickled as a worker sends it (:class:`_SharePickler`)."""
    buf = io.BytesIO()
    _SharePickler(buf, protocol=pickle.HIGHEST_PROTOCOL).dump(result)
    return buf.getvalue()


@contextlib.contextmanager
def _share_executor(
    station: Any, executor: Executor | None, shares: int
) -> Iterator[tuple[Executor | None, int, str]]:
    """``(executor for the shares or None: in turn, jobs per share, where they run)``."""
    if shares < 2 or (executor is None and station.jobs <= 1):
        yield None, station.jobs, "in turn"
    elif executor is not None:
        yield executor, 1, "executor"
    else:
        workers = min(station.jobs, shares)
        with ProcessPoolExecutor(max_workers=workers) as pool:
            yield pool, max(1, station.jobs // workers), f"process pool of {workers}"


def plan_shares(
    station: Any,
    allocation: Any,
    *,
    seed: int | None,
    executor: Executor | None = None,
    progress: Progress | None = None,
) -> Shares:
    """Plan every robot's share of ``allocation`` (module docstring).

    Parameters
    ----------
    station
        The :class:`~weldplan.station.model.Station`, every robot at its base (searched ones
        placed).
    allocation
        The :class:`~weldplan.multi.result.Allocation` (``welds_of(k)``, ``robots`` names).
    seed
        The station's integer seed: every share's.
    executor
        The run's executor (module docstring), or None.
    progress
        ``progress(stage, done, total)`` (module docstring, *Progress*).

    Returns
    -------
    Shares
        Per robot in station order its plan, ``None`` for a robot with no weld.
    """
    say = progress or (lambda stage, done, total: None)
    tasks = share_tasks(station, allocation, seed, station.jobs)
    results: dict[int, ShareResult] = {}
    t, c = time.perf_counter(), cpu_seconds()
    say("plan", 0, len(tasks))
    with _share_executor(station, executor, len(tasks)) as (ex, jobs, ran):
        if ex is None:
            for n, task in enumerate(tasks):
                results[task.k] = run_share(task, executor=executor, progress=progress)
                say("plan", n + 1, len(tasks))
        else:
            futures = [ex.submit(_remote, dataclasses.replace(task, jobs=jobs)) for task in tasks]
            for n, (task, fut) in enumerate(zip(tasks, futures, strict=True)):
                try:
                    results[task.k] = pickle.loads(fut.result())
                except ShareFailed as exc:  # its events, as a share planned in turn gave them
                    for event in exc.events:
                        say(*event)
                    raise
                for event in results[task.k].events:
                    say(*event)
                say("plan", n + 1, len(tasks))
    seconds: dict[str, float] = {}
    cpu: dict[str, float] = {}
    for task in tasks:
        r = results[task.k]
        seconds[f"plan {task.name}"] = r.seconds
        cpu[f"plan {task.name}"] = round(r.cpu, 2)
        cpu.update(r.stage_cpu)
    seconds["shares"] = time.perf_counter() - t
    cpu["shares"] = round(cpu_seconds() - c, 2)
    plans = tuple(results[k].plan if k in results else None for k in range(len(station.robots)))
    return Shares(plans, seconds, cpu, ran)
