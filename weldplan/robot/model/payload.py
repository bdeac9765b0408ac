"""The tool's load on the flange: mass and centre of gravity from its URDF ``<inertial>`` tags.

A controller needs the tool's mass and centre of gravity (ABB ``tooldata.tload``, KUKA
``$LOAD``). A URDF carries them per link as ``<inertial><origin xyz=../><mass value=../>``;
:func:`urdf_payload` sums every link of the tool (all joints fixed) into one mass and one centre
of gravity in the tool's root frame. A URDF without any ``<mass>`` gives ``None``: the caller then
needs ``--tool-mass`` (no silent default). Deviation named: inertia tensors are not carried over
(ABB's ``ix, iy, iz`` are written as 0, which the controller treats as a point mass).
"""

from __future__ import annotations

import logging
import math
import xml.etree.ElementTree as ET
from os import PathLike
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from weldplan.errors import InputError
from weldplan.robot.model.urdf import chain_transform

log = logging.getLogger(__name__)

#: mm per URDF length unit
URDF_MM = 1000.0


def urdf_payload(path: str | PathLike[str]) -> tuple[float, NDArray[np.float64]] | None:
    """``(mass kg, centre of gravity (3,) mm in the root link's frame)``, or ``None`` when no
    link has a ``<mass>``.

    Raises
    ------
    InputError
        A mass or origin that is not a finite number (a negative or zero total mass too), naming
        the file and link.
    """
    path = Path(path)
    try:
        root = ET.parse(path).getroot()
    except (OSError, ET.ParseError) as exc:
        raise InputError(f"cannot read the tool URDF ({exc})", path=path, field="--tool") from None
    children = {c.get("link", "") for j in root.iter("joint") for c in j.iter("child")}
    total, moment = 0.0, np.zeros(3)
    found = False
    for link in root.iter("link"):
        name = link.get("name", "")
        inert = link.find("inertial")
        mass_el = None if inert is None else inert.find("mass")
        if mass_el is None:
            continue
        try:
            m = float(mass_el.get("value", "nan"))
            org = inert.find("origin") if inert is not None else None
            xyz = np.array(
                [
                    float(v)
                    for v in (org.get("xyz", "0 0 0") if org is not None else "0 0 0").split()
                ]
            )
        except ValueError:
            m, xyz = math.nan, np.zeros(0)
        if not (math.isfinite(m) and m >= 0) or xyz.shape != (3,) or not np.all(np.isfinite(xyz)):
            raise InputError(
                f"link {name!r}: inertial mass/origin is not a finite number",
                path=path,
                field="inertial",
            )
        T = chain_transform(path, name) if name in children else np.eye(4)
        c = T[:3, :3] @ (xyz * URDF_MM) + T[:3, 3]
        total += m
        moment += m * c
        found = True
    if not found:
        return None
    if not total > 0:
        raise InputError("the tool's total mass is 0 kg", path=path, field="inertial")
    return total, moment / total
