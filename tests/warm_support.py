"""Test helpers for warm starts: random observation batches, and the actor of a shipped run as it was saved."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import torch

from policies.config import PPOConfig
from policies.rsl_backend import build_ppo, dummy_observations
from policies.warm_start import warm_start


def random_observations(sizes: dict, n: int, seed: int):
    """A batch of `n` observations of group sizes `sizes`, normal noise (every input matters to a network)."""
    rng = np.random.default_rng(seed)
    obs = dummy_observations(sizes, n)
    for key in obs.keys():
        obs[key] = torch.as_tensor(rng.normal(size=obs[key].shape), dtype=torch.float32)
    return obs


def saved_actor(run: Path, sizes: dict, actions: int, ppo: PPOConfig):
    """The PPO algorithm of a run's observation `sizes` with its newest checkpoint's actor loaded."""
    alg = build_ppo(dummy_observations(sizes, 8), 8, actions, ppo, "cpu")
    payload = torch.load(sorted((run / "checkpoints").glob("*.pt"))[-1], weights_only=True)
    alg.actor.load_state_dict(payload["alg"]["actor_state_dict"])
    return alg


def warm_started(source: Path, env, task: str, actions: int, ppo: PPOConfig, n: int = 32, seed: int = 0):
    """(a new run's PPO for `env` warm-started from `source`, the random observations it saw, the warm start's note)."""
    obs = random_observations(env.observation_dims(), n, seed)
    alg = build_ppo(obs, n, actions, ppo, "cpu")
    return alg, obs, warm_start(alg, source, env, obs, task)
