"""`weldplan planar` and `weldplan bench planar` end to end on tiny budgets."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import pytest

from weldplan.cli import main
from weldplan.optim import registry
from weldplan.planar.solve import PlanarRun


@pytest.fixture
def local_search(monkeypatch: pytest.MonkeyPatch) -> str:
    """Register the tests' tiny local search so the CLI has an optimiser on any branch."""
    monkeypatch.setitem(
        registry.ALGORITHMS, "test-local", "tests.test_planar_encodings:LocalSearch"
    )
    return "test-local"


@pytest.mark.slow
def test_planar_prints_metrics_and_plots(tmp_path: Path, local_search: str, capsys) -> None:
    png = tmp_path / "p.png"
    rc = main(
        [
            "planar",
            "circles-1",
            "--algorithm",
            local_search,
            "--seed",
            "3",
            "--iters",
            "20",
            "--plot",
            str(png),
        ]
    )
    out = capsys.readouterr().out
    assert rc == 0
    for word in ("length", "optimum", "gap", "smoothness", "success", "time"):
        assert word in out
    assert "28.88" in out  # the exact optimum of circles-1
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_planar_json_round_trip_and_seed(local_search: str, capsys) -> None:
    runs = []
    for _ in range(2):
        assert (
            main(["planar", "map20-1", "-a", local_search, "--seed", "5", "--iters", "5", "--json"])
            == 0
        )
        runs.append(PlanarRun.from_json(capsys.readouterr().out))
    a, b = runs
    assert a.points == b.points and a.length == b.length  # same seed, same path
    assert a.encoding == "segments" and a.n_eval > 0
    assert PlanarRun.from_json(a.to_json()) == a
    assert json.loads(a.to_json())["scenario"] == "map20-1"


def test_planar_bad_input_is_one_line(tmp_path: Path, local_search: str, capsys) -> None:
    assert main(["planar", "circles-1", "--algorithm", "nope"]) == 2
    err = capsys.readouterr().err
    assert "unknown algorithm 'nope'" in err and "--algorithm" in err and "Traceback" not in err
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"bounds": [0, 0, 5, 5], "start": [9, 1], "goal": [4, 4]}))
    assert main(["planar", str(bad), "--algorithm", local_search]) == 2
    err = capsys.readouterr().err
    assert "field 'start'" in err and "outside the bounds" in err
    assert main(["planar", "no-such-map", "--algorithm", local_search]) == 2
    assert main(["planar", "circles-1", "--algorithm", "pso", "--init", "problem"]) == 2
    err = capsys.readouterr().err
    assert "--init" in err and "'pso'" in err and "Traceback" not in err


def test_planar_init_problem_seeds_lrsma(capsys) -> None:
    """`--init problem` reaches the optimiser: seeded LRSMA on circles-3 with a starved budget
    lands in the optimal corridor, the uniform start with the same seed does not do better."""
    got = {}
    for init in ("uniform", "problem"):
        argv = ["planar", "circles-3", "-a", "lrsma", "--seed", "1", "--iters", "5", "--json"]
        assert main([*argv, "--init", init]) == 0
        got[init] = PlanarRun.from_json(capsys.readouterr().out)
    assert got["problem"].success
    assert got["problem"].gap < 0.05
    assert got["problem"].length <= got["uniform"].length


@pytest.mark.slow
def test_bench_planar_tiny(tmp_path: Path, local_search: str, monkeypatch) -> None:
    from weldplan.bench import planar
    from weldplan.bench import planar_papers as bench

    monkeypatch.setattr(bench, "P000_ALGOS", [local_search])
    monkeypatch.setattr(bench, "P000_MAPS", ["circles-1"])
    monkeypatch.setattr(bench, "P000_VARIANTS", [(f"{local_search}+x", local_search, {})])
    import weldplan.planar.solve as solve_mod

    monkeypatch.setattr(solve_mod, "spline_encoding_optimum", lambda sc: 28.889)
    monkeypatch.setattr(
        bench,
        "P003_ALGOS",
        [("LS", local_search, "rotated"), ("LS(ori)", local_search, "original")],
    )
    monkeypatch.setattr(bench, "P001_ALGOS", [local_search])
    monkeypatch.setattr(bench, "P001_MAPS", ["grid20"])
    args = argparse.Namespace(
        out=str(tmp_path),
        protocols="000,003,001",
        runs=2,
        runs_003=1,
        runs_001=1,
        iters_003=3,
        maps_003="map20-2",
        jobs=1,
        exact_seconds=1.0,
        mesh_seconds=1.0,
        data=None,
    )
    assert planar.run(args) == 0
    md = (tmp_path / "planar.md").read_text()
    assert "Paper 000 Table 3" in md and "Paper 003" in md and "Paper 001" in md
    assert "| circles-1 | 28.884 |" in md
    pngs = sorted(p.name for p in tmp_path.glob("*.png"))
    assert "p000-circles-1-paths.png" in pngs and "p003-map20-2-convergence.png" in pngs
    # the default pipeline beside the papers' algorithms: a row in 000 and 001, a column in 003
    assert "| circles-1 | 28.884 | 28.889 | DEFAULT |" in md and "| grid20 |" in md
    assert "| DEFAULT |" in md.split("Paper 001")[1]
    assert "| Default |" in md.split("Paper 003")[1].splitlines()[4]


@pytest.mark.slow
def test_bench_planar_defaults_protocol(tmp_path: Path, monkeypatch) -> None:
    from weldplan.bench import planar
    from weldplan.planar import scenarios

    monkeypatch.setattr(scenarios, "available_scenarios", lambda: ["map20-4"])
    args = argparse.Namespace(out=str(tmp_path), protocols="defaults", runs_defaults=1, jobs=1)
    assert planar.run(args) == 0
    md = (tmp_path / "planar.md").read_text()
    row = next(x for x in md.splitlines() if x.startswith("| map20-4 |"))
    cells = [c.strip() for c in row.strip("|").split("|")]
    assert cells[1] == "45.736"  # the exact any-angle optimum
    assert cells[2] == "+0.00 %" and cells[4] == "0"  # default: optimal, no collision
    assert cells[10] == "1"  # as printed, the segment encoding collides here
