"""The pages' opening view and their pictures: the camera framed on everything drawn, labels of
one screen size, and ``--png`` / :func:`weldplan.viz.render_png` rendered by headless Chromium and
checked on the image itself (not blank, the part's and the route's colours, framed about the
centre)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from tests.cli_helpers import one_line_error, run_cli
from tests.route_fixtures import box_part, box_route
from tests.test_viewer import _chromium
from weldplan.errors import ConfigError, RunError
from weldplan.viz import camera
from weldplan.viz.camera import MARGIN, camera_local, camera_view, scene_transform

meshcat = pytest.importorskip("meshcat")


# ---------------------------------------------------------------------------- image checks
def load_rgb(data: bytes) -> np.ndarray:
    """``(h, w, 3) float`` pixels of PNG bytes."""
    import io

    from PIL import Image

    return np.asarray(Image.open(io.BytesIO(data)).convert("RGB"), dtype=float)


def greyish(img: np.ndarray) -> np.ndarray:
    """The see-through grey part over meshcat's blue background: red close to blue."""
    return (np.abs(img[..., 0] - img[..., 2]) < 40) & (img[..., 1] > 90)


def reddish(img: np.ndarray) -> np.ndarray:
    """The route's red (the first leg, the joints, the robot page's route and welds)."""
    return (img[..., 0] > 150) & (img[..., 1] < 90) & (img[..., 2] < 90)


def check_picture(img: np.ndarray, *masks: np.ndarray, min_pixels: int = 20) -> None:
    """Not blank; every colour of ``masks`` present; what they cover is framed about the
    centre (its bounding box holds the picture's centre, its middle is in the central half)
    and fills the view (it spans at least 40 % of the picture's width or height)."""
    h, w = img.shape[:2]
    assert img.std() > 10.0, "blank picture"
    for k, m in enumerate(masks):
        assert m.sum() >= min_pixels, f"colour {k} missing ({int(m.sum())} pixels)"
    ys, xs = np.nonzero(np.logical_or.reduce(masks))
    assert xs.min() < w / 2 < xs.max() and ys.min() < h / 2 < ys.max(), "the centre is empty"
    cx, cy = (xs.min() + xs.max()) / 2, (ys.min() + ys.max()) / 2
    assert w / 4 < cx < 3 * w / 4 and h / 4 < cy < 3 * h / 4, (cx, cy)
    span = max(np.ptp(xs) / w, np.ptp(ys) / h)
    assert span > 0.4, f"the framed content spans {span:.0%} of the view"


# ---------------------------------------------------------------------------- the camera
def _pinhole_ndc(position, corners, aspect):
    """Normalised device coordinates of ``corners`` seen from ``position`` looking at the origin
    with z up, by a pinhole of the page's field of view (an independent look-at)."""
    f = -np.asarray(position) / np.linalg.norm(position)
    r = np.cross(f, [0.0, 0.0, 1.0])
    r /= np.linalg.norm(r)
    u = np.cross(r, f)
    rel = corners - np.asarray(position)
    depth = rel @ f
    t = np.tan(np.radians(camera.FOV_DEG) / 2)
    return (rel @ r) / (depth * t * aspect), (rel @ u) / (depth * t), depth


@pytest.mark.parametrize("seed", range(6))
def test_the_camera_fits_the_box_tightly(seed):
    rng = np.random.default_rng(seed)
    half = rng.uniform(0.05, 1.0, 3)
    half *= 1.0 / half.max()  # scene_transform's box: 2 units on its longest side
    lo, hi = -half, half
    corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1])
                        for z in (lo[2], hi[2])])  # fmt: skip
    view = camera_view(corners)
    x, y, depth = _pinhole_ndc(view.position, corners, camera.ASPECT)
    assert np.all(np.abs(x) <= 1 / MARGIN + 1e-9) and np.all(np.abs(y) <= 1 / MARGIN + 1e-9)
    # tight: some corner touches the margin (the box is not a speck in the view)
    assert max(np.abs(x).max(), np.abs(y).max()) == pytest.approx(1 / MARGIN, rel=1e-6)
    assert np.all(depth > view.near) and np.all(depth < view.far)
    assert view.position[2] > 0 and view.position[1] < 0  # from above, at the front


def test_the_robot_cell_is_seen_across_the_robots_reach():
    from weldplan.viz.camera import ROBOT_AZIMUTH_OFFSET_DEG, robot_azimuth, view_direction

    # the robot at the origin reaching along +y: the camera 60 deg to the left of that line
    az = robot_azimuth([0.0, 0.0, 0.0], [0.0, 1500.0, 800.0])
    assert az == pytest.approx(90.0 + ROBOT_AZIMUTH_OFFSET_DEG)
    d = view_direction(az, 0.0)
    assert np.degrees(np.arccos(d @ [0.0, 1.0, 0.0])) == pytest.approx(ROBOT_AZIMUTH_OFFSET_DEG)
    assert robot_azimuth([5.0, 5.0, 0.0], [5.0, 5.0, 900.0]) == camera.AZIMUTH_DEG  # overhead


def test_camera_local_undoes_meshcats_quarter_turn():
    # meshcat hangs its camera under a group turned by +90 deg about x (three.js is y up)
    Rx = np.array([[1.0, 0, 0], [0, 0, -1], [0, 1, 0]])
    p = np.array([0.3, -1.2, 0.7])
    np.testing.assert_allclose(Rx @ camera_local(p), p)


def test_scene_transform_centres_the_box_on_two_units():
    P = np.array([[1000.0, -200, 650], [1600, 20, 900], [1300, 0, 700]])
    T = scene_transform(P)
    Q = P @ T[:3, :3].T + T[:3, 3]
    np.testing.assert_allclose(Q.min(axis=0) + Q.max(axis=0), 0.0, atol=1e-12)
    assert np.ptp(Q, axis=0).max() == pytest.approx(camera.SCENE_SIZE)


def test_the_route_page_sets_the_framed_camera_and_screen_size_labels():
    import umsgpack
    from meshcat.servers.tree import find_node

    from weldplan.viz.viewer import LABEL_SIZE, RecordingWindow, build_scene, label_image

    window = RecordingWindow()
    build_scene(meshcat.Visualizer(window=window), box_route(), box_part())
    cam = find_node(window.tree, ["Cameras", "default", "rotated", "<object>"])
    props = {(d := umsgpack.unpackb(b))["property"]: d["value"] for b in cam.properties}
    # the framed box: the part's and the route's, centred on the origin, 2 units across
    route = box_route()
    P = np.concatenate([box_part().vertices, route.joint_xyz, *(g.points for g in route.legs)])
    s = camera.SCENE_SIZE / np.ptp(P, axis=0).max()
    view = camera_view(s * (P - (P.min(axis=0) + P.max(axis=0)) / 2))
    np.testing.assert_allclose(props["position"], camera_local(view.position), rtol=1e-6)
    assert props["near"] == pytest.approx(view.near) and props["far"] == pytest.approx(view.far)
    assert props["fov"] == camera.FOV_DEG
    node = find_node(window.tree, ["meshcat", "weldplan", "labels", "A"])
    label = umsgpack.unpackb(node.object)["object"]
    assert label["object"]["renderOrder"] > 0  # after the see-through part
    mat = label["materials"][0]
    assert mat["sizeAttenuation"] is False and mat["depthTest"] is False
    assert label["object"]["name"] == "label A"
    T = np.array(umsgpack.unpackb(node.transform)["matrix"]).reshape(4, 4).T
    _, aspect, height = label_image("A")
    assert T[1, 1] * s / height == pytest.approx(LABEL_SIZE, rel=1e-5)  # one box height
    assert T[0, 0] / T[1, 1] == pytest.approx(aspect, rel=1e-5)  # the image's own width


def test_a_label_is_a_white_box_with_dark_text():
    import io

    from PIL import Image

    from weldplan.viz.viewer import label_image

    png, aspect, height = label_image("13")
    rgba = np.asarray(Image.open(io.BytesIO(png)).convert("RGBA"), dtype=float)
    h, w = rgba.shape[:2]
    assert aspect == pytest.approx(w / h)
    box = rgba[: int(round(h / height))]  # the box on top, clear below the box's gap
    assert (rgba[h // 2 :, :, 3] == 0).all()  # the weld below the label stays visible
    rgb = box[..., :3]
    dark = (rgb.max(axis=2) < 80).mean()
    assert 0.03 < dark < 0.5 and (rgb.min(axis=2) > 200).mean() > 0.4  # text on white


def test_joint_spheres_never_merge():
    from weldplan.viz.viewer import JOINT_GAP_SHARE, JOINT_SHARE, joint_radius

    P = np.array([[0.0, 0, 0], [10, 0, 0], [500, 0, 0]])
    assert joint_radius(P, 1000.0) == pytest.approx(JOINT_GAP_SHARE * 10)
    assert joint_radius(P[[0, 2]], 600.0) == pytest.approx(JOINT_SHARE * 600)
    assert joint_radius(P[[0, 0]], 600.0) == pytest.approx(0.6)  # duplicates: a floor


# ---------------------------------------------------------------------------- --png errors
@pytest.fixture
def no_chromium(monkeypatch, tmp_path):
    monkeypatch.delenv("WELDPLAN_CHROMIUM", raising=False)
    monkeypatch.setenv("PATH", str(tmp_path / "empty"))


def test_no_chromium_is_one_line_naming_the_package(no_chromium, tmp_path):
    from weldplan.viz import render_png
    from weldplan.viz.viewer import static_html

    with pytest.raises(ConfigError, match="apt-get install chromium"):
        render_png(static_html(box_route(), box_part()), tmp_path / "x.png")
    assert not (tmp_path / "x.png").exists()


def test_view_png_without_chromium_fails_before_any_work(no_chromium, tmp_path, capsys):
    from weldplan.io.export import write_json

    route = write_json(box_route(), tmp_path / "r.json")
    rc = run_cli(["view", str(route), "--png", str(tmp_path / "x.png"), "--html",
                  str(tmp_path / "x.html")])  # fmt: skip
    assert rc == 2
    assert "apt-get install chromium" in one_line_error(capsys)
    assert not (tmp_path / "x.png").exists() and not (tmp_path / "x.html").exists()


def test_a_failed_render_leaves_the_old_picture(monkeypatch, tmp_path):
    from weldplan.viz import render_png

    monkeypatch.setenv("WELDPLAN_CHROMIUM", "false")  # exits 1, writes nothing
    old = tmp_path / "x.png"
    old.write_bytes(b"old picture")
    with pytest.raises(RunError, match="wrote no PNG"):
        render_png("<html></html>", old)
    assert old.read_bytes() == b"old picture"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["x.png"]  # no temporary left


# ---------------------------------------------------------------------------- pictures
@pytest.mark.slow
def test_png_of_the_box_route(tmp_path):
    pytest.importorskip("PIL")
    _chromium()
    from weldplan.viz import render_png
    from weldplan.viz.png import PngSettings
    from weldplan.viz.viewer import static_html

    settings = PngSettings(width=900, height=600)
    path = render_png(static_html(box_route(), box_part()), tmp_path / "box.png", settings)
    img = load_rgb(path.read_bytes())
    assert img.shape == (600, 900, 3)
    check_picture(img, greyish(img), reddish(img))
    assert greyish(img).mean() > 0.05  # the part, not a sliver


@pytest.mark.slow
def test_view_png_of_the_demo_route(tmp_path):
    pytest.importorskip("PIL")
    _chromium()
    from weldplan.io.export import write_json
    from weldplan.weld.cell import demo_cell
    from weldplan.weld.pipeline import PlanConfig, plan_route

    cell = demo_cell()
    route = plan_route(cell, config=PlanConfig(planner="exact", sequencer="exact"))
    write_json(route, tmp_path / "r.json")
    cell.part.export(tmp_path / "part.stl")
    rc = run_cli(["view", str(tmp_path / "r.json"), str(tmp_path / "part.stl"),
                  "--png", str(tmp_path / "demo.png")])  # fmt: skip
    assert rc == 0
    img = load_rgb((tmp_path / "demo.png").read_bytes())
    check_picture(img, greyish(img), reddish(img))


def test_weld_slider_data_is_on_the_page():
    from weldplan.viz.overlay import WeldSlider

    T = np.tile(np.eye(4), (2, 1, 1))
    T[1, :3, 3] = [1.0, 2.0, 3.0]
    page = WeldSlider.from_poses(["A", "B</script>"], T, "/meshcat/weldplan/tool/gun").html()
    data = json.loads(page.split("var data = ", 1)[1].split(";\n", 1)[0].replace("<\\/", "</"))
    assert data["ids"] == ["A", "B</script>"] and data["times"] == []
    assert data["matrices"][1][12:15] == [1.0, 2.0, 3.0]  # column-major: translation last
    assert "</script>" not in page.split("var data = ", 1)[1].split(";\n", 1)[0]
    assert 'max="1"' in page


@pytest.mark.slow
def test_plan_png_of_the_demo_station_with_the_gun_and_the_robot(tmp_path):
    """The demo station (the shared gun on the shared KUKA): ``--png`` is the robot cell's page,
    the route page shows the gun at the weld asked for."""
    pytest.importorskip("PIL")
    _chromium()
    from tests.conftest import ROOT, require_shared
    from weldplan.viz.png import PngSettings, png_bytes

    require_shared("robots", "kuka_kr150r3100_2")
    station = ROOT / "examples" / "demo_station.toml"
    out = {k: str(tmp_path / k) for k in ("route.csv", "route.html", "cell.png")}
    rc = run_cli(["plan", str(station), "-o", out["route.csv"], "--quiet",
                  "--html", out["route.html"], "--png", out["cell.png"]])  # fmt: skip
    assert rc == 0
    img = load_rgb((tmp_path / "cell.png").read_bytes())
    r, g, b = img[..., 0], img[..., 1], img[..., 2]
    orange = (r > 180) & (g > 90) & (g < 170) & (b < 80)  # the robot (0xF28C28)
    check_picture(img, orange, greyish(img), reddish(img), min_pixels=10)
    assert orange.mean() > 0.02  # the robot whole in the view, not cut off
    page = (tmp_path / "route.html").read_text(encoding="utf-8")
    img = load_rgb(png_bytes(page, PngSettings(width=900, height=600, weld="7")))
    r, g, b = img[..., 0], img[..., 1], img[..., 2]
    purple = (b > g + 40) & (r > g + 20)  # the gun (0x8E44AD)
    green = (g > r + 40) & (g > b + 30)  # welds with a free gun pose (0x2CA02C)
    check_picture(img, purple, greyish(img), green, min_pixels=10)


def test_a_picture_is_written_byte_for_byte_with_the_set(tmp_path):
    from weldplan.io.outputset import write_outputs

    data = bytes(range(256)) * 4  # every byte value, newlines and all
    write_outputs({tmp_path / "a.png": data, tmp_path / "a.txt": "text\n"})
    assert (tmp_path / "a.png").read_bytes() == data
    assert (tmp_path / "a.txt").read_text() == "text\n"
