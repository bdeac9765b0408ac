"""Fault injection in child processes (slow tier): memory, time and what C libraries print.

Each case runs ``python -m weldplan`` under a 3 GiB address-space ceiling and a time limit
(tests/faults/subproc.py), so a case that today allocates gigabytes or runs for minutes fails
without taking the machine with it. The invariant is the suite's: one line on the real stderr
(C libraries included), the exit code of the scheme, no traceback.
"""

from __future__ import annotations

import numpy as np
import pytest

from tests.faults.harness import (
    BAD_INPUT,
    FAILURE,
    SPOTS,
    assert_one_line_error,
    make_scene,
    wall_plate,
)
from tests.faults.subproc import run_weldplan

pytestmark = pytest.mark.slow


def _xfail(item: int, branch: str, what: str):
    return pytest.mark.xfail(
        strict=True, reason=f"#14 item {item}: fixed on branch {branch} ({what})"
    )


def test_child_process_harness_sees_a_clean_run(tmp_path):
    """The harness itself: a good station plans in a child and writes its route."""
    sc = make_scene(tmp_path)
    o = run_weldplan(sc.plan_argv(), timeout=180)
    assert o.code == 0 and o.crash is None, o.stderr
    assert sc.json.exists()


@pytest.mark.parametrize(
    "margin",
    [
        pytest.param("1e6"),
        pytest.param("2700"),
    ],
)
def test_huge_margin_is_refused_in_one_line_naming_it(tmp_path, margin):
    sc = make_scene(tmp_path)
    o = run_weldplan(sc.plan_argv("--margin", margin), timeout=60)
    assert_one_line_error(o, BAD_INPUT, "--margin")


def test_mm_files_read_as_metres_are_refused_before_the_grid(tmp_path):
    """A station 1000 mm from the origin read with ``--units m``: a grid kilometres wide."""
    off = np.array([1000.0, 500.0, 800.0])
    m = wall_plate()
    m.apply_translation(off)
    sc = make_scene(tmp_path, mesh=m, xyz=SPOTS + off)
    o = run_weldplan(sc.plan_argv("--units", "m"), timeout=60)
    assert_one_line_error(o, BAD_INPUT)


def test_a_hundred_thousand_joints_are_refused_up_front(tmp_path):
    """100,000 joints on the plate: refused in one line naming an option, within the limit
    (today: minutes of work, then memory)."""
    rng = np.random.default_rng(14)
    xyz = np.column_stack(
        [rng.uniform(5.0, 45.0, 100_000), rng.uniform(-45.0, 45.0, 100_000), np.zeros(100_000)]
    )
    sc = make_scene(tmp_path, xyz=xyz)
    o = run_weldplan(sc.plan_argv(), timeout=60)
    line = assert_one_line_error(o, BAD_INPUT)
    assert "--" in line, line


def test_unreachable_dask_scheduler_is_one_line(tmp_path):
    sc = make_scene(tmp_path)
    o = run_weldplan(sc.plan_argv("--dask", "tcp://127.0.0.1:9"), timeout=90)
    assert_one_line_error(o, FAILURE, "127.0.0.1:9")


@pytest.mark.parametrize(
    "value",
    [
        pytest.param("nan"),
        pytest.param("inf"),
    ],
)
def test_verify_with_a_bad_clearance_prints_one_line_from_c_too(tmp_path, value):
    """In process, only Python's stderr is captured; here fcl's own messages count too."""
    sc = make_scene(tmp_path)
    assert run_weldplan(sc.plan_argv(), timeout=180).code == 0
    o = run_weldplan(["verify", sc.json, sc.mesh, "--clearance", value], timeout=180)
    assert_one_line_error(o, BAD_INPUT, "clearance")


def test_bad_joints_file_is_one_line_on_the_real_stderr(tmp_path):
    sc = make_scene(tmp_path)
    sc.joints.write_text("id,x,y,z\nJ1,1,2\n")
    o = run_weldplan(sc.plan_argv(), timeout=180)
    assert_one_line_error(o, BAD_INPUT, "joints.csv", "line 2")
