"""A vision player's estimate of the game: its parts, the labels of a student's actions, its errors.

A vision player whose walker adds the placo command (`command_prior=placo`) cannot read the ball and goals that
command is computed from; it estimates them (legged.soccer.learner.LearnerView, `estimates_world`): its actions are
[corrections to the placo command (COMMAND_SIZE), its estimate of the game features after the proprioception
(ball, goals, other players, as legged.soccer.observe.game_features)]. Here: which positions of that estimate are
reported and drawn (`estimate_parts`), the named groups of such a player's actions that are also its teacher's
labels (`label_groups`), and the squared errors of an estimate against the truth (`squared_errors`).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from legged.envs.api import layout_slices
from legged.soccer.observe import feature_layout
from legged.soccer.walker import COMMAND_SIZE

NEAR_BALL_M = 1.0
"""The ball this close to the learner (metres, in the ground plane) is near: the estimate's `ball_near` error
counts those steps only, where kicking needs the estimate most."""


def estimate_parts(players_per_team: int) -> dict[str, slice]:
    """Positions in an estimate of the game features whose errors are reported and drawn: ball (x, y, z), own
    and opponent goal (x, y), the first other player's position (x, y; the teammate in 2v2)."""
    parts = layout_slices(feature_layout(players_per_team)[1:])  # the game features after the proprioception
    first_other = list(parts.values())[4]
    return {"ball": parts["ball"], "own_goal": parts["own_goal"], "opponent_goal": parts["opponent_goal"],
            "first_other": slice(first_other.start, first_other.start + 2)}


def label_groups(players_per_team: int) -> dict[str, slice]:
    """Named groups of the actions of a learner that estimates the game (`estimates_world`), which are also its
    teacher's labels: `corrections` to the placo command, then the game features after the proprioception."""
    return layout_slices([("corrections", COMMAND_SIZE)] + feature_layout(players_per_team)[1:])


def squared_errors(estimate: jax.Array, truth: jax.Array, parts: dict[str, slice]) -> tuple[jax.Array, jax.Array]:
    """(squared errors (metres^2), steps counted) of `estimate` against `truth` (game features) for each of `parts`
    (`estimate_parts`, the ball first), then of the ball when it is near (NEAR_BALL_M; else neither counts)."""
    error = estimate - truth
    sq = jnp.stack([jnp.sum(error[part] ** 2) for part in parts.values()])
    ball = parts["ball"]
    near = (jnp.linalg.norm(truth[ball][:2]) < NEAR_BALL_M).astype(sq.dtype)
    return jnp.append(sq, near * sq[0]), jnp.append(jnp.ones_like(sq), near)
