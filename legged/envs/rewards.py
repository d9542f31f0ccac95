"""Reward shaping pieces shared by tasks."""

import jax.numpy as jnp


def tracking(error_sq, sigma):
    """exp(-error^2 / sigma): 1 when a command is tracked exactly, decaying with the squared error."""
    return jnp.exp(-error_sq / sigma)


def roll_pitch_rate_sq(qvel):
    """Sum of the squared roll and pitch rates of a free-floating base (rad/s, body frame: qvel[3:5] of its free
    joint), the tipping that the walkers' and the confined tasks' `ang_vel_xy` terms charge."""
    return jnp.sum(jnp.square(qvel[3:5]))


def penalty_terms(scales, q, q_range, qd, last_qvel, dt, torque, action, last_action, collisions) -> dict:
    """The penalty terms every task shares (weights from a PenaltyScales `scales`).

    q, qd: joint positions and velocities; q_range: [n_joints, 2] joint limits (a joint beyond 95% of its
    range is penalised by the excursion); torque: actuator forces; collisions: count of penalised contacts.
    Works for one robot or, with a leading agent axis on every array, per agent (sums over the last axis).
    """
    lo, hi = q_range[..., 0], q_range[..., 1]
    soft = 0.05 * (hi - lo)
    limit = jnp.sum(jnp.clip(lo + soft - q, 0.0) + jnp.clip(q - hi + soft, 0.0), -1)
    return {
        "joint_acc": scales.joint_acc * jnp.sum(jnp.square((qd - last_qvel) / dt), -1),
        "torques": scales.torques * jnp.sum(jnp.square(torque), -1),
        "joint_limits": scales.joint_limits * limit,
        "collisions": scales.collisions * jnp.asarray(collisions, jnp.float32),
        "action_rate": scales.action_rate * jnp.sum(jnp.square(action - last_action), -1),
    }


def step_reward(terms: dict, ended_in_failure, only_positive: bool, failure_penalty: float):
    """A step's reward from its named `terms`: their sum, clipped at 0 when `only_positive`, plus `failure_penalty`
    where the episode ends in failure (a fall, the task's failure). Adds that penalty to `terms` as "failure" when it
    is not 0, so it is logged like the others."""
    reward = sum(terms.values())
    if only_positive:
        reward = jnp.maximum(reward, 0.0)
    if failure_penalty:
        terms["failure"] = failure_penalty * jnp.asarray(ended_in_failure, jnp.float32)
        reward = reward + terms["failure"]
    return reward


def wrap_angle(angle):
    """Angle wrapped to (-pi, pi]."""
    return jnp.arctan2(jnp.sin(angle), jnp.cos(angle))
