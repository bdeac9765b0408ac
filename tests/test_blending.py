"""Corner blends of the robot posts (#14 item 11): a zone only where the part leaves room.

The blends are sampled as a controller flies them (tests/faults/oracle.py: a parabola from the
zone's entry to its exit through the corner) and judged by python-fcl on the raw triangles.
"""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from tests.faults.oracle import Triangles, blend_curve, point_distance
from tests.faults.programs import krl_moves, rapid_moves
from tests.route_fixtures import box_part, box_route
from weldplan.errors import WeldplanError
from weldplan.geometry.collision import CollisionModel
from weldplan.io.blending import krl_cdis, rapid_zone
from weldplan.io.export import render_post, write_post
from weldplan.weld.route import Leg, Route

C = 5.0
A_SPOT = np.array([-40.0, 0.0, 0.0])
B_SPOT = np.array([40.0, 0.0, 0.0])


def floor_part() -> trimesh.Trimesh:
    """A 200 x 200 x 2 mm plate, top face z = 0."""
    m = trimesh.creation.box(extents=[200.0, 200.0, 2.0])
    m.apply_translation([0.0, 0.0, -1.0])
    return m


def floor_route(*inner) -> Route:
    """A -> B over the floor: spot, virtual joint 10 mm above, ``inner`` vias, virtual, spot."""
    vA, vB = A_SPOT + [0, 0, 10.0], B_SPOT + [0, 0, 10.0]
    pts = [A_SPOT, vA, *[np.asarray(p, float) for p in inner], vB, B_SPOT]
    return Route(
        order=("A", "B"),
        legs=(Leg("A", "B", pts, "exact"),),
        joint_ids=("A", "B"),
        joint_xyz=np.array([A_SPOT, B_SPOT]),
        directions=None,
        virtual_xyz=np.array([vA, vB]),
        lower_bound=80.0,
        lower_bound_method="held-karp",
        settings={"clearance": C, "planner": "exact"},
        seed=0,
        stats={},
    )


def _tri(mesh: trimesh.Trimesh) -> Triangles:
    return Triangles(np.asarray(mesh.vertices), np.asarray(mesh.faces))


def _worst_blend(tri: Triangles, pts: np.ndarray, radii: np.ndarray) -> float:
    """Smallest distance (mm) to the part over every blended corner's curve (inf: none)."""
    worst = np.inf
    for k in range(1, len(pts) - 1):
        if radii[k] > 0:
            curve = blend_curve(pts[k - 1], pts[k], pts[k + 1], radii[k])
            worst = min(worst, min(point_distance(tri, q) for q in curve))
    return worst


def test_open_space_corners_keep_their_zone_and_virtual_joints_shrink_it():
    route = floor_route([-40.0, 0.0, 40.0], [40.0, 0.0, 40.0])
    text = render_post(route, "rapid", floor_part())
    _, _, zones = rapid_moves(text)
    # approach (MoveJ) and weld spots stop; the virtual joints 10 mm up have 5 mm of margin
    # less the round-off: z1; the corners 40 mm up keep the program's z5
    assert zones == ["fine", "fine", "z1", "z5", "z5", "z1", "fine", "fine"]
    assert "4 of 4 via points fly by" in text
    # a larger maximum zone: the high corners get the half-segment cap (15 mm -> z15)
    _, _, zones = rapid_moves(render_post(route, "rapid", floor_part(), zone="z50"))
    assert zones[3:5] == ["z15", "z15"]


def test_corner_near_the_part_is_an_exact_stop():
    route = floor_route([0.0, 0.0, C + 0.05])  # 0.05 mm of free margin
    _, _, zones = rapid_moves(render_post(route, "rapid", floor_part()))
    assert zones[3] == "fine"
    pts, cdis = krl_moves(render_post(route, "krl", floor_part()))
    assert cdis[3] == 0.0
    np.testing.assert_allclose(pts[3], [0.0, 0.0, C + 0.05])
    # with 0.35 mm of margin: z0 (0.3 mm) and C_DIS 0.3
    route = floor_route([0.0, 0.0, C + 0.35])
    assert rapid_moves(render_post(route, "rapid", floor_part()))[2][3] == "z0"
    assert krl_moves(render_post(route, "krl", floor_part()))[1][3] == pytest.approx(0.3)


#: around the end of the box part's wall (x in [-1, 1], y <= 50), 0.35 mm of free margin
WALL_END = [0.0, 50.0 + C + 0.35, 10.0]


def test_the_old_fixed_zone_would_cut_into_the_clearance():
    """The check can fail: the z5 every via point used to get cuts the corner around the wall's
    end down to about 2.3 mm from the wall; the post now gives it z0 (0.3 mm)."""
    route = floor_route(WALL_END)
    pts = route.legs[0].points
    curve = blend_curve(pts[1], pts[2], pts[3], 5.0)
    assert min(point_distance(_tri(box_part()), q) for q in curve) < C - 2.0
    assert rapid_moves(render_post(route, "rapid", box_part()))[2][3] == "z0"


@pytest.mark.parametrize("post", ["rapid", "krl"])
@pytest.mark.parametrize(
    "scene",
    ["box", "wall-end", "floor-high", "floor-low", "floor-zigzag"],
)
def test_every_emitted_blend_keeps_the_clearance(post, scene):
    if scene == "box":
        part, route = box_part(), box_route()
    elif scene == "wall-end":
        part, route = box_part(), floor_route(WALL_END)
    else:
        part = floor_part()
        inner = {
            "floor-high": [[-40.0, 0.0, 40.0], [40.0, 0.0, 40.0]],
            "floor-low": [[0.0, 0.0, C + 0.35]],
            "floor-zigzag": [[-20.0, 5.0, 8.0], [0.0, -5.0, 30.0], [20.0, 5.0, 6.5]],
        }[scene]
        route = floor_route(*inner)
    for zone_opts in ({}, {"zone": "z50"} if post == "rapid" else {"cdis": 50.0}):
        text = render_post(route, post, part, **zone_opts)
        pts, radii = rapid_moves(text)[:2] if post == "rapid" else krl_moves(text)
        assert np.any(radii > 0) or scene == "floor-low"
        assert _worst_blend(_tri(part), pts, radii) >= C - 1e-9


def test_part_can_be_a_cell_like_object_or_a_collision_model(tmp_path):
    route = floor_route([-40.0, 0.0, 40.0], [40.0, 0.0, 40.0])
    mesh = floor_part()
    expected = render_post(route, "rapid", mesh)
    assert render_post(route, "rapid", CollisionModel(mesh)) == expected
    write_post(route, tmp_path / "r.src", "krl", part=mesh)
    assert "C_DIS" in (tmp_path / "r.src").read_text()
    write_post(route, tmp_path / "r.mod", "rapid", part=mesh)
    assert (tmp_path / "r.mod").read_text() == expected


def test_posts_refuse_without_the_part_or_a_clearance():
    route = floor_route([0.0, 0.0, 40.0])
    for post in ("rapid", "krl"):
        with pytest.raises(WeldplanError, match="need the part"):
            render_post(route, post)
        with pytest.raises(WeldplanError, match="part must be a trimesh"):
            render_post(route, post, "car.stl")
    bare = Route.from_dict({**route.to_dict(), "settings": {}})
    with pytest.raises(WeldplanError, match="positive finite clearance"):
        render_post(bare, "rapid", floor_part())
    assert "fly by" in render_post(bare, "rapid", floor_part(), clearance=C)
    with pytest.raises(WeldplanError, match="zone must be"):
        render_post(route, "rapid", floor_part(), zone="z7")
    with pytest.raises(WeldplanError, match="cdis must be"):
        render_post(route, "krl", floor_part(), cdis=float("nan"))


@pytest.mark.parametrize(
    ("radius", "cap", "zone"),
    [(0.0, "z5", "fine"), (0.29, "z5", "fine"), (0.3, "z5", "z0"), (4.99, "z5", "z1"),
     (5.0, "z5", "z5"), (100.0, "z5", "z5"), (100.0, "z200", "z100"), (3.0, "fine", "fine")],
)  # fmt: skip
def test_rapid_zone_is_the_largest_standard_zone_that_fits(radius, cap, zone):
    assert rapid_zone(radius, cap) == zone


@pytest.mark.parametrize(
    ("radius", "cap", "cdis"),
    [(0.05, 5.0, 0.0), (0.1, 5.0, 0.1), (1.37, 5.0, 1.3), (7.0, 5.0, 5.0), (2.0, 0.0, 0.0)],
)
def test_krl_cdis_rounds_down(radius, cap, cdis):
    assert krl_cdis(radius, cap) == pytest.approx(cdis)
    assert krl_cdis(radius, cap) <= radius


@pytest.mark.slow
@pytest.mark.shared
def test_car2_station_blends_keep_the_clearance(tmp_path):
    """The 50-joint car2 station through the CLI: every zone the RAPID and KRL programs emit keeps
    the 5 mm clearance along its blend (the 200-joint station of docs/bench-scale.md, exported
    with the old fixed z5, came within 4.884 mm between two via points and 0.119 mm next to a
    weld spot)."""
    from tests.conftest import ROOT, require_shared
    from weldplan.cli import main

    mesh = require_shared("bodies", "car2.obj")
    joints = ROOT / "assets" / "car2" / "car2_synthetic_50.csv"
    loaded = trimesh.load(str(mesh), force="mesh", process=False)
    v = np.asarray(loaded.vertices)[np.unique(loaded.faces)]
    tri = Triangles(
        np.asarray(loaded.vertices) * (4500.0 / np.max(v.max(0) - v.min(0))),
        np.asarray(loaded.faces),
    )
    base = [
        "plan", str(mesh), str(joints), "--length", "4500", "--candidates", "6", "--quiet",
        "-o", str(tmp_path / "r.csv"),
    ]  # fmt: skip
    assert main([*base, "--post", "rapid", "--json", str(tmp_path / "r.json")]) == 0
    text = (tmp_path / "r.mod").read_text()
    pts, radii, _ = rapid_moves(text)
    assert np.sum(radii > 0) > 20
    assert _worst_blend(tri, pts, radii) >= C - 1e-6
    # the old post's z5 at every via point (not the welds, the approach, the retreat) cuts into
    # the clearance on this station too
    moves = [ln for ln in text.splitlines() if ln.lstrip().startswith(("MoveJ ", "MoveL "))]
    via = np.array(["! weld joint" not in ln for ln in moves])
    via[[0, -1]] = False
    assert _worst_blend(tri, pts, np.where(via, 5.0, 0.0)) < C - 0.05
    from weldplan.io.export import read_route

    route = read_route(tmp_path / "r.json")
    pts, radii = krl_moves(render_post(route, "krl", trimesh.Trimesh(tri.vertices, tri.faces)))
    assert np.sum(radii > 0) > 20
    assert _worst_blend(tri, pts, radii) >= C - 1e-6
