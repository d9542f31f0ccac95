"""How much of the state teacher's corrections the walker's clip removes (the reason its vision students'
labels are clipped): 16 games of 15 s against the placo player, native physics, seed 777, every 5th step.

    .venv/bin/python assets/runs/soccer-1v1-vision-clipped-cpu2/teacher_corrections.py
"""
import dataclasses

import jax.numpy as jnp
import numpy as np

from policies.evaluate import evaluate, soccer_opponent
from policies.policy_io import load_policy
from policies.training import build_env

policy, config = load_policy("assets/policies/op3-soccer-1v1")
env = build_env(dataclasses.replace(config, env=dataclasses.replace(config.env, episode_seconds=15.0)))
seen, act = [], policy.act


def recording(obs):
    out = act(obs)
    seen.append((np.asarray(obs), out))
    return out


policy.act = recording
evaluate(env, policy, 16, 777, "native", 16, 1, False, env_args=(soccer_opponent("placo", env),))
states = np.concatenate([s for s, _ in seen[::5]])
raw = np.concatenate([a for _, a in seen[::5]])
prior = np.asarray(env.walker.prior_actions(jnp.asarray(states), env.walker.prior))
clipped = np.clip(prior + raw, -1.0, 1.0) - prior
print(f"{len(states)} states; mean square (forward, sideways, turn):")
print("  raw corrections     ", np.round((raw ** 2).mean(0), 2))
print("  clipped corrections ", np.round((clipped ** 2).mean(0), 2))
print("  placo command       ", np.round((prior ** 2).mean(0), 2))
print("  |raw| median, 90%   ", np.round(np.quantile(np.abs(raw), [0.5, 0.9], axis=0), 2).tolist())
