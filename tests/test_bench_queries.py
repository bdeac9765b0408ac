"""``weldplan bench queries``: counts against the file's lengths, the CSV, one-line errors."""

from __future__ import annotations

import csv
import math

import numpy as np
import pytest

from tests.cli_helpers import run_cli
from tests.conftest import require_shared
from weldplan.bench.queries import read_queries
from weldplan.errors import InputError

#: two unit squares side by side, as a Polyanya .mesh v2 file
TWO_SQUARES = """mesh
2
6 2
0 0 1 0
1 0 2 1 0
2 0 1 1
2 1 1 1
1 1 2 0 1
0 1 1 0
4 0 1 4 5 -1 -1 1 -1
4 1 2 3 4 0 -1 -1 -1
"""


def _scen(rows: list[tuple[float, float, float, float, str]]) -> str:
    lines = ["version 1"]
    for sx, sy, gx, gy, length in rows:
        lines.append(f"0\tm.map\t2\t1\t{sx:g}\t{sy:g}\t{gx:g}\t{gy:g}\t{length}")
    return "\n".join(lines) + "\n"


def test_counts_equal_shorter_longer_and_no_path(tmp_path, capsys):
    mesh = tmp_path / "two.mesh"
    mesh.write_text(TWO_SQUARES)
    scen = tmp_path / "two.scen"
    # exact 2.0 (within 1e-6), a reference too long (ours shorter), one too short (ours
    # longer), and a goal off the mesh (no path)
    scen.write_text(
        _scen([(0, 0, 2, 0, "2.0000001"), (0, 0, 2, 1, "3"), (0, 0, 1, 1, "1"), (0, 0, 5, 5, "9")])
    )
    out_csv = tmp_path / "q.csv"
    assert run_cli(["bench", "queries", str(mesh), str(scen), "--csv", str(out_csv)]) == 0
    out = capsys.readouterr().out
    assert "4 queries, any-angle" in out
    assert "equal to the file's" in out and ": 1, shorter: 1, longer: 1, no path: 1" in out
    rows = list(csv.DictReader(out_csv.open()))
    assert list(rows[0]) == ["index", "sx", "sy", "gx", "gy", "reference", "length", "ms"]
    L = [float(r["length"]) for r in rows]
    assert L[0] == pytest.approx(2.0) and L[1] == pytest.approx(math.sqrt(5))
    assert L[2] == pytest.approx(math.sqrt(2)) and math.isnan(L[3])


def test_printed_digits_count_as_equal():
    """Moving AI files print 6 significant digits: 5.24264 equals 3 + 1.5 sqrt 2 (5.2426407),
    but "1" is 1.00000, not anything within a unit."""
    q_text = _scen([(0, 0, 1, 1, "5.24264"), (0, 0, 1, 1, "1")])
    import tempfile
    from pathlib import Path

    with tempfile.TemporaryDirectory() as d:
        f = Path(d) / "x.scen"
        f.write_text(q_text)
        q = read_queries(f)
    assert q.resolution[0] == pytest.approx(1e-5) and q.resolution[1] == pytest.approx(1e-5)


def test_arena_octile_and_any_angle(capsys):
    folder = require_shared("movingai")
    argv = ["bench", "queries", str(folder / "arena.map"), str(folder / "arena.map.scen")]
    assert run_cli(argv) == 0
    out = capsys.readouterr().out
    assert "160 queries, octile" in out and ": 160, shorter: 0, longer: 0, no path: 0" in out
    mesh = require_shared("meshmaps", "arena.mesh")
    aa = require_shared("meshmaps", "arena.mesh.anyangle.scen")
    assert run_cli(["bench", "queries", str(mesh), str(aa)]) == 0
    out = capsys.readouterr().out
    assert "160 queries, any-angle" in out and ": 160, shorter: 0, longer: 0, no path: 0" in out


def test_bad_files_are_one_line_errors(tmp_path, capsys):
    mesh = tmp_path / "two.mesh"
    mesh.write_text(TWO_SQUARES)
    scen = tmp_path / "bad.scen"
    scen.write_text("version 1\n0\tm.map\t2\t1\t0\t0\t1\tx\t1.0\n")
    assert run_cli(["bench", "queries", str(mesh), str(scen)]) == 2
    err = [ln for ln in capsys.readouterr().err.splitlines() if ln.strip()]
    assert len(err) == 1 and "bad.scen" in err[0] and "2" in err[0] and "goal y" in err[0]
    bad_mesh = tmp_path / "bad.mesh"
    bad_mesh.write_text(TWO_SQUARES.replace("4 1 2 3 4 0", "4 1 2 3 x 0"))
    scen.write_text(_scen([(0, 0, 2, 0, "2")]))
    assert run_cli(["bench", "queries", str(bad_mesh), str(scen)]) == 2
    err = [ln for ln in capsys.readouterr().err.splitlines() if ln.strip()]
    assert len(err) == 1 and "bad.mesh" in err[0] and "11" in err[0]
    assert run_cli(["bench", "queries", str(mesh), str(scen), "--metric", "octile"]) == 2
    assert "octile" in capsys.readouterr().err
    with pytest.raises(InputError):
        read_queries(tmp_path / "missing.scen")


def test_queries_keep_float_coordinates(tmp_path):
    f = tmp_path / "f.scen"
    f.write_text(_scen([(0.5, 0.25, 1.5, 0.75, "1.1180339887")]))
    q = read_queries(f)
    np.testing.assert_allclose(q.start, [[0.5, 0.25]])
    np.testing.assert_allclose(q.goal, [[1.5, 0.75]])
    assert q.line.tolist() == [2]
