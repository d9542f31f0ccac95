"""Errors like a vision player's estimate of the game, for state players that must steer from such estimates.

A vision student that estimates the game (command_prior=placo) can be steered by a state player from its
estimate (`legged eval VISION_RUN --pilot STATE_RUN`, `LearnerView.steer_with`). A state player trained on the
truth is brittle there: its corrections assume exact features. `SoccerConfig.estimate_noise` trains one on game
features with errors shaped like the estimate's:

- the goals are seen through the tracker's pose (legged.soccer.tracker): one error of the player's x, y and yaw
  moves both goals together, the yaw's share growing with their distance;
- the ball and the other players are estimated in the heading frame (sighted, remembered or regressed): an
  error per coordinate whose size grows with the distance (near the feet a sighting or a fresh memory is within
  centimetres; across the pitch the network's guess is off by decimetres);
- velocities: an error per coordinate.

Each error is an Ornstein-Uhlenbeck process (stationary, its correlation decaying over `correlation_s`:
estimates err for a while, not per frame). They are added to the deployable `state` only, so the learner's
placo command reads them too; critics, teachers and frozen opponents read the clean `privileged_state`.
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np

from legged.envs.math import yaw_rotate


@dataclasses.dataclass(frozen=True)
class EstimateNoise:
    """Errors on a state player's game features shaped like a tracked vision player's (per coordinate)."""

    enabled: bool = False
    """Switch for the whole group (state tasks only: a vision player estimates the game itself)."""
    pose_xy: float = 0.15
    """The tracker's position error, x and y, metres: moves both goals (the shipped vision student's goal
    errors with its tracker were 0.36-0.52 m RMS, the first seconds before it locks on included)."""
    pose_yaw: float = 0.08
    """The tracker's heading error, radians: turns both goals about the player."""
    ball: float = 0.03
    """Ball position error at the player's feet, x and y, metres (sighted: 0.02 m; remembered for under 0.5 s:
    0.09 m RMS)."""
    ball_per_m: float = 0.1
    """... growing by this per metre of distance (the student's ball error: 0.18 m within 1 m, 0.33 m overall)."""
    ball_vel: float = 0.2
    """Ball velocity error, x and y, m/s (the vertical, like the ball's height, is left exact)."""
    players: float = 0.1
    """Other players' position error at the player's feet, x and y, metres ..."""
    players_per_m: float = 0.15
    """... growing by this per metre (the student's opponent error: 0.52 m RMS)."""
    player_vel: float = 0.2
    """Other players' velocity error, x and y, m/s."""
    correlation_s: float = 1.0
    """Time over which an error's correlation decays by e, seconds."""

    def validate(self) -> None:
        sizes = [v for k, v in dataclasses.asdict(self).items() if k not in ("enabled", "correlation_s")]
        if min(sizes) < 0 or self.correlation_s <= 0:
            raise ValueError(f"estimate_noise: error sizes must be non-negative and correlation_s positive, got "
                             f"{dataclasses.asdict(self)}")


def error_size(others: int) -> int:
    """Unit errors per player: pose (3), ball and its velocity (2 + 2), each other player (4)."""
    return 7 + 4 * others


def first_error(rng: jax.Array, agents: int, others: int) -> jax.Array:
    """[agents, error_size] unit errors at a game's start, drawn from the stationary distribution."""
    return jax.random.normal(rng, (agents, error_size(others)))


def next_error(noise: EstimateNoise, error: jax.Array, rng: jax.Array, dt: float) -> jax.Array:
    """The unit errors one control period `dt` on (each stays a standard normal: the process is stationary)."""
    keep = float(np.exp(-dt / noise.correlation_s))
    return keep * error + float(np.sqrt(1.0 - keep ** 2)) * jax.random.normal(rng, error.shape)


def blurred(noise: EstimateNoise, error: jax.Array, game: jax.Array) -> jax.Array:
    """Game features [A, 10 + 4 others] (observe.game_features, heading frame) with the unit errors [A,
    error_size] applied: the goals through a pose error, the ball and players by distance-scaled errors."""
    pose_xy, yaw = noise.pose_xy * error[:, 0:2], noise.pose_yaw * error[:, 2]
    goals = game[:, 6:10].reshape(-1, 2, 2)
    goals = yaw_rotate(yaw[:, None], goals - pose_xy[:, None])  # seen from a misplaced, misturned player
    ball_xy = game[:, 0:2]
    ball_xy = ball_xy + (noise.ball + noise.ball_per_m * jnp.linalg.norm(ball_xy, axis=-1, keepdims=True)) \
        * error[:, 3:5]
    ball_vel = game[:, 3:5] + noise.ball_vel * error[:, 5:7]
    others = game[:, 10:].reshape(game.shape[0], -1, 4)
    where = others[..., :2]
    unit = error[:, 7:].reshape(others.shape)
    where = where + (noise.players + noise.players_per_m * jnp.linalg.norm(where, axis=-1, keepdims=True)) \
        * unit[..., :2]
    moving = others[..., 2:] + noise.player_vel * unit[..., 2:]
    return jnp.concatenate([ball_xy, game[:, 2:3], ball_vel, game[:, 5:6], goals.reshape(-1, 4),
                            jnp.concatenate([where, moving], -1).reshape(game.shape[0], -1)], -1)
