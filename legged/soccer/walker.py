"""A trained walking skill as a frozen low level: soccer players that command velocities instead of joints.

The anchors (Haarnoja et al. 2024) train soccer end to end from skill teachers on far more compute than this
project has; here a soccer learner can instead play through a frozen `op3-walk` policy (legged.soccer.skills):
its action is a (vx, vy, yaw rate) command, which the walker turns into the 20 joint actions at the control
rate, reading the robot's own proprioception, the command and its gait clock, as it did in training. Like an
`Opponent`, the walker is arrays (no Python objects in the step); each robot keeps its own gait clock in the
game's `info['walker_phase']`.
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp

from legged.soccer.opponents import Opponent, OpponentNet, network_actions

COMMAND_SIZE = 3
"""A commanding player's action: (vx, vy, yaw rate), each in [-1, 1] of the walker's command range."""


@dataclasses.dataclass(frozen=True, eq=False)
class Walker:
    """A frozen walking policy (an op3-walk run's deterministic actor) and the commands it was trained on."""

    policy: Opponent
    """The actor's normaliser and layers (`Opponent.weight` 1)."""
    net: OpponentNet
    """How its layers are joined (activation)."""
    command_low: tuple[float, float, float]
    """Lowest (vx, vy, yaw rate) it was trained to follow, m/s, m/s, rad/s: an action of -1 commands this."""
    command_high: tuple[float, float, float]
    """Highest command it was trained to follow: an action of +1 commands this."""
    period: float
    """Its gait clock's period, seconds (the placo gait's stride)."""

    def command(self, action: jax.Array) -> jax.Array:
        """The velocity command [..., 3] of commanding actions [..., 3] (clipped to [-1, 1])."""
        low, high = jnp.asarray(self.command_low), jnp.asarray(self.command_high)
        return low + (high - low) * (jnp.clip(action, -1.0, 1.0) + 1.0) / 2.0

    def actions(self, proprio: jax.Array, action: jax.Array, phase: jax.Array) -> jax.Array:
        """Joint actions [n, 20] for robots' proprioception [n, 66] (the walk skill's noisy `state` head),
        commanding actions [n, 3] and gait phases [n]."""
        clock = 2.0 * jnp.pi * phase[:, None]
        inputs = jnp.concatenate([proprio, self.command(action), jnp.sin(clock), jnp.cos(clock)], axis=-1)
        return network_actions(self.net, self.policy, inputs)

    def advance(self, phase: jax.Array, dt: float) -> jax.Array:
        """Gait phases dt seconds on, wrapped to [0, 1)."""
        return jnp.mod(phase + dt / self.period, 1.0)
