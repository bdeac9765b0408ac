"""Run ``python -m weldplan`` in a child process, with a memory ceiling and a time limit.

For the cases that must not run in the test process: ones that may allocate gigabytes or hang
(huge grids, 100,000 joints, an unreachable scheduler), and ones whose C libraries write to the
real stderr (which in-process capture does not see).
"""

from __future__ import annotations

import os
import resource
import subprocess
import sys

from tests.conftest import ROOT
from tests.faults.harness import Outcome


def run_weldplan(argv: list, *, memory_gb: float = 3.0, timeout: float = 120.0) -> Outcome:
    """Exit code (``None`` on timeout), stdout, stderr; ``crash`` holds stderr when it shows a
    traceback or the child was killed (memory ceiling: ``RLIMIT_AS``)."""
    limit = int(memory_gb * 2**30)

    def ceiling() -> None:  # runs in the child
        resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
        os.nice(5)

    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    try:
        p = subprocess.run(
            [sys.executable, "-m", "weldplan", *[str(a) for a in argv]],
            capture_output=True,
            text=True,
            timeout=timeout,
            preexec_fn=ceiling,
            cwd=ROOT,
            env=env,
        )
    except subprocess.TimeoutExpired as exc:
        err = exc.stderr.decode() if isinstance(exc.stderr, bytes) else (exc.stderr or "")
        return Outcome(None, "", err, crash=f"timed out after {timeout} s")
    crash = p.stderr if ("Traceback" in p.stderr or p.returncode < 0) else None
    return Outcome(p.returncode, p.stdout, p.stderr, crash)
