"""Reproducibility (issue 27): the same command, inputs and seed write the same files.

A station with the robot is planned twice, each in its own process (no shared cache, no shared
random state), and every file the runs write is compared byte for byte, except the timings
file, which holds the run's measured seconds and nothing else (:func:`weldplan.io.export.
split_timings`).
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace

import pytest

from tests.conftest import ROOT, require_shared
from tests.robot.test_robot_cli import _torch_urdf
from weldplan.station.summary import clock_caps


def _plan(folder: Path, torch: Path, seed: int) -> subprocess.CompletedProcess:
    """``weldplan plan`` of the demo cell with the arc torch on the KR 150 (base searched), in
    a fresh process, writing every output into ``folder``."""
    folder.mkdir()
    demo = ROOT / "assets" / "demo"
    robot = require_shared("robots", "kuka_kr150r3100_2", "kr150r3100_2.urdf")
    argv = [
        sys.executable, "-m", "weldplan", "plan", str(demo / "part.stl"),
        str(demo / "joints.csv"), "-o", "route.csv", "--json", "route.json",
        "--tool", str(torch), "--tool-csv", "tool.csv", "--robot", str(robot),
        "--post", "krl", "--trajectory", "traj.csv", "--seed", str(seed),
    ]  # fmt: skip
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.run(argv, cwd=folder, env=env, capture_output=True, text=True, timeout=1200)


@pytest.mark.slow
def test_two_runs_in_separate_processes_write_the_same_bytes(tmp_path):
    pytest.importorskip("ompl")
    torch = _torch_urdf(tmp_path)
    runs = [_plan(tmp_path / name, torch, seed=3) for name in ("a", "b")]
    for r in runs:
        assert r.returncode in (0, 3), r.stderr
        assert re.search(r"^reproducible +yes", r.stdout, re.M), r.stdout
    names = sorted(p.name for p in (tmp_path / "a").iterdir())
    assert names == sorted(p.name for p in (tmp_path / "b").iterdir())
    assert {"route.csv", "route.json", "route.src", "route.dat", "tool.csv", "traj.csv"} <= set(
        names
    )
    for name in names:
        if name.endswith(".timings.json"):
            continue
        a, b = ((tmp_path / d / name).read_bytes() for d in ("a", "b"))
        assert a == b, f"{name} differs between two runs of the same command"
    # the timings went to their own file, and the route JSON has none left
    timings = json.loads((tmp_path / "a" / "route.timings.json").read_text())
    assert timings["stats"]["seconds"]["total"] > 0
    assert "seconds" not in json.loads((tmp_path / "a" / "route.json").read_text())["stats"]


def _route(**kw):
    base = {"stats": {"sequence_method": "nn+polish"}, "settings": {}, "tool": {}}
    base.update(kw)
    return SimpleNamespace(**base)


def test_the_summary_names_every_clock_cap_and_nothing_else():
    assert clock_caps(_route()) == []
    assert clock_caps(_route(stats={"sequence_method": "fast-tsp"})) == [
        "the weld order came from fast-tsp (no seed)"
    ]
    # a real route's tool section (the box with the KR 150, tests/data), its clock marks set
    saved = json.loads((ROOT / "tests" / "data" / "route_box_kr150_v1.json").read_text())
    tool = saved["tool"]
    tool["transitions"]["stats"]["se3_runs"] = [{"clock": False}, {"clock": True}]
    tool["robot"]["stats"]["ompl"] = {"runs": 3.0, "clock": 2.0}
    caps = clock_caps(_route(tool=tool, settings={"local_time_budget": 1.5}))
    assert caps == [
        "the local paths had a clock budget (1.5 s)",
        "1 SE(3) re-plan(s) of the gun stopped by the clock",
        "2 joint-space transfer(s) stopped by the clock",
    ]
    tool["robot"]["stats"]["ompl"]["clock"] = 0.0
    tool["transitions"]["stats"]["se3_runs"][1]["clock"] = False
    assert clock_caps(_route(tool=tool)) == []


def test_the_ompl_local_planner_is_named_a_clock_cap_when_it_planned_a_pair():
    ompl = {"planner": "ompl"}
    planned = {"sequence_method": "nn+polish", "pairs_planned": 3}
    assert clock_caps(_route(settings=ompl, stats=planned)) == [
        "the local paths of --planner ompl had a clock budget (1 s)"
    ]
    assert clock_caps(_route(settings=ompl, stats={**planned, "pairs_planned": 0})) == []
    assert clock_caps(_route(settings={"planner": "exact"}, stats=planned)) == []
