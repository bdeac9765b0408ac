"""The obstacle grid: the obstacle rule against brute force, regions, grid <-> world conversions."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from conftest import require_shared
from geometry_brute import mesh_distance, winding_number
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import ndimage

from weldplan.geometry.grid import ObstacleGrid, build_grid, grid_region
from weldplan.io.mesh import load_part

#: centres closer than this to the clearance are ties that single-precision distances may flip
TIE = 1e-3


def small_part() -> trimesh.Trimesh:
    """A sheet, a tilted bar and a coarse sphere: faces, edges and vertices all matter."""
    sheet = trimesh.creation.box(extents=(60, 40, 1.5))
    bar = trimesh.creation.box(
        extents=(8, 50, 8),
        transform=trimesh.transformations.rotation_matrix(0.6, [1, 1, 0], [20, 0, 20]),
    )
    bar.apply_translation([0, 0, 12])
    ball = trimesh.creation.icosphere(subdivisions=1, radius=9)
    ball.apply_translation([-22, 12, -14])
    return trimesh.util.concatenate([sheet, bar, ball])


def assert_rule_holds(grid: ObstacleGrid, mesh: trimesh.Trimesh, n_far: int = 3000) -> int:
    """Check every voxel within two voxels of an obstacle, and a sample of the others.

    The truth: closer than the clearance to a triangle (brute-force distance), or inside a
    closed component (brute-force winding number; every closed part of these meshes is
    outward-wound, and the open ones are far from the sampled centres' thresholds).
    """
    near = ndimage.binary_dilation(grid.occupied, iterations=2)
    far = np.argwhere(~near)
    rng = np.random.default_rng(1)
    far = far[rng.choice(len(far), min(n_far, len(far)), replace=False)]
    idx = np.concatenate([np.argwhere(near), far])
    centres = grid.index_to_world(idx)
    d = mesh_distance(centres, mesh)
    inside = np.zeros(len(idx), dtype=bool)
    for comp in mesh.split(only_watertight=True, repair=False):
        inside |= np.abs(winding_number(centres, comp)) > 0.5
    got = grid.occupied[idx[:, 0], idx[:, 1], idx[:, 2]]
    clear = np.abs(d - grid.clearance) > TIE
    np.testing.assert_array_equal(got[clear], ((d < grid.clearance) | inside)[clear])
    return int(np.sum((d < grid.clearance) | inside))


@pytest.mark.parametrize(("pitch", "clearance"), [(5.0, 5.0), (2.0, 3.0), (3.0, 0.7)])
def test_obstacle_rule_matches_brute_force_point_triangle_distances(pitch, clearance):
    mesh = small_part()
    grid = build_grid(mesh, pitch=pitch, clearance=clearance, region="all", margin=10.0)
    n_obstacle = assert_rule_holds(grid, mesh)
    assert n_obstacle > 50  # the rule is exercised, not vacuous
    assert grid.n_free > n_obstacle


def test_obstacle_rule_on_a_grid_larger_than_the_coarse_blocks():
    """Blocks of 16^3 voxels are decided whole: check a grid of several blocks per axis."""
    mesh = small_part()
    grid = build_grid(mesh, pitch=1.5, clearance=2.0, region="all", margin=6.0)
    assert grid.n_obstacle > 1000
    assert min(grid.shape) > 32
    assert_rule_holds(grid, mesh)


def test_edges_and_vertices_count_not_only_faces():
    """The paper's projection rule misses centres beyond an edge; the exact rule does not."""
    tri = trimesh.Trimesh(vertices=[[0, 0, 0], [10, 0, 0], [0, 10, 0]], faces=[[0, 1, 2]])
    box = np.array([[-6.0, -6.0, -6.0], [16.0, 16.0, 6.0]])
    grid = build_grid(tri, pitch=2.0, clearance=3.0, region=box)
    # (-2, -2, 0) projects outside the triangle but is 2.83 mm from vertex (0, 0, 0)
    i = grid.world_to_index([-2.0, -2.0, 0.0])
    assert grid.occupied[tuple(i)]
    j = grid.world_to_index([-4.0, -2.0, 0.0])  # 4.47 mm from the vertex
    assert not grid.occupied[tuple(j)]
    assert_rule_holds(grid, tri)


def test_region_is_on_the_world_lattice_and_covers_joints_plus_margin():
    mesh = small_part()
    pts = np.array([[1.2, -3.3, 0.4], [7.9, 4.1, 2.2]])
    origin, shape = grid_region(mesh, pitch=5.0, region="joints", points=pts, margin=12.0)
    np.testing.assert_allclose(origin / 5.0, np.round(origin / 5.0))
    grid = ObstacleGrid(np.zeros(shape, bool), origin, 5.0, 5.0)
    lo, hi = grid.index_to_world([0, 0, 0]), grid.index_to_world(np.array(shape) - 1)
    assert np.all(lo >= pts.min(0) - 12.0) and np.all(lo - 5.0 < pts.min(0) - 12.0)
    assert np.all(hi <= pts.max(0) + 12.0) and np.all(hi + 5.0 > pts.max(0) + 12.0)
    # two regions of one part agree voxel for voxel where they overlap
    g1 = build_grid(mesh, region="joints", points=pts, margin=12.0, pitch=2.0, clearance=2.0)
    g2 = build_grid(mesh, region="all", margin=0.0, pitch=2.0, clearance=2.0)
    off = np.round((g1.origin - g2.origin) / 2.0).astype(int)
    sub = g2.occupied[
        off[0] : off[0] + g1.shape[0], off[1] : off[1] + g1.shape[1], off[2] : off[2] + g1.shape[2]
    ]
    np.testing.assert_array_equal(sub, g1.occupied)


def test_bad_regions_are_rejected():
    mesh = small_part()
    with pytest.raises(ValueError, match="points"):
        build_grid(mesh, region="joints")
    with pytest.raises(ValueError, match="region"):
        build_grid(mesh, region="everything")
    with pytest.raises(ValueError, match="bounds"):
        build_grid(mesh, region=[[0, 0, 0], [-1, 1, 1]])
    with pytest.raises(ValueError, match="pitch"):
        build_grid(mesh, region="all", pitch=0)


def test_explicit_bounds_far_from_the_part_are_all_free():
    grid = build_grid(small_part(), region=[[500, 500, 500], [600, 600, 600]])
    assert grid.n_obstacle == 0 and grid.shape == (21, 21, 21)


coords = st.integers(min_value=-50, max_value=80)


@settings(max_examples=200, deadline=None)
@given(
    i=st.tuples(coords, coords, coords),
    origin=st.tuples(*[st.floats(-5000, 5000, allow_nan=False)] * 3),
    pitch=st.sampled_from([0.5, 1.0, 2.5, 5.0, 7.3]),
)
def test_index_world_round_trip(i, origin, pitch):
    grid = ObstacleGrid(np.zeros((4, 5, 6), bool), np.array(origin), pitch, 5.0)
    idx = np.array(i)
    np.testing.assert_array_equal(grid.world_to_index(grid.index_to_world(idx)), idx)
    flat_ok = grid.contains(idx)
    if flat_ok:
        np.testing.assert_array_equal(grid.unravel(grid.ravel(idx)), idx)


@settings(max_examples=200, deadline=None)
@given(
    p=st.tuples(*[st.floats(-1000, 1000, allow_nan=False)] * 3),
    pitch=st.sampled_from([1.0, 2.5, 5.0]),
)
def test_world_to_index_gives_the_nearest_centre(p, pitch):
    grid = ObstacleGrid(np.zeros((2, 2, 2), bool), np.array([3.0, -7.0, 11.0]), pitch, 5.0)
    p = np.array(p)
    c = grid.index_to_world(grid.world_to_index(p))
    assert np.all(np.abs(p - c) <= 0.5 * pitch + 1e-9)


def test_car2_region_agrees_with_brute_force_on_sampled_voxels():
    mesh = load_part(require_shared("bodies", "car2.obj"), length=4500)
    centre = mesh.triangles_center[np.argmax(mesh.area_faces)]
    box = np.stack([centre - 150.0, centre + 150.0])
    grid = build_grid(mesh, region=box)
    assert grid.n_obstacle > 0
    rng = np.random.default_rng(0)
    occ = np.argwhere(grid.occupied)
    free = np.argwhere(grid.free)
    near = free[rng.choice(len(free), 1500, replace=False)]
    idx = np.concatenate([occ[rng.choice(len(occ), min(500, len(occ)), replace=False)], near])
    # only triangles that reach into the box can be closer than the clearance: brute force
    # over those decides "d < clearance" exactly (d over a subset is never smaller)
    lo, hi = box[0] - 2 * grid.clearance, box[1] + 2 * grid.clearance
    tri = mesh.triangles
    keep = np.all((tri.min(axis=1) <= hi) & (tri.max(axis=1) >= lo), axis=1)
    local = trimesh.Trimesh(mesh.vertices, mesh.faces[keep], process=False)
    assert 0 < keep.sum() < len(keep)
    d = mesh_distance(grid.index_to_world(idx), local, chunk=500)
    clear = np.abs(d - grid.clearance) > TIE
    got = grid.occupied[idx[:, 0], idx[:, 1], idx[:, 2]]
    np.testing.assert_array_equal(got[clear], (d < grid.clearance)[clear])


def test_grid_pickles_bit_packed():
    import pickle

    rng = np.random.default_rng(0)
    grid = ObstacleGrid(rng.random((40, 50, 60)) < 0.3, np.array([1.0, -2.0, 3.5]), 2.5, 4.0)
    data = pickle.dumps(grid)
    assert len(data) < grid.occupied.size / 8 + 1000
    back = pickle.loads(data)
    np.testing.assert_array_equal(back.occupied, grid.occupied)
    np.testing.assert_array_equal(back.free, grid.free)
    np.testing.assert_array_equal(back.origin, grid.origin)
    assert (back.pitch, back.clearance) == (2.5, 4.0)
