"""Brax PPO's networks of a run: how they are built from its config, and the parameters a checkpoint fills.

The policy reads `state`, the value function `privileged_state`; both are MLPs of the config's hidden sizes
behind Brax's running observation normaliser. Training (policies.brax_backend), loading a policy
(policies.policy_io) and converting old checkpoints (policies.convert) build them here.
"""

from __future__ import annotations

import functools

import jax
import jax.numpy as jnp
from brax.training.acme import running_statistics, specs
from brax.training.agents.ppo import networks as ppo_networks

from policies.config import TrainConfig


def network_factory(config: TrainConfig):
    """Brax PPO networks: the policy reads `state`, the value function `privileged_state`."""
    return functools.partial(
        ppo_networks.make_ppo_networks, policy_hidden_layer_sizes=tuple(config.ppo.actor_hidden),
        value_hidden_layer_sizes=tuple(config.ppo.critic_hidden), policy_obs_key="state",
        value_obs_key="privileged_state")


def params_template(config: TrainConfig, obs_sizes: dict, num_actions: int):
    """(normalizer, policy, value) parameters of freshly built networks: the structure checkpoints fill."""
    networks = network_factory(config)(obs_sizes, num_actions, preprocess_observations_fn=running_statistics.normalize)
    key_policy, key_value = jax.random.split(jax.random.PRNGKey(0))
    shapes = {k: specs.Array((v,), jnp.dtype("float32")) for k, v in obs_sizes.items()}
    return (running_statistics.init_state(shapes), networks.policy_network.init(key_policy),
            networks.value_network.init(key_value))
