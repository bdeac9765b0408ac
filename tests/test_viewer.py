"""The meshcat viewer: scene contents, the static page, and a real headless Chromium render."""

from __future__ import annotations

import os
import shutil
import subprocess

import numpy as np
import pytest

from tests.route_fixtures import box_part, box_route
from weldplan.viz.viewer import RecordingWindow, build_scene, leg_colors, static_html, write_html


def _scene():
    import meshcat
    from meshcat.servers.tree import find_node

    window = RecordingWindow()
    build_scene(meshcat.Visualizer(window=window), box_route(), box_part())
    return window, lambda path: find_node(window.tree, [p for p in path.split("/") if p])


def test_scene_holds_part_joints_labels_legs_vias_and_torch():
    window, node = _scene()
    root = "meshcat/weldplan"
    assert node(root).transform is not None
    assert node(f"{root}/part").object is not None
    for jid in ("A", "B", "C"):
        assert node(f"{root}/joints/{jid}").object is not None
        assert node(f"{root}/labels/{jid}").object is not None
        assert jid.encode() in node(f"{root}/labels/{jid}").object  # the label's text
    assert sorted(node(f"{root}/route")) == ["leg_0", "leg_0_tube", "leg_1", "leg_1_tube"]
    assert len(node(f"{root}/route/leg_1_tube")) == 4  # one tube per segment
    assert len(node(f"{root}/vias/leg_0")) == 2 and len(node(f"{root}/vias/leg_1")) == 3
    assert node(f"{root}/torch").object is not None
    assert window.tree.animation is not None  # the torch's animation along the route
    assert b"data:image/png;base64," in node(f"{root}/labels/A").object  # the label's box


def test_leg_colours_are_distinct():
    c = leg_colors(20)
    assert len(set(c)) == 20 and all(0 <= v <= 0xFFFFFF for v in c)


def test_static_page_is_self_contained(tmp_path):
    page = static_html(box_route(), box_part())
    assert page.startswith("<!DOCTYPE html>")
    assert "MeshCat.Viewer" in page and "handle_command_bytearray" in page
    assert "http://" not in page.split("<script>")[0]  # no remote assets in the head
    assert "<script src" not in page
    p = write_html(box_route(), box_part(), tmp_path / "route.html")
    assert p.read_text() == page or p.stat().st_size > 100_000


def test_notebook_view_is_the_static_page_in_an_iframe():
    pytest.importorskip("IPython")
    from html import unescape

    import weldplan.viz

    view = weldplan.viz.show(box_route(), box_part(), height=300)
    assert "height: 300px" in view.data and "<iframe srcdoc=" in view.data
    srcdoc = view.data.split('srcdoc="', 1)[1].split('" style=', 1)[0]
    page = unescape(srcdoc)
    assert page.startswith("<!DOCTYPE html>") and "MeshCat.Viewer" in page
    assert "<script src" not in page  # the same self-contained page as static_html


def test_view_without_part_draws_the_route_only():
    window = RecordingWindow()
    import meshcat

    build_scene(meshcat.Visualizer(window=window), box_route(), None)
    assert "part" not in window.tree["meshcat"]["weldplan"]


def _chromium() -> str:
    for name in ("chromium", "chromium-browser", "google-chrome"):
        path = shutil.which(name)
        if path:
            return path
    if os.environ.get("WELDPLAN_REQUIRE_BROWSER") == "1":
        pytest.fail("chromium not found (WELDPLAN_REQUIRE_BROWSER=1)")
    pytest.skip("chromium not installed (Debian: apt-get install chromium)")


def _run_chromium(tmp_path, *args: str) -> subprocess.CompletedProcess:
    flags = [
        "--headless",
        "--no-sandbox",
        "--disable-gpu",
        "--disable-quic",
        "--no-first-run",
        "--disable-background-networking",
        "--disable-component-update",
        "--disable-sync",
        "--use-angle=swiftshader",
        "--enable-unsafe-swiftshader",
        f"--user-data-dir={tmp_path / 'profile'}",
        "--window-size=900,700",
        "--virtual-time-budget=4000",
    ]
    return subprocess.run(
        [_chromium(), *flags, *args], capture_output=True, text=True, timeout=120, check=False
    )


@pytest.mark.slow
def test_headless_chromium_draws_the_scene(tmp_path):
    pytest.importorskip("PIL")
    from PIL import Image

    chromium = _chromium()
    assert chromium
    page = write_html(box_route(), box_part(), tmp_path / "route.html")
    url = page.resolve().as_uri()

    dom = _run_chromium(tmp_path, "--dump-dom", url)
    assert dom.returncode == 0, dom.stderr[-2000:]
    assert "<canvas" in dom.stdout, "the viewer made no WebGL canvas"
    assert "scene commands)" in dom.stdout  # our script ran to its end
    assert "ERR_" not in dom.stdout and "neterror" not in dom.stdout

    png = tmp_path / "shot.png"
    shot = _run_chromium(tmp_path, f"--screenshot={png}", url)
    assert shot.returncode == 0 and png.exists(), shot.stderr[-2000:]
    img = np.asarray(Image.open(png).convert("RGB"), dtype=float)
    assert img.shape[:2] == (700, 900)
    assert img.std() > 10.0, "blank screenshot"
    # the joints are drawn red (0xD62728): meshcat's background is a blue gradient and the
    # part grey, so clearly red pixels only come from the scene
    r, g, b = img[..., 0], img[..., 1], img[..., 2]
    red = (r > 150) & (g < 90) & (b < 90)
    assert red.sum() >= 10, "no joint drawn"
    # the part (grey, partly transparent) covers a good share of the middle of the view
    mid = img[200:500, 250:650]
    greyish = (np.abs(mid[..., 0] - mid[..., 2]) < 40) & (mid[..., 1] > 90)
    assert greyish.mean() > 0.2, "part not drawn"


def test_convergence_plots_draw(tmp_path):
    import matplotlib

    matplotlib.use("Agg")
    from weldplan.viz.plots import plot_convergence, plot_leg_lengths, plot_route_convergence

    r = box_route()
    stats = dict(r.stats)
    stats["local_paths"] = {"C-B": {"length": 150.0, "history": [200.0, 170.0, 150.0]}}
    stats["sequence_history"] = [300.0, 260.0, 250.0]
    from weldplan.weld.route import Route

    r = Route(r.order, r.legs, r.joint_ids, r.joint_xyz, lower_bound=160.0, stats=stats)
    fig = plot_route_convergence(r)
    fig.savefig(tmp_path / "c.png")
    a1, a2 = fig.axes
    np.testing.assert_allclose(a1.lines[0].get_ydata(), [200 / 150, 170 / 150, 1.0])
    np.testing.assert_allclose(a2.lines[0].get_ydata(), [300.0, 260.0, 250.0])
    ax = plot_leg_lengths(r)
    assert len(ax.patches) == 2
    ax = plot_convergence([3.0, float("inf"), 1.0], reference=0.5)
    assert len(ax.lines) == 2


@pytest.mark.slow
def test_live_viewer_serves_the_same_scene():
    pytest.importorskip("zmq")
    from weldplan.viz.viewer import live_view

    vis, server = live_view(box_route(), box_part())
    try:
        assert vis.url().startswith("http://127.0.0.1:")
        page = vis.static_html()  # the server's own snapshot of what it holds
        assert "handle_command_bytearray" in page
        ours = static_html(box_route(), box_part())
        # same commands: the server's page and ours carry the same scene blobs
        assert abs(len(page) - len(ours)) < 0.05 * len(ours)
    finally:
        server.close()
    assert server.proc.returncode is not None
