"""``weldplan bench local --peers``: the blocked pairs, the car2 stations, the summary arithmetic
and a run end to end on the box station."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("ompl")

from route_fixtures import box_part  # noqa: E402

from weldplan.bench import local_peers  # noqa: E402
from weldplan.cli import main  # noqa: E402
from weldplan.io.joints import Joints, read_joints  # noqa: E402
from weldplan.weld.cell import build_cell  # noqa: E402

# A (-40, 0), B (40, 0), C (-40, 60), D (40, -30) about the wall x = 0, |y| <= 50: every pair
# that crosses x = 0 within the wall is blocked (A-B, A-D, B-C, C-D); A-C and B-D stay on a side
BLOCKED = [(0, 1), (0, 3), (1, 2), (2, 3)]


@pytest.fixture(scope="module")
def box_cell():
    xyz = np.array([[-40.0, 0, 0], [40.0, 0, 0], [-40.0, 60, 0], [40.0, -30, 0]])
    return build_cell(box_part(), Joints(ids=("A", "B", "C", "D"), xyz=xyz, directions=None))


def test_blocked_pairs_are_those_behind_the_wall(box_cell):
    assert local_peers.blocked_pairs(box_cell, None) == BLOCKED
    assert local_peers.blocked_pairs(box_cell, 2) == [BLOCKED[0], BLOCKED[-1]]


def test_car2_stations_are_the_joints_nearest_each_station_centroid():
    stations = local_peers.car2_stations(12)
    j = read_joints(local_peers.CAR2_SET)
    prefix = np.array([i.rsplit("-", 1)[0] for i in j.ids])
    names, counts = np.unique(prefix, return_counts=True)
    assert sorted(stations) == sorted(n for n, c in zip(names, counts, strict=True) if c >= 12)
    for name, joints in stations.items():
        assert len(joints) == 12 and all(i.startswith(name + "-") for i in joints.ids)
        mine = prefix == name
        c = j.xyz[mine].mean(axis=0)
        picked = np.isin(np.asarray(j.ids), joints.ids)
        d = np.linalg.norm(j.xyz - c, axis=1)
        assert d[picked].max() <= d[mine & ~picked].min()


def _rec(cell, lengths, times):
    runs = {
        k: {"length": v, "success": v is not None, "wall_s": t, "cpu_s": t / 2, "reason": ""}
        for (k, v), t in zip(lengths.items(), times, strict=True)
    }
    done = [v for v in lengths.values() if v is not None]
    return {"cell": cell, "pair": ["a", "b"], "runs": runs, "best": min(done)}


def test_summary_ratios_against_best_and_reference():
    recs = [
        _rec("x", {"ours": 101.0, "ref": 100.0}, [0.5, 1.0]),
        _rec("x", {"ours": 200.0, "ref": 202.0}, [0.1, 1.0]),
        _rec("x", {"ours": None, "ref": 50.0}, [0.3, 1.0]),
    ]
    s = local_peers.summarise(recs, ["ours", "ref"], "ref")
    assert s["ours"]["solved"] == 2 and s["ours"]["pairs"] == 3
    assert s["ours"]["best_mean"] == pytest.approx((1.01 + 1.0) / 2)
    assert s["ours"]["best_max"] == pytest.approx(1.01)
    assert s["ours"]["within_1pct"] == 2
    assert s["ours"]["ref_mean"] == pytest.approx((1.01 + 200 / 202) / 2)
    assert s["ours"]["wall_median"] == pytest.approx(0.3)
    assert s["ref"]["best_mean"] == pytest.approx((1.0 + 1.01 + 1.0) / 3)
    assert s["ref"]["ref_max"] == pytest.approx(1.0)


def test_bench_local_peers_end_to_end(box_cell, tmp_path: Path, monkeypatch) -> None:
    monkeypatch.setattr(local_peers, "build_cells", lambda spec, size: [("box", box_cell)])
    argv = ["bench", "local", "--peers", "--pairs", "2", "--budgets", "0.05,0.2"]
    rc = main([*argv, "--ompl-planners", "bitstar", "--out", str(tmp_path)])
    assert rc == 0
    data = json.loads((tmp_path / "local-peers.json").read_text())
    cols = [
        "SO-ACO (paper)",
        "SO-ACO + refine",
        "exact (A* + SO)",
        "exact + refine, one class",
        "exact + refine + 2nd class (default)",
        "OMPL BIT* 0.05 s",
        "OMPL BIT* 0.2 s",
    ]
    assert [r["pair"] for r in data["records"]] == [["A", "B"], ["C", "D"]]
    for r in data["records"]:
        assert list(r["runs"]) == cols
        ok = [v["length"] for v in r["runs"].values() if v["success"]]
        assert r["best"] == min(ok)
        # the refinement starts from the same seeded SO-ACO path and is never longer
        runs = r["runs"]
        assert runs["SO-ACO + refine"]["length"] <= runs["SO-ACO (paper)"]["length"] + 1e-9
        exact = runs["exact (A* + SO)"]["length"]
        one = runs["exact + refine, one class"]["length"]
        assert one <= exact + 1e-9
        # the second class is kept only when it refines shorter
        assert runs["exact + refine + 2nd class (default)"]["length"] <= one + 1e-9
    md = (tmp_path / "local-peers.md").read_text()
    assert "| exact + refine + 2nd class (default) | 2/2 |" in md
    assert "Reference: OMPL BIT* 0.2 s" in md
    assert "## Targets" in md and "load average" in md


def test_bench_local_peers_every_pair_in_two_processes(box_cell, tmp_path: Path, monkeypatch):
    # the workers are forked after the patch, so they build the same box cell
    monkeypatch.setattr(local_peers, "build_cells", lambda spec, size: [("box", box_cell)])
    common = ["bench", "local", "--peers", "--pairs", "all", "--budgets", "0.05"]
    common += ["--ompl-planners", "bitstar", "--ours", "exact,default"]
    runs = {}
    for jobs in (1, 2):
        out = tmp_path / f"jobs{jobs}"
        assert main([*common, "--jobs", str(jobs), "--out", str(out)]) == 0
        runs[jobs] = json.loads((out / "local-peers.json").read_text())
    for data in runs.values():
        assert [r["pair"] for r in data["records"]] == [
            [["A", "B", "C", "D"][i], ["A", "B", "C", "D"][j]] for i, j in BLOCKED
        ]
        assert list(data["records"][0]["runs"]) == [
            "exact (A* + SO)",
            "exact + refine + 2nd class (default)",
            "OMPL BIT* 0.05 s",
        ]
    # our planners are deterministic: the same lengths in one process or two
    for a, b in zip(runs[1]["records"], runs[2]["records"], strict=True):
        for col in ("exact (A* + SO)", "exact + refine + 2nd class (default)"):
            assert a["runs"][col]["length"] == pytest.approx(b["runs"][col]["length"], abs=1e-9)
    assert runs[2]["meta"]["jobs"] == 2 and runs[2]["meta"]["pairs_limit"] is None


@pytest.mark.parametrize(
    "bad", [["--pairs", "0"], ["--pairs", "some"], ["--ours", "nope"], ["--jobs", "0"]]
)
def test_bench_local_peers_rejects_bad_options(bad, tmp_path: Path, capsys) -> None:
    rc = main(["bench", "local", "--peers", *bad, "--out", str(tmp_path)])
    assert rc != 0
    assert "Traceback" not in capsys.readouterr().err
