"""Robots' shares of a station planned in turn or on an executor (weldplan.multi.shares): a
share's result pickles with its live models (tool and robot caches, the reach test's checker)
and comes back working; progress names the robot; where the shares run follows the station's
jobs and the executor given; slow: a two-robot demo station planned in turn and on a process
pool of 2 writes the same files byte for byte."""

from __future__ import annotations

import filecmp
import json
import pickle
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pytest

from tests.conftest import require_shared
from weldplan.multi import shares as sh


def test_a_tool_with_its_collision_cache_travels_and_collides_the_same():
    import fcl

    from weldplan.tool import arc_torch

    tool = arc_torch(bend_angle=0.0)
    model, _ = tool.fcl_model(20.0)  # warms the cache with an FCL BVH: plain pickle refuses it
    with pytest.raises(TypeError):
        pickle.dumps(tool)
    back = pickle.loads(sh.dumps(tool))
    assert back._cache == {} and back is not tool
    np.testing.assert_array_equal(back.vertices, tool.vertices)
    np.testing.assert_array_equal(back.faces, tool.faces)

    # the rebuilt cache answers as the original: the same distance to a sphere 30 mm off the tip
    def distance(m):
        req, res = fcl.DistanceRequest(), fcl.DistanceResult()
        sphere = fcl.CollisionObject(fcl.Sphere(5.0), fcl.Transform(np.array([30.0, 0.0, 0.0])))
        return fcl.distance(fcl.CollisionObject(m, fcl.Transform()), sphere, req, res)

    assert distance(back.fcl_model(20.0)[0]) == pytest.approx(distance(model), abs=1e-9)


def test_a_robot_with_its_ik_solver_travels_and_solves_the_same():
    from weldplan.robot import load_robot

    urdf = require_shared("robots", "kuka_kr150r3100_2", "kr150r3100_2.urdf")
    robot = load_robot(urdf)
    q = np.radians([10.0, -80.0, 100.0, 5.0, 30.0, -20.0])
    T = robot.fk(q)
    before = robot.ik_all(T)  # the OPW solver lives in the cache: plain pickle refuses it
    with pytest.raises(TypeError):
        pickle.dumps(robot)
    back = pickle.loads(sh.dumps(robot))
    np.testing.assert_allclose(back.fk(q), T, atol=1e-9)
    after = back.ik_all(T)
    np.testing.assert_allclose(np.asarray(after.q), np.asarray(before.q), atol=1e-9)


def test_a_shares_events_name_its_robot_and_its_stages_get_cpu():
    seen = []
    rec = sh._Recorder("robot2", lambda *e: seen.append(e))
    for e in [("cell", 0, 1), ("local", 3, 10), ("cell", 1, 1), ("poses", 0, 1), ("poses", 1, 1)]:
        rec(*e)
    assert seen == rec.events
    assert [e[0] for e in seen] == ["robot2 cell", "robot2 local", "robot2 cell",
                                    "robot2 poses", "robot2 poses"]  # fmt: skip
    assert set(rec.cpu) == {"robot2 cell", "robot2 poses"}
    assert all(v >= 0.0 for v in rec.cpu.values())


class _St:
    def __init__(self, jobs):
        self.jobs = jobs


@pytest.mark.parametrize(
    ("jobs", "shares", "given", "ran", "inner"),
    [
        (1, 4, False, "in turn", 1),  # the default: in turn
        (4, 1, False, "in turn", 4),  # one share: in turn, its pairs on the station's jobs
        (2, 4, False, "process pool of 2", 1),
        (8, 2, False, "process pool of 2", 4),  # the jobs left over go to each share's pairs
        (1, 3, True, "executor", 1),  # an executor given (Dask): the shares on it
        (1, 1, True, "in turn", 1),
    ],
)
def test_where_the_shares_run(jobs, shares, given, ran, inner):
    with ThreadPoolExecutor(1) as given_ex:
        with sh._share_executor(_St(jobs), given_ex if given else None, shares) as (ex, j, r):
            assert (r, j) == (ran, inner)
            assert (ex is None) == (ran == "in turn")
            if ran == "executor":
                assert ex is given_ex


def _two_robot_station(tmp_path: Path) -> Path:
    """The demo part, welds 1, 5, 9, 13 and two KR 150 with the spot gun at the bench's bases."""
    from weldplan.bench.station import DEMO_BASES, DEMO_HOME
    from weldplan.io.joints import Joints, read_joints
    from weldplan.weld import demo_part

    data = require_shared()
    ids = ("1", "5", "9", "13")
    j = read_joints(demo_part.DEMO_JOINTS)
    k = [j.ids.index(i) for i in ids]
    Joints(ids=ids, xyz=np.asarray(j.xyz)[k], directions=np.asarray(j.directions)[k]).to_csv(
        tmp_path / "welds.csv"
    )
    robots = "".join(
        f'\n[[robot]]\nurdf = "{data}/robots/kuka_kr150r3100_2/kr150r3100_2.urdf"\n'
        f"base = {list(b)}\nhome = {list(DEMO_HOME)}\n[robot.tool]\n"
        f'file = "{data}/tools/spot_welding_gun/spot_welding_gun.urdf"\n'
        for b in DEMO_BASES
    )
    toml = tmp_path / "two.toml"
    toml.write_text(
        f'seed = 0\n[part]\nmesh = "{demo_part.DEMO_PART}"\nwelds = "welds.csv"\n'
        '[route]\nplanner = "exact"\n' + robots
    )
    return toml


class _Allocation:
    robots = ("robot1", "robot2")

    def welds_of(self, k):
        return (("1", "5"), ("9", "13"))[k]


def test_a_share_failing_in_a_worker_fails_the_station_with_its_own_one_line_error(tmp_path):
    import dataclasses

    import weldplan
    from weldplan.errors import InputError

    station = weldplan.load_station(_two_robot_station(tmp_path))
    part = dataclasses.replace(station.part, mesh=tmp_path / "gone.stl")
    station = dataclasses.replace(station, part=part, jobs=2)
    with pytest.raises(InputError) as got:  # raised in a pool worker, re-raised here
        sh.plan_shares(station, _Allocation(), seed=0)
    assert "gone.stl" in str(got.value) and "\n" not in str(got.value)


def test_a_share_that_fails_on_an_executor_reports_the_events_it_gave_in_turn(
    tmp_path, monkeypatch
):
    """A share the pipeline cannot plan raises ``ShareFailed`` carrying its progress events up
    to the failure: planned on an executor (a worker: its events come back with the error) the
    parent reports the same events as a share planned in turn gave live."""
    import weldplan
    from weldplan.errors import PlanningError
    from weldplan.station import pipeline

    station = weldplan.load_station(_two_robot_station(tmp_path))

    def fails(sub, rng=None, executor=None, progress=None):
        progress("reach", 0, 1)
        progress("reach", 1, 1)
        raise PlanningError("no home leg for weld 1")

    monkeypatch.setattr(pipeline, "plan", fails)
    got = {}
    for ran, ex in (("in turn", None), ("executor", ThreadPoolExecutor(2))):
        events = []
        with pytest.raises(sh.ShareFailed) as err:
            sh.plan_shares(station, _Allocation(), seed=0, executor=ex,
                           progress=lambda *e, ev=events: ev.append(e))  # fmt: skip
        got[ran] = events
        back = pickle.loads(pickle.dumps(err.value))
        assert (back.k, back.welds, back.events) == (0, ("1", "5"), err.value.events)
        assert "no home leg for weld 1" in str(back)
    want = [("plan", 0, 2), ("robot1 reach", 0, 1), ("robot1 reach", 1, 1)]
    assert got["in turn"] == got["executor"] == want


@pytest.mark.slow
def test_a_station_planned_in_turn_and_on_a_pool_writes_the_same_files(tmp_path):
    import dataclasses

    import weldplan
    from weldplan.io.joints import read_joints
    from weldplan.multi.saved import station_paths, write_station
    from weldplan.station.model import OutputSpec

    station = weldplan.load_station(_two_robot_station(tmp_path))
    out = {}
    for jobs in (1, 2):
        events = []
        p = weldplan.plan(dataclasses.replace(station, jobs=jobs), rng=0,
                          progress=lambda *e, ev=events: ev.append(e))  # fmt: skip
        folder = tmp_path / f"jobs{jobs}"
        folder.mkdir()
        spec = OutputSpec(csv=folder / "route.csv", json=folder / "route.json",
                          post="krl", trajectory=folder / "traj.csv")  # fmt: skip
        write_station(p, station_paths(spec, len(p.plans)))
        out[jobs] = (p, events, folder)
    (p1, ev1, f1), (p2, ev2, f2) = out[1], out[2]
    # a later pass with one new share plans it in turn (a pool of one is no pool)
    assert set(p1.stats["shares"].split(", ")) == {"in turn"}
    assert p2.stats["shares"].split(", ")[0] == "process pool of 2"
    assert all(p is not None for p in p2.plans)  # both robots had welds: both went to the pool
    names = sorted(x.name for x in f1.iterdir())
    assert names == sorted(x.name for x in f2.iterdir()) and len(names) >= 5
    same = [n for n in names if not n.endswith(".timings.json")]  # wall seconds: never the same
    _, mismatch, errors = filecmp.cmpfiles(f1, f2, same, shallow=False)
    assert mismatch == [] and errors == []
    # the route JSON names the file its share was read from: the share's welds exactly
    for k, sub in enumerate(p2.plans):
        src = json.loads((f2 / f"route_robot{k + 1}.json").read_text())["provenance"]["joints"]
        got = read_joints(src["source"])
        assert got.ids == sub.cell.joints.ids == p2.allocation.welds_of(k)
    # the same events, each naming its robot, in robot order; the shares counted by "plan"
    assert ev1 == ev2
    staged = [e for e in ev1 if e[0].startswith("robot")]
    assert {e[0].split()[0] for e in staged} == {"robot1", "robot2"}
    assert ("plan", 2, 2) in ev1 and ("robot1 poses", 1, 1) in ev1
    cpu = p2.stats["cpu"]
    assert {"plan robot1", "plan robot2", "robot1 poses", "robot2 program"} <= set(cpu)
