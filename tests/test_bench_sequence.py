"""``weldplan bench sequence`` runs end to end on a small configuration and writes its tables."""

from __future__ import annotations

from pathlib import Path

from conftest import require_shared

from weldplan.cli import main


def test_bench_sequence_quick(tmp_path: Path) -> None:
    data = require_shared("tsplib")
    rc = main(
        [
            "bench",
            "sequence",
            "--out",
            str(tmp_path),
            "--data",
            str(data),
            "--instances",
            "att48",
            "--budget",
            "0.2",
            "--ortools-time",
            "0.2",
            "--paper-seeds",
            "1",
            "--hk-sizes",
            "8",
        ]
    )
    assert rc == 0
    md = (tmp_path / "sequence.md").read_text()
    assert "| att48 | 48 | 10628 | 10628 |" in md
    assert "Held-Karp: 595.10 mm" in md and "the paper's order: yes" in md
    assert "| + polish | 1 / 1 |" in md
    assert "| 8 |" in md and "load average" in md
    png = tmp_path / "sequence-convergence.png"
    assert png.stat().st_size > 1000 and png.read_bytes()[:4] == b"\x89PNG"
