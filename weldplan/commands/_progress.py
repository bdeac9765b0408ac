"""Progress bars for the command line: one line per stage on a terminal, silent otherwise.

The library reports progress through callbacks (``progress(stage, done, total)``); this turns
them into bars on stderr, with counts, elapsed seconds and, once a stage has made progress, an
estimate of the time left (from its rate since the stage began). It draws only when the
stream is a terminal and ``--quiet`` was not given, so pipes, logs and CI output stay clean.
"""

from __future__ import annotations

import re
import sys
import time
from typing import TextIO

#: stage name -> label shown on the bar
LABELS = {
    "cell": "cell (grid)",
    "cost": "leg times",
    "straight": "straight pairs",
    "local": "local paths",
    "sequence": "sequencing",
    "route": "route",
    "verify": "verifying",
    "reach": "reach",
    "poses": "gun poses",
    "transitions": "transitions",
    "robot": "robot motion",
    "program": "program",
    "export": "writing",
    "study": "robot studies",
    "allocation": "allocation",
    "plan": "robots' shares",
    "interference": "interference",
}

#: a station's event of one robot's share: ``"robot2 local"`` (weldplan.multi.shares)
_ROBOT_STAGE = re.compile(r"robot(\d+) (.+)")


def label(stage: str) -> str:
    """The words a bar shows for ``stage``: its :data:`LABELS` entry, and for one robot's
    stage of a station ``"robot 2: local paths"`` (not the raw ``"robot2 local"``)."""
    m = _ROBOT_STAGE.fullmatch(stage)
    if m is not None:
        return f"robot {m.group(1)}: {LABELS.get(m.group(2), m.group(2))}"
    return LABELS.get(stage, stage)


class ProgressBars:
    """Callable ``(stage, done, total)`` drawing a bar per stage on ``stream``.

    Parameters
    ----------
    enabled
        Draw at all; None = only when ``stream`` is a terminal.
    stream
        Where to draw (stderr by default, so stdout keeps only the summary).
    """

    def __init__(self, enabled: bool | None = None, stream: TextIO | None = None) -> None:
        self.stream = sys.stderr if stream is None else stream
        if enabled is None:
            enabled = bool(getattr(self.stream, "isatty", lambda: False)())
        self.enabled = enabled
        self._stage: str | None = None
        self._t0 = time.perf_counter()
        self._last = 0.0
        self._done0 = 0

    def __call__(self, stage: str, done: int, total: int) -> None:
        if not self.enabled:
            return
        now = time.perf_counter()
        if stage != self._stage:
            self.close()
            self._stage = stage
            self._t0 = now
            self._done0 = done
        elif done < total and now - self._last < 0.05:
            return  # at most 20 redraws a second
        self._last = now
        width = 28
        frac = 1.0 if total <= 0 else min(done / total, 1.0)
        fill = int(round(frac * width))
        words = label(stage)
        elapsed = now - self._t0
        eta = ""
        if 0 < done < total and done > self._done0 and elapsed > 0.5:
            eta = f"  ETA {elapsed / (done - self._done0) * (total - done):6.1f} s"
        self.stream.write(
            f"\r{words:<15} [{'#' * fill}{'.' * (width - fill)}] {done}/{total} "
            f"{elapsed:6.2f} s{eta}  "
        )
        self.stream.flush()

    def close(self) -> None:
        """End the current bar's line."""
        if self.enabled and self._stage is not None:
            self.stream.write("\n")
            self.stream.flush()
        self._stage = None

    def stage(self, stage: str) -> _Stage:
        """Context manager showing a bar that completes when the block ends."""
        return _Stage(self, stage)


class _Stage:
    def __init__(self, bars: ProgressBars, stage: str) -> None:
        self.bars = bars
        self.name = stage
        self.seconds = 0.0

    def __enter__(self) -> _Stage:
        self._t = time.perf_counter()
        self.bars(self.name, 0, 1)
        return self

    def __exit__(self, *exc: object) -> None:
        self.seconds = time.perf_counter() - self._t
        if exc[0] is None:
            self.bars(self.name, 1, 1)
        self.bars.close()
