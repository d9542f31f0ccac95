"""Who drives the robots the learner does not control: a frozen policy given as data, or a script.

An `Opponent` is a pytree of arrays (no Python objects), passed to `step` as an argument: swapping one
snapshot of a pool for another changes data, not the compiled program. Its network is an MLP with an
input normaliser, (obs - mean) / std, then Linear-activation layers, the actor layout of both training
backends; `weight` 1 uses the network, 0 a script: `placo` 1 the placo player (walks to the ball and kicks
it, legged.soccer.placo.player; it keeps a memory per robot, `opponent_step`), 0 the standing script.
Every opponent reads the full egocentric features (`SoccerEnv.policy_state_size` first entries of
`privileged_state`), so a state-task teacher can play against a vision student.
"""

from __future__ import annotations

import dataclasses
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from legged.soccer.observe import PROPRIO_SIZE
from legged.soccer.placo.player import actions_of, motion_step, request_from_features

ACTIVATIONS = {"elu": jax.nn.elu, "relu": jax.nn.relu, "tanh": jnp.tanh, "swish": jax.nn.swish,
               "silu": jax.nn.silu, "selu": jax.nn.selu}
"""Hidden activations an opponent network may use, by the names the training configs use."""


class Opponent(NamedTuple):
    """A frozen player as data."""

    weight: jax.Array
    """1.0: act with the network; 0.0: act with the script."""
    mean: jax.Array
    """Input normaliser mean, [obs]."""
    std: jax.Array
    """Input normaliser divisor, [obs] (eps already added)."""
    layers: tuple
    """((w [in, out], b [out]), ...) from input to action."""
    placo: jax.Array = 0.0
    """Without a network: 1.0 plays the placo player, 0.0 the standing script."""


@dataclasses.dataclass(frozen=True)
class OpponentNet:
    """The static half of an opponent network: how its layers are joined (not data)."""

    activation: str = "elu"
    """Hidden activation (ACTIVATIONS)."""
    squash: bool = False
    """Apply tanh to the output (Brax PPO's deterministic action); rsl-rl's actions are the raw mean."""

    def __post_init__(self):
        if self.activation not in ACTIVATIONS:
            raise ValueError(f"unknown activation {self.activation!r}; one of {sorted(ACTIVATIONS)}")


def network_opponent(mean, std, layers) -> Opponent:
    """An opponent that plays with a network (numpy or jax arrays), copied: it never changes with them."""
    f32 = lambda x: jnp.array(x, jnp.float32, copy=True)  # asarray may alias a numpy view of torch memory
    return Opponent(jnp.float32(1.0), f32(mean), f32(std), tuple((f32(w), f32(b)) for w, b in layers),
                    jnp.float32(0.0))


def placo_opponent(obs_size: int, action_size: int, hidden: tuple[int, ...] = ()) -> Opponent:
    """The placo player, shaped like a network of `hidden` layers (to share a pool's structure)."""
    return scripted_opponent(obs_size, action_size, hidden)._replace(placo=jnp.float32(1.0))


def scripted_opponent(obs_size: int, action_size: int, hidden: tuple[int, ...] = ()) -> Opponent:
    """The scripted player, shaped like a network of `hidden` layers so it can share a pool's structure."""
    sizes = (obs_size, *hidden, action_size)
    layers = tuple((jnp.zeros((a, b)), jnp.zeros(b)) for a, b in zip(sizes[:-1], sizes[1:]))
    return Opponent(jnp.float32(0.0), jnp.zeros(obs_size), jnp.ones(obs_size), layers, jnp.float32(0.0))


def network_actions(net: OpponentNet, opp: Opponent, obs) -> jax.Array:
    """The network's deterministic actions for observations [..., obs]."""
    x = (obs - opp.mean) / opp.std
    for i, (w, b) in enumerate(opp.layers):
        x = x @ w + b
        if i < len(opp.layers) - 1:
            x = ACTIVATIONS[net.activation](x)
    return jnp.tanh(x) if net.squash else x


HEAD_PAN_LIMIT = 1.2
"""Largest head pan (radians either way) with which a player looks toward the ball (the joint reaches 1.57)."""


def ball_pan(ball_xy: jax.Array) -> jax.Array:
    """Head pan [...] that faces a ball at `ball_xy` [..., 2] in the heading frame, within HEAD_PAN_LIMIT."""
    return jnp.clip(jnp.arctan2(ball_xy[..., 1], ball_xy[..., 0]), -HEAD_PAN_LIMIT, HEAD_PAN_LIMIT)


def scripted_actions(obs, action_scale: float, head_pan: int = 0, head_tilt: int = 1) -> jax.Array:
    """The scripted player: stands in its default pose and keeps its head on the ball (pan toward the
    ball's bearing, tilt toward its depression), like a goalkeeper that does not move. A weak, fixed
    reference opponent for evaluation; its actions are [..., 20]."""
    ball = obs[..., PROPRIO_SIZE:PROPRIO_SIZE + 3]  # ball position in the heading frame
    depression = jnp.arctan2(jnp.maximum(0.45 - ball[..., 2], 0.0), jnp.linalg.norm(ball[..., :2], axis=-1))
    actions = jnp.zeros(obs.shape[:-1] + (20,))
    actions = actions.at[..., head_pan].set(ball_pan(ball[..., :2]) / action_scale)
    return actions.at[..., head_tilt].set(-jnp.clip(depression, 0.0, 0.9) / action_scale)


def opponent_actions(net: OpponentNet, opp: Opponent, obs, action_scale: float) -> jax.Array:
    """Actions of the robots an `Opponent` drives, for their observations [..., policy_state_size]."""
    return jnp.where(opp.weight > 0.5, network_actions(net, opp, obs), scripted_actions(obs, action_scale))


def placo_actions(tables, obs, memory, action_scale: float) -> tuple[jax.Array, jax.Array]:
    """(actions [n, 20], memories [n, MEMORY_SIZE]) of the placo player for robots' features [n, obs]."""
    def one(features, row):
        targets, row = motion_step(tables, row, *request_from_features(tables, features))
        return actions_of(targets, tables.default_pose, action_scale), row

    return jax.vmap(one)(obs, memory)


def opponent_step(net: OpponentNet, opp: Opponent, obs, memory, tables, action_scale: float, walker=None,
                  walker_state=None, velocity=None) -> tuple[jax.Array, jax.Array, jax.Array]:
    """(actions, next memories, next walker states) of the robots an `Opponent` drives, from their features
    [n, obs] and their player memories [n, MEMORY_SIZE] (only the placo player uses and changes them). With a
    `walker` (legged.soccer.walker) a network opponent commands velocities that it turns into joint actions,
    from the robots' walker states [n, WALKER_STATE_SIZE] (None without a walker) and, for a walker that reads
    them, their torso velocity estimates [n, 3]."""
    played, moved = placo_actions(tables, obs, memory, action_scale)
    if walker is None:
        stateless, stepped = opponent_actions(net, opp, obs, action_scale), walker_state
    else:
        command = walker.with_prior(network_actions(net, opp, obs), obs)
        walked = walker.actions(obs[..., :PROPRIO_SIZE], command, walker_state, velocity)
        stateless = jnp.where(opp.weight > 0.5, walked, scripted_actions(obs, action_scale))
        stepped = walker.step(walker_state, command, obs[..., :PROPRIO_SIZE])
    use_placo = (opp.weight < 0.5) & (opp.placo > 0.5)
    return jnp.where(use_placo, played, stateless), jnp.where(use_placo, moved, memory), stepped


def stack_opponents(opponents) -> Opponent:
    """A pool of opponents of one structure as one pytree with a leading pool axis."""
    return jax.tree_util.tree_map(lambda *xs: jnp.stack(xs), *opponents)


def pick(pool: Opponent, index) -> Opponent:
    """Member `index` of a stacked pool."""
    return jax.tree_util.tree_map(lambda x: x[index], pool)


def opponent_to_numpy(opp: Opponent) -> dict:
    """A picklable copy (for checkpoints)."""
    return {"weight": float(opp.weight), "mean": np.asarray(opp.mean), "std": np.asarray(opp.std),
            "layers": [(np.asarray(w), np.asarray(b)) for w, b in opp.layers], "placo": float(opp.placo)}


def opponent_from_numpy(d: dict) -> Opponent:
    """The inverse of `opponent_to_numpy`."""
    opp = network_opponent(d["mean"], d["std"], d["layers"])
    return opp._replace(weight=jnp.float32(d["weight"]), placo=jnp.float32(d.get("placo", 0.0)))
