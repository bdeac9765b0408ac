"""Whole-body scale (issue #18 item 3): candidate-neighbour planning on a piece of the synthetic
4000-joint car2 set gives a verified route above its proved bound; the bench's memory sampler
and its tables."""

from __future__ import annotations

import argparse
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from conftest import require_shared

from weldplan.io.joints import Joints, read_joints

ROOT = Path(__file__).resolve().parents[1]
WHOLE = ROOT / "assets" / "car2" / "car2_synthetic_4000.csv"
#: joints of the test station: above Held-Karp size (16), so the 1-tree bound, the known-first
#: rounds and the converging gap rounds all run
N_PIECE = 40


@pytest.fixture(scope="module")
def piece():
    """The 40 joints of the whole-body set nearest its joint 'Z2L-...' with the most joints
    within 100 mm (a dense flange area), in a cell."""
    from weldplan.io.mesh import load_part
    from weldplan.weld.cell import build_cell
    from weldplan.weld.synthetic import CAR2_LENGTH_MM

    part = load_part(require_shared("bodies", "car2.obj"), length=CAR2_LENGTH_MM)
    j = read_joints(WHOLE)
    in_z2l = np.flatnonzero([i.startswith("Z2L-") for i in j.ids])
    d = np.linalg.norm(j.xyz[in_z2l, None] - j.xyz[None, in_z2l], axis=-1)
    centre = in_z2l[np.argmax((d < 100.0).sum(axis=1))]
    pick = np.sort(np.argsort(np.linalg.norm(j.xyz - j.xyz[centre], axis=1))[:N_PIECE])
    joints = Joints(
        ids=tuple(j.ids[k] for k in pick), xyz=j.xyz[pick], directions=j.directions[pick]
    )
    return build_cell(part, joints)


@pytest.mark.slow
def test_candidate_neighbours_give_a_verified_route_above_its_proved_bound(piece):
    from weldplan.weld.pipeline import PlanConfig, plan_route
    from weldplan.weld.verify import verify_route

    n = N_PIECE
    cfg = PlanConfig(candidates=3, planner="exact")
    route = plan_route(piece, config=cfg, rng=0)
    assert sorted(route.order) == sorted(piece.joints.ids)
    assert verify_route(route, piece.part, joints=piece.joints).ok
    s = route.stats
    # candidate neighbours: far fewer pairs checked than the n (n - 1) / 2 of the dense matrix
    assert s["pairs"] == n * (n - 1) // 2
    assert s["pairs_candidates"] <= 3 * n
    assert s["pairs_checked"] < s["pairs"] // 3
    # every leg of the route is a planned leg or a straight one that was checked
    assert s["legs_planned"] <= s["pairs_planned"]
    # the proved bounds sit below the route; the gap is what the summary reports
    assert s["bound_planned_method"] == "1-tree"
    assert route.lower_bound <= s["bound_planned"] + 1e-6
    assert s["bound_planned"] <= route.length + 1e-6
    assert s["gap_planned"] == pytest.approx(route.length / s["bound_planned"] - 1.0)
    assert s["gap_rounds"] is not None and s["gap_rounds"]["rounds"] >= 1
    # a bound mixing in unproved costs could exceed the route: planned legs cost at least
    # their straight polyline, so the bound over them is at least the straight-line bound
    assert s["bound_planned"] >= route.lower_bound


def test_tree_memory_sums_the_descendants():
    from weldplan.bench.scale_body import MIB, TreeMemory

    hold = "import time; b = bytearray(200 * 2**20); b[::4096] = b'x' * len(b[::4096]); " + (
        "print('up', flush=True); time.sleep(30)"
    )
    with TreeMemory(interval=0.05) as mem:
        base = mem.now()
        child = subprocess.Popen([sys.executable, "-c", hold], stdout=subprocess.PIPE)
        try:
            assert child.stdout.readline().strip() == b"up"
            mem.mark()
            import time

            time.sleep(0.3)
            peak_mark = mem.since_mark
        finally:
            child.kill()
            child.wait()
    assert peak_mark - base >= 190 * MIB  # the child's 200 MiB counted in the tree
    assert mem.peak >= peak_mark


def _parser():
    from weldplan.bench import scale

    p = argparse.ArgumentParser()
    scale.add_arguments(p)
    return p


def test_bench_scale_whole_body_options_parse():
    a = _parser().parse_args(["--joints", "4000", "--workers", "1,2,4", "--e2e-workers", "1,2"])
    assert a.joints == 4000 and a.workers == [1, 2, 4] and a.e2e_workers == [1, 2]
    assert _parser().parse_args([]).joints is None


def test_bench_scale_whole_body_writes_both_tables(tmp_path):
    """run_body turns the children's figures into the two tables (children faked: their real
    runs take minutes), a refused plan into a row."""
    from weldplan.bench import scale_body

    thr = {"n": 4000, "candidates": 13338, "blocked": 4905, "pairs": 2, "cell": 100.0,
           "planner": "exact + refine",
           "runs": [dict(workers=w, wall=10.0 / w, cpu=10.0, peak_mib=900.0 * w, same=True,
                         load_before=[1, 1, 1], load_after=[2, 2, 2]) for w in (1, 2)]}  # fmt: skip
    e2e = {"workers": 2, "cell": 90.0, "wall": 500.0, "cpu_self": 100.0, "cpu_children": 300.0,
           "peak_mib": 4000.0, "error": "the joints fall into 2 groups", "plan": 10.0,
           "load_before": [1, 1, 1], "load_after": [2, 2, 2]}  # fmt: skip
    got = iter([thr, e2e])
    args = _parser().parse_args(["--joints", "4000", "--workers", "1,2"])
    assert scale_body.run_body(args, "car2.obj", tmp_path, "before", lambda code: next(got)) == 0
    md = (tmp_path / "scale-4000.md").read_text()
    assert "| 2 | 5.0 | **2.00x** | 10.0 | 1800 | True |" in md
    assert "planner exact + refine (the pipeline's default)" in md
    assert "| 2 | 90 |" in md and "2 groups" in md and "| 400 | 4000 |" in md
    bad = _parser().parse_args(["--joints", "7"])
    from weldplan.errors import InputError

    with pytest.raises(InputError, match="--joints"):
        scale_body.run_body(bad, "car2.obj", tmp_path, "before", lambda code: {})


def test_child_code_names_the_measurement():
    from weldplan.bench.scale_body import child_code

    code = child_code("throughput", {"joints": "a'b.csv", "workers": [1, 2]})
    assert "throughput_child" in code
    compile(code, "<child>", "exec")
