"""rsl-rl's VecEnv over a `VectorEnv`: arrays cross from JAX to PyTorch through DLPack (shared memory, no copies),
from PyTorch to JAX through NumPy on the CPU and DLPack elsewhere (`to_jax`).

Observation groups: the environment's (`state`, `privileged_state`, and `camera` or `history` where a task
has them; policies.algorithms says who reads which), plus `latent_noise` for Gaussian-latent actors.
`extras['time_outs']` marks episodes cut by the time limit (rsl-rl bootstraps their value); `extras['log']`
carries the mean of every finished episode's statistics (return, length, each reward term, the task's
metrics).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import torch
from rsl_rl.env import VecEnv
from tensordict import TensorDict

from legged.envs.curriculum import level_carry
from legged.envs.vector import VectorEnv
from policies.latent_models import NOISE_GROUP


@jax.jit
def _episode_totals(result) -> tuple[jax.Array, dict]:
    """Number of episodes that ended in a step and the sum of each of their statistics (on the device)."""
    return result.done.sum(), {k: v.sum() for k, v in result.finished.items()}


class EpisodeStats:
    """Statistics of finished episodes, summed between two `means()` calls (one host transfer per step)."""

    def __init__(self):
        self.count, self.sums = 0, {}

    def add(self, result) -> dict:
        """Add one vector step; returns that step's means ({} when no episode ended)."""
        count, totals = jax.device_get(_episode_totals(result))
        count = int(count)
        if not count:
            return {}
        self.count += count
        for k, v in totals.items():
            self.sums[k] = self.sums.get(k, 0.0) + float(v)
        return {k: float(v) / count for k, v in totals.items()}

    def means(self) -> dict:
        """{'episodes': n, 'episode_<stat>': mean} over the episodes since the last call, then reset."""
        out = {"episodes": self.count}
        out.update({f"episode_{k.replace('/', '_')}": total / self.count for k, total in self.sums.items()})
        self.count, self.sums = 0, {}
        return out


def to_torch(x: jax.Array, device: torch.device) -> torch.Tensor:
    """A JAX array as a torch tensor (shared memory through DLPack where the devices match)."""
    tensor = torch.from_dlpack(x)
    return tensor if tensor.device == device else tensor.to(device)


def to_jax(t: torch.Tensor) -> jax.Array:
    """A torch tensor as a JAX array: on the CPU through NumPy, on other devices through DLPack.

    DLPack gives a JAX array committed to its device, and a jitted function's outputs are committed when any of
    its inputs is, while the environment's reset makes uncommitted arrays: the first committed action would send
    the step, and the first episode end the reset, to be compiled again (5 s of a go1-flat run's first minute on a
    2-core CPU). A NumPy array becomes an uncommitted JAX array, so the loop keeps the programs it started with.
    """
    t = t.detach()
    if t.device.type == "cpu":
        return jnp.asarray(t.contiguous().numpy())
    return jax.dlpack.from_dlpack(t.contiguous())


class RslVecEnv(VecEnv):
    """rsl-rl interface to a batch of MJX environments (auto-reset, time-outs, episode logs)."""

    def __init__(self, vector: VectorEnv, seed: int, device: str = "cpu", cfg: dict | None = None,
                 latent_noise: int = 0, levels: np.ndarray | None = None, dr_scale: float | np.ndarray | None = None,
                 dr_step: float = 0.0):
        self.vector = vector
        self.latent_noise = latent_noise
        """Size of the standard-normal `latent_noise` observation drawn at every step (0: none)."""
        self._noise = torch.Generator(device=device).manual_seed(seed)
        self.num_envs = vector.num_envs
        self.num_actions = vector.env.action_size
        self.max_episode_length = vector.env.config.episode_steps
        self.device = torch.device(device)
        self.cfg = cfg or {}
        carry = None
        if levels is not None:  # a resumed run: every environment goes on at its curriculum level
            carry = level_carry(levels)
        if dr_scale is not None:  # a randomisation ramp or curriculum: the first episodes at its scale too
            carry = {**(carry or {}), "dr_scale": jnp.asarray(np.broadcast_to(dr_scale, self.num_envs), jnp.float32)}
        if dr_step:  # a curriculum: each episode's outcome moves its environment's scale (legged.envs.api)
            carry = {**(carry or {}), "dr_step": jnp.full(self.num_envs, dr_step, jnp.float32)}
        self.batch = vector.reset(jax.random.PRNGKey(seed), carry)
        self._obs = self.batch.state.obs
        self.episode_stats = EpisodeStats()
        self.env_args = ()
        """Extra arguments of every env step (a soccer LearnerView's opponent), set between iterations."""

    def physics_seconds(self) -> float | None:
        """Wall time in MuJoCo's C engine so far (None on MJX): VectorEnv.physics_seconds."""
        return self.vector.physics_seconds()

    def curriculum_levels(self) -> np.ndarray | None:
        """Each environment's terrain-curriculum level (None for tasks without one), saved with checkpoints so
        that a resumed run goes on where it was rather than from the easiest row."""
        level = self.batch.state.info.get("level")
        return None if level is None else np.asarray(jax.device_get(level), np.int32)

    @property
    def episode_length_buf(self) -> torch.Tensor:
        return to_torch(self.batch.state.info["step"], self.device)

    @episode_length_buf.setter
    def episode_length_buf(self, value: torch.Tensor) -> None:
        """Randomised initial episode lengths (rsl-rl's init_at_random_ep_len)."""
        self.batch.state.info["step"] = to_jax(value.to(torch.int32))

    def randomization_scales(self) -> np.ndarray:
        """Each environment's randomisation scale (a ramp's or curriculum's; 1 without either)."""
        return np.asarray(jax.device_get(self.batch.state.info["dr_scale"]), np.float32)

    def set_randomization_scale(self, scale: float) -> None:
        """The randomisation scale of the episodes that start from now on (legged.envs.base.LeggedEnv.spawn)."""
        self.batch.state.info["dr_scale"] = jnp.full(self.num_envs, scale, jnp.float32)

    def _observations(self, obs: dict) -> TensorDict:
        groups = {k: to_torch(v, self.device) for k, v in obs.items()}
        if self.latent_noise:
            groups[NOISE_GROUP] = torch.randn(self.num_envs, self.latent_noise, generator=self._noise,
                                              device=self.device)
        return TensorDict(groups, batch_size=[self.num_envs], device=self.device)

    def get_observations(self) -> TensorDict:
        return self._observations(self._obs)

    def step(self, actions: torch.Tensor) -> tuple[TensorDict, torch.Tensor, torch.Tensor, dict]:
        self.batch, result = self.vector.step(self.batch, to_jax(actions).astype(jnp.float32), *self.env_args)
        self._obs = result.obs
        step_means = self.episode_stats.add(result)
        extras = {"time_outs": to_torch(result.time_out, self.device),
                  "log": {f"/episode/{k}": v for k, v in step_means.items()}}
        done = to_torch(result.done, self.device).long()
        return self.get_observations(), to_torch(result.reward, self.device), done, extras
