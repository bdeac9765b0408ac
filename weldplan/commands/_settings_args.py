"""Command-line options made from the stage settings' fields.

Each field of a stage's settings object (:class:`~weldplan.station.model.CellSettings`,
:class:`~weldplan.station.model.RouteSettings`, :class:`~weldplan.station.model.ToolSettings`,
:class:`~weldplan.station.model.RobotSettings`, and the station's ``clearance``) declares its
option in its metadata (:func:`weldplan.station.model.setting`): the option's default, help and
choices are the field's, its value is checked by the settings object's own validation, and its
help names the station file's key. A setting is declared once (../shared/DESIGN.md, "settings
objects, not long signatures"), so an option and its station-file key cannot drift.
"""

from __future__ import annotations

import argparse
import dataclasses
from collections.abc import Callable, Iterable
from typing import Any

from weldplan.errors import ConfigError


def add_settings_options(
    group: Any, cls: type, section: str | None, *, only: Iterable[str] | None = None
) -> None:
    """Add an option for every field of ``cls`` that declares one (``only``: these fields).

    Parameters
    ----------
    group
        The parser or argument group the options join.
    cls
        The settings dataclass; each option's ``dest`` is its field's name.
    section
        Where the station file sets these fields (``"[cell]"``; ``""``: the file's top level;
        ``None``: not a station's settings), said in each option's help.
    only
        Field names to add (default: every field with an option).
    """
    names = None if only is None else set(only)
    for f in dataclasses.fields(cls):
        meta = f.metadata
        if "option" not in meta or (names is not None and f.name not in names):
            continue
        key = None if section is None else f"{section} {f.name}" if section else f.name
        kw: dict[str, Any] = {"dest": f.name, "default": f.default}
        notes = [] if key is None else [f"station file: {key}"]
        if isinstance(f.default, bool):
            kw["action"] = "store_false" if meta["option"].startswith("--no-") else "store_true"
            notes = [f"{n} = {str(not f.default).lower()}" for n in notes]
        else:
            kw.update(type=_parser(cls, f.name), metavar=meta["metavar"], choices=meta["choices"])
            notes = ([] if f.default is None else [f"default {_fmt(f.default)}"]) + notes
        kw["help"] = _escape(f"{meta['help']} ({'; '.join(notes)})" if notes else meta["help"])
        group.add_argument(meta["option"], **kw)


def settings_from_args(cls: type, args: argparse.Namespace, **given: Any) -> Any:
    """``cls`` from the options' values (a field whose option the parser lacks keeps its
    default; ``given``: fields set by the caller)."""
    kw = {
        f.name: getattr(args, f.name, f.default)
        for f in dataclasses.fields(cls)
        if "option" in f.metadata and f.name not in given
    }
    return cls(**kw, **given)


def _parser(cls: type, name: str) -> Callable[[str], Any]:
    """argparse type of field ``name``: the text as the field's type (``str``, ``int``, else a
    float), checked by ``cls``'s own validation of that field alone (a rule that
    ties two fields is checked when the whole object is made)."""
    t = next(f.type for f in dataclasses.fields(cls) if f.name == name)
    annotation = t if isinstance(t, str) else getattr(t, "__name__", None) or str(t)
    to: Callable[[str], Any] = {"str": str, "int": int}.get(annotation.split()[0], float)
    if annotation.startswith("tuple"):  # numbers separated by commas, e.g. a robot's home
        to = _numbers

    def parse(text: str) -> Any:
        try:
            value = to(text)
        except ValueError:
            what = "an integer" if to is int else "numbers" if "," in text else "a number"
            raise argparse.ArgumentTypeError(f"not {what}: {text!r}") from None
        try:
            cls(**{name: value})
        except ConfigError as exc:
            if exc.field in (None, name):
                raise argparse.ArgumentTypeError(exc.message) from None
        return value

    return parse


def _numbers(text: str) -> tuple[float, ...]:
    """``"0,-90,90"`` -> ``(0.0, -90.0, 90.0)``; ValueError on a word that is not a number."""
    return tuple(float(v) for v in text.split(","))


def _fmt(v: Any) -> str:
    return f"{v:g}" if isinstance(v, float) else str(v)


def _escape(text: str) -> str:
    """``text`` as an argparse help string (which %-formats it)."""
    return text.replace("%", "%%")
