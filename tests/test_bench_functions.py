"""``weldplan bench functions`` and ``bench mealpy`` on tiny settings: files and figures."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from weldplan.cli import main


def test_bench_functions_writes_table_json_and_plots(tmp_path: Path) -> None:
    argv = ["bench", "functions", "--out", str(tmp_path), "--runs", "2", "--iters", "5"]
    argv += ["--dim", "4", "--algorithms", "sma,pso,random", "--functions", "sphere,rastrigin"]
    assert main(argv) == 0
    md = (tmp_path / "functions.md").read_text()
    assert "| sma |" in md and "| random |" in md and "sphere mean" in md
    data = json.loads((tmp_path / "functions.json").read_text())
    runs = data["results"]["sphere"]["random"]["f"]
    assert len(runs) == 2 and all(v > 0 for v in runs)
    assert data["results"]["rastrigin"]["pso"]["n_eval"] == 30 * 6
    for name in ("sphere", "rastrigin"):
        png = tmp_path / f"convergence-{name}.png"
        assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_bench_functions_shift_and_bad_names(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    argv = ["bench", "functions", "--out", str(tmp_path), "--runs", "1", "--iters", "3"]
    argv += ["--dim", "3", "--algorithms", "sma", "--functions", "sphere", "--shift", "0.5"]
    assert main(argv) == 0
    assert (tmp_path / "convergence-sphere-shifted.png").exists()
    assert main(["bench", "functions", "--out", str(tmp_path), "--algorithms", "nope"]) == 2
    assert "unknown algorithm" in capsys.readouterr().err


def test_bench_mealpy_tiny(tmp_path: Path) -> None:
    pytest.importorskip("mealpy")
    argv = ["bench", "mealpy", "--out", str(tmp_path), "--seeds", "1", "--iters", "3"]
    argv += ["--dim", "5", "--algorithms", "woa", "--functions", "sphere"]
    assert main(argv) == 0
    row = json.loads((tmp_path / "mealpy.json").read_text())["rows"][0]
    assert row["ours"] == "woa" and row["mealpy"] == "OriginalWOA"
    assert row["speedup"] > 0 and row["ours_n_eval"] == 30 * 4
    assert "OriginalWOA" in (tmp_path / "mealpy.md").read_text()
