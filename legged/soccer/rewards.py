"""Per-agent soccer rewards: the sparse goal reward, shaping after dm_control's statistics, penalties."""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np

from legged.envs.rewards import penalty_terms
from legged.soccer.config import SoccerRewards
from legged.soccer.observe import Bodies
from legged.soccer.rules import BallCall


def _unit(v):
    return v / jnp.maximum(jnp.linalg.norm(v, axis=-1, keepdims=True), 1e-6)


def reward_terms(w: SoccerRewards, b: Bodies, call: BallCall, team: np.ndarray, goals: np.ndarray,
                 newly_fallen, torque, action, last_action, last_qvel, q_range, dt) -> dict:
    """Weighted reward terms, each [A] (agent order), for one control step.

    goal: +1 for the scoring team's players, -1 for the other team's. vel_to_ball: torso velocity toward
    the ball (with `approach_offset`, toward a spot behind it on the line from the agent's opponent goal, which
    closes in on the ball as the robot lines up behind it).
    ball_vel_to_goal: ball velocity toward the agent's opponent goal. upright: torso up axis z. fall: on the
    step an agent falls. Then the shared penalties on the agent's joints and actions.
    """
    team_f = jnp.asarray(team, jnp.float32)
    scored = jnp.where(team_f == 0, 1.0, -1.0) * (call.home_scores.astype(jnp.float32)
                                                  - call.away_scores.astype(jnp.float32))
    to_goal = _unit(jnp.asarray(goals[1 - team, :2], jnp.float32) - b.ball_pos[:2])
    # the spot behind the ball (seen from the goal it should enter), drawn in to the ball itself as the robot
    # lines up behind it: from there, walking into the ball pushes it goalwards
    lined_up = jnp.clip(jnp.sum(_unit(b.ball_pos[:2] - b.pos[:, :2]) * to_goal, -1, keepdims=True), 0.0, 1.0)
    spot = b.ball_pos[:2] - w.approach_offset * (1.0 - lined_up) * to_goal
    to_ball = _unit(spot - b.pos[:, :2])
    terms = {
        "goal": w.goal * scored,
        "vel_to_ball": w.vel_to_ball * jnp.sum(b.vel[:, :2] * to_ball, -1),
        "ball_vel_to_goal": w.ball_vel_to_goal * jnp.sum(b.ball_vel[:2] * to_goal, -1),
        "upright": w.upright * b.up_z,
        "fall": w.fall * newly_fallen.astype(jnp.float32),
    }
    penalties = penalty_terms(w.penalties, b.q, q_range, b.qd, last_qvel, dt, torque, action, last_action,
                              jnp.zeros_like(b.up_z))
    penalties.pop("collisions")  # robots may touch anything: there is no collision penalty in soccer
    terms.update(penalties)
    return terms
