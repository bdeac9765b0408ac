"""Polyanya against independent answers: the authors' optimum lengths on arena, the visibility
graph on random maps (property-based) and on aurora queries, hand-made corner cases, and the
starved variant (pruning off) giving the same lengths."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tests.conftest import require_shared
from weldplan.errors import InputError, PlanningError
from weldplan.geometry.obstacles2d import Obstacles2D
from weldplan.planar.anyangle import scenario_navmesh
from weldplan.planar.exact import (
    MeshFreeSpace,
    mesh_shortest_path_bounded,
    read_scen,
    visibility_shortest_path,
)
from weldplan.planar.navmesh import NavMesh, grid_navmesh
from weldplan.planar.polyanya import Polyanya


def _framed(rects: np.ndarray, bounds: tuple[float, float, float, float]) -> Obstacles2D:
    """Rectangles plus frame rectangles around ``bounds`` (as Scenario.world does)."""
    x0, y0, x1, y1 = bounds
    m = max(x1 - x0, y1 - y0)
    frame = [
        [x0 - m, y0 - m, x1 + m, y0],
        [x0 - m, y1, x1 + m, y1 + m],
        [x0 - m, y0, x0, y1],
        [x1, y0, x1 + m, y1],
    ]
    return Obstacles2D(rectangles=np.concatenate([np.reshape(rects, (-1, 4)), frame]))


def _vg_length(world: Obstacles2D, s, t, bounds) -> float:
    try:
        return visibility_shortest_path(world, s, t, bounds=bounds).length
    except PlanningError:
        return math.inf


#: two unit squares side by side: [0, 1] x [0, 1] and [1, 2] x [0, 1]
TWO = NavMesh([[0, 0], [1, 0], [2, 0], [2, 1], [1, 1], [0, 1]], [[0, 1, 4, 5], [1, 2, 3, 4]])


def _u_room() -> tuple[NavMesh, Obstacles2D, tuple[float, float, float, float]]:
    """A 10 x 10 room with a wall x in [4, 6], y in [0, 7] (its top corners are the turns)."""
    bounds = (0.0, 0.0, 10.0, 10.0)
    rects = np.array([[4.0, 0.0, 6.0, 7.0]])
    return scenario_navmesh(Obstacles2D(rectangles=rects), bounds), _framed(rects, bounds), bounds


# ------------------------------------------------------------------------------ exact answers
def test_arena_matches_the_authors_optimum_every_query():
    folder = require_shared("meshmaps")
    mesh = NavMesh.read(folder / "arena.mesh")
    sc = read_scen(folder / "arena.mesh.anyangle.scen")
    assert len(sc.length) == 160
    for prune in (True, False):
        pa = Polyanya(mesh, prune=prune)
        L = np.array([pa.distance(s, g) for s, g in zip(sc.start, sc.goal, strict=True)])
        np.testing.assert_allclose(L, sc.length, rtol=1e-6)


def test_arena_grid_made_a_mesh_gives_the_same_optima():
    """arena.map converted here (cell corners at integers) answers the mesh's any-angle file:
    the .scen values are raw points, not cell centres."""
    from weldplan.planar.exact import read_movingai_map

    free = read_movingai_map(require_shared("movingai", "arena.map"))
    sc = read_scen(require_shared("meshmaps", "arena.mesh.anyangle.scen"))
    pa = Polyanya(grid_navmesh(free))
    L = np.array([pa.distance(s, g) for s, g in zip(sc.start, sc.goal, strict=True)])
    np.testing.assert_allclose(L, sc.length, rtol=1e-6)
    shifted = np.array(
        [pa.distance(s + 0.5, g + 0.5) for s, g in zip(sc.start, sc.goal, strict=True)]
    )
    assert np.sum(np.abs(shifted - sc.length) > 1e-6 * sc.length) > 10


def test_aurora_sample_equals_the_visibility_graph():
    """Short aurora queries (the bounded visibility search is cheap there): Polyanya equals it
    and stays at or below the file's octile lengths."""
    folder = require_shared("meshmaps")
    mesh = NavMesh.read(folder / "aurora.mesh")
    space = MeshFreeSpace.read(folder / "aurora.mesh")
    sc = read_scen(folder / "aurora.mesh.scen")
    pa = Polyanya(mesh)
    idx = np.nonzero(sc.length < 60)[0][::6][:12]
    assert len(idx) >= 8
    for k in idx:
        ours = pa.query(sc.start[k], sc.goal[k])
        vg = mesh_shortest_path_bounded(space, sc.start[k], sc.goal[k], sc.length[k] + 1e-6)
        assert ours.length == pytest.approx(vg.length, rel=1e-9), k
        assert ours.length <= sc.length[k] + 1e-5
        # the returned waypoints are a free polyline of that length
        P = ours.points
        assert np.all(space.segments_free(P[:-1], P[1:]))
        assert np.sum(np.linalg.norm(np.diff(P, axis=0), axis=1)) == pytest.approx(ours.length)


# --------------------------------------------------------------------------- property-based
@settings(max_examples=25, deadline=None)
@given(
    rects=st.lists(
        st.tuples(
            st.floats(0, 8, allow_nan=False),
            st.floats(0, 8, allow_nan=False),
            st.floats(0.5, 4),
            st.floats(0.5, 4),
        ),
        min_size=1,
        max_size=5,
    ),
    pts=st.lists(st.tuples(st.floats(0.05, 9.95), st.floats(0.05, 9.95)), min_size=6, max_size=6),
)
def test_random_rectangle_maps_match_the_visibility_graph(rects, pts):
    # coordinates on a 1/64 grid: features closer than floating point resolves (hypothesis found
    # a rectangle 5e-324 above the frame) are refused by the triangulation, tested below
    rects = [tuple(round(v * 64) / 64 for v in r) for r in rects]
    bounds = (0.0, 0.0, 10.0, 10.0)
    R = np.array([[x, y, min(x + w, 10.0), min(y + h, 10.0)] for x, y, w, h in rects])
    world = _framed(R, bounds)
    mesh = scenario_navmesh(Obstacles2D(rectangles=R), bounds)
    pa, starved = Polyanya(mesh), Polyanya(mesh, prune=False)
    P = np.array(pts)
    P = P[world.clearance(P) > 1e-6]
    for s, t in zip(P[::2], P[1::2], strict=False):
        want = _vg_length(world, s, t, bounds)
        got = pa.distance(s, t)
        assert got == pytest.approx(want, rel=1e-9) or (math.isinf(got) and math.isinf(want))
        assert starved.distance(s, t) == pytest.approx(got, rel=1e-12) or math.isinf(got)


@settings(max_examples=20, deadline=None)
@given(
    seed=st.integers(0, 2**31),
    pts=st.lists(st.tuples(st.floats(0, 7), st.floats(0, 7)), min_size=4, max_size=4),
)
def test_random_grids_made_meshes_match_the_visibility_graph(seed, pts):
    free = np.random.default_rng(seed).random((7, 7)) > 0.3
    blocked = np.argwhere(~free).astype(float)
    R = np.concatenate([blocked, blocked + 1.0], axis=1)
    bounds = (0.0, 0.0, 7.0, 7.0)
    world = _framed(R, bounds)
    pa = Polyanya(grid_navmesh(free))
    P = np.array(pts)
    P = P[world.clearance(P) > 1e-6]
    for s, t in zip(P[::2], P[1::2], strict=False):
        want = _vg_length(world, s, t, bounds)
        got = pa.distance(s, t)
        assert got == pytest.approx(want, rel=1e-9) or (math.isinf(got) and math.isinf(want))


# ------------------------------------------------------------------------------ corner cases
def test_overlapping_outlines_on_the_frame_are_triangulated():
    """Collinear overlapping outlines (two rectangles on the frame, found by hypothesis) made
    Triangle fail; they are cut into shared pieces first."""
    R = np.array([[2.6e-125, 1.0, 1.0, 2.0], [1.9e-242, 1.5, 1.0, 2.5]])
    bounds = (0.0, 0.0, 10.0, 10.0)
    pa = Polyanya(scenario_navmesh(Obstacles2D(rectangles=R), bounds))
    want = _vg_length(_framed(R, bounds), np.array([0.5, 0.5]), np.array([0.5, 3.0]), bounds)
    assert pa.distance([0.5, 0.5], [0.5, 3.0]) == pytest.approx(want, rel=1e-12)
    assert want == pytest.approx(1.5 + math.sqrt(2))


def test_same_polygon_same_point_and_shared_edge():
    pa = Polyanya(TWO)
    r = pa.query([0.2, 0.2], [0.8, 0.9])
    assert r.length == pytest.approx(math.hypot(0.6, 0.7))
    assert r.points.shape == (2, 2)
    assert pa.distance([0.3, 0.3], [0.3, 0.3]) == 0.0
    assert pa.distance([0.5, 0.5], [1.5, 0.5]) == pytest.approx(1.0)  # across the shared edge
    assert pa.distance([1.0, 0.5], [1.9, 0.1]) == pytest.approx(math.hypot(0.9, 0.4))  # on it


def test_turning_at_a_wall_corner_vertices_and_edges():
    mesh, world, bounds = _u_room()
    pa = Polyanya(mesh)
    # around the wall's two top corners (4, 7) and (6, 7)
    r = pa.query([2.0, 1.0], [8.0, 1.0])
    assert r.length == pytest.approx(2 * math.hypot(2.0, 6.0) + 2.0)
    np.testing.assert_allclose(r.points, [[2, 1], [4, 7], [6, 7], [8, 1]], atol=1e-12)
    # start on a corner vertex, goal on the wall's side (a boundary edge)
    assert pa.distance([4.0, 7.0], [6.0, 3.0]) == pytest.approx(2.0 + 4.0)
    # collinear with the wall's top: straight along it
    assert pa.distance([1.0, 7.0], [9.0, 7.0]) == pytest.approx(8.0)
    # the goal exactly behind a corner, on the line through the other corner
    want = _vg_length(world, np.array([0.5, 8.5]), np.array([7.0, 5.5]), bounds)
    assert pa.distance([0.5, 8.5], [7.0, 5.5]) == pytest.approx(want, rel=1e-12)


def test_unreachable_and_outside_points_have_no_path():
    # two rooms separated by a full-height wall
    mesh = scenario_navmesh(Obstacles2D(rectangles=[[4.0, -1.0, 6.0, 11.0]]), (0, 0, 10, 10))
    pa = Polyanya(mesh)
    r = pa.query([1.0, 1.0], [9.0, 9.0])
    assert math.isinf(r.length) and not r.found and len(r.points) == 0
    assert math.isinf(pa.distance([1.0, 1.0], [5.0, 5.0]))  # inside the wall
    assert math.isinf(pa.distance([-3.0, 1.0], [2.0, 2.0]))  # off the map
    assert pa.distance([1.0, 1.0], [2.0, 9.0]) == pytest.approx(math.hypot(1, 8))


def test_pruning_off_gives_the_same_lengths_with_more_work():
    mesh, world, bounds = _u_room()
    rng = np.random.default_rng(3)
    P = rng.uniform(0, 10, (80, 2))
    P = P[world.clearance(P) > 1e-6]
    full, starved = Polyanya(mesh), Polyanya(mesh, prune=False)
    work_full = work_starved = 0
    for s, t in zip(P[::2], P[1::2], strict=False):
        a, b = full.query(s, t), starved.query(s, t)
        assert a.length == pytest.approx(b.length, rel=1e-12)
        work_full += a.generated
        work_starved += b.generated
    assert work_starved > work_full


def test_a_search_that_outgrows_its_room_is_rerun_with_more_and_agrees():
    """The kernel's node arrays have a fixed room per try; with room for 16 nodes every query
    of the U room overflows at least once and must give the same answer as with ample room."""
    from weldplan.planar._polyanya_kernel import Query, search

    mesh, world, _ = _u_room()
    pa = Polyanya(mesh)
    rng = np.random.default_rng(5)
    P = rng.uniform(0, 10, (40, 2))
    P = P[world.clearance(P) > 1e-6]
    overflowed = 0
    for s, t in zip(P[::2], P[1::2], strict=False):
        sp, tp = mesh.locate(s), mesh.locate(t)
        if set(sp) & set(tp):
            continue
        q = Query(*map(float, (*s, *t)), np.array(sp), np.array(tp), True)
        (la, pts_a), ea, ga = search(pa._kernel_mesh, q, 16)
        (lb, pts_b), eb, gb = search(pa._kernel_mesh, q, 1 << 15)
        assert la == lb and (ea, ga) == (eb, gb)
        np.testing.assert_array_equal(pts_a, pts_b)
        overflowed += gb + 3 * pa._kernel_mesh.max_sides + 4 > 16
    assert overflowed > 0


# ------------------------------------------------------------------------------ mesh files
def test_mesh_reader_names_file_and_line(tmp_path):
    f = tmp_path / "bad.mesh"
    f.write_text("mesh\n3\n")
    with pytest.raises(InputError, match="version 2") as e:
        NavMesh.read(f)
    assert e.value.line == 1 and str(f) in str(e.value)
    f.write_text("mesh\n2\n3 1\n0 0 1 0\n1 0 1 0\n0 1 x 0\n3 0 1 2 -1 -1 -1\n")
    with pytest.raises(InputError) as e:
        NavMesh.read(f)
    assert e.value.line == 6
    f.write_text("mesh\n2\n3 1\n0 0 1 0\n1 0 1 0\n0 1 1 0\n3 0 1 7 -1 -1 -1\n")
    with pytest.raises(InputError, match="out of range") as e:
        NavMesh.read(f)
    assert e.value.line == 7


def test_clockwise_polygons_and_file_neighbours_agree_with_matched_edges():
    """The same two squares given clockwise with explicit neighbours: same answers."""
    V = [[0, 0], [1, 0], [2, 0], [2, 1], [1, 1], [0, 1]]
    cw = NavMesh(V, [[5, 4, 1, 0], [4, 3, 2, 1]], [[-1, 1, -1, -1], [-1, -1, -1, 0]])
    assert cw.neighbours == TWO.neighbours and cw.polygons == TWO.polygons
    assert Polyanya(cw).distance([0.1, 0.1], [1.9, 0.9]) == pytest.approx(math.hypot(1.8, 0.8))


# ------------------------------------------------------------------------ planar scenarios
#: bundled scenarios whose visibility graph (128-gon circles, many obstacles) takes seconds
_HEAVY = {"circles-2", "circles-3", "map20-3"}


def _scenario_case(name: str) -> None:
    from weldplan.planar.scenarios import load_scenario
    from weldplan.planar.solve import exact_optimum

    sc = load_scenario(name)
    ours = exact_optimum(sc, "segments")
    assert ours.method == "polyanya"
    vg = visibility_shortest_path(sc.world, sc.start, sc.goal, bounds=sc.bounds)
    assert ours.length == pytest.approx(vg.length, rel=1e-9), name
    P = ours.points_array
    np.testing.assert_allclose(P[[0, -1]], [sc.start, sc.goal])
    assert np.all(sc.world.segments_free(P[:-1], P[1:])), name


def _bundled() -> list[str]:
    from weldplan.planar.scenarios import available_scenarios

    return available_scenarios()


@pytest.mark.parametrize("name", [n for n in _bundled() if n not in _HEAVY])
def test_exact_optimum_is_polyanya_and_equals_the_visibility_graph(name):
    _scenario_case(name)


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(_HEAVY))
def test_exact_optimum_equals_the_visibility_graph_on_heavy_scenarios(name):
    _scenario_case(name)


def test_a_map_that_cannot_be_triangulated_is_an_input_error():
    """Found by hypothesis: a rectangle 5e-324 above the frame made Triangle raise RuntimeError
    from inside scenario_navmesh; the user gets weldplan's error naming the cause instead."""
    R = np.array([[0.0, 0.0, 0.5, 1.0], [1.0, 5e-324, 1.5, 2.0]])
    with pytest.raises(InputError, match="cannot be triangulated"):
        scenario_navmesh(Obstacles2D(rectangles=R), (0.0, 0.0, 10.0, 10.0))


def test_a_goal_walled_off_is_unreachable_at_once_with_or_without_pruning():
    # hypothesis's case: the goal (0.5, 0.05) sits in a pocket closed by the frame and two
    # overlapping rectangles; the starved search exhausted memory proving it had no path
    R = np.array(
        [[1.75, 3.890625, 4.09375, 6.78125], [4.640625, 1.53125, 7.0625, 3.96875],
         [2.609375, 0.0, 3.125, 1.28125], [0.0, 0.4375, 2.875, 2.515625]]
    )  # fmt: skip
    mesh = scenario_navmesh(Obstacles2D(rectangles=R), (0.0, 0.0, 10.0, 10.0))
    s, t = (7.198727555460549, 7.892768675185769), (0.5, 0.05)
    world = _framed(R, (0.0, 0.0, 10.0, 10.0))
    assert math.isinf(_vg_length(world, np.array(s), np.array(t), (0.0, 0.0, 10.0, 10.0)))
    for prune in (True, False):
        res = Polyanya(mesh, prune=prune).query(s, t)
        assert math.isinf(res.length) and res.expanded == 0
    # and a goal in the same component is still searched and found
    assert math.isfinite(Polyanya(mesh, prune=False).distance(s, (9.5, 0.5)))
