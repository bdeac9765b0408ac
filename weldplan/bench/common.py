"""Helpers shared by the benchmarks: machine conditions, child-process measurements, markdown."""

from __future__ import annotations

import json
import os
import platform
import subprocess
import sys
from pathlib import Path
from typing import Any

#: where the shared real data lives relative to the project root (data/README.md)
SHARED_DATA = Path(__file__).resolve().parents[2].parent / "shared" / "data"


def shared_path(*parts: str) -> Path:
    """Path of a shared data file, or a clear error when it is absent."""
    from weldplan.errors import WeldplanError

    path = SHARED_DATA.joinpath(*parts)
    if not path.exists():
        raise WeldplanError(f"benchmark data not found: {path} (see ../shared/data/README.md)")
    return path


def conditions() -> str:
    """One line on the machine: CPU count, load average, Python and numpy versions."""
    import numpy as np

    load = os.getloadavg() if hasattr(os, "getloadavg") else (float("nan"),) * 3
    return (
        f"{platform.node()} ({os.cpu_count()} CPUs), load average "
        f"{load[0]:.2f} {load[1]:.2f} {load[2]:.2f}; Python {platform.python_version()}, "
        f"numpy {np.__version__}"
    )


def run_child(code: str, timeout: float | None = None) -> dict[str, Any]:
    """Run ``code`` in a fresh interpreter; it must print one JSON object as its last line.

    A child per measurement keeps peak-memory figures (``ru_maxrss``) separate.
    """
    proc = subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        timeout=timeout,
        check=False,
        cwd=str(Path(__file__).resolve().parents[2]),
    )
    if proc.returncode != 0:
        raise RuntimeError(f"benchmark child failed:\n{proc.stderr[-3000:]}")
    return json.loads(proc.stdout.strip().splitlines()[-1])


#: prelude for child processes: RSS now, and peak RSS, in MiB
CHILD_PRELUDE = """
import json, resource, time
def rss_mib():
    with open('/proc/self/status') as f:
        for line in f:
            if line.startswith('VmRSS:'):
                return int(line.split()[1]) / 1024
    return float('nan')
def peak_mib():
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
"""


def table(header: list[str], rows: list[list[Any]]) -> str:
    """A markdown table."""
    out = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    out += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return "\n".join(out)
