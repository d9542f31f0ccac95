"""ROBOTIS' scripted OP3 get-ups as reference motions of the get-up skill (op3-getup).

ROBOTIS ships two get-ups for the real OP3 in its action module (op3_action_module's motion_4095.bin, page
122 `f_get_up` from the front and page 123 `b_get_up` from the back). Their key poses, converted from servo
ticks to radians ((tick - 2048) pi / 2048, ROBOTIS' joint signs being this model's), are below; each key pose
is reached by a linear ramp of its move time, then held for its hold time. We add a short settle before the
first and a last ramp into this project's default standing pose, where the walking skill takes over.

The get-up skill is residual on this reference (`GetUpConfig.residual`): it starts out playing the script
and learns the corrections (the randomised physics, side and twisted starts). Which motion plays is chosen
once, when getting up starts, from gravity in the torso frame: face down by more than 30 degrees plays the
front get-up, anything else (back, sides) the back get-up.
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np

from legged.robots.op3 import OP3

SETTLE_S = 0.25
"""Seconds the reference holds the default pose before the first key pose (the fall comes to rest)."""
STAND_MOVE_S = 0.5
"""Seconds of the last ramp, from ROBOTIS' last key pose into the default standing pose."""
FRONT_GRAVITY_X = 0.5
"""Gravity's x component in the torso frame above which the robot lies face down (the front get-up)."""

_KEY_JOINTS = ("sho_pitch", "sho_roll", "el", "hip_roll", "hip_pitch", "knee", "ank_pitch", "ank_roll")
"""Left-side joints of a key pose (the right side mirrors them: right = -left), then head_tilt (hip yaw and
head pan stay at the default pose's 0)."""

# (move s, hold s, left sho_pitch, sho_roll, el, hip_roll, hip_pitch, knee, ank_pitch, ank_roll, head_tilt)
_FRONT = ((0.32, 0.0, 0.126, -0.884, -2.530, -0.031, 0.253, 0.831, 0.522, -0.026, -0.348),
          (0.40, 0.0, -1.620, -0.597, -2.503, -0.032, -1.933, 1.944, 1.758, -0.120, 0.158),
          (0.64, 0.64, -0.900, 1.496, -0.086, -0.032, -1.933, 2.457, 1.071, -0.120, 0.158),
          (1.04, 0.0, -0.089, 0.785, -0.787, -0.015, -0.431, 0.836, 0.515, -0.023, -0.348))
_BACK = ((0.56, 0.0, 1.832, -1.261, -2.572, -0.038, 0.449, 1.500, 0.018, -0.063, 0.156),
         (0.56, 0.0, 2.138, -0.195, -2.571, -0.038, 0.449, 1.500, 0.018, -0.063, 0.156),
         (0.80, 0.64, 1.437, 1.407, -0.124, -0.040, 0.489, 2.192, 1.807, -0.006, 0.158),
         (1.04, 0.0, -0.089, 0.785, -0.787, -0.015, -0.431, 0.836, 0.515, -0.023, -0.348))


@dataclasses.dataclass(frozen=True, eq=False)
class GetUpMotion:
    """The front (row 0) and back (row 1) get-ups as piecewise-linear servo targets over time."""

    poses: jax.Array
    """Key poses [2, K + 1, 20] in OP3 joint order, the first the default pose (where the ramps start)."""
    starts: jax.Array
    """When each ramp starts [2, K], seconds after getting up started."""
    moves: jax.Array
    """How long each ramp lasts [2, K], seconds."""
    length: jax.Array
    """When each motion ends [2], seconds: it then holds the default pose."""


def _key_pose(values, default: np.ndarray) -> np.ndarray:
    index = {name: i for i, name in enumerate(OP3.joint_names)}
    pose = default.copy()
    for name, angle in zip(_KEY_JOINTS, values[:-1], strict=True):
        pose[index[f"l_{name}"]], pose[index[f"r_{name}"]] = angle, -angle
    pose[index["head_tilt"]] = values[-1]
    return pose


def getup_motion() -> GetUpMotion:
    """ROBOTIS' two get-ups, with the settle before and the ramp into the default pose after."""
    default = np.asarray(OP3.default_pose, np.float64)
    poses, starts, moves, lengths = [], [], [], []
    for keys in (_FRONT, _BACK):
        rows, t = [default], SETTLE_S
        start, move = [], []
        for key in keys:
            rows.append(_key_pose(key[2:], default))
            start.append(t)
            move.append(key[0])
            t += key[0] + key[1]
        rows.append(default)
        start.append(t)
        move.append(STAND_MOVE_S)
        poses.append(np.stack(rows))
        starts.append(start)
        moves.append(move)
        lengths.append(t + STAND_MOVE_S)
    f32 = lambda x: jnp.asarray(np.asarray(x), jnp.float32)  # noqa: E731
    return GetUpMotion(poses=f32(poses), starts=f32(starts), moves=f32(moves), length=f32(lengths))


def lies_on_back(gravity: jax.Array) -> jax.Array:
    """1.0 where the back get-up should play (the robot is not face down), 0.0 for the front one, from gravity
    in the torso frame [..., 3] (the proprioception's first three numbers)."""
    return (gravity[..., 0] <= FRONT_GRAVITY_X).astype(jnp.float32)


def motion_targets(motion: GetUpMotion, back: jax.Array, t: jax.Array) -> jax.Array:
    """Servo targets (20,) of the back (1.0) or front (0.0) get-up `t` seconds after it started."""
    row = back.astype(jnp.int32)
    poses, starts, moves = motion.poses[row], motion.starts[row], motion.moves[row]
    ramp = jnp.clip((t - starts) / moves, 0.0, 1.0)
    return poses[0] + jnp.sum(ramp[:, None] * (poses[1:] - poses[:-1]), axis=0)


def motion_features(motion: GetUpMotion, back: jax.Array, t: jax.Array) -> jax.Array:
    """What the get-up policy reads after its proprioception (2,): which motion plays, and how far it is
    (0 at the start, 1 once the reference stands in the default pose)."""
    progress = jnp.clip(t / motion.length[back.astype(jnp.int32)], 0.0, 1.0)
    return jnp.stack([back.astype(jnp.float32), progress])
