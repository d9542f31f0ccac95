"""The motors behind the joint servos: the torque a motor can give at a speed (its torque-speed line).

A DC motor driven from a fixed supply gives its stall torque at rest, and less the faster it turns in the direction
of the torque (back-EMF), none at its free speed; torque against the motion (braking) is limited only by the current,
i.e. by the same force limit. With the force limit F at rest and free speed w0 (RobotSpec.motor_speeds):

    torque in [-F * clip(1 + qd / w0, 0, 1),  F * clip(1 - qd / w0, 0, 1)]

(EnvConfig.motor_curve applies it to the PD servos' targets: `within_motor_curve`).
"""

from __future__ import annotations

import jax.numpy as jnp
import mujoco
import numpy as np

from legged.robots.spec import RobotSpec


def motor_torque_range(force_limit, free_speed, qd, xp=jnp):
    """(upper, lower) torque a motor with `force_limit` at rest and `free_speed` can give at joint velocity `qd`."""
    upper = force_limit * xp.clip(1.0 - qd / free_speed, 0.0, 1.0)
    lower = -force_limit * xp.clip(1.0 + qd / free_speed, 0.0, 1.0)
    return upper, lower


def within_motor_curve(targets, q, qd, kp, kd, force_limit, free_speed):
    """PD position targets clipped so that the servo's torque kp (target - q) - kd qd, at joint angles `q` and
    velocities `qd`, stays inside its motor's torque-speed line (all arrays broadcast per joint)."""
    upper, lower = motor_torque_range(force_limit, free_speed, qd)
    return jnp.clip(targets, q + (lower + kd * qd) / kp, q + (upper + kd * qd) / kp)


def servo_gains(gainprm, biasprm, kp_scale, kd_scale, strength) -> tuple:
    """(Kp, Kd) of PD position servos (MuJoCo's affine `general` actuators' nominal `gainprm`, `biasprm` rows) with an
    episode's scales and motor strength applied, as legged.envs.randomize.servo_fields applies them to the model."""
    return gainprm[..., 0] * kp_scale * strength, -biasprm[..., 2] * kd_scale * strength


def motor_limits(model: mujoco.MjModel, robot: RobotSpec, actuators, needed: bool) -> tuple:
    """(force limit at rest of `actuators` (ids, any shape), free speed of each of the robot's joints) as float32
    arrays (inf where none); ValueError when `needed` (EnvConfig.motor_curve) and the spec has no motor speeds."""
    if needed and len(robot.motor_speeds) != robot.num_joints:
        raise ValueError(f"motor_curve needs {robot.name}'s motor speeds (RobotSpec.motor_speeds, one per joint)")
    limits = np.where(model.actuator_forcelimited, model.actuator_forcerange[:, 1], np.inf)[np.asarray(actuators)]
    speeds = robot.motor_speeds or (np.inf,) * robot.num_joints
    return jnp.asarray(limits, jnp.float32), jnp.asarray(speeds, jnp.float32)
