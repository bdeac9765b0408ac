"""The continuous refinement (weldplan.weld.refine) against exact answers on a box."""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh

from weldplan.errors import ConfigError, InputError
from weldplan.geometry.collision import CollisionModel
from weldplan.geometry.pathcore import PathObstacle, polyline_length
from weldplan.weld.refine import REFINE_MARGIN, RefinedPath, RefineSettings, refine_path

R = 5.0  # mm clearance


@pytest.fixture(scope="module")
def cube() -> CollisionModel:
    """A 100 mm cube centred at the origin."""
    return CollisionModel(trimesh.creation.box(extents=(100.0, 100.0, 100.0)))


def fcl(model: CollisionModel):
    return lambda A, B, r: model.segments_free(A, B, r, method="fcl")


def over_the_cube() -> float:
    """Shortest path from (-100, 0, 0) to (100, 0, 0) outside the cube grown by R: in the plane
    y = 0, tangent to the rounded edge at (-50, 50), along z = 55, tangent again (exact)."""
    d = math.hypot(50.0, 50.0)
    alpha = math.pi / 4 + math.asin(R / d)
    return 2.0 * (math.sqrt(d * d - R * R) + R * alpha) + 100.0


def detour() -> np.ndarray:
    """A free, grid-like detour over the cube (360 mm)."""
    return np.array(
        [[-100.0, 0, 0], [-100, 0, 80], [-50, 0, 80], [50, 0, 80], [100, 0, 80], [100, 0, 0]]
    )


def test_collision_model_is_a_path_obstacle(cube: CollisionModel) -> None:
    assert isinstance(cube, PathObstacle)


@pytest.mark.parametrize(("taut", "within"), [(True, 1.001), (False, 1.002)])
def test_refined_path_is_near_the_exact_optimum_and_free(
    cube: CollisionModel, taut: bool, within: float
) -> None:
    P = detour()
    assert cube.path_free(P, R, method="fcl")
    # the sweeps need the contact splits of three levels to wrap the rounded edges of the
    # grown cube; the joint program (default) follows them by itself
    r = refine_path(P, cube, R, check=fcl(cube), final_check=fcl(cube), levels=3, taut=taut)
    best = over_the_cube()
    assert r.refined, r.status
    assert r.input_length == pytest.approx(360.0)
    # a polyline outside the rounded edges is never shorter than the exact optimum
    assert r.length >= best - 1e-6
    assert r.length <= best * within, (r.length, best)
    assert r.shortcut_length <= r.input_length
    assert np.array_equal(r.points[0], P[0]) and np.array_equal(r.points[-1], P[-1])
    assert r.length == pytest.approx(polyline_length(r.points))
    assert cube.path_free(r.points, R, method="fcl")


def test_one_level_is_coarser_on_the_rounded_edges(cube: CollisionModel) -> None:
    kw = {"check": fcl(cube), "final_check": fcl(cube), "taut": False}
    one = refine_path(detour(), cube, R, levels=1, **kw)
    three = refine_path(detour(), cube, R, levels=3, **kw)
    assert three.length < one.length <= over_the_cube() * 1.01


def test_the_joint_program_beats_the_sweeps(cube: CollisionModel) -> None:
    kw = {"check": fcl(cube), "final_check": fcl(cube)}
    sweeps = refine_path(detour(), cube, R, levels=3, taut=False, **kw)
    joint = refine_path(detour(), cube, R, **kw)
    assert over_the_cube() - 1e-6 <= joint.length < sweeps.length


def test_a_starved_budget_stops_at_the_shortcut(cube: CollisionModel) -> None:
    kw = {"check": fcl(cube), "final_check": fcl(cube)}
    starved = refine_path(detour(), cube, R, time_budget=0.0, **kw)
    full = refine_path(detour(), cube, R, **kw)
    # no round of the vertex optimisation ran: the shortcut is what comes back, checked
    assert starved.refined and starved.sweeps == 0
    assert starved.length == pytest.approx(starved.shortcut_length)
    assert starved.length > full.length * 1.05
    assert cube.path_free(starved.points, R, method="fcl")
    # the cap that cut it is said, so the route can be marked not reproducible; the work
    # bounds alone (no cap, or one never reached) are not
    assert starved.clock_stopped
    assert not full.clock_stopped
    assert not refine_path(detour(), cube, R, time_budget=60.0, **kw).clock_stopped


def test_refined_path_touches_the_clearance(cube: CollisionModel) -> None:
    r = refine_path(detour(), cube, R, check=fcl(cube), final_check=fcl(cube))
    # dense samples of the refined segments: the closest comes within a hair of the clearance
    P = r.points
    t = np.linspace(0.0, 1.0, 400)[:, None]
    samples = np.concatenate([a + t * (b - a) for a, b in zip(P[:-1], P[1:], strict=True)])
    dmin = float(cube.clearance(samples).min())
    assert R - 1e-3 <= dmin <= R + 0.25, dmin


def test_a_straight_free_path_is_left_straight(cube: CollisionModel) -> None:
    P = np.array([[-100.0, 0, 80], [0, 0, 80], [100, 0, 80]])
    r = refine_path(P, cube, R)
    assert r.length == pytest.approx(200.0)
    assert len(r.points) == 2


def test_two_points_come_back_unchanged(cube: CollisionModel) -> None:
    P = np.array([[-100.0, 0, 80], [100, 0, 80]])
    r = refine_path(P, cube, R)
    assert not r.refined and np.array_equal(r.points, P)


def test_a_rejecting_final_check_keeps_the_input(cube: CollisionModel) -> None:
    P = detour()
    r = refine_path(P, cube, R, final_check=lambda A, B, rad: np.zeros(len(A), dtype=bool))
    assert not r.refined and "final check" in r.status
    assert np.array_equal(r.points, P)


def test_checks_use_the_margin(cube: CollisionModel) -> None:
    radii: list[float] = []

    def spy(A, B, rad):
        radii.append(rad)
        return cube.segments_free(A, B, rad, method="fcl")

    refine_path(detour(), cube, R, check=spy, final_check=fcl(cube))
    assert set(radii) == {R + REFINE_MARGIN}


def test_round_trip(cube: CollisionModel) -> None:
    r = refine_path(detour(), cube, R)
    back = RefinedPath.from_dict(r.to_dict())
    assert np.array_equal(back.points, r.points) and back.status == r.status


@pytest.mark.parametrize("kw", [{"clearance": float("nan")}, {"clearance": -1.0}])
def test_a_bad_clearance_is_an_input_error(cube: CollisionModel, kw: dict) -> None:
    args = {"clearance": R} | kw
    with pytest.raises(InputError):
        refine_path(detour(), cube, **args)


@pytest.mark.parametrize("kw", [{"margin": math.inf}, {"tol": -1.0}, {"levels": -1}])
def test_bad_settings_are_config_errors_naming_the_field(cube: CollisionModel, kw: dict) -> None:
    with pytest.raises(ConfigError) as info:
        refine_path(detour(), cube, R, **kw)
    assert info.value.field == next(iter(kw))
    with pytest.raises(TypeError, match="'tautt'"):
        refine_path(detour(), cube, R, tautt=False)


def test_a_settings_object_and_its_keywords_refine_the_same(cube: CollisionModel) -> None:
    a = refine_path(detour(), cube, R, RefineSettings(levels=2, taut=False))
    b = refine_path(detour(), cube, R, levels=2, taut=False)
    c = refine_path(detour(), cube, R, RefineSettings(levels=5), levels=2, taut=False)
    assert a.refined and np.array_equal(a.points, b.points) and np.array_equal(a.points, c.points)
    assert a.checks == b.checks == c.checks


def test_bad_points_are_input_errors(cube: CollisionModel) -> None:
    P = detour()
    P[2, 1] = np.nan
    with pytest.raises(InputError):
        refine_path(P, cube, R)
