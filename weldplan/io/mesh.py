"""Loading a part: any mesh file trimesh reads, merged into one triangle mesh in millimetres.

Every 3D quantity inside weldplan is in mm (DESIGN.md); this loader is where files in other units
are converted. Multi-body files (OBJ groups, GLB scenes) become one part, since the torch must
avoid all of it.

What the loader refuses and what it repairs
-------------------------------------------
* A vertex with a NaN or infinite coordinate is an :class:`~weldplan.errors.InputError` naming
  the file, how many vertices are bad and the first one. (trimesh's own processing drops the
  faces that use such vertices without a word: a hole in the part that a route could cross.)
* A coordinate beyond :data:`MAX_COORD_MM` mm after units and scale (1e300, or a wrong
  ``scale``) is an InputError too: no workshop is 100 km across, and grid indices of such
  coordinates overflow.
* Faces of zero area (repeated or collinear vertices) and duplicated faces carry no geometry and
  upset the distance and collision queries: they are removed, and the removal is reported (a log
  warning, and the counts in ``mesh.metadata["weldplan"]["repairs"]``, which the cell summary and
  the route JSON carry).

Provenance
----------
:func:`load_part` records in ``mesh.metadata["weldplan"]`` the file, its sha256, the units and
the total scale factor applied; :func:`geometry_hash` is the hash of the loaded geometry in mm.
A route carries both, so that ``weldplan verify`` can refuse a route checked against another
mesh or another scale (:mod:`weldplan.weld.verify`).
"""

from __future__ import annotations

import hashlib
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
#: largest |coordinate| (mm) accepted after units and scale: 100 km. A car body is 5 m long, a
#: ship hull 300 m; beyond this the input is a unit mistake, and 5 mm grid indices of coordinates
#: near 1e300 overflow int64.
MAX_COORD_MM = 1e8
#: vertex coordinates are rounded to this many decimals (mm) before :func:`geometry_hash`, so
#: that last-bit differences of the scaling arithmetic between platforms do not change the hash
HASH_DECIMALS = 6


def unit_scale(units: str) -> float:
    """Millimetres per unit of ``units`` (one of :data:`UNITS_MM`)."""
    try:
        return UNITS_MM[units]
    except (KeyError, TypeError):
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
        The part in mm, with degenerate (zero-area) and duplicate faces and unreferenced
        vertices removed (and the removal logged as a warning and counted in
        ``metadata["weldplan"]["repairs"]``). Not necessarily watertight: sheet-metal parts
        rarely are. ``metadata["weldplan"]`` also holds ``file``, ``file_sha256``, ``units``
        and ``scale`` (the total factor from file units to mm).

    Raises
    ------
    InputError
        The file is missing, unreadable, has an unsupported suffix, holds no triangles, has a
        vertex with a NaN or infinite coordinate, a coordinate beyond :data:`MAX_COORD_MM` after
        scaling, or the scale options are invalid; the message names the file.
    """
    path = Path(path)
    factor = unit_scale(units)
    if scale is not None and length is not None:
        raise InputError("give scale or length, not both", path=path, field="scale")
    if scale is not None:
        scale = _positive(scale, "scale", "scale must be a positive number", path)
    if length is not None:
        length = _positive(length, "length", "length must be a positive number of mm", path)
    _check_mesh_path(path)
    raw = _as_single_mesh(_load(path, process=False), path)
    _check_finite(raw, path)
    factor *= 1.0 if scale is None else float(scale)
    raw_max = float(np.abs(raw.vertices).max(initial=0.0))
    if length is None:  # before trimesh's processing overflows on such coordinates
        _check_magnitude(raw_max * factor, path, units, scale, length)
    mesh, repairs = _load_clean(path)
    if length is not None:
        factor *= _length_factor(mesh, factor, length, path)
    _check_magnitude(raw_max * factor, path, units, scale, length)
    if factor != 1.0:
        mesh.apply_scale(factor)
    mesh.metadata["weldplan"] = {
        "file": str(path),
        "file_sha256": file_sha256(path),
        "units": units,
        "scale": float(factor),
        "repairs": repairs,
    }
    log.info(
        "loaded %s: %d vertices, %d faces, extents %s mm",
        path,
        len(mesh.vertices),
        len(mesh.faces),
        np.round(mesh.extents, 2),
    )
    return mesh


def _check_mesh_path(path: Path) -> None:
    """InputError unless ``path`` is an existing file with a suffix in :data:`MESH_SUFFIXES`."""
    if not path.exists():
        raise InputError("mesh file not found", path=path)
    if path.is_dir():
        raise InputError("expected a mesh file, got a directory", path=path)
    if path.suffix.lower() not in MESH_SUFFIXES:
        raise InputError(
            f"unsupported mesh format {path.suffix!r}; use one of {', '.join(MESH_SUFFIXES)}",
            path=path,
        )


def _load_clean(path: Path) -> tuple[trimesh.Trimesh, dict[str, int]]:
    """The file processed by trimesh and cleaned (:func:`clean_mesh_report`), in file units,
    with the removals logged as a warning; InputError when no triangle is left."""
    mesh = _as_single_mesh(_load(path, process=True), path)
    mesh, repairs = clean_mesh_report(mesh)
    if len(mesh.faces) == 0:
        raise InputError("mesh has no non-degenerate triangles", path=path)
    if repairs["degenerate_faces"] or repairs["duplicate_faces"]:
        log.warning(
            "%s: removed %d degenerate (zero-area) and %d duplicate faces",
            path,
            repairs["degenerate_faces"],
            repairs["duplicate_faces"],
        )
    return mesh, repairs


def _length_factor(mesh: trimesh.Trimesh, factor: float, length: float, path: Path) -> float:
    """The extra factor that makes the largest extent of ``mesh`` (file units, times ``factor``
    mm per unit) ``length`` mm; InputError when that extent is zero or not finite."""
    extent = float(np.max(mesh.extents)) * factor
    if not (np.isfinite(extent) and extent > 0):
        raise InputError(
            f"cannot scale to length {length:g} mm: the part's extent is {extent:g}",
            path=path,
            field="length",
        )
    return float(length) / extent


def _positive(value: object, field: str, message: str, path: Path) -> float:
    """``float(value)`` when it is a positive finite number, else InputError(message)."""
    try:
        v = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        v = float("nan")
    if not (np.isfinite(v) and v > 0):
        raise InputError(f"{message}, got {value!r}", path=path, field=field)
    return v


def _load(path: Path, *, process: bool) -> object:
    try:
        return trimesh.load(str(path), force="mesh", process=process)
    except Exception as exc:  # trimesh raises many kinds on bad files
        raise InputError(f"cannot read mesh: {exc}", path=path) from exc


def _check_finite(raw: trimesh.Trimesh, path: Path) -> None:
    """InputError when a vertex of the unprocessed mesh has a NaN or infinite coordinate."""
    bad = np.flatnonzero(~np.all(np.isfinite(np.asarray(raw.vertices, dtype=np.float64)), axis=1))
    if len(bad) == 0:
        return
    faces = np.asarray(raw.faces, dtype=np.int64).reshape(-1, 3)
    used = np.flatnonzero(np.isin(faces, bad).any(axis=1))
    first_face = f", used by {len(used)} faces (first: face {int(used[0])})" if len(used) else ""
    raise InputError(
        f"{len(bad)} of {len(raw.vertices)} vertices have a NaN or infinite coordinate "
        f"(first: vertex {int(bad[0])}, 0-based, {raw.vertices[bad[0]].tolist()}){first_face}; "
        "fix or re-export the mesh",
        path=path,
    )


def _check_magnitude(
    max_abs_mm: float, path: Path, units: str, scale: float | None, length: float | None
) -> None:
    if not max_abs_mm <= MAX_COORD_MM:
        raise InputError(
            f"coordinates reach {max_abs_mm:.3g} mm after units {units!r}"
            + (f" and scale {scale:g}" if scale is not None else "")
            + (f" and length {length:g}" if length is not None else "")
            + f", beyond the {MAX_COORD_MM:.0e} mm weldplan accepts: check --units/--scale",
            path=path,
        )


def file_sha256(path: str | PathLike[str]) -> str:
    """Hex sha256 of a file's bytes."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def geometry_hash(mesh: trimesh.Trimesh) -> str:
    """Hex sha256 of a mesh's geometry in mm: its vertices (rounded to :data:`HASH_DECIMALS`
    decimals, float64) and faces (int64), in order. Two loads of one file with the same units
    and scale give the same hash; another scale or another file gives another."""
    h = hashlib.sha256()
    v = np.round(np.asarray(mesh.vertices, dtype=np.float64), HASH_DECIMALS) + 0.0  # no -0.0
    h.update(np.ascontiguousarray(v).tobytes())
    h.update(np.ascontiguousarray(np.asarray(mesh.faces, dtype=np.int64)).tobytes())
    return h.hexdigest()


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
    """A copy of ``mesh`` without degenerate or duplicate faces, unreferenced or non-finite
    vertices (the counts: :func:`clean_mesh_report`)."""
    return clean_mesh_report(mesh)[0]


def clean_mesh_report(mesh: trimesh.Trimesh) -> tuple[trimesh.Trimesh, dict[str, int]]:
    """:func:`clean_mesh` and what it removed.

    A face is degenerate when its area is zero to round-off (repeated or collinear vertices) or
    when it uses a non-finite vertex; a face is a duplicate when an earlier face has the same
    three vertices (in any order).

    Returns
    -------
    mesh, repairs
        The cleaned copy and ``{"degenerate_faces": int, "duplicate_faces": int}``.
    """
    vertices = np.asarray(mesh.vertices, dtype=np.float64)
    faces = np.asarray(mesh.faces, dtype=np.int64).reshape(-1, 3)
    if len(faces) == 0:
        empty = trimesh.Trimesh(
            vertices=np.zeros((0, 3)), faces=np.zeros((0, 3), int), process=False
        )
        return empty, {"degenerate_faces": 0, "duplicate_faces": 0}
    tri = vertices[faces]
    finite = np.all(np.isfinite(tri), axis=(1, 2))
    cross = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    area2 = np.linalg.norm(cross, axis=1)
    edge2 = np.max(np.sum((tri - np.roll(tri, 1, axis=1)) ** 2, axis=2), axis=1)
    keep = finite & (area2 > _DEGENERATE_REL_AREA * np.maximum(edge2, np.finfo(float).tiny))
    keep &= (
        (faces[:, 0] != faces[:, 1]) & (faces[:, 1] != faces[:, 2]) & (faces[:, 0] != faces[:, 2])
    )
    degenerate = int((~keep).sum())
    first = np.zeros(len(faces), dtype=bool)
    kept = np.flatnonzero(keep)
    _, uniq = np.unique(np.sort(faces[kept], axis=1), axis=0, return_index=True)
    first[kept[uniq]] = True
    duplicate = int(keep.sum() - first.sum())
    out = trimesh.Trimesh(vertices=vertices, faces=faces[first], process=False)
    out.remove_unreferenced_vertices()
    return out, {"degenerate_faces": degenerate, "duplicate_faces": duplicate}
