"""The default planar pipeline (seeded optimiser, repair, polish) against the exact optimum, and
the papers' algorithms as printed, bit for bit."""

from __future__ import annotations

import numpy as np
import pytest

from weldplan.cli import main
from weldplan.errors import ConfigError
from weldplan.geometry.pathmetrics import measure
from weldplan.optim.core import minimize
from weldplan.optim.registry import get_optimizer
from weldplan.planar.encodings import make_problem
from weldplan.planar.freespace import free_space_mesh
from weldplan.planar.pipeline import STAGES, polish_path, repair_path
from weldplan.planar.scenarios import load_scenario
from weldplan.planar.solve import PlanarRun, PlanarSettings, exact_optimum, solve


def _check_default(name: str, seed: int) -> PlanarRun:
    sc = load_scenario(name)
    r = solve(sc, "lrsma", rng=seed)
    assert r.pipeline == "default"
    assert tuple(s.name for s in r.stages) == STAGES
    # the independent check, re-run here on the returned points
    m = measure(np.array(r.points), sc.world)
    assert m.collisions == 0 and r.collisions == 0 and r.success
    assert r.stages[-1].length == pytest.approx(r.length, rel=1e-12)
    assert r.optimum == pytest.approx(exact_optimum(sc, "segments").length, rel=1e-12)
    assert r.gap <= 0.03
    assert np.allclose(r.points[0], sc.start) and np.allclose(r.points[-1], sc.goal)
    return r


@pytest.mark.parametrize(("name", "seed"), [("map20-4", 0), ("circles-1", 1)])
def test_default_is_collision_free_and_within_3_percent(name: str, seed: int) -> None:
    r = _check_default(name, seed)
    if name == "map20-4":  # every segment-encoded optimiser collides here on its own
        assert r.stages[0].collisions > 0 and r.stages[1].collisions == 0


@pytest.mark.slow
@pytest.mark.parametrize("name", ["circles-3", "grid20", "map20-7", "map50-2"])
@pytest.mark.parametrize("seed", [0, 1])
def test_default_within_3_percent_on_more_maps(name: str, seed: int) -> None:
    _check_default(name, seed)


def test_repair_then_polish_turn_the_straight_line_into_the_optimum() -> None:
    """map20-4's walls block the straight line; on a map of polygons the taut path in the
    optimal corridor is the exact any-angle optimum (visibility graph)."""
    sc = load_scenario("map20-4")
    fs = free_space_mesh(sc)
    line = np.stack([sc.start, sc.goal])
    assert measure(line, sc.world).collisions == 1
    R, note = repair_path(line, fs, sc.world)
    assert "1 stretch" in note
    assert measure(R, sc.world).collisions == 0
    Q = polish_path(R, fs)
    mq = measure(Q, sc.world)
    assert mq.collisions == 0
    assert mq.length == pytest.approx(exact_optimum(sc, "segments").length, rel=1e-9)
    assert mq.length < measure(R, sc.world).length


def test_repair_leaves_a_free_path_alone() -> None:
    sc = load_scenario("map20-1")
    P = exact_optimum(sc, "segments").points_array
    R, note = repair_path(P, free_space_mesh(sc), sc.world)
    assert note == "nothing to repair" and np.array_equal(R, P)


def test_as_printed_is_the_optimiser_alone_bit_for_bit() -> None:
    """The paper's algorithm with the paper's budget, as ``minimize`` gives it directly."""
    sc = load_scenario("map20-1")
    r = solve(sc, "pso", rng=7, pop_size=12, max_iter=15, as_printed=True)
    prob = make_problem(sc)
    res = minimize(prob, get_optimizer("pso", pop_size=12), max_iter=15, rng=7)
    assert r.pipeline == "as-printed" and r.stages == ()
    assert np.array_equal(np.array(r.points), prob.path(res.x_array))
    assert r.history == res.history and r.n_eval == res.n_eval and r.fitness == res.f
    assert r.optimum_method == exact_optimum(sc).method


def test_a_settings_object_and_its_keywords_are_one_run() -> None:
    sc = load_scenario("map20-1")
    st = PlanarSettings(pop_size=12, max_iter=15, as_printed=True, with_optimum=False)
    a = solve(sc, "pso", st, rng=7)
    b = solve(sc, "pso", rng=7, pop_size=12, max_iter=15, as_printed=True, with_optimum=False)
    c = solve(sc, "pso", PlanarSettings(pop_size=3), rng=7, pop_size=12, max_iter=15,
              as_printed=True, with_optimum=False)  # fmt: skip
    assert a.points == b.points == c.points and a.n_eval == b.n_eval == 12 * 16
    with pytest.raises(ConfigError) as info:
        PlanarSettings(max_iter=0)
    assert info.value.field == "max_iter"
    with pytest.raises(TypeError, match="'max_iters'"):
        solve(sc, "pso", max_iters=3)


def test_as_printed_grid_keeps_the_octile_baseline() -> None:
    sc = load_scenario("grid20")
    r = solve(sc, "pso", rng=0, pop_size=8, max_iter=3, as_printed=True)
    assert r.optimum == pytest.approx(exact_optimum(sc, "grid").length)
    assert r.optimum > exact_optimum(sc, "segments").length  # octile > any-angle here


def test_json_round_trip_keeps_the_stages() -> None:
    sc = load_scenario("map20-4")
    r = solve(sc, "pso", rng=1, pop_size=10, max_iter=5)
    back = PlanarRun.from_json(r.to_json())
    assert back == r and back.stages[1].name == "repair"


def test_a_starved_optimiser_shows_in_its_own_stage() -> None:
    """The summary's first stage is the optimiser's own result: starving it shows there, even
    where repair and polish still reach the optimum."""
    sc = load_scenario("circles-2")
    full, starved = [], []
    for seed in range(3):
        full.append(solve(sc, "lrsma", rng=seed, with_optimum=False).stages[0].length)
        s = solve(sc, "lrsma", rng=seed, pop_size=4, max_iter=1, with_optimum=False)
        starved.append(s.stages[0].length)
    assert np.median(starved) > np.median(full)


def test_summary_names_the_pipeline_and_its_stages(capsys) -> None:
    assert main(["planar", "map20-4", "--algorithm", "pso", "--seed", "2", "--iters", "5"]) == 0
    out = capsys.readouterr().out
    assert "pipeline   default" in out
    for stage in STAGES:
        assert f"\n{stage}" in out
    assert "the optimiser's own" in out and "exact any-angle" in out and "gap" in out
    argv = ["planar", "map20-4", "-a", "pso", "--seed", "2", "--iters", "5", "--as-printed"]
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "as printed" in out and "\nrepair" not in out and "\npolish" not in out


def test_free_space_mesh_locates_points_and_outline_crossings() -> None:
    sc = load_scenario("circles-1")
    fs = free_space_mesh(sc)
    centres = sc.obstacles.circles[:, :2]
    tri = fs.locate(np.vstack([sc.start, sc.goal, centres]))
    assert np.all(tri[:2] >= 0) and np.all(tri[2:] == -1)
    # the straight line crosses circles; the exact path's corners only touch outlines
    sc4 = load_scenario("map20-4")
    fs4 = free_space_mesh(sc4)
    assert fs4.crosses_outline(sc4.start[None], sc4.goal[None])[0]
    ex = exact_optimum(sc4, "segments").points_array
    assert not fs4.crosses_outline(ex[:-1], ex[1:]).any()


def test_pinch_points_are_blocked_and_the_default_avoids_them() -> None:
    """grid20 has cells touching only at a corner: no path may squeeze through there."""
    sc = load_scenario("grid20")
    fs = free_space_mesh(sc)
    pinch = sc.world.pinch_points()
    assert len(pinch) == fs.blocked.sum() > 0
    assert np.allclose(np.sort(fs.mesh.nodes[fs.blocked], axis=0), np.sort(pinch, axis=0))
    r = solve(sc, "lrsma", rng=0, with_optimum=False)
    P = np.array(r.points)
    assert np.min(np.linalg.norm(P[:, None] - pinch[None], axis=-1)) > 1e-6
