"""Issue 14, the CLI half: exit codes and one-line errors, outputs written as a set, the size
check before planning, --skip-unreachable, argument checks of the planning API."""

from __future__ import annotations

import errno
import json
import os
import re
from pathlib import Path

import numpy as np
import pytest
import trimesh

from tests.cli_helpers import run_cli
from tests.route_fixtures import BOX_JOINTS_CSV, box_part, write_box_station
from weldplan.cli import main
from weldplan.errors import ConfigError, InputError, RunError, UnreachableJointsError
from weldplan.io import outputset

#: the box scene of tests/route_fixtures (floor and a wall with free ends)
JOINTS_CSV = BOX_JOINTS_CSV
#: beside a panel (2 x 2000 x 2000 mm at the origin) that spans any region of interest near
#: it: A, C, D on one side, B alone on the other
PANEL_JOINTS_CSV = "id,x,y,z\nA,-8,0,0\nB,8,0,0\nC,-8,40,0\nD,-8,-30,0\n"


def _one_line(capsys) -> str:
    err = capsys.readouterr().err
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1, err
    assert "Traceback" not in err
    return lines[0]


@pytest.fixture
def files(tmp_path):
    return write_box_station(tmp_path)


@pytest.fixture
def panel(tmp_path):
    mesh = tmp_path / "panel.stl"
    trimesh.creation.box(extents=[2.0, 2000.0, 2000.0]).export(mesh)
    joints = tmp_path / "joints.csv"
    joints.write_text(PANEL_JOINTS_CSV)
    return tmp_path, mesh, joints


def _plan_argv(mesh, joints, out, *extra):
    return ["plan", str(mesh), str(joints), "-o", str(out), "--quiet", "--margin", "50", *extra]


def _old_outputs(tmp: Path) -> dict[Path, bytes]:
    old = {tmp / "r.csv": b"old csv\n", tmp / "r.json": b'{"old": 1}\n'}
    for p, b in old.items():
        p.write_bytes(b)
    return old


def _unchanged(old: dict[Path, bytes]) -> None:
    for p, b in old.items():
        assert p.read_bytes() == b, p
    folders = {p.parent for p in old}
    left = [f for d in folders for f in os.listdir(d) if f.startswith(outputset.TEMP_PREFIX)]
    assert not left, left


# ---------------------------------------------------------------- item 8: one line, exit codes
def test_help_documents_the_exit_codes(capsys):
    with pytest.raises(SystemExit):
        main(["plan", "--help"])
    out = capsys.readouterr().out
    for code in ("0  done", "1  the run failed", "2  bad input", "3  partial route"):
        assert code in out


@pytest.mark.parametrize("seed", ["-1", "1.5", "x"])
def test_negative_or_non_integer_seed_is_one_line_exit_2(files, capsys, seed):
    tmp, mesh, joints = files
    assert run_cli(_plan_argv(mesh, joints, tmp / "r.csv", "--seed", seed)) == 2
    line = _one_line(capsys)
    assert "--seed" in line
    assert not (tmp / "r.csv").exists()


def test_seed_takes_what_numpy_takes():
    from weldplan.weld.validate import seed

    assert seed(2**100) == 2**100  # numpy's default_rng takes any integer >= 0
    np.random.default_rng(seed(2**100))
    with pytest.raises(ConfigError, match=r"seed \(rng\) must be an integer >= 0"):
        seed(-1)
    with pytest.raises(ConfigError):
        seed(True)


def test_a_huge_coordinate_is_one_line(files, capsys):
    tmp, mesh, _ = files
    joints = tmp / "far.csv"
    joints.write_text("id,x,y,z\nA,1e300,0,0\nB,0,0,0\n")
    rc = run_cli(_plan_argv(mesh, joints, tmp / "r.csv"))
    assert rc == 2
    line = _one_line(capsys)
    assert "weldplan plan: error:" in line


def test_unreachable_dask_scheduler_is_one_line_exit_1(files, capsys, monkeypatch):
    pytest.importorskip("distributed")
    tmp, mesh, joints = files
    from weldplan.weld import cell as cell_mod

    # the scheduler is reached before the cell is built
    monkeypatch.setattr(cell_mod, "load_cell", lambda *a, **k: 1 / 0)
    # port 1 on this machine: nothing listens; the connection is refused or times out (5 s)
    rc = run_cli(_plan_argv(mesh, joints, tmp / "r.csv", "--dask", "tcp://127.0.0.1:1"))
    assert rc == 1
    line = _one_line(capsys)
    assert "cannot reach the Dask scheduler at tcp://127.0.0.1:1" in line
    assert not (tmp / "r.csv").exists()


def test_malformed_dask_address_is_bad_input(files, capsys):
    pytest.importorskip("distributed")
    tmp, mesh, joints = files
    assert run_cli(_plan_argv(mesh, joints, tmp / "r.csv", "--dask", "nohostnoport")) == 2
    assert "Dask scheduler address" in _one_line(capsys)


def test_full_disk_at_the_write_layer_is_one_line_exit_1(files, capsys, monkeypatch):
    """A full disk, injected (honestly named): the second temporary file fails with ENOSPC the
    way os.write does on a full file system (no tmpfs can be mounted in the test)."""
    tmp, mesh, joints = files
    old = _old_outputs(tmp)
    real = outputset._write_temp
    calls = []

    def full_disk(path, text, encoding):
        calls.append(path)
        if len(calls) == 2:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(path))
        return real(path, text, encoding)

    monkeypatch.setattr(outputset, "_write_temp", full_disk)
    rc = run_cli(_plan_argv(mesh, joints, tmp / "r.csv", "--json", str(tmp / "r.json")))
    assert rc == 1
    line = _one_line(capsys)
    assert "No space left on device" in line and "no output file was changed" in line
    assert len(calls) == 2
    _unchanged(old)


@pytest.fixture
def tiny_disk(tmp_path):
    """A 64 KiB tmpfs (needs root and the right to mount; skipped otherwise)."""
    import subprocess

    mnt = tmp_path / "disk"
    mnt.mkdir()
    r = subprocess.run(
        ["mount", "-t", "tmpfs", "-o", "size=64k", "tmpfs", str(mnt)], capture_output=True
    )
    if r.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here: {r.stderr.decode().strip()}")
    try:
        yield mnt
    finally:
        subprocess.run(["umount", str(mnt)], check=True)


def test_a_real_full_disk_is_one_line_exit_1(files, tiny_disk, capsys):
    """The outputs go to a full 64 KiB tmpfs that holds the previous outputs."""
    tmp, mesh, joints = files
    old = _old_outputs(tiny_disk)
    fd = os.open(tiny_disk / "filler", os.O_CREAT | os.O_WRONLY)
    try:
        while True:
            os.write(fd, b"x" * 1024)
    except OSError as exc:
        assert exc.errno == errno.ENOSPC
    finally:
        os.close(fd)
    rc = run_cli(_plan_argv(mesh, joints, tiny_disk / "r.csv", "--json", str(tiny_disk / "r.json")))
    assert rc == 1
    line = _one_line(capsys)
    assert "No space left on device" in line and "no output file was changed" in line
    _unchanged(old)


def test_a_bug_keeps_its_traceback(files, monkeypatch):
    """Only weldplan's errors, OSError and MemoryError become one line: a TypeError is a bug."""
    tmp, mesh, joints = files
    from weldplan.commands import _planning

    def broken(*a, **k):
        raise TypeError("a bug")

    monkeypatch.setattr(_planning, "summary_table", broken)
    with pytest.raises(TypeError, match="a bug"):
        main(["plan", str(mesh), str(joints), "-o", str(tmp / "r.csv"), "--margin", "50"])


# ---------------------------------------------------------------- items 6 and 9: outputs
def test_write_protected_output_is_refused_before_planning(files, capsys, monkeypatch):
    tmp, mesh, joints = files
    old = _old_outputs(tmp)
    (tmp / "r.json").chmod(0o444)
    from weldplan.weld import pipeline

    def no_planning(*a, **k):  # the check must come first
        raise AssertionError("planned before checking the outputs")

    monkeypatch.setattr(pipeline, "plan_route", no_planning)
    rc = run_cli(_plan_argv(mesh, joints, tmp / "r.csv", "--json", str(tmp / "r.json")))
    assert rc == 2
    line = _one_line(capsys)
    assert "r.json" in line and "write-protected" in line
    _unchanged(old)


def test_unwritable_folder_is_refused_before_planning(files, capsys, monkeypatch):
    tmp, mesh, joints = files
    locked = tmp / "locked"
    locked.mkdir()
    locked.chmod(0o555)
    from weldplan.weld import pipeline

    monkeypatch.setattr(pipeline, "plan_route", lambda *a, **k: 1 / 0)
    try:
        rc = run_cli(_plan_argv(mesh, joints, locked / "r.csv"))
    finally:
        locked.chmod(0o755)
    assert rc == 2
    assert "not writable" in _one_line(capsys)
    assert os.listdir(locked) == []


def test_folder_on_a_read_only_file_system_is_refused():
    """/proc accepts no new files, for root too: the probe file finds it."""
    target = Path("/proc/self/weldplan-route.csv")
    try:
        fd = os.open(target, os.O_CREAT | os.O_WRONLY)
    except OSError:
        pass
    else:  # pragma: no cover - not Linux /proc
        os.close(fd)
        pytest.skip("/proc accepts files here")
    with pytest.raises(InputError, match="not writable"):
        outputset.check_outputs({"csv": target})


def test_a_name_too_long_is_refused_up_front(files, capsys):
    tmp, mesh, joints = files
    old = _old_outputs(tmp)
    long_json = tmp / ("j" * 300 + ".json")
    assert run_cli(_plan_argv(mesh, joints, tmp / "r.csv", "--json", str(long_json))) == 2
    assert "File name too long" in _one_line(capsys)
    _unchanged(old)


def test_failed_rename_in_the_middle_restores_every_file(files, capsys, monkeypatch):
    """A failure injected (honestly named) at the second rename, after the CSV was renamed
    over the old one: the old CSV must come back, the JSON stay as it was, nothing left over."""
    tmp, mesh, joints = files
    old = _old_outputs(tmp)
    (tmp / "r.html").write_text("old html")
    old[tmp / "r.html"] = b"old html"
    real = os.replace
    calls = []

    def failing_replace(src, dst):
        calls.append(dst)
        if len(calls) == 2:
            raise OSError(errno.EIO, os.strerror(errno.EIO), str(dst))
        return real(src, dst)

    monkeypatch.setattr(outputset.os, "replace", failing_replace)
    argv = _plan_argv(mesh, joints, tmp / "r.csv", "--json", str(tmp / "r.json"))
    rc = run_cli([*argv, "--html", str(tmp / "r.html")])
    monkeypatch.setattr(outputset.os, "replace", real)
    assert rc == 1
    assert "no output file was changed" in _one_line(capsys)
    assert calls[:2] == [tmp / "r.csv", tmp / "r.json"]
    _unchanged(old)
    assert sorted(os.listdir(tmp)) == ["box.stl", "joints.csv", "r.csv", "r.html", "r.json"]


def test_write_outputs_is_all_or_none_for_new_files_too(tmp_path):
    a, b = tmp_path / "a.txt", tmp_path / "no" / "b.txt"
    with pytest.raises(InputError):
        outputset.write_outputs({a: "A", b: "B"})
    assert not a.exists()
    assert os.listdir(tmp_path) == []
    written = outputset.write_outputs({a: "A", tmp_path / "c.txt": "C"})
    assert [p.read_text() for p in written] == ["A", "C"]
    assert sorted(os.listdir(tmp_path)) == ["a.txt", "c.txt"]


def test_write_outputs_keeps_the_mode_of_a_replaced_file(tmp_path):
    a = tmp_path / "a.txt"
    a.write_text("old")
    a.chmod(0o640)
    outputset.write_outputs({a: "new"})
    assert a.read_text() == "new"
    assert a.stat().st_mode & 0o777 == 0o640


# ---------------------------------------------------------------- item 7: size up front
def test_estimated_voxels_match_the_grid_layout():
    from weldplan.geometry.grid import grid_region
    from weldplan.weld.sizing import grid_voxels

    rng = np.random.default_rng(3)
    mesh = box_part()
    for _ in range(20):
        P = rng.uniform(-500, 500, size=(rng.integers(1, 30), 3))
        pitch = float(rng.choice([1.0, 2.5, 5.0, 7.0]))
        margin = float(rng.uniform(0, 300))
        _, shape = grid_region(mesh, pitch=pitch, points=P, margin=margin)
        assert grid_voxels(P, pitch, margin) == float(np.prod(shape))


def test_huge_margin_is_refused_up_front_naming_the_option(files, capsys, monkeypatch):
    tmp, mesh, joints = files
    from weldplan.weld import cell as cell_mod

    monkeypatch.setattr(cell_mod, "load_cell", lambda *a, **k: 1 / 0)  # never reached
    rc = run_cli(_plan_argv(mesh, joints, tmp / "r.csv", "--margin", "2700", "--memory-limit", "1"))
    assert rc == 2
    line = _one_line(capsys)
    assert "--margin" in line and "--pitch" in line and "1.0 GB limit (--memory-limit)" in line


@pytest.mark.parametrize("value", ["0", "-1", "nan", "inf", "lots"])
def test_memory_limit_must_be_a_positive_number(files, capsys, value):
    tmp, mesh, joints = files
    assert run_cli(_plan_argv(mesh, joints, tmp / "r.csv", "--memory-limit", value)) == 2
    assert "--memory-limit" in _one_line(capsys)


def test_memory_limit_that_fits_plans(files, capsys):
    tmp, mesh, joints = files
    assert run_cli(_plan_argv(mesh, joints, tmp / "r.csv", "--memory-limit", "4")) == 0


def test_many_joints_are_refused_naming_candidates_or_a_split():
    from weldplan.weld import sizing

    n = 100_000
    P = np.random.default_rng(0).uniform(0, 1000, size=(n, 3))
    with pytest.raises(ConfigError, match="split the joints") as e:
        sizing.check_size(P, pitch=5.0, margin=10.0, n_joints=n, candidates=None, memory_limit=8)
    assert "100,000 joints" in str(e.value)
    # a size where the candidates' (n, n) tables fit and all pairs do not
    n = int(np.sqrt(5e9 / sizing.PAIR_BYTES)) + 100
    limit = sizing.estimate(None, 5, 0, n, 6).total_bytes / 1e9 * 1.01
    with pytest.raises(ConfigError, match="--candidates K"):
        sizing.check_size(
            None, pitch=5, margin=0, n_joints=n, candidates=None, memory_limit=limit, cli=True
        )


def test_plan_route_refuses_pair_work_over_the_limit():
    from weldplan.io.joints import Joints
    from weldplan.weld.pipeline import PlanConfig, plan_route

    n = 100_000
    xyz = np.random.default_rng(0).uniform(0, 1000, size=(n, 3))

    class Cell:
        joints = Joints(ids=tuple(map(str, range(n))), xyz=xyz)
        virtual_xyz = xyz
        collision = None
        clearance = 5.0

    with pytest.raises(ConfigError, match="memory_limit"):
        plan_route(Cell(), config=PlanConfig(memory_limit=16.0))


def test_default_memory_limit_is_a_share_of_available_memory():
    from weldplan.weld import sizing

    avail = sizing.available_memory()
    assert avail is not None and avail > 0
    assert sizing.default_memory_limit() == pytest.approx(
        sizing.DEFAULT_MEMORY_FRACTION * sizing.available_memory() / 1e9, rel=0.2
    )


# ---------------------------------------------------------------- item 10: the API boundary
@pytest.mark.parametrize(
    "kwargs, needle",
    [
        ({"clearance": float("nan")}, "clearance must be a positive number of mm"),
        ({"pitch": "5"}, "pitch must be a positive number of mm"),
        ({"margin": -1.0}, "margin must be >= 0 mm"),
        ({"planner": 3}, "unknown planner"),
        ({"aco": {"n_ants": 0}}, "aco['n_ants'] must be a positive integer"),
        ({"aco": [1, 2]}, "aco must be a mapping"),
        ({"pso": {"particle": 3}}, "pso: unknown parameter"),
        ({"pso": {"c1": float("nan")}}, "pso['c1']"),
        ({"polish": "yes"}, "polish must be True or False"),
        ({"max_rounds": 1.5}, "max_rounds must be a positive integer"),
        ({"candidates": 0}, "candidates must be a positive integer"),
        ({"candidate_radius": float("nan")}, "candidate_radius"),
        ({"local_time_budget": -2}, "local_time_budget"),
        ({"warm_kicks": -1}, "warm_kicks must be an integer >= 0"),
        ({"memory_limit": 0}, "memory_limit"),
        ({"skip_unreachable": 1}, "skip_unreachable must be True or False"),
    ],
)
def test_plan_config_rejects_bad_values_with_weldplan_errors(kwargs, needle):
    from weldplan.weld.pipeline import PlanConfig

    with pytest.raises(ConfigError) as e:
        PlanConfig(**kwargs)
    assert isinstance(e.value, ValueError)
    assert needle in str(e.value)


def test_plan_config_normalises_numpy_values():
    from weldplan.weld.pipeline import PlanConfig

    c = PlanConfig(clearance=np.float32(4.0), candidates=np.int64(6), polish=np.bool_(False))
    assert type(c.clearance) is float and type(c.candidates) is int and c.polish is False
    assert PlanConfig.from_dict(c.to_dict()) == c


def test_plan_route_rejects_bad_arguments_before_any_work():
    from weldplan.weld.cell import demo_cell
    from weldplan.weld.pipeline import PlanConfig, plan_route

    cell = demo_cell()
    cases = [
        ({"rng": -1}, "seed (rng) must be an integer >= 0"),
        ({"rng": 1.5}, "seed (rng) must be an integer >= 0"),
        ({"config": {"planner": "exact"}}, "config must be a PlanConfig"),
        ({"executor": "pool"}, "executor must be"),
        ({"progress": 3}, "progress must be"),
    ]
    for kwargs, needle in cases:
        with pytest.raises(ConfigError, match=re.escape(needle)):
            plan_route(cell, **{"config": PlanConfig(), **kwargs})
    with pytest.raises(ConfigError, match="cell must be a Cell"):
        plan_route("cell.stl")


def test_cli_and_api_say_the_same_about_a_seed(files, capsys):
    from weldplan.weld.cell import demo_cell
    from weldplan.weld.pipeline import plan_route

    tmp, mesh, joints = files
    run_cli(_plan_argv(mesh, joints, tmp / "r.csv", "--seed", "-3"))
    line = _one_line(capsys)
    with pytest.raises(ConfigError) as e:
        plan_route(demo_cell(), rng=-3)
    assert e.value.message in line


# ---------------------------------------------------------------- section 3: --skip-unreachable
def test_unreachable_joint_fails_the_run_without_the_flag(panel, capsys):
    tmp, mesh, joints = panel
    assert run_cli(_plan_argv(mesh, joints, tmp / "r.csv")) == 1
    line = _one_line(capsys)
    assert "no collision-free path from joint(s) B to any other joint" in line
    assert not (tmp / "r.csv").exists()


def test_skip_unreachable_plans_the_rest_lists_it_and_exits_3(panel, capsys):
    tmp, mesh, joints = panel
    out, js = tmp / "r.csv", tmp / "r.json"
    argv = ["plan", str(mesh), str(joints), "-o", str(out), "--json", str(js), "--margin", "50"]
    assert run_cli([*argv, "--skip-unreachable"]) == 3
    cap = capsys.readouterr()
    assert "skipped" in cap.out and "B" in cap.out
    assert "partial route: 1 joint(s) skipped (B)" in cap.err
    route = json.loads(js.read_text())
    assert [s["id"] for s in route["stats"]["skipped"]] == ["B"]
    assert "no collision-free path" in route["stats"]["skipped"][0]["reason"]
    assert sorted(route["order"]) == ["A", "C", "D"]
    assert route["joints"]["ids"] == ["A", "B", "C", "D"]
    assert route["settings"]["skip_unreachable"] is True
    # the independent check accepts the route with B listed as skipped, against the whole file
    assert run_cli(["verify", str(js), str(mesh), "--joints", str(joints)]) == 0
    # ... and refuses it once B is no longer listed
    route["stats"]["skipped"] = []
    js.write_text(json.dumps(route))
    assert run_cli(["verify", str(js), str(mesh), "--joints", str(joints)]) == 1
    assert "joint B is never visited" in capsys.readouterr().err


def test_skip_unreachable_on_the_api(panel):
    from weldplan.weld.cell import load_cell
    from weldplan.weld.pipeline import PlanConfig, plan_route
    from weldplan.weld.verify import verify_route

    tmp, mesh, joints = panel
    cell = load_cell(mesh, joints, margin=50.0)
    with pytest.raises(UnreachableJointsError) as e:
        plan_route(cell, rng=0)
    assert e.value.stranded == ["B"]
    route = plan_route(cell, config=PlanConfig(skip_unreachable=True), rng=0)
    assert [s["id"] for s in route.stats["skipped"]] == ["B"]
    assert verify_route(route, cell.part, joints=cell.joints).ok
    # the same route as planning the three reachable joints alone
    alone = tmp / "three.csv"
    alone.write_text("id,x,y,z\nA,-8,0,0\nC,-8,40,0\nD,-8,-30,0\n")
    ref = plan_route(load_cell(mesh, alone, margin=50.0), rng=0)
    assert route.order == ref.order
    assert route.length == pytest.approx(ref.length)


def test_skip_unreachable_leaves_out_the_smaller_group(panel):
    """Two joints behind the panel reach each other but not the other three: the groups are
    found (not a stranded joint), the smaller one is skipped with its reason."""
    from weldplan.weld.cell import load_cell
    from weldplan.weld.pipeline import PlanConfig, plan_route
    from weldplan.weld.verify import verify_route

    tmp, mesh, _ = panel
    joints = tmp / "five.csv"
    joints.write_text(PANEL_JOINTS_CSV + "E,8,30,0\n")
    cell = load_cell(mesh, joints, margin=50.0)
    with pytest.raises(UnreachableJointsError) as e:
        plan_route(cell, rng=0)
    assert e.value.groups == [["A", "C", "D"], ["B", "E"]]
    assert "2 groups" in str(e.value)
    route = plan_route(cell, config=PlanConfig(skip_unreachable=True), rng=0)
    assert [s["id"] for s in route.stats["skipped"]] == ["B", "E"]
    assert "its group (2 joints: B, E)" in route.stats["skipped"][0]["reason"]
    assert sorted(route.order) == ["A", "C", "D"]
    assert verify_route(route, cell.part, joints=cell.joints).ok


def test_run_error_is_exit_1():
    from weldplan.errors import exit_code

    assert exit_code(RunError("x")) == 1
    assert exit_code(UnreachableJointsError("x")) == 1
    assert exit_code(InputError("x")) == 2
    assert exit_code(ConfigError("x")) == 2


def _closed_room() -> trimesh.Trimesh:
    """Six 2 mm plates (each a closed box) enclosing a free 60 mm cube at the origin."""
    plates = []
    for axis in range(3):
        for side in (-1.0, 1.0):
            extents = np.full(3, 64.0)
            extents[axis] = 2.0
            plate = trimesh.creation.box(extents=extents)
            centre = np.zeros(3)
            centre[axis] = side * 31.0
            plate.apply_translation(centre)
            plates.append(plate)
    return trimesh.util.concatenate(plates)


def test_skip_unreachable_leaves_out_a_joint_inside_a_closed_room(tmp_path, capsys):
    """E sits in the free interior of a closed room, the others outside under its floor."""
    mesh = tmp_path / "room.stl"
    _closed_room().export(mesh)
    joints = tmp_path / "joints.csv"
    joints.write_text("id,x,y,z\nA,0,0,-40\nC,20,0,-40\nE,0,0,-22\nD,-20,10,-40\n")
    out, js = tmp_path / "r.csv", tmp_path / "r.json"
    argv = ["plan", str(mesh), str(joints), "-o", str(out), "--json", str(js), "--margin", "30"]
    assert run_cli(argv) == 1
    assert "no collision-free path from joint(s) E" in _one_line(capsys)
    assert run_cli([*argv, "--skip-unreachable", "--quiet"]) == 3
    route = json.loads(js.read_text())
    assert [s["id"] for s in route["stats"]["skipped"]] == ["E"]
    assert sorted(route["order"]) == ["A", "C", "D"]
    assert run_cli(["verify", str(js), str(mesh), "--joints", str(joints)]) == 0


def test_skipped_joint_before_blocked_pairs_plans_the_right_pairs(tmp_path):
    """E (first in the file) is shut in a closed room; A-B is blocked by the wall of the box
    scene and must be planned as A-B in the cell (the kept joints' indices are shifted by the
    skipped one), serially and through an executor: same route as the four joints alone."""
    from concurrent.futures import ThreadPoolExecutor

    from weldplan.weld.cell import load_cell
    from weldplan.weld.pipeline import PlanConfig, plan_route
    from weldplan.weld.verify import verify_route

    room = _closed_room()
    room.apply_translation([300.0, 0.0, 31.0])
    mesh = tmp_path / "scene.stl"
    trimesh.util.concatenate([box_part(), room]).export(mesh)
    joints = tmp_path / "joints.csv"
    joints.write_text("id,x,y,z\nE,300,0,9\n" + JOINTS_CSV.split("\n", 1)[1])
    alone = tmp_path / "alone.csv"
    alone.write_text(JOINTS_CSV)
    cell = load_cell(mesh, joints, margin=50.0)
    config = PlanConfig(skip_unreachable=True)
    serial = plan_route(cell, config=config, rng=5)
    with ThreadPoolExecutor(2) as ex:
        pooled = plan_route(cell, config=config, rng=5, executor=ex)
    ref = plan_route(load_cell(mesh, alone, margin=50.0), rng=5)
    assert ref.stats["pairs_planned"] >= 1  # the wall blocks A-B: a local path is planned
    for route in (serial, pooled):
        assert [s["id"] for s in route.stats["skipped"]] == ["E"]
        assert route.order == ref.order
        assert route.length == pytest.approx(ref.length)
        assert verify_route(route, cell.part, joints=cell.joints).ok
