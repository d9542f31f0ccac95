"""A trained walking skill as a frozen low level: soccer players that command velocities instead of joints.

Soccer can be trained end to end from skill teachers, on far more compute than this project has; here a soccer
learner can instead play through a frozen `op3-walk` policy (legged.skills.env):
its action is a (vx, vy, yaw rate) command, which the walker turns into the 20 joint actions at the control
rate, reading the robot's own proprioception, the command, its low-pass filtered copy and its gait clock, as
it did in training (a residual walker adds the placo gait's reference at the clock and the filtered command,
as in training). Like an `Opponent`, the walker is arrays (no Python objects in the step); each robot keeps
its walker state, one row of `WALKER_STATE_SIZE` floats, in the game's `info['walker_state']`.

With a get-up skill as well (`Walker.getup_motion`), a fall need not end the game: a robot tilted past
`GETUP_START_UP_Z` hands its joints to the get-up skill until it stands upright near its default pose again
(`GETUP_END_UP_Z`, `GETUP_END_POSE_RAD`, read from its own proprioception, as on a real robot); meanwhile its
commands are ignored and its gait clock and filtered command restart from zero. The get-up skill is ROBOTIS'
scripted get-up from the front or the back (legged.soccer.getup_motion, chosen when the fall is seen), with
a frozen `op3-getup` policy's corrections added (`Walker.getup`), or the script alone; one that has not
stood `GETUP_RETRY_S` after its script ended starts it again.
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp

from legged.soccer.getup_motion import GetUpMotion, lies_on_back, motion_features, motion_targets
from legged.soccer.opponents import Opponent, OpponentNet, network_actions
from legged.soccer.placo.gait_table import GaitTable, advance_phase, filter_command, gait_targets
from legged.soccer.placo.player import PlacoTables, actions_of, request_from_features

COMMAND_SIZE = 3
"""A commanding player's action: (vx, vy, yaw rate), each in [-1, 1] of the walker's command range."""
WALKER_STATE_SIZE = 7
"""Per robot: gait phase in [0, 1), the low-pass filtered command (vx, vy, yaw rate), getting up (1) or not (0),
seconds since the get-up started, and which get-up plays (1 back, 0 front)."""
GETUP_START_UP_Z = 0.5
"""A robot whose torso's up axis has a z component below this (tilted past 60 degrees) starts getting up."""
GETUP_END_UP_Z = 0.9
"""It walks again once that z component is above this (within about 25 degrees of upright) ..."""
GETUP_END_POSE_RAD = 0.25
"""... and its joints are within this mean absolute angle of the default pose, radians."""
GETUP_RETRY_S = 1.0
"""Seconds after the get-up's script ended without standing before it starts again."""


def getting_up(state: jax.Array) -> jax.Array:
    """Whether each robot of walker states [..., WALKER_STATE_SIZE] is getting up (its get-up skill has the joints)."""
    return state[..., 4] > 0.5


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
    getup_motion: GetUpMotion | None = None
    """The scripted get-ups (legged.soccer.getup_motion) of robots that get up; None: fallen robots stay down."""
    getup: Opponent | None = None
    """A frozen op3-getup actor (reads the proprioception and the script's features); None: the script alone."""
    getup_net: OpponentNet | None = None
    """How the get-up actor's layers are joined."""
    getup_residual: bool = True
    """The get-up actor's actions are corrections added to the script's (op3-getup's `residual`)."""
    velocity_input: bool = False
    """It reads each robot's torso velocity estimate after its gait clock (op3-walk's `velocity_in_state`): the game
    must keep one (`velocity_in_state`)."""
    prior: PlacoTables | None = None
    """With the placo player's tables, a commanding player's actions are corrections added to the placo player's
    walking command (to the spot behind the ball, lined up on the goal; `with_prior`); None: the command itself."""

    def with_prior(self, action: jax.Array, features: jax.Array) -> jax.Array:
        """Commanding actions [n, 3] with the prior's command added (from the robots' game features [n, obs]:
        legged.soccer.observe), or as they are without a prior."""
        return action if self.prior is None else action + self.prior_actions(features, self.prior)

    def prior_actions(self, features: jax.Array, tables: PlacoTables) -> jax.Array:
        """The placo player's walking command for robots' game features [n, obs], as commanding actions [n, 3]
        (not clipped: `command` clips the sum)."""
        request = jax.vmap(lambda f: request_from_features(tables, f)[0])(features)
        low, high = jnp.asarray(self.command_low), jnp.asarray(self.command_high)
        return 2.0 * (request - low) / (high - low) - 1.0

    def command(self, action: jax.Array) -> jax.Array:
        """The velocity command [..., 3] of commanding actions [..., 3] (clipped to [-1, 1])."""
        low, high = jnp.asarray(self.command_low), jnp.asarray(self.command_high)
        return low + (high - low) * (jnp.clip(action, -1.0, 1.0) + 1.0) / 2.0

    def actions(self, proprio: jax.Array, action: jax.Array, state: jax.Array,
                velocity: jax.Array | None = None) -> jax.Array:
        """Joint actions [n, 20] for robots' proprioception [n, 66] (the walk skill's noisy `state` head),
        commanding actions [n, 3], walker states [n, WALKER_STATE_SIZE] and, for a walker with `velocity_input`,
        their torso velocity estimates [n, 3] (the game's `info['velocity_estimate']`)."""
        clock = 2.0 * jnp.pi * state[:, :1]
        parts = [proprio, self.command(action), state[:, 1:4], jnp.sin(clock), jnp.cos(clock)]
        if self.velocity_input:
            if velocity is None:
                raise ValueError("this walker reads a torso velocity estimate: the game must keep one "
                                 "(env.velocity_in_state)")
            parts.append(velocity)
        inputs = jnp.concatenate(parts, axis=-1)
        out = network_actions(self.net, self.policy, inputs)
        if self.residual:
            targets = jax.vmap(lambda s: gait_targets(self.gait, s[0], s[1:4]))(state)
            out = out + actions_of(targets, jnp.asarray(self.default_pose), self.action_scale)
        if self.getup_motion is not None:
            out = jnp.where(getting_up(state)[:, None], self._getup_actions(proprio, state[:, 6], state[:, 5]), out)
        return out

    def _getup_actions(self, proprio: jax.Array, back: jax.Array, t: jax.Array) -> jax.Array:
        """Joint actions [n, 20] of the get-up skill, `t` seconds into the back (1) or front (0) get-up."""
        motion = self.getup_motion
        out = jnp.zeros((proprio.shape[0], len(self.default_pose)), proprio.dtype)
        if self.getup is not None:
            features = jax.vmap(lambda b, s: motion_features(motion, b, s))(back, t)
            out = network_actions(self.getup_net, self.getup, jnp.concatenate([proprio, features], axis=-1))
        if self.getup is None or self.getup_residual:
            targets = jax.vmap(lambda b, s: motion_targets(motion, b, s))(back, t)
            out = out + actions_of(targets, jnp.asarray(self.default_pose), self.action_scale)
        return out

    def step(self, state: jax.Array, action: jax.Array, proprio: jax.Array) -> jax.Array:
        """Walker states one control period on, the robots commanded by `action` [n, 3] meanwhile; with a
        get-up skill, who gets up next is decided from their proprioception [n, 66] now."""
        phase = advance_phase(state[:, 0], self.dt, self.gait)
        filtered = filter_command(state[:, 1:4], self.command(action), self.dt, self.gait)
        rising = jnp.zeros_like(phase, dtype=bool)
        t, back = jnp.zeros_like(phase), jnp.zeros_like(phase)
        if self.getup_motion is not None:
            up_z = -proprio[:, 2]  # the proprioception starts with gravity in the torso frame
            stood = (up_z > GETUP_END_UP_Z) & (jnp.mean(jnp.abs(proprio[:, 6:26]), axis=-1) < GETUP_END_POSE_RAD)
            was = getting_up(state)
            rising = jnp.where(was, ~stood, up_z < GETUP_START_UP_Z)
            retry = was & (state[:, 5] >= self.getup_motion.length[state[:, 6].astype(jnp.int32)] + GETUP_RETRY_S)
            again = rising & (~was | retry)                    # a script (re)starts: choose it, clock at 0
            back = jnp.where(again, lies_on_back(proprio[:, :3]), state[:, 6])
            t = jnp.where(rising & ~again, state[:, 5] + self.dt, 0.0)
            phase = jnp.where(rising, 0.0, phase)
            filtered = jnp.where(rising[:, None], 0.0, filtered)
        return jnp.concatenate([phase[:, None], filtered, rising[:, None].astype(phase.dtype), t[:, None],
                                back[:, None]], axis=-1)
