"""The robot model: URDF chain FK, OPW IK through py-opw-kinematics, their agreement, bad input."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from tests.conftest import require_shared
from weldplan.errors import InputError
from weldplan.robot import ELBOW, SHOULDER, WRIST, load_opw, load_robot

KUKA = ("robots", "kuka_kr150r3100_2")


@pytest.fixture(scope="module")
def kuka_dir() -> Path:
    return require_shared(*KUKA)


@pytest.fixture(scope="module")
def robot(kuka_dir):
    return load_robot(kuka_dir / "kr150r3100_2.urdf")


def _random_q(robot, n, seed):
    rng = np.random.default_rng(seed)
    lo = np.maximum(robot.lower, -math.pi)
    hi = np.minimum(robot.upper, math.pi)
    return lo + (hi - lo) * rng.random((n, 6))


def _pose_error(A, B):
    """mm and degrees between two stacks of (4, 4) poses."""
    dp = np.linalg.norm(A[..., :3, 3] - B[..., :3, 3], axis=-1)
    R = np.swapaxes(A[..., :3, :3], -1, -2) @ B[..., :3, :3]
    da = np.degrees(Rotation.from_matrix(R.reshape(-1, 3, 3)).magnitude()).reshape(dp.shape)
    return dp, da


def test_urdf_limits_and_names(robot):
    assert robot.name == "kuka_kr150r3100_2"
    assert robot.joint_names == tuple(f"joint_a{i}" for i in range(1, 7))
    np.testing.assert_allclose(
        robot.lower,
        [-3.228859116, -2.443460953, -2.094395102, -6.108652382, -2.181661565, -6.108652382],
    )
    np.testing.assert_allclose(robot.upper[1], -0.087266463)
    np.testing.assert_allclose(robot.velocity[5], 4.537856055)
    np.testing.assert_allclose(robot.acceleration, robot.velocity / 0.5)
    assert robot.link_names == ("base_link",) + tuple(f"link_{i}" for i in range(1, 7))


def test_fk_at_zero_is_the_urdf_sum_of_offsets(robot):
    # every joint at zero: the origins add up along x and z; tool0 = link_6 turned +90 deg about y
    T = robot.fk(np.zeros(6))[0]
    np.testing.assert_allclose(T[:3, 3], [330 + 1350 + 1420 + 215, 0, 645 + 115], atol=1e-9)
    np.testing.assert_allclose(T[:3, 2], [1, 0, 0], atol=1e-9)  # flange z out along base x
    np.testing.assert_allclose(T[:3, 0], [0, 0, -1], atol=1e-9)
    # A1 turns the arm about -z (axis 0 0 -1): +90 deg takes it to -y
    T1 = robot.fk([math.pi / 2, 0, 0, 0, 0, 0])[0]
    np.testing.assert_allclose(T1[:3, 3], [0, -3315, 760], atol=1e-9)


def test_ik_round_trip_all_branches(robot):
    q = _random_q(robot, 200, seed=1)
    T = robot.fk(q)
    found_original = 0
    n_solutions = 0
    for i in range(len(q)):
        sol = robot.ik(T[i])
        assert len(sol) >= 1  # the configuration itself is a solution inside the limits
        dp, da = _pose_error(robot.fk(sol.q), np.broadcast_to(T[i], (len(sol), 4, 4)))
        assert dp.max() < 1e-6 and da.max() < 1e-6
        assert len(set(sol.branch.tolist())) == len(sol)
        assert robot.in_limits(sol.q).all()
        # distinct configurations, also modulo full turns
        w = np.angle(np.exp(1j * (sol.q[:, None] - sol.q[None])))
        off = ~np.eye(len(sol), dtype=bool)
        assert (np.abs(w).max(axis=2)[off] > 1e-6).all()
        d = np.abs(np.angle(np.exp(1j * (sol.q - q[i])))).max(axis=1)
        found_original += int(d.min() < 1e-7)
        n_solutions += len(sol)
    assert found_original == len(q)
    assert n_solutions > 2 * len(q)  # several branches per pose, not only the one we started from


def test_ik_from_a_moved_base(robot):
    B = np.eye(4)
    B[:3, :3] = Rotation.from_euler("z", 37, degrees=True).as_matrix()
    B[:3, 3] = [1200.0, -800.0, 150.0]
    moved = robot.with_base(B)
    q = _random_q(robot, 20, seed=2)
    np.testing.assert_allclose(moved.fk(q), B @ robot.fk(q), atol=1e-9)
    T = moved.fk(q)
    for i in range(len(q)):
        sol = moved.ik(T[i])
        dp, da = _pose_error(moved.fk(sol.q), np.broadcast_to(T[i], (len(sol), 4, 4)))
        assert dp.max() < 1e-6 and da.max() < 1e-6


def test_branch_bits_have_their_documented_meaning(robot):
    q = _random_q(robot, 300, seed=3)
    br = robot.branch_of(q)
    frames = robot.link_frames(q)
    wc = frames[:, 5, :3, 3]  # link_5's origin is the wrist centre (A4, A5, A6 meet)
    a1 = robot.fk(np.c_[q[:, :1], np.zeros((len(q), 5))])[:, :3, 3]  # arm direction of A1
    front = np.einsum("ij,ij->i", wc[:, :2], a1[:, :2]) > 0
    assert np.array_equal((br & SHOULDER) > 0, ~front)
    assert np.array_equal((br & WRIST) > 0, q[:, 4] <= 0)
    straight = math.atan2(115.0, 1420.0)  # A3 at which the forearm's wrist line is straight
    assert np.array_equal((br & ELBOW) > 0, q[:, 2] < straight)
    # ik labels what branch_of labels
    sol = robot.ik(robot.fk(q[0])[0])
    np.testing.assert_array_equal(robot.branch_of(sol.q), sol.branch)


def test_branch_bits_from_joints_equal_the_ik_label(robot):
    # over the whole joint range (A4 and A6 turn +-350 deg): the cheap label is the IK's own
    rng = np.random.default_rng(11)
    q = rng.uniform(robot.lower, robot.upper, (2000, 6))
    np.testing.assert_array_equal(robot.branch_bits(q), robot.branch_of(q))


@pytest.mark.parametrize("signs", [(1, 1, 1, 1, 1, 1), (-1, 1, -1, -1, -1, -1)])
def test_branch_bits_label_each_solver_slot_under_signs_and_offsets(signs):
    # the solver's own slots for arbitrary poses, with sign corrections and offsets on the
    # joints that decide the bits (A2, A3, A5): the raw angles are recovered the solver's way
    from py_opw_kinematics import RigidTransform

    from weldplan.robot.model import OPWParams, branch_bits

    p = OPWParams(330.0, -115.0, 0.0, 645.0, 1350.0, 1420.0, 215.0,
                  offsets=(0.1, -1.2, 0.4, 0.0, 0.3, 0.0), signs=signs)  # fmt: skip
    solver = p.solver()
    rng = np.random.default_rng(5)
    poses = []
    for _ in range(40):
        T = np.eye(4)
        T[:3, :3] = Rotation.random(random_state=rng).as_matrix()
        T[:3, 3] = rng.uniform([-1500, -1500, 0], [1500, 1500, 2000])
        poses.append(T)
    res = solver.reach(RigidTransform.from_matrix(np.array(poses)), joint_limits=None)
    q = np.asarray(res.joints, dtype=np.float64)  # (40, 8, 6), NaN where a slot does not exist
    ok = np.all(np.isfinite(q), axis=2)
    assert ok.sum() > 100
    slots = np.broadcast_to(np.arange(8), ok.shape)[ok]
    np.testing.assert_array_equal(branch_bits(p, q[ok]), slots)


def test_jacobian_matches_finite_differences(robot):
    q = _random_q(robot, 5, seed=4)
    J = robot.jacobian(q)
    h = 1e-6
    for j in range(6):
        dq = np.zeros(6)
        dq[j] = h
        Tp, Tm = robot.fk(q + dq), robot.fk(q - dq)
        v = (Tp[:, :3, 3] - Tm[:, :3, 3]) / (2 * h)
        dR = (Tp[:, :3, :3] - Tm[:, :3, :3]) / (2 * h) @ np.swapaxes(robot.fk(q)[:, :3, :3], 1, 2)
        w = np.stack([dR[:, 2, 1], dR[:, 0, 2], dR[:, 1, 0]], axis=1)
        np.testing.assert_allclose(J[:, :3, j], v, atol=1e-3)
        np.testing.assert_allclose(J[:, 3:, j], w, atol=1e-6)
    qs = q.copy()
    qs[:, 4] = 0.0  # A5 = 0: A4 and A6 aligned, the wrist singularity
    assert robot.manipulability(qs).max() < 1e-9
    assert robot.manipulability(q).min() > 1e-3


def _copy_urdf(kuka_dir, tmp_path, edit):
    text = (kuka_dir / "kr150r3100_2.urdf").read_text()
    text = text.replace('filename="collision/', f'filename="{kuka_dir}/collision/')
    p = tmp_path / "robot.urdf"
    p.write_text(edit(text))
    return p


def test_missing_limit_names_the_joint_field_and_line(kuka_dir, tmp_path):
    p = _copy_urdf(kuka_dir, tmp_path, lambda t: t.replace(' velocity="1.8675023"', ""))
    with pytest.raises(InputError) as ei:
        load_robot(p, kuka_dir / "opw_parameters.yaml")
    err = ei.value
    assert err.field == "joint 'joint_a2' limit velocity"
    lines = p.read_text().splitlines()
    assert err.line is not None and "<limit" in lines[err.line - 1]
    assert 'lower="-2.443460953"' in lines[err.line - 1]
    assert str(p) in str(err) and "\n" not in str(err)

    p2 = _copy_urdf(
        kuka_dir,
        tmp_path,
        lambda t: t.replace(
            '<limit effort="0" lower="-2.094395102" upper="2.932153143" velocity="1.989675347"/>',
            "",
        ),
    )
    with pytest.raises(InputError, match="no <limit>") as ei:
        load_robot(p2, kuka_dir / "opw_parameters.yaml")
    assert ei.value.field == "joint 'joint_a3' limit"


def test_no_opw_beside_the_urdf(kuka_dir, tmp_path):
    p = _copy_urdf(kuka_dir, tmp_path, lambda t: t)
    with pytest.raises(InputError) as ei:
        load_robot(p)
    assert ei.value.field == "opw"


def test_opw_that_disagrees_with_the_urdf_is_refused(kuka_dir, tmp_path):
    good = (kuka_dir / "opw_parameters.yaml").read_text()
    for bad in (
        good.replace("[-1, 1, 1, -1, 1, -1]", "[1, 1, 1, -1, 1, -1]"),  # A1 sign
        good.replace("deg(-90.0)", "deg(90.0)"),  # A2 offset
        good.replace("c3:  1.42", "c3:  1.43"),  # a length
    ):
        assert bad != good
        y = tmp_path / "opw.yaml"
        y.write_text(bad)
        with pytest.raises(InputError, match="do not reproduce the URDF chain") as ei:
            load_robot(kuka_dir / "kr150r3100_2.urdf", y)
        assert ei.value.field == "opw"


def test_opw_yaml_fields(kuka_dir, tmp_path):
    p = load_opw(kuka_dir / "opw_parameters.yaml")
    assert (p.a1, p.a2, p.c3) == (330.0, -115.0, 1420.0)
    assert p.offsets[1] == pytest.approx(-math.pi / 2)
    assert p.signs == (-1, 1, 1, -1, 1, -1)
    y = tmp_path / "opw.yaml"
    y.write_text("opw_kinematics_geometric_parameters: {a1: 0.33, a2: 0.1}\n")
    with pytest.raises(InputError) as ei:
        load_opw(y)
    assert ei.value.field == "opw_kinematics_geometric_parameters.b"
    with pytest.raises(InputError) as ei:
        load_opw(
            {
                "opw_kinematics_geometric_parameters": dict.fromkeys(
                    "a1 a2 b c1 c2 c3 c4".split(), 1.0
                ),
                "opw_kinematics_joint_sign_corrections": [1, 1, 2, 1, 1, 1],
            }
        )
    assert ei.value.field == "opw_kinematics_joint_sign_corrections"


def test_unreachable_pose_has_no_solution(robot):
    T = np.eye(4)
    T[:3, 3] = [5000.0, 0.0, 700.0]  # beyond the 3.1 m reach
    assert len(robot.ik(T)) == 0
    br = robot.ik_all(T)
    assert br.extension[0] < 0 and not br.exists.any()


def test_link_meshes_load_in_mm(robot):
    links = robot.links
    assert [lk.name for lk in links] == list(robot.link_names)
    # link_2 (upper arm) spans the 1350 mm between A2 and A3 and more
    ext = np.ptp(links[2].vertices, axis=0).max()
    assert 1350 < ext < 2000


def test_shared_gun_flange_tcp(robot):
    """The gun's root mounts on the URDF 'flange' link (x out of the face); tool0 is that link
    turned +90 deg about y, so the gun's TCP (root xyz 0.67936, 0, 0.00043 m, rpy 0, pi/2, 0)
    lies 679.36 mm out along tool0's z with tool0's own axes."""
    from weldplan.robot.route import tool_flange_tcp

    gun = require_shared("tools", "spot_welding_gun")
    F = tool_flange_tcp(robot, gun / "spot_welding_gun.urdf", "nozzle_tip")
    np.testing.assert_allclose(F[:3, 3], [-0.43, 0.0, 679.36], atol=1e-3)
    np.testing.assert_allclose(F[:3, :3], np.eye(3), atol=1e-5)  # the URDF's 1.5708 ~ pi/2
    np.testing.assert_allclose(robot.mount[:3, 0], [0, 0, 1], atol=1e-9)  # flange x = tool0 z


@pytest.mark.parametrize("acc", [[1.0, 2.0], "fast", [[1.0] * 6] * 2])
def test_acceleration_of_the_wrong_shape_is_an_input_error(kuka_dir, acc):
    with pytest.raises(InputError, match="one value or six") as ei:
        load_robot(kuka_dir / "kr150r3100_2.urdf", acceleration=acc)
    assert ei.value.field == "acceleration"


def _wrap_three_turns(q, lower, upper):
    """wrap_into_limits' definition: every value tried at -1, 0 and +1 turn."""
    out = q.copy()
    best = np.full(q.shape, np.inf)
    for k in (0.0, -1.0, 1.0):
        cand = q + 2 * np.pi * k
        ok = (cand >= lower) & (cand <= upper) & (np.abs(cand) < best)
        out = np.where(ok, cand, out)
        best = np.where(ok, np.abs(cand), best)
    return out


def test_wrap_into_limits_is_the_three_turn_choice_to_the_bit():
    from weldplan.robot.model import wrap_into_limits

    lower = np.radians([-185.0, -140.0, -120.0, -350.0, -125.0, -350.0])
    upper = np.radians([185.0, -5.0, 168.0, 350.0, 125.0, 350.0])
    rng = np.random.default_rng(5)
    for scale in (np.pi, 2 * np.pi, 8.0):
        q = rng.uniform(-scale, scale, (3000, 8, 6))
        q[::7] = np.pi
        q[::11] = -np.pi
        q[::13] = -0.0
        q[::17, :, 1] = -1.5 * np.pi  # an offset joint beyond -pi
        q[::23] = np.nextafter(np.pi, 0.0)
        got = wrap_into_limits(q, lower, upper)
        want = _wrap_three_turns(q, lower, upper)
        np.testing.assert_array_equal(got.view(np.int64), want.view(np.int64))


def test_link_frames_are_the_chain_of_each_joints_frame_to_the_bit(robot):
    """link_frames (all six joints' frames in one pass) is the product, joint by joint, of each
    joint's own frame (origin times Rodrigues rotation), the same bits one configuration at a
    time and in a batch."""
    q = _random_q(robot, 200, seed=9)
    chain = np.empty((len(q), 7, 4, 4))
    T = np.broadcast_to(robot.base, (len(q), 4, 4)).copy()
    chain[:, 0] = T
    for j in range(6):
        T = T @ robot._joint_frames(j, q[:, j])
        chain[:, j + 1] = T
    assert np.array_equal(robot.link_frames(q), chain)
    for k in range(0, 200, 37):
        assert np.array_equal(robot.link_frames(q[k])[0], chain[k])
