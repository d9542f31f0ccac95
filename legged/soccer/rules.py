"""The laws of the game as pure jax.numpy functions: goals, ball out of play, kick-off and spawn positions."""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np

from legged.envs.math import quat_from_yaw
from legged.soccer.config import SoccerSceneConfig


@dataclasses.dataclass(frozen=True)
class BallCall:
    """What the ball's position means this step (scalar booleans)."""

    home_scores: jnp.ndarray
    """The whole ball is behind the away goal's line, inside its mouth (the home team attacks +x)."""
    away_scores: jnp.ndarray
    """The whole ball is behind the home goal's line, inside its mouth."""
    out: jnp.ndarray
    """The whole ball is over a touch line, or over a goal line outside the goal: out of play."""

    @property
    def goal(self) -> jnp.ndarray:
        """Either team scored."""
        return self.home_scores | self.away_scores


def call_ball(scene: SoccerSceneConfig, ball_pos) -> BallCall:
    """Goal, out of play or in play, for the ball centre `ball_pos` (3,)."""
    r = scene.ball_radius
    x, y, z = ball_pos[0], ball_pos[1], ball_pos[2]
    behind_home = x < -scene.field_length / 2 - r
    behind_away = x > scene.field_length / 2 + r
    in_mouth = (jnp.abs(y) < scene.goal_width / 2) & (z < scene.goal_height)
    over_touch = jnp.abs(y) > scene.field_width / 2 + r
    return BallCall(home_scores=behind_away & in_mouth, away_scores=behind_home & in_mouth,
                    out=((behind_home | behind_away) & ~in_mouth) | over_touch)


def place_players(qpos, root_qpos_adr: np.ndarray, poses, height: float):
    """qpos with each robot's free joint at its ground pose (x, y, yaw) [A, 3], upright at `height`."""
    quats = jax.vmap(quat_from_yaw)(poses[:, 2])
    roots = jnp.concatenate([poses[:, :2], jnp.full((poses.shape[0], 1), height), quats], -1)  # [A, 7]
    return qpos.at[root_qpos_adr[:, None] + np.arange(7)].set(roots)


def place_ball(qpos, qvel, ball_qpos_adr: int, ball_dof_adr: int, xy, radius: float):
    """qpos, qvel with the ball resting on the ground at `xy`."""
    qpos = qpos.at[ball_qpos_adr:ball_qpos_adr + 7].set(
        jnp.concatenate([xy, jnp.array([radius, 1.0, 0.0, 0.0, 0.0])]))
    return qpos, qvel.at[ball_dof_adr:ball_dof_adr + 6].set(0.0)


def back_in_play(scene: SoccerSceneConfig, ball_xy, inset: float):
    """Where a ball that left the pitch is put back: its position clamped to `inset` inside the lines."""
    half = jnp.array([scene.field_length / 2 - inset, scene.field_width / 2 - inset])
    return jnp.clip(ball_xy, -half, half)


def spawn_poses(rng, kickoff, spread: float, yaw_range: float):
    """Random ground poses around the kick-off poses [A, 3]: +-spread metres per axis, +-yaw_range radians."""
    k_xy, k_yaw = jax.random.split(rng)
    xy = jax.random.uniform(k_xy, kickoff[:, :2].shape, minval=-spread, maxval=spread)
    yaw = jax.random.uniform(k_yaw, kickoff[:, 2].shape, minval=-yaw_range, maxval=yaw_range)
    return kickoff + jnp.concatenate([xy, yaw[:, None]], -1)


def random_ball_xy(rng, scene: SoccerSceneConfig, inset: float):
    """A ball position anywhere on the pitch `inset` inside the lines."""
    half = jnp.array([scene.field_length / 2 - inset, scene.field_width / 2 - inset])
    return jax.random.uniform(rng, (2,), minval=-half, maxval=half)


def start_state(rng, config, qpos0, kickoff, layout, standing_height: float, nv: int):
    """qpos, qvel of a new game (SoccerConfig `config`): robots around their kick-off poses, the ball at
    rest on the pitch (anywhere with `random_ball`, else on the centre spot). Used by `SoccerEnv.reset`
    and, eagerly, by `legged camera` so both show the same game for a seed."""
    k_pose, k_ball = jax.random.split(rng)
    poses = spawn_poses(k_pose, kickoff, config.spawn_spread, config.spawn_yaw)
    qpos = place_players(qpos0, layout.root_qpos_adr, poses, standing_height)
    ball = random_ball_xy(k_ball, config.scene, config.restart_inset) if config.random_ball else jnp.zeros(2)
    return place_ball(qpos, jnp.zeros(nv), layout.ball_qpos_adr, layout.ball_dof_adr, ball, config.scene.ball_radius)
