"""Analytic inverse kinematics of an ortho-parallel 6-axis arm (OPW), through py-opw-kinematics.

The OPW parameters (Brandstötter, Angerer, Hofbaur, "An analytical solution of the inverse
kinematics problem of industrial serial manipulators with an ortho-parallel basis and a spherical
wrist", Austrian Robotics Workshop 2014: ``a1, a2, b, c1, c2, c3, c4``, per-joint offsets and
sign corrections) are read from the ROS-Industrial ``opw_parameters.yaml`` layout and solved by
the Rust solver of ``py-opw-kinematics`` (``Robot.reach``: all eight branches per pose in stable
slots).

Branch labels. A solution's branch is the solver's slot ``4 * wrist + 2 * shoulder + elbow``
(bits :data:`ELBOW`, :data:`SHOULDER`, :data:`WRIST`), decided on the raw OPW angles (before
offsets and sign corrections):

- ``SHOULDER`` set: the arm reaches back, the wrist centre lies behind the A1 axis (KUKA
  Status bit 0, "overhead area"; ABB cfx's "backward" half).
- ``ELBOW`` set: raw ``theta3 = -acos(..) - psi3``, the elbow's second root; for the KUKA
  KR 150 R3100-2 (sign +1, offset 0 on A3) that is ``A3 < atan2(-a2, c3)``.
- ``WRIST`` set: raw ``theta5 <= 0``; for the KUKA (sign +1 on A5) ``A5 <= 0`` (Status bit 2).

The solver returns angles in ``(-pi, pi]``. Joints whose range spans more than a turn (KUKA A4
and A6, +-350 deg) have several equivalents: :func:`solve` returns, per branch, the equivalent
inside the limits nearest zero (the principal value when it is inside); the route planner picks
other turns itself.
"""

from __future__ import annotations

import logging
import math
import re
from collections.abc import Mapping
from dataclasses import dataclass
from os import PathLike
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from weldplan.errors import InputError

log = logging.getLogger(__name__)

#: branch bits (module docstring)
ELBOW = 1
SHOULDER = 2
WRIST = 4
#: number of OPW branches
N_BRANCHES = 8
#: mm per unit of the OPW yaml's lengths (metres, as ROS-Industrial writes them)
OPW_YAML_MM = 1000.0
#: rad: how far inside pi a joint value must be for :func:`wrap_into_limits` to keep its turn
#: without trying the others (far above the round-off of ``q -+ 2 pi``)
WRAP_SLACK = 1e-6
#: the geometric parameters an OPW description needs
OPW_KEYS = ("a1", "a2", "b", "c1", "c2", "c3", "c4")


@dataclass(frozen=True)
class OPWParams:
    """OPW kinematic parameters, mm and rad.

    Attributes
    ----------
    a1, a2, b, c1, c2, c3, c4
        Lengths (mm) as in Brandstötter et al. 2014, figure 1.
    offsets
        ``(6,)`` rad added to the raw OPW angles.
    signs
        ``(6,)`` +-1 sign corrections (ROS-Industrial ``opw_kinematics_joint_sign_corrections``).
    source
        The file the parameters came from, or ``"given"``.
    """

    a1: float
    a2: float
    b: float
    c1: float
    c2: float
    c3: float
    c4: float
    offsets: tuple[float, ...]
    signs: tuple[int, ...]
    source: str = "given"

    def solver(self) -> Any:
        """A ``py_opw_kinematics.Robot`` in mm and radians."""
        from py_opw_kinematics import KinematicModel
        from py_opw_kinematics import Robot as OPWRobot

        km = KinematicModel(
            a1=self.a1,
            a2=self.a2,
            b=self.b,
            c1=self.c1,
            c2=self.c2,
            c3=self.c3,
            c4=self.c4,
            offsets=tuple(float(o) for o in self.offsets),
            flip_axes=tuple(s < 0 for s in self.signs),
        )
        return OPWRobot(km, degrees=False)


_EXPR = re.compile(r"^\s*(deg|rad)\s*\(\s*([-+0-9.eE]+)\s*\)\s*$")


def _angle(v: Any, path: Any, fld: str) -> float:
    """A yaml angle: a number (rad) or ``deg(x)`` / ``rad(x)`` (the rosparam expressions)."""
    if isinstance(v, (int, float)) and not isinstance(v, bool):
        out = float(v)
    else:
        m = _EXPR.match(str(v))
        if m is None:
            raise InputError(
                f"not an angle: {v!r} (a number, deg(x) or rad(x))", path=path, field=fld
            )
        out = math.radians(float(m.group(2))) if m.group(1) == "deg" else float(m.group(2))
    if not math.isfinite(out):
        raise InputError(f"not a finite angle: {v!r}", path=path, field=fld)
    return out


def load_opw(
    opw: str | PathLike[str] | Mapping[str, Any], *, scale: float = OPW_YAML_MM
) -> OPWParams:
    """OPW parameters from a ROS-Industrial ``opw_parameters.yaml`` or a mapping of the same keys.

    Parameters
    ----------
    opw
        A yaml file, or a mapping with ``opw_kinematics_geometric_parameters`` (``a1 ... c4``),
        ``opw_kinematics_joint_offsets`` and ``opw_kinematics_joint_sign_corrections`` (both
        optional: zeros and ones).
    scale
        mm per length unit of the parameters (default: metres).

    Raises
    ------
    InputError
        An unreadable file, a missing or non-finite parameter, offsets or signs that are not six
        values (signs +-1), naming the field.
    """
    import yaml

    path: Any = None
    if isinstance(opw, Mapping):
        data: Any = dict(opw)
    else:
        path = Path(opw)
        try:
            data = yaml.safe_load(path.read_text(encoding="utf-8"))
        except (OSError, UnicodeDecodeError, yaml.YAMLError) as exc:
            raise InputError(f"cannot read the OPW parameters: {exc}", path=path) from None
    if not isinstance(data, Mapping):
        raise InputError("not a mapping of OPW parameters", path=path)
    geo = data.get("opw_kinematics_geometric_parameters")
    if not isinstance(geo, Mapping):
        raise InputError("missing mapping", path=path, field="opw_kinematics_geometric_parameters")
    vals = {}
    for k in OPW_KEYS:
        fld = f"opw_kinematics_geometric_parameters.{k}"
        if k not in geo:
            raise InputError("missing parameter", path=path, field=fld)
        try:
            v = float(geo[k])
        except (TypeError, ValueError):
            v = math.nan
        if not math.isfinite(v):
            raise InputError(f"not a finite number: {geo[k]!r}", path=path, field=fld)
        vals[k] = v * scale
    offs = data.get("opw_kinematics_joint_offsets", [0] * 6)
    signs = data.get("opw_kinematics_joint_sign_corrections", [1] * 6)
    if not isinstance(offs, list) or len(offs) != 6:
        raise InputError("need six offsets", path=path, field="opw_kinematics_joint_offsets")
    if not isinstance(signs, list) or len(signs) != 6 or any(s not in (1, -1) for s in signs):
        raise InputError(
            f"need six signs, each 1 or -1, got {signs!r}",
            path=path,
            field="opw_kinematics_joint_sign_corrections",
        )
    offsets = tuple(
        _angle(o, path, f"opw_kinematics_joint_offsets[{i}]") for i, o in enumerate(offs)
    )
    return OPWParams(
        **vals,
        offsets=offsets,
        signs=tuple(int(s) for s in signs),
        source="given" if path is None else str(path),
    )


def branch_bits(params: OPWParams, q: ArrayLike) -> NDArray[np.int64]:
    """``(n,) int``: the branch label of configurations ``q (n, 6)`` rad, from the joint angles
    alone (no FK, no IK): the module docstring's bits on the raw OPW angles
    ``raw = sign * q - offset`` (opw_kinematics' convention, ``q = (raw + offset) * sign``).

    - ``WRIST``: ``raw5 <= 0``;
    - ``ELBOW``: ``raw3 < -psi3``, ``psi3 = atan2(a2, c3)`` (the second root of
      Brandstötter et al.'s eq. for theta3, ``-acos(..) - psi3``);
    - ``SHOULDER``: the wrist centre behind the A1 axis, ``a1 + c2 sin(raw2) +
      k sin(raw2 + raw3 + psi3) < 0`` with ``k = sqrt(a2^2 + c3^2)`` (the paper's ``c_x1``, the
      wrist centre's reach along the arm plane).

    Equal to :meth:`weldplan.robot.model.Robot.branch_of` (IK of the FK pose) away from the
    branch boundaries (tested on random configurations), about a hundred times cheaper: the
    joint-space planner asks it of every state it samples."""
    Q = np.asarray(q, dtype=np.float64).reshape(-1, 6)
    raw = Q * np.asarray(params.signs, dtype=np.float64) - np.asarray(params.offsets)
    raw = np.angle(np.exp(1j * raw))
    psi3 = math.atan2(params.a2, params.c3)
    k = math.hypot(params.a2, params.c3)
    wrist = raw[:, 4] <= 0
    elbow = np.angle(np.exp(1j * (raw[:, 2] + psi3))) < 0
    reach = params.a1 + params.c2 * np.sin(raw[:, 1]) + k * np.sin(raw[:, 1] + raw[:, 2] + psi3)
    return (WRIST * wrist + SHOULDER * (reach < 0) + ELBOW * elbow).astype(np.int64)


@dataclass(frozen=True, eq=False)
class IKSolutions:
    """The IK solutions of one flange pose, one per existing branch inside the joint limits.

    Attributes
    ----------
    q
        ``(k, 6)`` rad, ``k <= 8``.
    branch
        ``(k,) int`` in ``0..7``: the branch label of each row (module docstring).
    """

    q: NDArray[np.float64]
    branch: NDArray[np.int64]

    def __len__(self) -> int:
        return len(self.branch)


@dataclass(frozen=True, eq=False)
class IKBranches:
    """All eight branches of ``n`` flange poses, in the solver's stable slots.

    Attributes
    ----------
    q
        ``(n, 8, 6)`` rad: per branch the equivalent inside the limits nearest zero (module
        docstring); NaN rows where the branch does not exist.
    exists
        ``(n, 8) bool``: the branch exists (the wrist centre is within reach for it).
    in_limits
        ``(n, 8) bool``: it exists and every joint is within its limits.
    margin
        ``(n, 8)`` rad: the smallest distance to a joint limit (negative outside, NaN where the
        branch does not exist).
    wrist
        ``(n, 8)``: ``|sin(theta5)|`` of the raw OPW angle, zero at the wrist singularity (NaN
        where the branch does not exist).
    extension
        ``(n,)`` mm: signed distance of the wrist centre inside the reachable annulus (negative:
        out of reach for every branch).
    """

    q: NDArray[np.float64]
    exists: NDArray[np.bool_]
    in_limits: NDArray[np.bool_]
    margin: NDArray[np.float64]
    wrist: NDArray[np.float64]
    extension: NDArray[np.float64]

    def solutions(self, i: int) -> IKSolutions:
        """The usable solutions of pose ``i`` (existing, inside the limits)."""
        b = np.flatnonzero(self.in_limits[i])
        return IKSolutions(q=self.q[i, b].copy(), branch=b.astype(np.int64))


def wrap_into_limits(
    q: NDArray[np.float64], lower: NDArray[np.float64], upper: NDArray[np.float64]
) -> NDArray[np.float64]:
    """``q (..., 6)`` with each joint moved by a multiple of 2 pi (-1, 0 or +1 turn) into
    ``[lower, upper]`` where one fits, the smallest ``|q|`` first; unchanged where none does.

    A value inside the limits with ``|q| < pi - WRAP_SLACK`` keeps its own turn (another is
    farther from zero), so only the other values go through the three turns: the same results
    as trying them on every value, at a fraction of the cost on the base search's 10^6 angles.
    """
    q = np.broadcast_to(q, np.broadcast_shapes(q.shape, np.shape(lower)))
    own = q + 0.0  # the k = 0 candidate as the three-turn loop forms it (-0.0 becomes 0.0)
    rest = ~((own >= lower) & (own <= upper) & (np.abs(q) < np.pi - WRAP_SLACK))
    if not rest.any():
        return own
    lo = np.broadcast_to(lower, q.shape)[rest]
    hi = np.broadcast_to(upper, q.shape)[rest]
    x = q[rest]
    sub = x.copy()
    best = np.full(x.shape, np.inf)
    for k in (0.0, -1.0, 1.0):
        cand = x + 2 * np.pi * k
        ok = (cand >= lo) & (cand <= hi) & (np.abs(cand) < best)
        sub = np.where(ok, cand, sub)
        best = np.where(ok, np.abs(cand), best)
    own[rest] = sub
    return own


def solve(
    params: OPWParams,
    solver: Any,
    T_base_flange: ArrayLike,
    lower: NDArray[np.float64],
    upper: NDArray[np.float64],
) -> IKBranches:
    """All branches of flange poses ``(n, 4, 4)`` mm given in the robot's base frame."""
    from py_opw_kinematics import RigidTransform

    T = np.asarray(T_base_flange, dtype=np.float64).reshape(-1, 4, 4)
    if len(T) == 0:
        z = np.zeros((0, N_BRANCHES))
        return IKBranches(np.zeros((0, N_BRANCHES, 6)), z > 0, z > 0, z, z, np.zeros(0))
    if not np.all(np.isfinite(T)):
        raise InputError("a flange pose is not finite", field="pose")
    res = solver.reach(RigidTransform.from_matrix(T), joint_limits=None)
    q = np.asarray(res.joints, dtype=np.float64)
    exists = np.all(np.isfinite(q), axis=2)
    q = np.where(exists[..., None], wrap_into_limits(np.nan_to_num(q), lower, upper), np.nan)
    margin = np.minimum(q - lower, upper - q).min(axis=2)
    in_limits = exists & (margin >= 0)
    return IKBranches(
        q=q,
        exists=exists,
        in_limits=in_limits,
        margin=margin,
        wrist=np.where(exists, np.asarray(res.wrist, dtype=np.float64), np.nan),
        extension=np.asarray(res.extension, dtype=np.float64),
    )
