"""The feasibility study's stack column from the mesh (weldplan.study.stacks), against the
sheet-metal generator's own ground truth."""

from __future__ import annotations

import numpy as np
import pytest

from weldplan.study.stacks import flange_stacks, stack_words
from weldplan.weld.sheetmetal import generate_side_frame

pytest.importorskip("open3d")


@pytest.fixture(scope="module")
def frame():
    return generate_side_frame(rng=0)


def test_each_generated_spot_names_the_two_sheets_of_its_flange(frame):
    pick = np.arange(0, len(frame.spots), 15)
    words = flange_stacks()(frame.sheets, np.asarray(frame.spots.xyz)[pick])
    flanges = {f.name: f for f in frame.flanges}
    for k, w in zip(pick, words, strict=True):
        f = flanges[frame.spot_flange[k]]
        assert not w.startswith("none"), w
        assert all(b in w for b in f.bodies), (w, f.bodies)
        assert f"gap {f.gap:.2f} mm" in w, w


def test_a_spot_off_the_sheets_and_one_on_a_single_skin_say_why(frame):
    sill = frame.members[0]
    far = [1000.0, -30.0 - 0.2 - sill.t_inner, 80.0]  # 30 mm from the inner panel
    crown = [1000.0, sill.profile.depth + sill.t_hat, 81.5]  # the hat's crown, one sheet
    words = flange_stacks()(frame.combined(), np.array([far, crown]))
    assert words[0].startswith("none: no sheet: no sheet within"), words[0]
    assert words[1].startswith("none: single skin:"), words[1]


def test_the_study_fills_its_stack_column_from_the_hook(frame):
    """check_spots with the hook: the column is the hook's words (not 'not analysed'), and a
    spot off the part keeps the study's own 'no surface' verdict."""
    from weldplan.geometry.flanges import snap_spots
    from weldplan.geometry.stacks import FlangeSettings
    from weldplan.study.feasibility import _stacks

    part = frame.combined()
    spots = frame.spots
    near = np.ones(len(spots), dtype=bool)
    near[3] = False
    got = _stacks(flange_stacks(), part, spots, near)
    want = [stack_words(s) for s in snap_spots(part, spots.xyz, FlangeSettings())]
    assert got[3] == "none (no surface)"
    assert got[:3] == want[:3] and got[4:] == want[4:]


def test_with_walls_a_thin_single_sheet_at_a_free_edge_is_a_wall_and_one_without_is_not(frame):
    sill = frame.members[0]
    crown = [1000.0, sill.profile.depth + sill.t_hat, 81.5]  # no free edge within reach
    word = flange_stacks(walls=True)(frame.sheets, np.array([crown]))[0]
    assert word.startswith("none: "), word
