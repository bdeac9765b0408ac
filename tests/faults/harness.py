"""Hostile inputs and the one invariant every fault case must meet (issue #14, "Done when").

Every case ends either

* in a one-line error: exit code 2 (bad input), 1 (failure) or 3 (joints skipped), nothing on
  stderr but that one line, no traceback, the line naming what the case says it must name
  (the file, the field, the joint, the option); or
* in a route (exit 0) that the independent oracle (tests/faults/oracle.py) confirms: python-fcl
  on the raw triangles, the approach cone, and the winding-number inside test.

Scenes are tiny (a 100 mm plate, a 40 mm closed box) on a coarse grid so that a plan takes a
fraction of a second in process.
"""

from __future__ import annotations

import contextlib
import io
import json
import traceback
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import trimesh

from tests.faults.oracle import Uncheckable, check_route_file

#: exit codes of the scheme the CLI follows (issue #14 items 8 and 3)
BAD_INPUT, FAILURE, SKIPPED = 2, 1, 3

#: default planning options of the tiny scenes: coarse, small grid, quiet
FAST = ["--pitch", "5", "--margin", "20", "--quiet", "--planner", "exact"]


@dataclass
class Outcome:
    """What one CLI run did."""

    code: int | None
    stdout: str
    stderr: str
    crash: str | None = None  # the traceback of an exception that escaped main()

    @property
    def err_lines(self) -> list[str]:
        """stderr's lines other than log warnings (``WARNING name: ...``): a warning said before
        an error (a repaired face, coincident joints) is information, the error is the one line."""
        return [ln for ln in self.stderr.splitlines() if ln.strip() and not _is_warning(ln)]

    @property
    def warnings(self) -> list[str]:
        return [ln for ln in self.stderr.splitlines() if _is_warning(ln)]


def _is_warning(line: str) -> bool:
    return line.startswith("WARNING weldplan")


def run_cli(argv: list[str]) -> Outcome:
    """``weldplan.cli.main(argv)`` in process, stdout and stderr captured, crashes recorded."""
    from weldplan.cli import main

    out, err = io.StringIO(), io.StringIO()
    crash = None
    code: int | None = None
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = main([str(a) for a in argv])
        except SystemExit as exc:  # argparse usage errors
            code = exc.code if isinstance(exc.code, int) else 2
        except BaseException:  # noqa: BLE001 - a traceback is what the suite looks for
            crash = traceback.format_exc()
    return Outcome(code, out.getvalue(), err.getvalue(), crash)


def assert_one_line_error(o: Outcome, code: int, *names: str) -> str:
    """The run ended in exactly one stderr line, exit ``code``, naming every one of ``names``
    (case-insensitive). Returns the line."""
    assert o.crash is None, f"traceback instead of a one-line error:\n{o.crash}"
    assert "Traceback" not in o.stderr, o.stderr
    lines = o.err_lines
    assert len(lines) == 1, f"expected one stderr line, got {len(lines)}:\n{o.stderr}"
    assert o.code == code, f"exit code {o.code}, expected {code}: {lines[0]}"
    for n in names:
        assert n.lower() in lines[0].lower(), f"{n!r} not named in: {lines[0]}"
    return lines[0]


def assert_invariant(
    o: Outcome,
    route_json: Path,
    mesh: Path,
    joints: Path,
    clearance: float,
    *,
    scale: float = 1.0,
) -> str:
    """Either a one-line error (exit 1, 2 or 3) or exit 0 with a route the oracle confirms.

    Returns ``"error"`` or ``"route"``.
    """
    assert o.crash is None, f"traceback:\n{o.crash}"
    assert "Traceback" not in o.stderr, o.stderr
    if o.code != 0:
        assert o.code in (BAD_INPUT, FAILURE, SKIPPED), f"exit code {o.code}: {o.stderr}"
        assert len(o.err_lines) == 1, f"expected one stderr line:\n{o.stderr}"
        return "error"
    try:
        problems = check_route_file(route_json, mesh, joints, clearance, scale=scale)
    except Uncheckable as exc:
        raise AssertionError(
            f"a route was written for input the oracle cannot check: {exc}"
        ) from None
    assert not problems, "route written but the oracle disagrees:\n" + "\n".join(problems)
    return "route"


# ---------------------------------------------------------------------------- scenes
def plate() -> trimesh.Trimesh:
    """A 100 x 100 x 2 mm plate, top face z = 0, centred on the origin (a thin closed box)."""
    m = trimesh.creation.box(extents=[100.0, 100.0, 2.0])
    m.apply_translation([0.0, 0.0, -1.0])
    return m


def sheet() -> trimesh.Trimesh:
    """An open 100 x 100 mm sheet at z = 0 (two triangles): a surface, no inside."""
    v = np.array([[-50.0, -50.0, 0.0], [50.0, -50.0, 0.0], [50.0, 50.0, 0.0], [-50.0, 50.0, 0.0]])
    return trimesh.Trimesh(v, [[0, 1, 2], [0, 2, 3]], process=False)


def wall_plate() -> trimesh.Trimesh:
    """The plate with a 40 mm high, 2 mm thick wall across it at x = 0 (|y| <= 30)."""
    w = trimesh.creation.box(extents=[2.0, 60.0, 40.0])
    w.apply_translation([0.0, 0.0, 20.0])
    return trimesh.util.concatenate([plate(), w])


def closed_box(size: float = 40.0) -> trimesh.Trimesh:
    """A closed cube of side ``size`` mm standing on z = 0, centred on x = y = 0."""
    m = trimesh.creation.box(extents=[size, size, size])
    m.apply_translation([0.0, 0.0, size / 2])
    return m


#: weld spots on the plate's top face, either side of the wall, approach straight up
SPOTS = np.array([[-20.0, -10.0, 0.0], [-20.0, 15.0, 0.0], [20.0, 10.0, 0.0], [20.0, -15.0, 0.0]])
UP = np.array([0.0, 0.0, 1.0])


def write_mesh(path: Path, mesh: trimesh.Trimesh) -> Path:
    mesh.export(str(path))
    return path


def write_joints(
    path: Path,
    xyz: np.ndarray,
    dirs: np.ndarray | None = None,
    ids: list[str] | None = None,
) -> Path:
    """A joints CSV in the simple layout (comma separated, header id,x,y,z[,nx,ny,nz])."""
    xyz = np.asarray(xyz, dtype=float).reshape(-1, 3)
    ids = ids or [f"J{k + 1}" for k in range(len(xyz))]
    head = "id,x,y,z" + (",nx,ny,nz" if dirs is not None else "")
    lines = [head]
    for k, p in enumerate(xyz):
        row = [ids[k], *(repr(float(v)) for v in p)]
        if dirs is not None:
            row += [repr(float(v)) for v in np.asarray(dirs, dtype=float).reshape(-1, 3)[k]]
        lines.append(",".join(row))
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


@dataclass
class Scene:
    """Files of one case: mesh, joints, and where the outputs go."""

    dir: Path
    mesh: Path
    joints: Path

    @property
    def csv(self) -> Path:
        return self.dir / "route.csv"

    @property
    def json(self) -> Path:
        return self.dir / "route.json"

    def plan_argv(self, *extra: str, fast: bool = True) -> list[str]:
        argv = ["plan", self.mesh, self.joints, "-o", self.csv, "--json", self.json]
        return [str(a) for a in argv] + (FAST if fast else []) + list(extra)

    def route(self) -> dict:
        return json.loads(self.json.read_text(encoding="utf-8"))


def make_scene(
    tmp: Path,
    mesh: trimesh.Trimesh | None = None,
    xyz: np.ndarray | None = None,
    dirs: np.ndarray | None | str = "up",
    *,
    suffix: str = ".stl",
) -> Scene:
    """The wall plate (default) with :data:`SPOTS` approached from above, written to ``tmp``."""
    mesh = wall_plate() if mesh is None else mesh
    xyz = SPOTS if xyz is None else np.asarray(xyz, dtype=float)
    if isinstance(dirs, str):
        dirs = np.tile(UP, (len(xyz), 1))
    m = write_mesh(tmp / f"part{suffix}", mesh)
    j = write_joints(tmp / "joints.csv", xyz, dirs)
    return Scene(tmp, m, j)
