"""The independent check of a route before it leaves weldplan.

:func:`verify_route` trusts nothing the planner computed: it builds its own
:class:`~weldplan.geometry.collision.CollisionModel` from the part mesh (python-fcl), re-checks
every segment of every leg, and checks that the route visits every joint exactly once, starting
and ending each leg on the joint's weld spot.

How the approach segments are exempted, exactly
-----------------------------------------------
The torch tip is a sphere of radius ``c`` (the clearance), and a segment is free when the capsule
it sweeps misses the part. The first and the last segment of every leg run between a weld spot
``p``, which lies *on* the surface, and its virtual joint ``v`` (length ``L``); any sphere centred
at ``p`` touches the part, so these two segments cannot be checked at ``c``. Nothing else is
exempt: every other segment is checked at the full clearance.

An approach segment is checked as a *cone*: at distance ``s`` from the spot the sphere has radius
``r(s) = c * s / L``, growing linearly from 0 at the spot to ``c`` at the virtual joint. This is
exactly what a straight descent onto a locally flat spot allows: if the surface is a plane
through ``p`` and ``v`` is at height ``h >= c`` above it (the grid's obstacle rule), the point at
distance ``s`` along the approach is at height ``s * h / L >= r(s)``, whatever the angle of the
approach. The cone rejects any approach that grazes a flange, an edge or a second panel on the way
down. It is checked with :data:`APPROACH_PIECES` capsules covering ``s`` from
:data:`APPROACH_EXEMPT_MM` to ``L``: piece ``m`` spans ``[s_m, s_m+1]`` with radius
``r(s_m) * (1 - APPROACH_SLACK)``, so the pieces lie inside the cone (the check never asks more
than the cone) and touching contact at equality (e.g. a spot in a 90-degree inside corner, where
the cone is tangent to both walls) is not reported. The first ``APPROACH_EXEMPT_MM`` mm around the
spot, where the torch is at the weld, are the only part of the route not checked at all.

A weld spot that is its own virtual joint (it lies in free space, at least ``c`` from the part)
has no approach: the segment leaving it is checked at the full clearance like any other.

Inside closed solids
--------------------
A capsule check sees triangles only: a segment deep inside a closed solid (a block, a cast
bracket) touches none. So every point of the route but the weld spots on the surface (every
virtual joint and via, and a spot that is its own virtual joint) is inside-tested against each
closed component of the part (:class:`~weldplan.geometry.solids.ClosedSolids`, trimesh's ray
parity through embree: not the open3d occupancy the grid uses). A segment whose capsule misses
every triangle cannot cross the surface, so it lies wholly inside or wholly outside each closed
component, and its end points decide which; an approach segment is decided by its virtual joint.

Provenance
----------
A route planned by this version records what it was planned against
(:attr:`weldplan.weld.route.Route.provenance`). :func:`verify_route` refuses, with an
:class:`~weldplan.errors.InputError`, to check it against a mesh with other geometry (another
file, or the same file at another units or scale) or at another clearance than it was planned
for; a route without provenance (written before) is checked with a logged warning.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import trimesh
from numpy.typing import NDArray

from weldplan.errors import InputError
from weldplan.geometry.checker import CheckVerdict
from weldplan.geometry.collision import CollisionModel
from weldplan.geometry.solids import ClosedSolids
from weldplan.io.mesh import MAX_COORD_MM, geometry_hash
from weldplan.weld.approach import (  # noqa: F401 - verify's names: tests and callers import them here
    APPROACH_EXEMPT_MM,
    APPROACH_PIECES,
    APPROACH_SLACK,
    approach_free,
    approach_pieces,
    spot_depth,
)
from weldplan.weld.route import Route

log = logging.getLogger(__name__)

#: mm: how far a leg's end may be from the joint's weld spot (JSON round trips are exact; CSV
#: and hand-edited routes are not)
ENDPOINT_TOL_MM = 1e-3


@dataclass(frozen=True)
class Violation:
    """One thing wrong with a route.

    ``leg`` and ``segment`` are 0-based (``segment`` k joins ``points[k]`` and ``points[k + 1]`` of
    the leg); both are ``None`` for route-level problems (a joint missing or visited twice).
    """

    kind: str
    message: str
    leg: int | None = None
    segment: int | None = None
    from_id: str | None = None
    to_id: str | None = None

    def __str__(self) -> str:
        if self.leg is None:
            return self.message
        where = f"leg {self.leg} ({self.from_id} -> {self.to_id})"
        if self.segment is not None:
            where += f", segment {self.segment}"
        return f"{where}: {self.message}"


@dataclass(frozen=True)
class VerifyReport:
    """The verdict of :func:`verify_route`: ``ok`` and every violation found."""

    ok: bool
    violations: tuple[Violation, ...]
    clearance: float
    segments_checked: int
    approach_segments: int
    joints_visited: int
    stats: dict[str, Any] = field(default_factory=dict)

    def __bool__(self) -> bool:
        return self.ok

    @property
    def verdict(self) -> CheckVerdict:
        """This check as a :class:`~weldplan.geometry.checker.CheckVerdict` (places: legs and
        segments; the route's segments are judged free or not, no distance is measured)."""
        fails = []
        for v in self.violations:
            where = str(v)[: -len(v.message)].rstrip(": ") if v.leg is not None else ""
            fails.append((where, v.message))
        return CheckVerdict.of("route", self.segments_checked, fails, ok=self.ok)

    def describe(self, limit: int = 5) -> str:
        """One line a user can act on (the first ``limit`` violations)."""
        if self.ok:
            smooth = self.stats.get("smooth_segments")
            return (
                f"route ok: {self.segments_checked} segments free at {self.clearance:g} mm "
                f"clearance, {self.approach_segments} approaches within their cones, "
                f"{self.joints_visited} joints visited once each"
                + (
                    f"; {smooth} segments of {self.stats['smooth_legs']} smooth legs free too"
                    if smooth
                    else ""
                )
            )
        shown = "; ".join(str(v) for v in self.violations[:limit])
        more = len(self.violations) - limit
        return f"route fails verification: {shown}" + (f" (and {more} more)" if more > 0 else "")

    def to_dict(self) -> dict[str, Any]:
        return {
            "ok": self.ok,
            "clearance": self.clearance,
            "segments_checked": self.segments_checked,
            "approach_segments": self.approach_segments,
            "joints_visited": self.joints_visited,
            "violations": [v.__dict__.copy() for v in self.violations],
            "stats": self.stats,
        }

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> VerifyReport:
        return cls(
            ok=bool(d["ok"]),
            violations=tuple(Violation(**v) for v in d["violations"]),
            clearance=float(d["clearance"]),
            segments_checked=int(d["segments_checked"]),
            approach_segments=int(d["approach_segments"]),
            joints_visited=int(d["joints_visited"]),
            stats=dict(d.get("stats") or {}),
        )


def _collision_model(part: Any) -> CollisionModel:
    """A fresh CollisionModel from a mesh or a cell; a CollisionModel given is used as is."""
    if isinstance(part, CollisionModel):
        return part
    mesh = getattr(part, "part", part)  # a Cell carries its mesh as .part
    if not isinstance(mesh, trimesh.Trimesh):
        raise InputError(
            f"expected a trimesh.Trimesh, a Cell or a CollisionModel, got {type(part).__name__}"
        )
    return CollisionModel(mesh)


def check_clearance(clearance: Any, what: str = "clearance") -> float:
    """``float(clearance)`` when it is a positive finite number of mm, else InputError (the
    message the CLI gives)."""
    try:
        c = float(clearance)
    except (TypeError, ValueError):
        c = float("nan")
    if not (np.isfinite(c) and c > 0):
        raise InputError(f"{what} must be a positive number of mm, got {clearance!r}")
    return c


def check_provenance(route: Route, mesh: trimesh.Trimesh, clearance: float | None) -> None:
    """InputError when ``route`` was planned against another mesh, scale or clearance.

    ``clearance`` is the one the caller asked for (None: the route's own). A route without
    provenance passes with a logged warning.
    """
    prov = route.provenance
    if not prov:
        log.warning(
            "the route carries no provenance (written before weldplan recorded it): cannot "
            "check that it was planned for this mesh, scale and clearance"
        )
        return
    planned = prov.get("mesh") or {}
    want = planned.get("geometry_sha256")
    if want and geometry_hash(mesh) != want:
        meta = mesh.metadata.get("weldplan") or {}
        same_file = planned.get("file_sha256") and meta.get("file_sha256") == planned.get(
            "file_sha256"
        )
        then = f"units {planned.get('units')!r}, scale {planned.get('scale')}"
        if same_file:
            now = f"units {meta.get('units')!r}, scale {meta.get('scale')}"
            raise InputError(
                f"the route was planned for this mesh file at {then}, it is loaded at {now}: "
                "give the same --units/--scale/--length as when planning"
            )
        raise InputError(
            f"the route was planned for another mesh ({planned.get('file') or 'in memory'}, "
            f"{then}; geometry sha256 {str(want)[:12]}..., this one "
            f"{geometry_hash(mesh)[:12]}...): verify it against the mesh it was planned for"
        )
    planned_c = prov.get("clearance")
    if clearance is not None and planned_c is not None and float(planned_c) != clearance:
        raise InputError(
            f"the route was planned at clearance {float(planned_c):g} mm, not {clearance:g} mm: "
            "verify it at its own clearance (leave --clearance out) or plan it again"
        )


def _inside_solids(
    route: Route, solids: ClosedSolids, tol: float, smooth: bool = False
) -> list[tuple[int, int, NDArray[np.float64]]]:
    """``(leg, segment, point)`` of each route point (but weld spots on the surface) that lies
    inside a closed solid (trimesh ray parity: :meth:`ClosedSolids.contains`); ``smooth``: of
    the legs' smooth paths instead of their polylines."""
    if len(solids) == 0:
        return []
    pts, where = [], []
    for k, leg in enumerate(route.legs):
        if smooth and leg.smooth is None:
            continue
        P = leg.smooth if smooth else leg.points
        if not (np.all(np.isfinite(P)) and np.abs(P).max() <= MAX_COORD_MM):
            continue
        first = 0 if route.is_virtual(leg.from_id, P[0], tol) else 1
        last = len(P) if route.is_virtual(leg.to_id, P[-1], tol) else len(P) - 1
        for m in range(first, last):
            pts.append(P[m])
            where.append((k, min(m, len(P) - 2)))  # the segment that starts at the point
    if not pts:
        return []
    inside = solids.contains(np.array(pts))
    return [(k, seg, pts[i]) for i, (k, seg) in enumerate(where) if inside[i]]


def verify_route(
    route: Route,
    part: Any,
    *,
    clearance: float | None = None,
    joints: Any = None,
    approach_pieces_per_segment: int = APPROACH_PIECES,
) -> VerifyReport:
    """Re-check ``route`` against the part, independently of the planner.

    Parameters
    ----------
    route
        The route to check.
    part
        The part as a ``trimesh.Trimesh`` or a Cell (a new CollisionModel is built from its mesh,
        so the check shares nothing with the planner but the triangles), or a ready
        ``CollisionModel`` (used as is; saves the BVH build when the caller owns one).
    clearance
        mm, the radius of the torch-tip sphere, positive and finite. Default: the clearance in
        ``route.settings``, else 5 mm. A route that records its provenance is refused at any
        other clearance than its own.
    joints
        Optional ``Joints`` (ids, xyz) from the joints CSV: when given, the route's joint table
        must match it (same ids, weld spots within :data:`ENDPOINT_TOL_MM`).
    approach_pieces_per_segment
        Capsules per approach cone.

    Returns
    -------
    VerifyReport
        ``ok`` is true when every middle segment is free at ``clearance``, every approach is
        inside its cone (module docstring), every leg starts and ends on its joints' weld spots,
        and every joint is visited exactly once, and no point of the route lies inside a
        closed solid of the part (module docstring).

    Raises
    ------
    InputError
        ``clearance`` is not a positive finite number, or the route was planned for another
        mesh, scale or clearance (module docstring).
    """
    asked = None if clearance is None else check_clearance(clearance)
    model = _collision_model(part)
    check_provenance(route, model.mesh, asked)
    if asked is None:
        clearance = check_clearance(route.settings.get("clearance", 5.0), "the route's clearance")
    else:
        clearance = asked
    violations = _joint_table(route, joints)
    counts, visit_violations = _visits(route)
    violations += visit_violations
    pieces = _LegPieces(spot_depth(route))
    for k, leg in enumerate(route.legs):
        violations += pieces.add(route, k, leg, clearance, approach_pieces_per_segment)
    failed = _collisions(model, pieces, clearance)
    violations += _collision_violations(route, failed)
    violations += _inside_violations(route, model, failed)
    smooth = _smooth_paths(route, model, clearance, approach_pieces_per_segment)
    violations += smooth[0]
    report = VerifyReport(
        ok=not violations,
        violations=tuple(violations),
        clearance=float(clearance),
        segments_checked=len(pieces.mid_a),
        approach_segments=len(set(pieces.app_where)),
        joints_visited=sum(1 for jid in route.joint_ids if counts.get(jid, 0) == 1),
        stats=smooth[1],
    )
    log.info("%s", report.describe())
    return report


class _SmoothView:
    """A leg seen through its smooth path (what :class:`_LegPieces` reads of a leg)."""

    def __init__(self, leg: Any) -> None:
        self.points = leg.smooth
        self.from_id = leg.from_id
        self.to_id = leg.to_id


def _smooth_paths(
    route: Route, model: CollisionModel, clearance: float, n_pieces: int
) -> tuple[list[Violation], dict[str, Any]]:
    """The legs' smooth paths (``weldplan plan --smooth``), checked as their polylines are: each
    chord between dense waypoints at the full clearance with python-fcl, the approach segments
    as cones, the ends on the weld spots, no point inside a closed solid. Violations are of
    kind ``"smooth"``, their segment numbered along the smooth path."""
    legs = [k for k, leg in enumerate(route.legs) if leg.smooth is not None]
    if not legs:
        return [], {}
    pieces = _LegPieces(spot_depth(route))
    found: list[Violation] = []
    for k in legs:
        found += pieces.add(route, k, _SmoothView(route.legs[k]), clearance, n_pieces)
    failed = _collisions(model, pieces, clearance)
    found += _collision_violations(route, failed)
    out = []
    for k, seg, p in _inside_solids(route, ClosedSolids.of(model.mesh), ENDPOINT_TOL_MM, True):
        if (k, seg) not in failed:
            failed[(k, seg)] = "inside"
            msg = f"the point {np.round(p, 3).tolist()} lies inside a closed solid of the part"
            found.append(Violation("inside", msg, k, seg))
    for v in found:
        leg = route.legs[v.leg] if v.leg is not None else None
        out.append(
            Violation(
                "smooth",
                f"smooth path: {v.message}",
                v.leg,
                v.segment,
                None if leg is None else leg.from_id,
                None if leg is None else leg.to_id,
            )
        )
    stats = {"smooth_legs": len(legs), "smooth_segments": len(pieces.mid_a)}
    return out, stats


def _joint_table(route: Route, joints: Any) -> list[Violation]:
    """The route's joint table against the joints given (same ids, spots within tolerance)."""
    if joints is None:
        return []
    ids = route.joint_ids
    jids = tuple(str(i) for i in joints.ids)
    jxyz = np.asarray(joints.xyz, dtype=float).reshape(-1, 3)
    if set(jids) != set(ids):
        missing = sorted(set(jids) - set(ids))
        extra = sorted(set(ids) - set(jids))
        return [
            Violation(
                "joints",
                f"the route's joints differ from the joints given "
                f"(missing {missing or 'none'}, unknown {extra or 'none'})",
            )
        ]
    out = []
    for jid, p in zip(jids, jxyz, strict=True):
        q = route.joint_xyz[route.index_of(jid)]
        if np.linalg.norm(q - p) > ENDPOINT_TOL_MM:
            out.append(
                Violation(
                    "joints",
                    f"joint {jid} is at {q.tolist()} in the route, "
                    f"{p.tolist()} in the joints given",
                )
            )
    return out


def _visits(route: Route) -> tuple[dict[str, int], list[Violation]]:
    """How often the order visits each joint, and what is wrong with that: each joint exactly
    once, but the joints ``--skip-unreachable`` listed in ``stats.skipped``, which never."""
    ids = route.joint_ids
    counts: dict[str, int] = {}
    for jid in route.order:
        counts[jid] = counts.get(jid, 0) + 1
    skipped = {str(s["id"]) for s in route.stats.get("skipped") or ()}
    out = []
    for jid in ids:
        if jid in skipped:
            if counts.get(jid, 0):
                out.append(Violation("skipped", f"joint {jid} is skipped but visited"))
        elif counts.get(jid, 0) == 0:
            out.append(Violation("missing", f"joint {jid} is never visited"))
        elif counts[jid] > 1:
            out.append(Violation("duplicate", f"joint {jid} is visited {counts[jid]} times"))
    for jid in counts:
        if jid not in ids:
            out.append(Violation("unknown", f"joint {jid} in the order is not a joint"))
    return counts, out


class _LegPieces:
    """The capsules to check, gathered leg by leg: middle segments at the full clearance, and
    the approach cones as :func:`approach_pieces` (module docstring)."""

    def __init__(self, depth: float = 0.0) -> None:
        self.depth = depth
        self.mid_a: list[NDArray] = []
        self.mid_b: list[NDArray] = []
        self.mid_where: list[tuple[int, int]] = []
        self.app_a: list[NDArray] = []
        self.app_b: list[NDArray] = []
        self.app_r: list[float] = []
        self.app_where: list[tuple[int, int]] = []

    def add(self, route: Route, k: int, leg: Any, clearance: float, n_pieces: int) -> list:
        """Gather leg ``k``'s pieces; returns the leg's violations found without geometry
        (endpoints off their weld spots, points that cannot be checked, spot to spot)."""
        P = leg.points
        tag = {"leg": k, "from_id": leg.from_id, "to_id": leg.to_id}
        out = _endpoint_violations(route, leg, tag)
        if not np.all(np.isfinite(P)):
            return out + [Violation("points", "the leg has non-finite points", **tag)]
        if not np.abs(P).max() <= MAX_COORD_MM:
            # FCL's capsule of a segment 1e300 mm long has no precision left: nothing to verify
            msg = f"the leg has points beyond {MAX_COORD_MM:.0e} mm, which cannot be checked"
            return out + [Violation("points", msg, **tag)]
        # A segment is an approach when it leaves a weld spot that is not its own virtual joint
        # (a joint lying in free space is its own virtual joint and has no approach).
        start_app = not route.is_virtual(leg.from_id, P[0], ENDPOINT_TOL_MM)
        end_app = not route.is_virtual(leg.to_id, P[-1], ENDPOINT_TOL_MM)
        last = len(P) - 2
        if last == 0 and start_app and end_app:
            msg = "the leg goes from weld spot to weld spot with no virtual joint between"
            return out + [Violation("approach", msg, segment=0, **tag)]
        for seg in range(last + 1):
            if seg == 0 and start_app:
                spot, virt = P[0], P[1]
            elif seg == last and end_app:
                spot, virt = P[-1], P[-2]
            else:
                self.mid_a.append(P[seg])
                self.mid_b.append(P[seg + 1])
                self.mid_where.append((k, seg))
                continue
            A, B, r = approach_pieces(spot, virt, clearance, pieces=n_pieces, depth=self.depth)
            self.app_a += list(A)
            self.app_b += list(B)
            self.app_r += [float(x) for x in r]
            self.app_where += [(k, seg)] * len(r)
        return out


def _endpoint_violations(route: Route, leg: Any, tag: dict[str, Any]) -> list[Violation]:
    """A leg must start and end on its joints' weld spots."""
    out = []
    P = leg.points
    for end, jid, p in (("start", leg.from_id, P[0]), ("end", leg.to_id, P[-1])):
        if jid in route.joint_ids:
            q = route.joint_xyz[route.index_of(jid)]
            if np.linalg.norm(p - q) > ENDPOINT_TOL_MM:
                out.append(
                    Violation(
                        "endpoint",
                        f"the leg's {end} {np.round(p, 3).tolist()} is not the weld spot of "
                        f"joint {jid} {np.round(q, 3).tolist()}",
                        **tag,
                    )
                )
    return out


def _collisions(
    model: CollisionModel, pieces: _LegPieces, clearance: float
) -> dict[tuple[int, int], str]:
    """``(leg, segment) -> reason`` of every middle segment that hits the part at ``clearance``
    and every approach that leaves its cone."""
    failed: dict[tuple[int, int], str] = {}
    if pieces.mid_a:
        free = model.segments_free(np.array(pieces.mid_a), np.array(pieces.mid_b), clearance)
        for where, ok in zip(pieces.mid_where, free, strict=True):
            if not ok:
                failed.setdefault(where, f"the segment hits the part at {clearance:g} mm clearance")
    for a, b, r, where in zip(
        pieces.app_a, pieces.app_b, pieces.app_r, pieces.app_where, strict=True
    ):
        if where in failed:
            continue
        if not model.segment_free(a, b, float(r)):
            failed[where] = (
                "the approach to the weld spot leaves its cone "
                f"(the sphere radius grows from 0 at the spot to {clearance:g} mm)"
            )
    return failed


def _collision_violations(route: Route, failed: dict[tuple[int, int], str]) -> list[Violation]:
    out = []
    for (k, seg), msg in sorted(failed.items()):
        leg = route.legs[k]
        out.append(Violation("collision", msg, k, seg, leg.from_id, leg.to_id))
    return out


def _inside_violations(
    route: Route, model: CollisionModel, failed: dict[tuple[int, int], str]
) -> list[Violation]:
    """Route points inside a closed solid of the part, on segments not already reported
    (a segment that crosses the solid's surface is a collision)."""
    out = []
    for k, seg, p in _inside_solids(route, ClosedSolids.of(model.mesh), ENDPOINT_TOL_MM):
        if (k, seg) in failed:
            continue
        failed[(k, seg)] = "inside"
        leg = route.legs[k]
        msg = f"the point {np.round(p, 3).tolist()} lies inside a closed solid of the part"
        out.append(Violation("inside", msg, k, seg, leg.from_id, leg.to_id))
    return out
