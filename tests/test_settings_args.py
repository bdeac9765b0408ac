"""The option groups of ``weldplan plan`` come from the stage settings' fields (issue 28, Build
2): one group per stage, each option's default, help and checks the field's, so an option and
its station-file key cannot drift."""

from __future__ import annotations

import argparse
import dataclasses

import pytest

import weldplan.station.model as m
from weldplan.cli import build_parser
from weldplan.commands._settings_args import add_settings_options, settings_from_args

#: each stage's settings, the title word of its help group, its station-file section
STAGES = [
    (m.CellSettings, "cell stage", "[cell]"),
    (m.RouteSettings, "route stage", "[route]"),
    (m.ToolSettings, "tool stage", "[tool_settings]"),
    (m.RobotSettings, "robot stage", "[[robot]]"),
]
#: the station's own fields in a stage's group
EXTRA = {"cell stage": {"clearance"}}


def _subparser(name: str) -> argparse.ArgumentParser:
    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return sub.choices[name]


def _group(p: argparse.ArgumentParser, word: str) -> argparse._ArgumentGroup:
    (g,) = [g for g in p._action_groups if (g.title or "").startswith(word)]
    return g


@pytest.mark.parametrize(("cls", "word", "section"), STAGES)
def test_every_setting_is_one_option_of_its_stage_group_with_the_field_default(cls, word, section):
    p = _subparser("plan")
    group = {a.dest: a for a in _group(p, word)._group_actions}
    for f in dataclasses.fields(cls):
        assert f.name in group, f"{cls.__name__}.{f.name} has no option in '{word}'"
        action = group[f.name]
        assert action.option_strings == [f.metadata["option"]]
        assert action.default == f.default
        assert f"{section} {f.name}" in action.help  # the station file's key
    assert set(group) == {f.name for f in dataclasses.fields(cls)} | EXTRA.get(word, set())


@pytest.mark.parametrize(("cls", "word", "section"), STAGES)
def test_no_options_give_the_default_settings(cls, word, section):
    args = _subparser("plan").parse_args(["part.stl", "welds.csv", "-o", "r.csv"])
    assert settings_from_args(cls, args) == cls()


def test_options_set_their_fields_and_no_flags_clear_them():
    argv = ["part.stl", "welds.csv", "-o", "r.csv", "--no-refine", "--smooth", "--aco", "7",
            "--tool-cone", "12.5", "--no-slide", "--tool-order", "route", "--approach-cone", "30",
            "--weld-time", "0.25", "--roadmap", "--clearance", "3"]  # fmt: skip
    args = _subparser("plan").parse_args(argv)
    route = settings_from_args(m.RouteSettings, args)
    assert (route.refine, route.smooth, route.aco) == (False, True, 7)
    tool = settings_from_args(m.ToolSettings, args)
    assert (tool.cone, tool.slide, tool.order, tool.exit_check) == (12.5, False, "route", True)
    assert settings_from_args(m.CellSettings, args).approach_cone == 30.0
    robot = settings_from_args(m.RobotSettings, args)
    assert (robot.weld_time, robot.roadmap, robot.home) == (0.25, True, None)
    assert args.clearance == 3.0
    args = _subparser("plan").parse_args(argv + ["--home", "90,-90,90,0,0,0"])
    assert settings_from_args(m.RobotSettings, args).home == (90.0, -90.0, 90.0, 0.0, 0.0, 0.0)


@pytest.mark.parametrize(
    ("option", "value", "words"),
    [
        ("--tool-cone", "95", "cone must be a number in [0, 90]"),
        ("--approach-cone", "0", "approach_cone must be a number in (0, 90]"),
        ("--acc-scale", "1.5", "acc_scale must be a number in (0, 1]"),
        ("--aco", "2.5", "not an integer"),
        ("--moves", "fast", "moves must be one of linear, joint"),
        ("--home", "0,-90,x", "not numbers"),
        ("--home", "0,-90,nan,0,0,0", "home must be a number"),
    ],
)
def test_a_bad_value_is_refused_by_the_settings_own_check_naming_the_option(
    capsys, option, value, words
):
    with pytest.raises(SystemExit) as e:
        _subparser("plan").parse_args(["part.stl", "welds.csv", "-o", "r.csv", option, value])
    assert e.value.code == 2
    err = capsys.readouterr().err
    assert f"argument {option}" in err and words in err


def test_a_rule_between_two_fields_waits_for_the_whole_object():
    """A field checked alone passes when only its pairing is wrong; the object then refuses."""

    @dataclasses.dataclass(frozen=True)
    class Pair:
        lo: float = m.setting(0.0, "--lo", "low")
        hi: float = m.setting(1.0, "--hi", "high")

        def __post_init__(self) -> None:
            if self.lo > self.hi:
                raise m.ConfigError("lo must not exceed hi", field="hi")
            if self.lo < 0:
                raise m.ConfigError("lo must be >= 0", field="lo")

    p = argparse.ArgumentParser()
    add_settings_options(p, Pair, "[pair]")
    args = p.parse_args(["--lo", "5", "--hi", "6"])  # lo = 5 alone breaks hi's rule: not lo's
    assert settings_from_args(Pair, args) == Pair(5.0, 6.0)
    with pytest.raises(m.ConfigError, match="lo must not exceed hi"):
        settings_from_args(Pair, p.parse_args(["--lo", "5"]))
    with pytest.raises(SystemExit):
        p.parse_args(["--lo", "-1"])


def test_the_demo_keeps_its_own_cell_options():
    p = _subparser("demo")
    group = {a.dest for a in _group(p, "cell stage")._group_actions}
    assert group == {"clearance", "pitch", "margin"}


def test_an_option_parses_as_its_field_type_with_or_without_postponed_annotations():
    real = dataclasses.make_dataclass(
        "Real",
        [("n", int, m.setting(3, "--n", "n")), ("k", int | None, m.setting(None, "--k", "k")),
         ("x", float, m.setting(1.0, "--x", "x")), ("s", str, m.setting("a", "--s", "s"))],
        frozen=True,
    )  # fmt: skip
    for cls in (real, _Postponed):
        p = argparse.ArgumentParser()
        add_settings_options(p, cls, None)
        got = settings_from_args(
            cls, p.parse_args(["--n", "4", "--k", "5", "--x", "2", "--s", "b"])
        )
        assert (got.n, got.k, got.x, got.s) == (4, 5, 2.0, "b")
        assert [type(v) for v in (got.n, got.k, got.x)] == [int, int, float]


@dataclasses.dataclass(frozen=True)
class _Postponed:
    n: int = m.setting(3, "--n", "n")
    k: int | None = m.setting(None, "--k", "k")
    x: float = m.setting(1.0, "--x", "x")
    s: str = m.setting("a", "--s", "s")
