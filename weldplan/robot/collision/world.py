"""The robot's collision world: its links, its tool, the part and the floor as named bodies
(:class:`~weldplan.geometry.world.CollisionWorld`), and the pairs of them never checked, with
the reason for each, as data (:func:`robot_world`); :class:`AllowedCollisions` is that data by
body index, as the self check (:class:`~weldplan.robot.collision.SelfCheck`) reads it.

Allowed pairs (the contact rules' computed once per robot + tool and cached). A pair of bodies
is not checked when it is

1. *joined in the chain*, read from the robot's URDF (:func:`chain_exemptions`): two links that a
   joint joins are ``"adjacent"`` (the note names the joint); the tool rides on the last link
   through the fixed mount, so it is ``"tool-flange"`` with that link and ``"adjacent"`` with
   the one before it (through the last joint), as MoveIt's setup assistant merges links joined
   by fixed joints;
2. *disabled by the robot's description*: a ``<disable_collisions link1 link2 reason>`` in the
   URDF or in an SRDF of the same name beside it (MoveIt's semantic description;
   :func:`disabled_exemptions`), ``"disabled"``;
3. *in contact at the zero pose* (every joint 0, clamped into its limits): closer than
   :data:`SELF_GAP_MM` there (MoveIt's "default" pairs, ``"zero pose"``);
4. *in contact at every one of* :data:`ACM_SAMPLES` *random configurations* (uniform inside the
   joint limits, seed :data:`ACM_SEED`; MoveIt's "always" pairs).

MoveIt's last rule ("never" in contact over the samples) is not used: a sample proves nothing
about the configurations it missed, and the tool folded into the upper arm is exactly such a
rare configuration. Every other pair is checked; on the shared KUKA with the gun (no SRDF) only
rule 1 applies (no other pair touches at the zero pose, none touches at every sample): 20 of its
28 pairs are checked.

The root link is allowed against the floor it stands on (``"on the floor"``). The tool against
the part is checked, with its contact zone exempt on the motions that end at a weld (the world's
``"contact zone"``; the part check, :mod:`weldplan.robot.collision.checker`).
"""

from __future__ import annotations

import hashlib
import logging
import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import fcl
import numpy as np
from numpy.typing import NDArray

from weldplan.errors import InputError
from weldplan.geometry.world import CollisionWorld, Exemption, WorldBody
from weldplan.robot.collision.nearpart import fcl_distance, fcl_tf
from weldplan.robot.model.urdf import parse_urdf

log = logging.getLogger(__name__)

#: mm: two bodies (or a body and the floor) closer than this count as colliding (as the part's)
SELF_GAP_MM = 1.0
#: random configurations of the allowed-collision-matrix's "always in contact" rule, and their seed
ACM_SAMPLES = 1000
ACM_SEED = 0
#: the floor's name in the world and in a hit
FLOOR = "floor"
#: the kinds of world body that are the robot's own (the self check's bodies)
ROBOT_KINDS = ("link", "tool")
#: the pairs the contact rules allow, already computed (key: the bodies' names, frames, meshes)
_CONTACT_CACHE: dict[str, dict[tuple[str, str], Exemption]] = {}


@dataclass(frozen=True)
class AllowedCollisions:
    """A view of the robot's bodies in a :class:`~weldplan.geometry.world.CollisionWorld`:
    which pairs of them are never checked and why, as indices into the checker's body list
    (the world holds the data; :meth:`of` reads it).

    Attributes
    ----------
    names
        The robot's bodies (links and tool), in the checker's order.
    reasons
        ``{(i, j): "adjacent" | "tool-flange" | "disabled" | "zero pose" | "always"}`` for the
        allowed pairs ``i < j``.
    checked
        The pairs ``(i, j)`` that are checked, ``i`` on the later (or same) link.
    """

    names: tuple[str, ...]
    reasons: dict[tuple[int, int], str]
    checked: tuple[tuple[int, int], ...]

    @classmethod
    def of(cls, world: CollisionWorld) -> AllowedCollisions:
        """The view of ``world``'s link and tool bodies."""
        names = tuple(b.name for b in world.of_kind(*ROBOT_KINDS))
        at = {n: k for k, n in enumerate(names)}
        reasons = {
            (i, j): str(world.allowed(names[i], names[j]))
            for i in range(len(names))
            for j in range(i + 1, len(names))
            if world.allowed(names[i], names[j]) is not None
        }
        checked = tuple((at[a], at[b]) for a, b in world.pairs_to_check(ROBOT_KINDS))
        return cls(names, reasons, checked)

    def allowed(self, a: str, b: str) -> str | None:
        """Why the pair of bodies named ``a`` and ``b`` is not checked (``None``: it is)."""
        i, j = sorted((self.names.index(a), self.names.index(b)))
        return self.reasons.get((i, j))

    def describe(self) -> list[str]:
        """One line per allowed pair: ``"link_5/tool: adjacent"``."""
        return [f"{self.names[i]}/{self.names[j]}: {w}" for (i, j), w in self.reasons.items()]


@dataclass(frozen=True, eq=False)
class FloorBox:
    """The floor as a body: a box of side ``side`` mm (python-fcl ``obj``) whose top face the
    checks place on the floor plane under the robot (:meth:`SelfCheck._below`)."""

    side: float
    obj: fcl.CollisionObject


def floor_box(reach: float) -> FloorBox:
    """A floor box wider and deeper than anything within ``reach`` mm of the robot's base: there
    it is the half-space below the floor (FCL's Halfspace crashed python-fcl's distance)."""
    side = 2.0 * (reach + 1000.0)
    return FloorBox(side, fcl.CollisionObject(fcl.Box(side, side, side), fcl.Transform()))


def pair_distance(bodies: list[Any], i: int, j: int, F: NDArray[np.float64]) -> float:
    """mm: FCL distance of bodies ``i`` and ``j`` at link frames ``F (7, 4, 4)``; 0 on contact."""
    a, b = bodies[i], bodies[j]
    b.obj.setTransform(fcl_tf(F[b.frame]))
    return fcl_distance(a.obj, F[a.frame], b.obj)


def _key(bodies: list[Any], robot: Any, samples: int, seed: int, gap: float) -> str:
    h = hashlib.sha1()
    h.update(repr((samples, seed, gap, robot.lower.tolist(), robot.upper.tolist())).encode())
    h.update(np.ascontiguousarray(robot.origins).tobytes())
    for b in bodies:
        h.update(f"{b.name}:{b.frame}".encode())
        h.update(np.ascontiguousarray(b.vertices).tobytes())
        h.update(np.ascontiguousarray(b.faces).tobytes())
    return h.hexdigest()


def _link_name(robot: Any, frame: int) -> str:
    names = getattr(robot, "link_names", ())
    return names[frame] if frame < len(names) else f"frame {frame}"


def chain_exemptions(robot: Any, bodies: list[Any]) -> dict[tuple[str, str], Exemption]:
    """The pairs the robot's kinematic chain exempts (module docstring, rule 1), from its URDF
    data: two bodies on the link frames that a joint joins are ``"adjacent"`` (the note names
    the joint, :attr:`Robot.joint_names <weldplan.robot.model.Robot.joint_names>`); a tool on
    the same frame as a link is mounted on it, ``"tool-flange"``."""
    out: dict[tuple[str, str], Exemption] = {}
    for i, a in enumerate(bodies):
        for b in bodies[i + 1 :]:
            lo, hi = sorted((a.frame, b.frame))
            if hi - lo == 1:
                joint = robot.joint_names[lo]
                note = f"joint {joint}: {_link_name(robot, lo)} -> {_link_name(robot, hi)}"
                out[(a.name, b.name)] = Exemption("adjacent", note)
            elif hi == lo:
                tool = "tool" in (a.name, b.name)
                reason = "tool-flange" if tool else "adjacent"
                out[(a.name, b.name)] = Exemption(reason, f"both on {_link_name(robot, lo)}")
    return out


def _element_lines(text: str, tag: str) -> list[int]:
    """The 1-based line of each ``<tag`` in ``text``, in order, comments left out (ElementTree
    keeps no line numbers)."""
    bare = re.sub(r"<!--.*?-->", lambda m: "\n" * m.group().count("\n"), text, flags=re.S)
    return [bare.count("\n", 0, m.start()) + 1 for m in re.finditer(rf"<{tag}\b", bare)]


def disabled_exemptions(robot: Any, bodies: list[Any]) -> dict[tuple[str, str], Exemption]:
    """The pairs the robot's description disables (module docstring, rule 2): every
    ``<disable_collisions link1="a" link2="b" reason="..."/>`` of its URDF (``robot.source``)
    and of an SRDF of the same name beside it (MoveIt's semantic description,
    ``kr150r3100_2.srdf``), between two links that carry a body.

    Raises
    ------
    InputError
        An unreadable SRDF, or an element whose ``link1`` or ``link2`` is not a link of the URDF
        (file, line and attribute named).
    """
    urdf = Path(robot.source) if getattr(robot, "source", "") else None
    if urdf is None or not urdf.is_file():
        return {}
    root, text, _ = parse_urdf(urdf)
    known = {lk.get("name") for lk in root.findall("link")}
    docs = [(urdf, root, text)]
    srdf = urdf.with_suffix(".srdf")
    if srdf.is_file():
        try:
            stext = srdf.read_text(encoding="utf-8")
            docs.append((srdf, ET.fromstring(stext), stext))
        except (OSError, UnicodeDecodeError, ET.ParseError) as exc:
            raise InputError(f"cannot read the SRDF: {exc}", path=srdf) from None
    have = {b.name for b in bodies if b.name != "tool"}
    out: dict[tuple[str, str], Exemption] = {}
    for path, doc, txt in docs:
        lines = _element_lines(txt, "disable_collisions")
        for el, line in zip(doc.iter("disable_collisions"), lines, strict=False):
            a, b = el.get("link1"), el.get("link2")
            for fld, v in (("link1", a), ("link2", b)):
                if v not in known:
                    msg = f"<disable_collisions> names {v!r}, not a link of {urdf.name}"
                    raise InputError(msg, path=path, line=line, field=fld)
            if a in have and b in have and a != b:
                why = el.get("reason", "")
                note = f"{path.name} line {line}" + (f": {why}" if why else "")
                out[(str(a), str(b))] = Exemption("disabled", note)
    return out


def _contact_exemptions(
    robot: Any, bodies: list[Any], skip: set[frozenset[str]], samples: int, seed: int, gap: float
) -> dict[tuple[str, str], Exemption]:
    """The pairs not in ``skip`` in contact at the zero pose, or at every one of ``samples``
    random configurations (module docstring, rules 3 and 4). Cached per robot chain + limits +
    meshes."""
    key = _key(bodies, robot, samples, seed, gap) + repr(sorted(sorted(p) for p in skip))
    if key in _CONTACT_CACHE:
        return _CONTACT_CACHE[key]
    n = len(bodies)
    out: dict[tuple[str, str], Exemption] = {}
    rest = []
    at = robot.with_base(np.eye(4))
    F0 = at.link_frames(np.clip(np.zeros(6), robot.lower, robot.upper))[0]
    for i in range(n):
        for j in range(i + 1, n):
            if frozenset((bodies[i].name, bodies[j].name)) in skip:
                continue
            if pair_distance(bodies, i, j, F0) <= gap:
                out[(bodies[i].name, bodies[j].name)] = Exemption("zero pose", f"within {gap:g} mm")
            else:
                rest.append((i, j))
    Q = np.random.default_rng(seed).uniform(robot.lower, robot.upper, (samples, 6))
    F = at.link_frames(Q)
    for i, j in rest:
        # "always": stops at the first sample where the pair is apart (bounding spheres first)
        for k in range(samples):
            ci = F[k, bodies[i].frame, :3, :3] @ bodies[i].centre + F[k, bodies[i].frame, :3, 3]
            cj = F[k, bodies[j].frame, :3, :3] @ bodies[j].centre + F[k, bodies[j].frame, :3, 3]
            far = np.linalg.norm(ci - cj) > bodies[i].radius + bodies[j].radius + gap
            if far or pair_distance(bodies, i, j, F[k]) > gap:
                break
        else:
            note = f"{samples} samples, seed {seed}"
            out[(bodies[i].name, bodies[j].name)] = Exemption("always", note)
    _CONTACT_CACHE[key] = out
    return out


@dataclass(frozen=True)
class WorldSettings:
    """What :func:`robot_world` adds to the robot's bodies.

    Attributes
    ----------
    part
        The part's body (kind ``"part"``), or ``None``.
    floor
        The floor box (:func:`floor_box`), ``None`` when no floor is known.
    floor_z
        mm: the floor height in the part frame (with ``floor``).
    contact_radius
        mm: the tool's contact zone against the part (``None``: none).
    """

    part: WorldBody | None = None
    floor: FloorBox | None = None
    floor_z: float | None = None
    contact_radius: float | None = None


def robot_world(
    robot: Any,
    bodies: list[Any],
    settings: WorldSettings,
) -> CollisionWorld:
    """The collision world of ``robot``'s ``bodies`` (``name``, ``frame``, ``obj``, ``centre``,
    ``radius``, ``vertices``, ``faces``: :class:`~weldplan.robot.collision.Body`; the tool is
    the one named ``"tool"``), the part and the floor of ``settings``, with the allowed pairs
    of the module docstring: the chain's (:func:`chain_exemptions`), the description's
    (:func:`disabled_exemptions`), the contact rules' (zero pose, always; cached), the root link
    on the floor; and the tool's contact zone against the part."""
    allowed: dict[tuple[str, str], Exemption] = chain_exemptions(robot, bodies)
    skip = {frozenset(k) for k in allowed}
    for pair, e in disabled_exemptions(robot, bodies).items():
        if frozenset(pair) not in skip:
            allowed[pair] = e
            skip.add(frozenset(pair))
    allowed.update(_contact_exemptions(robot, bodies, skip, ACM_SAMPLES, ACM_SEED, SELF_GAP_MM))
    world_bodies = [
        WorldBody(
            b.name,
            "tool" if b.name == "tool" else "link",
            b.obj,
            b.frame,
            _link_name(robot, b.frame),
            f"BVH, {len(b.faces)} triangles",
            b,
        )
        for b in bodies
    ]
    zones: dict[tuple[str, str], Exemption] = {}
    if settings.part is not None:
        world_bodies.append(settings.part)
        if settings.contact_radius is not None and any(b.name == "tool" for b in bodies):
            note = f"a sphere of {settings.contact_radius:g} mm about the TCP, on motions to a weld"
            zones[("tool", settings.part.name)] = Exemption("contact zone", note)
    if settings.floor is not None:
        fb = settings.floor
        shape = f"box {fb.side:.0f} mm, top face at z = {settings.floor_z:g} mm"
        world_bodies.append(WorldBody(FLOOR, "floor", fb.obj, None, "", shape, fb))
        for b in bodies:
            if b.frame == 0:
                allowed[(b.name, FLOOR)] = Exemption("on the floor", "the root link")
    world = CollisionWorld.of(world_bodies, allowed, zones)
    if log.isEnabledFor(logging.DEBUG):
        log.debug("%s", world.describe())
    return world


def allowed_collisions(robot: Any, bodies: list[Any]) -> AllowedCollisions:
    """The allowed collision matrix of ``bodies`` on ``robot`` alone (no part, no floor): the
    view (:class:`AllowedCollisions`) of their :func:`robot_world`."""
    return AllowedCollisions.of(robot_world(robot, bodies, WorldSettings()))
