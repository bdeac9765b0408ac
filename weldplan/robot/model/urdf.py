"""Reading a serial robot from a URDF: the chain of revolute joints, their limits, link meshes.

Lengths in a URDF are metres (the format fixes it); everything returned here is in mm and
radians. A joint's pose is ``origin @ rotation(axis, q)`` (URDF semantics); a link's collision
mesh is placed by its ``<collision><origin>`` in the link frame.

Errors name the file, the line of the element and the field (``joint 'joint_a2' limit
velocity``): a user bringing their own robot sees what to fix.
"""

from __future__ import annotations

import logging
import math
import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from os import PathLike
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from weldplan.errors import InputError

log = logging.getLogger(__name__)

#: millimetres per URDF length unit (metres)
URDF_MM = 1000.0


@dataclass(frozen=True)
class UrdfJoint:
    """One ``<joint>`` of a URDF.

    Attributes
    ----------
    name, kind, parent, child
        The joint's name, ``type`` and its parent and child links.
    origin
        ``(4, 4)`` mm: the child frame at ``q = 0`` in the parent link frame.
    axis
        ``(3,)`` unit vector in the joint frame.
    line
        1-based line of the ``<joint`` element in the file (for error messages).
    """

    name: str
    kind: str
    parent: str
    child: str
    origin: NDArray[np.float64]
    axis: NDArray[np.float64]
    line: int | None


@dataclass(frozen=True)
class UrdfLink:
    """A link and its collision (else visual) mesh file, if any.

    Attributes
    ----------
    name
        The link's name.
    mesh
        The mesh file, resolved beside the URDF, or ``None`` for a link without geometry.
    origin
        ``(4, 4)`` mm: the mesh frame in the link frame.
    scale
        ``(3,)`` the mesh's ``scale`` attribute times :data:`URDF_MM` (mesh units are metres).
    """

    name: str
    mesh: Path | None
    origin: NDArray[np.float64]
    scale: NDArray[np.float64]


def frame(xyz: ArrayLike, rpy: ArrayLike, scale: float = 1.0) -> NDArray[np.float64]:
    """``(4, 4)``: translation ``xyz * scale`` and fixed-axis roll-pitch-yaw (rad, URDF)."""
    T = np.eye(4)
    T[:3, :3] = Rotation.from_euler("xyz", np.asarray(rpy, dtype=np.float64)).as_matrix()
    T[:3, 3] = np.asarray(xyz, dtype=np.float64) * scale
    return T


def element_line(text: str, tag: str, name: str) -> int | None:
    """1-based line of ``<tag ... name="name"`` in ``text`` (ElementTree keeps no line numbers)."""
    m = re.search(rf"<{tag}\b[^>]*\bname\s*=\s*[\"']{re.escape(name)}[\"']", text)
    return None if m is None else text.count("\n", 0, m.start()) + 1


def _floats(text: str | None, n: int, path: Path, line: int | None, fld: str) -> NDArray:
    if text is None:
        return np.zeros(n)
    try:
        vals = np.array([float(t) for t in text.split()])
    except ValueError:
        raise InputError(f"not {n} numbers: {text!r}", path=path, line=line, field=fld) from None
    if vals.shape != (n,) or not np.all(np.isfinite(vals)):
        raise InputError(f"need {n} finite numbers, got {text!r}", path=path, line=line, field=fld)
    return vals


def parse_urdf(path: str | PathLike[str]) -> tuple[ET.Element, str, list[UrdfJoint]]:
    """The root element, the file's text and every ``<joint>`` (mm), in file order."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
        root = ET.fromstring(text)
    except (OSError, UnicodeDecodeError, ET.ParseError) as exc:
        raise InputError(f"cannot read the URDF: {exc}", path=path) from None
    if root.tag != "robot":
        raise InputError(f"root element is <{root.tag}>, not <robot>", path=path, line=1)
    joints = []
    for j in root.findall("joint"):
        name = j.get("name", "")
        line = element_line(text, "joint", name)
        parent, child = j.find("parent"), j.find("child")
        if parent is None or child is None or not parent.get("link") or not child.get("link"):
            raise InputError(
                "joint without parent or child link", path=path, line=line, field=f"joint '{name}'"
            )
        org = j.find("origin")
        xyz = _floats(None if org is None else org.get("xyz"), 3, path, line, f"joint '{name}' xyz")
        rpy = _floats(None if org is None else org.get("rpy"), 3, path, line, f"joint '{name}' rpy")
        ax = j.find("axis")
        axis = _floats(
            "1 0 0" if ax is None else ax.get("xyz"), 3, path, line, f"joint '{name}' axis"
        )
        kind = j.get("type", "")
        if kind in ("revolute", "continuous", "prismatic"):
            nrm = float(np.linalg.norm(axis))
            if not nrm > 0:
                raise InputError("zero axis", path=path, line=line, field=f"joint '{name}' axis")
            axis = axis / nrm
        joints.append(
            UrdfJoint(
                name=name,
                kind=kind,
                parent=str(parent.get("link")),
                child=str(child.get("link")),
                origin=frame(xyz, rpy, URDF_MM),
                axis=axis,
                line=line,
            )
        )
    return root, text, joints


def chain(joints: list[UrdfJoint], tip: str, path: Path) -> list[UrdfJoint]:
    """The joints from the root link (a link no joint has as child) down to link ``tip``."""
    by_child = {j.child: j for j in joints}
    out: list[UrdfJoint] = []
    link = tip
    while link in by_child:
        j = by_child[link]
        if j in out:
            raise InputError("the joints form a loop", path=path, field=f"link '{link}'")
        out.append(j)
        link = j.parent
    return out[::-1]


def chain_transform(path: str | PathLike[str], tip: str) -> NDArray[np.float64]:
    """``(4, 4)`` mm: the pose of link (or fixed joint) ``tip`` in the URDF's root link frame,
    through fixed joints only; a tool's mounting frame -> TCP transform, for example.

    Raises
    ------
    InputError
        No such link or joint, or a movable joint on the way.
    """
    path = Path(path)
    _, _, joints = parse_urdf(path)
    names = {j.name: j.child for j in joints}
    link = names.get(tip, tip)
    if link not in {j.child for j in joints}:
        raise InputError(f"no link or joint named {tip!r}", path=path, field="tcp")
    T = np.eye(4)
    for j in chain(joints, link, path):
        if j.kind != "fixed":
            raise InputError(
                f"joint {j.name!r} between the root and {tip!r} is {j.kind}, not fixed",
                path=path,
                line=j.line,
                field=f"joint '{j.name}' type",
            )
        T = T @ j.origin
    return T


def joint_limits(
    root: ET.Element, text: str, joint: UrdfJoint, path: Path
) -> tuple[float, float, float]:
    """``(lower, upper, velocity)`` (rad, rad, rad/s) of a revolute joint's ``<limit>``.

    Raises
    ------
    InputError
        A missing ``<limit>`` or attribute, a non-finite value, ``lower >= upper`` or a
        velocity that is not positive, naming the joint and the attribute.
    """
    el = root.find(f"joint[@name='{joint.name}']/limit")
    where = f"joint '{joint.name}' limit"
    if el is None:
        raise InputError(
            "no <limit> element: a robot joint needs lower, upper and velocity limits",
            path=path,
            line=joint.line,
            field=where,
        )
    line = joint.line
    m = re.search(r"<limit\b", text[_offset(text, line) :]) if line else None
    if m is not None:
        line = line + text[_offset(text, joint.line) :][: m.start()].count("\n")
    vals = []
    for attr in ("lower", "upper", "velocity"):
        raw = el.get(attr)
        if raw is None:
            raise InputError(
                f"missing {attr!r} in <limit>", path=path, line=line, field=f"{where} {attr}"
            )
        try:
            v = float(raw)
        except ValueError:
            v = math.nan
        if not math.isfinite(v):
            raise InputError(
                f"{attr} must be a finite number, got {raw!r}",
                path=path,
                line=line,
                field=f"{where} {attr}",
            )
        vals.append(v)
    lo, hi, vel = vals
    if not lo < hi:
        raise InputError(
            f"lower {lo} is not below upper {hi}", path=path, line=line, field=f"{where} lower"
        )
    if not vel > 0:
        raise InputError(
            f"velocity must be positive, got {vel}", path=path, line=line, field=f"{where} velocity"
        )
    return lo, hi, vel


def _offset(text: str, line: int | None) -> int:
    """Character offset of the start of 1-based ``line`` in ``text``."""
    if not line:
        return 0
    pos = 0
    for _ in range(line - 1):
        pos = text.index("\n", pos) + 1
    return pos


def link_geometry(root: ET.Element, name: str, path: Path) -> UrdfLink:
    """The link's collision mesh (else its visual mesh), resolved beside the URDF."""
    el = root.find(f"link[@name='{name}']")
    for kind in ("collision", "visual"):
        node = None if el is None else el.find(kind)
        m = None if node is None else node.find("geometry/mesh")
        if node is None or m is None:
            continue
        fname = (m.get("filename") or "").replace("file://", "")
        if fname.startswith("package://"):
            fname = fname.split("/", 3)[-1]  # package://pkg/rest -> rest, beside the URDF
        mesh = (path.parent / fname).resolve()
        fld = f"link '{name}' {kind} mesh filename"
        if not mesh.is_file():
            raise InputError(f"mesh {fname!r} not found beside the URDF", path=path, field=fld)
        org = node.find("origin")
        T = frame(
            _floats(None if org is None else org.get("xyz"), 3, path, None, f"link '{name}' xyz"),
            _floats(None if org is None else org.get("rpy"), 3, path, None, f"link '{name}' rpy"),
            URDF_MM,
        )
        s = _floats(m.get("scale", "1 1 1"), 3, path, None, f"link '{name}' mesh scale")
        return UrdfLink(name=name, mesh=mesh, origin=T, scale=s * URDF_MM)
    return UrdfLink(name=name, mesh=None, origin=np.eye(4), scale=np.full(3, URDF_MM))
