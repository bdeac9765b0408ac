"""Scenario files: the shipped ones load; bad input names the file and the field."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from weldplan.errors import InputError
from weldplan.planar.scenarios import available_scenarios, load_scenario

GOOD = {
    "bounds": [0, 0, 10, 10],
    "start": [1, 1],
    "goal": [9, 9],
    "obstacles": [
        {"type": "circle", "center": [5, 5], "radius": 1},
        {"type": "rectangle", "min": [2, 6], "max": [3, 8]},
        {"type": "polygon", "vertices": [[6, 1], [8, 1], [7, 3]]},
    ],
}


def _write(tmp_path: Path, data: object, name: str = "s.json") -> Path:
    p = tmp_path / name
    p.write_text(json.dumps(data) if not isinstance(data, str) else data)
    return p


def test_shipped_scenarios_load() -> None:
    names = available_scenarios()
    assert {"circles-1", "circles-2", "circles-3", "map20-4", "map50-1", "building100"} <= set(
        names
    )
    assert sum(n.startswith("map20-") for n in names) == 7
    for n in names:
        sc = load_scenario(n)
        assert sc.obstacles.n_obstacles > 0
        assert not sc.world.contains(sc.start) and not sc.world.contains(sc.goal)
    g = load_scenario("grid20")
    assert g.grid is not None and g.grid.shape == (20, 20)
    assert not g.grid.occupied[0, 0] and not g.grid.occupied[19, 19]


def test_good_file_round_trip(tmp_path: Path) -> None:
    sc = load_scenario(_write(tmp_path, GOOD))
    assert sc.name == "s" and sc.obstacles.n_obstacles == 3
    np.testing.assert_array_equal(sc.start, [1, 1])


@pytest.mark.parametrize(
    "patch, field, words",
    [
        ({"start": [5, 5]}, "start", "inside an obstacle"),
        ({"goal": [11, 5]}, "goal", "outside the bounds"),
        ({"start": [1]}, "start", "shape"),
        (
            {"obstacles": [{"type": "polygon", "vertices": [[0, 0], [2, 2], [2, 0], [0, 2]]}]},
            "obstacles[0].vertices",
            "not simple",
        ),
        ({"obstacles": [{"type": "star", "center": [1, 1]}]}, "obstacles[0].type", "unknown"),
        (
            {"obstacles": [{"type": "circle", "center": [5, 5], "radius": -1}]},
            "obstacles[0].radius",
            "positive",
        ),
        (
            {"obstacles": [{"type": "grid", "rows": ["..#", ".x."]}]},
            "obstacles[0].rows",
            "characters",
        ),
        ({"encoding": "polar"}, "encoding", "unknown encoding"),
        ({"bounds": [0, 0, -1, 10]}, "bounds", "min < max"),
    ],
)
def test_bad_input_names_file_and_field(tmp_path: Path, patch: dict, field: str, words: str):
    p = _write(tmp_path, {**GOOD, **patch})
    with pytest.raises(InputError) as err:
        load_scenario(p)
    assert err.value.field == field
    assert str(p) in str(err.value) and words in str(err.value)


def test_missing_field_and_bad_json(tmp_path: Path) -> None:
    bad = dict(GOOD)
    del bad["goal"]
    with pytest.raises(InputError, match="'goal'"):
        load_scenario(_write(tmp_path, bad))
    with pytest.raises(InputError, match="line 2"):
        load_scenario(_write(tmp_path, '{"bounds": [0, 0, 1, 1],\n "start": [0, 0],,}'))


def test_generator_script_rewrites_the_shipped_files(tmp_path: Path, monkeypatch) -> None:
    import importlib.util

    from weldplan.planar.scenarios import SCENARIO_DIR

    root = Path(__file__).resolve().parents[1]
    spec = importlib.util.spec_from_file_location(
        "make_scenarios", root / "scripts" / "make_scenarios.py"
    )
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    monkeypatch.setattr(mod, "OUT", tmp_path)
    for make in (mod.circle_maps, mod.maps20, mod.maps50, mod.building, mod.grids):
        make()
    made = sorted(p.name for p in tmp_path.glob("*.json"))
    assert made == sorted(p.name for p in SCENARIO_DIR.glob("*.json"))
    for name in made:
        assert (tmp_path / name).read_text() == (SCENARIO_DIR / name).read_text(), name
