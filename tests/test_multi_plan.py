"""``weldplan.plan`` on a station of two robots (weldplan.multi.station): the demo part, the
shared spot gun on two KUKA KR 150 at given bases on either side of the part, six of the demo's
welds (15 among them: no robot reaches it). Slow: it runs the whole single-robot pipeline once
per robot (about 3 min wall, 70 s CPU on a loaded machine)."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from tests.conftest import require_shared

ROOT = Path(__file__).resolve().parents[1]
#: (x, y, z mm, yaw deg), part frame: behind the demo part facing it, and in front facing back
BASES = ((448.1, 95.3, 652.7, -7.5), (2450.0, -150.0, 652.7, 180.0))
#: the demo welds of the station
IDS = ("1", "5", "7", "9", "13", "15")


def _station(folder: Path | None = None):
    """The demo station with two robots at BASES; with ``folder``, only the welds IDS (a
    welds file written there)."""
    import weldplan
    from weldplan.io.joints import Joints, read_joints
    from weldplan.weld import demo_part

    require_shared("robots", "kuka_kr150r3100_2", "kr150r3100_2.urdf")
    st = weldplan.load_station(ROOT / "examples" / "demo_station.toml")
    specs = tuple(dataclasses.replace(st.robots[0], base=b) for b in BASES)
    st = dataclasses.replace(st, robots=specs)
    if folder is None:
        return st
    j = read_joints(demo_part.DEMO_JOINTS)
    k = [j.ids.index(i) for i in IDS]
    sub = Joints(ids=IDS, xyz=np.asarray(j.xyz)[k], directions=np.asarray(j.directions)[k])
    sub.to_csv(folder / "welds.csv")
    part = dataclasses.replace(st.part, mesh=demo_part.DEMO_PART, welds=folder / "welds.csv")
    return dataclasses.replace(st, part=part)


@pytest.mark.slow
def test_two_robots_share_the_demo_welds_and_each_plans_its_share(tmp_path):
    import weldplan
    from weldplan.multi.station import NO_INTERFERENCE, StationPlan

    p = weldplan.plan(_station(tmp_path), rng=0)
    assert isinstance(p, StationPlan)
    a = p.allocation
    every = set(p.plans[0].cell.joints.ids) | set(p.plans[1].cell.joints.ids)
    assert [u.weld for u in a.unreached] == ["15"]  # A2 past its limit from both bases
    assert every | {"15"} == set(IDS)
    for r, sub in enumerate(p.plans):
        # each robot's plan is over its share exactly, and its program welds every weld or
        # says which it left out
        assert set(sub.cell.joints.ids) == set(a.welds_of(r))
        assert len(sub.station.robots) == 1 and sub.station.robots[0].base == BASES[r]
        timing = sub.program.timing
        assert timing.total >= timing.weld_time * len(sub.robot.robot_route.weld_ids) - 1e-9
    assert p.cycle_time == max(p.timed_cycles)
    assert p.report.bound.value <= a.cycle_time + 1e-9
    rows = dict(p.summary_rows())
    assert rows["interference"] == NO_INTERFERENCE
    assert {f"robot robot{k}" for k in (1, 2)} <= set(rows)
    assert np.isfinite(p.cycle_time) and p.cycle_time > 0
    # the schedule runs each robot's own timing (no interlocks yet): the same cycles, no waits,
    # and every weld of every program on the clock under its id
    s = p.schedule
    assert s is not None and s.interlocks == () and s.waiting == (0.0, 0.0)
    assert s.cycle_times == pytest.approx(p.timed_cycles, abs=1e-9)
    for r, sub in enumerate(p.plans):
        welded = {t.joint_id for t in sub.program.program.targets if t.kind == "weld"}
        assert {a.label for a in s.of(r) if a.kind == "weld"} == welded
