"""go1-rough: blind velocity tracking on slopes, stairs and bumps, with domain randomisation and pushes.

The task where privileged information matters: `state` is what the robot can measure
(proprioception, IMU gravity, command; noisy), `privileged_state` adds what it cannot: base velocity, contact
forces, the randomised dynamics and the terrain heights around each foot. A terrain curriculum (legged_gym's,
measured against what each command asks: see `RoughEnv.carry`) moves each environment a level up after it
covered what its command asked, and down after a fall or after covering less than half of it.
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np

from legged.envs.config import GO1_RANDOMIZATION, NoiseConfig, RandomizationConfig
from legged.envs.curriculum import next_level, pick_tile
from legged.envs.flat import FlatConfig, VelocityTrackingEnv
from legged.robots import GO1
from legged.robots.spec import RobotSpec
from legged.worlds.mjcf import SceneOptions
from legged.worlds.rough import RoughTerrainConfig, rough_terrain


@dataclasses.dataclass(frozen=True)
class RoughConfig(FlatConfig):
    """Velocity tracking on tiled rough ground (legged.worlds.rough)."""

    terrain: RoughTerrainConfig = RoughTerrainConfig()
    """The rough-ground generator."""
    terrain_seed: int = 0
    """Seed of the terrain (the bumps); evaluations use another."""
    curriculum: bool = True
    """Terrain curriculum: start on the easiest row, move by the distance walked (see module docstring)."""
    spawn_jitter: float = 0.25
    """Start positions are uniform in +-this around a tile's centre, metres."""
    foot_scan_spacing: float = 0.1
    """Spacing of the 3 x 3 terrain heights around each foot in `privileged_state`, metres."""
    edge_margin: float = 1.0
    """An episode ends as a truncation when the body comes this close to the terrain's edge, metres."""
    randomization: RandomizationConfig = GO1_RANDOMIZATION
    """Domain randomisation (on: friction, masses, centre of mass, motor strength, PD gains, pushes, and the model
    ranges that cover the reference robots: COVERING)."""
    noise: NoiseConfig = NoiseConfig(enabled=True)
    """Observation noise on `state` (on)."""
    gyro_in_state: bool = True
    """`state` holds the IMU's angular velocity (a real robot measures it; the yaw rate is commanded)."""


def commanded_displacement(command: jax.Array, seconds: jax.Array) -> jax.Array:
    """Straight-line distance from start after `seconds` of tracking a constant body-frame (vx, vy, yaw rate)
    command perfectly: an arc of radius |v| / |w|, whose chord is 2 |v| |sin(w t / 2)| / |w| (|v| t as w -> 0)."""
    speed, rate = jnp.linalg.norm(command[:2]), jnp.abs(command[2])
    turning = rate > 1e-4
    return speed * jnp.where(turning, 2 * jnp.abs(jnp.sin(rate * seconds / 2)) / jnp.where(turning, rate, 1.0),
                             seconds)


class RoughEnv(VelocityTrackingEnv):
    """Go1 on rough ground tracking a random (vx, vy, yaw rate) command, blind."""

    def __init__(self, config: RoughConfig = RoughConfig(), robot: RobotSpec = GO1):
        terrain = rough_terrain(config.terrain_seed, config.terrain)
        super().__init__(robot, terrain, SceneOptions(ceiling=False), config)
        self._starts = jnp.asarray(terrain.starts, jnp.float32)
        self._tile_level = jnp.asarray(terrain.difficulties, jnp.int32)
        self._n_levels = config.terrain.levels
        s = config.foot_scan_spacing
        self._foot_scan = jnp.asarray([(i * s, j * s) for i in (-1, 0, 1) for j in (-1, 0, 1)], jnp.float32)
        lo = np.asarray(terrain.origin) + config.edge_margin
        self._inside = jnp.asarray(np.stack([lo, lo + (np.array(terrain.shape) - 1) * terrain.resolution
                                             - 2 * config.edge_margin]), jnp.float32)

    @property
    def levels(self) -> np.ndarray:
        """The curriculum's levels (terrain rows), easiest first."""
        return np.arange(self._n_levels)

    def carry(self, info):
        """Curriculum: up after covering, without falling, at least 80% of what the command asked (but no more
        than half a tile), when it asked for at least a quarter of a tile; down after a fall or after covering
        less than half of what it asked. What a command asks is the straight-line distance a perfect tracker
        covers: the chord of the arc that a constant (vx, vy, yaw rate) command draws."""
        walked = jnp.linalg.norm(info["base_xy"] - info["spawn_xy"])
        fell = info["truncation"] < 0.5
        asked = commanded_displacement(info["command"], info["step"] * self.dt)
        tile = self.config.terrain.tile_size
        up = (asked >= tile / 4) & (walked > 0.8 * jnp.minimum(asked, tile / 2)) & ~fell
        return next_level(info["level"], up, fell | (walked < 0.5 * asked))

    def _spawn_pose(self, rng, carry):
        k_tile, k_xy = jax.random.split(rng)
        tile, level = pick_tile(k_tile, carry, self._tile_level, self._n_levels, self.config.curriculum)
        j = self.config.spawn_jitter
        xy = self._starts[tile, :2] + jax.random.uniform(k_xy, (2,), minval=-j, maxval=j)
        z = self.floor_height(xy) + self.robot.standing_height + 0.02
        return jnp.array([xy[0], xy[1], z]), dict(tile=tile, level=level, spawn_xy=xy, base_xy=xy)

    def _task_privileged(self, data, info):
        feet = self.feet_positions(data)
        around = feet[:, None, :2] + self._foot_scan[None]                           # (feet, 9, 2)
        heights = jnp.clip(feet[:, None, 2] - self.floor_height(around), -0.3, 0.3)
        base = data.xpos[self._trunk]
        return jnp.concatenate([heights.reshape(-1), (base[2] - self.floor_height(base[:2]))[None]])

    def _task_truncated(self, data, info):
        xy = data.xpos[self._trunk, :2]
        return jnp.any(xy < self._inside[0]) | jnp.any(xy > self._inside[1])

    def _task_step(self, data, info, action):
        terms, success, metrics, info = super()._task_step(data, info, action)
        info["base_xy"] = data.xpos[self._trunk, :2]
        metrics["curriculum_level"] = info["level"].astype(jnp.float32)
        return terms, success, metrics, info
