"""The scripted OP3 soccer player: placo's walk and kick, played back from tables in JAX.

A player is a pure function of its egocentric game features and a small memory (`PlayerMemory`, one row of
floats per robot), so it runs inside jitted MJX steps and native stepping alike:

- motion (`motion_step`): blend from the robot's default pose to the walk's stance, `start` sequence, the
  gait (table lookup at the gait phase and the low-pass filtered command), `stop` sequence, a kick, stand;
- soccer (`soccer_request`): walk to the spot behind the ball from which the ball sits at the kick's aim
  point and the robot faces the opponent goal (around the ball if the robot is on its far side), then
  stop and kick with the foot on the ball's side;
- drills (`command_request`): follow a given velocity command, never kick.

Targets are servo positions (the tables hold them, feedforward included); `actions_of` turns them into
the actions the environments take (offsets from the default pose over the action scale).
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp

from legged.robots.op3 import OP3, OP3_CTRL_DT
from legged.soccer.observe import PROPRIO_SIZE
from legged.soccer.placo.gait_table import (GaitTable, advance_phase, filter_command, gait_targets, load_gait_table,
                                            sequence_targets)
from legged.soccer.placo.kick_table import KickTable, advance_kick_phase, kick_targets, load_kick_table

BLEND, START, WALK, STOP, KICK, STAND = range(6)
"""Motion modes of a player's memory."""
BLEND_SECONDS = 0.5
"""From the default pose (where episodes start) to the walk's stance."""
MEMORY_SIZE = 8
"""Floats per robot: mode, sequence time, gait phase, filtered command (3), kick side, kick phase."""


class PlacoTables(NamedTuple):
    """The walk and the kick as data (a pytree: closed over or passed through jit)."""

    gait: GaitTable
    """The gait table (legged.soccer.placo.gait_table)."""
    kick: KickTable
    """The kick table (legged.soccer.placo.kick_table)."""
    default_pose: jax.Array
    """(20,) the robot's default pose (episodes start in it)."""


def load_tables() -> PlacoTables:
    """The committed tables (assets/placo/)."""
    return PlacoTables(load_gait_table(), load_kick_table(), jnp.asarray(OP3.default_pose, jnp.float32))


class PlayerMemory(NamedTuple):
    """A player's state between control steps (arrays with any leading shape)."""

    mode: jax.Array
    """Motion mode (BLEND ... STAND), as a float."""
    time: jax.Array
    """Seconds into the current sequence (blend, start, stop)."""
    phase: jax.Array
    """Gait phase in [0, 1)."""
    command: jax.Array
    """(3,) the filtered command the gait is looked up with."""
    side: jax.Array
    """Kicking foot: 0 right, 1 left."""
    kick: jax.Array
    """Kick phase in [0, 1]; while stopping, 1 when a kick follows (the decision is kept once taken)."""

    def pack(self) -> jax.Array:
        """As one row of MEMORY_SIZE floats."""
        return jnp.concatenate([jnp.stack([self.mode, self.time, self.phase]), self.command,
                                jnp.stack([self.side, self.kick])], -1)

    @staticmethod
    def unpack(row: jax.Array) -> "PlayerMemory":
        return PlayerMemory(row[..., 0], row[..., 1], row[..., 2], row[..., 3:6], row[..., 6], row[..., 7])


def initial_memory(n: int) -> jax.Array:
    """Packed memories of `n` players at an episode's start (blending out of the default pose)."""
    return jnp.zeros((n, MEMORY_SIZE), jnp.float32)


def motion_step(t: PlacoTables, memory: jax.Array, request: jax.Array, want_kick: jax.Array, kick_side: jax.Array,
                dt: float = OP3_CTRL_DT) -> tuple[jax.Array, jax.Array]:
    """(servo targets (20,), next packed memory) of one robot for one control step. `request`: the velocity
    command wanted (vx, vy, yaw rate); `want_kick`: stop and kick with `kick_side` once stopped."""
    m = PlayerMemory.unpack(memory)
    g, k = t.gait, t.kick
    mode = m.mode.astype(jnp.int32)
    n_start, n_stop = g.start.shape[0], g.stop.shape[0]
    blend = jnp.clip(m.time / BLEND_SECONDS, 0.0, 1.0)
    command = filter_command(m.command, jnp.where(want_kick, 0.0, request), dt, g)
    settled = jnp.max(jnp.abs(command) / g.command_high) < 0.15
    at_stop = jnp.mod(m.phase - g.stop_phase, 1.0) < dt / g.period
    moving = jnp.max(jnp.abs(request)) > 1e-3
    targets = jnp.stack([
        (1.0 - blend) * t.default_pose + blend * g.stand,
        sequence_targets(g.start, m.time, dt),
        gait_targets(g, m.phase, command),
        sequence_targets(g.stop, m.time, dt),
        kick_targets(k, m.kick, m.side),
        g.stand,
    ])[mode]
    done_seq = m.time + dt >= jnp.array([BLEND_SECONDS, n_start * dt, 0.0, n_stop * dt, 0.0, 0.0])[mode] - 1e-6
    kick_over = advance_kick_phase(m.kick, dt, k) >= 1.0
    stop_now = (want_kick | ~moving) & settled & at_stop
    intent = m.kick > 0.5                                        # stopping in order to kick
    next_mode = jnp.select(
        [(mode == BLEND) & done_seq, (mode == START) & done_seq, (mode == WALK) & stop_now,
         (mode == STOP) & done_seq & intent, (mode == STOP) & done_seq, (mode == KICK) & kick_over,
         (mode == STAND) & want_kick, (mode == STAND) & moving],
        [START, WALK, STOP, KICK, STAND, STAND, KICK, START], mode)
    changed = next_mode != mode
    time = jnp.where(changed, 0.0, m.time + dt)
    phase = jnp.where(mode == WALK, advance_phase(m.phase, dt, g), jnp.where(next_mode == WALK, g.start_phase, m.phase))
    decided = changed & (((mode == WALK) & (next_mode == STOP) & want_kick) | ((mode == STAND) & (next_mode == KICK)))
    side = jnp.where(decided, kick_side, m.side)
    kick = jnp.select([mode == KICK, (next_mode == STOP) & (decided | ((mode == STOP) & intent))],
                      [advance_kick_phase(m.kick, dt, k), 1.0], 0.0)
    kick = jnp.where((next_mode == KICK) & changed, 0.0, kick)
    command = jnp.where(mode == WALK, command, 0.0)
    nxt = PlayerMemory(next_mode.astype(jnp.float32), time, phase, command, side.astype(jnp.float32), kick)
    return targets, nxt.pack()


def command_request(command: jax.Array) -> tuple[jax.Array, jax.Array, jax.Array]:
    """A drill's request: follow `command`, never kick."""
    return command, jnp.bool_(False), jnp.float32(0.0)


def soccer_request(t: PlacoTables, ball: jax.Array, ball_vel: jax.Array, goal: jax.Array
                   ) -> tuple[jax.Array, jax.Array, jax.Array]:
    """(command, want_kick, side) from the ball's position and velocity and the opponent goal's centre, all
    (x, y) in the robot's heading frame."""
    g = t.gait
    to_goal = goal - ball
    u = to_goal / jnp.maximum(jnp.linalg.norm(to_goal), 1e-6)
    side = jnp.where(ball[1] < 0.0, 0, 1)                       # the foot on the ball's side
    aim = t.kick.ball[side]                                      # where the ball should be, standing frame
    rot = jnp.array([[u[0], -u[1]], [u[1], u[0]]])
    spot = ball - rot @ aim                                      # the robot's origin at the kick
    across = jnp.array([-u[1], u[0]])
    ahead = jnp.dot(-ball, u) > -0.15                           # the robot is level with or past the ball
    detour = ball - 0.4 * u + 0.35 * jnp.sign(jnp.dot(-ball, across) + 1e-6) * across
    target = jnp.where(ahead, detour, spot)
    dist = jnp.linalg.norm(target)
    heading = jnp.where(dist > 0.3, jnp.arctan2(target[1], target[0]), jnp.arctan2(u[1], u[0]))
    turning = jnp.abs(heading) > 0.5                              # turn on the spot first: combined
    far = jnp.where(turning, jnp.stack([0.0, 0.0, 1.5 * heading]),  # commands are cut down by the walk
                    jnp.stack([jnp.minimum(0.8 * dist, g.command_high[0]), 0.0, 1.5 * heading]))
    near = jnp.stack([1.5 * target[0], 1.5 * target[1], 1.5 * jnp.arctan2(u[1], u[0])])
    command = jnp.clip(jnp.where(dist > 0.3, far, near), g.command_low, g.command_high)
    placed = (jnp.abs(target[0]) < 0.04) & (jnp.abs(target[1]) < 0.025)  # the kick tolerates about this
    ready = placed & (jnp.abs(jnp.arctan2(u[1], u[0])) < 0.25) & (jnp.linalg.norm(ball_vel) < 0.1) & ~ahead
    return command, ready, side.astype(jnp.float32)


def request_from_features(t: PlacoTables, features: jax.Array) -> tuple[jax.Array, jax.Array, jax.Array]:
    """`soccer_request` from a robot's egocentric game features (legged.soccer.observe: proprioception, then
    ball position (3) and velocity (3), own goal (2), opponent goal (2), ...)."""
    g = PROPRIO_SIZE
    return soccer_request(t, features[g:g + 2], features[g + 3:g + 5], features[g + 8:g + 10])


def actions_of(targets: jax.Array, default_pose: jax.Array, action_scale: float) -> jax.Array:
    """Environment actions (offsets from the default pose over the action scale) for servo targets."""
    return (targets - default_pose) / action_scale
