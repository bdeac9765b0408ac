"""The tool stage's settings objects (weldplan.tool.settings): checked once, when made, with a
ConfigError naming the field; the station's ToolSettings mapped onto them in one place
(weldplan.station.toolstage)."""

from __future__ import annotations

import math

import pytest

from weldplan.errors import ConfigError
from weldplan.station.settings import ToolSettings
from weldplan.station.toolstage import order_settings, pose_settings, transition_settings
from weldplan.tool.settings import OrderSettings, PoseSearchSettings, TransitionSettings


@pytest.mark.parametrize(
    ("cls", "field", "value"),
    [
        (PoseSearchSettings, "cone", -1.0),
        (PoseSearchSettings, "tilt_step", 0.0),
        (PoseSearchSettings, "spin_step", math.nan),
        (PoseSearchSettings, "azimuths", 0),
        (PoseSearchSettings, "contact_radius", -0.5),
        (PoseSearchSettings, "clearance", -1.0),
        (PoseSearchSettings, "both_sides", "yes"),
        (PoseSearchSettings, "max_vetoes", 2.5),
        (TransitionSettings, "retract", -1.0),
        (TransitionSettings, "side_exit", math.inf),
        (TransitionSettings, "time_s", 0.0),
        (TransitionSettings, "rot_weight", 0.0),
        (TransitionSettings, "min_step", 0.0),
        (TransitionSettings, "se3", 1),
        (TransitionSettings, "planner", ""),
        (TransitionSettings, "seed", -1),
        (TransitionSettings, "se3_samples", 0),
        (TransitionSettings, "se3_checks", 0),
        (OrderSettings, "rot_weight", -1.0),
        (OrderSettings, "keep_order", None),
        (OrderSettings, "rounds", 0),
    ],
)
def test_a_bad_field_is_a_config_error_naming_it(cls, field, value):
    with pytest.raises(ConfigError) as e:
        cls(**{field: value})
    assert e.value.field == field and field in str(e.value)


def test_the_settings_are_frozen_and_compare_by_value():
    s = TransitionSettings(retract=30)
    assert s.retract == 30.0 and isinstance(s.retract, float)  # normalised once
    assert s == TransitionSettings(retract=30.0) != TransitionSettings()
    with pytest.raises(AttributeError):
        s.retract = 40.0  # type: ignore[misc]


def test_the_station_maps_its_tool_settings_in_one_place():
    ts = ToolSettings(cone=10.0, contact_radius=15.0, retract=40.0, side_exit=0.0, slide=False,
                      rot_weight=0.0, order="route", se3_time=0.0)  # fmt: skip
    assert pose_settings(ts) == PoseSearchSettings(cone=10.0, contact_radius=15.0)
    t = transition_settings(ts, seed=7)
    # no SE(3) re-plan at se3_time 0, its clock a positive placeholder; the SE(3) metric's
    # weight at least 1 mm per rad, while the order weighs rotation by the station's 0
    assert (t.retract, t.side_exit, t.slide, t.se3, t.time_s, t.seed, t.rot_weight) == (
        40.0, 0.0, False, False, 1e-3, 7, 1.0,
    )  # fmt: skip
    assert order_settings(ts) == OrderSettings(rot_weight=0.0, keep_order=True)
    d = ToolSettings()
    assert transition_settings(d, 0) == TransitionSettings()  # the station's defaults are these
    assert pose_settings(d) == PoseSearchSettings() and order_settings(d) == OrderSettings()
