"""Joint-to-joint local paths: collision-free, right endpoints, reproducible, honest failures."""

from __future__ import annotations

import math

import numpy as np
import pytest
from _boxcell import J3, J7, BoxCell, box_cell, box_distance, panel_cell
from hypothesis import given, settings
from hypothesis import strategies as st

from weldplan.errors import ConfigError, PlanningError
from weldplan.geometry.collision import CollisionModel
from weldplan.weld.local import (
    LocalParams,
    LocalPath,
    LocalSearchSettings,
    plan_local_path,
    polyline_length,
    secondary_optimization,
)

QUICK = {"n_iterations": 10, "n_ants": 10}


@pytest.fixture(scope="module")
def cell() -> BoxCell:
    return panel_cell()


def analytic_clearance(cell: BoxCell, points: np.ndarray, step: float = 0.25) -> float:
    """Smallest distance (mm) from the polyline to the boxes, sampled every ``step`` mm: a check
    that shares nothing with FCL."""
    worst = math.inf
    for a, b in zip(points[:-1], points[1:], strict=True):
        n = max(2, int(np.linalg.norm(b - a) / step) + 2)
        t = np.linspace(0.0, 1.0, n)[:, None]
        pts = a + t * (b - a)
        for lo, hi in cell.boxes:
            worst = min(worst, float(box_distance(pts, lo, hi).min()))
    return worst


def assert_valid(cell: BoxCell, lp: LocalPath, start, goal, s_idx, g_idx) -> None:
    assert lp.success, lp.reason
    P = lp.points
    assert np.allclose(P[0], start) and np.allclose(P[-1], goal)
    vs, vg = cell.grid.index_to_world(s_idx), cell.grid.index_to_world(g_idx)
    assert np.allclose(P[1], vs) and np.allclose(P[-2], vg)
    inner = P[1:-1]
    # the judge, rebuilt from the mesh, and an analytic distance check
    judge = CollisionModel(cell.collision.mesh.copy())
    assert judge.path_free(inner, cell.grid.clearance)
    assert analytic_clearance(cell, inner) >= cell.grid.clearance - 0.05
    assert lp.length == pytest.approx(polyline_length(P))
    assert lp.inner_length == pytest.approx(polyline_length(inner))
    assert lp.inner_length <= lp.raw_length + 1e-9


@pytest.mark.parametrize("method", ["so-aco", "aco", "exact"])
def test_paths_are_collision_free_between_the_right_joints(cell: BoxCell, method: str) -> None:
    s, g = cell.virtual(J3), cell.virtual(J7)
    lp = plan_local_path(
        cell.grid, cell.collision, J3, J7, s, g, method=method, params=QUICK, rng=3
    )
    assert_valid(cell, lp, J3, J7, s, g)
    assert not lp.fast_path and lp.method == method
    straight = np.linalg.norm(cell.grid.index_to_world(g) - cell.grid.index_to_world(s))
    assert lp.inner_length > straight  # the panel is in the way
    if method == "aco":
        assert lp.so_passes == 0 and lp.inner_length == lp.raw_length
        steps = np.linalg.norm(np.diff(lp.points[1:-1], axis=0), axis=1)
        assert np.allclose(steps, cell.grid.pitch)
    else:
        assert lp.so_passes >= 1
    if method == "exact":
        assert lp.iterations == 0 and lp.evaluations > 0
    else:
        assert lp.iterations == 10 * (lp.repairs + 1) and lp.ants == 10 * lp.iterations
        assert len(lp.history) == lp.iterations


def test_so_aco_is_close_to_the_exact_baseline(cell: BoxCell) -> None:
    s, g = cell.virtual(J3), cell.virtual(J7)
    exact = plan_local_path(cell.grid, cell.collision, J3, J7, s, g, method="exact")
    so = [
        plan_local_path(
            cell.grid, cell.collision, J3, J7, s, g, method="so-aco", params=QUICK, rng=k
        ).inner_length
        for k in range(3)
    ]
    aco = plan_local_path(
        cell.grid, cell.collision, J3, J7, s, g, method="aco", params=QUICK, rng=0
    ).inner_length
    assert max(so) <= 1.05 * exact.inner_length
    assert aco > 1.5 * max(so)  # the secondary optimisation is what makes the path short


def test_same_seed_same_path(cell: BoxCell) -> None:
    s, g = cell.virtual(J3), cell.virtual(J7)
    kw = dict(method="so-aco", params={"n_iterations": 4, "n_ants": 5})
    a = plan_local_path(cell.grid, cell.collision, J3, J7, s, g, rng=7, **kw)
    b = plan_local_path(cell.grid, cell.collision, J3, J7, s, g, rng=7, **kw)
    assert np.array_equal(a.points, b.points) and a.history == b.history and a.seed == 7
    c = plan_local_path(cell.grid, cell.collision, J3, J7, s, g, rng=8, **kw)
    assert c.history != a.history or not np.array_equal(c.points, a.points)


def test_a_settings_object_and_its_keywords_plan_the_same_path(cell: BoxCell) -> None:
    s, g = cell.virtual(J3), cell.virtual(J7)
    st = LocalSearchSettings("so-aco", {"n_iterations": 4, "n_ants": 5})
    assert isinstance(st.params, LocalParams) and st.params.colony.n_ants == 5
    a = plan_local_path(cell.grid, cell.collision, J3, J7, s, g, st, rng=7)
    b = plan_local_path(cell.grid, cell.collision, J3, J7, s, g, rng=7, method="so-aco",
                        params={"n_iterations": 4, "n_ants": 5})  # fmt: skip
    assert np.array_equal(a.points, b.points) and a.history == b.history
    e = plan_local_path(cell.grid, cell.collision, J3, J7, s, g, st, method="exact")
    assert e.method == "exact"
    with pytest.raises(ConfigError) as info:
        LocalSearchSettings(method="rrt")
    assert info.value.field == "method"
    with pytest.raises(TypeError, match="'time_budgett'"):
        plan_local_path(cell.grid, cell.collision, J3, J7, s, g, time_budgett=1.0)


def test_starved_colony_is_measurably_worse(cell: BoxCell) -> None:
    s, g = cell.virtual(J3), cell.virtual(J7)

    def raw(n: int, seed: int) -> float:
        prm = {"n_iterations": n, "n_ants": n}
        lp = plan_local_path(
            cell.grid, cell.collision, J3, J7, s, g, method="aco", params=prm, rng=seed
        )
        return lp.raw_length

    starved = np.mean([raw(2, k) for k in range(4)])
    fed = np.mean([raw(12, k) for k in range(4)])
    assert fed < 0.8 * starved


def test_fast_path_when_the_straight_segment_is_free(cell: BoxCell) -> None:
    a = J3 + np.array([0.0, 0.0, 0.0])
    b = J3 + np.array([0.0, 30.0, 20.0])
    sa, sb = cell.virtual(a), cell.virtual(b)
    for method in ("so-aco", "exact"):
        lp = plan_local_path(cell.grid, cell.collision, a, b, sa, sb, method=method, rng=0)
        assert lp.success and lp.fast_path and lp.reason == "straight segment free"
        assert lp.iterations == 0 and lp.evaluations == 0 and lp.collision_checks == 1
        assert len(lp.points) == 4
        assert lp.inner_length == pytest.approx(
            np.linalg.norm(cell.grid.index_to_world(sb) - cell.grid.index_to_world(sa))
        )


def test_same_virtual_joint() -> None:
    c = panel_cell()
    s = c.virtual(J3)
    lp = plan_local_path(c.grid, c.collision, J3, J3 + 0.5, s, s, method="exact")
    assert lp.success and lp.fast_path and lp.inner_length == 0.0


def hollow_box_cell() -> tuple[BoxCell, np.ndarray, np.ndarray]:
    """A closed 60 mm box (walls 2 mm) with the goal inside and the start outside."""
    c, h, t = np.array([60.0, 0.0, 0.0]), 30.0, 2.0
    walls = []
    for axis in range(3):
        for sign in (-1, 1):
            lo, hi = c - h, c + h
            lo = lo.copy()
            hi = hi.copy()
            if sign < 0:
                hi[axis] = lo[axis] + t
            else:
                lo[axis] = hi[axis] - t
            walls.append((lo, hi))
    cell = box_cell(walls, np.array([-20.0, -45.0, -45.0]), np.array([105.0, 45.0, 45.0]))
    return cell, np.array([-10.0, 0.0, 0.0]), c


@pytest.mark.parametrize("method", ["so-aco", "aco", "exact"])
def test_enclosed_goal_fails_with_a_reason(method: str) -> None:
    cell, a, b = hollow_box_cell()
    sa, sb = cell.virtual(a), cell.virtual(b)
    lp = plan_local_path(cell.grid, cell.collision, a, b, sa, sb, method=method, params=QUICK)
    assert not lp.success and "not reachable" in lp.reason
    assert len(lp.points) == 0 and math.isinf(lp.length)
    LocalPath.from_json(lp.to_json())  # failures serialise too


def test_goal_cut_off_by_the_region_of_interest() -> None:
    # a wall wider than the region splits the grid in two
    wall = (np.array([48.0, -100.0, -100.0]), np.array([52.0, 100.0, 100.0]))
    cell = box_cell([wall], np.array([0.0, -20.0, -20.0]), np.array([100.0, 20.0, 20.0]))
    a, b = np.array([10.0, 0.0, 0.0]), np.array([90.0, 0.0, 0.0])
    lp = plan_local_path(
        cell.grid, cell.collision, a, b, cell.virtual(a), cell.virtual(b), method="so-aco"
    )
    assert not lp.success and "region of interest" in lp.reason
    with pytest.raises(PlanningError, match="outside the grid"):
        plan_local_path(cell.grid, cell.collision, a, b, cell.virtual(a), (99, 0, 0))
    occupied = np.argwhere(cell.grid.occupied)[0]
    with pytest.raises(PlanningError, match="not a free voxel"):
        plan_local_path(cell.grid, cell.collision, a, b, cell.virtual(a), occupied)


def test_time_budget_is_honoured(cell: BoxCell) -> None:
    s, g = cell.virtual(J3), cell.virtual(J7)
    prm = {"n_iterations": 100_000, "n_ants": 50}
    lp = plan_local_path(
        cell.grid, cell.collision, J3, J7, s, g, method="so-aco", params=prm, rng=0,
        time_budget=0.3,
    )  # fmt: skip
    assert lp.iterations < 100_000
    if lp.success:
        assert_valid(cell, lp, J3, J7, s, g)
    else:
        assert "time budget" in lp.reason


def test_local_path_json_round_trip(cell: BoxCell) -> None:
    s, g = cell.virtual(J3), cell.virtual(J7)
    lp = plan_local_path(cell.grid, cell.collision, J3, J7, s, g, method="exact")
    back = LocalPath.from_json(lp.to_json())
    assert np.array_equal(back.points, lp.points)
    assert back.to_dict() == lp.to_dict()
    with pytest.raises(ValueError):
        lp.points[0, 0] = 1.0  # read-only


def test_params_coercion() -> None:
    p = LocalParams.coerce({"n_iterations": 3, "beta": 2.0, "max_repairs": 1})
    assert p.colony.n_iterations == 3 and p.colony.beta == 2.0 and p.max_repairs == 1
    with pytest.raises(ValueError, match="unknown"):
        LocalParams.coerce({"iterations": 3})
    with pytest.raises(ValueError, match="method"):
        plan_local_path(None, None, J3, J7, (0, 0, 0), (0, 0, 0), method="astar")  # type: ignore[arg-type]


# ------------------------------------------------------------------ secondary optimisation


def test_so_straightens_a_staircase_in_free_space() -> None:
    pts = np.array([[0, 0, 0], [5, 0, 0], [5, 5, 0], [10, 5, 0], [10, 10, 0]], dtype=float)
    r = secondary_optimization(pts, lambda a, b: True)
    assert np.array_equal(r.points, pts[[0, -1]]) and r.converged


def test_so_keeps_the_corner_around_an_obstacle() -> None:
    # an L route around a square obstacle [1, 9] x [1, 9] in the plane: no shortcut crosses it
    def free(a, b) -> bool:
        t = np.linspace(0, 1, 200)[:, None]
        p = a + t * (b - a)
        return not np.any((p[:, 0] > 1) & (p[:, 0] < 9) & (p[:, 1] > 1) & (p[:, 1] < 9))

    pts = np.array([[0, 0, 0], [0, 5, 0], [0, 10, 0], [5, 10, 0], [10, 10, 0]], dtype=float)
    r = secondary_optimization(pts, free)
    assert r.points[0].tolist() == [0, 0, 0] and r.points[-1].tolist() == [10, 10, 0]
    assert polyline_length(r.points) <= polyline_length(pts)
    assert polyline_length(r.points) > math.hypot(10, 10)
    assert all(free(a, b) for a, b in zip(r.points[:-1], r.points[1:], strict=True))


@settings(max_examples=40, deadline=None)
@given(
    st.lists(st.tuples(*[st.floats(-50, 50, allow_nan=False)] * 3), min_size=2, max_size=12),
    st.floats(1.0, 30.0),
)
def test_so_never_lengthens_a_route(raw, radius) -> None:
    # segments are free when they keep `radius` away from the z axis (a pole)
    def free(a, b) -> bool:
        t = np.linspace(0, 1, 64)[:, None]
        p = a + t * (b - a)
        return bool(np.all(np.hypot(p[:, 0], p[:, 1]) >= radius))

    pts = np.asarray(raw, dtype=float)
    r = secondary_optimization(pts, free, max_passes=20)
    assert polyline_length(r.points) <= polyline_length(pts) + 1e-9
    assert np.array_equal(r.points[0], pts[0]) and np.array_equal(r.points[-1], pts[-1])


def test_adjacent_check_reports_the_grazing_move() -> None:
    pts = np.array([[0, 0, 0], [5, 0, 0], [10, 0, 0]], dtype=float)

    def free(a, b) -> bool:
        return max(a[0], b[0]) <= 5  # everything beyond x = 5 is blocked: move 1 -> 2 is bad

    r = secondary_optimization(pts, free, check_adjacent=True)
    assert r.bad_segment == 1 and np.array_equal(r.points, pts)
    assert secondary_optimization(pts, free).bad_segment is None


def test_exact_with_and_without_corner_cutting(cell: BoxCell) -> None:
    s, g = cell.virtual(J3), cell.virtual(J7)
    cut = plan_local_path(
        cell.grid, cell.collision, J3, J7, s, g, method="exact", params={"corner_cutting": True}
    )
    no_cut = plan_local_path(cell.grid, cell.collision, J3, J7, s, g, method="exact")
    assert_valid(cell, cut, J3, J7, s, g)
    assert_valid(cell, no_cut, J3, J7, s, g)
    assert cut.raw_length <= no_cut.raw_length  # the plain lattice is the less constrained


# ------------------------------------------------------------------------------ the demo cell


@pytest.fixture(scope="module")
def demo():
    from weldplan.weld.cell import demo_cell

    return demo_cell()


@pytest.mark.slow
@pytest.mark.parametrize("method", ["so-aco", "exact"])
def test_demo_pair_3_to_7(demo, method: str) -> None:
    from weldplan.weld.local import plan_pair

    ids = list(demo.joints.ids)
    i, j = ids.index("3"), ids.index("7")
    lp = plan_pair(demo, i, j, method=method, params=QUICK, rng=0)
    assert lp.success and not lp.fast_path  # the demo part blocks the straight line
    P = lp.points
    assert np.allclose(P[0], demo.joints.xyz[i]) and np.allclose(P[-1], demo.joints.xyz[j])
    assert np.allclose(P[1], demo.virtual_xyz[i]) and np.allclose(P[-2], demo.virtual_xyz[j])
    inner = P[1:-1]
    r = demo.clearance
    # fcl (the judge) and open3d sphere tracing (an independent distance-based check)
    assert demo.collision.path_free(inner, r, method="fcl")
    assert demo.collision.path_free(inner, r, method="auto")
    straight = np.linalg.norm(demo.virtual_xyz[j] - demo.virtual_xyz[i])
    assert straight < lp.inner_length < 1.25 * straight


@pytest.mark.slow
def test_demo_fast_path_and_bad_indices(demo) -> None:
    from weldplan.weld.local import plan_pair

    V = demo.virtual_xyz
    pairs = [
        (a, b)
        for a in range(len(V))
        for b in range(a + 1, len(V))
        if demo.collision.segment_free(V[a], V[b], demo.clearance)
    ]
    a, b = pairs[0]
    lp = plan_pair(demo, a, b, method="so-aco", rng=0)
    assert lp.fast_path and lp.success and lp.iterations == 0
    assert lp.inner_length == pytest.approx(np.linalg.norm(V[b] - V[a]))
    with pytest.raises(IndexError):
        plan_pair(demo, 0, len(V))


def test_fcl_capsule_orientation_matches_the_rotation_matrix_form() -> None:
    # the scalar quaternion in CollisionModel._fcl_segment_free against the matrix construction
    import fcl
    import trimesh

    from weldplan.geometry.collision import _rotation_z_to

    mesh = trimesh.creation.box(extents=(60.0, 4.0, 80.0))
    mesh.apply_translation([3.0, 1.0, -2.0])
    cm = CollisionModel(mesh)
    rng = np.random.default_rng(0)
    A = rng.uniform(-60, 60, (600, 3))
    B = rng.uniform(-60, 60, (600, 3))
    B[::5] = A[::5] + np.array([0.0, 0.0, 30.0]) * rng.choice([-1, 1], (120, 1))  # +-z axis
    got = cm.segments_free(A, B, 5.0, method="fcl")
    want = []
    for a, b in zip(A, B, strict=True):
        d = b - a
        L = float(np.linalg.norm(d))
        tf = fcl.Transform(_rotation_z_to(d / L), 0.5 * (a + b))
        obj = fcl.CollisionObject(fcl.Capsule(5.0, L), tf)
        want.append(fcl.collide(obj, cm._part, fcl.CollisionRequest(), fcl.CollisionResult()) == 0)
    assert np.array_equal(got, want) and 0 < got.sum() < len(got)
