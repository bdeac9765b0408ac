"""The committed demo assets are what the committed generator produces (same geometry)."""

from __future__ import annotations

import numpy as np
import trimesh

from weldplan.io.mesh import load_part
from weldplan.weld.demo_part import DEMO_JOINTS, DEMO_PART, demo_joints_csv, write_demo_assets


def _sorted_triangles(path) -> np.ndarray:
    """The mesh's triangles as (n, 9) rows in a canonical order (file order and normals ignored)."""
    mesh = trimesh.load(str(path), force="mesh", process=False)
    rows = np.asarray(mesh.triangles, dtype=np.float64).reshape(-1, 9)
    return rows[np.lexsort(rows.T[::-1])]


def _joint_rows(path) -> tuple[list[str], np.ndarray]:
    lines = [x for x in path.read_text(encoding="utf-8").splitlines() if x and x[0] != "#"]
    rows = [x.split(",") for x in lines[1:]]
    return [r[0] for r in rows], np.array([[float(v) for v in r[1:]] for r in rows])


def test_committed_assets_equal_a_fresh_generation(tmp_path):
    """Same geometry, not the same bytes: an STL writer may change normals or float rounding."""
    part, joints = write_demo_assets(tmp_path)
    ids, values = _joint_rows(joints)
    ids0, values0 = _joint_rows(DEMO_JOINTS)
    assert ids == ids0
    np.testing.assert_allclose(values, values0, rtol=0, atol=1e-9)
    fresh, committed = _sorted_triangles(part), _sorted_triangles(DEMO_PART)
    assert fresh.shape == committed.shape
    # binary STL stores float32: ~1e-4 mm at 1500 mm
    np.testing.assert_allclose(fresh, committed, rtol=0, atol=1e-3)


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
