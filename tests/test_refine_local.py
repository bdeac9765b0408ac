"""The continuous refinement inside the local planners and the pipeline (issue 15 item 1)."""

from __future__ import annotations

import argparse

import numpy as np
import pytest
from _boxcell import J3, J7, BoxCell, panel_cell
from test_local import analytic_clearance

from weldplan.geometry.collision import CollisionModel
from weldplan.weld.local import LocalParams, plan_local_path, polyline_length


@pytest.fixture(scope="module")
def cell() -> BoxCell:
    return panel_cell()


def plan(cell: BoxCell, method: str, **params):
    s, g = cell.virtual(J3), cell.virtual(J7)
    return plan_local_path(
        cell.grid, cell.collision, J3, J7, s, g, method=method, rng=0,
        params={"n_iterations": 10, "n_ants": 10, **params},
    )  # fmt: skip


@pytest.mark.parametrize("method", ["exact", "so-aco"])
def test_refined_path_is_shorter_free_and_touches_the_clearance(cell: BoxCell, method) -> None:
    plain = plan(cell, method)
    lp = plan(cell, method, refine=True)
    assert plain.success and lp.success
    assert not plain.refined and plain.inner_length == pytest.approx(plain.so_length)
    assert lp.refined
    assert lp.so_length == pytest.approx(plain.inner_length)  # the same grid path went in
    # the panel's edge is a straight line: the refined path wraps it closer than grid points
    assert lp.inner_length < lp.so_length - 0.5, (lp.inner_length, lp.so_length)
    inner = lp.points[1:-1]
    assert np.allclose(lp.points[[0, -1]], [J3, J7])
    assert lp.inner_length == pytest.approx(polyline_length(inner))
    judge = CollisionModel(cell.collision.mesh.copy())
    assert judge.path_free(inner, cell.grid.clearance, method="fcl")
    # an analytic distance check that shares nothing with FCL: never inside, and within a
    # fraction of a millimetre of the clearance (the grid path kept a voxel's distance)
    worst = analytic_clearance(cell, inner, step=0.05)
    assert cell.grid.clearance - 1e-6 <= worst <= cell.grid.clearance + 0.1, worst
    assert analytic_clearance(cell, plain.points[1:-1], step=0.05) > worst


def test_refine_is_off_in_the_planner_defaults(cell: BoxCell) -> None:
    assert LocalParams().refine is False
    assert LocalParams.coerce({"refine": True}).refine is True


def test_the_pipeline_refines_by_default_and_one_flag_turns_it_off() -> None:
    from weldplan.commands._planning import add_planning_arguments, config_from_args
    from weldplan.weld.pipeline import PlanConfig

    assert PlanConfig().aco["refine"] is True
    assert PlanConfig(refine=False).aco["refine"] is False
    assert PlanConfig(refine=False, aco={"refine": True}).aco["refine"] is True
    p = argparse.ArgumentParser()
    add_planning_arguments(p, default_output="route.csv")
    assert config_from_args(p.parse_args([])).aco["refine"] is True
    assert config_from_args(p.parse_args(["--no-refine"])).aco["refine"] is False


def test_refine_must_be_a_flag() -> None:
    from weldplan.errors import ConfigError
    from weldplan.weld.pipeline import PlanConfig

    with pytest.raises(ConfigError):
        PlanConfig(refine="yes")  # type: ignore[arg-type]


def test_refine_local_path_matches_the_planner_stage(cell: BoxCell) -> None:
    from weldplan.weld.refine import refine_local_path

    plain = plan(cell, "exact")
    inline = plan(cell, "exact", refine=True)
    apart = refine_local_path(cell, plain)
    assert apart.refined and apart.so_length == pytest.approx(plain.inner_length)
    assert apart.inner_length == pytest.approx(inline.inner_length, abs=1e-9)
    assert np.allclose(apart.points, inline.points)
    assert refine_local_path(cell, apart) is apart
