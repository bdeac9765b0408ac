"""A 6-axis robot arm: URDF chain (limits, velocities, link meshes) plus OPW parameters for IK.

::

    from weldplan.robot import load_robot
    robot = load_robot("../shared/data/robots/kuka_kr150r3100_2/kr150r3100_2.urdf")
    T = robot.fk(q)              # (n, 4, 4) flange poses, part frame, mm (URDF chain)
    sol = robot.ik(T[0])         # IKSolutions: q (k, 6) rad, branch (k,) in 0..7

Frames (all mm, rad).

- The *part frame* is the frame of the weld cell; ``Robot.base`` is the pose of the URDF's root
  link (``base_link``) in it.
- The *flange frame* is the chain's tip: the URDF link ``tool0`` when there is one (the
  ROS-Industrial convention: the controller's flange frame, KUKA ``$FLANGE``, ABB ``tool0``:
  origin on the flange face, z out of it), else the last joint's child. :meth:`Robot.fk` and
  :meth:`Robot.ik` speak of this frame; a tool's TCP is ``flange @ T_flange_tcp``.
- A tool is mounted at the *mount frame*, the URDF link ``flange`` when there is one (the
  ROS-Industrial attachment point of end effectors, x out of the flange face) else the flange
  frame; ``Robot.mount`` is its pose in the flange frame, so a tool whose URDF root is its
  mounting frame has ``T_flange_tcp = robot.mount @ T_root_tcp`` (:meth:`Robot.tool_transform`).

FK runs the URDF chain (numpy, vectorised over configurations), not the OPW formulas, so it is an
independent check of the IK. :func:`load_robot` makes that check on a fixed set of configurations
and refuses OPW parameters that disagree with the URDF (a wrong offset, sign or length).
"""

from __future__ import annotations

import dataclasses
import logging
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from os import PathLike
from pathlib import Path
from typing import Any

import numpy as np
import trimesh
from numpy.typing import ArrayLike, NDArray

from weldplan.errors import InputError
from weldplan.robot.model.ik import (
    IKBranches,
    IKSolutions,
    OPWParams,
    branch_bits,
    load_opw,
    solve,
)
from weldplan.robot.model.urdf import UrdfJoint, chain, joint_limits, link_geometry, parse_urdf

log = logging.getLogger(__name__)

#: default joint acceleration limits when none are given: each joint reaches its URDF velocity
#: limit in this many seconds (URDFs carry no acceleration limits; an assumption, not vendor data)
DEFAULT_RAMP_S = 0.5
#: the OPW parameters must reproduce the URDF chain's flange pose within these, or the robot is
#: refused (mm; rad)
OPW_CHECK_MM = 1e-6
OPW_CHECK_RAD = 1e-8
#: configurations of the OPW-vs-URDF check at load time (seeded, inside the joint limits)
OPW_CHECK_SAMPLES = 64


@dataclass(frozen=True, eq=False)
class RobotLink:
    """A link's collision mesh in its link frame.

    Attributes
    ----------
    name
        The URDF link name.
    index
        Which frame of :meth:`Robot.link_frames` carries it (0 = base link, ``i`` = after joint i).
    vertices
        ``(n, 3) float`` mm, link frame.
    faces
        ``(m, 3) int``.
    """

    name: str
    index: int
    vertices: NDArray[np.float64]
    faces: NDArray[np.int64]


@dataclass(frozen=True, eq=False)
class Robot:
    """A 6-axis arm with a spherical wrist (module docstring for the frames).

    Attributes
    ----------
    name
        The URDF robot name.
    joint_names
        The six movable joints, base to wrist, as the URDF names them.
    lower, upper
        ``(6,)`` rad joint limits.
    velocity
        ``(6,)`` rad/s velocity limits (URDF).
    acceleration
        ``(6,)`` rad/s^2 acceleration limits (given, else ``velocity / DEFAULT_RAMP_S``).
    base
        ``(4, 4)`` mm: the root link in the part frame.
    origins
        ``(6, 4, 4)`` mm: each joint's origin in its parent link (URDF ``<origin>``).
    axes
        ``(6, 3)`` unit joint axes in the joint frames.
    tip
        ``(4, 4)`` mm: the flange frame in the last joint's child link.
    mount
        ``(4, 4)`` mm: the tool mounting frame in the flange frame.
    opw
        The OPW parameters the IK uses.
    source
        The URDF file.
    link_names
        The seven links carried by :meth:`link_frames` (root link, then each joint's child).
    """

    name: str
    joint_names: tuple[str, ...]
    lower: NDArray[np.float64]
    upper: NDArray[np.float64]
    velocity: NDArray[np.float64]
    acceleration: NDArray[np.float64]
    base: NDArray[np.float64]
    origins: NDArray[np.float64]
    axes: NDArray[np.float64]
    tip: NDArray[np.float64]
    mount: NDArray[np.float64]
    opw: OPWParams
    source: str = ""
    link_names: tuple[str, ...] = ()
    _geometry: tuple[Any, ...] = field(default=(), repr=False)
    _cache: dict[str, Any] = field(default_factory=dict, repr=False)

    def __post_init__(self) -> None:
        for name in (
            "lower",
            "upper",
            "velocity",
            "acceleration",
            "base",
            "origins",
            "axes",
            "tip",
            "mount",
        ):
            a = np.array(getattr(self, name), dtype=np.float64)
            a.setflags(write=False)
            object.__setattr__(self, name, a)

    # ------------------------------------------------------------------ placement
    def with_base(self, base: ArrayLike) -> Robot:
        """The same robot with its root link at ``base`` ``(4, 4)`` mm in the part frame (the
        IK solver and the link meshes are shared)."""
        B = _check_base(base)
        return dataclasses.replace(self, base=B, _cache=self._cache)

    # ------------------------------------------------------------------ kinematics
    def link_frames(self, q: ArrayLike) -> NDArray[np.float64]:
        """``(n, 7, 4, 4)`` mm: the root link and each joint's child link in the part frame.

        Parameters
        ----------
        q
            ``(n, 6)`` or ``(6,)`` rad.
        """
        Q = _as_q(q)
        n = len(Q)
        out = np.empty((n, 7, 4, 4))
        T = np.broadcast_to(self.base, (n, 4, 4)).copy()
        out[:, 0] = T
        # the six joints' frames in one pass (the collision checks ask one configuration at a
        # time, thousands of times: the per-joint calls cost more than the arithmetic); the
        # same operations element by element as :meth:`_joint_frames`, so the same bits
        A, B, C = self._rodrigues_all()
        QT = np.ascontiguousarray(Q.T)
        s = np.sin(QT)[:, :, None, None]
        c = np.cos(QT)[:, :, None, None]
        J = A[:, None] + s * B[:, None] + (1 - c) * C[:, None]  # (6, n, 4, 4)
        for j in range(6):
            T = T @ J[j]
            out[:, j + 1] = T
        return out

    def _rodrigues_all(self) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray]:
        """``(6, 4, 4)`` each: :meth:`_joint_frames`' cached terms ``A, B, C`` of the six joints."""
        key = ("rodrigues", "all")
        if key not in self._cache:
            for j in range(6):
                self._joint_frames(j, np.zeros(1))
            terms = [self._cache[("rodrigues", j)] for j in range(6)]
            self._cache[key] = tuple(np.stack([t[i] for t in terms]) for i in range(3))
        return self._cache[key]  # type: ignore[no-any-return]

    def _joint_frames(self, j: int, angles: NDArray[np.float64]) -> NDArray[np.float64]:
        """``(n, 4, 4)``: ``origin_j @ rotation(axis_j, angle)`` (Rodrigues, terms cached)."""
        key = ("rodrigues", j)
        if key not in self._cache:
            a = self.axes[j]
            K = np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])
            O = self.origins[j]
            # origin @ [[I + s K + (1 - c) K^2, 0], [0, 1]] = A + s B + (1 - c) C
            A = O.copy()
            B = np.zeros((4, 4))
            C = np.zeros((4, 4))
            B[:3, :3] = O[:3, :3] @ K
            C[:3, :3] = O[:3, :3] @ K @ K
            self._cache[key] = (A, B, C)
        A, B, C = self._cache[key]
        s = np.sin(angles)[:, None, None]
        c = np.cos(angles)[:, None, None]
        return A + s * B + (1 - c) * C

    def fk(self, q: ArrayLike) -> NDArray[np.float64]:
        """``(n, 4, 4)`` mm: the flange pose in the part frame from the URDF chain.

        Parameters
        ----------
        q
            ``(n, 6)`` or ``(6,)`` rad.
        """
        return self.link_frames(q)[:, 6] @ self.tip

    def jacobian(self, q: ArrayLike) -> NDArray[np.float64]:
        """``(n, 6, 6)``: the geometric Jacobian of the flange origin in the part frame, rows
        ``(vx, vy, vz)`` in mm/rad then ``(wx, wy, wz)`` in rad/rad, from the URDF chain."""
        F = self.link_frames(q)
        Q = _as_q(q)
        p_end = (F[:, 6] @ self.tip)[:, :3, 3]
        J = np.empty((len(Q), 6, 6))
        for j in range(6):
            Tj = F[:, j] @ self.origins[j]  # the joint frame (its rotation does not move the axis)
            z = Tj[:, :3, :3] @ self.axes[j]
            J[:, :3, j] = np.cross(z, p_end - Tj[:, :3, 3])
            J[:, 3:, j] = z
        return J

    def manipulability(self, q: ArrayLike, length: float | None = None) -> NDArray[np.float64]:
        """``(n,)``: the smallest singular value of the Jacobian with its translation rows divided
        by ``length`` mm (default: ``c2 + c3``, the arm's length), so both halves are in rad/rad
        and the measure is unitless; zero at a singularity."""
        L = float(length) if length is not None else self.opw.c2 + self.opw.c3
        J = self.jacobian(q)
        J[:, :3] /= L
        return np.linalg.svd(J, compute_uv=False)[:, -1]

    def _solver(self) -> Any:
        if "solver" not in self._cache:
            self._cache["solver"] = self.opw.solver()
        return self._cache["solver"]

    def ik_all(self, T_flange: ArrayLike) -> IKBranches:
        """All eight branches of flange poses ``(n, 4, 4)`` or ``(4, 4)`` mm in the part frame
        (:class:`~weldplan.robot.model.IKBranches`)."""
        T = np.asarray(T_flange, dtype=np.float64).reshape(-1, 4, 4)
        Tb = np.linalg.solve(self.base, T) if len(T) else T
        return solve(self.opw, self._solver(), Tb, self.lower, self.upper)

    def ik(self, T_flange: ArrayLike) -> IKSolutions:
        """The solutions of one flange pose ``(4, 4)`` mm (part frame) inside the joint limits,
        one per existing branch, labelled as :mod:`weldplan.robot.model.ik` documents."""
        T = np.asarray(T_flange, dtype=np.float64)
        if T.shape != (4, 4):
            raise InputError(f"a flange pose is a (4, 4) matrix, got shape {T.shape}", field="pose")
        return self.ik_all(T).solutions(0)

    def branch_of(self, q: ArrayLike) -> NDArray[np.int64]:
        """``(n,) int``: the branch label of configurations ``(n, 6)`` rad (the IK slot of their
        own FK pose that reproduces them, modulo full turns)."""
        Q = _as_q(q)
        br = self.ik_all(self.fk(Q))
        d = np.angle(np.exp(1j * (br.q - Q[:, None, :])))  # wrapped differences
        err = np.where(br.exists, np.abs(d).max(axis=2), np.inf)
        return np.argmin(err, axis=1).astype(np.int64)

    def branch_bits(self, q: ArrayLike) -> NDArray[np.int64]:
        """``(n,) int``: :meth:`branch_of` from the joint angles alone
        (:func:`weldplan.robot.model.branch_bits`: no FK or IK, for the planner's inner loops)."""
        return branch_bits(self.opw, _as_q(q))

    def tool_transform(self, T_root_tcp: ArrayLike) -> NDArray[np.float64]:
        """``(4, 4)`` mm: flange -> TCP of a tool whose URDF root is its mounting frame, given the
        tool's root -> TCP ``(4, 4)`` mm (:func:`weldplan.robot.model.chain_transform`)."""
        return self.mount @ np.asarray(T_root_tcp, dtype=np.float64).reshape(4, 4)

    def in_limits(self, q: ArrayLike, tol: float = 0.0) -> NDArray[np.bool_]:
        """``(n,) bool``: every joint within its limits (widened by ``tol`` rad)."""
        Q = _as_q(q)
        return np.all((Q >= self.lower - tol) & (Q <= self.upper + tol), axis=1)

    # ------------------------------------------------------------------ geometry
    @property
    def links(self) -> tuple[RobotLink, ...]:
        """The collision mesh of every link that has one (mm, link frame), loaded once."""
        if "links" not in self._cache:
            out = []
            for i, g in enumerate(self._geometry):
                if g.mesh is None:
                    continue
                try:
                    tm = trimesh.load(g.mesh, force="mesh", process=False)
                except Exception as exc:  # trimesh raises many types for unreadable files
                    raise InputError(f"cannot read the link mesh: {exc}", path=g.mesh) from None
                if not isinstance(tm, trimesh.Trimesh) or len(tm.faces) == 0:
                    raise InputError("the link mesh has no triangles", path=g.mesh)
                v = np.asarray(tm.vertices, dtype=np.float64) * g.scale
                v = v @ g.origin[:3, :3].T + g.origin[:3, 3]
                out.append(RobotLink(g.name, i, v, np.asarray(tm.faces, dtype=np.int64)))
            self._cache["links"] = tuple(out)
        return self._cache["links"]


def _as_q(q: ArrayLike) -> NDArray[np.float64]:
    Q = np.asarray(q, dtype=np.float64)
    if Q.ndim == 1:
        Q = Q[None]
    if Q.ndim != 2 or Q.shape[1] != 6:
        raise InputError(f"joint vectors must be (n, 6), got shape {Q.shape}", field="q")
    return Q


def _check_base(base: ArrayLike | None) -> NDArray[np.float64]:
    if base is None:
        return np.eye(4)
    B = np.asarray(base, dtype=np.float64)
    if B.shape != (4, 4) or not np.all(np.isfinite(B)):
        raise InputError("the robot base must be a finite (4, 4) matrix", field="base")
    R = B[:3, :3]
    if not (
        np.allclose(R @ R.T, np.eye(3), atol=1e-9)
        and np.linalg.det(R) > 0
        and np.allclose(B[3], [0, 0, 0, 1])
    ):
        raise InputError("the robot base is not a rigid transform", field="base")
    return B


def load_robot(
    urdf: str | PathLike[str],
    opw: str | PathLike[str] | Mapping[str, Any] | OPWParams | None = None,
    *,
    base: ArrayLike | None = None,
    acceleration: float | ArrayLike | None = None,
    tip: str | None = None,
) -> Robot:
    """Read a 6-axis robot: URDF chain and limits, OPW parameters, checked against each other.

    Parameters
    ----------
    urdf
        The robot's URDF (metres): a chain of six revolute joints with ``<limit lower upper
        velocity>``; link collision meshes resolved beside it.
    opw
        OPW parameters: a yaml file (ROS-Industrial layout, :func:`~weldplan.robot.model.load_opw`),
        a mapping of the same keys, or :class:`~weldplan.robot.model.OPWParams`; default
        ``opw_parameters.yaml`` beside the URDF.
    base
        ``(4, 4)`` mm: the root link's pose in the part frame (default identity).
    acceleration
        rad/s^2, one value or six (default ``velocity / DEFAULT_RAMP_S``).
    tip
        The flange link (default ``tool0`` when the URDF has it, else the last joint's child).

    Raises
    ------
    InputError
        An unreadable URDF or yaml; not six revolute joints between the root and the tip; a
        missing or bad ``<limit>`` (the message names the joint, the attribute and the line);
        OPW parameters whose FK differs from the URDF chain's.
    """
    path = Path(urdf)
    root, text, joints = parse_urdf(path)
    tip = _tip_link(joints, tip, path)
    moving, origins, tip_T = _arm_chain(joints, tip, path)
    limits = np.array([joint_limits(root, text, j, path) for j in moving])
    lower, upper, velocity = limits.T
    acc = _acceleration(acceleration, velocity)
    mount = _flange_mount(joints, tip, path)
    params = _opw_params(opw, path)
    link_root = moving[0].parent
    geometry = [link_geometry(root, link_root, path)] + [
        link_geometry(root, j.child, path) for j in moving
    ]
    robot = Robot(
        name=root.get("name", path.stem),
        joint_names=tuple(j.name for j in moving),
        lower=lower,
        upper=upper,
        velocity=velocity,
        acceleration=acc,
        base=_check_base(base),
        origins=origins,
        axes=np.array([j.axis for j in moving]),
        tip=tip_T,
        mount=mount,
        opw=params,
        source=str(path),
        link_names=tuple(g.name for g in geometry),
        _geometry=tuple(geometry),
    )
    _check_opw(robot, path)
    log.debug("robot %s: joints %s, OPW from %s", robot.name, robot.joint_names, params.source)
    return robot


def _tip_link(joints: list[UrdfJoint], tip: str | None, path: Path) -> str:
    """The flange link: ``tip`` when given, else ``tool0`` when the URDF has it, else the last
    movable joint's child (else the last leaf); InputError when no joint has it as child."""
    children = {j.child for j in joints}
    parents = {j.parent for j in joints}
    if tip is None:
        tip = "tool0" if "tool0" in children else None
        if tip is None:
            leaves = [j.child for j in joints if j.child not in parents]
            movable = [j for j in joints if j.kind != "fixed"]
            tip = movable[-1].child if movable else (leaves[-1] if leaves else "")
    if tip not in children:
        raise InputError(f"no link named {tip!r}", path=path, field="tip")
    return tip


def _arm_chain(
    joints: list[UrdfJoint], tip: str, path: Path
) -> tuple[list[UrdfJoint], NDArray[np.float64], NDArray[np.float64]]:
    """The six revolute joints from the root to ``tip``, with fixed joints folded away.

    Returns
    -------
    moving, origins, tip
        The six joints; ``(6, 4, 4)`` mm each one's origin with the fixed joints before it
        folded in; ``(4, 4)`` mm the fixed joints after the sixth (the flange in its child).
        InputError unless exactly six movable joints, all revolute, lie on the chain.
    """
    ch = chain(joints, tip, path)
    while ch and ch[0].kind == "fixed":  # the base is the first movable joint's parent link
        ch = ch[1:]
    moving = [j for j in ch if j.kind != "fixed"]
    if len(moving) != 6 or any(j.kind != "revolute" for j in moving):
        kinds = ", ".join(f"{j.name} ({j.kind})" for j in moving) or "none"
        raise InputError(
            f"need six revolute joints between the root and {tip!r}, found: {kinds}",
            path=path,
            field="joint",
        )
    # fold fixed joints into the next movable joint's origin (or the tip)
    origins, pending = [], np.eye(4)
    for j in ch:
        if j.kind == "fixed":
            pending = pending @ j.origin
        else:
            origins.append(pending @ j.origin)
            pending = np.eye(4)
    return moving, np.array(origins), pending


def _flange_mount(joints: list[UrdfJoint], tip: str, path: Path) -> NDArray[np.float64]:
    """``(4, 4)`` mm: the ROS-Industrial ``flange`` link in the ``tip`` frame when the URDF has
    one other than the tip (both reached through fixed joints), else the identity."""
    mount = np.eye(4)
    if "flange" in {j.child for j in joints} and "flange" != tip:
        T_tip = _fixed_pose(joints, tip, path)
        T_fl = _fixed_pose(joints, "flange", path)
        if T_tip is not None and T_fl is not None:
            mount = np.linalg.solve(T_tip, T_fl)
    return mount


def _opw_params(
    opw: str | PathLike[str] | Mapping[str, Any] | OPWParams | None, path: Path
) -> OPWParams:
    """The OPW parameters given, or ``opw_parameters.yaml`` beside the URDF ``path``."""
    if opw is None:
        opw = path.parent / "opw_parameters.yaml"
        if not Path(opw).is_file():
            raise InputError(
                f"no OPW parameters: {opw} not found beside the URDF (give them with --opw)",
                path=path,
                field="opw",
            )
    return opw if isinstance(opw, OPWParams) else load_opw(opw)


def _fixed_pose(joints: list[UrdfJoint], link: str, path: Path) -> NDArray | None:
    """The pose of ``link`` in the last movable joint's child frame, through fixed joints only
    (``None`` when the link is not below the last movable joint by fixed joints)."""
    T = np.eye(4)
    for j in reversed(chain(joints, link, path)):
        if j.kind != "fixed":
            return T
        T = j.origin @ T
    return None


def _acceleration(acceleration: float | ArrayLike | None, velocity: NDArray) -> NDArray:
    if acceleration is None:
        return velocity / DEFAULT_RAMP_S
    try:
        a = np.broadcast_to(np.asarray(acceleration, dtype=np.float64), (6,)).copy()
    except (TypeError, ValueError):
        raise InputError(
            f"acceleration limits must be one value or six (rad/s^2), got {acceleration!r}",
            field="acceleration",
        ) from None
    if not np.all(np.isfinite(a) & (a > 0)):
        raise InputError(
            f"acceleration limits must be positive and finite, got {a.tolist()}",
            field="acceleration",
        )
    return a


def _check_opw(robot: Robot, path: Path) -> None:
    """Refuse OPW parameters whose FK is not the URDF chain's (module docstring)."""
    rng = np.random.default_rng(0)
    lo = np.maximum(robot.lower, -math.pi)
    hi = np.minimum(robot.upper, math.pi)
    q = lo + (hi - lo) * rng.random((OPW_CHECK_SAMPLES, 6))
    T_urdf = np.linalg.solve(robot.base, robot.fk(q))
    T_opw = np.asarray(robot._solver().batch_forward(q).as_matrix()).reshape(-1, 4, 4)
    dp = np.linalg.norm(T_urdf[:, :3, 3] - T_opw[:, :3, 3], axis=1)
    dR = np.abs(T_urdf[:, :3, :3] - T_opw[:, :3, :3]).max(axis=(1, 2))
    i = int(np.argmax(dp / OPW_CHECK_MM + dR / OPW_CHECK_RAD))
    if dp[i] > OPW_CHECK_MM or dR[i] > OPW_CHECK_RAD:
        raise InputError(
            f"the OPW parameters ({robot.opw.source}) do not reproduce the URDF chain: at "
            f"q = {np.round(q[i], 4).tolist()} rad the flange differs by {dp[i]:.4g} mm and "
            f"{dR[i]:.3g} in rotation (check offsets, sign corrections and lengths)",
            path=path,
            field="opw",
        )
