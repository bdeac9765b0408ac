"""The station's Gantt chart (weldplan.viz.gantt) on schedules of routes timed by toppra with an
interlock's wait: the same bytes twice, each robot's row holds its bars' colours, a wait's bar is
as long in pixels as its duration on the chart's own scale, the SVG's time axis where the PNG's
bars are."""

from __future__ import annotations

import io

import numpy as np
import pytest

from weldplan.multi.schedule import Interlock, station_schedule
from weldplan.robot.program import time_route

pytest.importorskip("matplotlib")
Image = pytest.importorskip("PIL.Image")

VEL = np.full(6, 2.0)
ACC = np.full(6, 8.0)
WT = 0.5


def _timed(offset: float, n: int = 4):
    q = np.zeros((n, 6))
    q[:, 0] = offset + 0.3 * np.arange(n)
    return time_route(q, VEL, ACC, weld_rows=np.arange(n), weld_time=WT)


@pytest.fixture(scope="module")
def schedule():
    """Robot 2 waits at its first weld until robot 1 is done with its third (Z1_R1_R2)."""
    lock = Interlock("Z1", first=0, release_row=2, second=1, wait_row=0, signal=1)
    ids = [{k: f"w{k + 1}" for k in range(4)}, {k: f"v{k + 1}" for k in range(4)}]
    return station_schedule(["robot1", "robot2"], [_timed(0.0), _timed(1.0)], [lock], ids)


def _rgb(hex_color: str) -> np.ndarray:
    return np.array([int(hex_color[k : k + 2], 16) for k in (1, 3, 5)])


def _image(data: bytes) -> np.ndarray:
    return np.asarray(Image.open(io.BytesIO(data)).convert("RGB"), dtype=int)


def _mask(img: np.ndarray, hex_color: str) -> np.ndarray:
    return np.all(img == _rgb(hex_color), axis=2)


def test_the_png_is_the_same_bytes_twice_and_written_whole(schedule, tmp_path):
    from weldplan.viz.gantt import DPI, WIDTH_IN, gantt_png, gantt_png_bytes

    a = gantt_png(schedule, tmp_path / "a.png", bound=3.0).read_bytes()
    b = gantt_png_bytes(schedule, bound=3.0)
    assert a == b
    assert b"matplotlib" not in a  # no Software stamp
    img = _image(a)
    assert img.shape[1] == int(WIDTH_IN * DPI)
    assert img.std() > 20  # not blank
    assert gantt_png_bytes(schedule, bound=3.5) != b  # the bound is drawn


def test_each_robots_row_holds_its_bars_colours(schedule):
    from weldplan.viz.gantt import KIND_COLORS, bar_rows, gantt_png_bytes

    img = _image(gantt_png_bytes(schedule))
    h = img.shape[0]
    rows = {r: img[int(top * h) + 2 : int(bottom * h) - 1] for r, top, bottom in bar_rows(schedule)}
    for r, band in rows.items():
        kinds = {a.kind for a in schedule.of(r)}
        for kind, color in KIND_COLORS.items():
            present = _mask(band, color).sum()
            assert (present > 50) == (kind in kinds), (r, kind, present)
    assert "wait" not in {a.kind for a in schedule.of(0)}  # so the test above can fail


def test_a_wait_bar_spans_its_duration_on_the_charts_scale(schedule):
    from weldplan.viz.gantt import KIND_COLORS, bar_rows, gantt_png_bytes

    img = _image(gantt_png_bytes(schedule))
    h = img.shape[0]
    _, top, bottom = bar_rows(schedule)[1]
    mid = img[int((top + bottom) / 2 * h)]  # one pixel line through robot 2's bars
    coloured = np.flatnonzero(
        np.any([np.all(mid == _rgb(c), axis=1) for c in KIND_COLORS.values()], axis=0)
    )
    wait_px = np.flatnonzero(np.all(mid == _rgb(KIND_COLORS["wait"]), axis=1))
    # the scale from the row itself: its first bar starts at 0 s, its last ends at its cycle
    px_per_s = (coloured[-1] + 1 - coloured[0]) / schedule.cycle_times[1]
    (wait,) = [a for a in schedule.of(1) if a.kind == "wait"]
    assert wait.duration > 1.0
    assert abs((wait_px[-1] + 1 - wait_px[0]) - wait.duration * px_per_s) <= 2.0
    assert abs((wait_px[0] - coloured[0]) - wait.start * px_per_s) <= 2.0


def test_the_svg_names_the_welds_and_the_interlock_and_places_its_time_axis(schedule):
    from weldplan.viz.gantt import KIND_COLORS, bar_rows, gantt_png_bytes, gantt_svg

    g = gantt_svg(schedule, bound=3.0)
    assert g.svg.startswith("<svg") and g.svg.rstrip().endswith("</svg>")
    for text in ("Z1_R1_R2", "w1", "v4", "robot2", "bound 3.00 s", "station time (s)"):
        assert text in g.svg, text
    assert g.svg == gantt_svg(schedule, bound=3.0).svg
    # the axis fractions are those of the PNG of the same chart: the wait's edges land on them
    img = _image(gantt_png_bytes(schedule, bound=3.0))
    h, w = img.shape[:2]
    _, top, bottom = bar_rows(schedule)[1]
    wait_px = np.flatnonzero(_mask(img[int((top + bottom) / 2 * h)][None], KIND_COLORS["wait"])[0])
    (wait,) = [a for a in schedule.of(1) if a.kind == "wait"]
    assert abs(g.x_of(wait.start) * w - wait_px[0]) <= 1.5
    assert abs(g.x_of(wait.end) * w - (wait_px[-1] + 1)) <= 1.5
    assert 0 < g.y0 < top < bottom < g.y1 < 1


def test_an_idle_robot_gets_an_empty_row_said_idle():
    from weldplan.viz.gantt import KIND_COLORS, bar_rows, gantt_png_bytes, gantt_svg

    s = station_schedule(["robot1", "robot2", "robot3"], [_timed(0.0), None, _timed(2.0, 2)])
    img = _image(gantt_png_bytes(s))
    h = img.shape[0]
    for r, top, bottom in bar_rows(s):
        band = img[int(top * h) + 2 : int(bottom * h) - 1]
        bars = sum(_mask(band, c).sum() for c in KIND_COLORS.values())
        assert (bars > 50) == (r != 1), r
    assert "> idle</text>" in gantt_svg(s).svg
