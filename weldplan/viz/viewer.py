"""The meshcat viewer of a route: part, labelled joints, legs coloured by leg, vias, a torch.

Three ways to see the same scene (all built by :func:`build_scene`):

- :func:`write_html` / :func:`static_html`: a self-contained HTML page (the meshcat viewer's
  JavaScript and every scene command inlined) that works offline, from a file or an e-mail;
  :func:`weldplan.viz.png.render_png` renders it to a PNG for reports;
- :func:`jupyter_view` (and :func:`weldplan.viz.show`): that page inline in a notebook cell;
- :func:`view_route`: a live meshcat server (``weldplan view``), for stepping and inspecting.

The static page needs no meshcat server: the scene commands are recorded by
:class:`RecordingWindow`, which packs them exactly as meshcat's own server does for
``Visualizer.static_html()`` (same scene tree, same msgpack blobs, same page template). The torch
is a meshcat animation along the route at constant speed: the viewer's *Animations* panel plays,
pauses and scrubs it (step it with the time slider). A route planned with a tool shows the tool at
one weld at a time, picked by the weld slider laid over the page
(:class:`~weldplan.viz.overlay.WeldSlider`); its animation along the transitions waits in the
*Animations* panel.

The page opens framed on everything drawn, the part, the route and the tool at its weld poses
(:func:`weldplan.viz.camera.frame_scene`: scaled to about 2 viewer units, centred on the origin,
the camera on a diagonal, z up). Weld labels keep one size on the screen at any zoom
(:data:`LABEL_SIZE`), white boxes drawn over everything. Algorithms never import this module.
"""

from __future__ import annotations

import base64
import colorsys
import functools
import logging
import os
from os import PathLike
from pathlib import Path
from typing import Any

import numpy as np
import trimesh
from numpy.typing import NDArray

from weldplan.tool.section import ToolSection
from weldplan.viz.camera import FOV_DEG, SCENE_SIZE, frame_scene, scene_transform  # noqa: F401
from weldplan.viz.overlay import WeldSlider
from weldplan.weld.route import Route

log = logging.getLogger(__name__)

#: seconds the torch takes for the whole route in the animation
ANIMATION_SECONDS = 20.0
#: a label's height as a share of the view's height (its text is about 2/3 of it) ...
LABEL_SCREEN_SHARE = 0.034
#: the label images' font size (pixels; the texture's resolution, not the size on the screen)
LABEL_FONT_PX = 40
#: ... as the sprite's scale: three.js draws a sprite without size attenuation as if it stood
#: at distance 1, where the view is 2 tan(fov / 2) high
LABEL_SIZE = LABEL_SCREEN_SHARE * 2.0 * float(np.tan(np.radians(FOV_DEG) / 2))
#: labels are drawn after everything else (three.js renderOrder), so the part never veils them
LABEL_RENDER_ORDER = 1000
#: a joint sphere's radius: this share of the framed scene's size ...
JOINT_SHARE = 1.0 / 100.0
#: ... but at most this share of the distance between the two closest joints
JOINT_GAP_SHARE = 0.35


def _meshcat() -> Any:
    try:
        import meshcat
        import meshcat.geometry  # noqa: F401
    except ImportError as exc:  # pragma: no cover - meshcat is a runtime dependency
        raise ImportError("the viewer needs meshcat: pip install meshcat") from exc
    return meshcat


def _part_mesh(part: Any) -> trimesh.Trimesh | None:
    if part is None:
        return None
    mesh = getattr(part, "part", part)
    if not isinstance(mesh, trimesh.Trimesh):
        raise TypeError(f"expected a trimesh.Trimesh or a Cell, got {type(part)}")
    return mesh


def leg_colors(n: int) -> list[int]:
    """``n`` distinct colours (0xRRGGBB) around the hue circle, for the legs in order."""
    out = []
    for k in range(n):
        r, g, b = colorsys.hsv_to_rgb((k * 0.618033988749895) % 1.0, 0.85, 0.95)
        out.append((int(r * 255) << 16) | (int(g * 255) << 8) | int(b * 255))
    return out


# ---------------------------------------------------------------------------- recording window
class RecordingWindow:
    """A stand-in for meshcat's ``ViewerWindow`` that records commands instead of sending them.

    It keeps the scene tree the way meshcat's ZMQ server does (an object, its properties, a
    transform and an animation per path) and renders the same static page
    (:meth:`get_scene`), with no server process and no sockets.
    """

    def __init__(self) -> None:
        from meshcat.servers.tree import SceneTree

        self.tree = SceneTree()
        self.web_url = None
        self.zmq_url = None

    def send(self, command: Any) -> None:
        import umsgpack
        from meshcat.servers.tree import SceneTree, find_node

        data = command.lower()
        cmd = data["type"]
        path = [p for p in data["path"].split("/") if p]
        blob = umsgpack.packb(data)
        if cmd == "set_object":
            node = find_node(self.tree, path)
            node.object = blob
            node.properties = []
        elif cmd == "set_transform":
            find_node(self.tree, path).transform = blob
        elif cmd == "set_property":
            find_node(self.tree, path).properties.append(blob)
        elif cmd == "set_animation":
            find_node(self.tree, path).animation = blob
        elif cmd == "delete":
            if path:
                parent = find_node(self.tree, path[:-1])
                parent.pop(path[-1], None)
            else:
                self.tree = SceneTree()
        else:
            raise ValueError(f"unsupported meshcat command {cmd!r}")

    def get_scene(self, title: str = "weldplan route", overlay: str = "") -> str:
        """The self-contained HTML page of the recorded scene, with ``overlay`` (HTML) laid over
        it."""
        from meshcat.servers.tree import walk
        from meshcat.servers.zmqserver import VIEWER_ROOT

        blobs: list[bytes] = []
        for node in walk(self.tree):
            if node.object is not None:
                blobs.append(node.object)
            blobs.extend(node.properties)
            if node.transform is not None:
                blobs.append(node.transform)
            if node.animation is not None:
                blobs.append(node.animation)
        js = Path(VIEWER_ROOT, "main.min.js").read_text(encoding="utf-8")
        # Commands are applied in order (each awaits the previous), like meshcat's server does
        # it, but as one chain so a property never arrives before its object.
        b64 = ",\n".join(f'"{base64.b64encode(b).decode("ascii")}"' for b in blobs)
        return _PAGE.format(title=title, mainminjs=js, blobs=b64, overlay=overlay)

    def close(self) -> None:
        pass


_PAGE = """<!DOCTYPE html>
<html>
<head><meta charset="utf-8"><title>{title}</title>
<style>
body {{ margin: 0; }}
#meshcat-pane {{ width: 100vw; height: 100vh; overflow: hidden; }}
</style>
</head>
<body>
<div id="meshcat-pane"></div>
<script>
{mainminjs}
</script>
<script>
var viewer = new MeshCat.Viewer(document.getElementById("meshcat-pane"));
var weldplanCommands = [
{blobs}
];
function weldplanDecode(b64) {{
  var s = atob(b64), a = new Uint8Array(s.length);
  for (var i = 0; i < s.length; i++) a[i] = s.charCodeAt(i);
  return a;
}}
for (var i = 0; i < weldplanCommands.length; i++) {{
  viewer.handle_command_bytearray(weldplanDecode(weldplanCommands[i]));
}}
document.title = "{title} (" + weldplanCommands.length + " scene commands)";
</script>
{overlay}
</body>
</html>
"""


# ---------------------------------------------------------------------------- scene
@functools.lru_cache(maxsize=4096)
def label_image(text: str) -> tuple[bytes, float, float]:
    """``(PNG bytes, width / height, height / the box's height)``: ``text`` in black on a white
    rounded box with a grey edge, readable over the part, the route and the background alike
    (Pillow's own font, so no font file is needed). The box fills the image's top rows and the
    rest is clear: the image's centre, where the sprite stands, is a third of the box's height
    below the box, so the label sits over its weld without hiding it."""
    import io

    from PIL import Image, ImageDraw, ImageFont

    font = ImageFont.load_default(size=LABEL_FONT_PX)
    left, top, right, bottom = font.getbbox(text)
    pad = LABEL_FONT_PX // 4
    w, h = right - left + 2 * pad, LABEL_FONT_PX + 2 * pad
    img = Image.new("RGBA", (w, 2 * (h + h // 3)), (0, 0, 0, 0))
    draw = ImageDraw.Draw(img)
    draw.rounded_rectangle((0, 0, w - 1, h - 1), radius=pad, fill=(255, 255, 255, 225),
                           outline=(90, 90, 90, 255), width=2)  # fmt: skip
    draw.text((pad - left, pad + (LABEL_FONT_PX - bottom - top) // 2), text, fill=(17, 17, 17, 255),
              font=font)  # fmt: skip
    out = io.BytesIO()
    img.save(out, format="PNG")
    return out.getvalue(), w / img.height, img.height / h


def _text_sprite(text: str) -> Any:
    """A camera-facing label (three.js Sprite textured with :func:`label_image`) of one size on
    the screen whatever the zoom (no size attenuation), drawn over everything (no depth test,
    drawn last); the object carries ``text`` as its name."""
    g = _meshcat().geometry
    png = label_image(text)[0]

    class SpriteMaterial(g.GenericMaterial):
        _type = "SpriteMaterial"

    class Sprite(g.Object):
        _type = "Sprite"

        def lower(self) -> dict[str, Any]:
            data = super().lower()
            data["object"]["renderOrder"] = LABEL_RENDER_ORDER  # after the see-through part
            data["object"]["name"] = f"label {text}"
            return data

    material = SpriteMaterial(map=g.ImageTexture(g.PngImage(png)), transparent=True)
    material.properties = {"depthTest": False, "sizeAttenuation": False}
    return Sprite(g.Sphere(1.0), material)


def draw_label(node: Any, text: str, p: NDArray[np.float64], scale: float) -> None:
    """Label ``text`` at ``p`` (mm) under ``node``, whose scene scale is ``scale`` (viewer units
    per mm, :func:`~weldplan.viz.camera.frame_scene`): its box :data:`LABEL_SIZE` high on the
    screen, above ``p`` (:func:`label_image`)."""
    _, aspect, height = label_image(text)
    node.set_object(_text_sprite(text))
    T = _translation(p, scale=LABEL_SIZE * height / scale)
    T[0, 0] *= aspect
    node.set_transform(T)


def _translation(p: NDArray[np.float64], scale: float = 1.0) -> NDArray[np.float64]:
    T = np.eye(4)
    T[:3, :3] *= scale
    T[:3, 3] = p
    return T


def build_scene(
    vis: Any,
    route: Route,
    part: Any = None,
    *,
    labels: bool = True,
    animate: bool = True,
    camera: bool = True,
    tool: Any = None,
) -> WeldSlider | None:
    """Draw ``route`` (and ``part``, a mesh or a Cell) into meshcat visualizer ``vis``.

    Paths under ``vis["weldplan"]``: ``part``, ``joints/<id>``, ``labels/<id>``,
    ``route/leg_<k>`` (one colour per leg), ``vias/leg_<k>``, ``torch``. A route that carries
    weld poses (``weldplan plan --tool``) also gets ``tool/...``: the ``tool``
    (:class:`~weldplan.tool.model.Tool`) at one weld pose and the welds without a pose in red
    (:func:`weldplan.viz.tool_scene.draw_tool`); its animation along the transitions is loaded
    paused. With ``camera`` the view is framed on everything drawn
    (:func:`~weldplan.viz.camera.frame_scene`).

    Returns
    -------
    WeldSlider or None
        The weld slider that moves the tool (None without a tool drawn); :func:`static_html`
        lays it over the page.
    """
    g = _meshcat().geometry
    mesh = _part_mesh(part)
    root = vis["weldplan"]
    root.delete()
    r_joint, r_via, scale = _frame(vis, root, route, mesh, tool, camera)
    if mesh is not None:
        root["part"].set_object(
            g.TriangularMeshGeometry(np.asarray(mesh.vertices), np.asarray(mesh.faces)),
            g.MeshLambertMaterial(color=0x9AA6B2, opacity=0.55, transparent=True, side=2),
        )
    _draw_joints(root, route, r_joint, scale if labels else 0.0)
    _draw_legs(root, route, r_via)
    slider = None
    if ToolSection.of(route).poses is not None:  # the tool at its weld poses
        from weldplan.viz.tool_scene import draw_tool

        slider = draw_tool(root, route, tool, r_joint)
    _draw_torch(vis, root, route, tool, r_joint, animate, play=slider is None)
    log.debug("scene: %d legs, %d joints", len(route.legs), len(route.joint_ids))
    return slider


def _frame(
    vis: Any, root: Any, route: Route, mesh: trimesh.Trimesh | None, tool: Any, camera: bool
) -> tuple[float, float, float]:
    """Frame the scene on the part, the route (joints, legs, the tool's transitions) and the
    tool at its first weld pose (:func:`~weldplan.viz.camera.frame_scene`); return the joint
    and via sphere radii (mm, :func:`joint_radius`) and the scene's scale (viewer units per
    mm)."""
    pts = [route.joint_xyz, *(leg.points for leg in route.legs)]
    section = ToolSection.of(route)
    if section.transitions is not None:  # the tool's path too: its retracts and exits
        pts += [t.positions for t in section.transitions.transitions]
    framed = [np.concatenate(pts, axis=0)]
    if mesh is not None:
        framed.append(np.asarray(mesh.vertices))
    if section.poses is not None and tool is not None:
        from weldplan.viz.tool_scene import tool_corners

        framed.append(tool_corners(route, tool))
    framed_p = np.concatenate(framed, axis=0)
    scale = frame_scene(vis, root, framed_p, camera=camera)
    r_joint = joint_radius(route.joint_xyz, float(np.ptp(framed_p, axis=0).max()) or 1.0)
    return r_joint, 0.4 * r_joint, scale


def joint_radius(joints: NDArray[np.float64], size: float) -> float:
    """A joint sphere's radius (mm): :data:`JOINT_SHARE` of the framed ``size`` (mm), so the
    joints show in the opening view, but at most :data:`JOINT_GAP_SHARE` of the gap between
    the two closest of ``joints (n, 3)`` mm, so neighbours never merge (and at least a
    thousandth of ``size``)."""
    r = JOINT_SHARE * size
    P = np.asarray(joints, dtype=np.float64).reshape(-1, 3)
    if len(P) > 1:
        from scipy.spatial import cKDTree

        gap = float(cKDTree(P).query(P, k=2)[0][:, 1].min())
        r = min(r, JOINT_GAP_SHARE * gap)
    return max(r, 1e-3 * size)


def _draw_joints(root: Any, route: Route, r_joint: float, label_scale: float) -> None:
    """``joints/<id>`` spheres (red where visited, grey where not) and, with ``label_scale``
    (the scene's scale, 0 for none), ``labels/<id>``."""
    g = _meshcat().geometry
    visited = set(route.order)
    for jid, p in zip(route.joint_ids, route.joint_xyz, strict=True):
        color = 0xD62728 if jid in visited else 0x7F7F7F
        root["joints"][jid].set_object(g.Sphere(r_joint), g.MeshLambertMaterial(color=color))
        root["joints"][jid].set_transform(_translation(p))
        if label_scale:
            draw_label(root["labels"][jid], jid, p + [0.0, 0.0, 2.0 * r_joint], label_scale)


def _draw_legs(root: Any, route: Route, r_via: float) -> None:
    """``route/leg_<k>`` lines (one colour per leg) with their tubes, and ``vias/leg_<k>``."""
    g = _meshcat().geometry
    colors = leg_colors(len(route.legs))
    for k, (leg, c) in enumerate(zip(route.legs, colors, strict=True)):
        P = np.asarray(leg.points, dtype=np.float32)
        root["route"][f"leg_{k}"].set_object(
            g.Line(g.PointsGeometry(P.T), g.LineBasicMaterial(color=c, linewidth=3))
        )
        # thin tubes make the legs visible at any zoom (WebGL draws lines 1 px wide)
        for m in range(len(P) - 1):
            a, b = P[m].astype(float), P[m + 1].astype(float)
            L = float(np.linalg.norm(b - a))
            if L < 1e-9:
                continue
            tube = root["route"][f"leg_{k}_tube"][str(m)]
            tube.set_object(g.Cylinder(L, r_via * 0.8), g.MeshLambertMaterial(color=c))
            tube.set_transform(_cylinder_between(a, b))
        for m, v in enumerate(P[1:-1].astype(float)):
            via = root["vias"][f"leg_{k}"][str(m)]
            via.set_object(g.Sphere(r_via * 1.8), g.MeshLambertMaterial(color=0x222222))
            via.set_transform(_translation(v))


def _draw_torch(
    vis: Any, root: Any, route: Route, tool: Any, r_joint: float, animate: bool, *, play: bool
) -> None:
    """The ``torch`` cone at the first waypoint and, with ``animate``, its animation along
    the route at constant speed (:data:`ANIMATION_SECONDS`, 30 frames a second; the tool's
    too when the route carries one), playing at once with ``play``."""
    from meshcat.animation import Animation

    g = _meshcat().geometry
    torch = root["torch"]
    torch.set_object(
        g.Cylinder(6 * r_joint, radiusTop=2.0 * r_joint, radiusBottom=0.0),
        g.MeshLambertMaterial(color=0xFF8C00, opacity=0.9, transparent=True),
    )
    W = route.waypoints()
    if len(W):
        torch.set_transform(_torch_pose(W[0], r_joint))
    if animate and len(W) > 1:
        anim = Animation(default_framerate=30)
        cum = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(W, axis=0), axis=1))])
        frames = np.round(cum / max(cum[-1], 1e-9) * ANIMATION_SECONDS * 30).astype(int)
        for f, p in zip(frames, W, strict=True):
            with anim.at_frame(torch, int(f)) as frame:
                frame.set_transform(_torch_pose(p, r_joint))
        if ToolSection.of(route).transitions is not None:
            from weldplan.viz.tool_scene import animate_tool

            animate_tool(anim, root, route, tool, ANIMATION_SECONDS, 30)
        vis.set_animation(anim, play=play, repetitions=1000)


def _torch_pose(p: NDArray[np.float64], r_joint: float) -> NDArray[np.float64]:
    """The torch cone standing on point ``p`` (tip at ``p``, axis up)."""
    T = np.eye(4)
    # meshcat cylinders run along y; turn y to z so the cone stands over the tip
    T[:3, :3] = [[1, 0, 0], [0, 0, -1], [0, 1, 0]]
    T[:3, 3] = np.asarray(p, dtype=float) + [0.0, 0.0, 3 * r_joint]
    return T


def _cylinder_between(a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
    """Pose of a meshcat cylinder (axis y, centred) spanning segment ``a -> b``."""
    d = b - a
    L = float(np.linalg.norm(d))
    y = d / L
    ref = np.array([0.0, 0.0, 1.0]) if abs(y[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    x = np.cross(y, ref)
    x /= np.linalg.norm(x)
    z = np.cross(x, y)
    T = np.eye(4)
    T[:3, :3] = np.column_stack([x, y, z])
    T[:3, 3] = (a + b) / 2
    return T


# ---------------------------------------------------------------------------- entry points
def static_html(route: Route, part: Any = None, **kwargs: Any) -> str:
    """The self-contained page (no server, works offline) of :func:`build_scene`."""
    mc = _meshcat()
    window = RecordingWindow()
    vis = mc.Visualizer(window=window)
    slider = build_scene(vis, route, part, **kwargs)
    title = f"weldplan route: {len(route.joint_ids)} joints"
    return window.get_scene(title=title, overlay="" if slider is None else slider.html())


def write_html(route: Route, part: Any, path: str | PathLike[str], **kwargs: Any) -> Path:
    """Write :func:`static_html` to ``path`` atomically; returns the path."""
    from weldplan.io.export import write_text_atomic

    return write_text_atomic(path, static_html(route, part, **kwargs))


def jupyter_view(route: Route, part: Any = None, *, height: int = 480) -> Any:
    """An IPython ``HTML`` object: the static page in an iframe (works without a server)."""
    from html import escape

    from IPython.display import HTML

    page = static_html(route, part)
    return HTML(
        f'<div style="height: {int(height)}px; width: 100%; resize: both; overflow: hidden">'
        f'<iframe srcdoc="{escape(page, quote=True)}" '
        'style="width: 100%; height: 100%; border: none"></iframe></div>'
    )


def view_route(
    route: Route,
    part: Any = None,
    *,
    zmq_url: str | None = None,
    host: str = "127.0.0.1",
    port: int | None = None,
    tool: Any = None,
) -> Any:
    """Draw the route in a live meshcat viewer and return the ``meshcat.Visualizer``.

    With ``zmq_url`` None a server is started in a subprocess (:func:`live_view`: web page on
    ``host``, 127.0.0.1 unless told otherwise; stopped at exit, and it dies with this process).
    ``vis.url()`` is the page to open. The scene is the one of :func:`write_html`.
    """
    return live_view(route, part, zmq_url=zmq_url, host=host, port=port, tool=tool)[0]


def live_view(
    route: Route,
    part: Any = None,
    *,
    zmq_url: str | None = None,
    host: str = "127.0.0.1",
    port: int | None = None,
    tool: Any = None,
) -> tuple[Any, Any]:
    """:func:`view_route`, also returning the :class:`weldplan.viz.live.MeshcatServer` it
    started (None when ``zmq_url`` names a running one): ``(vis, server)``. Call
    ``server.close()`` when done."""
    import atexit
    import contextlib
    import io

    from weldplan.viz.live import MeshcatServer

    mc = _meshcat()
    server = None
    if zmq_url is None:
        server = MeshcatServer(host, port)
        zmq_url = server.zmq_url
        atexit.register(server.close)
    try:
        with contextlib.redirect_stdout(io.StringIO()):  # meshcat prints its URL
            vis = mc.Visualizer(zmq_url=zmq_url)
        build_scene(vis, route, part, tool=tool)
    except BaseException:
        if server is not None:
            server.close()
        raise
    return vis, server


def open_in_browser(path: str | PathLike[str]) -> None:  # pragma: no cover - interactive
    import webbrowser

    webbrowser.open("file://" + os.path.abspath(path))
