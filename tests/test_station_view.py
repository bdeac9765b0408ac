"""``weldplan view route_station.json``: the station page rebuilt from the saved files alone
(weldplan.viz.station_page.saved_station_page_text): the station file's robots, bases and
tools, each robot's trajectory CSV timed by the schedule. Two KR 150 with the spot gun crossing
in the middle (tests/multi_fixtures.py), interlocked by the live interference stage, saved as a
station plan writes them (tests/test_multi_verify_station.py). The rebuilt scene is checked
against the one drawn from the live timings; the page written by the command line is opened by
a real headless Chromium (slow)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from tests.cli_helpers import one_line_error, run_cli


def _station_json(tmp_path):
    """``(path of the station JSON, SavedStationPlan)``: the crossing pair saved with its
    programs (KRL), the JSON written as :func:`weldplan.multi.saved.station_dict` lays it out,
    its allocation report a stand-in (no allocation ran: every weld of the file unreached)."""
    from tests.test_multi_verify_station import _saved
    from weldplan.multi.result import Allocation, AllocationReport, LowerBound, RobotShare
    from weldplan.multi.saved import FORMAT_VERSION, STATION_FORMAT

    saved = _saved(tmp_path, "krl")
    names = tuple(r.name for r in saved.robots)
    shares = tuple(RobotShare(n, (), 0.0, 0.0) for n in names)
    report = AllocationReport(
        Allocation("ours", names, (), (), shares), LowerBound(1.5, "stand-in", 1.5, 0.0)
    )
    robots = [
        {
            "name": r.name, "urdf": None, "base": list(r.base), "welds": [], "route": None,
            "trajectory": r.trajectory.name, "program": [p.name for p in r.program],
            "timed_cycle": r.timed_cycle, "rows": list(r.rows),
        }
        for r in saved.robots
    ]  # fmt: skip
    d = {
        "format": STATION_FORMAT, "version": FORMAT_VERSION, "producer": {},
        "station_file": "station.toml", "seed": 0, "robots": robots,
        "allocation": report.to_dict(), "schedule": saved.schedule.to_dict(),
        "cycle_time": saved.schedule.cycle_time, "interference": "test",
        "replay": saved.replay.to_dict(),
    }  # fmt: skip
    path = tmp_path / "route_station.json"
    path.write_text(json.dumps(d, indent=1))
    return path, saved


def _tool_keys(robots, schedule, part=None):
    """Per robot the ``(f, 3)`` keyframes of its tool's position in the station's animation."""
    import meshcat
    import umsgpack

    from weldplan.viz.station_page import build_station_scene
    from weldplan.viz.viewer import RecordingWindow

    window = RecordingWindow()
    build_station_scene(meshcat.Visualizer(window=window), robots, schedule, part=part)
    clips = {a["path"]: a["clip"] for a in umsgpack.unpackb(window.tree.animation)["animations"]}
    out = []
    for k in range(len(robots)):
        tracks = clips[f"/meshcat/weldplan_station/robot{k + 1}/tool"]["tracks"]
        pos = next(t for t in tracks if t["name"] == ".position")
        out.append(np.array([key["value"] for key in pos["keys"]]))
    return out


def test_the_scene_rebuilt_from_the_files_is_the_live_one(tmp_path):
    from tests import multi_fixtures as mf
    from weldplan.multi.saved import load_station_plan
    from weldplan.station.mount import mount_tool
    from weldplan.viz.station_page import StationRobot, saved_station_robots

    path, _ = _station_json(tmp_path)
    saved = load_station_plan(path)
    station = saved.load_station()
    rebuilt = saved_station_robots(saved, station)
    arms, timings = mf.pair(distance=4000.0)
    live = []
    for k, (arm, t, spec) in enumerate(zip(arms, timings, station.robots, strict=True)):
        mounted = mount_tool(spec.tool, arm)
        live.append(StationRobot(f"robot{k + 1}", arm, mounted.flange_tcp, t, mounted.tool))
    for a, b, t in zip(rebuilt, live, timings, strict=True):
        np.testing.assert_allclose(a.robot.base, b.robot.base, atol=1e-9)
        np.testing.assert_allclose(a.flange_tcp, b.flange_tcp, atol=1e-12)
        np.testing.assert_array_equal(a.timing.weld_rows, t.weld_rows)
        assert a.timing.weld_time == pytest.approx(t.weld_time, abs=1e-6)
        assert a.weld_ids == ("w1",)  # labelled as the schedule labels them
        # the TCP path: forward kinematics of every CSV sample, ending where the live one ends
        end = (b.robot.fk(t.q[-1:]) @ b.flange_tcp)[0, :3, 3]
        np.testing.assert_allclose(a.route_points[-1], end, atol=1e-3)
    # every frame of the animation, the waits in: each tool where the live timing has it
    for a, b in zip(_tool_keys(rebuilt, saved.schedule), _tool_keys(live, saved.schedule),
                    strict=True):  # fmt: skip
        assert len(a) == len(b) > 10
        # mm: the CSV's times are to 0.1 ms, and the gun swings at up to ~2.5 m/s
        np.testing.assert_allclose(a, b, atol=0.25)
        assert np.ptp(a, axis=0).max() > 500.0  # and it does swing
    assert saved.schedule.waiting[1] > 0 or saved.schedule.waiting[0] > 0  # someone waits


def test_view_writes_the_station_page_from_the_station_json(tmp_path, capsys):
    path, saved = _station_json(tmp_path)
    out = tmp_path / "page.html"
    assert run_cli(["view", str(path), "--html", str(out)]) == 0
    page = out.read_text()
    lock = saved.schedule.interlocks[0]
    assert "weldplan-gantt" in page and "robot2" in page and lock.name in page
    assert "<title>weldplan station: 2 robots</title>" in page
    # a mesh beside a station JSON is refused in one line, nothing written
    capsys.readouterr()
    other = tmp_path / "other.html"
    assert run_cli(["view", str(path), "part.stl", "--html", str(other)]) == 2
    assert "is a station JSON: give no mesh" in one_line_error(capsys)
    assert not other.exists()


@pytest.mark.slow
def test_headless_chromium_opens_the_rebuilt_page(tmp_path):
    pytest.importorskip("PIL")
    from PIL import Image

    from tests.test_viewer import _run_chromium

    path, saved = _station_json(tmp_path)
    out = tmp_path / "page.html"
    assert run_cli(["view", str(path), "--html", str(out)]) == 0
    url = out.resolve().as_uri() + "#t=1.0"
    dom = _run_chromium(tmp_path, "--dump-dom", url)
    assert dom.returncode == 0, dom.stderr[-2000:]
    assert "<canvas" in dom.stdout and "scene commands)" in dom.stdout
    assert saved.schedule.interlocks[0].name in dom.stdout
    assert '<b id="weldplan-t">1.00</b>' in dom.stdout  # opened at the address's time
    png = tmp_path / "shot.png"
    shot = _run_chromium(tmp_path, f"--screenshot={png}", url)
    assert shot.returncode == 0 and png.exists(), shot.stderr[-2000:]
    img = np.asarray(Image.open(png).convert("RGB"), dtype=float)
    assert img.std() > 10.0
