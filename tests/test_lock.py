"""requirements.lock pins every dependency that pyproject.toml declares, inside its ranges.

The README's install command and CI install with ``-c requirements.lock``; a dependency added to
pyproject.toml without refreshing the lock would install unpinned, so this test fails instead.
"""

from __future__ import annotations

import re
import tomllib
from pathlib import Path

import pytest
from packaging.markers import Marker
from packaging.requirements import Requirement
from packaging.utils import canonicalize_name
from packaging.version import Version

ROOT = Path(__file__).resolve().parents[1]
LOCK = ROOT / "requirements.lock"
#: the extras the lock is compiled with (its header names the command)
LOCKED_EXTRAS = ("test", "dask")


def _pins() -> dict[str, list[tuple[Version, Marker | None]]]:
    pins: dict[str, list[tuple[Version, Marker | None]]] = {}
    for line in LOCK.read_text(encoding="utf-8").splitlines():
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        req = Requirement(line)
        (spec,) = req.specifier  # exactly one '==' pin a line
        assert spec.operator == "==", line
        pins.setdefault(canonicalize_name(req.name), []).append((Version(spec.version), req.marker))
    return pins


def _declared() -> list[Requirement]:
    project = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    reqs = [Requirement(r) for r in project["dependencies"]]
    for extra in LOCKED_EXTRAS:
        reqs += [Requirement(r) for r in project["optional-dependencies"][extra]]
    return reqs


def test_lock_header_names_the_compile_command():
    head = LOCK.read_text(encoding="utf-8").splitlines()[:3]
    command = next(x for x in head if "uv pip compile" in x)
    assert "--universal" in command
    for extra in LOCKED_EXTRAS:
        assert f"--extra {extra}" in command


@pytest.mark.parametrize("req", _declared(), ids=str)
def test_every_declared_dependency_is_pinned_inside_its_range(req):
    if req.marker is not None and not req.marker.evaluate():
        pytest.skip(f"{req} does not apply to this platform")
    pins = _pins().get(canonicalize_name(req.name))
    assert pins, f"{req.name} is declared in pyproject.toml but not pinned in requirements.lock"
    here = [v for v, marker in pins if marker is None or marker.evaluate()]
    assert len(here) == 1, f"{req.name}: {len(here)} pins apply to this interpreter"
    assert req.specifier.contains(here[0], prereleases=True), f"{req.name}=={here[0]} not in {req}"


def test_installed_versions_are_the_locked_ones():
    """The environment running the tests was installed from the lock (as README and CI do)."""
    from importlib.metadata import PackageNotFoundError, version

    off = []
    for name, pins in _pins().items():
        here = [v for v, marker in pins if marker is None or marker.evaluate()]
        if not here:
            continue
        try:
            installed = Version(version(name))
        except PackageNotFoundError:
            continue  # an optional extra not installed here (e.g. dask for a library user)
        if installed != here[0]:
            off.append(f"{name} {installed} (lock {here[0]})")
    assert not off, "installed versions differ from requirements.lock: " + ", ".join(off)


def test_lock_lines_are_plain_pins():
    bad = [
        x
        for x in LOCK.read_text(encoding="utf-8").splitlines()
        if x.strip() and not x.lstrip().startswith("#") and not re.match(r"^[A-Za-z0-9._-]+==", x)
    ]
    assert not bad, bad
