"""Issue 14 item 5: ``weldplan view`` listens on 127.0.0.1 only, stops on SIGINT and SIGTERM,
and leaves no server process behind. Real processes and sockets, checked with psutil."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from tests.route_fixtures import box_route

psutil = pytest.importorskip("psutil")
pytest.importorskip("meshcat")

ROOT = Path(__file__).resolve().parents[1]


def _start(tmp_path: Path, *extra: str) -> tuple[subprocess.Popen, str]:
    route = tmp_path / "route.json"
    route.write_text(box_route().to_json())
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    proc = subprocess.Popen(
        [sys.executable, "-m", "weldplan", "view", str(route), "--no-browser", *extra],
        cwd=ROOT,
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    deadline = time.monotonic() + 60
    line = ""
    while "meshcat viewer at" not in line:
        line = proc.stdout.readline()
        if (not line and proc.poll() is not None) or time.monotonic() > deadline:
            proc.kill()
            raise AssertionError(f"viewer did not start: {proc.stderr.read()}")
    return proc, line


def _listening(pids: list[int]) -> list[tuple[str, int]]:
    out = []
    for c in psutil.net_connections(kind="inet"):
        if c.status == psutil.CONN_LISTEN and c.pid in pids:
            out.append((c.laddr.ip, c.laddr.port))
    return out


def _gone(pids: list[int], timeout: float = 10.0) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        alive = [p for p in pids if psutil.pid_exists(p) and psutil.Process(p).status() != "zombie"]
        if not alive:
            return True
        time.sleep(0.1)
    return False


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT])
def test_view_listens_on_localhost_and_stops_cleanly(tmp_path, sig):
    proc, line = _start(tmp_path)
    try:
        assert "http://127.0.0.1:" in line
        children = [c.pid for c in psutil.Process(proc.pid).children(recursive=True)]
        assert children, "the meshcat server runs in a child process"
        addrs = _listening([proc.pid, *children])
        assert addrs, "the viewer listens somewhere"
        assert {ip for ip, _ in addrs} == {"127.0.0.1"}, addrs
        proc.send_signal(sig)
        assert proc.wait(timeout=15) == 0
        assert "Traceback" not in proc.stderr.read()
        assert _gone(children), "the meshcat server outlived weldplan view"
    finally:
        if proc.poll() is None:
            proc.kill()
        proc.stdout.close()
        proc.stderr.close()


@pytest.mark.slow
def test_server_dies_with_a_killed_viewer(tmp_path):
    """SIGKILL gives weldplan no chance to clean up: the server must notice on its own."""
    proc, _ = _start(tmp_path)
    children = [c.pid for c in psutil.Process(proc.pid).children(recursive=True)]
    try:
        proc.kill()
        proc.wait(timeout=10)
        assert _gone(children), "the meshcat server outlived a killed weldplan view"
    finally:
        for p in children:
            if psutil.pid_exists(p):
                os.kill(p, signal.SIGKILL)
        proc.stdout.close()
        proc.stderr.close()


@pytest.mark.slow
def test_explicit_host_is_the_one_bound(tmp_path):
    """--host names the web server's address (here another loopback address, so the test opens
    nothing to the network); the ZMQ command socket stays on 127.0.0.1."""
    proc, line = _start(tmp_path, "--host", "127.0.0.2")
    try:
        assert "http://127.0.0.2:" in line
        children = [c.pid for c in psutil.Process(proc.pid).children(recursive=True)]
        ips = {ip for ip, _ in _listening([proc.pid, *children])}
        assert ips == {"127.0.0.1", "127.0.0.2"}, ips
        proc.terminate()
        assert proc.wait(timeout=15) == 0
        assert _gone(children)
    finally:
        if proc.poll() is None:
            proc.kill()
        proc.stdout.close()
        proc.stderr.close()
