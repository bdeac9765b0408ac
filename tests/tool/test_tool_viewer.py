"""The viewer animates the tool along its transitions (issue 16, item 5): keyframes at the
waypoints with their orientations, blocked transitions in magenta; checked in headless Chromium."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import trimesh
import umsgpack

from tests.route_fixtures import box_part, box_route
from weldplan.tool import Tool, TransitionSettings, plan_weld_poses
from weldplan.tool.transitions import plan_transitions
from weldplan.viz.tool_scene import TOOL_COLOR, keyframe_times

meshcat = pytest.importorskip("meshcat")


@pytest.fixture(scope="module")
def tool_route():
    """The box route (A, C, B on a floor with a wall) with the poses and transitions of a small
    stick tool (8 x 8 x 50 mm behind the TCP: small enough to be seen in the route's frame)."""
    route = box_route(directions=True)
    stick = trimesh.creation.box((8.0, 8.0, 50.0)).apply_translation((0.0, 0.0, -25.0))
    torch = Tool("stick", np.asarray(stick.vertices), np.asarray(stick.faces))
    poses = plan_weld_poses(box_part(), route, torch)
    assert poses.n_ok == 3
    # retracted 80 mm the tip passes 20 mm over the 60 mm wall between C and B
    path = plan_transitions(box_part(), torch, poses, TransitionSettings(retract=80.0, se3=False))
    assert [t.status for t in path.transitions] == ["direct", "direct"], path.summary()
    data = {"provenance": {}, "poses": poses.to_dict(), "transitions": path.to_dict()}
    return dataclasses.replace(route, tool=data), torch, path


def _animations(window) -> dict[str, dict]:
    blob = umsgpack.unpackb(window.tree.animation)
    return {a["path"]: a["clip"] for a in blob["animations"]}


def test_the_tool_is_animated_through_every_waypoint_with_its_orientation(tool_route):
    from meshcat.servers.tree import find_node

    from weldplan.viz.viewer import ANIMATION_SECONDS, RecordingWindow, build_scene

    route, torch, path = tool_route
    window = RecordingWindow()
    build_scene(meshcat.Visualizer(window=window), route, box_part(), tool=torch)
    clips = _animations(window)
    (gun_path,) = [p for p in clips if p.endswith("/tool/gun")]
    tracks = {t["name"]: t["keys"] for t in clips[gun_path]["tracks"]}
    P, Q = path.waypoints()
    pos = np.array([k["value"] for k in tracks[".position"]])
    quat = np.array([k["value"] for k in tracks[".quaternion"]])  # three.js order x, y, z, w
    times = np.array([k["time"] for k in tracks[".position"]])
    assert len(pos) == len(P) and np.all(np.diff(times) >= 0)
    np.testing.assert_allclose(pos, P, atol=1e-3)
    # the same rotation (either sign of the quaternion)
    dots = np.abs(np.einsum("ij,ij->i", quat, np.roll(Q, -1, axis=1)))
    np.testing.assert_allclose(dots, 1.0, atol=1e-5)
    fps = clips[gun_path]["fps"]
    assert times[-1] == pytest.approx(ANIMATION_SECONDS * fps, abs=1)
    # one line per transition, in the tool's colour (all free here)
    for k in range(len(path.transitions)):
        line = umsgpack.unpackb(
            find_node(window.tree, [*gun_path.strip("/").split("/")[:-1], "path", str(k)]).object
        )
        assert line["object"]["materials"][0]["color"] == TOOL_COLOR


def test_keyframe_times_give_a_turn_on_the_spot_its_share():
    P = np.array([[0.0, 0, 0], [100, 0, 0], [100, 0, 0]])
    q0 = [1.0, 0, 0, 0]
    q90 = [np.cos(np.pi / 4), 0, 0, np.sin(np.pi / 4)]
    t = keyframe_times(P, np.array([q0, q0, q90]), reach=200.0)
    # 100 mm of travel, then 90 deg x 200 mm = 314 mm of bound on the spot
    np.testing.assert_allclose(t, [0.0, 100 / (100 + 100 * np.pi), 1.0])


def test_a_blocked_transition_is_drawn_magenta(tool_route):
    from meshcat.servers.tree import find_node

    from weldplan.viz.tool_scene import BLOCKED_COLOR
    from weldplan.viz.viewer import RecordingWindow, build_scene

    route, torch, path = tool_route
    d = dict(route.tool)
    tr = dict(d["transitions"])
    tr["transitions"] = [dict(t) for t in tr["transitions"]]
    tr["transitions"][1]["status"] = "blocked"
    d["transitions"] = tr
    window = RecordingWindow()
    build_scene(meshcat.Visualizer(window=window), dataclasses.replace(route, tool=d), box_part(),
                tool=torch)  # fmt: skip
    colors = [
        umsgpack.unpackb(
            find_node(window.tree, ["meshcat", "weldplan", "tool", "path", str(k)]).object
        )["object"]["materials"][0]["color"]
        for k in range(2)
    ]
    assert colors == [TOOL_COLOR, BLOCKED_COLOR]


def test_the_page_opens_with_the_tool_at_one_weld_and_its_animation_paused(tool_route):
    from meshcat.servers.tree import find_node

    from weldplan.viz.viewer import RecordingWindow, build_scene

    route, torch, _ = tool_route
    window = RecordingWindow()
    slider = build_scene(meshcat.Visualizer(window=window), route, box_part(), tool=torch)
    tool = find_node(window.tree, ["meshcat", "weldplan", "tool"])
    assert "gun" in tool and "tool" not in tool  # one tool, no copy per weld
    assert slider.ids == ("A", "C", "B") and slider.path == "/meshcat/weldplan/tool/gun"
    options = umsgpack.unpackb(window.tree.animation)["options"]
    assert options["play"] is False  # the slider's pose holds until the panel plays


@pytest.mark.slow
def test_headless_chromium_moves_the_tool_with_the_weld_slider(tool_route, tmp_path):
    pytest.importorskip("PIL")
    from tests.test_viewer import _chromium
    from tests.test_viewer_png import check_picture, greyish, load_rgb
    from weldplan.viz.png import PngSettings, png_bytes
    from weldplan.viz.viewer import static_html

    assert _chromium()
    route, torch, _ = tool_route
    page = static_html(route, box_part(), tool=torch)
    seen = {}
    for weld in ("A", "C", "B"):
        img = load_rgb(png_bytes(page, PngSettings(width=900, height=600, weld=weld)))
        r, g, b = img[..., 0], img[..., 1], img[..., 2]
        purple = (b > g + 40) & (r > g + 20)  # only the tool is purple (0x8E44AD)
        check_picture(img, greyish(img), purple)
        ys, xs = np.nonzero(purple)
        seen[weld] = np.array([xs.mean(), ys.mean()])
    # the tool stands at each weld in turn (A-C 60 mm, C-B 100 mm, A-B 80 mm apart)
    for a, b in (("A", "C"), ("C", "B"), ("A", "B")):
        assert np.linalg.norm(seen[a] - seen[b]) > 20.0, seen
