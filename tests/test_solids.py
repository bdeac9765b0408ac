"""Closed solids: their interior is obstacle in the grid, virtual joints stay out of it, and the
verifier rejects a route through it even where the route crosses no triangle (issue 14, 2.2)."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from geometry_brute import winding_number

from weldplan.geometry.grid import build_grid
from weldplan.geometry.solids import ClosedSolids
from weldplan.io.joints import Joints
from weldplan.weld.cell import build_cell
from weldplan.weld.route import Leg, Route
from weldplan.weld.verify import verify_route

#: a solid 100 mm cube, corners on the 5 mm lattice
LO, HI = np.zeros(3), np.full(3, 100.0)
#: joints on three faces, no approach directions. At pitch 5 and clearance 4 the centres 5 mm
#: inside and 5 mm outside a face are equally near and both free by the distance rule; the tie
#: goes to the lower grid index, which is the inside one for the faces x = 100 and z = 100.
FACE_JOINTS = np.array([[100.0, 50.0, 50.0], [50.0, 50.0, 100.0], [0.0, 50.0, 50.0]])


def cube() -> trimesh.Trimesh:
    m = trimesh.creation.box(extents=HI - LO)
    m.apply_translation(0.5 * (LO + HI))
    return m


def strictly_inside_cube(P: np.ndarray, tol: float = 1e-9) -> np.ndarray:
    return np.all((P > LO + tol) & (P < HI - tol), axis=-1)


def test_closed_components_are_found_and_open_sheets_are_not():
    sheet = trimesh.Trimesh(
        vertices=[[0, 0, 0], [10, 0, 0], [10, 10, 0], [0, 10, 0]], faces=[[0, 1, 2], [0, 2, 3]]
    )
    ball = trimesh.creation.icosphere(subdivisions=2, radius=20)
    ball.apply_translation([50, 0, 0])
    solids = ClosedSolids.of(trimesh.util.concatenate([sheet, cube(), ball]))
    assert solids.n_components == 3
    assert len(solids) == 2
    assert len(ClosedSolids.of(sheet)) == 0


def test_occupancy_and_contains_agree_with_the_winding_number():
    ball = trimesh.creation.icosphere(subdivisions=2, radius=30)
    ball.apply_translation([150, 50, 50])
    inverted = cube()
    inverted.invert()  # inward normals: inside is still inside
    part = trimesh.util.concatenate([inverted, ball])
    solids = ClosedSolids.of(part)
    rng = np.random.default_rng(3)
    P = rng.uniform([-20, -20, -20], [200, 120, 120], size=(3000, 3))
    truth = np.abs(winding_number(P, part)) > 0.5
    # points within 0.1 mm of a surface are ties either test may call either way
    d = trimesh.proximity.ProximityQuery(part).signed_distance(P)
    clear = np.abs(d) > 0.1
    assert truth[clear].sum() > 300  # the test is not vacuous
    np.testing.assert_array_equal(solids.occupancy(P)[clear], truth[clear])
    np.testing.assert_array_equal(solids.contains(P)[clear], truth[clear])


def test_interior_of_a_solid_cube_is_obstacle_in_the_grid():
    grid = build_grid(cube(), pitch=5.0, clearance=4.0, region="all", margin=20.0)
    centres = grid.index_to_world(np.indices(grid.shape).reshape(3, -1).T)
    occ = grid.occupied.reshape(-1)
    inside = strictly_inside_cube(centres)
    assert inside.sum() == 19**3  # centres 5 .. 95 mm on each axis
    assert occ[inside].all()
    # outside, the distance rule alone: closer than the clearance to the cube
    q = np.maximum(np.maximum(LO - centres, centres - HI), 0.0)
    d_out = np.linalg.norm(q, axis=1)
    np.testing.assert_array_equal(occ[~inside], d_out[~inside] < 4.0)
    # the paper's rule alone leaves the deep interior free
    paper = build_grid(cube(), pitch=5.0, clearance=4.0, region="all", margin=20.0, interior=False)
    assert not paper.occupied.reshape(-1)[inside].all()


def test_thin_closed_panels_keep_their_grid():
    """A 2 mm closed panel: its interior lies within the clearance anyway, nothing changes."""
    panel = trimesh.creation.box(extents=(2.0, 80.0, 80.0))
    kw = {"pitch": 5.0, "clearance": 5.0, "region": "all", "margin": 20.0}
    a = build_grid(panel, **kw)
    b = build_grid(panel, interior=False, **kw)
    np.testing.assert_array_equal(a.occupied, b.occupied)


def test_virtual_joints_of_joints_without_directions_stay_out_of_the_solid():
    joints = Joints(ids=("A", "B", "C"), xyz=FACE_JOINTS)
    cell = build_cell(cube(), joints, pitch=5.0, clearance=4.0, margin=30.0)
    assert not strictly_inside_cube(cell.virtual_xyz).any(), cell.virtual_xyz
    np.testing.assert_allclose(cell.offsets, 5.0)
    assert cell.summary()["checks"]["closed_solids"] == 1


def _route_through_the_cube() -> Route:
    """Spots on the faces x = 100 and z = 100, virtual joints 5 mm inside, a straight middle:
    every capsule at 4 mm misses every triangle (the route stays 5 mm inside the faces)."""
    spots = FACE_JOINTS[:2]
    virtual = spots - [[5.0, 0.0, 0.0], [0.0, 0.0, 5.0]]
    leg = Leg("A", "C", [spots[0], virtual[0], virtual[1], spots[1]])
    return Route(
        order=("A", "C"),
        legs=(leg,),
        joint_ids=("A", "C"),
        joint_xyz=spots,
        virtual_xyz=virtual,
        settings={"clearance": 4.0},
    )


def test_verify_rejects_a_route_inside_a_closed_solid_that_crosses_no_triangle():
    route = _route_through_the_cube()
    part = cube()
    leg = route.legs[0].points
    # the capsule check alone calls it free: the bug this test pins
    from weldplan.geometry.collision import CollisionModel

    assert CollisionModel(part).segment_free(leg[1], leg[2], 4.0)
    rep = verify_route(route, part)
    assert not rep.ok
    kinds = {v.kind for v in rep.violations}
    assert kinds == {"inside"}, rep.describe()
    assert "inside a closed solid" in rep.describe()
    # the same route past an open sheet (the cube without its x = 100 face) is not inside
    open_part = part.copy()
    keep = ~np.isclose(open_part.triangles_center[:, 0], 100.0)
    open_part.update_faces(keep)
    assert verify_route(route, open_part).ok


def test_planned_route_on_a_solid_cube_never_enters_it():
    pytest.importorskip("weldplan.weld.local")
    from weldplan.weld.pipeline import PlanConfig, plan_route

    joints = Joints(ids=("A", "B", "C"), xyz=FACE_JOINTS)
    cell = build_cell(cube(), joints, pitch=5.0, clearance=4.0, margin=30.0)
    route = plan_route(cell, config=PlanConfig(planner="exact", clearance=4.0), rng=0)
    assert verify_route(route, cell.part).ok
    for leg in route.legs:
        P = leg.points
        t = np.linspace(0.0, 1.0, 41)[:, None, None]
        samples = (P[:-1][None] + t * (P[1:] - P[:-1])[None]).reshape(-1, 3)
        assert not strictly_inside_cube(samples, tol=0.5).any(), (leg.from_id, leg.to_id)


def test_interior_without_a_distance_rule_is_tested_voxel_by_voxel():
    """clearance 0 marks nothing by distance; the interior is still obstacle."""
    grid = build_grid(cube(), pitch=5.0, clearance=0.0, region="all", margin=10.0)
    centres = grid.index_to_world(np.indices(grid.shape).reshape(3, -1).T)
    off_faces = ~np.isin(centres, [0.0, 100.0]).any(axis=1)  # centres on a face plane are ties
    np.testing.assert_array_equal(
        grid.occupied.reshape(-1)[off_faces], strictly_inside_cube(centres)[off_faces]
    )
    assert grid.n_obstacle >= 19**3
