"""Many copies of an environment stepped together, with automatic resets and per-episode statistics.

This is what trainers and evaluators drive. A finished environment is reset with a fresh random key (a new
world tile, spawn, randomisation), not rewound to its first state, and the episode it finished is summed
up: return, length, every reward term and the task's metrics at the last step.
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
from brax.envs.base import State


@jax.tree_util.register_dataclass
@dataclasses.dataclass
class Batch:
    """The JAX state of a vector of environments."""

    state: State
    """Batched environment state (leading axis = environment)."""
    keys: jax.Array
    """One PRNG key per environment, for its next reset."""
    sums: dict
    """Running sums of the current episode per environment: 'return', 'length' and each 'reward/<term>'."""


@jax.tree_util.register_dataclass
@dataclasses.dataclass
class StepResult:
    """What one vector step reports."""

    obs: dict
    """Observations after the step (of the fresh episode where one ended)."""
    reward: jax.Array
    """Reward of the step, shape (n,)."""
    done: jax.Array
    """Whether the episode ended at this step, shape (n,) bool."""
    time_out: jax.Array
    """Whether it ended only because of the time limit (for bootstrapping), shape (n,) bool."""
    finished: dict
    """For each episode statistic, its value for the episodes that ended here and 0 elsewhere, shape (n,)."""


def select_envs(mask, on_true, on_false):
    """Per-environment choice between two batched pytrees: `on_true` where mask (n,) is set."""
    def pick(a, b):
        m = mask.reshape(mask.shape + (1,) * (a.ndim - 1))
        return jnp.where(m, a, b)
    return jax.tree_util.tree_map(pick, on_true, on_false)


class VectorEnv:
    """`num_envs` copies of `env` with jitted batched reset and auto-resetting step.

    Build it with `VectorEnv.of(env, num_envs)` to reuse the compiled functions of an earlier one.
    """

    def __init__(self, env, num_envs: int):
        if num_envs < 1:
            raise ValueError(f"num_envs must be >= 1, got {num_envs}")
        self.env, self.num_envs = env, num_envs
        self.reset = jax.jit(self._reset)
        self.step = jax.jit(self._step)

    @classmethod
    def of(cls, env, num_envs: int) -> "VectorEnv":
        """The VectorEnv of (env, num_envs), made once per environment object (compilation is slow)."""
        cache = env.__dict__.setdefault("_vector_envs", {})
        if num_envs not in cache:
            cache[num_envs] = cls(env, num_envs)
        return cache[num_envs]

    def _zero_sums(self, state: State) -> dict:
        sums = {k: jnp.zeros(self.num_envs) for k in state.metrics if k.startswith("reward/")}
        sums.update(**{"return": jnp.zeros(self.num_envs), "length": jnp.zeros(self.num_envs)})
        return sums

    def _reset(self, key: jax.Array) -> Batch:
        keys = jax.random.split(key, self.num_envs + 1)
        state = jax.vmap(self.env.reset)(keys[1:])
        return Batch(state=state, keys=jax.random.split(keys[0], self.num_envs), sums=self._zero_sums(state))

    def _step(self, batch: Batch, action: jax.Array, *env_args) -> tuple[Batch, StepResult]:
        """Step every environment; `env_args` (e.g. a soccer opponent) go to every env's step unbatched."""
        nxt = jax.vmap(lambda s, a: self.env.step(s, a, *env_args))(batch.state, action)
        done = nxt.done > 0
        sums = dict(batch.sums)
        sums["return"] = sums["return"] + nxt.reward
        sums["length"] = sums["length"] + 1.0
        for k in sums:
            if k.startswith("reward/"):
                sums[k] = sums[k] + nxt.metrics[k]
        finished = {k: jnp.where(done, v, 0.0) for k, v in sums.items()}
        finished.update({k: jnp.where(done, v, 0.0) for k, v in nxt.metrics.items() if not k.startswith("reward/")})
        split = jax.vmap(jax.random.split)(batch.keys)
        fresh = jax.lax.cond(done.any(), lambda: jax.vmap(self.env.reset)(split[:, 0]), lambda: nxt)
        state = select_envs(done, fresh, nxt)
        sums = {k: jnp.where(done, 0.0, v) for k, v in sums.items()}
        result = StepResult(obs=state.obs, reward=nxt.reward, done=done,
                            time_out=done & (nxt.info["truncation"] > 0), finished=finished)
        return Batch(state=state, keys=split[:, 1], sums=sums), result
