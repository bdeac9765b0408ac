"""argparse types of the commands' options: numbers in a range, a seed.

Each raises :class:`argparse.ArgumentTypeError`, which the parser turns into one line naming the
option (``weldplan plan: error: argument --pitch: ...``)."""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable


def number_type(
    kind: str, lo: float, hi: float, *, lo_open: bool = False
) -> Callable[[str], float]:
    """argparse type: a finite number in ``[lo, hi]`` (``(lo, hi]`` when ``lo_open``); the
    error says it is a ``kind`` (``"number of mm"``) in that range."""

    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
        ok = math.isfinite(value) and (value > lo if lo_open else value >= lo) and value <= hi
        if not ok:
            bounds = f"{'(' if lo_open else '['}{lo:g}, {hi:g}]"
            raise argparse.ArgumentTypeError(f"must be a {kind} in {bounds}, got {text!r}")
        return value

    return parse


#: a positive, finite number of millimetres
positive_mm = number_type("number of mm", 0.0, math.inf, lo_open=True)
#: a finite number of millimetres >= 0
nonneg_mm = number_type("number of mm", 0.0, math.inf)
#: a finite number of millimetres
finite_mm = number_type("number of mm", -math.inf, math.inf)
#: a positive, finite number of GB
positive_gb = number_type("number of GB", 0.0, math.inf, lo_open=True)
#: a cone's half-angle, degrees in (0, 90]
cone_degrees = number_type("number of degrees", 0.0, 90.0, lo_open=True)


def seed_type(text: str) -> int:
    """argparse type: an integer >= 0 (what numpy's ``default_rng`` takes)."""
    from weldplan.errors import ConfigError
    from weldplan.weld.validate import seed

    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not an integer: {text!r}") from None
    try:
        return seed(value)
    except ConfigError as exc:
        raise argparse.ArgumentTypeError(exc.message) from None
