"""go1-flat: velocity tracking on flat ground, the sanity task for training pipelines."""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp

from legged.envs.base import LeggedEnv
from legged.envs.config import GO1_RANDOMIZATION, EnvConfig, NoiseConfig, PenaltyScales, RandomizationConfig
from legged.envs.math import yaw_rotate
from legged.envs.rewards import roll_pitch_rate_sq, tracking
from legged.robots import GO1
from legged.robots.spec import RobotSpec
from legged.worlds.mjcf import SceneOptions
from legged.worlds.terrain import Terrain


@dataclasses.dataclass(frozen=True)
class FlatRewards:
    """Weights of the velocity-tracking reward terms."""

    tracking_lin_vel: float = 1.0
    """exp(-|v_cmd - v_xy|^2 / tracking_sigma), velocities in the yaw frame."""
    tracking_yaw_rate: float = 0.5
    """exp(-(w_cmd - w_z)^2 / tracking_sigma)."""
    tracking_sigma: float = 0.25
    """Squared-error scale of the two tracking terms ((m/s)^2, (rad/s)^2): smaller pays precision more (at 0.1 an
    error of 0.14 m/s keeps 82% of the term, 0.055 m/s 97%; at 0.25, 92% and 99%)."""
    lin_vel_z: float = -2.0
    """Times the squared vertical base velocity."""
    ang_vel_xy: float = -0.05
    """Times the squared roll and pitch rates."""
    feet_air_time: float = 1.0
    """Times the sum over feet touching down of (air time - feet_air_threshold), while the command asks to move."""
    feet_air_threshold: float = 0.5
    """Air time (s) a foot's step must exceed to be paid by feet_air_time; shorter steps are charged."""


@dataclasses.dataclass(frozen=True)
class FlatConfig(EnvConfig):
    """Velocity tracking on an infinite plane."""

    lin_vel_x: tuple[float, float] = (-1.0, 1.0)
    """Range of the commanded forward velocity, m/s (sampled at reset)."""
    lin_vel_y: tuple[float, float] = (-0.5, 0.5)
    """Range of the commanded lateral velocity, m/s."""
    yaw_rate: tuple[float, float] = (-1.0, 1.0)
    """Range of the commanded yaw rate, rad/s."""
    rewards: FlatRewards = FlatRewards()
    """Task reward weights."""
    penalties: PenaltyScales = PenaltyScales(collisions=-1.0)
    """Penalty weights."""
    only_positive_rewards: bool = True
    """Clip each step's total reward at 0 (see EnvConfig)."""
    randomization: RandomizationConfig = GO1_RANDOMIZATION
    """Domain randomisation (on, with the model ranges that cover the reference robots: legged.envs.config.COVERING)."""
    noise: NoiseConfig = NoiseConfig(enabled=True)
    """Observation noise on `state` (on)."""


class VelocityTrackingEnv(LeggedEnv):
    """A robot tracking a random (vx, vy, yaw rate) command (sampled at reset) on some terrain; subclasses say
    where episodes start (`_spawn_pose`)."""

    @property
    def penalty_scales(self) -> PenaltyScales:
        return self.config.penalties

    @property
    def command_names(self) -> tuple[str, ...]:
        return ("vx", "vy", "yaw_rate")

    def mastered(self, info):
        """Ran to the time limit with a mean velocity error under half the commanded speed plus 5 cm/s (standing
        still does not count once a command asks for more than 10 cm/s)."""
        error = info["tracking_error_sum"] / jnp.maximum(info["step"], 1)
        return (info["truncation"] > 0.5) & (error < 0.5 * jnp.linalg.norm(info["command"][:2]) + 0.05)

    def _spawn_pose(self, rng, carry) -> tuple[jax.Array, dict]:
        """(start position (3,), the task's own entries of `info`) of a new episode."""
        return jnp.array([0.0, 0.0, self.robot.standing_height + 0.02]), {}

    def _task_reset(self, rng, carry=None):
        c = self.config
        k = jax.random.split(rng, 4)
        cmd = jnp.stack([jax.random.uniform(k[i], minval=r[0], maxval=r[1])
                         for i, r in enumerate((c.lin_vel_x, c.lin_vel_y, c.yaw_rate))])
        yaw = jax.random.uniform(k[3], minval=-jnp.pi, maxval=jnp.pi)
        pos, own = self._spawn_pose(jax.random.fold_in(rng, 1), carry)
        info = dict(command=cmd, air_time=jnp.zeros(len(self._feet)), tracking_error_sum=jnp.float32(0.0), **own)
        return pos, yaw, info

    def _command(self, data, info):
        return info["command"]

    def _exteroception(self, data, info):
        return jnp.zeros(0), jnp.zeros(0)

    def _task_step(self, data, info, action):
        w, cmd = self.config.rewards, info["command"]
        rot = self.base_rotation(data)
        local = yaw_rotate(self.base_yaw(data), data.qvel[0:2])
        ang = rot @ data.qvel[3:6]
        contact = data.contact_force[:len(self._feet)] > 1.0
        air = info["air_time"] + self.dt
        touchdown = contact & (info["air_time"] > 0.0)
        moving = jnp.linalg.norm(cmd[:2]) > 0.1
        info["air_time"] = jnp.where(contact, 0.0, air)
        error = jnp.linalg.norm(cmd[:2] - local)
        info["tracking_error_sum"] = info["tracking_error_sum"] + error
        terms = {
            "tracking_lin_vel": w.tracking_lin_vel * tracking(jnp.sum(jnp.square(cmd[:2] - local)), w.tracking_sigma),
            "tracking_yaw_rate": w.tracking_yaw_rate * tracking(jnp.square(cmd[2] - ang[2]), w.tracking_sigma),
            "lin_vel_z": w.lin_vel_z * jnp.square(data.qvel[2]),
            "ang_vel_xy": w.ang_vel_xy * roll_pitch_rate_sq(data.qvel),
            "feet_air_time": w.feet_air_time * moving * jnp.sum((air - w.feet_air_threshold) * touchdown),
        }
        metrics = {"command_speed": jnp.linalg.norm(cmd[:2]), "speed": jnp.linalg.norm(local),
                   "tracking_error_mps": info["tracking_error_sum"] / info["step"]}
        return terms, jnp.bool_(False), metrics, info


class FlatEnv(VelocityTrackingEnv):
    """A robot on flat ground tracking a random (vx, vy, yaw rate) command."""

    def __init__(self, config: FlatConfig = FlatConfig(), robot: RobotSpec = GO1):
        super().__init__(robot, Terrain.flat(), SceneOptions(flat=True), config)
