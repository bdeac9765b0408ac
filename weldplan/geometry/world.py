"""One collision world: named bodies, and the pairs of them allowed to touch, kept as data.

The shape is Pinocchio's ``GeometryModel`` (each geometry object named, carried by a joint's
frame, the collision pairs a list one reads and edits) and trimesh's ``CollisionManager`` (named
objects; a query answers with the names of what touches). A stage registers its bodies once (the
part, the robot's links, the tool, the floor) with the FCL object it already built, and the pairs
that are never checked with the reason for each; its checkers then read the pairs to check from
the world instead of keeping a private set, and :meth:`CollisionWorld.describe` prints what an
engineer checks: every body, what it moves with, and every exemption with its reason.

Two kinds of exemption:

- *allowed* (:attr:`CollisionWorld.allowed_pairs`): the pair is never checked (links joined by a
  joint, the tool and the link it is mounted on, pairs disabled by the robot's description, pairs
  in contact at the zero pose or at every sampled configuration, the root link and the floor it
  stands on); :data:`REASONS` lists the reasons.
- *zone* (:attr:`CollisionWorld.zones`): the pair is checked with part of a body exempt (the
  tool's contact zone against the part it welds).

The world holds no state of its own beyond its bodies' FCL objects (whose transforms the
checkers set before each query) and is built once per robot, tool and part.
"""

from __future__ import annotations

import logging
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

log = logging.getLogger(__name__)

#: the kinds of body a world holds
BODY_KINDS = ("part", "link", "tool", "floor", "fixture")

#: why a pair may be exempt, and what each reason means (:meth:`CollisionWorld.describe`)
REASONS: Mapping[str, str] = MappingProxyType(
    {
        "adjacent": "joined by a joint of the robot's URDF (never checked)",
        "tool-flange": "the tool is mounted on this link (never checked)",
        "disabled": "disabled by the robot's description, <disable_collisions> (never checked)",
        "zero pose": "in contact at the zero pose, MoveIt's 'default' rule (never checked)",
        "always": "in contact at every sampled configuration, MoveIt's 'always' (never checked)",
        "on the floor": "the root link stands on the floor or its pedestal (never checked)",
        "contact zone": "the tool touches the part at a weld (checked with the zone exempt)",
    }
)


def pair_key(a: str, b: str) -> frozenset[str]:
    """The key of the unordered pair of bodies named ``a`` and ``b``."""
    return frozenset((a, b))


@dataclass(frozen=True, eq=False)
class WorldBody:
    """A named rigid body of a :class:`CollisionWorld`.

    Attributes
    ----------
    name
        Unique in its world: ``"link_3"``, ``"tool"``, ``"part"``, ``"floor"``.
    kind
        One of :data:`BODY_KINDS`.
    obj
        Its python-fcl ``CollisionObject`` (a BVH of its mesh, or a primitive), in the frame it
        moves with; the checkers set its transform before a query.
    frame
        The index of the robot link frame it rides on (0 = the root link), ``None`` when it is
        fixed in the cell (the part, the floor).
    link
        The name of that link; for a body that moves but not on a robot frame, what it moves
        with (``"the TCP pose"``); ``""`` when fixed.
    shape
        Words for its geometry in :meth:`CollisionWorld.describe` (``"BVH, 1204 triangles"``).
    data
        The registering stage's own record of the body (its sphere cover, its mesh), which the
        stage's checkers read back.
    """

    name: str
    kind: str
    obj: Any
    frame: int | None = None
    link: str = ""
    shape: str = ""
    data: Any = field(default=None, repr=False)

    def moves_with(self) -> str:
        """``"link_6 (frame 6)"``; ``link`` alone for a body that moves but not on a robot
        frame (a tool planned in SE(3)); ``"fixed"``."""
        if self.frame is None:
            return self.link or "fixed"
        return f"{self.link} (frame {self.frame})"


@dataclass(frozen=True, eq=False)
class Exemption:
    """Why a pair of bodies is exempt: ``reason`` (a key of :data:`REASONS`) and ``note``
    (detail: the joint that joins two links, the zone's radius)."""

    reason: str
    note: str = ""


@dataclass(frozen=True, eq=False)
class CollisionWorld:
    """Named bodies and the exempt pairs between them (module docstring).

    Build it with :meth:`of`; it is immutable (the exemptions are read-only mappings).

    Attributes
    ----------
    bodies
        The bodies, in registration order (the order :meth:`pairs_to_check` follows).
    allowed_pairs
        ``{pair_key(a, b): Exemption}``: the pairs never checked.
    zones
        ``{pair_key(a, b): Exemption}``: the pairs checked with part of a body exempt.
    """

    bodies: tuple[WorldBody, ...]
    allowed_pairs: Mapping[frozenset[str], Exemption]
    zones: Mapping[frozenset[str], Exemption] = field(default_factory=lambda: MappingProxyType({}))
    _index: Mapping[str, int] = field(init=False, repr=False)

    def __post_init__(self) -> None:
        """Check the bodies and the pairs (:meth:`of`); the exemptions become read-only
        mappings keyed by :func:`pair_key`."""
        bodies = tuple(self.bodies)
        index: dict[str, int] = {}
        for i, b in enumerate(bodies):
            if b.name in index:
                raise ValueError(f"two bodies of the collision world are named {b.name!r}")
            if b.kind not in BODY_KINDS:
                raise ValueError(f"body {b.name!r}: kind {b.kind!r} is not one of {BODY_KINDS}")
            index[b.name] = i
        a = _exemptions(self.allowed_pairs, index)
        z = _exemptions(self.zones, index)
        both = set(a) & set(z)
        if both:
            raise ValueError(f"pairs both allowed and zoned: {sorted(map(sorted, both))}")
        object.__setattr__(self, "bodies", bodies)
        object.__setattr__(self, "allowed_pairs", MappingProxyType(a))
        object.__setattr__(self, "zones", MappingProxyType(z))
        object.__setattr__(self, "_index", MappingProxyType(index))

    @classmethod
    def of(
        cls,
        bodies: Iterable[WorldBody],
        allowed: Mapping[tuple[str, str] | frozenset[str], Exemption | str] | None = None,
        zones: Mapping[tuple[str, str] | frozenset[str], Exemption | str] | None = None,
    ) -> CollisionWorld:
        """A world of ``bodies`` with the ``allowed`` pairs (never checked) and the ``zones``
        (checked with a zone exempt), each keyed by a pair of body names (tuple or frozenset)
        with an :class:`Exemption` or a bare reason.

        Raises
        ------
        ValueError
            Two bodies of one name, an unknown kind, a pair naming an unknown body or one body
            twice, a reason not in :data:`REASONS`, or a pair both allowed and zoned.
        """
        return cls(tuple(bodies), allowed or {}, zones or {})  # type: ignore[arg-type]

    # ------------------------------------------------------------------ lookups
    @property
    def names(self) -> tuple[str, ...]:
        """The bodies' names, in order."""
        return tuple(b.name for b in self.bodies)

    def __contains__(self, name: object) -> bool:
        return name in self._index

    def body(self, name: str) -> WorldBody:
        """The body named ``name`` (ValueError naming the bodies there are when none is)."""
        if name not in self._index:
            raise ValueError(f"no body {name!r} in the collision world: {', '.join(self.names)}")
        return self.bodies[self._index[name]]

    def of_kind(self, *kinds: str) -> tuple[WorldBody, ...]:
        """The bodies of the given kinds, in order."""
        return tuple(b for b in self.bodies if b.kind in kinds)

    def allowed(self, a: str, b: str) -> str | None:
        """Why the pair of bodies ``a`` and ``b`` is never checked (a key of :data:`REASONS`),
        ``None`` when it is checked (ValueError for a name not in the world)."""
        self.body(a), self.body(b)
        e = self.allowed_pairs.get(pair_key(a, b))
        return None if e is None else e.reason

    def zone(self, a: str, b: str) -> str | None:
        """Why the pair ``a``, ``b`` is checked with a zone exempt (``"contact zone"``), ``None``
        when it is checked whole or never."""
        self.body(a), self.body(b)
        e = self.zones.get(pair_key(a, b))
        return None if e is None else e.reason

    def pairs_to_check(self, kinds: Iterable[str] | None = None) -> tuple[tuple[str, str], ...]:
        """The pairs not allowed (zoned ones included), among the bodies of ``kinds`` (default
        all): in body order (``i < j``), each pair with the body on the later robot frame first
        (a fixed body counts as before every frame: ``("link_2", "floor")``,
        ``("tool", "link_3")``)."""
        use = [b for b in self.bodies if kinds is None or b.kind in set(kinds)]
        out = []
        for i, bi in enumerate(use):
            for bj in use[i + 1 :]:
                if pair_key(bi.name, bj.name) in self.allowed_pairs:
                    continue
                fi, fj = _rank(bi), _rank(bj)
                out.append((bj.name, bi.name) if fj >= fi else (bi.name, bj.name))
        return tuple(out)

    # ------------------------------------------------------------------ a query
    def contacts(
        self, poses: Mapping[str, ArrayLike], kinds: Iterable[str] | None = None
    ) -> tuple[tuple[str, str], ...]:
        """The checked pairs (:meth:`pairs_to_check` of ``kinds``) that touch (python-fcl
        collide, nothing else: no broad phase, no gap) with the bodies placed at ``poses``
        (``{name: (4, 4) mm}``; a body not named keeps its object's transform), as trimesh's
        ``CollisionManager.in_collision_internal(return_names=True)``. A zoned pair is tested
        whole here."""
        import fcl

        for name, T in poses.items():
            M = np.asarray(T, dtype=np.float64)
            self.body(name).obj.setTransform(fcl.Transform(M[:3, :3], M[:3, 3]))
        out = []
        for a, b in self.pairs_to_check(kinds):
            req, res = fcl.CollisionRequest(), fcl.CollisionResult()
            if fcl.collide(self.body(a).obj, self.body(b).obj, req, res):
                out.append((a, b))
        return tuple(out)

    # ------------------------------------------------------------------ words
    def describe(self) -> str:
        """The bodies (name, kind, what they move with, geometry), the exempt pairs with their
        reasons, and how many pairs are checked: what an engineer reads to trust the checks."""
        lines = [f"collision world: {len(self.bodies)} bodies"]
        w = max((len(b.name) for b in self.bodies), default=4)
        m = max((len(b.moves_with()) for b in self.bodies), default=5)
        for b in self.bodies:
            lines.append(f"  {b.name:<{w}}  {b.kind:<6} {b.moves_with():<{m}}  {b.shape}".rstrip())
        n = len(self.bodies)
        lines.append(f"allowed pairs (never checked): {len(self.allowed_pairs)}")
        lines += [_pair_line(self, k, e) for k, e in self.allowed_pairs.items()]
        if self.zones:
            lines.append(f"zoned pairs (checked with a zone exempt): {len(self.zones)}")
            lines += [_pair_line(self, k, e) for k, e in self.zones.items()]
        lines.append(f"pairs checked: {len(self.pairs_to_check())} of {n * (n - 1) // 2}")
        return "\n".join(lines)


def _rank(b: WorldBody) -> int:
    return -1 if b.frame is None else b.frame


def _ordered(world: CollisionWorld, key: frozenset[str]) -> tuple[str, str]:
    """The pair ``key`` as ``(later body, earlier body)`` in :meth:`pairs_to_check`'s order."""
    a, b = sorted(key, key=world._index.__getitem__)
    return (b, a) if _rank(world.body(b)) >= _rank(world.body(a)) else (a, b)


def _pair_line(world: CollisionWorld, key: frozenset[str], e: Exemption) -> str:
    a, b = _ordered(world, key)
    return f"  {a}/{b}: {e.reason}" + (f" ({e.note})" if e.note else "")


def _exemptions(
    pairs: Mapping[tuple[str, str] | frozenset[str], Exemption | str], index: Mapping[str, int]
) -> dict[frozenset[str], Exemption]:
    """The pairs keyed by :func:`pair_key`, checked against the bodies and :data:`REASONS`."""
    out: dict[frozenset[str], Exemption] = {}
    for names, e in pairs.items():
        key = frozenset(names)
        e = Exemption(e) if isinstance(e, str) else e
        if len(key) != 2 or not key <= set(index):
            raise ValueError(f"exempt pair {sorted(names)}: not two bodies of the world")
        if e.reason not in REASONS:
            raise ValueError(f"exempt pair {sorted(names)}: reason {e.reason!r} not in REASONS")
        out[key] = e
    return out
