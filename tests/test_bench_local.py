"""``weldplan bench local`` runs end to end and writes its table and plot."""

from __future__ import annotations

from pathlib import Path

import pytest

from weldplan.bench import local as bench_local
from weldplan.cli import main


def test_bench_local_quick_writes_table_and_plot(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.setattr(bench_local, "QUICK_SIZES", ((2, 2), (3, 3)))
    rc = main(["bench", "local", "--quick", "--runs", "2", "--out", str(tmp_path)])
    assert rc == 0
    md = (tmp_path / "local.md").read_text()
    assert "| 2 | 2 | ACO |" in md and "| 3 | 3 | SO-ACO |" in md
    assert "Exact baseline" in md and "Load average" in md
    png = tmp_path / "local-convergence.png"
    assert png.stat().st_size > 1000 and png.read_bytes()[:4] == b"\x89PNG"
    import json

    data = json.loads((tmp_path / "local.json").read_text())
    rows = data["rows"]
    assert len(rows) == 4 and all(r["runs"] == 2 for r in rows)
    for aco, so in zip(rows[::2], rows[1::2], strict=True):
        assert so["length"]["mean"] <= aco["length"]["mean"]
    assert data["straight_real"] == pytest.approx(202.91, abs=0.01)
