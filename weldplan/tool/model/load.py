"""A tool as the command line names it (``--tool``, ``--tcp``, ``--tool-units``), with provenance.

:func:`load_tool` reads a URDF (``.urdf``) or any mesh with an explicit TCP, and returns the
:class:`~weldplan.tool.model.Tool` with a provenance dict that the route JSON carries: the files
and their sha256, the TCP as given, the units. ``weldplan verify --tool`` compares that dict to
the tool it is given and refuses a route planned with another tool.

The shared spot-welding gun's URDF names the mesh of its original CAD file, which is not beside
it; that one URDF is recognised by its sha256 (:data:`KNOWN_URDF_MESHES`) and read with the STL
that is beside it (``shared_spot_gun``). Any other URDF whose mesh reference does not resolve is
an error that asks for ``--tool-mesh``: no guess.
"""

from __future__ import annotations

import dataclasses
import logging
import math
from os import PathLike
from pathlib import Path
from typing import Any

from weldplan.errors import InputError
from weldplan.tool.model.tool import Tool, load_tool_urdf, tool_from_mesh

log = logging.getLogger(__name__)

#: URDF sha256 -> (mesh file beside it, its unit): URDFs whose own mesh reference is known not to
#: resolve, and the mesh in their root-link frame that replaces it (docs/tool.md)
KNOWN_URDF_MESHES = {
    # ../shared/data/tools/spot_welding_gun/spot_welding_gun.urdf (rlbotics, BSD-3)
    "286013d500a9eca3d41d2cd4a601bf44ca567633e80f8e6cbd0a3425e7fc51dc": (
        "spot_welding_gun.stl",
        "m",
    ),
}

#: the provenance keys that must agree for a route to be re-checked with a tool (``tip_cone``:
#: ``--tip-cone``, absent when not given)
PROVENANCE_KEYS = ("file_sha256", "mesh_sha256", "tcp", "units", "tip_cone")


def parse_tcp(text: str) -> list[float]:
    """``"x,y,z,rx,ry,rz"`` -> six finite floats, else :class:`InputError` (field ``--tcp``)."""
    parts = text.replace(";", ",").split(",")
    if len(parts) != 6:
        raise InputError(
            f"need six comma-separated numbers x,y,z,rx,ry,rz, got {len(parts)}: {text!r}",
            field="--tcp",
        )
    try:
        vals = [float(p) for p in parts]
    except ValueError:
        raise InputError(f"not six numbers: {text!r}", field="--tcp") from None
    if not all(math.isfinite(v) for v in vals):
        raise InputError(f"every number must be finite, got {text!r}", field="--tcp")
    return vals


def load_tool(
    path: str | PathLike[str],
    *,
    tcp: str | None = None,
    units: str | None = None,
    mesh: str | PathLike[str] | None = None,
) -> tuple[Tool, dict[str, Any]]:
    """Read the tool the CLI's ``--tool`` names.

    Parameters
    ----------
    path
        A URDF (``.urdf``: lengths in metres; its TCP is a fixed joint, see
        :func:`~weldplan.tool.model.load_tool_urdf`) or a mesh file (then ``tcp`` is required).
    tcp
        For a mesh: ``"x,y,z,rx,ry,rz"`` (position in ``units``, fixed-axis x-y-z rotations in
        degrees). For a URDF: the name of its TCP joint or link (default: the last fixed joint).
    units
        ``"m"`` or ``"mm"``: of the mesh file (default ``"mm"`` for a mesh, ``"m"`` for the mesh
        that replaces a URDF's own).
    mesh
        With a URDF: a mesh in its root-link frame used instead of the URDF's mesh reference.

    Returns
    -------
    tool, provenance
        The tool (mm, TCP frame) and ``{"file", "file_sha256", "mesh", "mesh_sha256", "tcp",
        "units", "name"}``.

    Raises
    ------
    InputError
        A missing or unreadable file, a mesh without ``tcp``, a URDF without a TCP, a TCP that is
        not six finite numbers, a mesh extent that does not fit ``units``, a TCP outside the tool.
    """
    from weldplan.io.mesh import file_sha256

    path = Path(path)
    if not path.is_file():
        raise InputError("no such tool file", path=path, field="--tool")
    sha = file_sha256(path)
    if path.suffix.lower() == ".urdf":
        mesh_units = units or "m"
        mesh_path = Path(mesh) if mesh is not None else None
        if mesh_path is None and sha in KNOWN_URDF_MESHES:
            name, mesh_units = KNOWN_URDF_MESHES[sha]
            mesh_path = path.parent / name
            log.info("%s: the known URDF of the shared gun; mesh %s (%s)", path, name, mesh_units)
        if mesh_path is not None and not mesh_path.is_file():
            raise InputError("no such tool mesh", path=mesh_path, field="--tool-mesh")
        try:
            tool = load_tool_urdf(path, tcp=tcp, mesh=mesh_path, mesh_units=mesh_units)
        except InputError as exc:
            if "pass the mesh explicitly" in exc.message:
                exc.message = exc.message.replace("pass the mesh explicitly", "pass --tool-mesh")
            raise
        prov_units = mesh_units if mesh_path is not None else "urdf"
        if sha in KNOWN_URDF_MESHES and mesh is None:  # the shared C-gun: welds from either side
            tool = dataclasses.replace(tool, straddles=True, _cache={})
    else:
        if mesh is not None:
            raise InputError("--tool-mesh goes with a URDF --tool", path=path, field="--tool-mesh")
        if tcp is None:
            raise InputError(
                "a mesh tool needs --tcp x,y,z,rx,ry,rz (TCP in the mesh frame)",
                path=path,
                field="--tcp",
            )
        vals = parse_tcp(tcp)
        tool = tool_from_mesh(path, vals, units=units or "mm")
        prov_units, mesh_path = units or "mm", None
        tcp = ",".join(f"{v:g}" for v in vals)
    prov = {
        "name": tool.name,
        "file": str(path),
        "file_sha256": sha,
        "mesh": None if mesh_path is None else str(mesh_path),
        "mesh_sha256": None if mesh_path is None else file_sha256(mesh_path),
        "tcp": tcp,
        "units": prov_units,
    }
    return tool, prov


def provenance_mismatch(planned: dict[str, Any], given: dict[str, Any]) -> list[str]:
    """The :data:`PROVENANCE_KEYS` on which two tool provenances differ, in words."""
    return [
        f"{k} {planned.get(k)!r} (route) != {given.get(k)!r} (given)"
        for k in PROVENANCE_KEYS
        if planned.get(k) != given.get(k)
    ]
