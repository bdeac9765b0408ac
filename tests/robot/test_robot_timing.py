"""Cycle time (weldplan.robot.program.timing): toppra against closed forms, limits, deviation,
dwell."""

from __future__ import annotations

import math

import numpy as np
import pytest

from weldplan.errors import ConfigError
from weldplan.robot.program import (
    DEFAULT_TOLERANCE_RAD,
    constant_speed_time,
    pair_time,
    time_route,
)

#: the KR 150 R3100-2's URDF velocities (rad/s) and twice them as accelerations
V = np.array([1.832595715, 1.8675023, 1.989675347, 3.316125579, 3.141592654, 4.537856055])
A = 2.0 * V


def _seg_dist(P: np.ndarray, Q: np.ndarray) -> np.ndarray:
    """(m,) distance of each point of P (m, d) to the polyline Q (k, d)."""
    a, b = Q[:-1], Q[1:]
    ab = b - a
    t = np.einsum("mkd,kd->mk", P[:, None, :] - a[None], ab) / np.maximum(
        np.einsum("kd,kd->k", ab, ab), 1e-300
    )
    t = np.clip(t, 0.0, 1.0)
    foot = a[None] + t[..., None] * ab[None]
    return np.min(np.linalg.norm(P[:, None, :] - foot, axis=2), axis=1)


@pytest.mark.parametrize("delta, joint", [(0.9, 0), (0.05, 3)])
def test_single_joint_move_is_the_closed_form_trapezoid(delta, joint):
    q = np.zeros((2, 6))
    q[1, joint] = delta
    v, a = V[joint], A[joint]
    exact = delta / v + v / a if delta >= v * v / a else 2.0 * math.sqrt(delta / a)
    tt = time_route(q, V, A, weld_rows=[0, 1])
    assert tt.total == pytest.approx(exact, rel=2e-3)
    assert pair_time(q[1] - q[0], V, A) == pytest.approx(exact, rel=1e-12)


def test_straight_multi_joint_move_matches_pair_time():
    dq = np.array([0.4, -0.3, 0.2, 1.0, -0.5, 0.8])
    tt = time_route(np.stack([np.zeros(6), dq]), V, A, weld_rows=[0, 1])
    assert tt.total == pytest.approx(float(pair_time(dq, V, A)), rel=2e-3)


def _route(seed=0, n=9):
    rng = np.random.default_rng(seed)
    return np.cumsum(rng.normal(0.0, 0.15, (n, 6)), axis=0)


def test_samples_respect_limits_stay_on_the_polyline_and_hit_every_waypoint():
    q = _route()
    tt = time_route(q, V, A, weld_rows=[0, 4, 8], weld_time=0.25)
    assert np.all(np.diff(tt.t) >= 0) and np.all(np.diff(tt.step) >= 0)
    qd = np.diff(tt.q, axis=0) / np.maximum(np.diff(tt.t), 1e-12)[:, None]
    moving = np.diff(tt.t) > 1e-9
    assert np.all(np.abs(qd[moving]) <= V * 1.01)
    # every sample within the tolerance of the joint polyline (an independent distance)
    assert _seg_dist(tt.q, q).max() <= DEFAULT_TOLERANCE_RAD * math.sqrt(6) + 1e-9
    for row, t in enumerate(tt.row_times):
        k = int(np.argmin(np.abs(tt.t - t)))
        assert abs(tt.t[k] - t) < 1e-9
        np.testing.assert_allclose(tt.q[k], q[row], atol=1e-9)
    assert tt.total == pytest.approx(tt.motion_time + 3 * 0.25, rel=1e-12)
    # from the end of the first weld's dwell to the end of the last one's
    assert tt.leg_times().sum() == pytest.approx(tt.total - 0.25, rel=1e-12)


def test_exact_stops_on_a_straight_sweep_cost_what_the_closed_form_says():
    # nine rows on one joint-space line: flying through is one trapezoid, stopping at rows 3
    # and 5 is three (the path is the same line either way)
    d = np.array([1.5, -0.8, 0.6, 2.0, 1.0, -2.5])
    q = np.linspace(0.0, 1.0, 9)[:, None] * d
    free = time_route(q, V, A, weld_rows=[0, 8])
    stopped = time_route(q, V, A, weld_rows=[0, 8], stops=np.isin(np.arange(9), [3, 5]))
    assert len(stopped.segments) == 3 and len(free.segments) == 1
    assert free.total == pytest.approx(float(pair_time(d, V, A)), rel=2e-3)
    parts = [3 / 8, 2 / 8, 3 / 8]
    exact = sum(float(pair_time(f * d, V, A)) for f in parts)
    assert stopped.total == pytest.approx(exact, rel=2e-3)
    assert stopped.total > free.total * 1.2


def test_a_tighter_tolerance_inserts_more_knots():
    q = _route(1)
    free = time_route(q, V, A, weld_rows=[0, 8])
    tight = time_route(q, V, A, weld_rows=[0, 8], tolerance=DEFAULT_TOLERANCE_RAD / 8)
    assert tight.segments[0].inserted > free.segments[0].inserted
    assert tight.deviation <= DEFAULT_TOLERANCE_RAD / 8 < free.deviation


def test_slower_limits_take_longer():
    q = _route(2)
    fast = time_route(q, V, A, weld_rows=[0, 8])
    slow = time_route(q, V, A / 4, weld_rows=[0, 8])
    assert slow.total > fast.total * 1.3


@pytest.mark.parametrize("bad", [math.nan, -1.0, math.inf, "x"])
def test_bad_weld_time_is_a_config_error_naming_the_field(bad):
    with pytest.raises(ConfigError) as e:
        time_route(_route(), V, A, weld_rows=[0], weld_time=bad)
    assert e.value.field == "weld_time"


def test_bad_limits_and_speed_are_config_errors():
    with pytest.raises(ConfigError, match="acceleration"):
        time_route(_route(), V, np.r_[A[:5], np.nan], weld_rows=[0])
    with pytest.raises(ConfigError, match="TCP speed"):
        constant_speed_time(np.zeros((2, 3)), 1, speed=0.0)


def test_constant_speed_time_is_length_over_speed_plus_dwell():
    P = np.array([[0, 0, 0], [300, 0, 0], [300, 400, 0]], float)
    assert constant_speed_time(P, 2, speed=500.0, weld_time=0.5) == pytest.approx(700 / 500 + 1)


@pytest.mark.parametrize("seed", [16, 29, 31, 39])
def test_written_times_strictly_increase_where_a_regular_sample_met_an_arrival(seed):
    # on these routes a 10 ms sample fell within 0.05 ms of a waypoint arrival and the CSV
    # wrote one time twice; the arrival now stands alone and the written t strictly increases
    from weldplan.io.trajectory import trajectory_csv_text

    q = _route(seed)
    tt = time_route(q, V, A, weld_rows=[0, 4, 8], weld_time=0.25)
    assert np.all(np.diff(tt.t) > 0)
    t = np.array([float(r.split(",")[0]) for r in trajectory_csv_text(tt).splitlines()[1:]])
    assert len(t) == len(tt.t) and np.all(np.diff(t) > 0)
    # every waypoint arrival is still a sample; no motion gap grows past 1.1 dt (weld dwells
    # of 0.25 s apart)
    assert np.all(np.isin(tt.row_times, tt.t))
    d = np.diff(tt.t)
    assert np.all((d <= 0.011 + 1e-12) | np.isclose(d, 0.25))


def test_trajectory_csv_refuses_times_that_would_repeat():
    import types

    from weldplan.errors import PlanningError
    from weldplan.io.trajectory import trajectory_csv_text

    fake = types.SimpleNamespace(
        t=np.array([0.0, 0.01, 0.01002]), step=np.array([0, 1, 1]), q=np.zeros((3, 1)),
        joint_names=("a1",),
    )  # fmt: skip
    with pytest.raises(PlanningError, match="samples 1 and 2"):
        trajectory_csv_text(fake)


def test_toppra_is_imported_without_pyplot_and_its_plots_still_load_it() -> None:
    """timing's toppra import leaves matplotlib.pyplot unloaded (toppra's own module-level
    ``import matplotlib.pyplot`` is deferred), and both toppra's ``plt`` and a later ordinary
    import get the real pyplot. In a fresh process: this one may have loaded pyplot already."""
    import os
    import subprocess
    import sys
    from pathlib import Path

    import weldplan

    code = (
        "import sys\n"
        "from weldplan.robot.program.timing import _toppra, time_route\n"
        "import numpy as np\n"
        "q = np.array([[0.0] * 6, [0.5] * 6])\n"
        "t = time_route(q, np.ones(6), np.ones(6), weld_rows=[0, 1])\n"
        "assert t.total > 0\n"
        "assert 'matplotlib.pyplot' not in sys.modules\n"
        "ta = _toppra()\n"
        "import matplotlib\n"
        "matplotlib.use('Agg')\n"
        "import matplotlib.pyplot as plt\n"
        "assert ta.algorithm.algorithm.plt.figure is plt.figure\n"
        "assert sys.modules['matplotlib.pyplot'] is plt\n"
    )
    root = str(Path(weldplan.__file__).parent.parent)  # this weldplan, not another checkout's
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([root, os.environ.get("PYTHONPATH", "")])}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env)
    assert out.returncode == 0, out.stderr


def test_a_program_names_the_welds_it_welds_not_the_ones_it_passes():
    """``ProgramBuild.welded_ids``: one id per timed weld row, in their order; a weld the
    program passes without welding (no weld target) is not one (the pages label the weld rows
    with it: the route's ``weld_ids`` also hold the passed welds)."""
    from types import SimpleNamespace as NS

    from weldplan.robot.program.build import ProgramBuild

    targets = [NS(kind="via", row=0, joint_id=""), NS(kind="weld", row=2, joint_id="7"),
               NS(kind="weld", row=5, joint_id="3")]  # fmt: skip
    # timed rows 0..4 stand on route rows 0, 2, 3, 5, 6 (route rows 1 and 4 only passed)
    timing = NS(row_times=np.arange(5.0), weld_rows=np.array([1, 3]))
    build = ProgramBuild(NS(targets=targets), timing, 0.0, 1.0, 0.0, skipped=("9",),
                         row=np.array([0, 2, 3, 5, 6]))  # fmt: skip
    assert build.welded_ids() == ("7", "3")
    bare = ProgramBuild(NS(targets=targets), NS(row_times=np.arange(6.0),
                        weld_rows=np.array([5, 2])), 0.0, 1.0, 0.0)  # fmt: skip
    assert bare.welded_ids() == ("3", "7")
