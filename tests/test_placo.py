"""placo's OP3 model, the gait and kick tables built from it, and the tables played open loop in MuJoCo."""

import subprocess
import sys

import jax
import jax.numpy as jnp
import mujoco
import numpy as np
import pytest

from legged.robots.op3 import OP3
from legged.soccer.placo.gait_table import (
    advance_phase,
    filter_command,
    gait_targets,
    load_gait_metadata,
    load_gait_table,
    planned_speed,
    sequence_targets,
)
from legged.soccer.placo.kick_table import kick_targets, load_kick_table
from legged.soccer.placo.mirror import mirror_joints, mirror_signs

N_JOINTS = len(OP3.joint_names)
batched_targets = jax.jit(jax.vmap(gait_targets, in_axes=(None, 0, 0)))
"""gait_targets for a batch of (phase, command) pairs."""


@pytest.fixture(scope="module")
def gait():
    return load_gait_table(xp=np)


@pytest.fixture(scope="module")
def kick():
    return load_kick_table(xp=np)


def _grid_command(table, ix, iy, iz):
    return np.array([table.vx[ix], table.vy[iy], table.yaw_rate[iz]])


# --------------------------------------------------------------------------------------------------
# The kinematic model placo uses is MuJoCo's.


def _random_pose(model, rng):
    """A base pose (4x4, and its quaternion) and joint angles within the MJCF's ranges."""
    ranges = np.array([model.jnt_range[model.joint(n).id] for n in OP3.joint_names])
    q = rng.uniform(ranges[:, 0], ranges[:, 1])
    quat = rng.normal(size=4)
    quat /= np.linalg.norm(quat)
    rotation = np.zeros(9)
    mujoco.mju_quat2Mat(rotation, quat)
    base = np.eye(4)
    base[:3, :3], base[:3, 3] = rotation.reshape(3, 3), rng.uniform(-1.0, 1.0, 3)
    return base, quat, q


def test_placo_and_mujoco_forward_kinematics_agree(tmp_path):
    import placo

    from legged.soccer.placo.urdf import op3_urdf_path

    robot = placo.HumanoidRobot(str(op3_urdf_path(directory=tmp_path)))
    model = mujoco.MjModel.from_xml_path(str(OP3.mjcf_path))
    data = mujoco.MjData(model)
    jq = [model.jnt_qposadr[model.joint(n).id] for n in OP3.joint_names]
    rng = np.random.default_rng(0)
    for _ in range(4):
        base, quat, q = _random_pose(model, rng)
        robot.set_T_world_fbase(base)
        for name, angle in zip(OP3.joint_names, q):
            robot.set_joint(name, angle)
        robot.update_kinematics()
        data.qpos[:3], data.qpos[3:7], data.qpos[jq] = base[:3, 3], quat, q
        mujoco.mj_kinematics(model, data)
        frames = {"trunk": data.body(OP3.root_body), "left_foot": data.site("l_foot"),
                  "right_foot": data.site("r_foot")}
        for frame, mj in frames.items():
            T = robot.get_T_world_frame(frame)
            np.testing.assert_allclose(T[:3, 3], mj.xpos, atol=1e-6, err_msg=frame)
            np.testing.assert_allclose(T[:3, :3], mj.xmat.reshape(3, 3), atol=1e-6, err_msg=frame)


def test_run_time_tables_import_without_placo():
    code = ("import sys, legged.soccer.placo.gait_table, legged.soccer.placo.kick_table, "
            "legged.soccer.placo.open_loop; sys.exit('placo' in sys.modules)")
    assert subprocess.run([sys.executable, "-c", code], check=False).returncode == 0


# --------------------------------------------------------------------------------------------------
# Gait table lookups.


def test_gait_table_shapes(gait):
    nx, ny, nz = len(gait.vx), len(gait.vy), len(gait.yaw_rate)
    assert gait.targets.shape[:3] == (nx, ny, nz) and gait.targets.shape[4] == N_JOINTS
    assert gait.kin_speed.shape == (nx, ny, nz, 3)
    assert gait.stand.shape == (N_JOINTS,)
    assert gait.start.shape[1] == gait.stop.shape[1] == N_JOINTS
    for axis in (gait.vx, gait.vy, gait.yaw_rate):
        assert np.all(np.diff(axis) > 0)
    assert load_gait_metadata()["joint_names"] == OP3.joint_names
    np.testing.assert_allclose(gait.start[0], gait.stand, atol=1e-6)
    np.testing.assert_allclose(gait.stop[-1], gait.stand, atol=1e-6)
    assert gait_targets(gait, 0.3, (0.1, 0.0, 0.0)).shape == (N_JOINTS,)


def test_gait_targets_at_grid_points_are_the_stored_samples(gait):
    n_phase = gait.targets.shape[3]
    rng = np.random.default_rng(1)
    cells = [(0, 0, 0), (len(gait.vx) - 1, len(gait.vy) - 1, len(gait.yaw_rate) - 1)]
    cells += [tuple(rng.integers(0, s) for s in gait.targets.shape[:3]) for _ in range(10)]
    for ix, iy, iz in cells:
        command = _grid_command(gait, ix, iy, iz)
        for p in (0, n_phase - 1, int(rng.integers(n_phase))):
            np.testing.assert_allclose(gait_targets(gait, p / n_phase, command), gait.targets[ix, iy, iz, p], atol=1e-6)
        np.testing.assert_allclose(planned_speed(gait, command), gait.kin_speed[ix, iy, iz], atol=1e-6)


def test_gait_targets_are_continuous_in_phase_and_wrap(gait):
    n_phase = gait.targets.shape[3]
    command = np.array([0.13, 0.01, -0.2])  # inside a cell: all 8 corners weigh in
    # Across the wrap: phase 1 is phase 0, and just below 1 it is close to both.
    np.testing.assert_allclose(gait_targets(gait, 1.0, command), gait_targets(gait, 0.0, command), atol=1e-6)
    np.testing.assert_allclose(gait_targets(gait, -0.25, command), gait_targets(gait, 0.75, command), atol=1e-6)
    # A fine sweep over [0.9, 1.1]: steps no larger than the steepest knot-to-knot slope allows.
    h = 1.0 / (8 * n_phase)
    phases = np.arange(0.9, 1.1, h)
    sweep = np.asarray(batched_targets(gait, phases, np.tile(command, (len(phases), 1))))
    slope = np.abs(np.diff(gait.targets, axis=3, append=gait.targets[:, :, :, :1])).max() * n_phase
    assert np.abs(np.diff(sweep, axis=0)).max() <= slope * h + 1e-5


def test_gait_targets_are_multilinear_in_command(gait):
    phase = 0.37
    for axis in range(3):  # one cell edge along each command axis
        corner = np.array([2, 1, 2])
        low, high = _grid_command(gait, *corner), _grid_command(gait, *(corner + np.eye(3, dtype=int)[axis]))
        f_low, f_high = np.asarray(gait_targets(gait, phase, low)), np.asarray(gait_targets(gait, phase, high))
        for w in (0.25, 0.5, 0.9):
            np.testing.assert_allclose(gait_targets(gait, phase, (1 - w) * low + w * high), (1 - w) * f_low + w * f_high,
                                       atol=1e-5)
    # Small command changes make small target changes (no jumps at cell boundaries).
    vx = np.linspace(gait.vx[0], gait.vx[-1], 400)
    sweep = np.asarray(batched_targets(gait, np.full(len(vx), phase), np.stack([vx, 0.02 + 0 * vx, 0.1 + 0 * vx], 1)))
    steepest = np.abs(np.diff(gait.targets, axis=0) / np.diff(gait.vx)[:, None, None, None, None]).max()
    assert np.abs(np.diff(sweep, axis=0)).max() <= steepest * (vx[1] - vx[0]) + 1e-5


def test_gait_lookups_jit_vmap_match_numpy(gait):
    rng = np.random.default_rng(2)
    phases = rng.uniform(-1.0, 2.0, 16).astype(np.float32)
    commands = rng.uniform(-0.6, 0.6, (16, 3)).astype(np.float32)
    expected = np.array([np.asarray(gait_targets(gait, p, c)) for p, c in zip(phases, commands)])
    table = load_gait_table(xp=jnp)
    batched = batched_targets(table, jnp.asarray(phases), jnp.asarray(commands))
    np.testing.assert_allclose(np.asarray(batched), expected, atol=1e-6)
    step = jax.jit(jax.vmap(lambda p, c: (advance_phase(p, 0.025, table), filter_command(c * 0, c, 0.025, table))))
    new_phase, filtered = step(jnp.asarray(phases), jnp.asarray(commands))
    np.testing.assert_allclose(new_phase, np.mod(phases + 0.025 / gait.period, 1.0), atol=1e-6)
    np.testing.assert_allclose(filtered, [filter_command(np.zeros(3), c, 0.025, gait) for c in commands], atol=1e-6)
    assert np.all((new_phase >= 0) & (new_phase < 1))


def test_commands_outside_the_grid_are_clipped(gait):
    low, high = np.asarray(gait.command_low), np.asarray(gait.command_high)
    for phase in (0.0, 0.4, 0.71):
        np.testing.assert_allclose(gait_targets(gait, phase, high + [1.0, 0.5, 3.0]), gait_targets(gait, phase, high), atol=1e-6)
        np.testing.assert_allclose(gait_targets(gait, phase, low - [1.0, 0.5, 3.0]), gait_targets(gait, phase, low), atol=1e-6)
    np.testing.assert_allclose(filter_command(np.zeros(3), [9.0, -9.0, 9.0], 100.0, gait),
                               [high[0], low[1], high[2]], atol=1e-6)


def test_sequence_targets_interpolate_and_hold_the_ends(gait):
    dt = float(gait.ctrl_dt)
    np.testing.assert_allclose(sequence_targets(gait.start, -1.0, dt), gait.start[0], atol=1e-6)
    np.testing.assert_allclose(sequence_targets(gait.start, 99.0, dt), gait.start[-1], atol=1e-6)
    np.testing.assert_allclose(sequence_targets(gait.start, 2.5 * dt, dt), (gait.start[2] + gait.start[3]) / 2, atol=1e-6)


# --------------------------------------------------------------------------------------------------
# Kick table.


def test_kick_starts_and_ends_standing(kick, gait):
    assert kick.targets.shape[0] == 2 and kick.targets.shape[2] == N_JOINTS
    np.testing.assert_allclose(kick.stand, gait.stand, atol=1e-6)
    for side in (0, 1):
        np.testing.assert_allclose(kick.targets[side, 0], kick.stand, atol=1e-6)
        np.testing.assert_allclose(kick.targets[side, -1], kick.stand, atol=1e-6)
        np.testing.assert_allclose(kick_targets(kick, 0.0, side), kick.stand, atol=1e-6)
        np.testing.assert_allclose(kick_targets(kick, 1.5, side), kick.stand, atol=1e-6)
    n = kick.targets.shape[1]
    np.testing.assert_allclose(kick_targets(kick, 10 / (n - 1), 1), kick.targets[1, 10], atol=1e-6)
    assert abs(float(kick.duration) - (n - 1) * float(kick.ctrl_dt)) < 1e-4
    # The kick moves: the kicking leg leaves the standing pose by a lot.
    assert np.abs(kick.targets[0] - kick.stand).max() > 0.5


def test_left_kick_mirrors_the_right(kick):
    signs = mirror_signs()
    expected = dict.fromkeys(OP3.joint_names, -1.0) | {"head_tilt": 1.0}
    np.testing.assert_array_equal(signs, [expected[n] for n in OP3.joint_names])
    np.testing.assert_allclose(mirror_joints(np.array(OP3.default_pose), signs), OP3.default_pose, atol=1e-9)
    right, left = kick.targets[0].astype(float), kick.targets[1].astype(float)
    offset = kick.stand - mirror_joints(kick.stand.astype(float), signs)
    np.testing.assert_allclose(left, mirror_joints(right, signs) + offset, atol=1e-5)
    assert np.abs(offset).max() < 0.01  # the standing pose is (nearly) symmetric itself
    np.testing.assert_allclose(kick.ball[1], kick.ball[0] * [1.0, -1.0], atol=1e-7)
    assert kick.ball[0, 1] < 0 < kick.ball[1, 1]  # the right foot kicks a ball on the right


# --------------------------------------------------------------------------------------------------
# Open loop in native MuJoCo.


def test_table_walk_moves_forward_without_falling(gait):
    from legged.soccer.placo.open_loop import walk_table_in_mujoco

    forward = _grid_command(gait, int(np.searchsorted(gait.vx, 0.1)), int(np.searchsorted(gait.vy, 0.0)),
                            int(np.searchsorted(gait.yaw_rate, 0.0)))
    assert forward[0] > 0 and forward[1] == forward[2] == 0
    (result,) = walk_table_in_mujoco(gait, [forward], duration=3.0, measure_last=2.0)
    assert result["fell"] is None
    dx, dy = result["displacement"]
    assert dx > 0.3 * forward[0] * 3.0 and abs(dy) < 0.5 * dx
    assert result["speed"][0] > 0.3 * forward[0]


@pytest.mark.parametrize("side", [0, 1])
def test_kick_sends_the_ball_forward_without_falling(kick, side):
    from legged.soccer.placo.open_loop import kick_ball_in_mujoco

    result = kick_ball_in_mujoco(kick, side, after=0.5)
    assert result["fell"] is None
    assert result["ball_speed_max"] > 0.5
    assert result["ball_forward"] > 0.3
    assert abs(result["ball_direction_deg"]) < 20
