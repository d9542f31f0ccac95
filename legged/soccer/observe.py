"""What each soccer player observes: proprioception and the game seen from its own heading frame.

Everything is read from qpos/qvel (not from forward-kinematics outputs), so observations stay exact right
after a kick-off restart moves the robots. The egocentric frame of an agent is its torso's heading frame:
x forward, y left, z up, origin at the torso. Goals are "own" and "opponent", teammates come before
opponents, so one policy can play either side of the pitch.
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np

from legged.envs.math import quat_to_mat, yaw_rotate
from legged.soccer.layout import SoccerLayout

PROPRIO_SIZE = 3 + 3 + 3 * 20
"""Gravity in the torso frame, gyro, joint positions (from the default pose), joint velocities, previous action."""


@dataclasses.dataclass(frozen=True, eq=False)
class Bodies:
    """The kinematic state of every robot and the ball, from qpos/qvel (jnp arrays)."""

    pos: jnp.ndarray
    """Torso origins in the world, [A, 3]."""
    rot: jnp.ndarray
    """World-from-torso rotations, [A, 3, 3]."""
    vel: jnp.ndarray
    """Torso linear velocities in the world, [A, 3]."""
    gyro: jnp.ndarray
    """Torso angular velocities in the torso frame, [A, 3]."""
    q: jnp.ndarray
    """Joint positions, [A, n_joints]."""
    qd: jnp.ndarray
    """Joint velocities, [A, n_joints]."""
    ball_pos: jnp.ndarray
    """Ball centre, [3]."""
    ball_vel: jnp.ndarray
    """Ball linear velocity, [3]."""

    @property
    def yaw(self) -> jnp.ndarray:
        """Heading of each torso, [A]."""
        return jnp.arctan2(self.rot[:, 1, 0], self.rot[:, 0, 0])

    @property
    def up_z(self) -> jnp.ndarray:
        """z component of each torso's up axis, [A]."""
        return self.rot[:, 2, 2]


def read_bodies(layout: SoccerLayout, qpos, qvel) -> Bodies:
    """Robot and ball state of one game."""
    root_q = layout.root_qpos_adr[:, None]
    root_v = layout.root_dof_adr[:, None]
    b_q, b_v = layout.ball_qpos_adr, layout.ball_dof_adr
    return Bodies(
        pos=qpos[root_q + np.arange(3)], rot=quat_to_mat(qpos[root_q + 3 + np.arange(4)]),
        vel=qvel[root_v + np.arange(3)], gyro=qvel[root_v + 3 + np.arange(3)],
        q=qpos[layout.joint_qpos_adr], qd=qvel[layout.joint_dof_adr],
        ball_pos=qpos[b_q:b_q + 3], ball_vel=qvel[b_v:b_v + 3])


def others_of(layout: SoccerLayout) -> np.ndarray:
    """For each agent, its teammates then its opponents in agent order, [A, A - 1]."""
    rows = []
    for a in range(layout.n_agents):
        mates = [b for b in range(layout.n_agents) if b != a and layout.team[b] == layout.team[a]]
        rows.append(mates + [b for b in range(layout.n_agents) if layout.team[b] != layout.team[a]])
    return np.array(rows, dtype=np.int32).reshape(layout.n_agents, layout.n_agents - 1)


def proprioception(b: Bodies, default_pose, last_action) -> jnp.ndarray:
    """[A, PROPRIO_SIZE]: gravity in the torso frame, gyro, q - default, qd, previous action."""
    gravity = -b.rot[:, 2, :]  # world -z expressed in the torso frame: R^T (0, 0, -1)
    return jnp.concatenate([gravity, b.gyro, b.q - default_pose, b.qd, last_action], -1)


def local_velocity(b: Bodies) -> jnp.ndarray:
    """[A, 3]: each torso's linear velocity in its own frame."""
    return jnp.einsum("aji,aj->ai", b.rot, b.vel)


def velocity_estimate(b: Bodies, noise: float, rng) -> jnp.ndarray:
    """[A, 3]: each torso's velocity in its own frame as a state estimator (IMU and leg odometry) gives it, off by a
    uniform error within +-`noise` m/s per axis and control step."""
    truth = local_velocity(b)
    return truth + noise * jax.random.uniform(rng, truth.shape, minval=-1.0, maxval=1.0) if noise else truth


def game_features(b: Bodies, team: np.ndarray, goals: np.ndarray, others: np.ndarray) -> jnp.ndarray:
    """[A, 10 + 4 (A - 1)] in each agent's heading frame: ball position (3) and velocity (3), own goal and
    opponent goal centres (2 + 2), then each teammate and opponent: position and velocity (x, y each)."""
    yaw = b.yaw
    ego = lambda xy: yaw_rotate(yaw[:, None] if xy.ndim == 3 else yaw, xy)
    ball_rel = b.ball_pos - b.pos
    ball = jnp.concatenate([ego(ball_rel[:, :2]), ball_rel[:, 2:]], -1)
    ball_vel = jnp.concatenate([ego(jnp.broadcast_to(b.ball_vel[:2], b.pos[:, :2].shape)),
                                jnp.broadcast_to(b.ball_vel[2:], b.pos[:, 2:].shape)], -1)
    goals = jnp.asarray(goals[:, :2], jnp.float32)
    own = ego(goals[team] - b.pos[:, :2])
    opp = ego(goals[1 - team] - b.pos[:, :2])
    rel = b.pos[others, :2] - b.pos[:, None, :2]  # [A, A-1, 2]
    vel = b.vel[others, :2]
    players = jnp.concatenate([ego(rel), ego(vel)], -1).reshape(b.pos.shape[0], -1)
    return jnp.concatenate([ball, ball_vel, own, opp, players], -1)


def attack_direction(b: Bodies, team: np.ndarray, goals: np.ndarray) -> jnp.ndarray:
    """[A, 2] unit vector from each agent's own goal towards the opponent goal, in its heading frame: the
    (cos, sin) of the angle from the agent's torso heading to the direction it attacks in."""
    goals = jnp.asarray(goals[:, :2], jnp.float32)
    along = goals[1 - team] - goals[team]
    return yaw_rotate(b.yaw, along / jnp.linalg.norm(along, axis=-1, keepdims=True))


HEADING_SIZE = 2
"""Length of `attack_direction` (vision players with `vision_heading`)."""

PRIVILEGED_SIZE = 17
"""Length of `privileged_features`."""


def feature_layout(players_per_team: int) -> list[tuple[str, int]]:
    """Named slices of a player's egocentric features (proprioception, then `game_features`): the layout a
    warm start maps inputs by, so that a 1v1 player's ball, goals and opponent reach a 2v2 player's."""
    return ([("proprio", PROPRIO_SIZE), ("ball", 3), ("ball_vel", 3), ("own_goal", 2), ("opponent_goal", 2)]
            + [(f"teammate{i}", 4) for i in range(players_per_team - 1)]
            + [(f"opponent{i}", 4) for i in range(players_per_team)])


def privileged_features(b: Bodies, team: np.ndarray, score, time_fraction) -> jnp.ndarray:
    """[A, 17] ground truth in each team's own pitch frame (the away team's is turned by 180 degrees, so
    both teams attack +x): torso velocity in the torso frame (3), torso height (1), position (2), heading
    cos and sin (2), ball position (3) and velocity (3), goal difference (1), time elapsed fraction (1),
    upright (1)."""
    sign = jnp.asarray(1.0 - 2.0 * team, jnp.float32)[:, None]
    yaw = b.yaw + jnp.pi * jnp.asarray(team, jnp.float32)
    local_vel = local_velocity(b)
    ball = jnp.concatenate([sign * b.ball_pos[:2], jnp.broadcast_to(b.ball_pos[2:], sign.shape)], -1)
    ball_vel = jnp.concatenate([sign * b.ball_vel[:2], jnp.broadcast_to(b.ball_vel[2:], sign.shape)], -1)
    diff = (score[team] - score[1 - team]).astype(jnp.float32)[:, None]
    n = b.pos.shape[0]
    return jnp.concatenate([local_vel, b.pos[:, 2:], sign * b.pos[:, :2], jnp.cos(yaw)[:, None],
                            jnp.sin(yaw)[:, None], ball, ball_vel, diff,
                            jnp.full((n, 1), time_fraction, jnp.float32), b.up_z[:, None]], -1)


def camera_observation(images: dict, max_depth: float) -> jnp.ndarray:
    """Camera images as network input, [A, 4, H, W] float32: RGB in [0, 1], then depth / max_depth."""
    rgb = jnp.moveaxis(images["rgb"].astype(jnp.float32) / 255.0, -1, 1)
    return jnp.concatenate([rgb, (images["depth"] / max_depth)[:, None]], 1)
