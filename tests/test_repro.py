"""Reproducibility (issue 27): the same command, inputs and seed write the same files.

A station is planned twice, each in its own process (no shared cache, no shared random state,
another ``PYTHONHASHSEED``; the point-tip route also once starved of CPU, pinned to one core
beside a busy process), and every file the runs write is compared byte for byte, except the
timings file, which holds the run's measured seconds and nothing else
(:func:`weldplan.io.export.split_timings`).
"""

from __future__ import annotations

import json
import os
import re
import shutil
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


def _fin_station(folder: Path) -> tuple[Path, Path]:
    """A 300 x 240 mm plate with a 80 mm fin across it and 40 spots, 20 each side: above
    Held-Karp size, so the route runs the seeded nearest neighbour + polish, its warm and gap
    rounds, the 1-tree bounds and the local planner (A*, refinement) on the pairs across the
    fin."""
    import numpy as np
    import trimesh

    plate = trimesh.creation.box(extents=(300.0, 240.0, 10.0))
    plate.apply_translation((0.0, 0.0, -5.0))
    fin = trimesh.creation.box(extents=(10.0, 240.0, 80.0))
    fin.apply_translation((0.0, 0.0, 40.0))
    trimesh.util.concatenate([plate, fin]).export(folder / "part.stl")
    spots = [
        (s * x, y + 7 * s) for s in (-1, 1) for y in np.linspace(-100, 100, 10) for x in (40, 110)
    ]
    rows = ["id,x,y,z,nx,ny,nz"] + [
        f"{k},{x:.1f},{y:.1f},0.0,0,0,1" for k, (x, y) in enumerate(spots, 1)
    ]
    (folder / "joints.csv").write_text("\n".join(rows) + "\n")
    return folder / "part.stl", folder / "joints.csv"


def _busy_core(core: int) -> subprocess.Popen:
    """A process spinning on ``core`` (the CPU-starved run shares it)."""
    code = f"import os\nos.sched_setaffinity(0, {{{core}}})\nwhile True:\n    pass\n"
    return subprocess.Popen([sys.executable, "-c", code])


def _plan_route(folder: Path, part: Path, joints: Path, hashseed: int, core: int | None):
    folder.mkdir()
    argv = [sys.executable, "-m", "weldplan", "plan", str(part), str(joints), "-o", "route.csv",
            "--json", "route.json", "--seed", "5"]  # fmt: skip
    if core is not None:
        argv = ["taskset", "-c", str(core), *argv]
    env = {**os.environ, "PYTHONPATH": str(ROOT), "PYTHONHASHSEED": str(hashseed)}
    return subprocess.run(argv, cwd=folder, env=env, capture_output=True, text=True, timeout=600)


@pytest.mark.slow
def test_the_route_is_the_same_bytes_under_another_hash_seed_and_starved_of_cpu(tmp_path):
    if shutil.which("taskset") is None or not hasattr(os, "sched_setaffinity"):
        pytest.skip("needs taskset and sched_setaffinity (Linux)")
    part, joints = _fin_station(tmp_path)
    a = _plan_route(tmp_path / "a", part, joints, hashseed=1, core=None)
    core = min(os.sched_getaffinity(0))
    busy = _busy_core(core)
    try:
        b = _plan_route(tmp_path / "b", part, joints, hashseed=2, core=core)
    finally:
        busy.kill()
        busy.wait()
    for r in (a, b):
        assert r.returncode == 0, r.stderr
        assert re.search(r"^reproducible +yes", r.stdout, re.M), r.stdout
    stats = json.loads((tmp_path / "a" / "route.json").read_text())["stats"]
    assert stats["sequence_method"].endswith("+polish") and stats["pairs_planned"] > 0
    assert stats["bound_planned_method"] == "1-tree" and stats["gap_rounds"]["rounds"] >= 1
    assert stats["clock_stops"] == {"refine_pairs": [], "lower_bound": False,
                                    "bound_planned": False}  # fmt: skip
    for name in ("route.csv", "route.json"):
        assert (tmp_path / "a" / name).read_bytes() == (tmp_path / "b" / name).read_bytes(), name


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
    # the route stage's CPU safety nets, once spent (Route.stats["clock_stops"])
    stops = {"refine_pairs": [f"{k}-{k + 1}" for k in range(7)], "lower_bound": False,
             "bound_planned": True}  # fmt: skip
    stats = {"sequence_method": "nn+polish", "clock_stops": stops}
    assert clock_caps(_route(stats=stats)) == [
        "7 local path refinement(s) stopped by their CPU cap (0-1, 1-2, 2-3, 3-4, 4-5, ...)",
        "the planned-leg 1-tree bound stopped by its CPU cap",
    ]
    stops.update(refine_pairs=[], bound_planned=False)
    assert clock_caps(_route(stats=stats)) == []


def test_the_ompl_local_planner_is_named_a_clock_cap_when_it_planned_a_pair():
    ompl = {"planner": "ompl"}
    planned = {"sequence_method": "nn+polish", "pairs_planned": 3}
    assert clock_caps(_route(settings=ompl, stats=planned)) == [
        "the local paths of --planner ompl had a clock budget (1 s)"
    ]
    assert clock_caps(_route(settings=ompl, stats={**planned, "pairs_planned": 0})) == []
    assert clock_caps(_route(settings={"planner": "exact"}, stats=planned)) == []
