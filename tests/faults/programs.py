"""Read back the moves of the RAPID and KRL programs weldplan writes (for the blend checks).

Zone radii come from ABB's predefined zonedata table as the RAPID manual prints it (``pzone_tcp``
in mm), typed here again rather than imported, so a wrong table in weldplan cannot agree with
itself.
"""

from __future__ import annotations

import re

import numpy as np

#: RAPID manual, zonedata: name -> pzone_tcp (mm); fine is an exact stop
ABB_ZONES = {
    "fine": 0.0,
    "z0": 0.3,
    "z1": 1.0,
    "z5": 5.0,
    "z10": 10.0,
    "z15": 15.0,
    "z20": 20.0,
    "z30": 30.0,
    "z40": 40.0,
    "z50": 50.0,
    "z60": 60.0,
    "z80": 80.0,
    "z100": 100.0,
    "z150": 150.0,
    "z200": 200.0,
}


def rapid_moves(text: str) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """``(n, 3)`` programmed points (mm), ``(n,)`` zone radii (mm), zone names, in move order."""
    targets = {
        name: [float(v) for v in xyz.split(",")]
        for name, xyz in re.findall(r"CONST robtarget (\w+):=\[\[([^\]]*)\]", text)
    }
    moves = re.findall(r"^\s+Move[JL] (\w+),\w+,(\w+),", text, re.M)
    pts = np.array([targets[name] for name, _ in moves], dtype=float)
    zones = [z for _, z in moves]
    return pts, np.array([ABB_ZONES[z] for z in zones]), zones


def krl_moves(text: str) -> tuple[np.ndarray, np.ndarray]:
    """``(n, 3)`` programmed points (mm) and ``(n,)`` approximation distances (0: exact stop)."""
    cdis = 0.0
    pts, radii = [], []
    for line in text.splitlines():
        m = re.match(r"\s+\$APO\.CDIS = ([-\d.eE+]+)", line)
        if m:
            cdis = float(m.group(1))
            continue
        m = re.match(r"\s+(?:PTP|LIN) \{X ([-\d.]+), Y ([-\d.]+), Z ([-\d.]+)", line)
        if m:
            pts.append([float(v) for v in m.groups()])
            radii.append(cdis if line.rstrip().endswith("C_DIS") else 0.0)
    return np.array(pts, dtype=float), np.array(radii)
