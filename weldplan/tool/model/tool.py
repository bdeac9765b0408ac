"""The tool a robot carries: a triangle mesh in its TCP frame (mm), loaded from a URDF or a mesh.

Frames. Every :class:`Tool` holds its mesh in the frame of its tool centre point (TCP), in mm:
the TCP at the origin and the TCP's +z axis pointing *into* the part (the approach direction, the
way a robot's tool frame is set up: for the shared spot-welding gun the URDF's ``nozzle_tip``
joint, whose +z points from the moving electrode towards the fixed one). A pose of the tool is
the TCP frame in the part frame: a rotation ``R (3, 3)`` whose columns are the TCP axes and a
position ``p (3,)`` mm; a tool vertex ``v`` lands at ``R @ v + p``.

Loaders check what can be checked and raise a one-line :class:`~weldplan.errors.InputError`
naming the file and field: a URDF without the TCP joint or link, a mesh whose extent does not fit
the declared unit (:data:`MIN_EXTENT_MM` to :data:`MAX_EXTENT_MM`), a TCP outside the tool's
bounding box (more than :data:`TCP_BOX_MARGIN_MM` beyond it).
"""

from __future__ import annotations

import logging
import math
import xml.etree.ElementTree as ET
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from os import PathLike
from pathlib import Path
from typing import Any

import fcl
import numpy as np
import trimesh
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from weldplan.errors import InputError

log = logging.getLogger(__name__)

#: millimetres per unit accepted by the loaders
UNITS: dict[str, float] = {"mm": 1.0, "cm": 10.0, "m": 1000.0, "in": 25.4}
#: a tool mesh's largest extent (mm, after unit conversion) must lie in this range: a welding gun
#: or torch is centimetres to a couple of metres long; outside it the declared unit is wrong
MIN_EXTENT_MM = 20.0
MAX_EXTENT_MM = 3000.0
#: the TCP may lie at most this far (mm) outside the tool mesh's axis-aligned bounding box (an
#: electrode tip or wire stick-out beyond the mesh: arc_torch()'s default stick-out is 15 mm,
#: MIG/MAG stick-outs run to about 25 mm; a TCP a tool length away is still refused)
TCP_BOX_MARGIN_MM = 25.0
#: triangles crossing the contact-zone sphere are subdivided until their longest edge is below
#: this (mm), so at most this much of the tool inside the sphere is still checked (conservative)
ZONE_EDGE_MM = 1.0
#: half-angle (deg) of an arc torch's tip cone: only the tool inside this cone about its own axis
#: (apex at the TCP, opening back along -z) and inside the contact sphere may touch the part
TORCH_TIP_CONE = 15.0


@dataclass(frozen=True, eq=False)
class Tool:
    """A rigid tool: triangle mesh in its TCP frame (mm), TCP +z into the part.

    Parameters
    ----------
    name
        A label for reports.
    vertices
        ``(n, 3) float`` mm, in the TCP frame.
    faces
        ``(m, 3) int`` triangles.
    source
        The file(s) it was read from, or a description of the parametric model.
    tip_cone
        Degrees, or ``None``. The tool's contact zone is the sphere of the contact radius about
        the TCP (the weld spot); with ``tip_cone`` it is only the part of that sphere within
        ``tip_cone`` degrees of the tool's axis behind the TCP (-z): an arc torch's wire and
        contact tip, so that its nozzle may never pass through a sheet near the spot. ``None``
        (a spot-welding C-gun, whose electrodes and arms close over the sheet): the whole sphere.
    straddles
        The tool clamps the sheet from both sides (a C-gun): the pose search also tries the
        tool turned over, approaching from the other side of the sheet.
    """

    name: str
    vertices: NDArray[np.float64]
    faces: NDArray[np.int64]
    source: str = ""
    tip_cone: float | None = None
    straddles: bool = False
    _cache: dict[Any, Any] = field(default_factory=dict, repr=False, compare=False)

    def __post_init__(self) -> None:
        v = np.array(self.vertices, dtype=np.float64).reshape(-1, 3)
        f = np.array(self.faces, dtype=np.int64).reshape(-1, 3)
        if len(f) == 0:
            raise ValueError("a tool needs at least one triangle")
        if f.min() < 0 or f.max() >= len(v):
            raise ValueError("tool faces index missing vertices")
        if self.tip_cone is not None and not 0 < self.tip_cone <= 90:
            raise ValueError(f"tip_cone must be in (0, 90] degrees, got {self.tip_cone}")
        v.setflags(write=False)
        f.setflags(write=False)
        object.__setattr__(self, "vertices", v)
        object.__setattr__(self, "faces", f)

    @property
    def mesh(self) -> trimesh.Trimesh:
        """The tool as a trimesh (mm, TCP frame), built once."""
        if "mesh" not in self._cache:
            self._cache["mesh"] = trimesh.Trimesh(self.vertices, self.faces, process=False)
        return self._cache["mesh"]

    @property
    def reach(self) -> float:
        """mm: the largest distance of a tool vertex from the TCP (a sphere about the TCP holds
        the whole tool)."""
        return float(np.linalg.norm(self.vertices, axis=1).max())

    @property
    def extent(self) -> NDArray[np.float64]:
        """``(3,) float`` mm: the bounding-box size in the TCP frame."""
        return np.ptp(self.vertices, axis=0)

    def in_zone(self, points: ArrayLike, radius: float) -> NDArray[np.bool_]:
        """``(...) bool``: whether points ``(..., 3)`` mm of the TCP frame lie in the contact
        zone: the sphere of ``radius`` about the TCP, cut to :attr:`tip_cone` when set."""
        P = np.asarray(points, dtype=np.float64)
        r = np.linalg.norm(P, axis=-1)
        inside = r < radius
        if self.tip_cone is not None:
            inside &= -P[..., 2] >= r * math.cos(math.radians(self.tip_cone))
        return inside

    def outside_zone(self, radius: float) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
        """The tool minus its part inside the contact zone (:meth:`in_zone`, radius in mm).

        :func:`outside_sphere` with the zone (the sphere, or a sphere cut to a cone of at most
        90 deg: convex, so a triangle whose corners are inside is inside): triangles reaching
        into the sphere are subdivided (midpoint subdivision, trimesh) until their longest edge
        is below :data:`ZONE_EDGE_MM`, then those wholly inside are dropped. What remains
        covers every point of the tool outside the zone, and reaches at most ``ZONE_EDGE_MM``
        into it: a check of this mesh against the whole part is the check of
        the whole tool against the part, except contact inside the zone (conservative by at most
        ``ZONE_EDGE_MM``).

        Returns
        -------
        vertices, faces
            ``(k, 3) float`` mm (TCP frame) and ``(j, 3) int``; a fresh computation (not cached).
        """
        cone = None if self.tip_cone is None else (lambda v: self.in_zone(v, radius))
        return outside_sphere(self.vertices, self.faces, np.zeros(3), radius, cone)

    def fcl_model(self, radius: float) -> tuple[fcl.BVHModel, NDArray[np.float64]]:
        """A python-fcl BVH of :meth:`outside_zone` (cached per radius and zone) and its
        ``(j, 3, 3)`` triangles (mm, TCP frame), to name the tool region an FCL answer points to."""
        key = ("fcl", float(radius), self.tip_cone)
        if key not in self._cache:
            v, f = self.outside_zone(radius)
            self._cache[key] = (bvh(v, f), v[f])
        return self._cache[key]

    def region(self, point: ArrayLike) -> str:
        """Words for where on the tool a point ``(3,)`` mm of its TCP frame lies."""
        x, y, z = (float(c) for c in np.asarray(point, dtype=np.float64).reshape(3))
        side = "behind" if z < 0 else "ahead of"
        return (
            f"{self.name}: {abs(z):.0f} mm {side} the TCP along the tool axis, "
            f"{math.hypot(x, y):.0f} mm off it (TCP frame x {x:.0f}, y {y:.0f}, z {z:.0f} mm)"
        )

    def transformed(self, rotation: ArrayLike, position: ArrayLike) -> trimesh.Trimesh:
        """The tool mesh placed at a pose: TCP rotation ``(3, 3)`` and position ``(3,)`` mm."""
        R = np.asarray(rotation, dtype=np.float64).reshape(3, 3)
        p = np.asarray(position, dtype=np.float64).reshape(3)
        return trimesh.Trimesh(self.vertices @ R.T + p, self.faces, process=False)


def bvh(vertices: ArrayLike, faces: ArrayLike) -> fcl.BVHModel:
    """A python-fcl BVH of a triangle soup ``(n, 3)`` mm, ``(m, 3)`` int.

    Only the vertices the faces use go to FCL, exact duplicates merged (the same triangles, so
    the same distances and contacts, with the faces' order and so FCL's triangle indices kept):
    python-fcl copies vertices one at a time in Python (about 3 us each), and a crop of a
    part or a tool read as a triangle soup (the shared gun: 70k vertices for 23k triangles)
    would otherwise pay for every vertex of the whole mesh.
    """
    v = np.asarray(vertices, dtype=np.float64).reshape(-1, 3)
    f = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    used, inv = np.unique(f, return_inverse=True)
    rows = np.ascontiguousarray(v[used])  # duplicates by their bytes (a void view: 4x as fast)
    _, first, merge = np.unique(
        rows.view(np.dtype((np.void, 24))).ravel(), return_index=True, return_inverse=True
    )
    uv = np.ascontiguousarray(rows[first])
    f = np.ascontiguousarray(merge.reshape(-1)[inv.reshape(-1)].reshape(-1, 3), dtype=np.int64)
    model = fcl.BVHModel()
    model.beginModel(len(f), len(uv))
    model.addSubModel(uv, f)
    model.endModel()
    return model


def _reaching(tri: NDArray[np.float64], c: NDArray[np.float64], radius: float) -> NDArray[np.bool_]:
    """``(m,) bool``: triangles ``(m, 3, 3)`` whose closest point to ``c`` lies within ``radius``
    (a large triangle can cover the sphere with all its vertices outside)."""
    edge = np.linalg.norm(tri - np.roll(tri, 1, axis=1), axis=2).max(axis=1)
    vmin = np.linalg.norm(tri - c, axis=2).min(axis=1)
    out = np.zeros(len(tri), dtype=bool)
    cand = np.flatnonzero(vmin < radius + edge)  # every point of a triangle is within its
    if len(cand):  # longest edge of a vertex: a cheap superset first
        cp = trimesh.triangles.closest_point(tri[cand], np.repeat(c[None], len(cand), axis=0))
        out[cand] = np.linalg.norm(cp - c, axis=1) < radius
    return out


def outside_sphere(
    vertices: ArrayLike,
    faces: ArrayLike,
    centre: ArrayLike,
    radius: float,
    in_zone: Callable[[NDArray[np.float64]], NDArray[np.bool_]] | None = None,
    *,
    bisect: bool = False,
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """A mesh minus its parts inside a zone: the sphere of ``radius`` mm about ``centre (3,)``,
    or the convex part of it that ``in_zone ((k, 3) mm) -> (k,) bool`` says (a tool's tip cone).

    The triangles that reach into the sphere (:func:`_reaching`: by their closest point, so a
    large triangle covering the sphere with all its corners outside counts) are subdivided
    (trimesh midpoint subdivision) until those still reaching in have their longest edge below
    :data:`ZONE_EDGE_MM`; then the triangles wholly inside the zone (all corners in it: the zone
    is convex) are dropped. The result covers every point of the mesh outside the zone and
    reaches at most ``ZONE_EDGE_MM`` into it (conservative). Only the reaching triangles are
    subdivided. One function for the tool's zone (:meth:`Tool.outside_zone`) and the part's
    zone about a weld spot (:mod:`weldplan.tool.transitions.sweep`).

    ``bisect``: split a reaching triangle at the midpoint of its longest edge instead
    (:func:`_outside_bisected`; the same guarantee). Midpoint subdivision keeps a sliver's shape,
    so car2's flange triangles (180 mm by a few mm) leave about 25,000 slivers 1 mm long in the
    band round a 20 mm sphere (0.3 s to cut and 0.35 s to build a BVH of, per weld spot);
    bisection turns slivers into well-shaped triangles and leaves far fewer.

    Returns
    -------
    vertices, faces
        ``(k, 3) float`` mm and ``(j, 3) int``.
    """
    v = np.asarray(vertices, dtype=np.float64)
    f = np.asarray(faces, dtype=np.int64)
    c = np.asarray(centre, dtype=np.float64).reshape(3)
    if radius <= 0 or len(f) == 0:
        return v.copy(), f.copy()

    def inside(tri: NDArray[np.float64]) -> NDArray[np.bool_]:
        if in_zone is None:
            return np.linalg.norm(tri - c, axis=2).max(axis=1) < radius
        return in_zone(tri.reshape(-1, 3) - c).reshape(-1, 3).all(axis=1)

    near = _reaching(v[f], c, radius)
    keep_f = f[~near]
    if bisect:
        return _compact(*_outside_bisected(v, keep_f, f[near], c, radius, inside))
    nv, nf = v, f[near]
    for _ in range(64):
        tri = nv[nf]
        whole = inside(tri)
        reach = _reaching(tri, c, radius) & ~whole
        edges = np.linalg.norm(tri - np.roll(tri, 1, axis=1), axis=2).max(axis=1)
        coarse = np.flatnonzero(reach & (edges > ZONE_EDGE_MM))
        if len(coarse) == 0:
            nf = nf[~whole]
            break
        nv, nf = trimesh.remesh.subdivide(nv, nf, face_index=coarse)
    # nv extends v (subdivision appends vertices), so the far faces keep their indices
    return _compact(nv, np.concatenate([keep_f, nf]))


def _compact(
    v: NDArray[np.float64], f: NDArray[np.int64]
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """The vertices ``f`` uses, and ``f`` re-indexed to them."""
    used = np.unique(f)
    remap = np.full(len(v), -1, dtype=np.int64)
    remap[used] = np.arange(len(used))
    return v[used], remap[f]


def _outside_bisected(
    v: NDArray[np.float64],
    keep: NDArray[np.int64],
    active: NDArray[np.int64],
    c: NDArray[np.float64],
    radius: float,
    inside: Callable[[NDArray[np.float64]], NDArray[np.bool_]],
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """:func:`outside_sphere`'s subdivision by longest-edge bisection: each reaching triangle
    ``(a, b, c)`` with longest edge ``ab`` becomes ``(a, m, c)`` and ``(m, b, c)``, ``m`` the
    edge's midpoint (appended to the vertices; the two halves cover the triangle exactly, with
    its winding). A triangle is final once it is wholly inside (dropped) or does not reach in
    or is finer than :data:`ZONE_EDGE_MM` (kept), so each level looks only at the new halves.
    Returns the vertices (``v`` extended) and the kept faces (``keep`` first)."""
    out = [keep]
    for _ in range(256):  # each level halves the area: ample for any mesh in mm
        if len(active) == 0:
            break
        tri = v[active]
        whole = inside(tri)
        edges = np.linalg.norm(tri - np.roll(tri, -1, axis=1), axis=2)  # edge k: k -> k + 1
        coarse = ~whole & (edges.max(axis=1) > ZONE_EDGE_MM)
        coarse[coarse] = _reaching(tri[coarse], c, radius)
        out.append(active[~whole & ~coarse])
        split, k = active[coarse], edges[coarse].argmax(axis=1)
        r = np.arange(len(split))
        a, b, o = split[r, k], split[r, (k + 1) % 3], split[r, (k + 2) % 3]
        m = len(v) + r
        v = np.concatenate([v, (v[a] + v[b]) / 2])
        active = np.concatenate([np.stack([a, m, o], axis=1), np.stack([m, b, o], axis=1)])
    if len(active):  # not reached for a mesh in mm; keeping them is conservative
        out.append(active[~inside(v[active])])
    return v, np.concatenate(out)


# --------------------------------------------------------------------------------------------
# loaders


def _unit_scale(units: str, path: str | PathLike[str] | None, fld: str) -> float:
    try:
        return UNITS[units]
    except KeyError:
        raise InputError(
            f"unknown unit {units!r} (use one of {', '.join(UNITS)})", path=path, field=fld
        ) from None


def _load_mesh_file(path: Path, where: str | PathLike[str], fld: str) -> trimesh.Trimesh:
    if not path.is_file():
        raise InputError(f"tool mesh not found: {path}", path=where, field=fld)
    try:
        mesh = trimesh.load(path, force="mesh", process=False)
    except Exception as exc:  # trimesh raises many types for unreadable files
        raise InputError(f"cannot read the tool mesh: {exc}", path=path) from None
    if not isinstance(mesh, trimesh.Trimesh) or len(mesh.faces) == 0:
        raise InputError("the tool mesh has no triangles", path=path)
    return mesh


def _check_extent(vertices_mm: NDArray, mesh_path: Path, units: str) -> None:
    ext = float(np.ptp(vertices_mm, axis=0).max())
    if not (MIN_EXTENT_MM <= ext <= MAX_EXTENT_MM):
        raise InputError(
            f"tool mesh is {ext:.4g} mm long when read in {units!r}, outside the "
            f"{MIN_EXTENT_MM:g}-{MAX_EXTENT_MM:g} mm of a tool: wrong unit?",
            path=mesh_path,
            field="units",
        )


def _check_tcp_inside(vertices_mm: NDArray, tcp_mm: NDArray, where: Any, fld: str) -> None:
    lo = vertices_mm.min(axis=0) - TCP_BOX_MARGIN_MM
    hi = vertices_mm.max(axis=0) + TCP_BOX_MARGIN_MM
    if np.any(tcp_mm < lo) or np.any(tcp_mm > hi):
        raise InputError(
            f"TCP at {np.round(tcp_mm, 2).tolist()} mm lies outside the tool's bounding box "
            f"{np.round(lo + TCP_BOX_MARGIN_MM, 1).tolist()} to "
            f"{np.round(hi - TCP_BOX_MARGIN_MM, 1).tolist()} mm",
            path=where,
            field=fld,
        )


def _frame(xyz: ArrayLike, rpy: ArrayLike, scale: float) -> NDArray[np.float64]:
    """4x4 transform from xyz (times ``scale``) and fixed-axis roll-pitch-yaw (rad, URDF)."""
    T = np.eye(4)
    T[:3, :3] = Rotation.from_euler("xyz", np.asarray(rpy, dtype=np.float64)).as_matrix()
    T[:3, 3] = np.asarray(xyz, dtype=np.float64) * scale
    return T


def _floats(text: str | None, n: int, where: Any, fld: str) -> NDArray[np.float64]:
    if text is None:
        return np.zeros(n)
    try:
        vals = np.array([float(t) for t in text.split()])
    except ValueError:
        raise InputError(f"not {n} numbers: {text!r}", path=where, field=fld) from None
    if vals.shape != (n,) or not np.all(np.isfinite(vals)):
        raise InputError(f"need {n} finite numbers, got {text!r}", path=where, field=fld)
    return vals


def _make_tool(
    name: str,
    vertices_mm: NDArray,
    faces: NDArray,
    T_mesh_tcp: NDArray,
    source: str,
) -> Tool:
    """Express mesh vertices (mm, mesh frame) in the TCP frame given by ``T_mesh_tcp`` (4x4, mm)."""
    R = T_mesh_tcp[:3, :3]
    t = T_mesh_tcp[:3, 3]
    return Tool(name=name, vertices=(vertices_mm - t) @ R, faces=faces, source=source)


def load_tool_urdf(
    path: str | PathLike[str],
    *,
    tcp: str | None = None,
    mesh: str | PathLike[str] | None = None,
    mesh_units: str = "m",
) -> Tool:
    """Read a tool from a URDF: its mesh and the TCP frame of a fixed joint.

    Parameters
    ----------
    path
        The URDF (lengths in metres, angles in radians, as the URDF format fixes them).
    tcp
        Name of the TCP joint or of its child link; default: the child of the last fixed joint in
        the file (``nozzle_tip`` for the shared spot-welding gun).
    mesh
        A mesh file in the URDF's root-link frame to use instead of the URDF's own mesh reference
        (whose ``origin`` and ``scale`` are then ignored). The shared gun needs this: its URDF
        names the original CAD file, and the STL beside it is already in the root frame.
    mesh_units
        Unit of the mesh file given by ``mesh`` (default ``"m"``).

    Returns
    -------
    Tool
        The mesh in the TCP frame, mm.

    Raises
    ------
    InputError
        Unreadable XML, no fixed joint or no joint/link named ``tcp``, a mesh that cannot be
        found or read, a mesh extent that does not fit ``mesh_units``, a TCP outside the mesh's
        bounding box.
    """
    path = Path(path)
    try:
        root = ET.parse(path).getroot()
    except (OSError, ET.ParseError) as exc:
        raise InputError(f"cannot read the URDF: {exc}", path=path) from None
    joints = []
    for j in root.findall("joint"):
        org = j.find("origin")
        parent, child = j.find("parent"), j.find("child")
        if parent is None or child is None:
            raise InputError("joint without parent or child", path=path, field=j.get("name"))
        name = j.get("name", "")
        xyz = _floats(None if org is None else org.get("xyz"), 3, path, f"joint '{name}' xyz")
        rpy = _floats(None if org is None else org.get("rpy"), 3, path, f"joint '{name}' rpy")
        joints.append((name, j.get("type"), parent.get("link"), child.get("link"), xyz, rpy))
    fixed = [j for j in joints if j[1] == "fixed"]
    if tcp is None:
        if not fixed:
            raise InputError("no fixed joint to take the TCP from", path=path, field="joint")
        tcp_joint = fixed[-1]
    else:
        found = [j for j in joints if tcp in (j[0], j[3])]
        if not found:
            raise InputError(f"no TCP joint or link named {tcp!r}", path=path, field="tcp")
        tcp_joint = found[0]
    by_child = {j[3]: j for j in joints}
    # the chain from the root link (a link no joint has as child) down to the TCP link
    T = np.eye(4)
    link = tcp_joint[3]
    seen = set()
    while link in by_child:
        if link in seen:
            raise InputError("the joints form a loop", path=path, field=f"link '{link}'")
        seen.add(link)
        _, _, parent, _, xyz, rpy = by_child[link]
        T = _frame(xyz, rpy, 1000.0) @ T
        link = parent
    root_link = link
    if mesh is not None:
        mesh_path = Path(mesh)
        scale = _unit_scale(mesh_units, mesh_path, "units")
        tm = _load_mesh_file(mesh_path, path, "mesh")
        V = np.asarray(tm.vertices, dtype=np.float64) * scale
        _check_extent(V, mesh_path, mesh_units)
    else:
        mesh_path, V, tm = _urdf_mesh(root, root_link, path)
    fld = f"joint '{tcp_joint[0]}' origin"
    _check_tcp_inside(V, T[:3, 3], path, fld)
    return _make_tool(
        name=f"{root.get('name', path.stem)} ({tcp_joint[3]})",
        vertices_mm=V,
        faces=np.asarray(tm.faces),
        T_mesh_tcp=T,
        source=f"{path} + {mesh_path}",
    )


def _urdf_mesh(root: ET.Element, link: str, path: Path) -> tuple[Path, NDArray, trimesh.Trimesh]:
    """The root link's collision (else visual) mesh, with its origin and scale, in mm."""
    el = root.find(f"link[@name='{link}']")
    geom = None
    for kind in ("collision", "visual"):
        node = None if el is None else el.find(kind)
        if node is not None and node.find("geometry/mesh") is not None:
            geom = node
            break
    fld = f"link '{link}' mesh filename"
    if geom is None:
        raise InputError(
            "the root link has no mesh; pass the mesh explicitly", path=path, field=fld
        )
    m = geom.find("geometry/mesh")
    assert m is not None
    fname = (m.get("filename") or "").replace("package://", "").replace("file://", "")
    mesh_path = (path.parent / fname).resolve()
    if not mesh_path.is_file():
        raise InputError(
            f"mesh {fname!r} not found beside the URDF; pass the mesh explicitly",
            path=path,
            field=fld,
        )
    tm = _load_mesh_file(mesh_path, path, fld)
    s = _floats(m.get("scale", "1 1 1"), 3, path, f"link '{link}' mesh scale")
    org = geom.find("origin")
    T = _frame(
        _floats(None if org is None else org.get("xyz"), 3, path, f"link '{link}' origin xyz"),
        _floats(None if org is None else org.get("rpy"), 3, path, f"link '{link}' origin rpy"),
        1000.0,
    )
    V = (np.asarray(tm.vertices, dtype=np.float64) * s * 1000.0) @ T[:3, :3].T + T[:3, 3]
    _check_extent(V, mesh_path, "m")
    return mesh_path, V, tm


def tool_from_mesh(
    path: str | PathLike[str],
    tcp: Sequence[float] | str,
    *,
    units: str = "mm",
    name: str | None = None,
) -> Tool:
    """A tool from a mesh file and an explicit TCP.

    Parameters
    ----------
    path
        The mesh (any format trimesh reads).
    tcp
        ``x, y, z, rx, ry, rz`` (a sequence or a comma-separated string): the TCP position in the
        mesh's frame and ``units``, and its orientation as fixed-axis rotations about x, then y,
        then z, in degrees (the URDF ``rpy`` convention, in degrees).
    units
        Unit of the mesh and of the TCP position (default ``"mm"``).
    """
    path = Path(path)
    if isinstance(tcp, str):
        try:
            vals = [float(t) for t in tcp.replace(";", ",").split(",")]
        except ValueError:
            raise InputError(f"not six numbers: {tcp!r}", path=path, field="tcp") from None
    else:
        vals = [float(t) for t in tcp]
    if len(vals) != 6 or not all(math.isfinite(v) for v in vals):
        raise InputError(
            f"need six finite numbers x,y,z,rx,ry,rz, got {tcp!r}", path=path, field="tcp"
        )
    scale = _unit_scale(units, path, "units")
    tm = _load_mesh_file(path, path, "mesh")
    V = np.asarray(tm.vertices, dtype=np.float64) * scale
    _check_extent(V, path, units)
    T = _frame(np.array(vals[:3]), np.radians(vals[3:]), scale)
    _check_tcp_inside(V, T[:3, 3], path, "tcp")
    return _make_tool(name or path.stem, V, np.asarray(tm.faces), T, f"{path} + tcp {vals}")
