"""Loading a part: any mesh file trimesh reads, merged into one triangle mesh in millimetres.

Every 3D quantity inside weldplan is in mm (DESIGN.md); this loader is where files in other units
are converted. Multi-body files (OBJ groups, GLB scenes) become one part, since the torch must
avoid all of it; faces of zero area are dropped because they carry no geometry and upset the
distance and collision queries.
"""

from __future__ import annotations

import logging
from os import PathLike
from pathlib import Path

import numpy as np
import trimesh

from weldplan.errors import InputError

log = logging.getLogger(__name__)

#: file suffixes :func:`load_part` accepts (those trimesh reads natively)
MESH_SUFFIXES: tuple[str, ...] = (".stl", ".obj", ".ply", ".off", ".glb", ".gltf")

#: millimetres per unit for the ``units`` option of the loaders
UNITS_MM: dict[str, float] = {
    "mm": 1.0,
    "cm": 10.0,
    "dm": 100.0,
    "m": 1000.0,
    "in": 25.4,
    "ft": 304.8,
}

#: faces with an area below this fraction of the mean face area squared-length scale are dropped
_DEGENERATE_REL_AREA = 1e-12


def unit_scale(units: str) -> float:
    """Millimetres per unit of ``units`` (one of :data:`UNITS_MM`)."""
    try:
        return UNITS_MM[units]
    except KeyError:
        raise InputError(
            f"unknown units {units!r}; use one of {', '.join(UNITS_MM)}", field="units"
        ) from None


def load_part(
    path: str | PathLike[str],
    *,
    units: str = "mm",
    scale: float | None = None,
    length: float | None = None,
) -> trimesh.Trimesh:
    """Load a part from STL, OBJ, PLY, OFF, GLB or GLTF into one mesh in millimetres.

    Parameters
    ----------
    path
        The mesh file. Scenes and multi-body files are merged (with their node transforms
        applied) into a single mesh.
    units
        Unit of the file's coordinates: ``"mm"`` (default), ``"cm"``, ``"dm"``, ``"m"``, ``"in"``
        or ``"ft"``. Coordinates are multiplied by :data:`UNITS_MM` ``[units]``.
    scale
        Extra factor applied after ``units`` (for files in arbitrary units).
    length
        Alternative to ``scale``: scale uniformly so that the largest bounding-box extent of the
        part is ``length`` mm. ``../shared/data/bodies/car2.obj`` is about 99 units long:
        ``load_part(car2, length=4500)`` gives a 4500 mm body.

    Returns
    -------
    trimesh.Trimesh
        The part in mm, with degenerate (zero-area) faces and unreferenced vertices removed.
        Not necessarily watertight: sheet-metal parts rarely are.

    Raises
    ------
    InputError
        The file is missing, unreadable, has an unsupported suffix, holds no triangles, or the
        scale options are invalid; the message names the file.
    """
    path = Path(path)
    factor = unit_scale(units)
    if scale is not None and length is not None:
        raise InputError("give scale or length, not both", path=path, field="scale")
    if scale is not None and not (np.isfinite(scale) and scale > 0):
        raise InputError(f"scale must be a positive number, got {scale}", path=path, field="scale")
    if length is not None and not (np.isfinite(length) and length > 0):
        raise InputError(
            f"length must be a positive number of mm, got {length}", path=path, field="length"
        )
    if not path.exists():
        raise InputError("mesh file not found", path=path)
    if path.is_dir():
        raise InputError("expected a mesh file, got a directory", path=path)
    if path.suffix.lower() not in MESH_SUFFIXES:
        raise InputError(
            f"unsupported mesh format {path.suffix!r}; use one of {', '.join(MESH_SUFFIXES)}",
            path=path,
        )
    try:
        loaded = trimesh.load(str(path), force="mesh", process=True)
    except Exception as exc:  # trimesh raises many kinds on bad files
        raise InputError(f"cannot read mesh: {exc}", path=path) from exc
    mesh = _as_single_mesh(loaded, path)

    mesh = clean_mesh(mesh)
    if len(mesh.faces) == 0:
        raise InputError("mesh has no non-degenerate triangles", path=path)
    factor *= 1.0 if scale is None else float(scale)
    if length is not None:
        extent = float(np.max(mesh.extents)) * factor
        factor *= float(length) / extent
    if factor != 1.0:
        mesh.apply_scale(factor)
    log.info(
        "loaded %s: %d vertices, %d faces, extents %s mm",
        path,
        len(mesh.vertices),
        len(mesh.faces),
        np.round(mesh.extents, 2),
    )
    return mesh


def _as_single_mesh(loaded: object, path: Path) -> trimesh.Trimesh:
    """One Trimesh from whatever trimesh.load returned (mesh, scene, list, point cloud)."""
    if isinstance(loaded, trimesh.Scene):
        geoms = [g for g in loaded.dump() if isinstance(g, trimesh.Trimesh)]
        loaded = trimesh.util.concatenate(geoms) if geoms else trimesh.Trimesh()
    elif isinstance(loaded, (list, tuple)):
        geoms = [g for g in loaded if isinstance(g, trimesh.Trimesh)]
        loaded = trimesh.util.concatenate(geoms) if geoms else trimesh.Trimesh()
    if not isinstance(loaded, trimesh.Trimesh):
        raise InputError(f"file holds no triangle mesh (got {type(loaded).__name__})", path=path)
    return loaded


def clean_mesh(mesh: trimesh.Trimesh) -> trimesh.Trimesh:
    """A copy of ``mesh`` without degenerate faces, unreferenced or non-finite vertices.

    A face is degenerate when its area is zero to round-off (repeated or collinear vertices).
    """
    vertices = np.asarray(mesh.vertices, dtype=np.float64)
    faces = np.asarray(mesh.faces, dtype=np.int64).reshape(-1, 3)
    if len(faces) == 0:
        return trimesh.Trimesh(
            vertices=np.zeros((0, 3)), faces=np.zeros((0, 3), int), process=False
        )
    tri = vertices[faces]
    finite = np.all(np.isfinite(tri), axis=(1, 2))
    cross = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    area2 = np.linalg.norm(cross, axis=1)
    edge2 = np.max(np.sum((tri - np.roll(tri, 1, axis=1)) ** 2, axis=2), axis=1)
    keep = finite & (area2 > _DEGENERATE_REL_AREA * np.maximum(edge2, np.finfo(float).tiny))
    keep &= (
        (faces[:, 0] != faces[:, 1]) & (faces[:, 1] != faces[:, 2]) & (faces[:, 0] != faces[:, 2])
    )
    dropped = int((~keep).sum())
    if dropped:
        log.info("dropped %d degenerate faces", dropped)
    out = trimesh.Trimesh(vertices=vertices, faces=faces[keep], process=False)
    out.remove_unreferenced_vertices()
    return out
