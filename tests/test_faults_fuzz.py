"""Property-based fault injection (hypothesis): joint CSVs as bytes and as structured text, and
small random meshes, all through the CLI (issue #14, "Done when").

The invariant is tests/faults/harness.py's: a one-line error (exit 2, naming the file) or a route
the independent oracle confirms. Example counts are small so the fast tier stays quick; the
slow tier runs the same properties with more examples. Inputs that only another branch handles
(non-finite mesh vertices, 1e300 coordinates) are properties of their own, strict xfails.
"""

from __future__ import annotations

import atexit
import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
import trimesh
from hypothesis import HealthCheck, Phase, assume, event, given, settings
from hypothesis import strategies as st

from tests.faults.harness import (
    BAD_INPUT,
    Scene,
    assert_invariant,
    assert_one_line_error,
    run_cli,
    wall_plate,
)
from tests.faults.oracle import check_route, load_triangles

FAST_EXAMPLES = 12
SLOW_EXAMPLES = 80
_HC = [HealthCheck.too_slow, HealthCheck.data_too_large, HealthCheck.filter_too_much]


def fast(n: int = FAST_EXAMPLES, *, shrink: bool = True):
    """Few examples, derandomized; ``shrink=False`` for the xfail properties (a known failure
    need not be shrunk through dozens of planning runs)."""
    phases = tuple(Phase) if shrink else (Phase.explicit, Phase.generate)
    return settings(
        max_examples=n,
        deadline=None,
        suppress_health_check=_HC,
        derandomize=True,
        phases=phases,
        report_multiple_bugs=False,
    )


def slow():
    return settings(max_examples=SLOW_EXAMPLES, deadline=None, suppress_health_check=_HC)


#: the wall plate, written once per process (hypothesis examples cannot use tmp_path)
_MESH_DIR = Path(tempfile.mkdtemp(prefix="weldplan-fuzz-"))
atexit.register(shutil.rmtree, _MESH_DIR, ignore_errors=True)
_WALL = _MESH_DIR / "wall.stl"
wall_plate().export(str(_WALL))


# ---------------------------------------------------------------------------- joint CSV bytes
def _check_csv_bytes(data: bytes) -> None:
    from weldplan.errors import InputError
    from weldplan.io.joints import read_joints

    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / "fuzz.csv"
        path.write_bytes(data)
        try:
            joints = read_joints(path)
        except InputError as exc:
            assert "fuzz.csv" in str(exc) and "\n" not in str(exc), str(exc)
            o = run_cli(["plan", _WALL, path, "-o", Path(d) / "r.csv", "--quiet"])
            assert_one_line_error(o, BAD_INPUT, "fuzz.csv")
            return
        assert len(joints) > 0 and len(set(joints.ids)) == len(joints.ids)
        assert np.all(np.isfinite(joints.xyz))
        assert all(i.strip() == i and i for i in joints.ids)


_CSV_ALPHABET = st.sampled_from(list(b"0123456789,;.-+eE \t\r\nidxyzn#\xef\xbb\xbfJ\xc3\xa9naNinf"))


@fast(40)
@given(st.binary(max_size=200))
def test_joint_csv_random_bytes(data):
    _check_csv_bytes(data)


@fast(40)
@given(st.lists(_CSV_ALPHABET, max_size=120).map(lambda b: b"id,x,y,z\n" + bytes(b)))
def test_joint_csv_bytes_after_a_valid_header(data):
    _check_csv_bytes(data)


# ---------------------------------------------------------------------------- structured CSVs
#: spots on the wall plate's top face (away from the wall) and points in the air above it
POOL = [(x, y, z) for x in (-30, -20, 20, 30) for y in (-20, 0, 20) for z in (0, 15)]
UNICODE_IDS = ["Jö", "焊点1", "J-😀", "ид", "J 1", "J#2"]
#: ways a file goes wrong; each must end in a one-line error naming the file
FATAL = ["missing-field", "empty-value", "duplicate-id", "nan", "inf", "word", "comma-decimal",
         "empty-file", "header-only", "missing-column", "zero-direction"]  # fmt: skip
#: ways a file looks odd but is fine
BENIGN = ["none", "bom", "crlf", "comments", "blank-lines", "unicode-ids", "extra-column",
          "spaces", "exponent", "plus-sign", "semicolon", "semicolon-decimal-comma",
          "header-case", "column-order", "tiny-numbers"]  # fmt: skip


@dataclass
class CsvCase:
    text: str
    ids: list[str]
    xyz: np.ndarray
    fault: str


@st.composite
def joint_csvs(draw, faults=tuple(FATAL + BENIGN)):
    fault = draw(st.sampled_from(faults))
    n = draw(st.integers(1, 4))
    idx = draw(st.lists(st.integers(0, len(POOL) - 1), min_size=n, max_size=n, unique=True))
    xyz = np.array([POOL[i] for i in idx], dtype=float)
    ids = [f"J{k + 1}" for k in range(n)]
    if fault == "unicode-ids":
        ids = draw(st.lists(st.sampled_from(UNICODE_IDS), min_size=n, max_size=n, unique=True))
    with_dirs = draw(st.booleans())
    cols = ["id", "x", "y", "z"] + (["nx", "ny", "nz"] if with_dirs else [])
    if fault == "extra-column":
        cols.append("station")
    if fault == "column-order":
        cols = draw(st.permutations(cols))
    sep = ";" if fault in ("semicolon", "semicolon-decimal-comma") else ","

    def num(v: float) -> str:
        s = {"exponent": f"{v:e}", "plus-sign": f"+{v:g}" if v >= 0 else f"{v:g}",
             "tiny-numbers": f"{v + 1e-300:.17g}"}.get(fault, f"{v:.2f}")  # fmt: skip
        return s.replace(".", ",") if fault == "semicolon-decimal-comma" else s

    rows = []
    for k in range(n):
        val = {"id": ids[k], "x": num(xyz[k, 0]), "y": num(xyz[k, 1]), "z": num(xyz[k, 2]),
               "nx": num(0.0), "ny": num(0.0), "nz": num(1.0), "station": "S1"}  # fmt: skip
        cells = [val[c] for c in cols]
        if fault == "spaces":
            cells = [f"  {c} " for c in cells]
        rows.append(cells)
    head = [c.upper() if fault == "header-case" else c for c in cols]
    bad_row = draw(st.integers(0, n - 1))
    xi = cols.index("x")
    if fault == "missing-field":
        del rows[bad_row][xi]
    elif fault == "empty-value":
        rows[bad_row][xi] = ""
    elif fault == "duplicate-id":
        rows.append(list(rows[bad_row]))
        rows[-1][xi] = num(99.0)
    elif fault in ("nan", "inf", "word"):
        rows[bad_row][xi] = {"nan": "nan", "inf": "-inf", "word": "twelve"}[fault]
    elif fault == "comma-decimal":
        rows[bad_row][xi] = "1,5"
    elif fault == "missing-column":
        head = [c for c in head if c != "y"]
    elif fault == "zero-direction":
        if not with_dirs:
            head += ["nx", "ny", "nz"]
            for r in rows:
                r += ["0", "0", "1"]
        rows[bad_row][-3:] = ["0", "0", "0"]
    lines = [sep.join(head)] + [sep.join(r) for r in rows]
    if fault == "comments":
        lines.insert(0, "# weld joints of station 1")
        lines.insert(2, "   # a comment between rows")
    if fault == "blank-lines":
        lines = [x for ln in lines for x in (ln, "")]
    if fault == "header-only":
        lines = lines[:1]
    text = "\n".join(lines) + "\n"
    if fault == "empty-file":
        text = draw(st.sampled_from(["", "\n\n", "# only a comment\n", "   \n"]))
    if fault == "crlf":
        text = text.replace("\n", "\r\n")
    if fault == "bom":
        text = "\ufeff" + text
    return CsvCase(text, ids, xyz, fault)


def _plan_csv_case(case: CsvCase) -> None:
    with tempfile.TemporaryDirectory() as d:
        sc = Scene(Path(d), _WALL, Path(d) / "joints.csv")
        sc.joints.write_text(case.text, encoding="utf-8")
        o = run_cli(sc.plan_argv())
        if case.fault in FATAL:
            assert_one_line_error(o, BAD_INPUT, "joints.csv")
            event("error (bad file)")
            return
        assert o.crash is None, o.crash
        if o.code != 0:  # a planning refusal is allowed, as one line
            assert_one_line_error(o, o.code)
            event(f"error: {o.err_lines[0][:60]}")
            return
        event("route")
        problems = check_route(
            sc.route(), load_triangles(_WALL), dict(zip(case.ids, case.xyz, strict=True)), 5.0
        )
        assert not problems, f"{case.fault}: " + "; ".join(problems)


@fast(20)
@given(joint_csvs())
def test_structured_joint_csvs(case):
    _plan_csv_case(case)


@fast(5, shrink=False)
@given(joint_csvs(faults=("none",)), st.sampled_from(["1e300", "-1e300", "1.7e308"]))
def test_structured_joint_csvs_with_a_huge_coordinate(case, huge):
    lines = case.text.splitlines()
    cells = lines[1].split(",")
    cells[1] = huge
    lines[1] = ",".join(cells)
    with tempfile.TemporaryDirectory() as d:
        sc = Scene(Path(d), _WALL, Path(d) / "joints.csv")
        sc.joints.write_text("\n".join(lines) + "\n")
        assert_one_line_error(run_cli(sc.plan_argv()), BAD_INPUT, "joints.csv")


# ---------------------------------------------------------------------------- meshes
#: the fuzzed stations' joints: in the air, 30 mm up (each is its own virtual joint)
AIR = np.array([[-30.0, -20.0, 30.0], [30.0, 20.0, 30.0], [-30.0, 20.0, 30.0]])
LATTICE = st.integers(-8, 8).map(lambda v: 5.0 * v)


@st.composite
def meshes(draw, non_finite: bool = False):
    """(vertices, faces, kind): a few random triangles on a 5 mm lattice below z = 45, maybe a
    closed box standing below the joints, maybe degenerate faces, maybe a non-finite vertex."""
    parts = []
    for _ in range(draw(st.integers(1, 6))):
        v = [[draw(LATTICE), draw(LATTICE), draw(st.integers(-2, 9)) * 5.0] for _ in range(3)]
        parts.append(trimesh.Trimesh(v, [[0, 1, 2]], process=False))
    if draw(st.booleans()):
        size = draw(st.sampled_from([10.0, 20.0]))
        box = trimesh.creation.box(extents=[size, size, size])
        box.apply_translation([draw(LATTICE), draw(LATTICE), size / 2 - 5.0])
        parts.append(box)
    if draw(st.booleans()):  # degenerate faces: a repeated vertex and a collinear triple
        parts.append(
            trimesh.Trimesh(
                [[0, 0, 0], [10, 0, 0], [20, 0, 0], [0, 10, 0]], [[0, 1, 2], [0, 0, 3]],
                process=False,
            )
        )  # fmt: skip
    m = trimesh.util.concatenate(parts)
    v = np.asarray(m.vertices, dtype=float).copy()
    f = np.asarray(m.faces)
    if non_finite:
        v[draw(st.integers(0, len(v) - 1))] = draw(st.sampled_from([np.nan, np.inf, -np.inf]))
    return v, f


def _write_mesh(path: Path, v: np.ndarray, f: np.ndarray) -> None:
    if path.suffix == ".obj":
        lines = [f"v {a!r} {b!r} {c!r}" for a, b, c in v.tolist()]
        lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in f.tolist()]
        path.write_text("\n".join(lines) + "\n")
    else:
        trimesh.Trimesh(v, f, process=False).export(str(path))


def _plan_mesh_case(v, f, suffix: str, scale: float) -> str:
    from tests.faults.harness import write_joints

    with tempfile.TemporaryDirectory() as d:
        mesh = Path(d) / f"part{suffix}"
        _write_mesh(mesh, v / scale, f)
        sc = Scene(Path(d), mesh, write_joints(Path(d) / "joints.csv", AIR))
        extra = ["--scale", repr(scale)] if scale != 1.0 else []
        with np.errstate(all="ignore"):
            o = run_cli(sc.plan_argv(*extra))
        outcome = assert_invariant(o, sc.json, sc.mesh, sc.joints, 5.0, scale=scale)
        event(outcome if outcome == "route" else f"error: {o.err_lines[0][:60]}")
        return outcome


SUFFIXES = st.sampled_from([".stl", ".obj"])
SCALES = st.sampled_from([1.0, 1.0, 2.0, 25.4])


@fast(15)
@given(meshes(), SUFFIXES, SCALES)
def test_random_small_meshes(mesh, suffix, scale):
    v, f = mesh
    _plan_mesh_case(v, f, suffix, scale)


@fast(5, shrink=False)
@given(meshes(non_finite=True), SUFFIXES)
def test_random_meshes_with_a_non_finite_vertex(mesh, suffix):
    v, f = mesh
    # the bad vertex must be used by a face, or there is nothing wrong with the geometry
    assume(not np.all(np.isfinite(v[np.unique(f)])))
    _plan_mesh_case(v, f, suffix, 1.0)


# ---------------------------------------------------------------------------- slow tier
@pytest.mark.slow
@slow()
@given(joint_csvs())
def test_structured_joint_csvs_many(case):
    _plan_csv_case(case)


@pytest.mark.slow
@slow()
@given(meshes(), SUFFIXES, SCALES)
def test_random_small_meshes_many(mesh, suffix, scale):
    v, f = mesh
    _plan_mesh_case(v, f, suffix, scale)


@pytest.mark.slow
@settings(max_examples=400, deadline=None, suppress_health_check=_HC)
@given(st.binary(max_size=400))
def test_joint_csv_random_bytes_many(data):
    _check_csv_bytes(data)
