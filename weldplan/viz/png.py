"""A static page as a PNG, for reports: rendered by headless Chromium, written whole or not at all.

:func:`render_png` writes the page (:func:`weldplan.viz.viewer.static_html`,
:func:`weldplan.viz.robot_scene.robot_html`, :func:`weldplan.viz.study_scene.study_html`) to a
temporary folder and runs ``chromium --headless --screenshot`` on it with a fixed window
(:class:`PngSettings`) and software WebGL (SwiftShader, so no GPU or display is needed). The page
opens as a user sees it: framed on the cell (:mod:`weldplan.viz.camera`), the tool or the robot
at the weld slider's first weld (or at ``weld``). Chromium's *virtual time budget* is the wait:
the page's clock runs only while the scene is being built and drawn, so the wait is counted in
page time, not in the machine's (a loaded machine renders the same picture, later).

Chromium is found as ``$WELDPLAN_CHROMIUM``, else ``chromium``, ``chromium-browser``,
``google-chrome`` or ``google-chrome-stable`` on the ``PATH``; without one,
:class:`~weldplan.errors.ConfigError` says which package to install. The PNG is checked (its
signature and size) before it replaces anything at ``path``.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import tempfile
from dataclasses import dataclass
from os import PathLike
from pathlib import Path
from urllib.parse import quote

from weldplan.errors import ConfigError, RunError

#: the executables tried, in order, after ``$WELDPLAN_CHROMIUM``
CHROMIUM_NAMES = ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable")
#: the one-line advice when none is found
INSTALL_HINT = (
    "no Chromium found to render the PNG: install it (Debian/Ubuntu: apt-get install chromium; "
    "Fedora: dnf install chromium) or set WELDPLAN_CHROMIUM to its executable"
)
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


@dataclass(frozen=True)
class PngSettings:
    """How a page is rendered.

    Attributes
    ----------
    width, height
        The window, pixels (the PNG's size).
    wait_ms
        Chromium's virtual time budget: page time given to build and draw the scene, ms.
    timeout_s
        Safety net on the machine's clock: Chromium is stopped past it (an error, nothing
        written).
    weld
        The weld the page opens at (its slider's ``#weld=<id>``); None: the first.
    """

    width: int = 1200
    height: int = 800
    wait_ms: int = 5000
    timeout_s: float = 300.0
    weld: str | None = None

    def __post_init__(self) -> None:
        for name in ("width", "height", "wait_ms"):
            if int(getattr(self, name)) <= 0:
                raise ConfigError(f"PNG {name} must be positive, got {getattr(self, name)}")


def find_chromium() -> str:
    """The Chromium executable (module docstring); raises :class:`ConfigError` without one."""
    given = os.environ.get("WELDPLAN_CHROMIUM")
    if given:
        path = shutil.which(given)
        if path is None:
            raise ConfigError(f"WELDPLAN_CHROMIUM={given}: no such executable")
        return path
    for name in CHROMIUM_NAMES:
        path = shutil.which(name)
        if path:
            return path
    raise ConfigError(INSTALL_HINT)


def chromium_flags(profile: Path, settings: PngSettings) -> list[str]:
    """Headless Chromium's flags: software WebGL, no network, no first-run work, a fixed
    window and the virtual time budget."""
    return [
        "--headless",
        "--no-sandbox",
        "--disable-gpu",
        "--use-angle=swiftshader",
        "--enable-unsafe-swiftshader",
        "--disable-quic",
        "--no-first-run",
        "--disable-background-networking",
        "--disable-component-update",
        "--disable-sync",
        "--hide-scrollbars",
        f"--user-data-dir={profile}",
        f"--window-size={int(settings.width)},{int(settings.height)}",
        f"--virtual-time-budget={int(settings.wait_ms)}",
    ]


def png_bytes(page: str, settings: PngSettings | None = None) -> bytes:
    """The PNG of HTML page ``page`` (module docstring).

    Raises
    ------
    ConfigError
        No Chromium.
    RunError
        Chromium failed, ran past ``settings.timeout_s`` or wrote no PNG.
    """
    settings = settings or PngSettings()
    chromium = find_chromium()
    with tempfile.TemporaryDirectory(prefix="weldplan-png-") as tmp:
        folder = Path(tmp)
        html = folder / "page.html"
        html.write_text(page, encoding="utf-8")
        shot = folder / "shot.png"
        url = html.as_uri()
        if settings.weld is not None:
            url += "#weld=" + quote(settings.weld, safe="")
        cmd = [chromium, *chromium_flags(folder / "profile", settings), f"--screenshot={shot}", url]
        try:
            done = subprocess.run(
                cmd, capture_output=True, text=True, timeout=settings.timeout_s, check=False
            )
        except subprocess.TimeoutExpired:
            raise RunError(
                f"Chromium did not render the page within {settings.timeout_s:g} s"
            ) from None
        data = shot.read_bytes() if shot.is_file() else b""
    if done.returncode != 0 or not data.startswith(PNG_SIGNATURE):
        last = (done.stderr.strip().splitlines() or ["no message"])[-1]
        raise RunError(f"Chromium wrote no PNG (exit {done.returncode}): {last}")
    return data


def render_png(page: str, path: str | PathLike[str], settings: PngSettings | None = None) -> Path:
    """Render HTML page ``page`` to a PNG at ``path`` (:func:`png_bytes`), written atomically:
    a failed render leaves ``path`` as it was. Returns the path."""
    from weldplan.io.outputset import write_outputs

    path = Path(path)
    write_outputs({path: png_bytes(page, settings)})
    return path
