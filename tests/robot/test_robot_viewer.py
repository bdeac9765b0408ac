"""The robot cell in meshcat: links, tool and part animated along the timed trajectory, with the
viewer's time slider; drawn by a real headless Chromium."""

from __future__ import annotations

import numpy as np
import pytest

from tests.robot_fixtures import box_joint_route, gun_tcp, shared_robot
from tests.route_fixtures import box_part
from tests.test_viewer import _run_chromium


@pytest.fixture(scope="module")
def cell():
    from weldplan.robot.program import robot_program
    from weldplan.robot.settings import ProgramSettings, ToolOnRobot
    from weldplan.tool.model import load_tool

    robot = shared_robot()
    Tft, gun = gun_tcp(robot)
    route, Q = box_joint_route(robot, Tft)
    b = robot_program(
        route, Q, robot, ToolOnRobot(Tft, mass=2.0, cog=np.zeros(3)), part=box_part(),
        settings=ProgramSettings(weld_time=0.5),
    )  # fmt: skip
    tool, _ = load_tool(gun)
    return robot, Tft, route, b.timing, tool


def test_scene_animates_every_link_and_the_tool_at_the_cycles_speed(cell):
    import meshcat
    import umsgpack
    from meshcat.servers.tree import find_node

    from weldplan.viz.robot_scene import FRAME_RATE, build_robot_scene
    from weldplan.viz.viewer import RecordingWindow

    robot, Tft, route, timing, tool = cell
    window = RecordingWindow()
    n = build_robot_scene(
        meshcat.Visualizer(window=window), robot, timing, Tft, part=box_part(), tool=tool,
        route_points=route.waypoints(),
    )  # fmt: skip
    assert n == int(np.floor(timing.total * FRAME_RATE + 1e-9)) + 1
    root = ["meshcat", "weldplan_robot"]
    names = sorted(find_node(window.tree, [*root, "links"]))
    assert names == sorted(link.name for link in robot.links) and len(names) == 7
    assert find_node(window.tree, [*root, "tool"]).object is not None
    anim = umsgpack.unpackb(window.tree.animation)
    clips = {a["path"]: a["clip"] for a in anim["animations"]}
    assert len(clips) == 8  # seven links and the tool
    tool_clip = clips["/meshcat/weldplan_robot/tool"]
    pos = next(t for t in tool_clip["tracks"] if t["name"] == ".position")
    assert len(pos["keys"]) == n and tool_clip["fps"] == FRAME_RATE
    assert [k["time"] for k in pos["keys"]] == list(range(n))
    # the tool's last keyframe is the TCP at the last weld (FK of the last joint vector)
    T = robot.fk(timing.q[-1])[0] @ Tft
    np.testing.assert_allclose(pos["keys"][-1]["value"], T[:3, 3], atol=1e-3)
    np.testing.assert_allclose(T[:3, 3], route.waypoints()[-1], atol=1e-2)


def test_the_view_holds_the_robot_over_its_whole_cycle_and_marks_the_welds(cell):
    import meshcat
    import umsgpack
    from meshcat.servers.tree import find_node

    from weldplan.viz.robot_scene import build_robot_scene, frame_times, robot_slider, sample_q
    from weldplan.viz.viewer import RecordingWindow

    robot, Tft, route, timing, tool = cell
    window = RecordingWindow()
    build_robot_scene(
        meshcat.Visualizer(window=window), robot, timing, Tft, part=box_part(), tool=tool,
        route_points=route.waypoints(), weld_ids=list(route.order),
    )  # fmt: skip
    root = ["meshcat", "weldplan_robot"]
    S = np.array(umsgpack.unpackb(find_node(window.tree, root).transform)["matrix"])
    S = S.reshape(4, 4).T  # mm -> viewer units
    # every link's every vertex at every frame lies in the framed box (+-1 unit about the origin)
    F = robot.link_frames(sample_q(timing, frame_times(float(timing.t[-1]))[0]))
    for link in robot.links:
        V = np.einsum("fij,nj->fni", F[:, link.index, :3, :3], link.vertices)
        V = V + F[:, None, link.index, :3, 3]
        W = V.reshape(-1, 3) @ S[:3, :3].T + S[:3, 3]
        assert np.abs(W).max() <= 1.0 + 1e-6, link.name
    # the weld markers stand on the route's joints, labelled with their ids
    for k, jid in enumerate(route.order):
        node = find_node(window.tree, [*root, "welds", str(k)])
        p = np.array(umsgpack.unpackb(node.transform)["matrix"]).reshape(4, 4).T[:3, 3]
        np.testing.assert_allclose(p, route.joint_xyz[route.index_of(jid)], atol=0.05)
        label = find_node(window.tree, [*root, "labels", str(k)]).object
        assert jid.encode() in label
    slider = robot_slider(timing, list(route.order))
    dwell = timing.row_times[timing.weld_rows] + timing.weld_time / 2
    np.testing.assert_allclose(slider.times, dwell)
    assert slider.ids == tuple(route.order)


@pytest.mark.slow
def test_headless_chromium_draws_the_robot_and_the_time_slider(cell, tmp_path):
    pytest.importorskip("PIL")
    from PIL import Image

    from weldplan.viz.robot_scene import write_robot_html

    robot, Tft, route, timing, tool = cell
    page = write_robot_html(
        tmp_path / "cell.html", robot, timing, Tft, part=box_part(), tool=tool,
        route_points=route.waypoints(),
    )  # fmt: skip
    url = page.resolve().as_uri()
    dom = _run_chromium(tmp_path, "--dump-dom", url)
    assert dom.returncode == 0, dom.stderr[-2000:]
    assert "<canvas" in dom.stdout and "scene commands)" in dom.stdout
    assert "Animations" in dom.stdout and ">time<" in dom.stdout  # the slider's controls
    png = tmp_path / "shot.png"
    shot = _run_chromium(tmp_path, f"--screenshot={png}", url)
    assert shot.returncode == 0 and png.exists(), shot.stderr[-2000:]
    img = np.asarray(Image.open(png).convert("RGB"), dtype=float)
    r, g, b = img[..., 0], img[..., 1], img[..., 2]
    orange = (r > 180) & (g > 90) & (g < 170) & (b < 80)  # the robot's links
    assert orange.mean() > 0.03, "robot not drawn"
    blue = (b > r + 40) & (g > 80) & (g < 140) & (r < 110) & (b < 200)  # the gun (0x4A6FA5)
    assert blue.sum() > 200, "tool not drawn"
    from tests.test_viewer_png import check_picture

    check_picture(img, orange, blue)  # the robot and its tool framed about the centre
