"""Errors like a vision player's estimate of the game, for state players that must steer from such estimates.

A vision student that estimates the game (command_prior=placo) can be steered by a state player from its
estimate (`legged eval VISION_RUN --pilot STATE_RUN`, `LearnerView.steer_with`). A state player trained on the
truth is brittle there: its corrections assume exact features. `SoccerConfig.estimate_noise` trains one on game
features with errors shaped like the estimate's:

- the goals are seen through the tracker's pose (legged.soccer.vision.tracker): one error of the player's x, y and yaw
  moves both goals together, the yaw's share growing with their distance;
- the ball and the other players are estimated in the heading frame (sighted, remembered or regressed): an
  error per coordinate whose size grows with the distance (near the feet a sighting or a fresh memory is within
  centimetres; across the pitch the network's guess is off by decimetres);
- velocities: an error per coordinate.

With `sight` the ball is given as a camera and its tracker give it instead: nearly exact where the head camera
would see it (ahead, within its horizontal field, neither under the lens nor too far for the detector), held
where it was last seen for `memory_s` when it is not (the robot's own pushes and turns make that stale), then
the network's guess, a larger error (`unseen_ball`, growing with distance).

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
    sight: bool = False
    """Give the ball as seen (sighted, held for `memory_s`, then guessed) instead of by distance alone."""
    sight_half_angle: float = 0.75
    """Half the head camera's horizontal field, radians (a 70 degree vertical field at 4:3: 0.75)."""
    sight_near_m: float = 0.2
    """A ball closer ahead than this is under the lens (70 degrees tilted 30 down, the head 0.4 m up), metres."""
    sight_far_m: float = 4.0
    """A ball farther than this is too small for the detector, metres."""
    memory_s: float = 1.0
    """How long an unseen ball is held where it was last seen, seconds (the tracker's `vision_ball_memory_s`)."""
    unseen_ball: float = 0.25
    """The guess's position error, x and y, metres (the shipped student's: 0.36 m RMS near it), growing by
    `ball_per_m` per metre."""

    def validate(self) -> None:
        sizes = [v for k, v in dataclasses.asdict(self).items() if k not in ("enabled", "correlation_s", "sight")]
        if min(sizes) < 0 or self.correlation_s <= 0:
            raise ValueError(f"estimate_noise: error sizes must be non-negative and correlation_s positive, got "
                             f"{dataclasses.asdict(self)}")
        if self.sight_near_m >= self.sight_far_m or not 0 < self.sight_half_angle < np.pi:
            raise ValueError(f"estimate_noise: sight_near_m ({self.sight_near_m}) must be below sight_far_m "
                             f"({self.sight_far_m}) and sight_half_angle in (0, pi), got {self.sight_half_angle}")


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


UNSEEN = 1e6
"""The age of a sighting that never was, seconds."""


def first_sighting(agents: int) -> jax.Array:
    """[agents, 3] sightings at a game's start (world x, y of the ball when last seen, seconds since): none."""
    return jnp.zeros((agents, 3)).at[:, 2].set(UNSEEN)


def in_sight(noise: EstimateNoise, ball_ego: jax.Array) -> jax.Array:
    """[A] whether each player's head camera would see the ball at `ball_ego` [A, 2] (its heading frame)."""
    distance = jnp.linalg.norm(ball_ego, axis=-1)
    bearing = jnp.arctan2(ball_ego[:, 1], ball_ego[:, 0])
    return (jnp.abs(bearing) < noise.sight_half_angle) & (ball_ego[:, 0] > noise.sight_near_m) \
        & (distance < noise.sight_far_m)


def next_sighting(noise: EstimateNoise, sighting: jax.Array, pos_xy: jax.Array, yaw: jax.Array, ball_xy: jax.Array,
                  dt: float, forget: jax.Array) -> jax.Array:
    """Sightings [A, 3] one control period `dt` on, for players at `pos_xy` [A, 2] heading `yaw` [A]: where the
    ball is (`ball_xy`, world) when in sight, else the last one aged by `dt`; `forget` (the ball was moved by a
    restart): the unseen ball is not held."""
    seen = in_sight(noise, yaw_rotate(yaw, ball_xy - pos_xy))
    age = jnp.where(forget, UNSEEN, sighting[:, 2] + dt)
    held = jnp.concatenate([sighting[:, :2], age[:, None]], -1)
    now = jnp.concatenate([jnp.broadcast_to(ball_xy, pos_xy.shape), jnp.zeros_like(age)[:, None]], -1)
    return jnp.where(seen[:, None], now, held)


def held_ball(sighting: jax.Array, pos_xy: jax.Array, yaw: jax.Array) -> jax.Array:
    """[A, 2] where each player's last sighting of the ball is, in its heading frame now."""
    return yaw_rotate(yaw, sighting[:, :2] - pos_xy)


def blurred(noise: EstimateNoise, error: jax.Array, game: jax.Array, held: tuple | None = None) -> jax.Array:
    """Game features [A, 10 + 4 others] (observe.game_features, heading frame) with the unit errors [A,
    error_size] applied: the goals through a pose error, the ball and players by distance-scaled errors. With
    `sight`, `held` = (the last sightings in the heading frame [A, 2], their ages [A]) gives the ball: seen now
    (age 0), held (up to `memory_s`), else guessed."""
    pose_xy, yaw = noise.pose_xy * error[:, 0:2], noise.pose_yaw * error[:, 2]
    goals = game[:, 6:10].reshape(-1, 2, 2)
    goals = yaw_rotate(yaw[:, None], goals - pose_xy[:, None])  # seen from a misplaced, misturned player
    ball_xy = game[:, 0:2]
    per_m = noise.ball_per_m * jnp.linalg.norm(ball_xy, axis=-1, keepdims=True)
    if noise.sight:
        last_seen, age = held
        guessed = age[:, None] > noise.memory_s
        ball_xy = jnp.where(guessed, ball_xy + (noise.unseen_ball + per_m) * error[:, 3:5],
                            last_seen + noise.ball * error[:, 3:5])
    else:
        ball_xy = ball_xy + (noise.ball + per_m) * error[:, 3:5]
    ball_vel = game[:, 3:5] + noise.ball_vel * error[:, 5:7]
    others = game[:, 10:].reshape(game.shape[0], -1, 4)
    where = others[..., :2]
    unit = error[:, 7:].reshape(others.shape)
    where = where + (noise.players + noise.players_per_m * jnp.linalg.norm(where, axis=-1, keepdims=True)) \
        * unit[..., :2]
    moving = others[..., 2:] + noise.player_vel * unit[..., 2:]
    return jnp.concatenate([ball_xy, game[:, 2:3], ball_vel, game[:, 5:6], goals.reshape(-1, 4),
                            jnp.concatenate([where, moving], -1).reshape(game.shape[0], -1)], -1)
