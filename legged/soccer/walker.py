"""A trained walking skill as a frozen low level: soccer players that command velocities instead of joints.

The anchors (Haarnoja et al. 2024) train soccer end to end from skill teachers on far more compute than this
project has; here a soccer learner can instead play through a frozen `op3-walk` policy (legged.soccer.skills):
its action is a (vx, vy, yaw rate) command, which the walker turns into the 20 joint actions at the control
rate, reading the robot's own proprioception, the command and its gait clock, as it did in training (a
residual walker adds the placo gait's reference at the clock and the filtered command, as in training). Like
an `Opponent`, the walker is arrays (no Python objects in the step); each robot keeps its walker state, one
row of `WALKER_STATE_SIZE` floats (gait phase, low-pass filtered command), in the game's
`info['walker_state']`.
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp

from legged.soccer.gait_table import GaitTable, advance_phase, filter_command, gait_targets
from legged.soccer.opponents import Opponent, OpponentNet, network_actions
from legged.soccer.placo_player import actions_of

COMMAND_SIZE = 3
"""A commanding player's action: (vx, vy, yaw rate), each in [-1, 1] of the walker's command range."""
WALKER_STATE_SIZE = 4
"""Per robot: gait phase in [0, 1), then the low-pass filtered command (vx, vy, yaw rate)."""


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
    gait: GaitTable
    """The placo gait table its clock and reference come from."""
    dt: float
    """Control period, seconds."""
    residual: bool = False
    """Its actions are offsets from the gait's reference (op3-walk's `residual`)."""
    default_pose: tuple[float, ...] = ()
    """The robot's default pose (residual walkers: the reference's targets become actions around it)."""
    action_scale: float = 1.0
    """Radians per unit of action (residual walkers)."""

    def command(self, action: jax.Array) -> jax.Array:
        """The velocity command [..., 3] of commanding actions [..., 3] (clipped to [-1, 1])."""
        low, high = jnp.asarray(self.command_low), jnp.asarray(self.command_high)
        return low + (high - low) * (jnp.clip(action, -1.0, 1.0) + 1.0) / 2.0

    def actions(self, proprio: jax.Array, action: jax.Array, state: jax.Array) -> jax.Array:
        """Joint actions [n, 20] for robots' proprioception [n, 66] (the walk skill's noisy `state` head),
        commanding actions [n, 3] and walker states [n, WALKER_STATE_SIZE]."""
        clock = 2.0 * jnp.pi * state[:, :1]
        inputs = jnp.concatenate([proprio, self.command(action), jnp.sin(clock), jnp.cos(clock)], axis=-1)
        out = network_actions(self.net, self.policy, inputs)
        if self.residual:
            targets = jax.vmap(lambda s: gait_targets(self.gait, s[0], s[1:]))(state)
            out = out + actions_of(targets, jnp.asarray(self.default_pose), self.action_scale)
        return out

    def step(self, state: jax.Array, action: jax.Array) -> jax.Array:
        """Walker states one control period on, the robots commanded by `action` [n, 3] meanwhile."""
        phase = advance_phase(state[:, 0], self.dt, self.gait)
        filtered = filter_command(state[:, 1:], self.command(action), self.dt, self.gait)
        return jnp.concatenate([phase[:, None], filtered], axis=-1)
