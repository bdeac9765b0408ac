"""The committed demo assets are exactly what the committed generator produces."""

from __future__ import annotations

import numpy as np
import trimesh

from weldplan.io.mesh import load_part
from weldplan.weld.demo_part import DEMO_JOINTS, DEMO_PART, demo_joints_csv, write_demo_assets


def test_committed_assets_equal_a_fresh_generation(tmp_path):
    part, joints = write_demo_assets(tmp_path)
    assert joints.read_text(encoding="utf-8") == DEMO_JOINTS.read_text(encoding="utf-8")
    assert part.read_bytes() == DEMO_PART.read_bytes()


def test_demo_part_is_closed_sheet_metal():
    mesh = trimesh.load(str(DEMO_PART), force="mesh")
    loaded = load_part(DEMO_PART)
    assert len(loaded.faces) == len(mesh.faces)
    parts = mesh.split(only_watertight=False)
    assert len(parts) >= 10
    # every panel is a closed box of sheet 1.5-2 mm thick (its smallest box extent)
    for p in parts:
        assert p.is_watertight
        thickness = 2 * p.volume / p.area  # thin plate: volume = area / 2 * t
        assert 1.3 < thickness < 2.1


def test_joints_csv_has_unit_directions():
    lines = [x for x in demo_joints_csv().splitlines() if x and not x.startswith("#")]
    values = np.array([[float(v) for v in x.split(",")[4:]] for x in lines[1:]])
    np.testing.assert_allclose(np.linalg.norm(values, axis=1), 1.0, atol=1e-3)
