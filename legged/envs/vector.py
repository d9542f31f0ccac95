"""Many copies of an environment stepped together, with automatic resets and per-episode statistics.

This is what trainers and evaluators drive. A finished environment is reset with a fresh random key (a new
world tile, spawn, randomisation), not rewound to its first state, and the episode it finished is summed
up: return, length, every reward term and every event count summed over the episode (`SUMMED`), the task's
other metrics at the last step.
"""

from __future__ import annotations

import dataclasses
import functools

import jax
import jax.numpy as jnp
import numpy as np
from brax.envs.base import State

from legged.envs.api import next_carry
from legged.envs.native import NativeEnvs
from legged.envs.physics import select_envs


@jax.tree_util.register_dataclass
@dataclasses.dataclass
class Batch:
    """The JAX state of a vector of environments."""

    state: State
    """Batched environment state (leading axis = environment)."""
    keys: jax.Array
    """One PRNG key per environment, for its next reset."""
    sums: dict
    """Running sums of the current episode per environment: 'return', 'length', each 'reward/<term>' and each
    'events/<event>'."""


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


SUMMED = ("reward/", "events/")
"""Prefixes of the metrics summed over an episode: weighted reward terms, and counts of events as they happen
(`events/falls`: each time the task's fall rule triggers; `events/seconds_down`: time spent fallen; ...)."""


def summed(key: str) -> bool:
    """Whether the metric `key` is summed over an episode (`SUMMED`) rather than read at its last step."""
    return key.startswith(SUMMED)


def account(sums: dict, nxt: State) -> tuple[dict, dict, jax.Array, jax.Array]:
    """Episode bookkeeping of one vector step: (running sums with finished episodes cleared, `finished`
    statistics, done, time_out) from the sums before the step and the stepped states `nxt`."""
    done = nxt.done > 0
    sums = dict(sums)
    sums["return"] = sums["return"] + nxt.reward
    sums["length"] = sums["length"] + 1.0
    for k in sums:
        if summed(k):
            sums[k] = sums[k] + nxt.metrics[k]
    finished = {k: jnp.where(done, v, 0.0) for k, v in sums.items()}
    finished.update({k: jnp.where(done, v, 0.0) for k, v in nxt.metrics.items() if not summed(k)})
    sums = {k: jnp.where(done, 0.0, v) for k, v in sums.items()}
    return sums, finished, done, done & (nxt.info["truncation"] > 0)


PHYSICS = ("mjx", "native")
"""Physics engines every task runs on."""


class VectorEnv:
    """`num_envs` copies of `env` with batched reset and auto-resetting step, on either physics engine.

    `reset(key, carry=None)` starts every environment (`carry`, batched: what each first episode is given,
    see MjxEnv.spawn); `step(batch, action)` steps them and restarts the ones that ended, each new episode
    inheriting `env.carry` of the one before.

    physics="mjx": everything jitted in JAX (`env.reset`/`env.step` vmapped). physics="native": MuJoCo's C
    engine (legged.envs.native) steps the physics on `threads` threads, the same task verbs in JAX do the
    rest. Build it with `VectorEnv.of(env, num_envs, ...)` to reuse the compiled functions of an earlier one.
    """

    def __init__(self, env, num_envs: int, physics: str = "mjx", threads: int | None = None):
        if num_envs < 1:
            raise ValueError(f"num_envs must be >= 1, got {num_envs}")
        if physics not in PHYSICS:
            raise ValueError(f"unknown physics {physics!r}; one of {', '.join(PHYSICS)}")
        self.env, self.num_envs, self.physics = env, num_envs, physics
        self._zero = jax.jit(self._zero_sums)
        self._account = jax.jit(account)
        if physics == "native":
            self.native = NativeEnvs(env, num_envs, threads)
            self.reset, self.step = self._native_reset, self._native_step
        else:
            self.reset = jax.jit(self._reset)
            self.step = jax.jit(self._step)

    @classmethod
    def of(cls, env, num_envs: int, physics: str = "mjx", threads: int | None = None) -> "VectorEnv":
        """The VectorEnv of (env, num_envs, physics), made once per environment object (compilation is
        slow); a native one is made anew when `threads` differs."""
        cache = env.__dict__.setdefault("_vector_envs", {})
        key = (num_envs, physics, threads if physics == "native" else None)
        if key not in cache:
            cache[key] = cls(env, num_envs, physics, threads)
        return cache[key]

    def physics_seconds(self) -> float | None:
        """Wall time spent in MuJoCo's C engine so far (native physics); None on MJX, whose physics is compiled
        into the same step as the task's verbs."""
        return self.native.physics.seconds if self.physics == "native" else None

    def _zero_sums(self, state: State) -> dict:
        sums = {k: jnp.zeros(self.num_envs) for k in state.metrics if summed(k)}
        sums.update(**{"return": jnp.zeros(self.num_envs), "length": jnp.zeros(self.num_envs)})
        return sums

    def _reset(self, key: jax.Array, carry: dict | None = None) -> Batch:
        keys = jax.random.split(key, self.num_envs + 1)
        state = jax.vmap(self.env.reset)(keys[1:], carry)
        return Batch(state=state, keys=jax.random.split(keys[0], self.num_envs), sums=self._zero_sums(state))

    def _step(self, batch: Batch, action: jax.Array, *env_args) -> tuple[Batch, StepResult]:
        """Step every environment; `env_args` (e.g. a soccer opponent) go to every env's step unbatched."""
        nxt = jax.vmap(lambda s, a: self.env.step(s, a, *env_args))(batch.state, action)
        sums, finished, done, time_out = account(batch.sums, nxt)
        split = jax.vmap(jax.random.split)(batch.keys)
        carry = jax.vmap(functools.partial(next_carry, self.env))(nxt.info)
        fresh = jax.lax.cond(done.any(), lambda: jax.vmap(self.env.reset)(split[:, 0], carry), lambda: nxt)
        state = select_envs(done, fresh, nxt)
        result = StepResult(obs=state.obs, reward=nxt.reward, done=done, time_out=time_out, finished=finished)
        return Batch(state=state, keys=split[:, 1], sums=sums), result

    def _native_reset(self, key: jax.Array, carry: dict | None = None) -> Batch:
        keys = jax.random.split(key, self.num_envs + 1)
        state = self.native.reset(keys[1:], carry=carry)
        return Batch(state=state, keys=jax.random.split(keys[0], self.num_envs), sums=self._zero(state))

    def _native_step(self, batch: Batch, action: jax.Array, *env_args) -> tuple[Batch, StepResult]:
        nxt = self.native.step(batch.state, action, *env_args)
        sums, finished, done, time_out = self._account(batch.sums, nxt)
        split = _split_keys(batch.keys)
        ended = np.flatnonzero(np.asarray(done))
        state = self.native.reset(split[:, 0], ended, nxt) if len(ended) else nxt
        result = StepResult(obs=state.obs, reward=nxt.reward, done=done, time_out=time_out, finished=finished)
        return Batch(state=state, keys=split[:, 1], sums=sums), result


_split_keys = jax.jit(jax.vmap(jax.random.split))
