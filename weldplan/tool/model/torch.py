"""Built-in tools: a parametric straight or bent arc-welding torch, and the shared spot gun.

The torch is three cylinders in its TCP frame (mm, TCP +z into the part): the nozzle from the
contact tip back along -z, the neck, bent by ``bend_angle`` about the TCP's y axis, and the body
(the part a robot's flange holds), with spheres closing the joints between them. It is a stand-in
with the dimensions a user gives, not a vendor's CAD.
"""

from __future__ import annotations

import dataclasses
import logging
from pathlib import Path

import numpy as np
import trimesh

from weldplan.tool.model.tool import TORCH_TIP_CONE, Tool, load_tool_urdf

log = logging.getLogger(__name__)

#: the shared spot-welding gun (../shared/data relative to the repository root), see docs/tool.md
SHARED_GUN_DIR = (
    Path(__file__).resolve().parents[3].parent / "shared" / "data" / "tools" / "spot_welding_gun"
)
#: the cylinder facets of the parametric torch
_SECTIONS = 24


def arc_torch(
    *,
    neck_length: float = 150.0,
    diameter: float = 25.0,
    bend_angle: float = 22.0,
    stickout: float = 15.0,
    nozzle_length: float = 60.0,
    body_length: float = 200.0,
    body_diameter: float = 45.0,
) -> Tool:
    """A straight (``bend_angle=0``) or bent arc-welding torch, mm and degrees.

    Parameters
    ----------
    neck_length
        Length of the neck between nozzle and body (mm).
    diameter
        Nozzle and neck diameter (mm).
    bend_angle
        Bend of the neck away from the nozzle axis, about the TCP's y axis (degrees; 0 straight).
    stickout
        Wire stick-out: the TCP lies this far beyond the nozzle's mouth, along +z (mm).
    nozzle_length, body_length, body_diameter
        The nozzle's length and the body's length and diameter (mm).
    """
    for label, val in (
        ("neck_length", neck_length),
        ("diameter", diameter),
        ("nozzle_length", nozzle_length),
        ("body_length", body_length),
        ("body_diameter", body_diameter),
    ):
        if not val > 0:
            raise ValueError(f"{label} must be positive, got {val}")
    if stickout < 0 or not -90 < bend_angle < 90:
        raise ValueError("stickout must be >= 0 and bend_angle within (-90, 90) degrees")
    b = np.radians(bend_angle)
    back = np.array([0.0, 0.0, -1.0])
    bent = np.array([-np.sin(b), 0.0, -np.cos(b)])
    p0 = back * stickout
    p1 = p0 + back * nozzle_length
    p2 = p1 + bent * neck_length
    p3 = p2 + bent * body_length
    r = diameter / 2
    parts = [
        trimesh.creation.cylinder(r, segment=[p0, p1], sections=_SECTIONS),
        trimesh.creation.cylinder(r, segment=[p1, p2], sections=_SECTIONS),
        trimesh.creation.cylinder(body_diameter / 2, segment=[p2, p3], sections=_SECTIONS),
        trimesh.creation.icosphere(2, radius=r).apply_translation(p1),
    ]
    mesh = trimesh.util.concatenate(parts)
    kind = "straight" if bend_angle == 0 else f"bent {bend_angle:g} deg"
    return Tool(
        name=f"arc torch ({kind})",
        vertices=mesh.vertices,
        faces=mesh.faces,
        tip_cone=TORCH_TIP_CONE,
        source=(
            f"arc_torch(neck_length={neck_length}, diameter={diameter}, bend_angle={bend_angle}, "
            f"stickout={stickout}, nozzle_length={nozzle_length}, body_length={body_length}, "
            f"body_diameter={body_diameter})"
        ),
    )


def shared_spot_gun(directory: str | Path | None = None) -> Tool:
    """The shared spot-welding gun (``../shared/data/tools/spot_welding_gun``), TCP ``nozzle_tip``.

    Its STL is in metres and already in the URDF's root frame; the URDF's own mesh reference
    (origin and scale of the original CAD file) does not apply to it, so the STL is passed
    explicitly. TCP: xyz (0.67936, 0, 0.00043) m, rpy (0, pi/2, 0) from the root. It is a C-gun
    (``straddles``): it clamps the sheet, so it may weld from either side of it.
    """
    d = Path(directory) if directory is not None else SHARED_GUN_DIR
    gun = load_tool_urdf(
        d / "spot_welding_gun.urdf",
        tcp="nozzle_tip",
        mesh=d / "spot_welding_gun.stl",
        mesh_units="m",
    )
    return dataclasses.replace(gun, straddles=True, _cache={})
