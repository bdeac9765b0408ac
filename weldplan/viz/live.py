"""A live meshcat server that listens where it is told (127.0.0.1 by default) and dies with us.

meshcat's own ``Visualizer()`` starts ``python -m meshcat.servers.zmqserver`` in a new session: its
web server binds every interface (``0.0.0.0`` and ``::``, port 7000 and up) whatever host it
prints, and the process outlives a parent killed by a signal (its only cleanup is an ``atexit``
hook, which SIGTERM skips). :class:`MeshcatServer` runs the same bridge
(``meshcat.servers.zmqserver.ZMQWebSocketBridge``) in a child process
(``python -m weldplan.viz.live --host H``) whose web server binds ``H`` only (its ZMQ socket,
which takes scene commands, always binds 127.0.0.1), and
which exits when its parent is gone: on Linux the kernel sends it SIGTERM when the parent dies
(``PR_SET_PDEATHSIG``), and everywhere it polls its parent id once a second. The parent stops it
with :meth:`MeshcatServer.close` (SIGTERM, then SIGKILL after a grace period).
"""

from __future__ import annotations

import contextlib
import logging
import os
import signal
import subprocess
import sys
from typing import Any

log = logging.getLogger(__name__)

#: where the viewer listens unless told otherwise: this machine only
DEFAULT_HOST = "127.0.0.1"
#: seconds to wait for the server to print its URLs, and for it to exit on close
START_TIMEOUT = 30.0
STOP_TIMEOUT = 5.0


def _die_with_parent() -> None:  # pragma: no cover - runs in the child before exec
    """``preexec_fn``: ask Linux to send SIGTERM to this process when its parent dies."""
    try:
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        pr_set_pdeathsig = 1
        libc.prctl(pr_set_pdeathsig, signal.SIGTERM)
    except (OSError, AttributeError):
        pass


class MeshcatServer:
    """A meshcat ZMQ + web server in a child process, bound to ``host``.

    Parameters
    ----------
    host
        The address to bind (``127.0.0.1`` by default; ``0.0.0.0`` opens it to the network).
    port
        Web port; None: the first free one from meshcat's 7000.

    Attributes
    ----------
    zmq_url, web_url
        Where a ``meshcat.Visualizer(zmq_url=...)`` connects, and the page a browser opens.
    proc
        The ``subprocess.Popen`` of the server.
    """

    def __init__(self, host: str = DEFAULT_HOST, port: int | None = None) -> None:
        args = [sys.executable, "-u", "-m", "weldplan.viz.live", "--host", host]
        if port is not None:
            args += ["--port", str(int(port))]
        self.host = host
        # the child imports this weldplan, wherever the current folder is
        package_root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
        path = os.environ.get("PYTHONPATH")
        env = {**os.environ, "PYTHONPATH": package_root + (os.pathsep + path if path else "")}
        self.proc = subprocess.Popen(
            args,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            env=env,
            preexec_fn=_die_with_parent if sys.platform.startswith("linux") else None,
        )
        try:
            self.zmq_url, self.web_url = self._read_urls()
        except BaseException:
            self.close()
            raise
        log.info("meshcat server pid %d: %s (zmq %s)", self.proc.pid, self.web_url, self.zmq_url)

    def _read_urls(self) -> tuple[str, str]:
        assert self.proc.stdout is not None
        urls: dict[str, str] = {}
        while len(urls) < 2:
            line = self.proc.stdout.readline().decode("utf-8", "replace").strip()
            if not line and self.proc.poll() is not None:
                err = self.proc.stderr.read().decode("utf-8", "replace") if self.proc.stderr else ""
                last = err.strip().splitlines()[-1:] or ["no output"]
                raise OSError(f"the meshcat server exited ({self.proc.returncode}): {last[0]}")
            key, _, value = line.partition("=")
            if key in ("zmq_url", "web_url"):
                urls[key] = value
        return urls["zmq_url"], urls["web_url"]

    def close(self) -> None:
        """Stop the server (SIGTERM, then SIGKILL) and reap it; safe to call twice."""
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(STOP_TIMEOUT)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        for f in (self.proc.stdout, self.proc.stderr):
            if f is not None:
                f.close()

    def __enter__(self) -> MeshcatServer:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()


def _serve(host: str, port: int | None) -> None:  # pragma: no cover - runs in the child
    """The child: meshcat's bridge with every socket bound to ``host``; exits with its parent."""
    import tornado.ioloop
    from meshcat.servers.zmqserver import ZMQWebSocketBridge

    class Bridge(ZMQWebSocketBridge):
        def make_app(self) -> Any:
            app = super().make_app()
            listen = app.listen
            # meshcat calls app.listen(port), which binds every interface: bind the host given
            app.listen = lambda port, **kw: listen(port, address=host, **kw)  # type: ignore[method-assign]
            return app

    parent = os.getppid()
    # the ZMQ socket takes scene commands: this machine only, whatever the web host
    bridge = Bridge(host=DEFAULT_HOST, port=port)
    web_url = bridge.web_url.replace(f"//{DEFAULT_HOST}:", f"//{host}:", 1)
    # the child's stdout is its protocol with MeshcatServer._read_urls (as meshcat's server)
    sys.stdout.write(f"zmq_url={bridge.zmq_url}\nweb_url={web_url}\n")
    sys.stdout.flush()
    loop = tornado.ioloop.IOLoop.current()

    def stop(*_: Any) -> None:
        raise KeyboardInterrupt

    def orphaned() -> None:
        if os.getppid() != parent:
            loop.stop()

    signal.signal(signal.SIGTERM, stop)
    signal.signal(signal.SIGINT, stop)
    tornado.ioloop.PeriodicCallback(orphaned, 1000).start()
    with contextlib.suppress(KeyboardInterrupt):
        bridge.run()


def main(argv: list[str] | None = None) -> None:  # pragma: no cover - runs in the child
    import argparse

    p = argparse.ArgumentParser(prog="python -m weldplan.viz.live")
    p.add_argument("--host", default=DEFAULT_HOST)
    p.add_argument("--port", type=int)
    a = p.parse_args(argv)
    _serve(a.host, a.port)


if __name__ == "__main__":  # pragma: no cover
    main()
