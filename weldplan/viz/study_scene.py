"""The feasibility study as a self-contained 3D page: the part, the spots coloured by verdict, the
robots' bases, a legend and the table of verdicts (``weldplan check-spots --html``).

The scene is recorded as :mod:`weldplan.viz.viewer` records a route's
(:class:`~weldplan.viz.viewer.RecordingWindow`: meshcat's own static page, no server); the
legend and the table are plain HTML laid over it. A spot's colour is its best verdict over the
tools and robots (:func:`spot_class`). The viewer consumes the study; it plans nothing.
"""

from __future__ import annotations

from html import escape
from os import PathLike
from pathlib import Path
from typing import Any

import numpy as np
import trimesh

from weldplan.study.result import NO_GUN_POSE, NO_SURFACE, FeasibilityStudy, SpotVerdict

#: class -> (colour 0xRRGGBB, legend words), in the legend's order
CLASSES: dict[str, tuple[int, str]] = {
    "feasible": (0x2CA02C, "feasible: a robot reaches a free gun pose"),
    "unreached": (0xFF7F0E, "the gun closes, no robot reaches a free pose"),
    "no_gun_pose": (0xD62728, "no free gun pose"),
    "no_surface": (0x7F7F7F, "no surface near the spot"),
}
#: spots labelled with their id when there are at most this many
MAX_LABELS = 60


def spot_class(spot: SpotVerdict) -> str:
    """The spot's class in :data:`CLASSES`: feasible; else the gun closes but no robot reaches
    (with robots); else no free gun pose; else no surface."""
    if spot.feasible:
        return "feasible"
    if any(g.ok for g in spot.guns):
        return "unreached"
    if any(g.status == NO_GUN_POSE for g in spot.guns):
        return "no_gun_pose"
    if all(g.status == NO_SURFACE for g in spot.guns):
        return "no_surface"
    return "no_gun_pose"


def build_study_scene(vis: Any, study: FeasibilityStudy, part: trimesh.Trimesh | None) -> None:
    """Draw ``study`` into meshcat visualizer ``vis`` under ``weldplan/``: ``part``,
    ``spots/<class>/<id>``, ``labels/<id>``, ``robots/<name>`` (a column at each base)."""
    from weldplan.viz.camera import frame_scene
    from weldplan.viz.viewer import _meshcat, _translation, draw_label

    g = _meshcat().geometry
    root = vis["weldplan"]
    root.delete()
    P = np.array([s.position for s in study.spots], dtype=np.float64).reshape(-1, 3)
    bases = np.array([r.base_matrix()[:3, 3] for r in study.robots]).reshape(-1, 3)
    frame = np.concatenate([P, bases])
    extent = float(np.ptp(frame, axis=0).max()) if len(frame) > 1 else 100.0
    r_spot = max(extent, 1.0) / 150.0
    # the opening view: the part, the spots and the robots' columns (40 spot radii tall)
    framed = [frame, bases + [0.0, 0.0, 40 * r_spot]]
    if part is not None:
        framed.append(np.asarray(part.vertices))
    scale = frame_scene(vis, root, np.concatenate(framed))
    if part is not None:
        root["part"].set_object(
            g.TriangularMeshGeometry(np.asarray(part.vertices), np.asarray(part.faces)),
            g.MeshLambertMaterial(color=0x9AA6B2, opacity=0.55, transparent=True, side=2),
        )
    labels = len(study.spots) <= MAX_LABELS
    for s, p in zip(study.spots, P, strict=True):
        c = spot_class(s)
        node = root["spots"][c][s.id]
        node.set_object(g.Sphere(r_spot), g.MeshLambertMaterial(color=CLASSES[c][0]))
        node.set_transform(_translation(p))
        if labels:
            draw_label(root["labels"][s.id], s.id, p + [0.0, 0.0, 2.0 * r_spot], scale)
    for r, b in zip(study.robots, bases, strict=True):
        col = root["robots"][r.name]
        col.set_object(g.Cylinder(40 * r_spot, 6 * r_spot), g.MeshLambertMaterial(color=0xF2B705))
        T = np.eye(4)
        T[:3, :3] = [[1, 0, 0], [0, 0, -1], [0, 1, 0]]  # meshcat cylinders run along y
        T[:3, 3] = b + [0.0, 0.0, 20 * r_spot]
        col.set_transform(T)


def study_html(study: FeasibilityStudy, part: trimesh.Trimesh | None = None) -> str:
    """The self-contained page: the 3D scene, the legend with counts, the table of verdicts."""
    from weldplan.viz.viewer import RecordingWindow, _meshcat

    window = RecordingWindow()
    vis = _meshcat().Visualizer(window=window)
    build_study_scene(vis, study, part)
    n_ok = int(study.feasible.sum())
    page = window.get_scene(title=f"weldplan check-spots: {n_ok} / {len(study.spots)} feasible")
    return page.replace("</body>", _overlay(study) + "\n</body>", 1)


def write_study_html(
    study: FeasibilityStudy, part: trimesh.Trimesh | None, path: str | PathLike[str]
) -> Path:
    """Write :func:`study_html` to ``path`` atomically; returns the path."""
    from weldplan.io.export import write_text_atomic

    return write_text_atomic(path, study_html(study, part))


def _overlay(study: FeasibilityStudy) -> str:
    """The legend (colour, words, count per class) and the verdict table, as HTML."""
    from collections import Counter

    counts = Counter(spot_class(s) for s in study.spots)
    items = "".join(
        f'<div><span style="display:inline-block;width:12px;height:12px;border-radius:6px;'
        f'background:#{col:06x};margin-right:6px"></span>{escape(words)}: {counts.get(c, 0)}'
        "</div>"
        for c, (col, words) in CLASSES.items()
    )
    robots = "".join(
        f"<div>robot {escape(r.name)}: base ({', '.join(f'{v:.0f}' for v in r.xyz_yaw()[:3])}) "
        f"mm, yaw {r.xyz_yaw()[3]:.1f} deg{' (searched)' if r.searched else ''}</div>"
        for r in study.robots
    )
    from weldplan.study.table import table_rows

    header, *rows = table_rows(study)
    head = "".join(f"<th>{escape(h)}</th>" for h in header)
    body = "".join("<tr>" + "".join(f"<td>{escape(v)}</td>" for v in r) + "</tr>" for r in rows)
    return (
        '<div style="position:fixed;top:8px;left:8px;background:rgba(255,255,255,0.92);'
        'padding:8px 10px;font:13px sans-serif;max-width:45vw;max-height:90vh;overflow:auto">'
        f"<b>weld feasibility study</b> ({study.frame} frame, mm)"
        f"{items}{robots}<details><summary>table ({len(rows)} spots)</summary>"
        f'<table style="border-collapse:collapse;font-size:11px" border="1">'
        f"<tr>{head}</tr>{body}</table></details></div>"
    )
