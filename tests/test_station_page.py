"""The station page (weldplan.viz.station_page): each robot's configuration at a station time
with waits against hand-computed values; the scene of two KUKA KR 150 with the spot gun on the
box route, one held by an interlock (the animation holds it still at its weld); drawn by a real
headless Chromium (slow)."""

from __future__ import annotations

import numpy as np
import pytest

from weldplan.multi.schedule import Interlock, station_schedule
from weldplan.robot.program import time_route

VEL = np.full(6, 2.0)
ACC = np.full(6, 8.0)
WT = 0.5


def _timed(offset: float, n: int = 4):
    """``n`` rows, each a weld, 0.3 rad apart on joint 1 from ``offset``."""
    q = np.zeros((n, 6))
    q[:, 0] = offset + 0.3 * np.arange(n)
    return time_route(q, VEL, ACC, weld_rows=np.arange(n), weld_time=WT)


def test_a_robot_held_by_an_interlock_stands_still_then_runs_its_own_timing_late():
    from weldplan.viz.station_page import own_times, station_q

    ta, tb = _timed(0.0), _timed(1.0)
    lock = Interlock("Z1", first=0, release_row=2, second=1, wait_row=0, signal=1)
    s = station_schedule(["a", "b"], [ta, tb], [lock])
    leave = tb.row_times[0] + WT  # b would leave its row 0 here, after its weld ...
    ready = ta.row_times[2] + WT  # ... but waits until a is done at its row 2
    wait = ready - leave
    assert wait > 0.5
    move = tb.row_times[1] - tb.row_times[0] - WT  # b's own move from row 0 to row 1
    t = np.array([0.2, leave + wait / 3, ready - 1e-9, ready + move / 2, ready + move + WT / 2,
                  s.cycle_time, s.cycle_time + 5.0])  # fmt: skip
    own_b = own_times(s, 1, t)
    np.testing.assert_allclose(
        own_b, [0.2, leave, leave, leave + move / 2, leave + move + WT / 2, tb.total, tb.total + 5],
        atol=1e-9,
    )  # fmt: skip
    np.testing.assert_allclose(own_times(s, 0, t), t)  # a never waits
    qa, qb = station_q(s, [ta, tb], t)
    # b welds at row 0 (joint 1 at 1.0 rad), holds there through the wait, welds row 1 at 1.3
    np.testing.assert_allclose(qb[:3, 0], 1.0, atol=1e-9)
    assert 1.0 < qb[3, 0] < 1.3  # on its way, mid-move
    np.testing.assert_allclose(qb[3, 0], 1.15, atol=0.01)  # rest to rest: halfway at half time
    np.testing.assert_allclose(qb[4, 0], 1.3, atol=1e-9)
    np.testing.assert_allclose(qb[5:, 0], 1.9, atol=1e-9)  # done: holds its last row
    np.testing.assert_allclose(qb[:, 1:], 0.0)
    # a at station time t is a at its own time t: at rest at row 2 when b is released
    np.testing.assert_allclose(qa[2, 0], 0.6, atol=1e-6)
    assert station_q(s, [ta, None], t)[1] is None


@pytest.fixture(scope="module")
def two_robots():
    """Two KR 150 on either side of the box part, each on the box route; robot 2 held at its
    first weld until robot 1 has welded its second."""
    from tests.conftest import require_shared
    from tests.robot_fixtures import BASE, box_joint_route, gun_tcp
    from tests.route_fixtures import box_part
    from weldplan.io.export import route_rows
    from weldplan.robot import load_robot
    from weldplan.tool.model import load_tool
    from weldplan.viz.station_page import StationRobot

    urdf = require_shared("robots", "kuka_kr150r3100_2", "kr150r3100_2.urdf")
    mirror = np.diag([-1.0, -1.0, 1.0, 1.0]) @ BASE  # across the part, facing it
    robots, timings = [], []
    for k, base in enumerate((BASE, mirror)):
        robot = load_robot(urdf, base=base)
        Tft, gun = gun_tcp(robot)
        route, Q = box_joint_route(robot, Tft)
        P = np.array([[r["x"], r["y"], r["z"]] for r in route_rows(route)])
        welds = [int(np.argmin(np.linalg.norm(P - j, axis=1))) for j in route.joint_xyz]
        timing = time_route(Q, robot.velocity, robot.acceleration, weld_rows=sorted(welds),
                            weld_time=WT)  # fmt: skip
        tool, _ = load_tool(gun)
        robots.append(StationRobot(f"robot{k + 1}", robot, Tft, timing, tool, P))
        timings.append(timing)
    w1 = int(timings[0].weld_rows[1])
    lock = Interlock("Z1", first=0, release_row=w1, second=1, wait_row=0, signal=1)
    s = station_schedule(["robot1", "robot2"], timings, [lock])
    assert s.waiting[1] > 0.5
    return robots, s, box_part()


def test_the_scene_holds_the_waiting_robot_still_at_its_weld(two_robots):
    import meshcat
    import umsgpack

    from weldplan.viz.robot_scene import FRAME_RATE
    from weldplan.viz.station_page import build_station_scene
    from weldplan.viz.viewer import RecordingWindow

    robots, s, part = two_robots
    window = RecordingWindow()
    n = build_station_scene(meshcat.Visualizer(window=window), robots, s, part=part)
    assert n == int(np.floor(s.cycle_time * FRAME_RATE + 1e-9)) + 1
    anim = umsgpack.unpackb(window.tree.animation)
    clips = {a["path"]: a["clip"] for a in anim["animations"]}
    assert len(clips) == 16  # seven links and a tool per robot, one clip
    keys = {}
    for k in (1, 2):
        tool = clips[f"/meshcat/weldplan_station/robot{k}/tool"]
        pos = next(t for t in tool["tracks"] if t["name"] == ".position")
        keys[k] = np.array([key["value"] for key in pos["keys"]])
        assert len(keys[k]) == n
    (wait,) = [a for a in s.of(1) if a.kind == "wait"]
    f = np.arange(n) / FRAME_RATE
    during = (f >= wait.start - 1e-9) & (f <= wait.end + 1e-9)
    held = keys[2][during]
    # robot 2's TCP stands on its first weld (the route's first joint) the whole wait
    first = robots[1].route_points[0]
    np.testing.assert_allclose(held, np.tile(first, (len(held), 1)), atol=0.05)
    # robot 1 moves meanwhile, and both end at their last weld
    assert np.ptp(keys[1][during], axis=0).max() > 10.0
    for k in (1, 2):
        np.testing.assert_allclose(keys[k][-1], robots[k - 1].route_points[-1], atol=0.05)


@pytest.mark.slow
def test_headless_chromium_draws_every_robot_and_the_chart(two_robots, tmp_path):
    pytest.importorskip("PIL")
    from PIL import Image

    from tests.test_viewer import _run_chromium
    from weldplan.viz.station_page import ROBOT_COLORS, station_html

    robots, s, part = two_robots
    page = tmp_path / "station.html"
    page.write_text(station_html(robots, s, part=part, bound=0.8 * s.cycle_time))
    url = page.resolve().as_uri() + "#t=1.0"
    dom = _run_chromium(tmp_path, "--dump-dom", url)
    assert dom.returncode == 0, dom.stderr[-2000:]
    assert "<canvas" in dom.stdout and "scene commands)" in dom.stdout
    assert "Z1_R1_R2" in dom.stdout and 'id="weldplan-cursor"' in dom.stdout
    assert '<b id="weldplan-t">1.00</b>' in dom.stdout  # opened at the address's time
    png = tmp_path / "shot.png"
    shot = _run_chromium(tmp_path, f"--screenshot={png}", url)
    assert shot.returncode == 0 and png.exists(), shot.stderr[-2000:]
    img = np.asarray(Image.open(png).convert("RGB"), dtype=float)
    assert img.std() > 10.0
    import colorsys

    hsv = np.array([colorsys.rgb_to_hsv(*(p / 255)) for p in img.reshape(-1, 3)[::3]])
    for k in range(2):
        c = ROBOT_COLORS[k]
        h0 = colorsys.rgb_to_hsv(((c >> 16) & 255) / 255, ((c >> 8) & 255) / 255, (c & 255) / 255)[
            0
        ]
        dh = np.abs((hsv[:, 0] - h0 + 0.5) % 1.0 - 0.5)
        hit = (dh < 0.03) & (hsv[:, 1] > 0.5) & (hsv[:, 2] > 0.25)
        assert hit.sum() > 300, f"robot {k + 1} not drawn ({int(hit.sum())} pixels)"


def test_the_camera_looks_across_the_line_of_the_robots():
    from weldplan.viz.camera import AZIMUTH_DEG
    from weldplan.viz.station_page import STATION_AZIMUTH_OFFSET_DEG as off
    from weldplan.viz.station_page import station_azimuth

    along_x = [[0.0, 0.0, 0.0], [2000.0, 0.0, 0.0]]
    assert station_azimuth(along_x) == pytest.approx(-90.0 + off)
    assert station_azimuth([[0.0, 0.0, 0.0], [0.0, -3000.0, 500.0]]) == pytest.approx(off)
    assert station_azimuth([[1.0, 2.0, 0.0]]) == AZIMUTH_DEG


def test_an_idle_robot_stands_at_its_base_with_its_tool_and_does_not_move(two_robots):
    import meshcat
    import umsgpack

    from tests.conftest import require_shared
    from weldplan.station.model import RobotSpec, ToolSpec
    from weldplan.viz.station_page import _idle_robot, build_station_scene
    from weldplan.viz.viewer import RecordingWindow

    robots, s, part = two_robots
    gun = require_shared("tools", "spot_welding_gun", "spot_welding_gun.urdf")
    urdf = require_shared("robots", "kuka_kr150r3100_2", "kr150r3100_2.urdf")
    spec = RobotSpec(tool=ToolSpec(file=gun), urdf=urdf, base=(0.0, 2500.0, -1000.0, -90.0))
    idle = _idle_robot("robot3", spec)
    np.testing.assert_allclose(idle.robot.base[:3, 3], [0.0, 2500.0, -1000.0])
    assert idle.timing is None and idle.tool is not None
    three = station_schedule(
        ["robot1", "robot2", "robot3"], [r.timing for r in robots] + [None], s.interlocks
    )
    window = RecordingWindow()
    build_station_scene(meshcat.Visualizer(window=window), [*robots, idle], three, part=part)
    anim = umsgpack.unpackb(window.tree.animation)
    clips = {a["path"]: a["clip"] for a in anim["animations"]}
    tool = clips["/meshcat/weldplan_station/robot3/tool"]
    pos = np.array(
        [k["value"] for k in next(t for t in tool["tracks"] if t["name"] == ".position")["keys"]]
    )
    T = idle.robot.fk(np.zeros(6))[0] @ idle.flange_tcp  # its zero pose, held
    np.testing.assert_allclose(pos, np.tile(T[:3, 3], (len(pos), 1)), atol=1e-3)
