"""Reading weld joints from CSV: ``id,x,y,z`` and optionally the torch approach ``nx,ny,nz``.

The format, and every way it can be wrong::

    id,x,y,z,nx,ny,nz          <- header (names case-insensitive, any order; nx,ny,nz optional)
    1,1443.60,-53.20,686.00,0,-1,0

* comma or semicolon separated (detected from the header); with semicolons a decimal comma
  (``1443,60``) is accepted too;
* blank lines and lines starting with ``#`` are skipped; nothing else is: a row that cannot be
  read is an :class:`~weldplan.errors.InputError` naming file, line and column (missing column,
  wrong number of fields, empty id, non-numeric value, NaN or infinite value, duplicate id,
  zero-length direction, empty file, header without data rows);
* columns other than those above are ignored with a warning in the log.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from os import PathLike
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from weldplan.errors import InputError
from weldplan.io.mesh import MAX_COORD_MM, unit_scale

log = logging.getLogger(__name__)

REQUIRED_COLUMNS: tuple[str, ...] = ("id", "x", "y", "z")
DIRECTION_COLUMNS: tuple[str, ...] = ("nx", "ny", "nz")

#: a direction shorter than this (in file units) is rejected as zero-length
_MIN_DIRECTION_NORM = 1e-12


#: joints closer than this (mm) are reported as lying at the same coordinates
COINCIDENT_MM = 0.01


@dataclass(frozen=True, eq=False)
class Joints:
    """Weld joints of a part.

    Parameters
    ----------
    ids
        Joint names, unique, in file order.
    xyz
        ``(n, 3) float``: joint positions in mm, finite, each within
        :data:`weldplan.io.mesh.MAX_COORD_MM` of the origin.
    directions
        ``(n, 3) float`` unit torch approach directions, or ``None`` when the file gives none.
    source
        The file they were read from, if any.
    lines
        The 1-based line of each joint in ``source``, if known (for error messages).

    Raises
    ------
    InputError
        (a ValueError) on mismatched lengths, repeated ids, non-finite or absurd positions,
        non-finite or zero directions; the message names the joint.
    """

    ids: tuple[str, ...]
    xyz: NDArray[np.float64]
    directions: NDArray[np.float64] | None = None
    source: Path | None = None
    lines: tuple[int, ...] | None = None

    def __post_init__(self) -> None:
        ids = tuple(str(i) for i in self.ids)
        src = self.source
        try:
            xyz = np.array(self.xyz, dtype=np.float64).reshape(-1, 3)
        except (TypeError, ValueError) as exc:
            raise InputError(f"joint positions must be (n, 3) numbers: {exc}", path=src) from None
        if len(ids) != len(xyz):
            raise InputError(f"{len(ids)} ids but {len(xyz)} positions", path=src)
        if len(set(ids)) != len(ids):
            raise InputError("joint ids must be unique", path=src, field="id")
        lines = None if self.lines is None else tuple(int(n) for n in self.lines)
        if lines is not None and len(lines) != len(ids):
            raise InputError(f"{len(lines)} line numbers for {len(ids)} joints", path=src)

        def where(k: int) -> dict[str, Any]:
            return {"path": src, "line": None if lines is None else lines[k]}

        bad = np.flatnonzero(~np.all(np.isfinite(xyz), axis=1))
        if len(bad):
            k = int(bad[0])
            raise InputError(
                f"joint {ids[k]!r}: position {xyz[k].tolist()} is not finite "
                f"({len(bad)} joints with NaN or infinite coordinates)",
                field="x",
                **where(k),
            )
        far = np.flatnonzero(np.abs(xyz).max(axis=1, initial=0.0) > MAX_COORD_MM)
        if len(far):
            k = int(far[0])
            raise InputError(
                f"joint {ids[k]!r}: position {xyz[k].tolist()} mm is beyond the "
                f"{MAX_COORD_MM:.0e} mm weldplan accepts: check the units",
                field="x",
                **where(k),
            )
        xyz.setflags(write=False)
        object.__setattr__(self, "ids", ids)
        object.__setattr__(self, "xyz", xyz)
        object.__setattr__(self, "lines", lines)
        if self.directions is not None:
            try:
                d = np.array(self.directions, dtype=np.float64).reshape(-1, 3)
            except (TypeError, ValueError) as exc:
                raise InputError(f"directions must be (n, 3) numbers: {exc}", path=src) from None
            if len(d) != len(xyz):
                raise InputError(f"{len(d)} directions for {len(xyz)} joints", path=src)
            norm = np.linalg.norm(d, axis=1, keepdims=True)
            bad = np.flatnonzero(~(np.isfinite(norm[:, 0]) & (norm[:, 0] >= _MIN_DIRECTION_NORM)))
            if len(bad):
                k = int(bad[0])
                raise InputError(
                    f"joint {ids[k]!r}: direction {d[k].tolist()} must be finite and non-zero",
                    field="nx",
                    **where(k),
                )
            d = d / norm
            d.setflags(write=False)
            object.__setattr__(self, "directions", d)
        if self.source is not None:
            object.__setattr__(self, "source", Path(self.source))

    def where(self, k: int) -> str:
        """``"joint 'id' (file, line n)"`` for messages about joint row ``k``."""
        loc = []
        if self.source is not None:
            loc.append(str(self.source))
        if self.lines is not None:
            loc.append(f"line {self.lines[k]}")
        return f"joint {self.ids[k]!r}" + (f" ({', '.join(loc)})" if loc else "")

    def __len__(self) -> int:
        return len(self.ids)

    def index(self, joint_id: str | int) -> int:
        """Row of the joint named ``joint_id`` (KeyError if absent)."""
        try:
            return self.ids.index(str(joint_id))
        except ValueError:
            raise KeyError(f"no joint with id {joint_id!r}") from None

    def to_csv(self, path: str | PathLike[str]) -> None:
        """Write ``id,x,y,z[,nx,ny,nz]`` in mm (round-trips through :func:`read_joints`)."""
        cols = list(REQUIRED_COLUMNS) + (
            list(DIRECTION_COLUMNS) if self.directions is not None else []
        )
        lines = [",".join(cols)]
        for k, jid in enumerate(self.ids):
            vals = [repr(float(v)) for v in self.xyz[k]]
            if self.directions is not None:
                vals += [repr(float(v)) for v in self.directions[k]]
            lines.append(",".join([jid, *vals]))
        Path(path).write_text("\n".join(lines) + "\n", encoding="utf-8")


def read_joints(path: str | PathLike[str], *, units: str = "mm") -> Joints:
    """Read weld joints from a CSV file (format in the module docstring).

    Parameters
    ----------
    path
        The CSV file.
    units
        Unit of ``x, y, z`` in the file (see :data:`weldplan.io.mesh.UNITS_MM`); positions are
        returned in mm. Directions are unitless and normalised to length 1.

    Returns
    -------
    Joints

    Raises
    ------
    InputError
        For every bad input, naming the file, the 1-based line and the column.
    """
    path = Path(path)
    factor = unit_scale(units)
    rows = _rows(path)
    header_line, header = rows[0]
    sep, names, numeric = _header(header, path=path, line=header_line)
    data = rows[1:]
    if not data:
        raise InputError("no data rows after the header", path=path, line=header_line)
    ids, values = _parse_rows(data, sep, names, numeric, path=path)
    xyz = values[:, :3] * factor
    _check_range(xyz, data, path=path)
    directions = values[:, 3:6] if len(numeric) > 3 else None
    log.info("read %d joints from %s", len(ids), path)
    lines = tuple(lineno for lineno, _ in data)
    return Joints(ids=tuple(ids), xyz=xyz, directions=directions, source=path, lines=lines)


def _rows(path: Path) -> list[tuple[int, str]]:
    """``(line number, text)`` of the lines that are neither blank nor ``#`` comments; the
    file's absence, a directory, non-UTF-8 text and an empty file are InputErrors."""
    if not path.exists():
        raise InputError("joints file not found", path=path)
    try:
        text = path.read_text(encoding="utf-8-sig")
    except UnicodeDecodeError as exc:
        raise InputError(f"not a UTF-8 text file ({exc.reason})", path=path) from exc
    except IsADirectoryError:
        raise InputError("expected a CSV file, got a directory", path=path) from None
    rows = [
        (n, line)
        for n, line in enumerate(text.splitlines(), start=1)
        if line.strip() and not line.lstrip().startswith("#")
    ]
    if not rows:
        raise InputError("empty file: expected a header 'id,x,y,z'", path=path)
    return rows


def _header(header: str, *, path: Path, line: int) -> tuple[str, list[str], list[str]]:
    """Separator, column names (lower case) and the numeric columns to read (``x, y, z`` and
    ``nx, ny, nz`` when present) of the header; InputError for a missing or repeated column or
    an incomplete direction. Unknown columns are logged and ignored."""
    sep = ";" if header.count(";") > header.count(",") else ","
    names = [h.strip().lower() for h in header.split(sep)]
    for col in REQUIRED_COLUMNS:
        if col not in names:
            raise InputError(
                f"missing column '{col}' in header {header.strip()!r} (need id,x,y,z)",
                path=path,
                line=line,
                field=col,
            )
    seen_cols: set[str] = set()
    for name in names:
        if name in seen_cols:
            raise InputError(f"column '{name}' appears twice", path=path, line=line, field=name)
        seen_cols.add(name)
    present_dir = [c for c in DIRECTION_COLUMNS if c in names]
    if present_dir and len(present_dir) != 3:
        missing = next(c for c in DIRECTION_COLUMNS if c not in names)
        raise InputError(
            "direction columns must come together as nx,ny,nz",
            path=path,
            line=line,
            field=missing,
        )
    known = set(REQUIRED_COLUMNS) | set(DIRECTION_COLUMNS)
    extra = [n for n in names if n not in known]
    if extra:
        log.warning("%s: ignoring columns %s", path, ", ".join(extra))
    return sep, names, ["x", "y", "z", *present_dir]


def _parse_rows(
    data: list[tuple[int, str]], sep: str, names: list[str], numeric: list[str], *, path: Path
) -> tuple[list[str], NDArray[np.float64]]:
    """Ids and ``(n, len(numeric))`` values (file units) of the data rows; InputError naming
    the line and column of a wrong field count, an empty or duplicate id, a value that is not
    a finite number, or a zero-length direction."""
    col_of = {name: names.index(name) for name in ["id", *numeric]}
    ids: list[str] = []
    first_line: dict[str, int] = {}
    values = np.empty((len(data), len(numeric)), dtype=np.float64)
    for r, (lineno, line) in enumerate(data):
        fields = line.split(sep)
        if len(fields) != len(names):
            raise InputError(
                f"expected {len(names)} fields, found {len(fields)}", path=path, line=lineno
            )
        jid = fields[col_of["id"]].strip()
        if not jid:
            raise InputError("empty id", path=path, line=lineno, field="id")
        if jid in first_line:
            raise InputError(
                f"duplicate id {jid!r} (first on line {first_line[jid]})",
                path=path,
                line=lineno,
                field="id",
            )
        first_line[jid] = lineno
        ids.append(jid)
        for c, name in enumerate(numeric):
            raw = fields[col_of[name]].strip()
            values[r, c] = _parse_number(raw, sep, path=path, line=lineno, field=name)
        if len(numeric) > 3:
            d = values[r, 3:6]
            if float(np.linalg.norm(d)) < _MIN_DIRECTION_NORM:
                raise InputError(
                    "zero-length direction (nx,ny,nz)", path=path, line=lineno, field="nx"
                )
    return ids, values


def _check_range(xyz: NDArray[np.float64], data: list[tuple[int, str]], *, path: Path) -> None:
    """InputError naming the first coordinate (mm) beyond :data:`MAX_COORD_MM`, with its line."""
    far = np.flatnonzero(np.abs(xyz).max(axis=1) > MAX_COORD_MM)
    if len(far):
        r = int(far[0])
        c = int(np.argmax(np.abs(xyz[r])))
        raise InputError(
            f"{xyz[r, c]:.3g} mm is beyond the {MAX_COORD_MM:.0e} mm weldplan accepts: "
            "check --units",
            path=path,
            line=data[r][0],
            field="xyz"[c],
        )


def coincident_joints(joints: Joints, tol: float = COINCIDENT_MM) -> list[tuple[int, int]]:
    """Pairs ``(i, j)``, ``i < j``, of joints closer than ``tol`` mm (the same weld spot twice:
    a copy-paste slip in the CSV, or two seams that meet). Sorted."""
    from scipy.spatial import cKDTree

    if len(joints) < 2:
        return []
    pairs = cKDTree(joints.xyz).query_pairs(tol, output_type="ndarray")
    return sorted((int(i), int(j)) for i, j in pairs)


def _parse_number(raw: str, sep: str, *, path: Path, line: int, field: str) -> float:
    text = raw.replace(",", ".") if sep == ";" else raw
    try:
        value = float(text)
    except ValueError:
        what = "empty value" if not raw else f"not a number: {raw!r}"
        raise InputError(what, path=path, line=line, field=field) from None
    if not np.isfinite(value):
        raise InputError(f"value must be finite, got {raw!r}", path=path, line=line, field=field)
    return value
