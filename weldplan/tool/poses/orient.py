"""Candidate tool orientations about an approach axis, and the least-rotation choice along a route.

A candidate is the nominal frame of a weld (TCP +z along the approach axis, x from the part's
own axes: :func:`nominal_frames`) turned by a spin ``psi`` about that axis and tilted by ``t``
about an axis perpendicular to it at azimuth ``phi``:
``R = R0 @ Rot(cos(phi) x + sin(phi) y, t) @ Rot(z, psi)``, with ``R0`` the nominal frame. The
local part (everything right of ``R0``) is the same for every weld, so it is built once and the
candidates of all welds come from one ``einsum``.
"""

from __future__ import annotations

import logging
from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

log = logging.getLogger(__name__)


def nominal_frames(axes: ArrayLike, frame: ArrayLike | None = None) -> NDArray[np.float64]:
    """``(n, 3, 3)``: a right-handed frame per unit axis ``(n, 3)``, its z column the axis.

    The x column is the part's own x axis (or its y, when the axis is within 0.9 of x) made
    perpendicular to the axis, so the frame is a fixed function of the axis and the part alone:
    a part turned in the cell gets its frames turned with it, and so the same candidates, the
    same poses and the same reach (../shared/DESIGN.md, "Frames": the part frame is where the
    welds are given).

    Parameters
    ----------
    axes
        ``(n, 3)`` approach axes in the planning frame (need not be unit).
    frame
        ``(3, 3)`` rotation: the part frame's axes (columns) in the planning frame, the
        rotation of the part's pose in the cell (:attr:`weldplan.cellframe.PartPose.matrix`);
        ``None``: the part frame is the planning frame. The frames are built in the part
        frame and turned back: ``frame @ nominal_frames(frame.T @ axes)``.
    """
    a = np.asarray(axes, dtype=np.float64).reshape(-1, 3)
    a = a / np.linalg.norm(a, axis=1, keepdims=True)
    R = None if frame is None else np.asarray(frame, dtype=np.float64).reshape(3, 3)
    if R is not None:
        a = a @ R  # each row R.T @ a: the axis in the part frame
    ref = np.where(np.abs(a[:, :1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    x = ref - np.sum(ref * a, axis=1, keepdims=True) * a
    x /= np.linalg.norm(x, axis=1, keepdims=True)
    y = np.cross(a, x)
    F = np.stack([x, y, a], axis=2)
    return F if R is None else np.einsum("ij,njk->nik", R, F)


def local_candidates(
    cone: float, tilt_step: float, spin_step: float, azimuths: int
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The candidate rotations relative to a nominal frame.

    Parameters
    ----------
    cone
        Largest tilt off the approach axis (deg); 0 samples the axis only.
    tilt_step
        Tilt spacing (deg): rings at ``tilt_step, 2 tilt_step, ... <= cone`` (the last ring at
        ``cone`` itself).
    spin_step
        Spin spacing about the axis (deg), over a full turn.
    azimuths
        Tilt directions sampled on each ring, evenly over a full turn.

    Returns
    -------
    local
        ``(c, 3, 3)`` rotations, the untilted ones first, in order of increasing tilt.
    params
        ``(c, 3)`` degrees: spin, tilt, azimuth of each candidate.
    """
    if spin_step <= 0 or tilt_step <= 0 or cone < 0 or azimuths < 1:
        raise ValueError("spin_step and tilt_step must be > 0, cone >= 0 and azimuths >= 1")
    spins = np.arange(0.0, 360.0 - 1e-9, spin_step)
    rings = int(np.ceil(cone / tilt_step - 1e-9)) if cone > 0 else 0
    tilts = np.linspace(0.0, cone, rings + 1)[1:] if rings else np.zeros(0)
    phis = np.arange(azimuths) * (360.0 / azimuths)
    tp = [(0.0, 0.0)] + [(t, p) for t in tilts for p in phis]
    params = np.array([(s, t, p) for t, p in tp for s in spins], dtype=np.float64)
    s, t, p = np.radians(params).T
    tilt_axis = np.stack([np.cos(p), np.sin(p), np.zeros_like(p)], axis=1)
    R_tilt = Rotation.from_rotvec(tilt_axis * t[:, None])
    R_spin = Rotation.from_rotvec(np.stack([np.zeros_like(s), np.zeros_like(s), s], axis=1))
    return (R_tilt * R_spin).as_matrix(), params


def candidate_rotations(
    axes: ArrayLike, local: ArrayLike, frame: ArrayLike | None = None
) -> NDArray[np.float64]:
    """``(n, c, 3, 3)``: every local candidate ``(c, 3, 3)`` applied to each axis ``(n, 3)``,
    its nominal frame built from the part's axes ``frame`` (:func:`nominal_frames`)."""
    F = nominal_frames(axes, frame)
    return np.einsum("nij,cjk->ncik", F, np.asarray(local, dtype=np.float64))


def rotation_angles(qa: ArrayLike, qb: ArrayLike) -> NDArray[np.float64]:
    """``(a, b)`` degrees: the rotation angle between unit quaternions ``(a, 4)`` and ``(b, 4)``
    (any component order, the same for both): ``2 arccos |qa . qb|``."""
    dot = np.abs(np.asarray(qa, dtype=np.float64) @ np.asarray(qb, dtype=np.float64).T)
    return np.degrees(2.0 * np.arccos(np.clip(dot, 0.0, 1.0)))


def least_rotation_choice(
    quats: list[NDArray[np.float64]],
    angles: Callable[[int], NDArray[np.float64]] | None = None,
) -> tuple[list[int], float]:
    """Pick one orientation per stage so that the summed rotation between stages is least.

    Dynamic programming over the stages (a shortest path through a layered graph whose edge
    weights are :func:`rotation_angles`): ``cost[k][j] = min_i cost[k-1][i] + angle(i, j)``,
    exact, ``O(sum c_k c_{k+1})`` with one vectorised ``(c_k, c_{k+1})`` step per stage. Ties go
    to the lower candidate index (the candidates come untilted first).

    Parameters
    ----------
    quats
        One ``(c_k, 4)`` array of unit quaternions per stage, ``c_k >= 1``, in route order.
    angles
        ``angles(k) -> (c_{k-1}, c_k)``: the :func:`rotation_angles` between stages ``k - 1``
        and ``k``, when the caller has them cached; default computed here.

    Returns
    -------
    choice
        The chosen index per stage.
    total
        Degrees: the summed rotation along the choice.
    """
    if not quats:
        return [], 0.0
    if any(len(q) == 0 for q in quats):
        raise ValueError("every stage needs at least one candidate")
    cost = np.zeros(len(quats[0]))
    back: list[NDArray[np.int64]] = []
    for k in range(1, len(quats)):
        ang = rotation_angles(quats[k - 1], quats[k]) if angles is None else angles(k)
        step = cost[:, None] + ang
        arg = np.argmin(step, axis=0)
        back.append(arg)
        cost = step[arg, np.arange(step.shape[1])]
    j = int(np.argmin(cost))
    total = float(cost[j])
    choice = [j]
    for arg in reversed(back):
        j = int(arg[j])
        choice.append(j)
    return choice[::-1], total
