"""TSPLIB 95 reader: problems (``.tsp``, ``.atsp``) and tours (``.opt.tour``).

Reinelt, G. (1991), "TSPLIB - A traveling salesman problem library", ORSA J. Computing 3(4), and
the TSPLIB 95 format description. Distances follow its integer rounding rules exactly, so the
known optimal tour lengths are reproduced:

* ``EUC_2D`` / ``EUC_3D``: ``nint(sqrt(dx^2 + dy^2 [+ dz^2]))`` with ``nint(x) = floor(x + 0.5)``;
* ``CEIL_2D``: ``ceil`` of the Euclidean distance;
* ``MAN_2D`` / ``MAX_2D``: ``nint`` of the Manhattan / maximum distance;
* ``ATT`` (pseudo-Euclidean): ``r = sqrt((dx^2 + dy^2) / 10)``, ``t = nint(r)``,
  ``d = t + 1 if t < r else t``;
* ``GEO``: coordinates are ``DDD.MM`` (degrees, minutes); ``deg = trunc(x)``,
  ``lat = pi (deg + 5 (x - deg) / 3) / 180`` with ``pi = 3.141592``, and
  ``d = int(6378.388 acos(((1 + q1) q2 - (1 - q1) q3) / 2) + 1)`` with ``q1 = cos(lon_i - lon_j)``,
  ``q2 = cos(lat_i - lat_j)``, ``q3 = cos(lat_i + lat_j)`` (TSPLIB FAQ: truncation, as in
  Concorde, not rounding, for ``deg``);
* ``EXPLICIT``: ``EDGE_WEIGHT_SECTION`` in ``FULL_MATRIX``, ``UPPER_ROW``, ``LOWER_ROW``,
  ``UPPER_DIAG_ROW``, ``LOWER_DIAG_ROW`` or their ``_COL`` forms.

Node numbers in files are 1-based; everything returned here is 0-based.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from os import PathLike
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from weldplan.errors import InputError

GEO_PI = 3.141592  #: the value of pi TSPLIB's GEO distance uses
GEO_RADIUS = 6378.388  #: the earth radius (km) TSPLIB's GEO distance uses

COORD_TYPES = ("EUC_2D", "EUC_3D", "CEIL_2D", "MAN_2D", "MAX_2D", "ATT", "GEO")
MATRIX_FORMATS = (
    "FULL_MATRIX",
    "UPPER_ROW",
    "LOWER_ROW",
    "UPPER_DIAG_ROW",
    "LOWER_DIAG_ROW",
    "UPPER_COL",
    "LOWER_COL",
    "UPPER_DIAG_COL",
    "LOWER_DIAG_COL",
)


@dataclass(frozen=True)
class TSPLIBProblem:
    """A TSPLIB instance.

    Attributes
    ----------
    name, type, comment
        Header fields (``type`` is ``TSP`` or ``ATSP``).
    dimension
        Number of nodes ``n``.
    edge_weight_type
        ``EUC_2D``, ``ATT``, ``GEO``, ``EXPLICIT``, ...
    coords
        ``(n, 2|3) float`` node coordinates, or ``None`` for explicit matrices without them.
    weights
        ``(n, n) float`` explicit matrix, or ``None``.
    path
        The file it was read from.
    """

    name: str
    type: str
    comment: str
    dimension: int
    edge_weight_type: str
    coords: NDArray[np.float64] | None
    weights: NDArray[np.float64] | None
    path: str | None = None

    def matrix(self) -> NDArray[np.float64]:
        """``(n, n) float`` integer-valued distances under the instance's rounding rule."""
        if self.weights is not None:
            return self.weights.copy()
        assert self.coords is not None
        return distance_matrix(self.coords, self.edge_weight_type)


def _nint(x: NDArray[np.float64]) -> NDArray[np.float64]:
    return np.floor(x + 0.5)


def distance_matrix(coords: NDArray[np.float64], kind: str) -> NDArray[np.float64]:
    """TSPLIB distances between all rows of ``coords (n, d)`` for edge weight type ``kind``."""
    X = np.asarray(coords, dtype=np.float64)
    if kind == "GEO":
        deg = np.trunc(X)
        rad = GEO_PI * (deg + 5.0 * (X - deg) / 3.0) / 180.0
        lat, lon = rad[:, 0], rad[:, 1]
        q1 = np.cos(lon[:, None] - lon[None, :])
        q2 = np.cos(lat[:, None] - lat[None, :])
        q3 = np.cos(lat[:, None] + lat[None, :])
        arg = np.clip(0.5 * ((1.0 + q1) * q2 - (1.0 - q1) * q3), -1.0, 1.0)
        D = np.floor(GEO_RADIUS * np.arccos(arg) + 1.0)
        np.fill_diagonal(D, 0.0)
        return D
    diff = X[:, None, :] - X[None, :, :]
    if kind in ("EUC_2D", "EUC_3D"):
        D = _nint(np.sqrt((diff**2).sum(-1)))
    elif kind == "CEIL_2D":
        D = np.ceil(np.sqrt((diff**2).sum(-1)))
    elif kind == "MAN_2D":
        D = _nint(np.abs(diff).sum(-1))
    elif kind == "MAX_2D":
        D = _nint(np.abs(diff).max(-1))
    elif kind == "ATT":
        r = np.sqrt((diff**2).sum(-1) / 10.0)
        t = _nint(r)
        D = np.where(t < r, t + 1.0, t)
    else:
        raise ValueError(f"unsupported TSPLIB EDGE_WEIGHT_TYPE {kind!r}")
    np.fill_diagonal(D, 0.0)
    return D


def _explicit(values: list[float], n: int, fmt: str) -> NDArray[np.float64]:
    """Assemble an ``(n, n)`` matrix from an EDGE_WEIGHT_SECTION in format ``fmt``."""
    v = np.asarray(values, dtype=np.float64)
    if fmt == "FULL_MATRIX":
        return v.reshape(n, n)
    # A symmetric matrix's column-wise upper triangle is its row-wise lower triangle, etc.
    alias = {
        "UPPER_COL": "LOWER_ROW",
        "LOWER_COL": "UPPER_ROW",
        "UPPER_DIAG_COL": "LOWER_DIAG_ROW",
        "LOWER_DIAG_COL": "UPPER_DIAG_ROW",
    }
    fmt = alias.get(fmt, fmt)
    diag = "DIAG" in fmt
    if fmt.startswith("UPPER"):
        i, j = np.triu_indices(n, k=0 if diag else 1)
    else:
        i, j = np.tril_indices(n, k=0 if diag else -1)
    M = np.zeros((n, n))
    M[i, j] = v
    M[j, i] = v
    return M


def _expected_count(n: int, fmt: str) -> int:
    if fmt == "FULL_MATRIX":
        return n * n
    return n * (n + 1) // 2 if "DIAG" in fmt else n * (n - 1) // 2


@dataclass
class _Sections:
    """What :func:`_parse_sections` collects from a TSPLIB file, before any checks of meaning."""

    header: dict[str, str] = field(default_factory=dict)
    #: 1-based node number -> its 2 or 3 coordinates
    coords: dict[int, list[float]] = field(default_factory=dict)
    weights: list[float] = field(default_factory=list)
    #: the line of ``EDGE_WEIGHT_SECTION`` (0 when absent), for error messages
    weights_line: int = 0


def read_tsplib(path: str | PathLike[str]) -> TSPLIBProblem:
    """Read a TSPLIB ``.tsp`` / ``.atsp`` file.

    Raises
    ------
    InputError
        Naming the file, line and field of anything malformed or unsupported.
    """
    p = Path(path)
    try:
        lines = p.read_text().splitlines()
    except OSError as e:
        raise InputError(f"cannot read TSPLIB file: {e.strerror}", path=p) from e
    s = _parse_sections(lines, p)
    header = s.header
    for name in ("DIMENSION", "EDGE_WEIGHT_TYPE"):
        if name not in header:
            raise InputError("missing header field", path=p, field=name)
    try:
        n = int(header["DIMENSION"])
    except ValueError:
        raise InputError(
            f"not an integer: {header['DIMENSION']!r}", path=p, field="DIMENSION"
        ) from None
    kind = header["EDGE_WEIGHT_TYPE"].upper()
    xy = _node_coords(s.coords, n, p)
    W = None
    if kind == "EXPLICIT":
        W = _edge_weights(s, n, p)
    elif kind in COORD_TYPES:
        if xy is None:
            raise InputError(f"{kind} needs a NODE_COORD_SECTION", path=p, field="NODE_COORD")
    else:
        raise InputError(f"unsupported edge weight type {kind!r}", path=p, field="EDGE_WEIGHT_TYPE")
    return TSPLIBProblem(
        name=header.get("NAME", p.stem),
        type=header.get("TYPE", "TSP").split()[0].upper(),
        comment=header.get("COMMENT", ""),
        dimension=n,
        edge_weight_type=kind,
        coords=xy,
        weights=W,
        path=str(p),
    )


def _parse_sections(lines: list[str], p: Path) -> _Sections:
    """The header fields, node coordinates and edge weights of a TSPLIB file's lines.

    ``DISPLAY_DATA_SECTION`` coordinates fill in nodes ``NODE_COORD_SECTION`` did not give;
    sections weldplan does not need (``FIXED_EDGES``, ``DEMAND``, ...) are skipped. Reading
    stops at ``EOF``. InputError (file, line, section) on a malformed number or a line outside
    any section that is not a ``KEY: value`` header.
    """
    s = _Sections()
    section = None
    for ln, raw in enumerate(lines, start=1):
        line = raw.strip()
        if not line:
            continue
        if line == "EOF":
            break
        key = line.split(":")[0].strip().upper() if ":" in line else line.split()[0].upper()
        if key.endswith("_SECTION"):
            section = key
            if key == "EDGE_WEIGHT_SECTION":
                s.weights_line = ln
            continue
        if ":" in line:
            k, _, val = line.partition(":")
            s.header[k.strip().upper()] = val.strip()
            section = None
            continue
        if section in ("NODE_COORD_SECTION", "DISPLAY_DATA_SECTION"):
            parts = line.split()
            try:
                idx = int(parts[0])
                xyz = [float(v) for v in parts[1:]]
            except ValueError:
                raise InputError(
                    f"bad coordinate line {line!r}", path=p, line=ln, field=section
                ) from None
            if len(xyz) not in (2, 3):
                raise InputError("expected 2 or 3 coordinates", path=p, line=ln, field=section)
            if section == "NODE_COORD_SECTION" or idx not in s.coords:
                s.coords[idx] = xyz
        elif section == "EDGE_WEIGHT_SECTION":
            try:
                s.weights.extend(float(v) for v in line.split())
            except ValueError:
                raise InputError(
                    f"bad weight line {line!r}", path=p, line=ln, field=section
                ) from None
        elif section is not None:
            continue  # sections we do not need (FIXED_EDGES, DEMAND, ...)
        else:
            raise InputError(f"unexpected line {line!r}", path=p, line=ln)
    return s


def _node_coords(coords: dict[int, list[float]], n: int, p: Path) -> NDArray[np.float64] | None:
    """``(n, 2|3) float`` coordinates of nodes 1..n in order, or None when the file had none."""
    if not coords:
        return None
    if sorted(coords) != list(range(1, n + 1)):
        raise InputError(
            f"node numbers must be 1..{n}, got {len(coords)} nodes", path=p, field="NODE_COORD"
        )
    return np.array([coords[i] for i in range(1, n + 1)], dtype=np.float64)


def _edge_weights(s: _Sections, n: int, p: Path) -> NDArray[np.float64]:
    """The ``(n, n)`` matrix of an ``EXPLICIT`` instance, after checking its format and count."""
    fmt = s.header.get("EDGE_WEIGHT_FORMAT", "").upper()
    if fmt not in MATRIX_FORMATS:
        raise InputError(f"unsupported format {fmt!r}", path=p, field="EDGE_WEIGHT_FORMAT")
    need = _expected_count(n, fmt)
    if len(s.weights) != need:
        raise InputError(
            f"{fmt} of dimension {n} needs {need} weights, found {len(s.weights)}",
            path=p,
            line=s.weights_line or None,
            field="EDGE_WEIGHT_SECTION",
        )
    return _explicit(s.weights, n, fmt)


def read_tour(path: str | PathLike[str]) -> NDArray[np.intp]:
    """Read a TSPLIB ``.tour`` file: the ``(n,) int`` 0-based node order of its first tour."""
    p = Path(path)
    try:
        lines = p.read_text().splitlines()
    except OSError as e:
        raise InputError(f"cannot read tour file: {e.strerror}", path=p) from e
    order: list[int] = []
    dim = None
    in_tour = False
    for ln, raw in enumerate(lines, start=1):
        line = raw.strip()
        if not line or line == "EOF":
            if line == "EOF":
                break
            continue
        if not in_tour:
            if line.upper().startswith("TOUR_SECTION"):
                in_tour = True
            elif line.upper().startswith("DIMENSION"):
                try:
                    dim = int(line.partition(":")[2])
                except ValueError:
                    raise InputError("bad DIMENSION", path=p, line=ln, field="DIMENSION") from None
            continue
        for tok in line.split():
            try:
                v = int(tok)
            except ValueError:
                raise InputError(
                    f"bad node {tok!r}", path=p, line=ln, field="TOUR_SECTION"
                ) from None
            if v == -1:
                in_tour = False
                break
            order.append(v - 1)
        if not in_tour:
            break
    if not order:
        raise InputError("no TOUR_SECTION", path=p, field="TOUR_SECTION")
    n = len(order)
    if dim is not None and n != dim:
        raise InputError(f"tour has {n} nodes, DIMENSION says {dim}", path=p, field="DIMENSION")
    if sorted(order) != list(range(n)):
        raise InputError("tour is not a permutation of 1..n", path=p, field="TOUR_SECTION")
    return np.asarray(order, dtype=np.intp)


def read_best_solutions(path: str | PathLike[str]) -> dict[str, float]:
    """Read ``bestSolutions.txt`` (``name : value`` lines) into ``{name: value}``."""
    p = Path(path)
    out: dict[str, float] = {}
    for ln, raw in enumerate(p.read_text().splitlines(), start=1):
        if ":" not in raw:
            continue
        name, _, val = raw.partition(":")
        try:
            out[name.strip()] = float(val.split()[0])
        except (ValueError, IndexError):
            raise InputError(
                f"bad value {val.strip()!r}", path=p, line=ln, field=name.strip()
            ) from None
    return out


def tour_length(D: NDArray[np.float64], order: NDArray[np.intp]) -> float:
    """Closed-tour length of ``order`` under the matrix ``D``."""
    o = np.asarray(order, dtype=np.intp)
    return float(D[o, np.roll(o, -1)].sum())


__all__ = [
    "TSPLIBProblem",
    "distance_matrix",
    "read_best_solutions",
    "read_tour",
    "read_tsplib",
    "tour_length",
]
