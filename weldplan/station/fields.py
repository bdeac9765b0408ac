"""The station's field checks: numbers, choices, flags, paths, and :func:`setting`, a settings
field that carries its command-line option (:mod:`weldplan.station.settings`,
:mod:`weldplan.station.model`). Each check raises a :class:`~weldplan.errors.ConfigError` naming
the field; the TOML loader adds the file and the line."""

from __future__ import annotations

import math
from dataclasses import field
from os import PathLike
from pathlib import Path
from typing import Any

from weldplan.errors import ConfigError


def _number(name: str, v: Any, lo: float, hi: float = math.inf, *, lo_open: bool = False) -> float:
    """``v`` as a finite float in ``[lo, hi]`` (``(lo, hi]`` when ``lo_open``), else ConfigError."""
    ok = isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
    ok = ok and (v > lo if lo_open else v >= lo) and v <= hi
    if not ok:
        bounds = f"{'(' if lo_open else '['}{lo:g}, {hi:g}]"
        raise ConfigError(f"{name} must be a number in {bounds}, got {v!r}", field=name)
    return float(v)


def _optional(name: str, v: Any, lo: float, hi: float = math.inf, **kw: bool) -> float | None:
    return None if v is None else _number(name, v, lo, hi, **kw)


def _choice(name: str, v: Any, choices: tuple[str, ...]) -> str:
    if v not in choices:
        raise ConfigError(f"{name} must be one of {', '.join(choices)}; got {v!r}", field=name)
    return str(v)


def _flag(name: str, v: Any) -> bool:
    if not isinstance(v, bool):
        raise ConfigError(f"{name} must be true or false, got {v!r}", field=name)
    return v


def setting(
    default: Any, option: str, help: str, *, metavar: str | None = None,
    choices: tuple[str, ...] | None = None,
) -> Any:  # fmt: skip
    """A settings field with its command-line option: the field's default and ``help`` are the
    option's (:mod:`weldplan.commands._settings_args` builds the option groups of ``weldplan
    plan`` from this metadata), so an option and its station-file key cannot drift.

    Parameters
    ----------
    default
        The field's default (the option's).
    option
        The long option, e.g. ``"--tool-cone"``; a bool field's option is a flag that sets it
        (``"--smooth"``) or, named ``"--no-..."``, clears it (``"--no-slide"``).
    help
        What the setting does, with its unit; the default and the station-file key are added.
    metavar, choices
        The option's value placeholder and its allowed words.
    """
    meta = {"option": option, "help": help, "metavar": metavar, "choices": choices}
    return field(default=default, metadata=meta)


def _normalise(obj: Any, name: str, value: Any) -> None:
    object.__setattr__(obj, name, value)


def _path(obj: Any, name: str) -> None:
    """Field ``name`` of ``obj`` as a Path (None stays None), else a ConfigError."""
    v = getattr(obj, name)
    if v is None:
        return
    if not isinstance(v, (str, PathLike)):
        raise ConfigError(f"{name} must be a path, got {v!r}", field=name)
    _normalise(obj, name, Path(v))
