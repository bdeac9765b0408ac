"""Station scale: candidate pairs plan the all-pairs route; executors (process pool, Dask) do not
change it. Runs on a small station of the synthetic car2 set (assets/car2, ../shared car2.obj)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from conftest import require_shared

from weldplan.errors import WeldplanError
from weldplan.io.joints import Joints, read_joints
from weldplan.weld.pipeline import PlanConfig, candidate_pairs, plan_route

ROOT = Path(__file__).resolve().parents[1]
N_STATION = 12


@pytest.fixture(scope="module")
def station():
    """The 12 joints of the 50-joint car2 set nearest its first joint, in a cell (about 4 s)."""
    from weldplan.io.mesh import load_part
    from weldplan.weld.cell import build_cell
    from weldplan.weld.synthetic import CAR2_LENGTH_MM

    part = load_part(require_shared("bodies", "car2.obj"), length=CAR2_LENGTH_MM)
    j = read_joints(ROOT / "assets" / "car2" / "car2_synthetic_50.csv")
    pick = np.sort(np.argsort(np.linalg.norm(j.xyz - j.xyz[0], axis=1))[:N_STATION])
    joints = Joints(
        ids=tuple(j.ids[k] for k in pick), xyz=j.xyz[pick], directions=j.directions[pick]
    )
    return build_cell(part, joints)


def _legs(route):
    return [(g.from_id, g.to_id, g.points.tobytes()) for g in route.legs]


def test_candidate_pairs_are_the_k_nearest():
    xyz = np.random.default_rng(0).uniform(0, 100, size=(30, 3))
    n, k = len(xyz), 4
    iu, ju = np.triu_indices(n, 1)
    got = candidate_pairs(xyz, k)
    D = np.linalg.norm(xyz[:, None] - xyz[None], axis=-1)
    np.fill_diagonal(D, np.inf)
    want = set()
    for i in range(n):
        for j in np.argsort(D[i])[:k]:
            want.add((min(i, j), max(i, j)))
    assert {(int(iu[p]), int(ju[p])) for p in got} == want
    assert len(candidate_pairs(xyz, 100)) == n * (n - 1) // 2
    near = candidate_pairs(xyz, k, radius=20.0)
    assert {(int(iu[p]), int(ju[p])) for p in near} == {(i, j) for i, j in want if D[i, j] <= 20.0}


def test_candidates_plan_the_all_pairs_route(station):
    """With an exact sequencer, candidate + on-demand pairs lose nothing against all pairs."""
    full = plan_route(station, config=PlanConfig(planner="exact", sequencer="exact", pairs="all"))
    cand = plan_route(station, config=PlanConfig(planner="exact", sequencer="exact", candidates=2))
    assert cand.order == full.order
    assert _legs(cand) == _legs(full)
    assert cand.length == pytest.approx(full.length, rel=1e-12)
    s, f = cand.stats, full.stats
    assert f["pairs_checked"] == f["pairs"] == N_STATION * (N_STATION - 1) // 2
    assert s["pairs_candidates"] < s["pairs_checked"] < f["pairs_checked"]  # some on demand
    assert s["pairs_planned"] < f["pairs_planned"]
    assert s["pairs_straight"] + s["pairs_blocked"] == s["pairs_checked"]


def test_candidates_config_is_checked():
    with pytest.raises(WeldplanError, match="candidates"):
        PlanConfig(candidates=0)
    with pytest.raises(WeldplanError, match="lazy"):
        PlanConfig(candidates=5, pairs="all")
    assert PlanConfig.from_dict(PlanConfig(candidates=5).to_dict()).candidates == 5


def _pool_cfg():
    return PlanConfig(candidates=3, aco={"n_iterations": 3, "n_ants": 4})


@pytest.fixture(scope="module")
def serial(station):
    return plan_route(station, config=_pool_cfg(), rng=11)


def test_process_pool_with_the_cell_installed_gives_the_serial_route(station, serial):
    from weldplan.weld.parallel import process_pool

    assert serial.stats["pairs_planned"] > 4
    with process_pool(station, 2) as ex:
        pooled = plan_route(station, config=_pool_cfg(), rng=11, executor=ex)
    assert pooled.order == serial.order
    assert _legs(pooled) == _legs(serial)


def test_a_plain_process_pool_gives_the_serial_route(station, serial):
    from concurrent.futures import ProcessPoolExecutor

    with ProcessPoolExecutor(2) as ex:
        pooled = plan_route(station, config=_pool_cfg(), rng=11, executor=ex)
    assert _legs(pooled) == _legs(serial)


@pytest.mark.slow
def test_dask_local_cluster_of_two_workers_gives_the_serial_route(station, serial):
    pytest.importorskip("distributed")
    from weldplan.weld.parallel import dask_executor

    with dask_executor("local", workers=2) as ex:
        dasked = plan_route(station, config=_pool_cfg(), rng=11, executor=ex)
    assert dasked.order == serial.order
    assert _legs(dasked) == _legs(serial)


def test_cell_ref_unpickles_once_per_process(station):
    import pickle

    from weldplan.weld import parallel

    ref = parallel.CellRef(station)
    blob = pickle.dumps(ref)
    parallel._CELLS.pop(ref.key, None)
    a = pickle.loads(blob)
    b = pickle.loads(blob)
    assert a is b  # the second task reuses the first one's cell (and its collision model)
    assert a.grid.occupied.shape == station.grid.occupied.shape
    token_only = pickle.dumps(parallel.CellRef(station, ref.key, ship=False))
    assert len(token_only) < 200 < len(blob)
    assert pickle.loads(token_only) is a


@pytest.mark.slow
def test_cli_jobs_and_dask_write_the_serial_route(tmp_path, capsys):
    """``weldplan plan --candidates K`` with ``--jobs 2`` and ``--dask local`` writes the serial
    route, byte for byte (box scene of tests/route_fixtures)."""
    pytest.importorskip("distributed")
    from tests.route_fixtures import box_part
    from weldplan.cli import main

    mesh = tmp_path / "box.stl"
    box_part().export(mesh)
    joints = tmp_path / "joints.csv"
    joints.write_text("id,x,y,z\nA,-40,0,0\nB,40,0,0\nC,-40,60,0\nD,40,-30,0\n")
    base = ["plan", str(mesh), str(joints), "--margin", "40", "--candidates", "1", "--quiet"]
    out = {}
    for name, extra in {"serial": [], "pool": ["--jobs", "2"], "dask": ["--dask", "local"]}.items():
        path = tmp_path / name / "route.csv"  # one name: the header names the station by it
        path.parent.mkdir()
        assert main([*base, "-o", str(path), *extra]) == 0
        out[name] = path.read_bytes()
    assert out["pool"] == out["serial"] == out["dask"]


def test_progress_bar_shows_counts_and_a_time_left_estimate(monkeypatch):
    import io

    from weldplan.commands import _progress

    clock = iter([0.0, 0.0, 2.0, 2.0])
    monkeypatch.setattr(_progress.time, "perf_counter", lambda: next(clock))

    class Tty(io.StringIO):
        def isatty(self):
            return True

    tty = Tty()
    bars = _progress.ProgressBars(stream=tty)
    bars("local", 0, 10)
    bars("local", 4, 10)  # 4 pairs in 2 s: 6 left take 3 s
    assert "4/10" in tty.getvalue() and "ETA    3.0 s" in tty.getvalue()


@pytest.mark.slow
def test_known_first_orders_over_known_legs_and_settles_in_few_rounds():
    """Above 16 joints with candidates, unknown legs are penalised: two rows of spots on either
    side of a wall (k = 3 keeps the candidates within each row) are joined by one planned leg."""
    from tests.route_fixtures import box_part
    from weldplan.weld.cell import build_cell
    from weldplan.weld.verify import verify_route

    y = np.linspace(-80.0, 80.0, 9)
    xyz = np.concatenate(
        [np.c_[np.full(9, -30.0), y, np.zeros(9)], np.c_[np.full(9, 30.0), y, np.zeros(9)]]
    )
    joints = Joints(ids=tuple(f"J{k}" for k in range(18)), xyz=xyz)
    cell = build_cell(box_part(), joints, margin=40.0)
    routes = {}
    for kf in (True, False):
        cfg = PlanConfig(planner="exact", sequencer="pso", candidates=3, known_first=kf)
        routes[kf] = plan_route(cell, config=cfg, rng=0)
        assert verify_route(routes[kf], cell.part, joints=joints).ok
    kf, est = routes[True], routes[False]
    assert kf.stats["rounds"] <= 3
    assert kf.stats["rounds"] <= est.stats["rounds"]
    assert kf.stats["pairs_planned"] <= est.stats["pairs_planned"]
    assert kf.length <= 1.05 * est.length
    with pytest.raises(WeldplanError, match="candidates"):
        PlanConfig(candidates=0, known_first=True)


def test_bench_scale_options_parse():
    import argparse

    from weldplan.bench import scale

    p = argparse.ArgumentParser()
    scale.add_arguments(p)
    a = p.parse_args(["--throughput-only", "--workers", "1,2,4", "--reference", "all"])
    assert a.throughput_only and a.workers == [1, 2, 4] and a.reference == "all"
    assert p.parse_args([]).workers == [1, 2]
    for bad in ("0,2", "a"):
        with pytest.raises(argparse.ArgumentTypeError):
            scale._ints(bad)


def test_throughput_plans_with_the_pipelines_default_planner(station):
    """bench scale's throughput batches (and the whole-body one) plan the blocked pairs with
    ``PlanConfig()``'s planner and parameters (refinement included), not a hard-coded one."""
    from weldplan.bench.scale_body import default_pair_args, default_planner
    from weldplan.weld.pairtasks import _plan_pairs_task

    cfg = PlanConfig()
    n = len(station.joints.ids)
    iu, ju = np.triu_indices(n, 1)
    V = station.virtual_xyz
    blocked = np.flatnonzero(~station.collision.segments_free(V[iu], V[ju], station.clearance))
    args = default_pair_args(iu, ju, blocked[:1])
    assert args == [(int(iu[blocked[0]]), int(ju[blocked[0]]), cfg.planner, dict(cfg.aco),
                     int(blocked[0]))]  # fmt: skip
    assert cfg.aco["refine"] and default_planner() == f"{cfg.planner} + refine"
    (lp,) = _plan_pairs_task(station, args, None)
    assert lp.success and lp.method == cfg.planner


def test_bench_scale_reports_a_refused_size_as_a_row(tmp_path, monkeypatch):
    """A size whose plan is refused (car2's 1000-joint set: 3 joints no path reaches) is a row
    of the table, not a crash of the whole benchmark."""
    import argparse

    from weldplan.bench import scale

    err = {"n": 1000, "cell": 20.0, "error": "the joints fall into 2 groups", "plan": 500.0}
    err.update(peak_mib=900.0, child_peak_mib=800.0, load_before=[1, 2, 3], load_after=[3, 2, 1])
    monkeypatch.setattr(scale, "run_child", lambda code: err)
    monkeypatch.setattr(scale, "shared_path", lambda *parts: tmp_path / "car2.obj")
    p = argparse.ArgumentParser()
    scale.add_arguments(p)
    args = p.parse_args(["--sizes", "1000"])
    args.out = str(tmp_path)
    assert scale.run(args) == 0
    md = (tmp_path / "scale.md").read_text()
    assert "| 1000 | 20.0 |" in md and "failed after 500.0" in md and "2 groups" in md


def test_batches_keep_order_and_respect_a_largest_size():
    from weldplan.weld.parallel import batches

    items = list(range(1000))
    big = batches(items, 2)
    assert len(big) == 8 and [x for b in big for x in b] == items
    small = batches(items, 2, max_size=64)
    assert max(len(b) for b in small) == 64 and len(small) == 16
    assert [x for b in small for x in b] == items
    assert batches(items[:5], 2, max_size=64) == [[0], [1], [2], [3], [4]]
