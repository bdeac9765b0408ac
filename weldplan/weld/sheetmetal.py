"""Sheet-metal test bodies with real lap joints (``python -m weldplan.weld.sheetmetal OUT``).

The shared bodies are slabs and tubes: no two sheets lie face to face anywhere in them (issue 29).
This module builds what a spot-welding gun is made for: a car **side frame** of pressed sheets,
each sheet a closed thin solid of exact thickness, joined by **lap joints** on their flanges.

The sub-assembly (z up, x along the car, y outwards; mm)
-------------------------------------------------------
Three members, each a **hat section** closed by a flat **inner panel** (:class:`Member`):

* the **sill** along x at the bottom (its lower flange edge on z = 0),
* the **roof rail** along x, ``height`` above the sill, shorter and centred over it,
* the **B-pillar** standing between them at mid-sill, ``end_gap`` clear of both.

A hat's profile (across the member) is a flange, a wall sloping up to the crown, the crown, the
other wall and the other flange; the sheet is that polyline thickened by its gauge to the outside
(+y), so its inner face lies on y = 0 along both flanges. The inner panel is a flat plate of
another gauge ``gap`` below them (y in [-gap - t_inner, -gap]), as wide as the hat from flange
edge to flange edge: each flange is a two-sheet **stack** whose overlap is the flange width
(15-25 mm, drawn per member), with a free edge on the outside. The air gap (0.2 mm by default:
a fit-up gap, and a clean interface for the tests) is a parameter; with 0 the sheets touch.

Spots
-----
Along each flange a spot line at mid-overlap, on the faying surface (the middle of the air gap,
where the nugget forms), at a pitch drawn uniformly from ``pitch`` (30-60 mm), starting
``end_margin`` in from the member's end. The approach direction (the joints CSV's ``nx,ny,nz``,
from the spot towards the torch) is -y: from the inner panel's flat side, the hat's crown
behind the flange. Flanges are filled member by member (sill, B-pillar, roof rail) until
``n_spots`` are placed.

Randomness (``rng``) draws each sheet's gauge from :data:`GAUGES_MM` within ``thickness``, each
member's overlap from ``overlap`` (rounded to 0.5 mm) and each pitch; everything else is the
settings. The same settings and seed give the same files.

Files (:func:`write_station`, all or none)
------------------------------------------
``body.obj``
    One OBJ object (``o name``) per sheet (``sill_hat``, ``sill_inner``, ...); weldplan's loader
    (:func:`weldplan.io.mesh.load_part`) merges them into one part, in which each sheet is a
    connected component; :func:`read_sheets` gives them back by name.
``spots.csv``
    The spots in the joints format (:mod:`weldplan.io.joints`) with a ``flange`` column,
    under a ``# SYNTHETIC`` header line naming the generator and seed.
``truth.json``
    The ground truth: every flange (its two sheets, their gauges, the gap, the overlap, the free
    edge line) and the settings.

All spot coordinates are synthetic: no measured weld data went into them.
"""

from __future__ import annotations

import argparse
import json
import logging
import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field
from os import PathLike
from pathlib import Path

import numpy as np
import trimesh
from numpy.typing import NDArray

from weldplan.errors import ConfigError, InputError
from weldplan.io.joints import Joints
from weldplan.random import RNGLike, as_generator, seed_of

log = logging.getLogger(__name__)

#: common body-in-white sheet gauges (mm); a sheet's gauge is drawn among those in ``thickness``
GAUGES_MM: tuple[float, ...] = (0.8, 1.0, 1.2, 1.5, 1.8, 2.0)
#: the order members are spotted in, and their names in body and flange names
MEMBERS: tuple[str, ...] = ("sill", "bpillar", "roofrail")


@dataclass(frozen=True)
class HatProfile:
    """Cross-section of a hat member (mm).

    Parameters
    ----------
    crown
        Width of the crown (the top of the hat), inner face.
    base
        Width between the two wall roots on the flange plane (inner face); ``base > crown``
        gives walls with a draft.
    depth
        Height of the crown's inner face above the flange plane.
    """

    crown: float = 60.0
    base: float = 110.0
    depth: float = 45.0


@dataclass(frozen=True)
class SheetFrameSettings:
    """Dimensions of the side frame (mm); module docstring.

    ``thickness``, ``overlap`` and ``pitch`` are ``(low, high)`` ranges drawn from with ``rng``.
    """

    sill_length: float = 2600.0
    rail_length: float = 2000.0
    height: float = 1250.0
    sill: HatProfile = field(default_factory=lambda: HatProfile(70.0, 120.0, 50.0))
    rail: HatProfile = field(default_factory=lambda: HatProfile(60.0, 100.0, 40.0))
    pillar: HatProfile = field(default_factory=HatProfile)
    thickness: tuple[float, float] = (0.8, 2.0)
    overlap: tuple[float, float] = (15.0, 25.0)
    pitch: tuple[float, float] = (30.0, 60.0)
    gap: float = 0.2
    end_gap: float = 10.0
    end_margin: float = 25.0
    n_spots: int | None = None

    def __post_init__(self) -> None:
        for name in ("sill_length", "rail_length", "height", "end_margin"):
            _positive(getattr(self, name), name)
        for name in ("thickness", "overlap", "pitch"):
            lo, hi = getattr(self, name)
            if not (math.isfinite(lo) and math.isfinite(hi) and 0 < lo <= hi):
                raise ConfigError(f"{name} must be a range 0 < low <= high, got {(lo, hi)}")
        if not [g for g in GAUGES_MM if self.thickness[0] <= g <= self.thickness[1]]:
            raise ConfigError(f"no gauge of {GAUGES_MM} lies in thickness {self.thickness}")
        if not (math.isfinite(self.gap) and 0 <= self.gap <= 4):
            raise ConfigError(f"gap must be 0-4 mm, got {self.gap}")
        if not (math.isfinite(self.end_gap) and self.end_gap > 0):
            raise ConfigError(f"end_gap must be > 0 mm, got {self.end_gap}")
        for name in ("sill", "rail", "pillar"):
            h = getattr(self, name)
            if not (0 < h.crown < h.base and h.depth > 0):
                raise ConfigError(f"{name}: need 0 < crown < base and depth > 0, got {h}")
        if self.n_spots is not None and self.n_spots < 1:
            raise ConfigError(f"n_spots must be >= 1, got {self.n_spots}")


@dataclass(frozen=True)
class Member:
    """One hat member placed in the frame: axis ``u``, across ``w``, out of the flanges ``h``.

    ``origin`` is where the member's axis starts on the flange plane; ``u, w, h`` are unit axes
    (3,), right-handed; the member runs ``length`` mm along ``u``.
    """

    name: str
    origin: tuple[float, float, float]
    u: tuple[float, float, float]
    w: tuple[float, float, float]
    length: float
    profile: HatProfile
    overlap: float
    t_hat: float
    t_inner: float


@dataclass(frozen=True)
class FlangeTruth:
    """A generated lap joint: two sheets face to face over ``overlap`` mm (ground truth).

    ``edge`` is the free edge of the stack, a segment ``(2, 3)`` mm; ``root`` the line where the
    hat's wall leaves the flange (the other side of the overlap); ``normal`` the stack's normal
    (3,), from the inner panel towards the hat; ``gap`` the air gap and ``thickness`` the stack
    from outer face to outer face (mm).
    """

    name: str
    bodies: tuple[str, str]
    gauges: tuple[float, float]
    gap: float
    thickness: float
    overlap: float
    normal: tuple[float, float, float]
    edge: tuple[tuple[float, float, float], tuple[float, float, float]]
    root: tuple[tuple[float, float, float], tuple[float, float, float]]


@dataclass(frozen=True, eq=False)
class SheetStation:
    """A generated station: one mesh per sheet, the spots and the ground truth.

    ``sheets`` maps each sheet's name to its closed solid (mm); ``spots`` are the welds
    (synthetic; directions from the spot towards the torch); ``spot_flange`` names the flange of
    each spot; ``flanges`` the ground truth.
    """

    sheets: dict[str, trimesh.Trimesh]
    spots: Joints
    spot_flange: tuple[str, ...]
    flanges: tuple[FlangeTruth, ...]
    members: tuple[Member, ...]
    settings: SheetFrameSettings
    seed: int | None

    def combined(self) -> trimesh.Trimesh:
        """All sheets in one mesh (what :func:`weldplan.io.mesh.load_part` makes of body.obj)."""
        return trimesh.util.concatenate(list(self.sheets.values()))

    def spot_depth(self) -> float:
        """mm: how far below the surface the gun presses (the inner panel's, the approach
        side) the deepest spot lies: that panel's gauge plus half the gap, the largest over the
        flanges that carry spots (``spot_depth`` of the route stage, docs/sheetmetal.md)."""
        used = set(self.spot_flange)
        depths = [
            g + f.gap / 2.0
            for f in self.flanges
            if f.name in used
            for b, g in zip(f.bodies, f.gauges, strict=True)
            if b.endswith("_inner")
        ]
        return max(depths, default=0.0)


def _positive(value: float, name: str) -> None:
    if not (math.isfinite(value) and value > 0):
        raise ConfigError(f"{name} must be a positive number of mm, got {value}")


def _frame_members(s: SheetFrameSettings, rng: np.random.Generator) -> tuple[Member, ...]:
    """The three members in place, with their drawn gauges and overlaps."""
    gauges = [g for g in GAUGES_MM if s.thickness[0] <= g <= s.thickness[1]]

    def draw() -> tuple[float, float, float]:
        o = float(np.round(rng.uniform(*s.overlap) * 2) / 2)
        o = min(max(o, s.overlap[0]), s.overlap[1])
        return o, float(rng.choice(gauges)), float(rng.choice(gauges))

    def half(p: HatProfile, o: float) -> float:
        return p.base / 2 + o

    X, Z = (1.0, 0.0, 0.0), (0.0, 0.0, 1.0)
    o_s, th_s, ti_s = draw()
    o_r, th_r, ti_r = draw()
    o_p, th_p, ti_p = draw()
    z_s = half(s.sill, o_s)
    z_r = z_s + s.height
    x_r = (s.sill_length - s.rail_length) / 2
    z0 = z_s + half(s.sill, o_s) + s.end_gap
    z1 = z_r - half(s.rail, o_r) - s.end_gap
    if z1 - z0 < 2 * s.end_margin:
        raise ConfigError(f"height {s.height} mm leaves no room for the B-pillar")
    # w x u = h = +y for all three: (u, w) = (x, -z)... chosen so that h = u x w is +y
    return (
        Member("sill", (0.0, 0.0, z_s), X, (0, 0, -1.0), s.sill_length, s.sill, o_s, th_s, ti_s),
        Member("bpillar", (s.sill_length / 2, 0.0, z0), Z, X, z1 - z0, s.pillar, o_p, th_p, ti_p),
        Member(
            "roofrail", (x_r, 0.0, z_r), X, (0, 0, -1.0), s.rail_length, s.rail, o_r, th_r, ti_r
        ),
    )


def _offset_polyline(P: NDArray[np.float64], t: float) -> NDArray[np.float64]:
    """The polyline ``P (m, 2)`` offset by ``t`` to the left of its direction, mitred, so that
    each segment's offset lies exactly ``t`` from it."""
    d = np.diff(P, axis=0)
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    n = np.column_stack([-d[:, 1], d[:, 0]])  # left normals of the segments
    Q = np.empty_like(P)
    Q[0] = P[0] + t * n[0]
    Q[-1] = P[-1] + t * n[-1]
    for k in range(1, len(P) - 1):
        b = n[k - 1] + n[k]
        b /= np.linalg.norm(b)
        Q[k] = P[k] + b * t / float(b @ n[k])
    return Q


def _strip_prism(
    lo: NDArray[np.float64], up: NDArray[np.float64], length: float
) -> trimesh.Trimesh:
    """The closed solid of the strip between polylines ``lo`` and ``up`` ``(m, 2)`` in (w, h),
    extruded over u in [0, length]; vertices ``(u, w, h)``."""
    m = len(lo)
    ring = np.concatenate([lo, up[::-1]])  # the closed profile polygon, 2m corners
    V = np.concatenate([np.column_stack([np.full(2 * m, u), ring]) for u in (0.0, float(length))])
    F = []
    for k in range(m - 1):  # end caps: the quads between lo[k], lo[k+1], up[k+1], up[k]
        a, b, c, d = k, k + 1, 2 * m - 2 - k, 2 * m - 1 - k
        F += [[a, c, b], [a, d, c]]
        F += [[a + 2 * m, b + 2 * m, c + 2 * m], [a + 2 * m, c + 2 * m, d + 2 * m]]
    for k in range(2 * m):  # the sides
        a, b = k, (k + 1) % (2 * m)
        F += [[a, b, b + 2 * m], [a, b + 2 * m, a + 2 * m]]
    mesh = trimesh.Trimesh(V, np.asarray(F), process=False)
    if mesh.volume < 0:
        mesh.invert()
    return mesh


def _hat_polyline(p: HatProfile, overlap: float) -> NDArray[np.float64]:
    """The inner face of a hat sheet in (w, h): flange, wall, crown, wall, flange."""
    b, c, o = p.base / 2, p.crown / 2, overlap
    return np.array([[-b - o, 0], [-b, 0], [-c, p.depth], [c, p.depth], [b, 0], [b + o, 0]], float)


def _to_world(member: Member, V: NDArray[np.float64]) -> NDArray[np.float64]:
    """Vertices ``(n, 3)`` given as (u, w, h) in the member's frame, in the frame of the body."""
    u, w = np.asarray(member.u, float), np.asarray(member.w, float)
    h = np.cross(u, w)
    return np.asarray(member.origin) + V[:, :1] * u + V[:, 1:2] * w + V[:, 2:3] * h


def member_sheets(member: Member, gap: float) -> dict[str, trimesh.Trimesh]:
    """The member's hat and inner panel as closed solids in the body frame (mm)."""
    lo = _hat_polyline(member.profile, member.overlap)
    hat = _strip_prism(lo, _offset_polyline(lo, member.t_hat), member.length)
    half = member.profile.base / 2 + member.overlap
    flat_up = np.array([[-half, -gap], [half, -gap]])
    inner = _strip_prism(flat_up - [0, member.t_inner], flat_up, member.length)
    out = {}
    for name, m in ((f"{member.name}_hat", hat), (f"{member.name}_inner", inner)):
        m.vertices = _to_world(member, np.asarray(m.vertices))
        out[name] = m
    return out


def member_flanges(member: Member, gap: float) -> tuple[FlangeTruth, FlangeTruth]:
    """The member's two lap joints (ground truth; ``a`` on the -w side, ``b`` on +w)."""
    b, o = member.profile.base / 2, member.overlap
    out = []
    for side, sgn in (("a", -1.0), ("b", 1.0)):
        ends = np.array([[0.0, sgn * (b + o), 0.0], [member.length, sgn * (b + o), 0.0]])
        roots = ends.copy()
        roots[:, 1] = sgn * b
        n = np.cross(np.asarray(member.u, float), np.asarray(member.w, float))
        out.append(
            FlangeTruth(
                name=f"{member.name}_{side}",
                bodies=(f"{member.name}_hat", f"{member.name}_inner"),
                gauges=(member.t_hat, member.t_inner),
                gap=gap,
                thickness=member.t_hat + member.t_inner + gap,
                overlap=o,
                normal=tuple(float(v) for v in n),  # type: ignore[arg-type]
                edge=_pair(_to_world(member, ends)),
                root=_pair(_to_world(member, roots)),
            )
        )
    return out[0], out[1]


def _pair(P: NDArray[np.float64]) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    return tuple(float(v) for v in P[0]), tuple(float(v) for v in P[1])  # type: ignore[return-value]


def _spot_line(
    member: Member, side: float, gap: float, s: SheetFrameSettings, rng: np.random.Generator
) -> NDArray[np.float64]:
    """Spots ``(k, 3)`` of one flange: mid-overlap, mid-gap, every drawn pitch along u."""
    us = [s.end_margin + rng.uniform(0, s.pitch[0] / 2)]
    while True:
        nxt = us[-1] + rng.uniform(*s.pitch)
        if nxt > member.length - s.end_margin:
            break
        us.append(nxt)
    w = side * (member.profile.base / 2 + member.overlap / 2)
    V = np.column_stack([us, np.full(len(us), w), np.full(len(us), -gap / 2)])
    return _to_world(member, V)


def generate_side_frame(
    settings: SheetFrameSettings | None = None, *, rng: RNGLike = None
) -> SheetStation:
    """A side-frame station: sheets, spots and ground truth (module docstring).

    Parameters
    ----------
    settings
        Dimensions and ranges; default :class:`SheetFrameSettings`.
    rng
        Seed or Generator for the gauges, overlaps and pitches.

    Raises
    ------
    ConfigError
        Inconsistent settings, or more ``n_spots`` than the flanges hold.
    """
    s = settings or SheetFrameSettings()
    seed = seed_of(rng)
    gen = as_generator(rng)
    members = _frame_members(s, gen)
    sheets: dict[str, trimesh.Trimesh] = {}
    flanges: list[FlangeTruth] = []
    xyz, names, fl = [], [], []
    for m in members:
        sheets.update(member_sheets(m, s.gap))
        fa, fb = member_flanges(m, s.gap)
        flanges += [fa, fb]
        for f, side in ((fa, -1.0), (fb, 1.0)):
            P = _spot_line(m, side, s.gap, s, gen)
            xyz.append(P)
            names += [f"{f.name}-{k + 1}" for k in range(len(P))]
            fl += [f.name] * len(P)
    P = np.concatenate(xyz)
    if s.n_spots is not None:
        if s.n_spots > len(P):
            raise ConfigError(f"the flanges hold {len(P)} spots at this pitch, not {s.n_spots}")
        P, names, fl = P[: s.n_spots], names[: s.n_spots], fl[: s.n_spots]
    # the torch comes from the inner panel's side: -h, h = u x w = +y for every member
    normal = np.cross(np.asarray(members[0].u, float), np.asarray(members[0].w, float))
    dirs = np.tile(-normal, (len(P), 1))
    spots = Joints(ids=tuple(names), xyz=P, directions=dirs)
    log.info("side frame: %d sheets, %d flanges, %d spots", len(sheets), len(flanges), len(P))
    return SheetStation(sheets, spots, tuple(fl), tuple(flanges), members, s, seed)


def obj_text(sheets: dict[str, trimesh.Trimesh]) -> str:
    """One OBJ object per sheet (``o name``, ``v``, ``f``), coordinates in mm to 1e-6."""
    lines = ["# weldplan.weld.sheetmetal: one object per sheet, mm"]
    base = 1
    for name, m in sheets.items():
        lines.append(f"o {name}")
        lines += [f"v {x:.6f} {y:.6f} {z:.6f}" for x, y, z in np.asarray(m.vertices)]
        lines += [f"f {a + base} {b + base} {c + base}" for a, b, c in np.asarray(m.faces)]
        base += len(m.vertices)
    return "\n".join(lines) + "\n"


def read_sheets(path: str | PathLike[str]) -> dict[str, trimesh.Trimesh]:
    """The sheets of an OBJ file by object name (``o`` lines; ``v`` and ``f`` of triangles).

    Raises
    ------
    InputError
        Missing file, a face before any ``o`` line, a bad or out-of-range ``f`` line (file, line).
    """
    path = Path(path)
    if not path.is_file():
        raise InputError("OBJ file not found", path=path)
    verts: list[list[float]] = []
    faces: dict[str, list[list[int]]] = {}
    current = None
    for lineno, line in enumerate(path.read_text(encoding="utf-8").splitlines(), start=1):
        tok = line.split()
        if not tok or tok[0].startswith("#"):
            continue
        try:
            if tok[0] == "o":
                current = " ".join(tok[1:])
                faces.setdefault(current, [])
            elif tok[0] == "v":
                verts.append([float(t) for t in tok[1:4]])
            elif tok[0] == "f":
                if current is None:
                    raise InputError("face before any 'o' line", path=path, line=lineno, field="o")
                idx = [int(t.split("/")[0]) - 1 for t in tok[1:4]]
                if len(idx) != 3 or min(idx) < 0 or max(idx) >= len(verts):
                    raise ValueError(f"vertex index out of range in {line!r}")
                faces[current].append(idx)
        except ValueError as exc:
            if isinstance(exc, InputError):
                raise
            raise InputError(
                f"cannot read {tok[0]!r} line: {exc}", path=path, line=lineno
            ) from None
    V = np.asarray(verts, dtype=np.float64)
    out = {}
    for name, F in faces.items():
        m = trimesh.Trimesh(V, np.asarray(F, dtype=np.int64).reshape(-1, 3), process=False)
        m.remove_unreferenced_vertices()
        out[name] = m
    return out


def station_texts(station: SheetStation) -> dict[str, str]:
    """The files of :func:`write_station` as texts, by file name."""
    s = station.settings
    n = len(station.spots)
    header = (
        f"# SYNTHETIC weld spots ({n}): not measured; generated by weldplan.weld.sheetmetal "
        f"(seed {station.seed}) on its side frame (sill, B-pillar, roof rail: hat sections closed "
        f"by inner panels); spots at mid-overlap on the faying surface of each flange, pitch "
        f"{s.pitch[0]:g}-{s.pitch[1]:g} mm, approach from the inner panel's side\n"
        f"# the deepest spot lies {station.spot_depth():g} mm below the inner panel's surface: "
        f"plan with --spot-depth {station.spot_depth():g} or more\n"
    )
    rows = ["id,x,y,z,nx,ny,nz,flange"]
    assert station.spots.directions is not None
    for k, jid in enumerate(station.spots.ids):
        x, y, z = station.spots.xyz[k]
        nx, ny, nz = station.spots.directions[k] + 0.0  # no "-0.000000"
        rows.append(
            f"{jid},{x:.6f},{y:.6f},{z:.6f},{nx:.6f},{ny:.6f},{nz:.6f},{station.spot_flange[k]}"
        )
    truth = {
        "synthetic": True,
        "generator": "weldplan.weld.sheetmetal.generate_side_frame",
        "seed": station.seed,
        "settings": asdict(s),
        "members": [asdict(m) for m in station.members],
        "flanges": [asdict(f) for f in station.flanges],
    }
    return {
        "body.obj": obj_text(station.sheets),
        "spots.csv": header + "\n".join(rows) + "\n",
        "truth.json": json.dumps(truth, indent=1) + "\n",
    }


def write_station(station: SheetStation, out: str | PathLike[str]) -> list[Path]:
    """Write ``body.obj``, ``spots.csv`` and ``truth.json`` into folder ``out`` (made if
    absent), all or none (:func:`weldplan.io.outputset.write_outputs`)."""
    from weldplan.io.outputset import check_outputs, write_outputs

    folder = Path(out)
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InputError(
            f"cannot make the output folder ({exc.strerror or exc})", path=folder
        ) from exc
    texts = {folder / name: text for name, text in station_texts(station).items()}
    check_outputs({p.name: p for p in texts})
    return write_outputs(texts)


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m weldplan.weld.sheetmetal OUT [--seed S] [--spots N] [--gap MM]
    [--thickness LO HI] [--overlap LO HI] [--pitch LO HI]``: write a station."""
    ap = argparse.ArgumentParser(
        prog="python -m weldplan.weld.sheetmetal", description=__doc__.splitlines()[0]
    )
    ap.add_argument("out", help="folder to write body.obj, spots.csv and truth.json into")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--spots", type=int, default=None, help="number of spots (default: all)")
    ap.add_argument("--gap", type=float, default=SheetFrameSettings.gap, help="air gap, mm")
    d = SheetFrameSettings()
    for name, what in (
        ("thickness", "sheet gauges"),
        ("overlap", "flange overlaps"),
        ("pitch", "spot pitch"),
    ):
        ap.add_argument(f"--{name}", type=float, nargs=2, metavar=("LO", "HI"),
                        default=getattr(d, name), help=f"range of the {what}, mm")  # fmt: skip
    args = ap.parse_args(argv)
    from weldplan.errors import WeldplanError

    try:
        station = generate_side_frame(
            SheetFrameSettings(
                n_spots=args.spots,
                gap=args.gap,
                thickness=tuple(args.thickness),
                overlap=tuple(args.overlap),
                pitch=tuple(args.pitch),
            ),
            rng=args.seed,
        )
        paths = write_station(station, args.out)
    except WeldplanError as exc:
        ap.exit(2, f"error: {exc}\n")
    log.info("wrote %s", ", ".join(str(p) for p in paths))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
